//! The C API (`src/capi`, `include/conetrace.h`): the committed header matches cbindgen's
//! output; the C and C++ examples compile against `libconetrace.so` and run, and the C
//! example also links statically against `libconetrace.a` with `conetrace.pc`'s flags; and
//! the entry points reject bad input (NULL pointers, null/dangling/wrong-kind handles,
//! unparsable scenes, wrong `struct_size`, a failing texture callback) with a status and a
//! message, while a render cancelled from the progress callback leaves a valid partial
//! image.
//!
//! Missing `cc`, `g++`, `pkg-config` or OpenImageIO's headers fail the tests with a message
//! naming `bash scripts/setup.sh`.

mod common;

use std::ffi::{c_char, c_void, CStr, CString};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::atomic::{AtomicUsize, Ordering};

use conetrace::capi::*;
use conetrace::film::read_exr;

const SETUP_HINT: &str =
    "run `bash scripts/setup.sh` (installs a C/C++ compiler, pkg-config and libopenimageio-dev)";

fn manifest_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The directory holding the binary, libconetrace.so and libconetrace.a of this build.
///
/// `cargo test` links the tests against the rlib and does not produce the shared and static
/// libraries, so they are brought up to date here with `cargo build --lib` (same profile and
/// target directory), once per test process. Cargo decides whether they are stale from the
/// same fingerprints as every other build (sources, build script, manifest, lock file,
/// environment), so a library left over from older sources is rebuilt, and a fresh one costs
/// only cargo's check.
fn library_dir() -> PathBuf {
    static BUILD: std::sync::Once = std::sync::Once::new();
    let bin = PathBuf::from(env!("CARGO_BIN_EXE_conetrace"));
    let dir = bin.parent().expect("binary has a directory").to_path_buf();
    BUILD.call_once(|| {
        let mut build = Command::new(env!("CARGO"));
        build.args(["build", "--lib"]).current_dir(manifest_dir());
        if dir.file_name().is_some_and(|name| name == "release") {
            build.arg("--release");
        }
        if let Some(target) = dir.parent() {
            build.env("CARGO_TARGET_DIR", target);
        }
        let status = build.status().expect("cargo runs");
        assert!(status.success(), "cargo build --lib failed");
    });
    for library in ["libconetrace.so", "libconetrace.a"] {
        assert!(
            dir.join(library).exists(),
            "{} has no {library} (is crate-type cdylib/staticlib set in Cargo.toml?)",
            dir.display()
        );
    }
    dir
}

fn last_error() -> String {
    // SAFETY: ct_last_error_message never returns NULL and the text is NUL-terminated.
    unsafe { CStr::from_ptr(ct_last_error_message()) }
        .to_string_lossy()
        .into_owned()
}

fn run(cmd: &mut Command) -> String {
    let out = cmd
        .output()
        .unwrap_or_else(|e| panic!("cannot run {cmd:?}: {e}. {SETUP_HINT}"));
    assert!(
        out.status.success(),
        "{cmd:?} failed ({}):\n{}\n{}",
        out.status,
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// A conetrace.pc for this build tree, generated from conetrace.pc.in into `dir`.
fn write_pkg_config(dir: &Path) {
    write_pkg_config_for(dir, &library_dir());
}

/// A conetrace.pc generated from conetrace.pc.in into `dir`, with `libdir` as its library
/// directory.
fn write_pkg_config_for(dir: &Path, libdir: &Path) {
    let template =
        std::fs::read_to_string(manifest_dir().join("conetrace.pc.in")).expect("conetrace.pc.in");
    let text = template
        .replace("@PREFIX@", &manifest_dir().display().to_string())
        .replace("@LIBDIR@", &libdir.display().to_string())
        .replace(
            "@INCLUDEDIR@",
            &manifest_dir().join("include").display().to_string(),
        )
        .replace("@VERSION@", env!("CARGO_PKG_VERSION"));
    std::fs::write(dir.join("conetrace.pc"), text).expect("write conetrace.pc");
}

/// `pkg-config --cflags --libs conetrace` against the generated file.
fn pkg_config_flags(dir: &Path) -> Vec<String> {
    write_pkg_config(dir);
    let out = run(Command::new("pkg-config")
        .args(["--cflags", "--libs", "conetrace"])
        .env("PKG_CONFIG_PATH", dir));
    out.split_whitespace().map(str::to_string).collect()
}

fn generated_header() -> String {
    let root = manifest_dir();
    let config = cbindgen::Config::from_file(root.join("cbindgen.toml")).expect("cbindgen.toml");
    let bindings = cbindgen::Builder::new()
        .with_config(config)
        .with_src(root.join("src/capi/mod.rs"))
        .generate()
        .expect("cbindgen generates the header");
    let mut bytes = Vec::new();
    bindings.write(&mut bytes);
    String::from_utf8(bytes).expect("header is UTF-8")
}

#[test]
fn header_is_up_to_date() {
    let path = manifest_dir().join("include/conetrace.h");
    let fresh = generated_header();
    if std::env::var_os("CONETRACE_BLESS_HEADER").is_some() {
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(&path, &fresh).expect("write include/conetrace.h");
    }
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        committed == fresh,
        "include/conetrace.h differs from the header cbindgen generates from src/capi; \
         regenerate it with `CONETRACE_BLESS_HEADER=1 cargo test --test c_api header_is_up_to_date`"
    );
}

#[test]
fn c_example_renders_an_exr_with_the_expected_channels() {
    let dir = common::temp_dir();
    let flags = pkg_config_flags(dir.path());
    let exe = dir.path().join("render");
    run(Command::new("cc")
        .args(["-std=c99", "-Wall", "-Wextra", "-Werror"])
        .arg(manifest_dir().join("examples/c/render.c"))
        .args(&flags)
        .arg("-o")
        .arg(&exe));
    let exr = dir.path().join("default.exr");
    let out = run(Command::new(&exe)
        .arg(&exr)
        .args(["96", "54"])
        .env("LD_LIBRARY_PATH", library_dir()));
    assert!(out.contains("rendered 96x54"), "{out}");
    let (film, attributes) = read_exr(&exr).expect("the example wrote a readable EXR");
    assert_eq!((film.width(), film.height()), (96, 54));
    // The standard camera matrices (4x4 floats) are in the header, as `render` writes them.
    let bytes = std::fs::read(&exr).unwrap();
    for attribute in [&b"worldToCamera\0m44f\0"[..], &b"worldToNDC\0m44f\0"[..]] {
        assert!(
            bytes.windows(attribute.len()).any(|w| w == attribute),
            "{} missing",
            String::from_utf8_lossy(attribute)
        );
    }
    let names = film.channel_names();
    for expected in [
        "R", "G", "B", "A", "Z", "N.X", "N.Y", "N.Z", "albedo.R", "albedo.G", "albedo.B", "uv.U",
        "uv.V",
    ] {
        assert!(
            names.iter().any(|n| n == expected),
            "no {expected} in {names:?}"
        );
    }
    assert!(!attributes.incomplete);
    let red = film.channel("R").unwrap();
    assert!(red.iter().any(|&v| v > 0.05), "the image is black");
}

/// A C program links `libconetrace.a` with exactly the flags `conetrace.pc` documents for a
/// static link (`pkg-config --static --libs`): the archive must not need a library the file
/// does not name (e.g. libstdc++ for C++ code of a command-line dependency).
#[test]
fn c_example_links_statically_with_the_documented_flags() {
    let dir = common::temp_dir();
    // A library directory holding only the archive, so `-lconetrace` can only mean it.
    let libdir = dir.path().join("lib");
    std::fs::create_dir(&libdir).unwrap();
    std::fs::copy(
        library_dir().join("libconetrace.a"),
        libdir.join("libconetrace.a"),
    )
    .expect("copy libconetrace.a");
    write_pkg_config_for(dir.path(), &libdir);
    let out = run(Command::new("pkg-config")
        .args(["--static", "--cflags", "--libs", "conetrace"])
        .env("PKG_CONFIG_PATH", dir.path()));
    let flags: Vec<&str> = out.split_whitespace().collect();
    let exe = dir.path().join("render_static");
    run(Command::new("cc")
        .args(["-std=c99", "-Wall", "-Wextra", "-Werror"])
        .arg(manifest_dir().join("examples/c/render.c"))
        .args(&flags)
        .arg("-o")
        .arg(&exe));
    // The program does not load libconetrace.so: the archive was linked in.
    let dynamic = run(Command::new("ldd").arg(&exe));
    assert!(!dynamic.contains("libconetrace"), "{dynamic}");
    let exr = dir.path().join("static.exr");
    let out = run(Command::new(&exe).arg(&exr).args(["64", "36"]));
    assert!(out.contains("rendered 64x36"), "{out}");
    assert!(out.contains("channels: R G B A"), "{out}");
    let (film, attributes) = read_exr(&exr).expect("the example wrote a readable EXR");
    assert_eq!((film.width(), film.height()), (64, 36));
    assert!(!attributes.incomplete);
    let red = film.channel("R").unwrap();
    assert!(red.iter().any(|&v| v > 0.05), "the image is black");
}

/// The command line's dependencies (clap, indicatif, ctrlc, plotters, nv-flip and its C++
/// code) belong to the `conetrace` binary: the static library defines none of their symbols
/// (Rust's legacy mangling starts a path with its crate's name: `_ZN4clap...`) and no C++
/// standard-library code (`std::` template instantiations, `_ZNSt`/`_ZNKSt`).
#[test]
fn static_library_carries_no_command_line_code() {
    let archive = library_dir().join("libconetrace.a");
    // readelf reads the ELF symbol tables themselves. GNU nm hands objects to the linker
    // plugins in /usr/lib/bfd-plugins first, and the LLVMgold plugin of Debian's llvm-14
    // (installed with clang for bindgen) claims the library object, which carries a copy of
    // its LLVM bitcode, fails to read the newer bitcode, and nm then lists no symbols for it.
    let listing = run(Command::new("readelf").arg("-sW").arg(&archive));
    // Defined symbols: a section index, not UND (columns: Num Value Size Type Bind Vis Ndx
    // Name).
    let symbols: Vec<&str> = listing
        .lines()
        .filter_map(|line| {
            let fields: Vec<&str> = line.split_whitespace().collect();
            (fields.len() >= 8 && fields[0].ends_with(':') && fields[6] != "UND").then(|| fields[7])
        })
        .collect();
    // The archive's own entry points are there, so the listing is not empty or mangled away.
    assert!(
        symbols.contains(&"ct_render"),
        "readelf lists no ct_render in {}",
        archive.display()
    );
    let foreign_prefixes = [
        "_ZN4clap",
        "_ZN12clap_builder",
        "_ZN9indicatif",
        "_ZN5ctrlc",
        "_ZN8plotters",
        "_ZN7nv_flip",
        "_ZNSt",
        "_ZNKSt",
    ];
    let foreign: Vec<&str> = symbols
        .iter()
        .copied()
        .filter(|name| foreign_prefixes.iter().any(|p| name.starts_with(p)))
        .take(5)
        .collect();
    assert!(foreign.is_empty(), "libconetrace.a defines {foreign:?}");
}

#[test]
fn cpp_example_with_openimageio_textures_matches_builtin_filtering() {
    let include = Path::new("/usr/include/OpenImageIO/texture.h");
    assert!(
        include.exists(),
        "{} is missing: {SETUP_HINT}",
        include.display()
    );
    let dir = common::temp_dir();
    let flags = pkg_config_flags(dir.path());
    let exe = dir.path().join("oiio_textures");
    run(Command::new("g++")
        .args(["-std=c++17", "-O1", "-Wall"])
        .arg(manifest_dir().join("examples/cpp/oiio_textures.cpp"))
        .args(&flags)
        .args(["-lOpenImageIO", "-lOpenImageIO_Util", "-o"])
        .arg(&exe));
    let scene = manifest_dir().join("assets/scenes/default.toml");
    let out = run(Command::new(&exe)
        .arg(&scene)
        .arg(dir.path())
        .args(["160", "90"])
        .env("LD_LIBRARY_PATH", library_dir()));
    println!("{out}");
    let printed: f64 = out
        .lines()
        .find_map(|l| l.strip_prefix("psnr_db "))
        .expect("the example prints psnr_db")
        .trim()
        .parse()
        .expect("a number");

    // Recompute from the two EXRs it wrote: linear RGB, peak 1.0.
    let (ours, _) = read_exr(&dir.path().join("builtin.exr")).expect("builtin.exr");
    let (theirs, _) = read_exr(&dir.path().join("oiio.exr")).expect("oiio.exr");
    let mut squared = 0.0f64;
    let mut n = 0usize;
    for c in ["R", "G", "B"] {
        for (a, b) in ours
            .channel(c)
            .unwrap()
            .iter()
            .zip(theirs.channel(c).unwrap())
        {
            squared += (*a as f64 - *b as f64).powi(2);
            n += 1;
        }
    }
    let mse = squared / n as f64;
    let psnr = if mse > 0.0 {
        10.0 * (1.0 / mse).log10()
    } else {
        f64::INFINITY
    };
    println!("recomputed PSNR {psnr:.2} dB (example printed {printed:.2})");
    assert!((psnr - printed).abs() < 0.05 || psnr.is_infinite());
    // Float rounding between two implementations of one filter leaves about 100 dB here;
    // OpenImageIO filtering float levels where ours reads 8-bit ones gives 65.6 dB.
    assert!(psnr >= 80.0, "PSNR {psnr:.2} dB < 80 dB");
    // The textures really went through the callback: the albedo AOV of the two renders is
    // computed from different texture systems, so it cannot be bit-identical everywhere.
    let differs = ours
        .channel("albedo.R")
        .unwrap()
        .iter()
        .zip(theirs.channel("albedo.R").unwrap())
        .any(|(a, b)| a != b);
    assert!(differs, "OpenImageIO's lookups left no trace in the albedo");
}

// ---- The entry points called directly, as a C caller would. ----

fn default_scene() -> CtScene {
    let mut scene = CtScene::default();
    // SAFETY: a valid out-pointer.
    assert_eq!(unsafe { ct_scene_default(&mut scene) }, CtStatus::CT_OK);
    scene
}

fn small_options() -> CtRenderOptions {
    let mut options = std::mem::MaybeUninit::<CtRenderOptions>::uninit();
    // SAFETY: the pointer is valid for size_of bytes.
    let status = unsafe {
        ct_render_options_init(options.as_mut_ptr(), std::mem::size_of::<CtRenderOptions>())
    };
    assert_eq!(status, CtStatus::CT_OK);
    // SAFETY: fully written by ct_render_options_init.
    let mut options = unsafe { options.assume_init() };
    options.width = 64;
    options.height = 48;
    options.threads = 2;
    options
}

#[test]
fn null_pointers_are_rejected_with_a_message() {
    let mut scene = CtScene { id: 12345 };
    // SAFETY: NULL is what is being tested; the out-pointer is valid.
    let status = unsafe { ct_scene_load_file(std::ptr::null(), &mut scene) };
    assert_eq!(status, CtStatus::CT_ERROR_NULL_POINTER);
    assert!(last_error().contains("path"), "{}", last_error());
    assert_eq!(scene, CtScene::default(), "the out-handle is reset to null");

    let path = CString::new("x.toml").unwrap();
    let status = unsafe { ct_scene_load_file(path.as_ptr(), std::ptr::null_mut()) };
    assert_eq!(status, CtStatus::CT_ERROR_NULL_POINTER);
    assert!(last_error().contains("out_scene"));

    let scene = default_scene();
    let status = unsafe { ct_render(scene, std::ptr::null(), std::ptr::null_mut()) };
    assert_eq!(status, CtStatus::CT_ERROR_NULL_POINTER);
    let status = unsafe { ct_scene_texture_count(scene, std::ptr::null_mut()) };
    assert_eq!(status, CtStatus::CT_ERROR_NULL_POINTER);
    assert_eq!(ct_scene_free(scene), CtStatus::CT_OK);
}

#[test]
fn null_dangling_and_wrong_kind_handles_are_rejected() {
    let mut count = 0u32;
    // The null handle.
    let status = unsafe { ct_scene_texture_count(CtScene::default(), &mut count) };
    assert_eq!(status, CtStatus::CT_ERROR_INVALID_HANDLE);
    assert!(last_error().contains("null"), "{}", last_error());
    // Freeing the null handle is a no-op, like free(NULL).
    assert_eq!(ct_scene_free(CtScene::default()), CtStatus::CT_OK);

    // A freed handle, used and freed again.
    let scene = default_scene();
    assert_eq!(
        unsafe { ct_scene_texture_count(scene, &mut count) },
        CtStatus::CT_OK
    );
    assert_eq!(
        count, 3,
        "the default scene's checker, crate and sky textures"
    );
    assert_eq!(ct_scene_free(scene), CtStatus::CT_OK);
    let status = unsafe { ct_scene_texture_count(scene, &mut count) };
    assert_eq!(status, CtStatus::CT_ERROR_INVALID_HANDLE);
    assert!(last_error().contains("not live"), "{}", last_error());
    assert_eq!(ct_scene_free(scene), CtStatus::CT_ERROR_INVALID_HANDLE);
    let mut image = CtImage::default();
    let status = unsafe { ct_render(scene, std::ptr::null(), &mut image) };
    assert_eq!(status, CtStatus::CT_ERROR_INVALID_HANDLE);
    assert_eq!(image, CtImage::default());

    // A forged id and a handle of another kind.
    let status = unsafe { ct_scene_texture_count(CtScene { id: u64::MAX }, &mut count) };
    assert_eq!(status, CtStatus::CT_ERROR_INVALID_HANDLE);
    let scene = default_scene();
    let mut width = 0u32;
    let status =
        unsafe { ct_image_size(CtImage { id: scene.id }, &mut width, std::ptr::null_mut()) };
    assert_eq!(status, CtStatus::CT_ERROR_INVALID_HANDLE);
    assert!(
        last_error().contains("is a scene, not an image"),
        "{}",
        last_error()
    );
    assert_eq!(
        ct_image_free(CtImage { id: scene.id }),
        CtStatus::CT_ERROR_INVALID_HANDLE
    );
    // The failed free of the wrong kind left the scene intact.
    assert_eq!(
        unsafe { ct_scene_texture_count(scene, &mut count) },
        CtStatus::CT_OK
    );
    assert_eq!(ct_scene_free(scene), CtStatus::CT_OK);
}

#[test]
fn scenes_that_do_not_parse_give_a_scene_error() {
    let dir = common::temp_dir();
    let bad = common::write(dir.path(), "bad.toml", "[camera\neye = [0, 1");
    let path = CString::new(bad.display().to_string()).unwrap();
    let mut scene = CtScene::default();
    let status = unsafe { ct_scene_load_file(path.as_ptr(), &mut scene) };
    assert_eq!(status, CtStatus::CT_ERROR_SCENE);
    assert!(last_error().contains("bad.toml"), "{}", last_error());
    assert_eq!(scene, CtScene::default());

    let missing = CString::new("/nonexistent/scene.obj").unwrap();
    let status = unsafe { ct_scene_load_file(missing.as_ptr(), &mut scene) };
    assert_eq!(status, CtStatus::CT_ERROR_SCENE);
    assert!(
        last_error().contains("/nonexistent/scene.obj"),
        "{}",
        last_error()
    );

    let text = CString::new("[[sphere]]\ncenter = [0, 0]\n").unwrap();
    let label = CString::new("inline").unwrap();
    let status = unsafe {
        ct_scene_load_toml_string(text.as_ptr(), std::ptr::null(), label.as_ptr(), &mut scene)
    };
    assert_eq!(status, CtStatus::CT_ERROR_SCENE);
    assert!(last_error().contains("inline"), "{}", last_error());

    let bytes = [0xffu8, 0xfe, 0];
    let status = unsafe {
        ct_scene_load_toml_string(
            bytes.as_ptr().cast::<c_char>(),
            std::ptr::null(),
            std::ptr::null(),
            &mut scene,
        )
    };
    assert_eq!(status, CtStatus::CT_ERROR_INVALID_ARGUMENT);
}

#[test]
fn options_with_a_wrong_size_or_bad_values_are_rejected() {
    let scene = default_scene();
    let mut options = small_options();
    // Neither today's size nor an earlier header's (which end before `integrator` or `clamp`).
    options.struct_size -= 4;
    let mut image = CtImage::default();
    let status = unsafe { ct_render(scene, &options, &mut image) };
    assert_eq!(status, CtStatus::CT_ERROR_STRUCT_SIZE);
    assert!(last_error().contains("struct_size"), "{}", last_error());
    assert_eq!(image, CtImage::default());

    let mut fresh = std::mem::MaybeUninit::<CtRenderOptions>::uninit();
    let status = unsafe { ct_render_options_init(fresh.as_mut_ptr(), 8) };
    assert_eq!(status, CtStatus::CT_ERROR_STRUCT_SIZE);

    let mut options = small_options();
    options.filter = 99;
    assert_eq!(
        unsafe { ct_render(scene, &options, &mut image) },
        CtStatus::CT_ERROR_INVALID_ARGUMENT
    );
    assert!(last_error().contains("filter"), "{}", last_error());
    let mut options = small_options();
    options.max_aniso = f32::NAN;
    assert_eq!(
        unsafe { ct_render(scene, &options, &mut image) },
        CtStatus::CT_ERROR_INVALID_ARGUMENT
    );
    let mut options = small_options();
    options.threads = 5000;
    assert_eq!(
        unsafe { ct_render(scene, &options, &mut image) },
        CtStatus::CT_ERROR_INVALID_ARGUMENT
    );
    let mut options = small_options();
    options.max_depth = -5;
    assert_eq!(
        unsafe { ct_render(scene, &options, &mut image) },
        CtStatus::CT_ERROR_INVALID_ARGUMENT
    );
    assert_eq!(image, CtImage::default());
    assert_eq!(ct_scene_free(scene), CtStatus::CT_OK);
}

unsafe extern "C" fn cancel_after_two(done: u32, _total: u32, user: *mut c_void) -> i32 {
    // SAFETY: the test passes an AtomicUsize.
    let calls = unsafe { &*(user as *const AtomicUsize) };
    calls.fetch_add(1, Ordering::Relaxed);
    i32::from(done >= 2)
}

/// The default scene at 320x180 on one thread, cancelled by the progress callback once two
/// tiles are done: the scene, its partial image and how often the callback was called.
fn render_cancelled_after_two_tiles() -> (CtScene, CtImage, usize) {
    let scene = default_scene();
    let calls = AtomicUsize::new(0);
    let mut options = small_options();
    options.width = 320;
    options.height = 180;
    options.threads = 1;
    options.progress = Some(cancel_after_two);
    options.progress_user_data = &calls as *const AtomicUsize as *mut c_void;
    let mut image = CtImage::default();
    let status = unsafe { ct_render(scene, &options, &mut image) };
    assert_eq!(status, CtStatus::CT_CANCELLED, "{}", last_error());
    (scene, image, calls.load(Ordering::Relaxed))
}

#[test]
fn a_render_cancelled_from_the_progress_callback_leaves_a_valid_partial_image() {
    let (scene, image, calls) = render_cancelled_after_two_tiles();
    assert_ne!(
        image,
        CtImage::default(),
        "a cancelled render still returns its image"
    );
    // One call may report several tiles (workers do not wait for the callback), so the
    // callback saw at least one call, and stopped the render at its first count >= 2.
    assert!(calls >= 1);
    let mut complete = 1;
    assert_eq!(
        unsafe { ct_image_is_complete(image, &mut complete) },
        CtStatus::CT_OK
    );
    assert_eq!(complete, 0);

    // Red: every rendered pixel (sky or surface) has some.
    let mut alpha = 0u32;
    let name = CString::new("R").unwrap();
    assert_eq!(
        unsafe { ct_image_find_channel(image, name.as_ptr(), &mut alpha) },
        CtStatus::CT_OK
    );
    let mut pixels: *const f32 = std::ptr::null();
    let mut count = 0usize;
    let status = unsafe { ct_image_channel_pixels(image, alpha, &mut pixels, &mut count) };
    assert_eq!(status, CtStatus::CT_OK);
    assert_eq!(count, 320 * 180);
    // SAFETY: the library says `count` floats live at `pixels` until ct_image_free.
    let plane = unsafe { std::slice::from_raw_parts(pixels, count) };
    let rendered = plane.iter().filter(|&&a| a > 0.0).count();
    assert!(rendered > 0, "the finished tiles are in the image");
    assert!(rendered < count / 2, "most tiles were never rendered");

    let dir = common::temp_dir();
    let exr = dir.path().join("partial.exr");
    let path = CString::new(exr.display().to_string()).unwrap();
    assert_eq!(
        unsafe { ct_image_write_exr(image, path.as_ptr()) },
        CtStatus::CT_OK
    );
    let (_, attributes) = read_exr(&exr).expect("partial EXR");
    assert!(attributes.incomplete);
    assert_eq!(ct_image_free(image), CtStatus::CT_OK);
    assert_eq!(ct_image_free(image), CtStatus::CT_ERROR_INVALID_HANDLE);
    assert_eq!(ct_scene_free(scene), CtStatus::CT_OK);
}

#[test]
fn a_cancelled_render_leaves_its_own_message() {
    // An unrelated failure first, whose message must not stand for the cancellation.
    let mut count = 0u32;
    let status = unsafe { ct_scene_texture_count(CtScene::default(), &mut count) };
    assert_eq!(status, CtStatus::CT_ERROR_INVALID_HANDLE);
    let stale = last_error();
    assert!(stale.contains("null"), "{stale}");

    let (scene, image, _) = render_cancelled_after_two_tiles();
    let message = last_error();
    assert_ne!(message, stale, "the message of an earlier failure was left");
    assert!(
        message.contains("cancelled by the progress callback"),
        "{message}"
    );
    // 320x180 in 16x16 tiles: 20 x 12.
    assert!(message.contains("of 240 tiles"), "{message}");
    assert_eq!(ct_image_free(image), CtStatus::CT_OK);
    assert_eq!(ct_scene_free(scene), CtStatus::CT_OK);
}

#[test]
fn image_writers_refuse_a_path_named_for_the_other_format() {
    let scene = default_scene();
    let options = small_options();
    let mut image = CtImage::default();
    let status = unsafe { ct_render(scene, &options, &mut image) };
    assert_eq!(status, CtStatus::CT_OK, "{}", last_error());
    let dir = common::temp_dir();
    let c_path = |name: &str| CString::new(dir.path().join(name).display().to_string()).unwrap();

    // Neither writer puts its format into a file named for another, nor creates the file.
    type Writer = unsafe extern "C" fn(CtImage, *const c_char) -> CtStatus;
    let cases: [(Writer, &str, &str); 4] = [
        (ct_image_write_png, "picture.exr", ".png"),
        (ct_image_write_png, "picture", ".png"),
        (ct_image_write_exr, "frame.png", ".exr"),
        (ct_image_write_exr, "frame.exr.tmp", ".exr"),
    ];
    for (write, name, expected) in cases {
        let status = unsafe { write(image, c_path(name).as_ptr()) };
        assert_eq!(status, CtStatus::CT_ERROR_INVALID_ARGUMENT, "{name}");
        let message = last_error();
        assert!(
            message.contains(name) && message.contains(expected),
            "{name}: {message}"
        );
        assert!(!dir.path().join(name).exists(), "{name} was written");
    }
    // An existing file under the wrong name is left as it was.
    let kept = common::write(dir.path(), "kept.exr", "not an image");
    let status = unsafe { ct_image_write_png(image, c_path("kept.exr").as_ptr()) };
    assert_eq!(status, CtStatus::CT_ERROR_INVALID_ARGUMENT);
    assert_eq!(std::fs::read_to_string(&kept).unwrap(), "not an image");

    // The right extensions, in any case, write their formats.
    for (write, name, magic) in [
        (ct_image_write_png as Writer, "ok.PNG", &b"\x89PNG"[..]),
        (
            ct_image_write_exr as Writer,
            "ok.Exr",
            &[0x76, 0x2f, 0x31, 0x01][..],
        ),
    ] {
        let status = unsafe { write(image, c_path(name).as_ptr()) };
        assert_eq!(status, CtStatus::CT_OK, "{name}: {}", last_error());
        let bytes = std::fs::read(dir.path().join(name)).expect(name);
        assert!(bytes.starts_with(magic), "{name} is not in its format");
    }
    assert_eq!(ct_image_free(image), CtStatus::CT_OK);
    assert_eq!(ct_scene_free(scene), CtStatus::CT_OK);
}

unsafe extern "C" fn red_textures(
    request: *const CtTextureRequest,
    rgba: *mut f32,
    user: *mut c_void,
) -> i32 {
    // SAFETY: valid during the call, per the callback contract; the test passes an AtomicUsize.
    let (request, rgba, calls) = unsafe {
        (
            &*request,
            std::slice::from_raw_parts_mut(rgba, 4),
            &*(user as *const AtomicUsize),
        )
    };
    calls.fetch_add(1, Ordering::Relaxed);
    assert_eq!(
        request.struct_size as usize,
        std::mem::size_of::<CtTextureRequest>()
    );
    let name = unsafe { CStr::from_ptr(request.texture_name) }.to_string_lossy();
    // The sky stays black so only surfaces turn red.
    if name == "sky" {
        rgba.copy_from_slice(&[0.0, 0.0, 0.0, 1.0]);
    } else {
        rgba.copy_from_slice(&[1.0, 0.0, 0.0, 1.0]);
    }
    0
}

unsafe extern "C" fn failing_textures(
    request: *const CtTextureRequest,
    _rgba: *mut f32,
    _user: *mut c_void,
) -> i32 {
    let name = unsafe { CStr::from_ptr((*request).texture_name) }.to_string_lossy();
    if name == "checker" {
        -7
    } else {
        0
    }
}

#[test]
fn the_texture_callback_serves_lookups_and_its_errors_stop_the_render() {
    let scene = default_scene();
    let calls = AtomicUsize::new(0);
    let mut options = small_options();
    options.texture_callback = Some(red_textures);
    options.texture_user_data = &calls as *const AtomicUsize as *mut c_void;
    let mut image = CtImage::default();
    let status = unsafe { ct_render(scene, &options, &mut image) };
    assert_eq!(status, CtStatus::CT_OK, "{}", last_error());
    assert!(
        calls.load(Ordering::Relaxed) > 100,
        "the callback was called"
    );
    let plane = |name: &str| -> Vec<f32> {
        let name = CString::new(name).unwrap();
        let mut index = 0u32;
        let mut pixels: *const f32 = std::ptr::null();
        let mut count = 0usize;
        unsafe {
            assert_eq!(
                ct_image_find_channel(image, name.as_ptr(), &mut index),
                CtStatus::CT_OK
            );
            assert_eq!(
                ct_image_channel_pixels(image, index, &mut pixels, &mut count),
                CtStatus::CT_OK
            );
            std::slice::from_raw_parts(pixels, count).to_vec()
        }
    };
    let (r, g) = (plane("albedo.R"), plane("albedo.G"));
    let red = r
        .iter()
        .zip(&g)
        .filter(|(r, g)| **r == 1.0 && **g == 0.0)
        .count();
    assert!(
        red > r.len() / 4,
        "the ground's albedo is the callback's red ({red} pixels)"
    );
    assert_eq!(ct_image_free(image), CtStatus::CT_OK);

    options.texture_callback = Some(failing_textures);
    options.texture_user_data = std::ptr::null_mut();
    let status = unsafe { ct_render(scene, &options, &mut image) };
    assert_eq!(status, CtStatus::CT_ERROR_CALLBACK);
    let message = last_error();
    assert!(
        message.contains("-7") && message.contains("checker"),
        "{message}"
    );
    assert_eq!(image, CtImage::default(), "no image after a callback error");
    // The scene is untouched and renders again.
    options.texture_callback = None;
    assert_eq!(
        unsafe { ct_render(scene, &options, &mut image) },
        CtStatus::CT_OK
    );
    assert_eq!(ct_image_free(image), CtStatus::CT_OK);
    assert_eq!(ct_scene_free(scene), CtStatus::CT_OK);
}

#[test]
fn texture_batches_match_the_library_filters() {
    let path = manifest_dir().join("assets/textures/checker.png");
    let c_path = CString::new(path.display().to_string()).unwrap();
    let mut texture = CtTexture::default();
    let status = unsafe { ct_texture_load(c_path.as_ptr(), CT_COLOR_SPACE_SRGB, &mut texture) };
    assert_eq!(status, CtStatus::CT_OK, "{}", last_error());
    let reference =
        conetrace::texture::Texture::from_file(&path, conetrace::texture::ColorSpace::Srgb)
            .expect("checker.png");
    let queries: Vec<CtTextureQuery> = (0..64)
        .map(|i| {
            let f = i as f32 / 64.0;
            CtTextureQuery {
                s: f * 3.1,
                t: 0.3 + f,
                dsdx: 0.001 + f * 0.05,
                dtdx: 0.002,
                dsdy: -0.001,
                dtdy: 0.004 * f,
            }
        })
        .collect();
    for filter in [
        CT_FILTER_CLOSEST,
        CT_FILTER_BILINEAR,
        CT_FILTER_TRILINEAR,
        CT_FILTER_ANISO,
        CT_FILTER_EWA,
    ] {
        let mut options = std::mem::MaybeUninit::<CtSampleOptions>::uninit();
        let status = unsafe {
            ct_sample_options_init(options.as_mut_ptr(), std::mem::size_of::<CtSampleOptions>())
        };
        assert_eq!(status, CtStatus::CT_OK);
        let mut options = unsafe { options.assume_init() };
        options.filter = filter;
        options.wrap_t = CT_WRAP_MIRROR;
        options.max_aniso = 8.0;
        let mut out = vec![0.0f32; 4 * queries.len()];
        let status = unsafe {
            ct_texture_sample(
                texture,
                &options,
                queries.as_ptr(),
                queries.len(),
                out.as_mut_ptr(),
            )
        };
        assert_eq!(status, CtStatus::CT_OK, "{}", last_error());
        let filter_mode = ["closest", "bilinear", "trilinear", "aniso", "ewa"][filter as usize];
        let opts = conetrace::texture::FilterOptions {
            filter: filter_mode.parse().unwrap(),
            wrap_s: conetrace::texture::WrapMode::Periodic,
            wrap_t: conetrace::texture::WrapMode::Mirror,
            max_aniso: 8.0,
        };
        for (q, rgba) in queries.iter().zip(out.chunks_exact(4)) {
            let expected = reference.sample(
                &conetrace::texture::TextureQuery {
                    s: q.s,
                    t: q.t,
                    dsdx: q.dsdx,
                    dtdx: q.dtdx,
                    dsdy: q.dsdy,
                    dtdy: q.dtdy,
                },
                &opts,
            );
            assert_eq!(rgba, expected.to_array(), "{filter_mode} at {q:?}");
        }
        // A wrong struct_size and NULL outputs are errors; nothing is written.
        options.struct_size = 3;
        let status =
            unsafe { ct_texture_sample(texture, &options, queries.as_ptr(), 1, out.as_mut_ptr()) };
        assert_eq!(status, CtStatus::CT_ERROR_STRUCT_SIZE);
        let status = unsafe {
            ct_texture_sample(
                texture,
                std::ptr::null(),
                queries.as_ptr(),
                1,
                std::ptr::null_mut(),
            )
        };
        assert_eq!(status, CtStatus::CT_ERROR_NULL_POINTER);
        // A NaN or infinite s or t is refused by index, and nothing is written (it used to
        // filter to NaN).
        options.struct_size = std::mem::size_of::<CtSampleOptions>() as u32;
        for bad in [f32::NAN, f32::INFINITY] {
            let mut odd = queries[..3].to_vec();
            odd[2].t = bad;
            let mut untouched = [7.0f32; 12];
            let status = unsafe {
                ct_texture_sample(texture, &options, odd.as_ptr(), 3, untouched.as_mut_ptr())
            };
            assert_eq!(status, CtStatus::CT_ERROR_INVALID_ARGUMENT, "{filter_mode}");
            assert!(last_error().contains("queries[2]"), "{}", last_error());
            assert_eq!(untouched, [7.0; 12]);
        }
    }
    let mut w = 0;
    let mut h = 0;
    assert_eq!(
        unsafe { ct_texture_size(texture, &mut w, &mut h) },
        CtStatus::CT_OK
    );
    assert_eq!((w, h), (reference.width(), reference.height()));
    assert_eq!(ct_texture_free(texture), CtStatus::CT_OK);
    assert_eq!(ct_texture_free(texture), CtStatus::CT_ERROR_INVALID_HANDLE);

    let missing = CString::new("/nonexistent.png").unwrap();
    let status = unsafe { ct_texture_load(missing.as_ptr(), CT_COLOR_SPACE_SRGB, &mut texture) };
    assert_eq!(status, CtStatus::CT_ERROR_TEXTURE);
    assert!(last_error().contains("/nonexistent.png"));
}

#[test]
fn version_and_status_names() {
    let version = unsafe { CStr::from_ptr(ct_version()) }.to_str().unwrap();
    assert_eq!(version, env!("CARGO_PKG_VERSION"));
    assert_eq!(ct_abi_version(), CT_ABI_VERSION);
    let name = unsafe { CStr::from_ptr(ct_status_name(CtStatus::CT_ERROR_CALLBACK as i32)) };
    assert_eq!(name.to_str().unwrap(), "CT_ERROR_CALLBACK");
    let unknown = unsafe { CStr::from_ptr(ct_status_name(-3)) };
    assert_eq!(unknown.to_str().unwrap(), "unknown status");
}

// ---- Textures the callback serves are not decoded by the library. ----

/// A scene whose sphere and sky use texture files in `dir` (written here as small PNGs), with
/// an optional alpha cut-out quad; loaded through `ct_scene_load_toml_string`.
fn scene_with_texture_files(dir: &Path, alpha_cutout: bool) -> CtScene {
    let png = |name: &str| {
        let path = dir.join(name);
        ::image::RgbaImage::from_pixel(8, 4, ::image::Rgba([40, 200, 90, 255]))
            .save(&path)
            .expect("write png");
    };
    png("ball.png");
    png("sky.png");
    let mut text = String::from(
        r#"
[render]
width = 48
height = 32

[camera]
type = "pinhole"
eye = [0.0, 0.0, 4.0]
target = [0.0, 0.0, 0.0]
fov = 60

[[texture]]
name = "ball"
file = "ball.png"

[[texture]]
name = "sky"
file = "sky.png"

[environment]
texture = "sky"

[[light]]
type = "point"
position = [2.0, 3.0, 4.0]
intensity = 30.0

[[material]]
name = "ball"
base_color = [1.0, 1.0, 1.0]
base_color_texture = "ball"

[[sphere]]
center = [0.0, 0.0, 0.0]
radius = 1.0
material = "ball"
"#,
    );
    if alpha_cutout {
        png("leaf.png");
        common::write(dir, "quad.obj", &common::square_obj(0.5, 1.5));
        text.push_str(
            r#"
[[texture]]
name = "leaf"
file = "leaf.png"
color_space = "linear"

[[material]]
name = "leaf"
base_color = [1.0, 1.0, 1.0]
alpha_texture = "leaf"
alpha_cutoff = 0.5

[[mesh]]
file = "quad.obj"
material = "leaf"
"#,
        );
    }
    let text = CString::new(text).unwrap();
    let base = CString::new(dir.display().to_string()).unwrap();
    let label = CString::new("files.toml").unwrap();
    let mut scene = CtScene::default();
    let status = unsafe {
        ct_scene_load_toml_string(text.as_ptr(), base.as_ptr(), label.as_ptr(), &mut scene)
    };
    assert_eq!(status, CtStatus::CT_OK, "{}", last_error());
    scene
}

/// The values of channel `name` of `image`.
fn image_plane(image: CtImage, name: &str) -> Vec<f32> {
    let name = CString::new(name).unwrap();
    let mut index = 0u32;
    let mut pixels: *const f32 = std::ptr::null();
    let mut count = 0usize;
    unsafe {
        assert_eq!(
            ct_image_find_channel(image, name.as_ptr(), &mut index),
            CtStatus::CT_OK
        );
        assert_eq!(
            ct_image_channel_pixels(image, index, &mut pixels, &mut count),
            CtStatus::CT_OK
        );
        std::slice::from_raw_parts(pixels, count).to_vec()
    }
}

#[test]
fn textures_served_by_the_callback_need_no_readable_file() {
    let dir = common::temp_dir();
    let scene = scene_with_texture_files(dir.path(), false);
    // The files were there when the scene loaded; now they are gone. Only the callback can
    // answer the lookups, so the library must not try to decode them.
    std::fs::remove_file(dir.path().join("ball.png")).unwrap();
    std::fs::remove_file(dir.path().join("sky.png")).unwrap();
    let calls = AtomicUsize::new(0);
    let mut options = small_options();
    options.width = 48;
    options.height = 32;
    options.texture_callback = Some(red_textures);
    options.texture_user_data = &calls as *const AtomicUsize as *mut c_void;
    let mut image = CtImage::default();
    let status = unsafe { ct_render(scene, &options, &mut image) };
    println!(
        "render with the callback and no files: {status:?} {}",
        last_error()
    );
    assert_eq!(status, CtStatus::CT_OK, "{}", last_error());
    assert!(
        calls.load(Ordering::Relaxed) > 100,
        "the callback was called"
    );
    let (r, g) = (
        image_plane(image, "albedo.R"),
        image_plane(image, "albedo.G"),
    );
    let red = r
        .iter()
        .zip(&g)
        .filter(|(r, g)| **r == 1.0 && **g == 0.0)
        .count();
    assert!(
        red > r.len() / 16,
        "the sphere's albedo is the callback's red ({red} pixels)"
    );
    assert_eq!(ct_image_free(image), CtStatus::CT_OK);

    // Without the callback the library needs the files, and says which one is missing.
    options.texture_callback = None;
    options.texture_user_data = std::ptr::null_mut();
    let status = unsafe { ct_render(scene, &options, &mut image) };
    assert_eq!(status, CtStatus::CT_ERROR_RENDER);
    assert!(last_error().contains("ball.png"), "{}", last_error());
    assert_eq!(ct_scene_free(scene), CtStatus::CT_OK);
}

#[test]
fn alpha_cutout_masks_are_read_by_the_library_even_with_a_callback() {
    let dir = common::temp_dir();
    let scene = scene_with_texture_files(dir.path(), true);
    std::fs::remove_file(dir.path().join("leaf.png")).unwrap();
    let mut options = small_options();
    options.texture_callback = Some(red_textures);
    let calls = AtomicUsize::new(0);
    options.texture_user_data = &calls as *const AtomicUsize as *mut c_void;
    let mut image = CtImage::default();
    let status = unsafe { ct_render(scene, &options, &mut image) };
    assert_eq!(status, CtStatus::CT_ERROR_RENDER);
    let message = last_error();
    assert!(
        message.contains("leaf.png") && message.contains("alpha"),
        "{message}"
    );
    assert_eq!(image, CtImage::default());
    assert_eq!(ct_scene_free(scene), CtStatus::CT_OK);
}

// ---- The progress callback does not hold up the workers. ----

/// What the progress and texture callbacks of the test below share.
struct ParkedProgress {
    /// Texture lookups answered so far: they only happen while workers render tiles.
    lookups: AtomicUsize,
    /// The lookups of the whole render (measured by an identical render beforehand).
    total_lookups: usize,
    /// Lookups when the first progress call started and when it returned.
    first_call: std::sync::Mutex<Option<(usize, usize)>>,
    /// The threads the progress callback ran on.
    threads: std::sync::Mutex<Vec<std::thread::ThreadId>>,
}

unsafe extern "C" fn counting_grey_textures(
    _request: *const CtTextureRequest,
    rgba: *mut f32,
    user: *mut c_void,
) -> i32 {
    // SAFETY: the test passes a ParkedProgress; rgba holds 4 floats during the call.
    let (state, rgba) = unsafe {
        (
            &*(user as *const ParkedProgress),
            std::slice::from_raw_parts_mut(rgba, 4),
        )
    };
    state.lookups.fetch_add(1, Ordering::SeqCst);
    rgba.copy_from_slice(&[0.5, 0.5, 0.5, 1.0]);
    0
}

/// On its first call, stays inside until every lookup of the render has happened (the
/// workers went on without it) or until the lookups stop advancing for 3 s (the workers
/// wait for it); records what it saw.
unsafe extern "C" fn parking_progress(_done: u32, _total: u32, user: *mut c_void) -> i32 {
    // SAFETY: the test passes a ParkedProgress.
    let state = unsafe { &*(user as *const ParkedProgress) };
    state
        .threads
        .lock()
        .unwrap()
        .push(std::thread::current().id());
    let mut first = state.first_call.lock().unwrap();
    if first.is_some() {
        return 0;
    }
    let at_entry = state.lookups.load(Ordering::SeqCst);
    let mut last = at_entry;
    let mut still_since = std::time::Instant::now();
    loop {
        let now = state.lookups.load(Ordering::SeqCst);
        if now >= state.total_lookups {
            break;
        }
        if now != last {
            last = now;
            still_since = std::time::Instant::now();
        } else if still_since.elapsed() > std::time::Duration::from_secs(3) {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(1));
    }
    *first = Some((at_entry, state.lookups.load(Ordering::SeqCst)));
    0
}

#[test]
fn workers_keep_rendering_while_the_progress_callback_runs() {
    let scene = default_scene();
    let mut options = small_options();
    options.width = 96;
    options.height = 64;
    options.threads = 2;
    options.texture_callback = Some(counting_grey_textures);

    // The number of lookups of this render, from an identical render without progress.
    let probe = ParkedProgress {
        lookups: AtomicUsize::new(0),
        total_lookups: usize::MAX,
        first_call: std::sync::Mutex::new(None),
        threads: std::sync::Mutex::new(Vec::new()),
    };
    options.texture_user_data = &probe as *const ParkedProgress as *mut c_void;
    let mut image = CtImage::default();
    assert_eq!(
        unsafe { ct_render(scene, &options, &mut image) },
        CtStatus::CT_OK
    );
    assert_eq!(ct_image_free(image), CtStatus::CT_OK);
    let total_lookups = probe.lookups.load(Ordering::SeqCst);
    assert!(total_lookups > 1000, "{total_lookups} lookups");

    let state = ParkedProgress {
        lookups: AtomicUsize::new(0),
        total_lookups,
        first_call: std::sync::Mutex::new(None),
        threads: std::sync::Mutex::new(Vec::new()),
    };
    options.texture_user_data = &state as *const ParkedProgress as *mut c_void;
    options.progress = Some(parking_progress);
    options.progress_user_data = &state as *const ParkedProgress as *mut c_void;
    let status = unsafe { ct_render(scene, &options, &mut image) };
    assert_eq!(status, CtStatus::CT_OK, "{}", last_error());
    assert_eq!(ct_image_free(image), CtStatus::CT_OK);
    assert_eq!(ct_scene_free(scene), CtStatus::CT_OK);

    let (at_entry, at_exit) = state
        .first_call
        .lock()
        .unwrap()
        .expect("progress was called");
    println!(
        "first progress call: {at_entry} lookups at entry, {at_exit} when it returned, \
         {total_lookups} in the render"
    );
    assert_eq!(
        at_exit, total_lookups,
        "the workers stopped while the progress callback ran ({at_exit} of {total_lookups} \
         lookups done when it gave up waiting)"
    );
    assert_eq!(state.lookups.load(Ordering::SeqCst), total_lookups);
    // Every call came on the thread that called ct_render.
    let threads = state.threads.lock().unwrap();
    assert!(
        threads.iter().all(|t| *t == std::thread::current().id()),
        "a progress call ran on a thread other than the caller's"
    );
}

// ---- The memory estimate, and renders refused by it. ----

fn memory_estimate(scene: CtScene, options: &CtRenderOptions) -> u64 {
    let mut bytes = 0u64;
    // SAFETY: valid options and out-pointer.
    let status = unsafe { ct_render_memory_estimate(scene, options, &mut bytes) };
    assert_eq!(status, CtStatus::CT_OK, "{}", last_error());
    bytes
}

#[test]
fn the_memory_estimate_bounds_the_render() {
    let scene = default_scene();
    let options = small_options();
    let estimate = memory_estimate(scene, &options);
    // The film grows with the image: four times the pixels, more than three times the bytes
    // (the textures stay the same).
    let mut larger = options;
    larger.width *= 2;
    larger.height *= 2;
    let film_part = memory_estimate(scene, &larger) - estimate;
    assert!(film_part > 3 * 64 * 48 * 4 * 4, "{film_part}");
    assert!(estimate > film_part / 3, "textures counted: {estimate}");

    // One byte less than the estimate is refused before anything is allocated.
    let mut limited = options;
    limited.max_memory = estimate - 1;
    let mut image = CtImage::default();
    // SAFETY: valid handles and out-pointer.
    let status = unsafe { ct_render(scene, &limited, &mut image) };
    assert_eq!(status, CtStatus::CT_ERROR_OUT_OF_MEMORY, "{}", last_error());
    assert_eq!(image, CtImage::default(), "no image on error");
    let message = last_error();
    println!("{message}");
    assert!(
        message.contains("needs about") && message.contains("max_memory"),
        "{message}"
    );

    // Exactly the estimate renders.
    limited.max_memory = estimate;
    // SAFETY: as above.
    let status = unsafe { ct_render(scene, &limited, &mut image) };
    assert_eq!(status, CtStatus::CT_OK, "{}", last_error());
    ct_image_free(image);
    ct_scene_free(scene);
}

#[test]
fn an_image_larger_than_memory_is_refused_not_aborted() {
    let scene = default_scene();
    let mut options = small_options();
    options.width = 65536;
    options.height = 65536;
    let estimate = memory_estimate(scene, &options);
    assert!(estimate > 65536 * 65536 * 16, "{estimate}");
    let mut image = CtImage::default();
    // SAFETY: valid handles and out-pointer.
    let status = unsafe { ct_render(scene, &options, &mut image) };
    let message = last_error();
    println!("{message}");
    assert_eq!(status, CtStatus::CT_ERROR_OUT_OF_MEMORY, "{message}");
    assert!(message.contains("available memory"), "{message}");
    // SAFETY: a valid out-pointer; NULL is what is being tested.
    let status = unsafe { ct_render_memory_estimate(scene, &options, std::ptr::null_mut()) };
    assert_eq!(status, CtStatus::CT_ERROR_NULL_POINTER);
    ct_scene_free(scene);
}

// ---- The integrator, chosen through the options. ----

/// A floor lit only by an emissive quad above it (no lights, black environment), whose
/// `[render] integrator` is Whitted: Whitted sees the quad but does not light the floor with
/// it, the path tracer does.
fn emissive_quad_scene(dir: &Path) -> CtScene {
    common::write(dir, "floor.obj", &common::square_obj(3.0, 0.0));
    common::write(dir, "lamp.obj", &common::square_obj(0.5, 0.0));
    let text = CString::new(
        r#"
[render]
width = 32
height = 24
spp = 16
integrator = "whitted"

[camera]
type = "pinhole"
eye = [0.0, 2.0, 4.0]
target = [0.0, 0.0, 0.0]
fov = 50

[[material]]
name = "floor"
base_color = [0.7, 0.7, 0.7]

[[material]]
name = "lamp"
base_color = [0.0, 0.0, 0.0]
emission = [5.0, 5.0, 5.0]

[[mesh]]
file = "floor.obj"
material = "floor"

[[mesh]]
file = "lamp.obj"
material = "lamp"
rotate = [180.0, 0.0, 0.0]
translate = [0.0, 1.5, 0.0]
"#,
    )
    .unwrap();
    let base = CString::new(dir.display().to_string()).unwrap();
    let label = CString::new("emissive.toml").unwrap();
    let mut scene = CtScene::default();
    let status = unsafe {
        ct_scene_load_toml_string(text.as_ptr(), base.as_ptr(), label.as_ptr(), &mut scene)
    };
    assert_eq!(status, CtStatus::CT_OK, "{}", last_error());
    scene
}

/// Mean of the R channel of `scene` rendered with `options`.
fn mean_red(scene: CtScene, options: &CtRenderOptions) -> f64 {
    let mut image = CtImage::default();
    let status = unsafe { ct_render(scene, options, &mut image) };
    assert_eq!(status, CtStatus::CT_OK, "{}", last_error());
    let red = image_plane(image, "R");
    assert_eq!(ct_image_free(image), CtStatus::CT_OK);
    red.iter().map(|&v| f64::from(v)).sum::<f64>() / red.len() as f64
}

#[test]
fn the_integrator_is_chosen_through_the_options() {
    let dir = common::temp_dir();
    let scene = emissive_quad_scene(dir.path());
    let with = |integrator: u32| {
        let mut options = small_options();
        options.integrator = integrator;
        mean_red(scene, &options)
    };
    let default = small_options();
    assert_eq!(default.integrator, CT_INTEGRATOR_SCENE);
    let scene_choice = mean_red(scene, &default);
    let whitted = with(CT_INTEGRATOR_WHITTED);
    let path = with(CT_INTEGRATOR_PATH);
    let auto = with(CT_INTEGRATOR_AUTO);
    eprintln!(
        "mean R: scene's choice (whitted) {scene_choice}, whitted {whitted}, path {path}, \
         auto {auto}"
    );
    // The floor is lit only by the path tracer: its image is much brighter.
    assert!(path > 1.5 * whitted, "path {path} vs whitted {whitted}");
    assert_eq!(scene_choice, whitted, "the scene asks for Whitted");
    // Auto picks the path tracer for emissive geometry (same seed: the same image).
    assert_eq!(auto, path);

    let mut options = small_options();
    options.integrator = 99;
    let mut image = CtImage::default();
    assert_eq!(
        unsafe { ct_render(scene, &options, &mut image) },
        CtStatus::CT_ERROR_INVALID_ARGUMENT
    );
    assert!(last_error().contains("integrator"), "{}", last_error());
    // The memory estimate checks the options as the render does.
    let mut bytes = 0u64;
    assert_eq!(
        unsafe { ct_render_memory_estimate(scene, &options, &mut bytes) },
        CtStatus::CT_ERROR_INVALID_ARGUMENT
    );
    assert!(last_error().contains("integrator"), "{}", last_error());
    // The voxel cone tracer's estimate holds its voxel pyramid on top of Whitted's.
    let estimate_with = |integrator: u32| {
        let mut options = small_options();
        options.integrator = integrator;
        let mut bytes = 0u64;
        let status = unsafe { ct_render_memory_estimate(scene, &options, &mut bytes) };
        assert_eq!(status, CtStatus::CT_OK, "{}", last_error());
        bytes
    };
    let (whitted_bytes, vct_bytes) = (
        estimate_with(CT_INTEGRATOR_WHITTED),
        estimate_with(CT_INTEGRATOR_VCT),
    );
    assert!(
        vct_bytes > whitted_bytes,
        "vct {vct_bytes} bytes, Whitted {whitted_bytes}"
    );

    // A caller built against the header before `integrator` existed: its struct ends at the
    // field, and it renders with the scene's integrator.
    let earlier_size = std::mem::offset_of!(CtRenderOptions, integrator);
    let mut earlier = std::mem::MaybeUninit::<CtRenderOptions>::uninit();
    // Bytes past the earlier struct hold garbage the library must not read.
    unsafe {
        std::ptr::write_bytes(earlier.as_mut_ptr().cast::<u8>(), 0xAB, size_of_options());
        assert_eq!(
            ct_render_options_init(earlier.as_mut_ptr(), earlier_size),
            CtStatus::CT_OK,
            "{}",
            last_error()
        );
    }
    let mut earlier = unsafe { earlier.assume_init() };
    assert_eq!(earlier.struct_size as usize, earlier_size);
    assert_eq!(
        earlier.integrator, 0xABAB_ABAB,
        "init wrote past the earlier size"
    );
    earlier.width = 64;
    earlier.height = 48;
    earlier.threads = 2;
    earlier.integrator = CT_INTEGRATOR_PATH; // past its struct_size: ignored
    assert_eq!(mean_red(scene, &earlier), whitted);
    assert_eq!(ct_scene_free(scene), CtStatus::CT_OK);
}

/// The largest red value of `scene` rendered with `options`.
fn max_red(scene: CtScene, options: &CtRenderOptions) -> f32 {
    let mut image = CtImage::default();
    let status = unsafe { ct_render(scene, options, &mut image) };
    assert_eq!(status, CtStatus::CT_OK, "{}", last_error());
    let red = image_plane(image, "R");
    assert_eq!(ct_image_free(image), CtStatus::CT_OK);
    red.into_iter().fold(0.0, f32::max)
}

/// `CtRenderOptions.clamp` caps every camera sample's largest component as `--clamp` does
/// (0: the scene's, here none); values that are not a finite number above 0 are refused; a
/// caller built against the header before `clamp` (its `struct_size` ends at the field)
/// renders unclamped.
#[test]
fn the_sample_clamp_is_set_through_the_options() {
    let dir = common::temp_dir();
    let scene = emissive_quad_scene(dir.path());
    let mut options = small_options();
    options.integrator = CT_INTEGRATOR_PATH;
    assert_eq!(options.clamp, 0.0);
    let free = max_red(scene, &options);
    options.clamp = 0.05;
    let clamped = max_red(scene, &options);
    eprintln!("largest red: {free} unclamped, {clamped} with clamp 0.05");
    assert!(free > 0.1, "unclamped {free}");
    assert!(clamped <= 0.05, "clamp 0.05 gave {clamped}");

    for bad in [-1.0, f64::NAN, f64::INFINITY] {
        options.clamp = bad;
        let mut image = CtImage::default();
        assert_eq!(
            unsafe { ct_render(scene, &options, &mut image) },
            CtStatus::CT_ERROR_INVALID_ARGUMENT,
            "clamp {bad}"
        );
        assert!(last_error().contains("clamp"), "{}", last_error());
        assert_eq!(image, CtImage::default());
    }

    let mut earlier = small_options();
    earlier.integrator = CT_INTEGRATOR_PATH;
    earlier.struct_size = std::mem::offset_of!(CtRenderOptions, clamp) as u32;
    earlier.clamp = 0.05; // past its struct_size: ignored
    assert_eq!(max_red(scene, &earlier), free);
    assert_eq!(ct_scene_free(scene), CtStatus::CT_OK);
}

fn size_of_options() -> usize {
    std::mem::size_of::<CtRenderOptions>()
}

#[test]
fn without_surface_aovs_the_image_has_colour_alone_and_the_same_colour() {
    // `CT_AOV_NO_SURFACE` drops Z, N, albedo and uv; the colour planes are those of a render
    // with them, bit for bit. Unknown flag bits next to it are still refused.
    let scene = default_scene();
    let channel_names = |image: CtImage| -> Vec<String> {
        let mut count = 0u32;
        assert_eq!(
            unsafe { ct_image_channel_count(image, &mut count) },
            CtStatus::CT_OK
        );
        (0..count)
            .map(|index| {
                let mut name: *const c_char = std::ptr::null();
                assert_eq!(
                    unsafe { ct_image_channel_name(image, index, &mut name) },
                    CtStatus::CT_OK
                );
                unsafe { CStr::from_ptr(name) }
                    .to_string_lossy()
                    .into_owned()
            })
            .collect()
    };
    let mut with = CtImage::default();
    let mut without = CtImage::default();
    let options = small_options();
    assert_eq!(
        unsafe { ct_render(scene, &options, &mut with) },
        CtStatus::CT_OK
    );
    let mut bare = small_options();
    bare.aovs = CT_AOV_NO_SURFACE;
    assert_eq!(
        unsafe { ct_render(scene, &bare, &mut without) },
        CtStatus::CT_OK
    );
    assert!(channel_names(with).contains(&"albedo.R".to_string()));
    assert_eq!(channel_names(without), ["R", "G", "B", "A"]);
    for channel in ["R", "G", "B", "A"] {
        let (a, b) = (image_plane(with, channel), image_plane(without, channel));
        assert!(a.iter().any(|&v| v > 0.0), "{channel} is black");
        assert!(
            a.iter().zip(&b).all(|(x, y)| x.to_bits() == y.to_bits()),
            "{channel} differs without the surface AOVs"
        );
    }
    let mut unknown = small_options();
    unknown.aovs = CT_AOV_NO_SURFACE | 8;
    let mut image = CtImage::default();
    assert_eq!(
        unsafe { ct_render(scene, &unknown, &mut image) },
        CtStatus::CT_ERROR_INVALID_ARGUMENT
    );
    assert!(last_error().contains("aovs"), "{}", last_error());
    assert_eq!(ct_image_free(with), CtStatus::CT_OK);
    assert_eq!(ct_image_free(without), CtStatus::CT_OK);
    assert_eq!(ct_scene_free(scene), CtStatus::CT_OK);
}

/// A quad textured with a 1024x1024 `.tx` (made by `maketx`, which must be installed:
/// scripts/setup.sh), seen at a slant.
fn tx_textured_scene(dir: &Path) -> CtScene {
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 56) as u8
    };
    let image =
        ::image::RgbImage::from_fn(1024, 1024, |_, _| ::image::Rgb([next(), next(), next()]));
    image.save(dir.join("noise.png")).unwrap();
    let status = Command::new("maketx")
        .arg(dir.join("noise.png"))
        .arg("-o")
        .arg(dir.join("noise.tx"))
        .status()
        .expect("maketx must be installed (scripts/setup.sh)");
    assert!(status.success(), "maketx failed");
    common::write(dir, "quad.obj", &common::square_obj(1.0, 0.0));
    let text = CString::new(
        r#"
[camera]
eye = [0.3, 1.5, 0.9]
target = [0.0, 0.0, 0.0]
fov = 40.0
[[light]]
type = "directional"
direction = [0.2, -1.0, -0.3]
[[texture]]
name = "t"
file = "noise.tx"
[[material]]
name = "m"
base_color = [1.0, 1.0, 1.0]
base_color_texture = "t"
[[mesh]]
file = "quad.obj"
material = "m"
"#,
    )
    .unwrap();
    let base = CString::new(dir.display().to_string()).unwrap();
    let label = CString::new("tx.toml").unwrap();
    let mut scene = CtScene::default();
    let status = unsafe {
        ct_scene_load_toml_string(text.as_ptr(), base.as_ptr(), label.as_ptr(), &mut scene)
    };
    assert_eq!(status, CtStatus::CT_OK, "{}", last_error());
    scene
}

/// `CtRenderOptions.texture_cache` caps the tiles of `.tx` textures (0: the default); a cap of
/// a few tiles gives the image of the default cap, bit for bit, and a caller built against
/// the header before the field (its `struct_size` ends at it) gets the default.
#[test]
fn the_texture_cache_cap_is_set_through_the_options_and_keeps_the_image() {
    let dir = common::temp_dir();
    let scene = tx_textured_scene(dir.path());
    let red = |options: &CtRenderOptions| {
        let mut image = CtImage::default();
        let status = unsafe { ct_render(scene, options, &mut image) };
        assert_eq!(status, CtStatus::CT_OK, "{}", last_error());
        let red = image_plane(image, "R");
        assert_eq!(ct_image_free(image), CtStatus::CT_OK);
        red.iter().map(|v| v.to_bits()).collect::<Vec<u32>>()
    };
    let mut options = small_options();
    options.lod = CT_LOD_MIP0;
    options.filter = CT_FILTER_BILINEAR;
    assert_eq!(options.texture_cache, 0);
    let default_cap = red(&options);
    options.texture_cache = 64 * 1024;
    assert_eq!(red(&options), default_cap, "a cap of 4 tiles");
    let mut earlier = options;
    earlier.struct_size = std::mem::offset_of!(CtRenderOptions, texture_cache) as u32;
    earlier.texture_cache = 1; // past its struct_size: ignored
    assert_eq!(red(&earlier), default_cap);
    assert_eq!(ct_scene_free(scene), CtStatus::CT_OK);
}
