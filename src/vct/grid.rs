//! The voxel grid: where it sits in the world (a [`GridFrame`]), how fine it is by default,
//! and its 3D mip pyramid ([`VoxelPyramid`]) with the quadrilinear lookup cones use.
//!
//! Voxels are cubes. `resolution` voxels span the longest side of the scene's bounds, and
//! half a voxel of margin surrounds the bounds on every side, so a surface lying on the
//! bounds is inside a voxel, not on the grid's edge. Other axes get as many voxels as their
//! extent needs (a flat scene gets a flat grid: dense, but not cubic).
//!
//! Voxels are built holding `[r, g, b, a]`: opacity `a` and radiance premultiplied by it
//! (`rgb = a * L`), so that averaging voxels is the alpha-weighted average of their
//! radiance (`mipmap`). Level `l` has voxels `2^l` times larger, `ceil(dims / 2)` of them per
//! axis; texels beyond a level's edge are empty (zero). Once built, every value is stored
//! as optical depth instead ([`to_optical_depth`]): `[tau L, tau]` with `tau = -ln(1 - a)`,
//! so that a lookup interpolates optical depth, not opacity. With [`VoxelKind::Directional`]
//! every level above 0 holds six such values per voxel, one for each axis direction a cone
//! may travel along (Crassin et al. 2011, sec. 3.1), and a lookup blends the three a
//! direction sees.

use glam::{Vec3, Vec3A, Vec4};

/// Default number of voxels along the longest side of the scene.
pub const DEFAULT_RESOLUTION: u32 = 128;
/// The default resolution is lowered until the whole pyramid fits in this many bytes.
pub const DEFAULT_MEMORY_BUDGET: u64 = 256 << 20;
/// Bytes of one voxel value (four `f32`).
pub const VOXEL_BYTES: u64 = 16;

/// How the levels above 0 represent a voxel.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum VoxelKind {
    /// Six values per voxel, one per axis direction of travel (Crassin et al. 2011, sec.
    /// 3.1): a surface one voxel thick stays opaque at every level seen along its normal.
    #[default]
    Directional,
    /// One value per voxel, the average of its children: thin surfaces are diluted at coarse
    /// levels (kept to measure the difference).
    Isotropic,
}

impl VoxelKind {
    /// The values stored per voxel at levels above 0.
    pub fn faces(self) -> usize {
        match self {
            VoxelKind::Directional => 6,
            VoxelKind::Isotropic => 1,
        }
    }

    /// The name `--vct-voxels` takes.
    pub fn name(self) -> &'static str {
        match self {
            VoxelKind::Directional => "directional",
            VoxelKind::Isotropic => "isotropic",
        }
    }
}

impl std::str::FromStr for VoxelKind {
    type Err = String;
    fn from_str(s: &str) -> Result<VoxelKind, String> {
        match s {
            "directional" => Ok(VoxelKind::Directional),
            "isotropic" => Ok(VoxelKind::Isotropic),
            _ => Err(format!(
                "unknown voxel kind `{s}` (expected directional or isotropic)"
            )),
        }
    }
}

/// The optical depth stored for an opaque voxel: a path one voxel long through it keeps
/// `e^-OPAQUE_DEPTH` (3.4e-4) of what is behind.
pub const OPAQUE_DEPTH: f32 = 8.0;

/// A built `[a L, a]` voxel value as the pyramid stores it, `[tau L, tau]` with
/// `tau = -ln(1 - a)` (at most [`OPAQUE_DEPTH`]).
///
/// Why: a lookup between voxel centres is a tent filter. Interpolating opacity, a sample
/// through a one-voxel opaque layer sees at most its centre's weight, and a cone crossing
/// it in half-voxel steps keeps `exp(int ln(|x|) dx) = e^-2` of what is behind (0.14
/// measured, through walls and emitters alike). Optical depth adds along a path, so the
/// tent's integral over the layer is the layer's own depth and the layer keeps what it
/// should; premultiplying radiance by it keeps the lookup's radiance a weighted mean.
#[inline]
pub fn to_optical_depth(value: [f32; 4]) -> [f32; 4] {
    let a = value[3];
    if a <= 0.0 {
        return [0.0; 4];
    }
    let tau = (-(1.0 - a).max((-OPAQUE_DEPTH).exp()).ln()).max(0.0);
    let scale = tau / a;
    [value[0] * scale, value[1] * scale, value[2] * scale, tau]
}

/// The face of a directional voxel seen by a cone travelling along `+axis` (`negative`
/// false) or `-axis`: `2 axis + negative`.
#[inline]
pub fn face_index(axis: usize, negative: bool) -> usize {
    2 * axis + usize::from(negative)
}

/// The three faces a unit direction sees and their weights, the squares of its components
/// (they sum to 1).
#[inline]
pub fn face_weights(direction: Vec3) -> [(usize, f32); 3] {
    let d = direction.to_array();
    std::array::from_fn(|axis| (face_index(axis, d[axis] < 0.0), d[axis] * d[axis]))
}

/// The placement of a voxel grid in world space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridFrame {
    /// World position of the corner of voxel (0, 0, 0).
    pub origin: Vec3,
    /// Edge length of a level-0 voxel.
    pub voxel_size: f32,
    /// Voxels per axis at level 0.
    pub dims: [u32; 3],
}

impl GridFrame {
    /// The frame with `resolution` voxels across the longest side of `(lo, hi)`, plus half a
    /// voxel of margin on every side. A degenerate (point-sized) scene gets unit extent.
    pub fn for_bounds(lo: Vec3, hi: Vec3, resolution: u32) -> GridFrame {
        let resolution = resolution.max(1);
        let extent = (hi - lo).max(Vec3::ZERO);
        let longest = extent.max_element().max(1e-6);
        let voxel_size = longest / resolution as f32;
        let origin = lo - Vec3::splat(0.5 * voxel_size);
        let count = |e: f32| ((e / voxel_size).ceil() as u32 + 1).max(1);
        GridFrame {
            origin,
            voxel_size,
            dims: [count(extent.x), count(extent.y), count(extent.z)],
        }
    }

    /// Level-0 voxel count.
    pub fn voxel_count(&self) -> u64 {
        self.dims.iter().map(|&d| u64::from(d)).product()
    }

    /// Continuous voxel coordinates of a world point (level-0 voxel `i` spans `[i, i+1)`).
    #[inline]
    pub fn to_voxel(&self, p: Vec3) -> Vec3 {
        (p - self.origin) / self.voxel_size
    }

    /// World centre of level-0 voxel `(x, y, z)`.
    #[inline]
    pub fn voxel_center(&self, x: u32, y: u32, z: u32) -> Vec3 {
        self.origin + (Vec3::new(x as f32, y as f32, z as f32) + 0.5) * self.voxel_size
    }

    /// Linear index of level-0 voxel `(x, y, z)` (x fastest).
    #[inline]
    pub fn index(&self, x: u32, y: u32, z: u32) -> usize {
        let [dx, dy, _] = self.dims;
        (x as usize) + (dx as usize) * ((y as usize) + (dy as usize) * (z as usize))
    }

    /// Whether a world point is inside the grid.
    #[inline]
    pub fn contains(&self, p: Vec3) -> bool {
        let v = self.to_voxel(p);
        v.cmpge(Vec3::ZERO).all()
            && v.x <= self.dims[0] as f32
            && v.y <= self.dims[1] as f32
            && v.z <= self.dims[2] as f32
    }

    /// The distance from a world point to the grid's box (0 inside it).
    #[inline]
    pub fn distance_outside(&self, p: Vec3) -> f32 {
        let dims = Vec3::new(
            self.dims[0] as f32,
            self.dims[1] as f32,
            self.dims[2] as f32,
        );
        let v = self.to_voxel(p);
        let outside = (-v).max(v - dims).max(Vec3::ZERO);
        outside.length() * self.voxel_size
    }

    /// Bytes of the whole pyramid of this frame (all levels) with voxels of `kind`.
    pub fn pyramid_bytes(&self, kind: VoxelKind) -> u64 {
        level_dims(self.dims)
            .iter()
            .enumerate()
            .map(|(l, d)| {
                let faces = if l == 0 { 1 } else { kind.faces() as u64 };
                d.iter().map(|&n| u64::from(n)).product::<u64>() * VOXEL_BYTES * faces
            })
            .sum()
    }
}

/// The default resolution for a scene with bounds `(lo, hi)`: [`DEFAULT_RESOLUTION`]
/// voxels across its longest side, halved until the pyramid of `kind` fits in `budget`
/// bytes.
pub fn default_resolution(lo: Vec3, hi: Vec3, budget: u64, kind: VoxelKind) -> u32 {
    let mut resolution = DEFAULT_RESOLUTION;
    while resolution > 8 && GridFrame::for_bounds(lo, hi, resolution).pyramid_bytes(kind) > budget {
        resolution /= 2;
    }
    resolution
}

/// The dimensions of every level, from level 0 up to the level of one voxel.
pub fn level_dims(dims: [u32; 3]) -> Vec<[u32; 3]> {
    let mut out = vec![dims];
    let mut d = dims;
    while d.iter().any(|&n| n > 1) {
        d = d.map(|n| n.div_ceil(2).max(1));
        out.push(d);
    }
    out
}

/// One level of the pyramid: `faces` premultiplied `[r, g, b, a]` values per voxel (1, or 6
/// in [`face_index`] order), voxels x fastest.
#[derive(Clone, Debug, PartialEq)]
pub struct VoxelLevel {
    pub dims: [u32; 3],
    pub faces: usize,
    pub voxels: Vec<[f32; 4]>,
}

impl VoxelLevel {
    /// An empty (transparent, black) level with one value per voxel.
    pub fn empty(dims: [u32; 3]) -> VoxelLevel {
        VoxelLevel::empty_with_faces(dims, 1)
    }

    /// An empty level with `faces` values per voxel.
    pub fn empty_with_faces(dims: [u32; 3], faces: usize) -> VoxelLevel {
        let count: usize = dims.iter().map(|&d| d as usize).product();
        VoxelLevel {
            dims,
            faces,
            voxels: vec![[0.0; 4]; count * faces],
        }
    }

    /// The linear index of the voxel at integer coordinates, `None` outside the level.
    #[inline]
    fn voxel_index(&self, x: i64, y: i64, z: i64) -> Option<usize> {
        let [dx, dy, dz] = self.dims.map(i64::from);
        if x < 0 || y < 0 || z < 0 || x >= dx || y >= dy || z >= dz {
            return None;
        }
        Some((x + dx * (y + dy * z)) as usize)
    }

    /// The voxel at integer coordinates (its first face), zero outside the level.
    #[inline]
    pub fn get(&self, x: i64, y: i64, z: i64) -> [f32; 4] {
        self.get_face(x, y, z, 0)
    }

    /// Face `face` of the voxel at integer coordinates (the only value of a one-face
    /// level, whatever `face`), zero outside the level.
    #[inline]
    pub fn get_face(&self, x: i64, y: i64, z: i64, face: usize) -> [f32; 4] {
        match self.voxel_index(x, y, z) {
            Some(i) if self.faces == 1 => self.voxels[i],
            Some(i) => self.voxels[i * self.faces + face],
            None => [0.0; 4],
        }
    }

    /// Trilinear interpolation between voxel centres at continuous coordinates `v` of this
    /// level (voxel `i` spans `[i, i+1)`, its centre is at `i + 0.5`), of the faces `faces`
    /// blended by their weights (one-face levels ignore which).
    #[inline]
    pub fn trilinear(&self, v: Vec3, faces: &[(usize, f32); 3]) -> [f32; 4] {
        let (corners, count) = self.corners(v);
        let corners = &corners[..count];
        let out = if self.faces == 1 {
            blend_voxels(&self.voxels, corners)
        } else {
            blend_voxel_faces(&self.voxels, self.faces, corners, faces)
        };
        out.to_array()
    }

    /// The voxels a trilinear lookup at `v` reads, as (index, weight), in corner order (x
    /// fastest), leaving out corners of zero weight and corners outside the level.
    #[inline]
    fn corners(&self, v: Vec3) -> ([(usize, f32); 8], usize) {
        let p = Vec3A::from(v) - Vec3A::splat(0.5);
        // Vec3A's floor is computed in vector registers, not by three calls to libm.
        let base = p.floor();
        let f = p - base;
        let (x0, y0, z0) = (base.x as i64, base.y as i64, base.z as i64);
        let [dx, dy, dz] = self.dims.map(i64::from);
        let weights = [[1.0 - f.x, f.x], [1.0 - f.y, f.y], [1.0 - f.z, f.z]];
        let mut corners = [(0usize, 0.0f32); 8];
        let mut count = 0;
        // Most lookups have all eight corners inside the level: one index and fixed
        // strides, no per-corner bounds test.
        let inside = x0 >= 0 && y0 >= 0 && z0 >= 0 && x0 + 1 < dx && y0 + 1 < dy && z0 + 1 < dz;
        let first = if inside {
            (x0 + dx * (y0 + dy * z0)) as usize
        } else {
            0
        };
        let (row, slice) = (dx as usize, (dx * dy) as usize);
        for corner in 0..8 {
            let (cx, cy, cz) = (corner & 1, (corner >> 1) & 1, (corner >> 2) & 1);
            let w = weights[0][cx] * weights[1][cy] * weights[2][cz];
            if w == 0.0 {
                continue;
            }
            let index = if inside {
                first + cx + row * cy + slice * cz
            } else {
                match self.voxel_index(x0 + cx as i64, y0 + cy as i64, z0 + cz as i64) {
                    Some(i) => i,
                    None => continue,
                }
            };
            corners[count] = (index, w);
            count += 1;
        }
        (corners, count)
    }
}

/// The sum of one-face voxels `corners` (index, weight), in their order.
#[inline]
fn blend_voxels(voxels: &[[f32; 4]], corners: &[(usize, f32)]) -> Vec4 {
    let mut out = Vec4::ZERO;
    for &(i, w) in corners {
        out += Vec4::splat(w) * Vec4::from_array(voxels[i]);
    }
    out
}

/// The sum of directional voxels `corners` (index, weight) of `face_count` faces each, of
/// the faces `faces` weighted by their weights, corner by corner and face by face.
#[inline]
fn blend_voxel_faces(
    voxels: &[[f32; 4]],
    face_count: usize,
    corners: &[(usize, f32)],
    faces: &[(usize, f32); 3],
) -> Vec4 {
    let mut out = Vec4::ZERO;
    for &(i, w) in corners {
        let voxel = &voxels[i * face_count..(i + 1) * face_count];
        for &(face, face_weight) in faces {
            out += Vec4::splat(w * face_weight) * Vec4::from_array(voxel[face]);
        }
    }
    out
}

/// The voxelised scene at every level of detail.
#[derive(Clone, Debug, PartialEq)]
pub struct VoxelPyramid {
    pub frame: GridFrame,
    pub kind: VoxelKind,
    /// Level 0 first (one value per voxel); the last level has one voxel per axis.
    pub levels: Vec<VoxelLevel>,
}

impl VoxelPyramid {
    /// The highest level index.
    pub fn max_level(&self) -> f32 {
        (self.levels.len() - 1) as f32
    }

    /// Bytes held by all levels.
    pub fn bytes(&self) -> u64 {
        self.levels
            .iter()
            .map(|l| l.voxels.len() as u64 * VOXEL_BYTES)
            .sum()
    }

    /// Quadrilinear lookup at world point `p` and fractional level `level` (clamped to the
    /// pyramid): trilinear within the two nearest levels, linear between them, as a
    /// trilinear mip-mapped texture lookup is bilinear within and linear across levels.
    /// Directional levels are seen by a cone travelling along the unit `direction`.
    pub fn sample(&self, p: Vec3, level: f32, direction: Vec3) -> [f32; 4] {
        let level = level.clamp(0.0, self.max_level());
        let lower = level.floor() as usize;
        let v = self.frame.to_voxel(p);
        let faces = face_weights(direction);
        let at = |l: usize| self.levels[l].trilinear(v / (1u32 << l) as f32, &faces);
        let t = level - lower as f32;
        if t == 0.0 || lower + 1 >= self.levels.len() {
            return at(lower);
        }
        // The upper level's corners hold the lower's parents, and a parent is empty only
        // when all its children are: an empty upper sample means an empty lower one, and
        // most of a scene is empty space.
        let b = at(lower + 1);
        if b[3] == 0.0 {
            return [0.0; 4];
        }
        let a = at(lower);
        std::array::from_fn(|i| a[i] + t * (b[i] - a[i]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_rng::{unit_f32, xorshift32};
    use crate::vct::mipmap::{build_pyramid, reduce_levels};
    use crate::vct::VoxelKind;

    /// A deterministic pseudo-random level 0 (xorshift), half the voxels empty.
    fn random_level(dims: [u32; 3]) -> VoxelLevel {
        let mut level = VoxelLevel::empty(dims);
        let mut state = 0x9E37_79B9u32;
        let mut next = || unit_f32(xorshift32(&mut state));
        for v in &mut level.voxels {
            if next() < 0.5 {
                let a = next();
                *v = [a * next(), a * next(), a * next(), a];
            }
        }
        level
    }

    /// The brute-force average of level 0 over the `2^l` block of level-`l` voxel
    /// `(x, y, z)`, voxels beyond the grid counting as empty.
    fn box_average(level0: &VoxelLevel, l: u32, x: i64, y: i64, z: i64) -> [f32; 4] {
        let s = 1i64 << l;
        let mut sum = [0.0f64; 4];
        for k in 0..s {
            for j in 0..s {
                for i in 0..s {
                    let t = level0.get(x * s + i, y * s + j, z * s + k);
                    for (a, b) in sum.iter_mut().zip(t) {
                        *a += f64::from(b);
                    }
                }
            }
        }
        sum.map(|a| (a / (s * s * s) as f64) as f32)
    }

    fn pyramid(dims: [u32; 3]) -> VoxelPyramid {
        let frame = GridFrame {
            origin: Vec3::new(-1.0, 2.0, 0.5),
            voxel_size: 0.25,
            dims,
        };
        build_pyramid(frame, random_level(dims), VoxelKind::Isotropic)
    }

    /// The levels of [`pyramid`] before they are stored as optical depth.
    fn opacity_levels(dims: [u32; 3]) -> Vec<VoxelLevel> {
        let frame = GridFrame {
            origin: Vec3::ZERO,
            voxel_size: 0.25,
            dims,
        };
        reduce_levels(frame, random_level(dims), VoxelKind::Isotropic)
    }

    fn close(a: [f32; 4], b: [f32; 4], tol: f32) -> bool {
        a.iter().zip(b).all(|(x, y)| (x - y).abs() <= tol)
    }

    #[test]
    fn every_level_is_the_box_average_of_level_zero() {
        // Odd dimensions: blocks at the far edges reach past the grid and count empty space.
        let levels = opacity_levels([13, 8, 5]);
        assert_eq!(levels.last().unwrap().dims, [1, 1, 1]);
        for (l, level) in levels.iter().enumerate().skip(1) {
            let [dx, dy, dz] = level.dims;
            for z in 0..dz as i64 {
                for y in 0..dy as i64 {
                    for x in 0..dx as i64 {
                        let expect = box_average(&levels[0], l as u32, x, y, z);
                        let got = level.get(x, y, z);
                        assert!(
                            close(got, expect, 1e-5),
                            "level {l} ({x},{y},{z}): {got:?} vs {expect:?}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn quadrilinear_lookup_matches_weighted_box_averages() {
        let p = pyramid([16, 12, 9]);
        let level0 = opacity_levels([16, 12, 9]).swap_remove(0);
        let frame = p.frame;
        let mut state = 7u32;
        let mut next = || {
            state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (state >> 8) as f32 / (1u32 << 24) as f32
        };
        for _ in 0..200 {
            let v = Vec3::new(next() * 16.0, next() * 12.0, next() * 9.0);
            let world = frame.origin + v * frame.voxel_size;
            let level = next() * 3.0;
            // Brute force: at each of the two levels, the eight box averages around the
            // point weighted by their distance to it.
            let brute_at = |l: u32| -> [f32; 4] {
                let s = (1u32 << l) as f32;
                let q = v / s - Vec3::splat(0.5);
                let b = q.floor();
                let f = q - b;
                let mut out = [0.0f32; 4];
                for corner in 0..8 {
                    let (cx, cy, cz) = (corner & 1, (corner >> 1) & 1, (corner >> 2) & 1);
                    let w = [f.x, f.y, f.z]
                        .iter()
                        .zip([cx, cy, cz])
                        .map(|(&t, c)| if c == 1 { t } else { 1.0 - t })
                        .product::<f32>();
                    let avg = to_optical_depth(box_average(
                        &level0,
                        l,
                        b.x as i64 + cx,
                        b.y as i64 + cy,
                        b.z as i64 + cz,
                    ));
                    for (o, a) in out.iter_mut().zip(avg) {
                        *o += w * a;
                    }
                }
                out
            };
            let lo = level.floor() as u32;
            let t = level - lo as f32;
            let (a, b) = (brute_at(lo), brute_at(lo + 1));
            let expect: [f32; 4] = std::array::from_fn(|i| a[i] + t * (b[i] - a[i]));
            let got = p.sample(world, level, Vec3::X);
            assert!(
                close(got, expect, 1e-4),
                "at {v} level {level}: {got:?} vs {expect:?}"
            );
        }
    }

    #[test]
    fn frame_spans_bounds_with_half_a_voxel_of_margin() {
        let f = GridFrame::for_bounds(Vec3::ZERO, Vec3::new(4.0, 1.0, 0.0), 8);
        assert_eq!(f.voxel_size, 0.5);
        assert_eq!(f.dims, [9, 3, 1]);
        assert!(f.contains(Vec3::new(4.0, 1.0, 0.0)));
        assert!(f.contains(Vec3::ZERO));
    }

    #[test]
    fn default_resolution_fits_the_budget() {
        let (lo, hi) = (Vec3::ZERO, Vec3::ONE);
        for kind in [VoxelKind::Directional, VoxelKind::Isotropic] {
            assert_eq!(default_resolution(lo, hi, DEFAULT_MEMORY_BUDGET, kind), 128);
            let small = default_resolution(lo, hi, 4 << 20, kind);
            assert!(GridFrame::for_bounds(lo, hi, small).pyramid_bytes(kind) <= 4 << 20);
            assert!(small < 128);
        }
    }
}
