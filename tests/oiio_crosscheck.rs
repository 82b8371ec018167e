//! Cross-check of the texture filters against OpenImageIO's TextureSystem.
//!
//! Each test writes its own textures (float OpenEXR and 8-bit PNG, power-of-two and
//! not, high-frequency content), turns them into mip-mapped textures with `maketx
//! --filter box`, looks a few hundred queries up with OIIO (tests/oiio/oiio_lookup.py
//! under /usr/bin/python3) and with our `conetrace sample-texture` binary on the
//! source image (which builds its own pyramid), and compares:
//! max |ours - OIIO| <= 1e-4 (float and 8-bit) for closest, bilinear, trilinear and
//! aniso in every wrap mode. Our pyramid levels must equal the levels `maketx` writes
//! within 1e-6 (float, and 8-bit, whose levels are stored as bytes rounded like maketx's).
//!
//! Queries whose anisotropic probe count (or magnification aspect rule) sits within
//! float rounding of a discontinuity are detected with an independent f64
//! computation; they are compared like the others, and for the `aniso` filter (the only
//! one with those discontinuities) a mismatch on them is printed and counted as a
//! rounding-boundary case instead of failing the test. The exemption is capped: at most
//! [`MAX_FLAGGED_SHARE`] of the queries may be flagged, at most
//! [`MAX_BOUNDARY_MISMATCHES`] lookups per texture may be exempted, and none by more than
//! [`MAX_BOUNDARY_DIFF`].
//!
//! If /usr/bin/python3 cannot import OpenImageIO the tests fail and name the set-up
//! command `bash scripts/setup.sh`.

use std::path::{Path, PathBuf};
use std::process::Command;

#[path = "oiio/lookup_support.rs"]
mod lookup_support;
use lookup_support::*;

/// Largest share of the queries the rounding-boundary detector may flag (35 of 223, 16 %,
/// with today's query sets: the exact aspect ratios 2, 3, 4, 8 and 16 sit on boundaries).
const MAX_FLAGGED_SHARE: f64 = 0.2;
/// Most aniso lookups (over the four wrap modes) of one texture that may differ from OIIO
/// beyond the tolerance because their query is flagged. None does today.
const MAX_BOUNDARY_MISMATCHES: usize = 4;
/// Largest exempted difference: a probe count one off (n vs n + 1 probes, n >= 2) moves an
/// average of values in [0, 1] by at most 1 / (n + 1) <= 1/3.
const MAX_BOUNDARY_DIFF: f64 = 1.0 / 3.0;

struct Case {
    name: &'static str,
    width: u32,
    height: u32,
    eight_bit: bool,
}

/// Writes the source image and returns (source path, maketx output path).
fn write_texture(dir: &Path, case: &Case) -> (PathBuf, PathBuf) {
    let tx = texels(
        case.width,
        case.height,
        case.width as u64 * 7919 + case.height as u64,
    );
    let (src, dst) = if case.eight_bit {
        let src = dir.join(format!("{}.png", case.name));
        // Opaque: OIIO's PNG reader premultiplies colour by alpha (associated
        // alpha) while we keep straight alpha, so a cross-check needs alpha = 1.
        let bytes: Vec<u8> = tx
            .iter()
            .flat_map(|t| {
                [t[0], t[1], t[2], 1.0].map(|v| (v * 255.0).round().clamp(0.0, 255.0) as u8)
            })
            .collect();
        image::RgbaImage::from_raw(case.width, case.height, bytes)
            .expect("buffer size")
            .save(&src)
            .expect("write png");
        (src, dir.join(format!("{}.tx", case.name)))
    } else {
        let src = dir.join(format!("{}.exr", case.name));
        let w = case.width as usize;
        exr::prelude::write_rgba_file(&src, w, case.height as usize, |x, y| {
            let t = tx[y * w + x];
            (t[0], t[1], t[2], t[3])
        })
        .expect("write exr");
        (src, dir.join(format!("{}_tex.exr", case.name)))
    };
    run(Command::new("maketx")
        .arg(&src)
        .arg("-o")
        .arg(&dst)
        .args(["--filter", "box"]));
    (src, dst)
}

fn crosscheck(case: Case) {
    require_oiio();
    let dir = tempfile::tempdir().expect("temp dir");
    let (src, tx) = write_texture(dir.path(), &case);
    let qs = queries(case.width, case.height, 42 + case.width as u64);
    let qpath = dir.path().join("queries.csv");
    write_queries(&qpath, &qs);
    let oiio_dir = dir.path().join("oiio");
    run(Command::new(PYTHON)
        .arg(script("oiio_lookup.py"))
        .arg(&tx)
        .arg(&qpath)
        .arg(&oiio_dir)
        .args(["--max-aniso", &MAX_ANISO.to_string()]));

    // 8-bit levels are rounded to bytes as maketx rounds them, so 8-bit textures meet
    // the float tolerance too.
    let tolerance = 1e-4;
    let boundary: Vec<bool> = qs
        .iter()
        .map(|q| on_rounding_boundary(q, case.width, case.height))
        .collect();
    let n_boundary = boundary.iter().filter(|b| **b).count();
    println!(
        "{}: {} queries, {} on a float rounding boundary",
        case.name,
        qs.len(),
        n_boundary
    );
    assert!(
        n_boundary as f64 <= MAX_FLAGGED_SHARE * qs.len() as f64,
        "{}: {n_boundary} of {} queries flagged as rounding-boundary cases (at most {:.0} %)",
        case.name,
        qs.len(),
        100.0 * MAX_FLAGGED_SHARE
    );
    let mut failures = Vec::new();
    let mut boundary_mismatches = 0;
    for filter in FILTERS {
        for wrap in WRAPS {
            let ours = run(Command::new(env!("CARGO_BIN_EXE_conetrace"))
                .arg("sample-texture")
                .arg(&src)
                .arg("--queries")
                .arg(&qpath)
                .args(["--filter", filter, "--wrap", wrap])
                .args(["--max-aniso", &MAX_ANISO.to_string()]));
            let ours = parse_rgba(&ours, "conetrace");
            let theirs_text =
                std::fs::read_to_string(oiio_dir.join(format!("{filter}_{wrap}.csv")))
                    .expect("OIIO output");
            let theirs = parse_rgba(&theirs_text, "oiio");
            assert_eq!(ours.len(), qs.len());
            assert_eq!(theirs.len(), qs.len());
            let mut max_diff = 0.0f64;
            for (i, (o, t)) in ours.iter().zip(&theirs).enumerate() {
                let d = (0..4).map(|c| (o[c] - t[c]).abs()).fold(0.0, f64::max);
                if d > tolerance {
                    if boundary[i] && filter == "aniso" && d <= MAX_BOUNDARY_DIFF {
                        boundary_mismatches += 1;
                        println!(
                            "  boundary case {filter}/{wrap} query {i} {:?}: ours {o:?} oiio {t:?} (diff {d:.3e})",
                            qs[i]
                        );
                        continue;
                    }
                    failures.push(format!(
                        "{filter}/{wrap} query {i} {:?}: ours {o:?} oiio {t:?} (diff {d:.3e})",
                        qs[i]
                    ));
                }
                if !(boundary[i] && filter == "aniso") {
                    max_diff = max_diff.max(d);
                }
            }
            println!("  {filter:9} {wrap:8} max |diff| = {max_diff:.3e}");
        }
    }
    println!(
        "{}: {} mismatches on rounding-boundary queries (exempted, at most {MAX_BOUNDARY_MISMATCHES})",
        case.name, boundary_mismatches
    );
    assert!(
        boundary_mismatches <= MAX_BOUNDARY_MISMATCHES,
        "{}: {boundary_mismatches} rounding-boundary mismatches, more than the \
         {MAX_BOUNDARY_MISMATCHES} allowed",
        case.name
    );
    assert!(
        failures.is_empty(),
        "{}: {} lookups differ from OIIO by more than {tolerance:e}:\n{}",
        case.name,
        failures.len(),
        failures[..failures.len().min(20)].join("\n")
    );
}

fn compare_levels(case: Case) {
    use conetrace::texture::{ColorSpace, Texture};
    require_oiio();
    let dir = tempfile::tempdir().expect("temp dir");
    let (src, tx) = write_texture(dir.path(), &case);
    let dump = dir.path().join("levels.bin");
    run(Command::new(PYTHON)
        .arg(script("oiio_levels.py"))
        .arg(&tx)
        .arg(&dump));
    let theirs = read_level_dump(&dump);
    let ours = Texture::from_file(&src, ColorSpace::Linear).expect("load source");
    // 8-bit levels are stored as bytes rounded like maketx's: equal, not half a step off.
    let tol = 1e-6;
    let check = |tex: &Texture, what: &str| {
        let levels = &tex.pyramid().levels;
        assert_eq!(levels.len(), theirs.len(), "{what}: level count");
        for (m, (l, (w, h, vals))) in levels.iter().zip(&theirs).enumerate() {
            assert_eq!((l.width, l.height), (*w, *h), "{what}: level {m} size");
            let max = l
                .to_rgba_f32()
                .iter()
                .flatten()
                .zip(vals)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0f32, f32::max);
            println!(
                "{} {what} level {m} ({w}x{h}): max |diff| = {max:.3e}",
                case.name
            );
            assert!(max <= tol, "{what}: level {m} differs from maketx by {max}");
        }
    };
    check(&ours, "built pyramid");
    if !case.eight_bit {
        // The maketx output itself, read level by level by our OpenEXR loader.
        let loaded = Texture::from_file(&tx, ColorSpace::Linear).expect("load maketx exr");
        check(&loaded, "loaded maketx levels");
    }
}

#[test]
fn float_pow2_matches_oiio() {
    crosscheck(Case {
        name: "float64",
        width: 64,
        height: 64,
        eight_bit: false,
    });
}

#[test]
fn float_non_pow2_matches_oiio() {
    crosscheck(Case {
        name: "float53x37",
        width: 53,
        height: 37,
        eight_bit: false,
    });
}

#[test]
fn png_pow2_matches_oiio() {
    crosscheck(Case {
        name: "png64x32",
        width: 64,
        height: 32,
        eight_bit: true,
    });
}

#[test]
fn png_non_pow2_matches_oiio() {
    crosscheck(Case {
        name: "png45x30",
        width: 45,
        height: 30,
        eight_bit: true,
    });
}

#[test]
fn float_levels_match_maketx() {
    compare_levels(Case {
        name: "lv_float",
        width: 128,
        height: 64,
        eight_bit: false,
    });
    compare_levels(Case {
        name: "lv_float_odd",
        width: 77,
        height: 45,
        eight_bit: false,
    });
}

#[test]
fn png_levels_match_maketx() {
    compare_levels(Case {
        name: "lv_png",
        width: 50,
        height: 34,
        eight_bit: true,
    });
}
