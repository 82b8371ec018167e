//! Build script: generates Rust bindings for Embree 3 with bindgen, compiles the small C shim
//! in `wrapper/`, and links `libembree3`.
//!
//! Bindings are generated at build time against the installed headers (never checked in), so
//! build-configuration values such as `RTC_MAX_INSTANCE_LEVEL_COUNT` match the library that
//! is linked. Only `rtc*` / `RTC*` items (and the shim's `conetrace_rtc*` functions) are bound.

use std::env;
use std::path::{Path, PathBuf};
use std::process;

/// Where Debian's `libembree-dev` puts the headers; `EMBREE_INCLUDE_DIR` overrides it.
const DEFAULT_INCLUDE_DIR: &str = "/usr/include";
const SETUP_HINT: &str =
    "run `bash scripts/setup.sh` (installs libembree-dev, libclang-dev and clang)";

fn fail(message: &str) -> ! {
    eprintln!("error: conetrace build: {message}; {SETUP_HINT}");
    println!("cargo:warning=conetrace build: {message}; {SETUP_HINT}");
    process::exit(1);
}

fn main() {
    let manifest_dir = env::var("CARGO_MANIFEST_DIR")
        .unwrap_or_else(|_| fail("CARGO_MANIFEST_DIR is not set (run the build through cargo)"));
    let wrapper_dir = Path::new(&manifest_dir).join("wrapper");
    let header = wrapper_dir.join("conetrace_embree.h");
    let shim = wrapper_dir.join("conetrace_embree.c");

    println!("cargo:rerun-if-changed={}", header.display());
    println!("cargo:rerun-if-changed={}", shim.display());
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-env-changed=EMBREE_INCLUDE_DIR");
    println!("cargo:rerun-if-env-changed=LIBCLANG_PATH");

    let include_dir = PathBuf::from(
        env::var("EMBREE_INCLUDE_DIR").unwrap_or_else(|_| DEFAULT_INCLUDE_DIR.into()),
    );
    let rtcore = include_dir.join("embree3").join("rtcore.h");
    if !rtcore.is_file() {
        fail(&format!("Embree 3 header {} not found", rtcore.display()));
    }
    println!("cargo:rerun-if-changed={}", rtcore.display());
    if !header.is_file() {
        fail(&format!("shim header {} not found", header.display()));
    }

    // Bindgen loads libclang at run time and panics when it cannot; turn that into a message.
    let include_arg = format!("-I{}", include_dir.display());
    let header_str = header.display().to_string();
    // Silence the default panic report (with backtrace) while bindgen runs; its message
    // is repeated in ours.
    let default_hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let generated = std::panic::catch_unwind(move || {
        bindgen::Builder::default()
            .header(header_str)
            .clang_arg(include_arg)
            .allowlist_function("rtc.*")
            .allowlist_function("conetrace_rtc.*")
            .allowlist_type("RTC.*")
            .allowlist_var("RTC.*")
            .default_enum_style(bindgen::EnumVariation::Consts)
            .prepend_enum_name(false)
            .derive_default(true)
            .layout_tests(true)
            .generate()
    });
    std::panic::set_hook(default_hook);
    let bindings = match generated {
        Ok(Ok(bindings)) => bindings,
        Ok(Err(err)) => fail(&format!(
            "bindgen could not parse {}: {err}",
            header.display()
        )),
        Err(payload) => {
            let reason = payload
                .downcast_ref::<String>()
                .map(String::as_str)
                .or_else(|| payload.downcast_ref::<&str>().copied())
                .unwrap_or("unknown reason");
            let first_line = reason.lines().next().unwrap_or(reason);
            fail(&format!("bindgen could not load libclang ({first_line})"))
        }
    };

    let out_dir = PathBuf::from(
        env::var("OUT_DIR")
            .unwrap_or_else(|_| fail("OUT_DIR is not set (run the build through cargo)")),
    );
    let out_file = out_dir.join("embree_bindings.rs");
    if let Err(err) = bindings.write_to_file(&out_file) {
        fail(&format!("cannot write {}: {err}", out_file.display()));
    }

    cc::Build::new()
        .file(&shim)
        .include(&include_dir)
        .include(&wrapper_dir)
        .opt_level(2)
        .warnings(true)
        .compile("conetrace_embree_shim");

    println!("cargo:rustc-link-lib=embree3");
}
