//! conetrace: a CPU ray tracer that traces packets of rays through Embree and filters every
//! texture lookup by the ray's footprint (ray cones, ray differentials).
//!
//! The modules follow the data flow: [`scene`] (description and loaders) -> [`embree`] (the
//! one safe layer over Embree) -> [`camera`] rays with [`footprint`]s -> packets through
//! [`render::tracer`] -> [`hit`]s -> [`shading`] in an [`integrator`] (with [`texture`]
//! filtering) -> [`film`] -> EXR/PNG. The command line (`src/cli`) belongs to the
//! `conetrace` binary, not to this library: `libconetrace.so`/`.a`, which C programs link,
//! carry none of its dependencies (clap, indicatif, ctrlc, plotters, nv-flip).
//!
//! Every `unsafe` block lives in [`embree`] (the FFI to Embree), [`capi`] (the C interface)
//! and [`simd`] (calls of functions compiled for vector instructions the processor was
//! checked to have); the rest of the crate is denied unsafe code by the compiler.

#![deny(unsafe_code)]

pub mod camera;
#[allow(unsafe_code)]
pub mod capi;
#[allow(unsafe_code)]
pub mod embree;
pub mod film;
pub mod footprint;
pub mod hit;
pub mod integrator;
pub mod medium;
pub mod render;
pub mod sampler;
pub mod scene;
pub mod shading;
#[allow(unsafe_code)]
pub mod simd;
pub mod srgb;
#[cfg(test)]
mod test_rng;
pub mod texture;
pub mod vct;

#[cfg(test)]
mod unsafe_boundary {
    use std::path::{Path, PathBuf};

    fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
        for entry in std::fs::read_dir(dir).expect("src/ is readable") {
            let path = entry.expect("directory entry").path();
            if path.is_dir() {
                rust_files(&path, out);
            } else if path.extension().is_some_and(|e| e == "rs") {
                out.push(path);
            }
        }
    }

    /// In `simd`, every unsafe block (a call of a function compiled for a level) comes after
    /// the check, in the same function, that the processor supports the level.
    fn simd_calls_check_the_processor_first(simd: &Path) {
        let mut files = Vec::new();
        rust_files(simd, &mut files);
        let mut blocks = 0;
        for file in &files {
            let text = std::fs::read_to_string(file).expect("source is UTF-8");
            for (at, _) in text.match_indices("unsafe {") {
                let function = text[..at]
                    .rfind("fn ")
                    .expect("unsafe block outside a function");
                assert!(
                    text[function..at].contains(".is_supported()"),
                    "{}: an unsafe block at byte {at} runs without checking the level",
                    file.display()
                );
                blocks += 1;
            }
        }
        assert!(blocks > 0, "no unsafe block found in {}", simd.display());
    }

    /// The modules allowed unsafe code.
    const UNSAFE_MODULES: [&str; 3] = ["capi", "embree", "simd"];

    /// The compiler denies unsafe code crate-wide; this keeps the only exceptions the three
    /// allow attributes on `embree`, `capi` and `simd` above (a module could otherwise lift
    /// the lint for itself).
    #[test]
    fn only_embree_capi_and_simd_may_use_unsafe_code() {
        let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
        let mut files = Vec::new();
        rust_files(&src, &mut files);
        let mut offenders = Vec::new();
        for file in &files {
            let relative = file.strip_prefix(&src).expect("under src/");
            if UNSAFE_MODULES.iter().any(|m| relative.starts_with(m)) {
                continue;
            }
            let text = std::fs::read_to_string(file).expect("source is UTF-8");
            let lifts = text.matches(concat!("allow(", "unsafe_code)")).count();
            let expected = if relative == Path::new("lib.rs") {
                UNSAFE_MODULES.len()
            } else {
                0
            };
            if lifts != expected {
                offenders.push(format!("{}: {lifts}", relative.display()));
            }
        }
        assert!(files.len() > 50, "only {} source files found", files.len());
        assert!(offenders.is_empty(), "unsafe_code allowed in {offenders:?}");
        let lib = std::fs::read_to_string(src.join("lib.rs")).unwrap();
        for module in UNSAFE_MODULES {
            let allowed = format!("#[allow({})]\npub mod {module};", "unsafe_code");
            assert!(
                lib.contains(&allowed),
                "lib.rs: {module} is not the allowed module"
            );
        }
        simd_calls_check_the_processor_first(&src.join("simd"));
        let main = std::fs::read_to_string(src.join("main.rs")).unwrap();
        assert!(main.contains(concat!("#![deny(", "unsafe_code)]")));
    }
}
