//! Helpers shared by the whole-program tests: run the binary, write scene files, read EXRs.

#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The conetrace binary built for these tests.
pub fn conetrace() -> Command {
    Command::new(env!("CARGO_BIN_EXE_conetrace"))
}

/// Run conetrace with `args` in `dir`.
pub fn run_in(dir: &Path, args: &[&str]) -> Output {
    conetrace()
        .args(args)
        .current_dir(dir)
        .output()
        .expect("the conetrace binary runs")
}

/// A fresh temporary directory for one test.
pub fn temp_dir() -> tempfile::TempDir {
    tempfile::tempdir().expect("temporary directory")
}

/// Write `text` to `dir/name` and return the path.
pub fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, text).expect("write test file");
    path
}

/// An OBJ square in the plane y = `y`, from -half to +half in x and z, facing +y, with uvs.
pub fn square_obj(half: f32, y: f32) -> String {
    format!(
        "v {n} {y} {n}\nv {p} {y} {n}\nv {p} {y} {p}\nv {n} {y} {p}\n\
         vt 0 1\nvt 1 1\nvt 1 0\nvt 0 0\nvn 0 1 0\n\
         f 1/1/1 4/4/1 3/3/1\nf 1/1/1 3/3/1 2/2/1\n",
        n = -half,
        p = half,
        y = y
    )
}

/// Axis-aligned boxes `[lo, hi]` as one OBJ, each with 12 outward-facing triangles.
pub fn boxes_obj(boxes: &[([f32; 3], [f32; 3])]) -> String {
    use std::fmt::Write;
    let mut obj = String::new();
    for (index, (lo, hi)) in boxes.iter().enumerate() {
        for corner in 0..8 {
            let pick = |axis: usize| {
                if corner >> axis & 1 == 0 {
                    lo[axis]
                } else {
                    hi[axis]
                }
            };
            writeln!(obj, "v {} {} {}", pick(0), pick(1), pick(2)).unwrap();
        }
        // Quads counter-clockwise seen from outside: -x, +x, -y, +y, -z, +z.
        let quads = [
            [0, 4, 6, 2],
            [1, 3, 7, 5],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 2, 3, 1],
            [4, 5, 7, 6],
        ];
        let base = 1 + 8 * index;
        for q in quads {
            let [a, b, c, d] = q.map(|i| base + i);
            writeln!(obj, "f {a} {b} {c}\nf {a} {c} {d}").unwrap();
        }
    }
    obj
}

/// A UV sphere of `segments` x `rings` around `center` with radius `radius`, as OBJ with
/// unit vertex normals (smooth shading) and counter-clockwise (outward) winding.
pub fn uv_sphere_obj(center: [f64; 3], radius: f64, segments: usize, rings: usize) -> String {
    use std::fmt::Write;
    let mut obj = String::new();
    // Vertex 1: north pole; then rings - 1 rings of `segments` vertices; last: south pole.
    let vertex = |obj: &mut String, n: [f64; 3]| {
        let p = [
            center[0] + radius * n[0],
            center[1] + radius * n[1],
            center[2] + radius * n[2],
        ];
        writeln!(obj, "v {:.9} {:.9} {:.9}", p[0], p[1], p[2]).unwrap();
        writeln!(obj, "vn {:.9} {:.9} {:.9}", n[0], n[1], n[2]).unwrap();
    };
    vertex(&mut obj, [0.0, 1.0, 0.0]);
    for ring in 1..rings {
        let theta = std::f64::consts::PI * ring as f64 / rings as f64;
        for segment in 0..segments {
            let phi = 2.0 * std::f64::consts::PI * segment as f64 / segments as f64;
            vertex(
                &mut obj,
                [
                    theta.sin() * phi.cos(),
                    theta.cos(),
                    -theta.sin() * phi.sin(),
                ],
            );
        }
    }
    vertex(&mut obj, [0.0, -1.0, 0.0]);
    let south = 1 + (rings - 1) * segments + 1;
    let ring_vertex = |ring: usize, segment: usize| 2 + (ring - 1) * segments + segment % segments;
    let face = |obj: &mut String, a: usize, b: usize, c: usize| {
        writeln!(obj, "f {a}//{a} {b}//{b} {c}//{c}").unwrap();
    };
    for s in 0..segments {
        face(&mut obj, 1, ring_vertex(1, s), ring_vertex(1, s + 1));
        for ring in 1..rings - 1 {
            let (a, b) = (ring_vertex(ring, s), ring_vertex(ring, s + 1));
            let (c, d) = (ring_vertex(ring + 1, s), ring_vertex(ring + 1, s + 1));
            face(&mut obj, a, c, d);
            face(&mut obj, a, d, b);
        }
        face(
            &mut obj,
            ring_vertex(rings - 1, s),
            south,
            ring_vertex(rings - 1, s + 1),
        );
    }
    obj
}

/// An image read back from an EXR: width, height and named channels.
pub struct ExrImage {
    pub width: usize,
    pub height: usize,
    pub channels: Vec<(String, Vec<f32>)>,
}

impl ExrImage {
    pub fn channel(&self, name: &str) -> &[f32] {
        &self
            .channels
            .iter()
            .find(|(n, _)| n == name)
            .unwrap_or_else(|| panic!("channel {name} missing; have {:?}", self.names()))
            .1
    }
    pub fn names(&self) -> Vec<String> {
        self.channels.iter().map(|(n, _)| n.clone()).collect()
    }
    pub fn at(&self, name: &str, x: usize, y: usize) -> f32 {
        self.channel(name)[y * self.width + x]
    }
}

/// Read every channel of the first layer group of an EXR as f32.
pub fn read_exr(path: &Path) -> ExrImage {
    use exr::prelude::*;
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .from_file(path)
        .unwrap_or_else(|e| panic!("read {}: {e}", path.display()));
    let mut channels = Vec::new();
    let mut size = (0, 0);
    for layer in &image.layer_data {
        size = (layer.size.width(), layer.size.height());
        let prefix = layer
            .attributes
            .layer_name
            .as_ref()
            .map(|n| format!("{n}."))
            .unwrap_or_default();
        for channel in &layer.channel_data.list {
            let values: Vec<f32> = channel.sample_data.values_as_f32().collect();
            channels.push((format!("{prefix}{}", channel.name), values));
        }
    }
    ExrImage {
        width: size.0,
        height: size.1,
        channels,
    }
}

/// Small deterministic generator (xorshift64*), so tests need no extra crate and their data
/// never changes.
pub struct Rng(pub u64);

impl Rng {
    pub fn next_f32(&mut self) -> f32 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let bits = self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 40;
        bits as f32 / (1u64 << 24) as f32
    }
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.next_f32()
    }
    pub fn vec(&mut self, lo: f32, hi: f32) -> glam::Vec3 {
        glam::Vec3::new(self.range(lo, hi), self.range(lo, hi), self.range(lo, hi))
    }
    /// A unit vector, uniform over directions (rejection from the unit ball).
    pub fn direction(&mut self) -> glam::Vec3 {
        loop {
            let v = self.vec(-1.0, 1.0);
            let l = v.length();
            if l > 0.1 && l <= 1.0 {
                return v / l;
            }
        }
    }
}

/// Standard base64 with padding.
pub fn base64(bytes: &[u8]) -> String {
    const ALPHABET: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for chunk in bytes.chunks(3) {
        let n = chunk
            .iter()
            .enumerate()
            .fold(0u32, |n, (i, &b)| n | u32::from(b) << (16 - 8 * i));
        for i in 0..4 {
            if i <= chunk.len() {
                out.push(ALPHABET[(n >> (18 - 6 * i) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

/// A shipped scene (`scene`, relative to the repository) rendered small by `integrator`:
/// 40x30 at 2 spp, then `options` applied to the scene's own; its film and work counters.
pub fn render_small<I: conetrace::render::Integrator>(
    scene: &str,
    integrator: &I,
    options: impl Fn(&mut conetrace::render::RenderOptions),
) -> (
    conetrace::film::Film,
    conetrace::render::stats::WorkCounters,
) {
    use conetrace::render::{self, RenderControl, RenderOptions};
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(scene);
    let scene = conetrace::scene::load::load_scene(&path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut render_options = RenderOptions::from_settings(&scene.settings);
    render_options.width = 40;
    render_options.height = 30;
    render_options.spp = 2;
    options(&mut render_options);
    let context = render::prepare(std::sync::Arc::new(scene), render_options).expect("prepare");
    let result = render::render(&context, integrator, &RenderControl::default()).expect("render");
    (result.film, result.stats.counters)
}

/// Every channel of the two films, compared bit for bit; panics naming `what` and the first
/// channel that differs.
pub fn assert_same_bits(what: &str, a: &conetrace::film::Film, b: &conetrace::film::Film) {
    let names = b.channel_names();
    assert_eq!(a.channel_names(), names, "{what}");
    for name in &names {
        let (x, y) = (
            a.channel(name).expect("channel"),
            b.channel(name).expect("channel"),
        );
        assert_eq!(x.len(), y.len(), "{what}: {name}");
        let differing = x
            .iter()
            .zip(y)
            .filter(|(p, q)| p.to_bits() != q.to_bits())
            .count();
        assert_eq!(differing, 0, "{what}: {differing} values of {name} differ");
    }
}
