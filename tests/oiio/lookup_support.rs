//! Shared pieces of the OpenImageIO cross-checks: the OIIO/maketx precondition, the
//! deterministic query set, the CSV formats of `conetrace sample-texture` and
//! `oiio_lookup.py`, the level dump of `oiio_levels.py`, and the detection of queries
//! that sit within float rounding of a discontinuity of OIIO's filter.
//!
//! Included by path (`#[path = "oiio/lookup_support.rs"] mod lookup_support;`).

#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::Command;

/// The interpreter that has Debian's python3-openimageio.
pub const PYTHON: &str = "/usr/bin/python3";
pub const SETUP_HINT: &str =
    "run `bash scripts/setup.sh` (installs python3-openimageio and openimageio-tools)";
pub const FILTERS: [&str; 4] = ["closest", "bilinear", "trilinear", "aniso"];
pub const WRAPS: [&str; 4] = ["periodic", "clamp", "black", "mirror"];
pub const MAX_ANISO: f64 = 16.0;

/// The `tests/oiio` directory.
pub fn oiio_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests")
        .join("oiio")
}

/// A helper script in `tests/oiio`.
pub fn script(name: &str) -> PathBuf {
    oiio_dir().join(name)
}

/// Fails (never skips) when OIIO's Python module or `maketx` is missing.
pub fn require_oiio() {
    let ok = Command::new(PYTHON)
        .args(["-c", "import OpenImageIO, numpy"])
        .status()
        .map(|s| s.success())
        .unwrap_or(false);
    assert!(
        ok,
        "{PYTHON} cannot import OpenImageIO (and numpy): {SETUP_HINT}"
    );
    let maketx = Command::new("maketx").arg("--help").output();
    assert!(maketx.is_ok(), "maketx not found: {SETUP_HINT}");
}

/// Runs `cmd`, fails the test with its stderr if it fails, returns its stdout.
pub fn run(cmd: &mut Command) -> String {
    let out = cmd
        .output()
        .unwrap_or_else(|e| panic!("cannot run {cmd:?}: {e}"));
    assert!(
        out.status.success(),
        "{cmd:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// Small deterministic generator (64-bit LCG), so the test data never changes.
pub struct Lcg(pub u64);
impl Lcg {
    pub fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }
}

/// High-frequency RGBA content: per-texel noise, one-texel stripes, a checker, noisy alpha.
pub fn texels(w: u32, h: u32, seed: u64) -> Vec<[f32; 4]> {
    let mut rng = Lcg(seed);
    (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            [
                rng.next() as f32,
                (x % 2) as f32 * 0.8 + 0.1,
                ((x / 3 + y / 2) % 2) as f32,
                0.25 + 0.75 * rng.next() as f32,
            ]
        })
        .collect()
}

/// A few hundred queries: magnification, isotropic minification over all levels,
/// anisotropy 2..64 at several angles, footprints across the wrap boundary, zero
/// derivatives.
pub fn queries(w: u32, h: u32, seed: u64) -> Vec<[f64; 6]> {
    let mut rng = Lcg(seed);
    let texel = 1.0 / w.min(h) as f64;
    let mut q = Vec::new();
    let rot = |major: f64, minor: f64, angle: f64| {
        let (s, c) = angle.sin_cos();
        [major * c, major * s, -minor * s, minor * c]
    };
    let mut push = |rng: &mut Lcg, d: [f64; 4], near_edge: bool| {
        let (s, t) = if near_edge {
            let side = |rng: &mut Lcg| {
                if rng.next() < 0.5 {
                    rng.range(-0.02, 0.02)
                } else {
                    rng.range(0.98, 1.02)
                }
            };
            (side(rng), side(rng))
        } else {
            (rng.range(0.0, 1.0), rng.range(0.0, 1.0))
        };
        q.push([s, t, d[0], d[1], d[2], d[3]]);
    };
    for _ in 0..10 {
        push(&mut rng, [0.0; 4], false);
    }
    for _ in 0..40 {
        let m = rng.range(0.05, 0.95) * texel;
        let a = rng.range(0.0, std::f64::consts::PI);
        let squash = rng.range(0.3, 1.0);
        push(&mut rng, rot(m, m * squash, a), false);
    }
    let levels = (w.max(h) as f64).log2().ceil() as i32 + 1;
    for k in 0..=levels {
        for _ in 0..8 {
            let m = texel * 2f64.powf(k as f64 + rng.range(-0.5, 0.5));
            let a = rng.range(0.0, std::f64::consts::PI);
            push(&mut rng, rot(m, m, a), false);
        }
    }
    for ratio in [2.0, 3.0, 4.0, 8.0, 16.0, 32.0, 64.0] {
        for deg in [0.0, 15.0, 30.0, 45.0, 60.0, 90.0, 135.0] {
            let minor = texel * 2f64.powf(rng.range(-1.0, 3.0));
            push(
                &mut rng,
                rot(minor * ratio, minor, f64::to_radians(deg)),
                false,
            );
        }
    }
    for _ in 0..60 {
        let minor = texel * 2f64.powf(rng.range(-1.0, 4.0));
        let ratio = rng.range(1.0, 20.0);
        let a = rng.range(0.0, std::f64::consts::PI);
        push(&mut rng, rot(minor * ratio, minor, a), true);
    }
    q
}

/// Writes queries as `s,t,dsdx,dtdx,dsdy,dtdy`, each value the exact f32 both sides read.
pub fn write_queries(path: &Path, q: &[[f64; 6]]) {
    let mut text = String::from("s,t,dsdx,dtdx,dsdy,dtdy\n");
    for r in q {
        let f: Vec<String> = r.iter().map(|v| format!("{}", *v as f32)).collect();
        text.push_str(&f.join(","));
        text.push('\n');
    }
    std::fs::write(path, text).expect("write queries");
}

/// Rows of an `r,g,b,a` CSV.
pub fn parse_rgba(text: &str, what: &str) -> Vec<[f64; 4]> {
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("r,g,b,a"), "{what}: bad header");
    lines
        .filter(|l| !l.is_empty())
        .map(|l| {
            let v: Vec<f64> = l
                .split(',')
                .map(|x| {
                    x.parse()
                        .unwrap_or_else(|_| panic!("{what}: bad number {x}"))
                })
                .collect();
            assert_eq!(v.len(), 4, "{what}: row '{l}' has {} values", v.len());
            [v[0], v[1], v[2], v[3]]
        })
        .collect()
}

/// True when an f32 computation of OIIO's discontinuous steps (probe count,
/// magnification aspect rule) could land on the other side than an f64 one.
pub fn on_rounding_boundary(q: &[f64; 6], w: u32, h: u32) -> bool {
    let [_, _, dsdx, dtdx, dsdy, dtdy] = q.map(|v| v as f32 as f64);
    let a = dtdx * dtdx + dtdy * dtdy;
    let b = -2.0 * (dsdx * dtdx + dsdy * dtdy);
    let c = dsdx * dsdx + dsdy * dsdy;
    if a + c < 1e-14 {
        return false;
    }
    let root = (a - c).hypot(b);
    let major = ((a + c + root) * 0.5).max(0.0).sqrt();
    let minor = ((a + c - root) * 0.5).max(0.0).sqrt();
    let raw = if minor > 0.0 { major / minor } else { 1e6 };
    let flips = |raw: f64| {
        if raw > MAX_ANISO * (1.0 + 1e-4) {
            return false;
        }
        let x = 2.0 * raw.min(MAX_ANISO) - 1.0;
        x > 1.5 && (x - x.round()).abs() < 1e-4 * x
    };
    let mut boundary = flips(raw);
    let r = w.max(h) as f64;
    let (maj_c, min_c) = if raw > MAX_ANISO {
        let m = (major + minor * MAX_ANISO) * 0.5;
        (m, m / MAX_ANISO)
    } else {
        (major, minor)
    };
    if min_c * w.min(h) as f64 <= 1.0 {
        boundary |= (min_c * r - 0.5).abs() < 1e-5;
        if min_c * r < 0.5 {
            boundary |= flips(maj_c * r * 2.0);
        }
    }
    boundary
}

/// Levels as written by `oiio_levels.py`: (width, height, RGBA f32 texels).
pub fn read_level_dump(path: &Path) -> Vec<(u32, u32, Vec<f32>)> {
    let bytes = std::fs::read(path).expect("level dump");
    let u32_at = |o: usize| u32::from_le_bytes(bytes[o..o + 4].try_into().expect("4 bytes"));
    let n = u32_at(0) as usize;
    let mut off = 4;
    let mut levels = Vec::new();
    for _ in 0..n {
        let (w, h) = (u32_at(off), u32_at(off + 4));
        off += 8;
        let count = (w * h * 4) as usize;
        let vals = bytes[off..off + 4 * count]
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes(c.try_into().expect("4 bytes")))
            .collect();
        off += 4 * count;
        levels.push((w, h, vals));
    }
    levels
}
