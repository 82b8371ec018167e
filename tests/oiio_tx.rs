//! `maketx` output (`.tx`: tiled, mip-mapped TIFF) read by our loader and compared with
//! OpenImageIO on the same file.
//!
//! Each test writes a source image, runs `maketx` on it (8-bit, 16-bit, half and float
//! data; one and four channels; square and non-power-of-two sizes; several tile sizes,
//! so levels span many tiles; deflate, LZW and PackBits; interleaved and separate
//! planes), then:
//! - checks that every level OIIO's `ImageBuf` reads from the `.tx`
//!   (tests/oiio/oiio_levels.py) is one of ours, with the same size and texels;
//! - looks the same few hundred queries up with `conetrace sample-texture FILE.tx` and
//!   with OIIO's TextureSystem on the same `.tx` (tests/oiio/oiio_lookup.py) for
//!   closest, bilinear, trilinear and aniso in every wrap mode, and requires
//!   max |ours - OIIO| <= 1e-4 (float data) or 1/255 (integer data), the limits of
//!   tests/oiio_crosscheck.rs; queries within float rounding of a discontinuity of
//!   OIIO's filter are reported, not failed, as there.
//!
//! One texture is made with a Lanczos filter, so its stored levels differ from the box
//! reduction of level 0 that our loader would build itself: the lookups must still match
//! OIIO, which proves the stored levels are the ones sampled.
//!
//! Without OpenImageIO's Python module or `maketx` the tests fail with the set-up command.

mod common;
#[path = "oiio/lookup_support.rs"]
mod lookup_support;

use std::path::{Path, PathBuf};
use std::process::Command;

use conetrace::texture::{ColorSpace, FilterMode, FilterOptions, Texture, TextureQuery, WrapMode};
use lookup_support::*;

/// What a test texture stores.
#[derive(Clone, Copy, PartialEq)]
enum Data {
    /// 8-bit RGBA PNG source; maketx keeps uint8.
    U8Rgba,
    /// 16-bit grey PNG source; maketx keeps uint16, one channel.
    U16Grey,
    /// float RGBA OpenEXR source, `maketx -d half`.
    Half,
    /// float RGBA OpenEXR source, `maketx -d float`.
    Float,
}

struct Case {
    name: &'static str,
    width: u32,
    height: u32,
    data: Data,
    /// Extra maketx arguments (tile size, compression, filter).
    maketx: &'static [&'static str],
}

impl Case {
    /// Channels stored in the `.tx`.
    fn channels(&self) -> usize {
        if self.data == Data::U16Grey {
            1
        } else {
            4
        }
    }

    fn tolerance(&self) -> f64 {
        match self.data {
            Data::U8Rgba | Data::U16Grey => 1.0 / 255.0,
            Data::Half | Data::Float => 1e-4,
        }
    }
}

/// Writes the source image, runs maketx, returns the `.tx` path.
fn make_tx(dir: &Path, case: &Case) -> PathBuf {
    let (w, h) = (case.width, case.height);
    let data = texels(w, h, w as u64 * 7919 + h as u64);
    let quantise = |v: f32, max: f32| (v * max).round().clamp(0.0, max);
    let src = match case.data {
        Data::U8Rgba => {
            let src = dir.join(format!("{}.png", case.name));
            let bytes = data
                .iter()
                .flat_map(|t| t.map(|v| quantise(v, 255.0) as u8))
                .collect();
            image::RgbaImage::from_raw(w, h, bytes)
                .expect("buffer size")
                .save(&src)
                .expect("write png");
            src
        }
        Data::U16Grey => {
            let src = dir.join(format!("{}.png", case.name));
            let grey = data
                .iter()
                .map(|t| quantise(t[0], 65535.0) as u16)
                .collect();
            image::ImageBuffer::<image::Luma<u16>, Vec<u16>>::from_raw(w, h, grey)
                .expect("buffer size")
                .save(&src)
                .expect("write png");
            src
        }
        Data::Half | Data::Float => {
            let src = dir.join(format!("{}.exr", case.name));
            let wu = w as usize;
            exr::prelude::write_rgba_file(&src, wu, h as usize, |x, y| {
                let t = data[y * wu + x];
                (t[0], t[1], t[2], t[3])
            })
            .expect("write exr");
            src
        }
    };
    let tx = dir.join(format!("{}.tx", case.name));
    let mut cmd = Command::new("maketx");
    cmd.arg(&src).arg("-o").arg(&tx).args(case.maketx);
    match case.data {
        Data::Half => {
            cmd.args(["-d", "half"]);
        }
        Data::Float => {
            cmd.args(["-d", "float"]);
        }
        Data::U8Rgba | Data::U16Grey => {}
    }
    run(&mut cmd);
    tx
}

/// Every level OIIO reads from `tx` must be one of ours, same size, same texels.
fn assert_levels_match_oiio(dir: &Path, case: &Case, tx: &Path) -> Texture {
    let dump = dir.join(format!("{}_levels.bin", case.name));
    run(Command::new(PYTHON)
        .arg(script("oiio_levels.py"))
        .arg(tx)
        .arg(&dump));
    let theirs = read_level_dump(&dump);
    let ours = Texture::from_file(tx, ColorSpace::Linear).expect("load .tx");
    let levels = &ours.pyramid().levels;
    let their_sizes: Vec<_> = theirs.iter().map(|(w, h, _)| (*w, *h)).collect();
    let our_sizes: Vec<_> = levels.iter().map(|l| (l.width, l.height)).collect();
    println!("{}: OIIO levels {their_sizes:?}", case.name);
    assert_eq!(our_sizes, their_sizes, "{}: level sizes", case.name);
    for (m, (l, (_, _, vals))) in levels.iter().zip(&theirs).enumerate() {
        let max = l
            .to_rgba_f32()
            .iter()
            .flatten()
            .zip(vals)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0f32, f32::max);
        assert!(
            max <= 1e-6,
            "{}: level {m} differs from OIIO's read by {max}",
            case.name
        );
    }
    ours
}

/// Our channel index for each channel OIIO returns from a texture of `channels` channels.
fn compared_channels(channels: usize) -> Vec<usize> {
    match channels {
        1 => vec![0],
        _ => vec![0, 1, 2, 3],
    }
}

/// Looks the queries up with OIIO on `tx`; returns `filter_wrap -> rows`.
fn oiio_lookups(dir: &Path, case: &Case, tx: &Path, qpath: &Path) -> PathBuf {
    let out = dir.join(format!("{}_oiio", case.name));
    run(Command::new(PYTHON)
        .arg(script("oiio_lookup.py"))
        .arg(tx)
        .arg(qpath)
        .arg(&out)
        .args(["--max-aniso", &MAX_ANISO.to_string()])
        .args(["--channels", &case.channels().to_string()]));
    out
}

fn crosscheck(case: Case) {
    require_oiio();
    let dir = tempfile::tempdir().expect("temp dir");
    let tx = make_tx(dir.path(), &case);
    assert_levels_match_oiio(dir.path(), &case, &tx);

    let qs = queries(case.width, case.height, 42 + case.width as u64);
    let qpath = dir.path().join("queries.csv");
    write_queries(&qpath, &qs);
    let oiio_out = oiio_lookups(dir.path(), &case, &tx, &qpath);
    let boundary: Vec<bool> = qs
        .iter()
        .map(|q| on_rounding_boundary(q, case.width, case.height))
        .collect();
    let tolerance = case.tolerance();
    let channels = compared_channels(case.channels());
    let mut failures = Vec::new();
    let mut boundary_mismatches = 0;
    let mut overall = 0.0f64;
    for filter in FILTERS {
        for wrap in WRAPS {
            let ours = run(Command::new(env!("CARGO_BIN_EXE_conetrace"))
                .arg("sample-texture")
                .arg(&tx)
                .arg("--queries")
                .arg(&qpath)
                .args(["--filter", filter, "--wrap", wrap])
                .args(["--max-aniso", &MAX_ANISO.to_string()]));
            let ours = parse_rgba(&ours, "conetrace");
            let theirs = std::fs::read_to_string(oiio_out.join(format!("{filter}_{wrap}.csv")))
                .expect("OIIO output");
            let theirs = parse_rgba(&theirs, "oiio");
            assert_eq!(ours.len(), qs.len());
            assert_eq!(theirs.len(), qs.len());
            let mut max_diff = 0.0f64;
            for (i, (o, t)) in ours.iter().zip(&theirs).enumerate() {
                let d = channels
                    .iter()
                    .enumerate()
                    .map(|(k, &c)| (o[c] - t[k]).abs())
                    .fold(0.0, f64::max);
                if d > tolerance {
                    let line = format!(
                        "{filter}/{wrap} query {i} {:?}: ours {o:?} oiio {t:?} (diff {d:.3e})",
                        qs[i]
                    );
                    if boundary[i] {
                        boundary_mismatches += 1;
                        println!("  boundary case {line}");
                    } else {
                        failures.push(line);
                    }
                }
                if !boundary[i] {
                    max_diff = max_diff.max(d);
                }
            }
            overall = overall.max(max_diff);
            println!("  {filter:9} {wrap:8} max |diff| = {max_diff:.3e}");
        }
    }
    println!(
        "{}: {} queries, {} on a rounding boundary, {boundary_mismatches} boundary mismatches, max |diff| = {overall:.3e}",
        case.name,
        qs.len(),
        boundary.iter().filter(|b| **b).count()
    );
    assert!(
        failures.is_empty(),
        "{}: {} lookups differ from OIIO by more than {tolerance:e}:\n{}",
        case.name,
        failures.len(),
        failures[..failures.len().min(20)].join("\n")
    );
}

#[test]
fn eight_bit_non_pow2_tx_matches_oiio() {
    crosscheck(Case {
        name: "u8_45x30",
        width: 45,
        height: 30,
        data: Data::U8Rgba,
        maketx: &["--filter", "box", "--tile", "16", "16"],
    });
}

#[test]
fn sixteen_bit_grey_lzw_tx_matches_oiio() {
    crosscheck(Case {
        name: "u16_grey_40x24",
        width: 40,
        height: 24,
        data: Data::U16Grey,
        maketx: &[
            "--filter",
            "box",
            "--tile",
            "16",
            "16",
            "--compression",
            "lzw",
        ],
    });
}

#[test]
fn half_non_pow2_tx_matches_oiio() {
    crosscheck(Case {
        name: "half_53x37",
        width: 53,
        height: 37,
        data: Data::Half,
        maketx: &["--filter", "box", "--tile", "32", "16", "--separate"],
    });
}

#[test]
fn float_tx_matches_oiio() {
    crosscheck(Case {
        name: "float_128x64",
        width: 128,
        height: 64,
        data: Data::Float,
        maketx: &["--filter", "box", "--compression", "packbits"],
    });
}

/// A `.tx` whose levels were made with a Lanczos filter: not what our own box
/// reduction of level 0 gives. Lookups must match OIIO, and a pyramid rebuilt from
/// level 0 must not (so the check can tell the two apart).
#[test]
fn stored_levels_that_are_not_box_reductions_are_the_ones_sampled() {
    let case = Case {
        name: "lanczos_96x64",
        width: 96,
        height: 64,
        data: Data::Float,
        maketx: &["--filter", "lanczos3", "--tile", "32", "32"],
    };
    require_oiio();
    let dir = tempfile::tempdir().expect("temp dir");
    let tx = make_tx(dir.path(), &case);
    let stored = assert_levels_match_oiio(dir.path(), &case, &tx);
    let rebuilt = stored
        .with_rebuilt_pyramid()
        .expect("box pyramid from level 0");
    let level_gap = stored.pyramid().levels[1]
        .to_rgba_f32()
        .iter()
        .flatten()
        .zip(rebuilt.pyramid().levels[1].to_rgba_f32().iter().flatten())
        .map(|(a, b)| (a - b).abs())
        .fold(0.0f32, f32::max);
    println!("level 1: stored vs box-rebuilt max |diff| = {level_gap:.3e}");
    assert!(
        level_gap > 1e-2,
        "maketx --filter lanczos3 wrote levels equal to a box reduction ({level_gap}); the test cannot tell them apart"
    );

    let qs = queries(case.width, case.height, 7);
    let qpath = dir.path().join("queries.csv");
    write_queries(&qpath, &qs);
    let oiio_out = oiio_lookups(dir.path(), &case, &tx, &qpath);
    for filter in ["trilinear", "aniso"] {
        let theirs = std::fs::read_to_string(oiio_out.join(format!("{filter}_periodic.csv")))
            .expect("OIIO output");
        let theirs = parse_rgba(&theirs, "oiio");
        let opts = FilterOptions {
            filter: filter.parse::<FilterMode>().expect("filter name"),
            wrap_s: WrapMode::Periodic,
            wrap_t: WrapMode::Periodic,
            max_aniso: MAX_ANISO as f32,
        };
        let (mut stored_diff, mut rebuilt_diff) = (0.0f64, 0.0f64);
        for (q, t) in qs.iter().zip(&theirs) {
            if on_rounding_boundary(q, case.width, case.height) {
                continue;
            }
            let q = TextureQuery {
                s: q[0] as f32,
                t: q[1] as f32,
                dsdx: q[2] as f32,
                dtdx: q[3] as f32,
                dsdy: q[4] as f32,
                dtdy: q[5] as f32,
            };
            let diff = |v: glam::Vec4| {
                (0..4)
                    .map(|c| (v[c] as f64 - t[c]).abs())
                    .fold(0.0, f64::max)
            };
            stored_diff = stored_diff.max(diff(stored.sample(&q, &opts)));
            rebuilt_diff = rebuilt_diff.max(diff(rebuilt.sample(&q, &opts)));
        }
        println!(
            "{filter}: stored levels max |diff| = {stored_diff:.3e}, box-rebuilt levels {rebuilt_diff:.3e}"
        );
        assert!(
            stored_diff <= 1e-4,
            "{filter}: lookups on the stored levels differ from OIIO by {stored_diff}"
        );
        assert!(
            rebuilt_diff > 1e-3,
            "{filter}: a box-rebuilt pyramid also matches OIIO ({rebuilt_diff}); the queries do not reach the coarser levels"
        );
    }
}

/// A `.tx` cut in half: `render` and `sample-texture` exit with status 2 and one line
/// naming the file, and write nothing.
#[test]
fn truncated_tx_is_rejected() {
    require_oiio();
    let dir = tempfile::tempdir().expect("temp dir");
    let case = Case {
        name: "whole",
        width: 64,
        height: 64,
        data: Data::U8Rgba,
        maketx: &["--filter", "box"],
    };
    let tx = make_tx(dir.path(), &case);
    let bytes = std::fs::read(&tx).expect("read .tx");
    std::fs::write(dir.path().join("cut.tx"), &bytes[..bytes.len() / 2]).expect("write cut");

    let scene = r#"
[render]
width = 8
height = 8

[camera]
type = "pinhole"
eye = [0.0, 1.0, 4.0]
target = [0.0, 0.0, 0.0]
up = [0.0, 1.0, 0.0]
fov = 40.0

[[light]]
type = "point"
position = [0.0, 4.0, 0.0]
color = [1.0, 1.0, 1.0]
intensity = 10.0

[[texture]]
name = "cut"
file = "cut.tx"

[[material]]
name = "matte"
base_color = [0.5, 0.5, 0.5]
base_color_texture = "cut"

[[sphere]]
center = [0.0, 0.0, 0.0]
radius = 1.0
material = "matte"
"#;
    common::write(dir.path(), "s.toml", scene);
    common::write(
        dir.path(),
        "q.csv",
        "s,t,dsdx,dtdx,dsdy,dtdy\n0.5,0.5,0,0,0,0\n",
    );
    let runs = [
        common::run_in(
            dir.path(),
            &["render", "s.toml", "-o", "out.exr", "--quiet"],
        ),
        common::run_in(
            dir.path(),
            &["sample-texture", "cut.tx", "--queries", "q.csv"],
        ),
    ];
    for out in runs {
        let stderr = String::from_utf8_lossy(&out.stderr);
        println!("stderr: {stderr}");
        assert_eq!(out.status.code(), Some(2), "stderr {stderr}");
        let lines: Vec<&str> = stderr.lines().filter(|l| !l.trim().is_empty()).collect();
        assert_eq!(lines.len(), 1, "expected one line, got {stderr:?}");
        assert!(
            lines[0].contains("cut.tx"),
            "'{}' does not name cut.tx",
            lines[0]
        );
        assert!(out.stdout.is_empty(), "something was printed to stdout");
    }
    assert!(!dir.path().join("out.exr").exists(), "an EXR was written");
    assert!(!dir.path().join("out.png").exists(), "a PNG was written");

    // The whole file loads, with every level of its chain.
    let whole = Texture::from_file(&tx, ColorSpace::Srgb).expect("whole .tx loads");
    assert_eq!(whole.level_count(), 7);
}

/// Renders `dir/s.toml` to `dir/out.exr` with `options`, fails the test (naming `what`)
/// if the render fails, and returns the image.
fn render_scene(dir: &Path, options: &[&str], what: &str) -> common::ExrImage {
    let mut args = vec!["render", "s.toml", "-o", "out.exr", "--quiet", "--no-png"];
    args.extend_from_slice(options);
    let out = common::run_in(dir, &args);
    assert!(
        out.status.success(),
        "{what}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    common::read_exr(&dir.join("out.exr"))
}

/// TIFFs as OpenImageIO writes them (libtiff: one SampleFormat value per channel) and a
/// `maketx` `.tx` made from one texture a render: the emission texture of a sphere seen
/// head-on gives its texel in the image, for 8-bit, 16-bit, half and float data. (The
/// render's memory estimate read the header with a single-valued SampleFormat and refused
/// every such file with "tag has invalid type".)
#[test]
fn tiffs_written_by_openimageio_and_maketx_texture_a_render() {
    require_oiio();
    let dir = common::temp_dir();
    let colour = [0.5f32, 0.25, 0.125];
    let pattern = format!("constant:color={},{},{}", colour[0], colour[1], colour[2]);
    let mut files = Vec::new();
    for depth in ["uint8", "uint16", "half", "float"] {
        let name = format!("{depth}.tif");
        run(Command::new("oiiotool").current_dir(dir.path()).args([
            "--pattern",
            &pattern,
            "16x8",
            "3",
            "-d",
            depth,
            "-o",
            &name,
        ]));
        files.push(name);
    }
    run(Command::new("maketx")
        .current_dir(dir.path())
        .args(["uint8.tif", "-o", "uint8.tx"]));
    files.push("uint8.tx".to_string());
    for file in &files {
        common::write(
            dir.path(),
            "s.toml",
            &format!(
                r#"
[render]
width = 9
height = 9
[camera]
eye = [0.0, 0.0, 4.0]
target = [0.0, 0.0, 0.0]
fov = 10.0
[[texture]]
name = "t"
file = "{file}"
color_space = "linear"
[[material]]
name = "m"
base_color = [0.0, 0.0, 0.0]
emission = [1.0, 1.0, 1.0]
emission_texture = "t"
[[sphere]]
center = [0.0, 0.0, 0.0]
radius = 1.0
material = "m"
"#
            ),
        );
        let image = render_scene(dir.path(), &["--integrator", "whitted"], file);
        for (channel, expected) in ["R", "G", "B"].iter().zip(colour) {
            let got = image.at(channel, 4, 4);
            // 8-bit data holds the colour to within half a step of 1/255.
            assert!(
                (got - expected).abs() <= 0.6 / 255.0,
                "{file}: {channel} = {got}, the texel is {expected}"
            );
        }
    }
}

/// A `.tx` made with a ringing filter (`maketx --filter lanczos3`) from a bright band on
/// black (rows 30-32, along the horizon of a lat-long map) holds negative texels in its coarser levels. Seen as an emission texture from
/// far (a coarse level) and as an environment map, it must render no negative radiance;
/// the emission rendered pixels of -0.27 here before (and, in a review, -0.23 through an
/// environment map).
#[test]
fn a_ringing_tx_renders_no_negative_radiance() {
    require_oiio();
    let dir = common::temp_dir();
    exr::prelude::write_rgb_file(dir.path().join("dot.exr"), 64, 64, |x, y| {
        let v = if (30..33).contains(&y) && x < 48 {
            10.0f32
        } else {
            0.0
        };
        (v, v, v)
    })
    .expect("dot.exr");
    run(Command::new("maketx").current_dir(dir.path()).args([
        "dot.exr", "--filter", "lanczos3", "-d", "float", "-o", "dot.tx",
    ]));
    let ringing =
        Texture::from_file(&dir.path().join("dot.tx"), ColorSpace::Linear).expect("dot.tx loads");
    let coarse_minimum = ringing.pyramid().levels[1..]
        .iter()
        .flat_map(|level| level.to_rgba_f32())
        .map(|t| t[0])
        .fold(f32::INFINITY, f32::min);
    assert!(
        coarse_minimum < -0.01,
        "maketx left no ringing: {coarse_minimum}"
    );
    common::write(dir.path(), "quad.obj", &common::square_obj(5.0, 0.0));
    let texture = "[[texture]]\nname = \"t\"\nfile = \"dot.tx\"\ncolor_space = \"linear\"\n";
    let emitter = r#"
[[material]]
name = "glow"
base_color = [0.0, 0.0, 0.0]
emission = [1.0, 1.0, 1.0]
emission_texture = "t"
texture_scale = [16.0, 16.0]
[[mesh]]
file = "quad.obj"
material = "glow"
"#;
    let camera = "[camera]\neye = [0.0, 5.0, 0.0]\ntarget = [0.0, 0.0, 0.0]\nup = [0.0, 0.0, -1.0]\nfov = 20.0\n";
    let sky = "[camera]\neye = [0.0, 0.0, 0.0]\ntarget = [0.0, 0.0, -1.0]\nfov = 120.0\n[environment]\ntexture = \"t\"\n";
    for (name, scene) in [
        ("emission", format!("{camera}{texture}{emitter}")),
        ("environment", format!("{sky}{texture}")),
    ] {
        common::write(dir.path(), "s.toml", &scene);
        for integrator in ["whitted", "path"] {
            let options = [
                "--width",
                "32",
                "--height",
                "32",
                "--spp",
                "4",
                "--filter",
                "trilinear",
                "--integrator",
                integrator,
            ];
            let image = render_scene(dir.path(), &options, name);
            let red = image.channel("R");
            let minimum = red.iter().copied().fold(f32::INFINITY, f32::min);
            let maximum = red.iter().copied().fold(f32::NEG_INFINITY, f32::max);
            println!("{name}, {integrator}: R in [{minimum}, {maximum}]");
            assert!(minimum >= 0.0, "{name}, {integrator}: a pixel of {minimum}");
            assert!(maximum > 0.0, "{name}, {integrator}: the band is not seen");
        }
    }
}
