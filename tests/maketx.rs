//! `conetrace maketx IN OUT.tx`: an untiled image becomes a tiled, mip-mapped TIFF that
//! renders read tile by tile, with the levels a render builds in memory, so the images are
//! the same bit for bit; OpenImageIO reads the file with the same texels and levels; OUT
//! never replaces IN; bad input is one line, exit status 2 and no file.
//!
//! The OpenImageIO check needs /usr/bin/python3 with the OpenImageIO module
//! (scripts/setup.sh); without it the test fails.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use conetrace::texture::{ColorSpace, Texture};

/// A `width` x `height` RGBA (or RGB) noise PNG at `dir/name`.
fn noise_png(dir: &Path, name: &str, width: u32, height: u32, alpha: bool) -> PathBuf {
    let mut rng = common::Rng(0x6d61_6b65_7478_0001);
    let path = dir.join(name);
    if alpha {
        image::RgbaImage::from_fn(width, height, |_, _| {
            image::Rgba(std::array::from_fn(|_| (rng.next_f32() * 255.0) as u8))
        })
        .save(&path)
        .unwrap();
    } else {
        image::RgbImage::from_fn(width, height, |_, _| {
            image::Rgb(std::array::from_fn(|_| (rng.next_f32() * 255.0) as u8))
        })
        .save(&path)
        .unwrap();
    }
    path
}

fn maketx(dir: &Path, args: &[&str]) -> Output {
    let mut all = vec!["maketx"];
    all.extend_from_slice(args);
    common::run_in(dir, &all)
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// A textured quad seen at a slant (so lookups span several levels) with `texture`.
fn scene(dir: &Path, texture: &str) {
    scene_stating(dir, texture, "");
}

/// [`scene`] with `color_space` (a line of the `[[texture]]` table, or nothing).
fn scene_stating(dir: &Path, texture: &str, color_space: &str) {
    common::write(dir, "quad.obj", &common::square_obj(1.0, 0.0));
    common::write(
        dir,
        "s.toml",
        &format!(
            r#"
[render]
width = 64
height = 48
[camera]
eye = [0.3, 0.9, 1.6]
target = [0.0, 0.0, -0.3]
fov = 50.0
[environment]
color = [0.2, 0.2, 0.2]
[[light]]
type = "directional"
direction = [0.2, -1.0, -0.3]
[[texture]]
name = "t"
file = "{texture}"
{color_space}
[[material]]
name = "m"
base_color = [1.0, 1.0, 1.0]
base_color_texture = "t"
[[mesh]]
file = "quad.obj"
material = "m"
"#
        ),
    );
}

/// Renders `s.toml` into `output` with `filter` and statistics in `stats`; returns the summary line
/// and the statistics.
fn render(dir: &Path, output: &str, stats: &str, filter: &str) -> (String, serde_json::Value) {
    let out = common::run_in(
        dir,
        &[
            "render",
            "s.toml",
            "-o",
            output,
            "--quiet",
            "--no-png",
            "--integrator",
            "whitted",
            "--stats",
            stats,
            "--filter",
            filter,
        ],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let json = serde_json::from_slice(&std::fs::read(dir.join(stats)).unwrap()).unwrap();
    (String::from_utf8_lossy(&out.stdout).into_owned(), json)
}

fn assert_same_pixels(a: &Path, b: &Path) {
    let (a, b) = (common::read_exr(a), common::read_exr(b));
    assert_eq!(a.names(), b.names());
    for (name, pixels) in &a.channels {
        let other = b.channel(name);
        let differing = pixels
            .iter()
            .zip(other)
            .filter(|(x, y)| x.to_bits() != y.to_bits())
            .count();
        assert_eq!(differing, 0, "channel {name}: {differing} pixels differ");
    }
}

#[test]
fn a_render_from_the_tx_equals_the_render_from_the_png_bit_for_bit() {
    let dir = common::temp_dir();
    for (alpha, filter) in [(false, "aniso"), (true, "trilinear"), (false, "ewa")] {
        noise_png(dir.path(), "in.png", 300, 200, alpha);
        let out = maketx(dir.path(), &["in.png", "in.tx"]);
        assert!(out.status.success(), "{}", stderr(&out));

        scene(dir.path(), "in.png");
        let (png_line, png_stats) = render(dir.path(), "png.exr", "png.json", filter);
        scene(dir.path(), "in.tx");
        let (tx_line, tx_stats) = render(dir.path(), "tx.exr", "tx.json", filter);
        assert_same_pixels(&dir.path().join("png.exr"), &dir.path().join("tx.exr"));

        // The PNG was decoded whole and says so; the .tx was read tile by tile.
        assert_eq!(png_stats["texture_memory"][0]["demand_loaded"], false);
        assert_eq!(tx_stats["texture_memory"][0]["demand_loaded"], true);
        assert!(
            png_line.contains("1 of 1 textures decoded whole in memory")
                && png_line.contains("conetrace maketx"),
            "{png_line}"
        );
        assert!(!tx_line.contains("decoded whole"), "{tx_line}");
        let tiles_read = tx_stats["texture_memory"][0]["tiles_read"]
            .as_u64()
            .unwrap();
        let in_file = tx_stats["texture_memory"][0]["tiles_in_file"]
            .as_u64()
            .unwrap();
        assert!(tiles_read >= 1 && tiles_read <= in_file);
        for stats in [&png_stats, &tx_stats] {
            let phases = &stats["phases"];
            let first_ray = phases["first_ray"].as_f64().expect("phases.first_ray");
            assert!(first_ray > 0.0 && first_ray <= phases["total"].as_f64().unwrap());
        }
    }
}

#[test]
fn half_and_float_images_keep_their_precision_and_levels() {
    use exr::prelude::*;
    let dir = common::temp_dir();
    let mut rng = common::Rng(99);
    let values: Vec<f32> = (0..90 * 70).map(|_| rng.range(0.0, 4.0)).collect();
    let half_path = dir.path().join("h.exr");
    write_rgb_file(&half_path, 90, 70, |x, y| {
        let v = f16::from_f32(values[y * 90 + x]);
        (v, f16::from_f32(0.5), v)
    })
    .unwrap();
    let float_path = dir.path().join("f.exr");
    write_rgb_file(&float_path, 90, 70, |x, y| {
        let v = values[y * 90 + x];
        (v, 0.25f32, -v)
    })
    .unwrap();
    for name in ["h", "f"] {
        let out = maketx(dir.path(), &[&format!("{name}.exr"), &format!("{name}.tx")]);
        assert!(out.status.success(), "{}", stderr(&out));
        let source =
            Texture::from_file_whole(&dir.path().join(format!("{name}.exr")), ColorSpace::Srgb)
                .unwrap();
        let tx_path = dir.path().join(format!("{name}.tx"));
        let demand = Texture::from_file(&tx_path, ColorSpace::Srgb).unwrap();
        assert!(demand.is_demand_loaded());
        let tx = Texture::from_file_whole(&tx_path, ColorSpace::Srgb).unwrap();
        assert_eq!(tx.pyramid(), source.pyramid(), "{name}: levels as built");
        assert_eq!(
            tx.memory_bytes(),
            source.memory_bytes(),
            "{name}: same precision"
        );
    }
}

/// Level count and level-0 texels of `tx` as OpenImageIO reads them (ImageInput), and the
/// colour space its TextureSystem reports.
fn oiio_levels_and_texels(tx: &Path, raw: &Path) -> (usize, String) {
    let script = r#"
import sys, OpenImageIO as oiio
tx, raw = sys.argv[1], sys.argv[2]
inp = oiio.ImageInput.open(tx)
assert inp, oiio.geterror()
pixels = inp.read_image(0, 0, 0, inp.spec().nchannels, "uint8")
open(raw, "wb").write(pixels.tobytes())
levels = 1
while inp.seek_subimage(0, levels):
    levels += 1
ts = oiio.TextureSystem()
print(levels, inp.spec().nchannels, ts.imagespec(tx).get_string_attribute("oiio:ColorSpace"))
"#;
    let out = Command::new("/usr/bin/python3")
        .args(["-c", script])
        .arg(tx)
        .arg(raw)
        .output()
        .expect("/usr/bin/python3 with OpenImageIO (scripts/setup.sh)");
    assert!(out.status.success(), "{}", stderr(&out));
    let text = String::from_utf8_lossy(&out.stdout);
    let fields: Vec<&str> = text.split_whitespace().collect();
    assert_eq!(fields.len(), 3, "{text}");
    assert_eq!(fields[1], "4", "RGBA");
    (fields[0].parse().unwrap(), fields[2].to_string())
}

#[test]
fn openimageio_reads_the_same_texels_and_levels() {
    let dir = common::temp_dir();
    let png = noise_png(dir.path(), "in.png", 200, 130, true);
    let out = maketx(dir.path(), &["in.png", "in.tx"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let raw = dir.path().join("level0.raw");
    let (levels, colour_space) = oiio_levels_and_texels(&dir.path().join("in.tx"), &raw);
    let ours = Texture::from_file_whole(&png, ColorSpace::Srgb).unwrap();
    assert_eq!(levels, ours.level_count());
    assert_eq!(colour_space, "sRGB");
    let source = image::open(&png).unwrap().to_rgba8().into_raw();
    assert_eq!(std::fs::read(&raw).unwrap(), source, "level 0 texels");
}

#[test]
fn the_input_is_never_the_output() {
    let dir = common::temp_dir();
    let png = noise_png(dir.path(), "in.png", 40, 30, false);
    let before = std::fs::read(&png).unwrap();
    std::os::unix::fs::symlink("in.png", dir.path().join("link.tx")).unwrap();
    std::fs::hard_link(&png, dir.path().join("hard.tx")).unwrap();
    let absolute = png.display().to_string();
    for output in [
        "in.png",
        "./in.png",
        absolute.as_str(),
        "link.tx",
        "hard.tx",
    ] {
        let out = maketx(dir.path(), &["in.png", output]);
        let message = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{output}: {message}");
        assert_eq!(message.trim().lines().count(), 1, "{message}");
        assert!(
            message.contains("the output is the input file"),
            "{message}"
        );
        assert_eq!(
            std::fs::read(&png).unwrap(),
            before,
            "{output}: IN unchanged"
        );
    }
    // A symbolic link as the input, the real file as the output.
    let out = maketx(dir.path(), &["link.tx", "in.png"]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert_eq!(std::fs::read(&png).unwrap(), before);
    let names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names.len(), 3, "no temporary file left: {names:?}");
}

#[test]
fn bad_input_is_one_line_naming_the_file_and_leaves_no_output() {
    let dir = common::temp_dir();
    let png = noise_png(dir.path(), "good.png", 64, 64, false);
    let bytes = std::fs::read(&png).unwrap();
    std::fs::write(dir.path().join("cut.png"), &bytes[..bytes.len() / 2]).unwrap();
    std::fs::write(dir.path().join("text.png"), b"not an image at all").unwrap();
    for (input, problem) in [
        ("cut.png", "cannot decode image"),
        ("missing.png", "cannot read file"),
        ("text.png", "unrecognised image format"),
    ] {
        let out = maketx(dir.path(), &[input, "out.tx"]);
        let message = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{input}: {message}");
        let line = message.trim();
        assert_eq!(line.lines().count(), 1, "{message}");
        assert!(
            line.contains(&format!("{input}: {problem}")),
            "{input}: {message}"
        );
        assert!(!dir.path().join("out.tx").exists(), "{input}: no output");
    }
    let names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names.len(), 3, "no temporary file left: {names:?}");
    // An existing output stays as it was when the input is bad.
    std::fs::write(dir.path().join("out.tx"), b"earlier").unwrap();
    let out = maketx(dir.path(), &["cut.png", "out.tx"]);
    assert_eq!(out.status.code(), Some(2));
    assert_eq!(
        std::fs::read(dir.path().join("out.tx")).unwrap(),
        b"earlier"
    );
}

#[test]
fn a_demand_loaded_file_is_identified_by_its_headers() {
    let dir = common::temp_dir();
    noise_png(dir.path(), "a.png", 130, 70, true);
    let out = maketx(dir.path(), &["a.png", "a.tx"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let tx = dir.path().join("a.tx");
    let texture = Texture::from_file(&tx, ColorSpace::Srgb).unwrap();
    let identity = texture.file_identity().expect("demand-loaded").to_vec();
    assert_eq!(identity[0], std::fs::metadata(&tx).unwrap().len());
    // 130x70 ... 1x1: 8 levels, each with its size, channels and two tile tables.
    let tiles: u64 = [
        (130, 70),
        (65, 35),
        (32, 17),
        (16, 8),
        (8, 4),
        (4, 2),
        (2, 1),
        (1, 1),
    ]
    .iter()
    .map(|&(w, h): &(u64, u64)| w.div_ceil(64) * h.div_ceil(64))
    .sum();
    assert_eq!(identity.len() as u64, 3 + 8 * 5 + 2 * tiles);
    // Other texels compress to other tile sizes: another identity.
    image::RgbaImage::from_pixel(130, 70, image::Rgba([9, 9, 9, 9]))
        .save(dir.path().join("b.png"))
        .unwrap();
    let out = maketx(dir.path(), &["b.png", "a.tx"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let again = Texture::from_file(&tx, ColorSpace::Srgb).unwrap();
    assert_ne!(again.file_identity().unwrap(), identity.as_slice());
    assert!(
        Texture::from_file(&dir.path().join("a.png"), ColorSpace::Srgb)
            .unwrap()
            .file_identity()
            .is_none()
    );
}

#[test]
fn a_tx_whose_scene_states_no_colour_space_is_decoded_in_the_one_it_records() {
    let dir = common::temp_dir();
    noise_png(dir.path(), "data.png", 150, 90, false);
    let out = maketx(
        dir.path(),
        &["--colorspace", "linear", "data.png", "data.tx"],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let render_stating = |color_space: &str, output: &str| {
        scene_stating(dir.path(), "data.tx", color_space);
        render(dir.path(), output, "s.json", "aniso");
        dir.path().join(output)
    };
    let unstated = render_stating("", "unstated.exr");
    let linear = render_stating("color_space = \"linear\"", "linear.exr");
    // The file records Linear: unstated is linear, bit for bit.
    assert_same_pixels(&unstated, &linear);
    // A colour space the scene states wins over the recorded one.
    let srgb = render_stating("color_space = \"srgb\"", "srgb.exr");
    let (a, b) = (common::read_exr(&srgb), common::read_exr(&linear));
    assert_ne!(a.channel("R"), b.channel("R"));
    // A .tx that records sRGB (the default of `conetrace maketx`) stays sRGB.
    let out = maketx(dir.path(), &["data.png", "colour.tx"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let colour = dir.path().join("colour.tx");
    assert_eq!(
        conetrace::texture::file_color_space(&colour),
        Some(ColorSpace::Srgb)
    );
    let tx = dir.path().join("data.tx");
    assert_eq!(
        conetrace::texture::file_color_space(&tx),
        Some(ColorSpace::Linear)
    );
    for whole in [false, true] {
        let load = |path: &Path, space: Option<ColorSpace>| match whole {
            true => Texture::from_file_whole(path, space).unwrap(),
            false => Texture::from_file(path, space).unwrap(),
        };
        assert_eq!(load(&tx, None).color_space(), Some(ColorSpace::Linear));
        assert_eq!(load(&colour, None).color_space(), Some(ColorSpace::Srgb));
        assert_eq!(
            load(&tx, Some(ColorSpace::Srgb)).color_space(),
            Some(ColorSpace::Srgb)
        );
    }
}

#[test]
fn a_demand_loaded_file_is_digested_from_its_headers_not_its_tiles() {
    // The render signature (`--resume`) of a .tx covers its length, modification time
    // and tile tables, never its tile bytes: texels rewritten in place, with the same
    // length and time, leave it as it was; a new time changes it.
    let dir = common::temp_dir();
    noise_png(dir.path(), "a.png", 300, 200, false);
    let out = maketx(dir.path(), &["--compression", "none", "a.png", "a.tx"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let tx = dir.path().join("a.tx");
    // What `resume::tiled_texture_digest` digests.
    let digest = || {
        let texture = Texture::from_file(&tx, ColorSpace::Srgb).unwrap();
        texture.file_identity().expect("demand-loaded").to_vec()
    };
    let before = digest();
    let modified = std::fs::metadata(&tx).unwrap().modified().unwrap();
    // Uncompressed, level 0's tiles come first and fill about three quarters of the file:
    // rewrite texels among them.
    let mut bytes = std::fs::read(&tx).unwrap();
    let middle = bytes.len() / 3;
    for byte in &mut bytes[middle..middle + 4096] {
        *byte = !*byte;
    }
    std::fs::write(&tx, &bytes).unwrap();
    let file = std::fs::File::options().write(true).open(&tx).unwrap();
    file.set_modified(modified).unwrap();
    drop(file);
    let whole = Texture::from_file_whole(&tx, ColorSpace::Srgb).unwrap();
    let original = Texture::from_file_whole(&dir.path().join("a.png"), ColorSpace::Srgb).unwrap();
    assert_ne!(
        whole.pyramid().levels[0],
        original.pyramid().levels[0],
        "the texels changed"
    );
    assert_eq!(digest(), before, "tile bytes are not digested");
    let file = std::fs::File::options().write(true).open(&tx).unwrap();
    file.set_modified(modified + std::time::Duration::from_secs(1))
        .unwrap();
    drop(file);
    assert_ne!(digest(), before, "the modification time is digested");
}
