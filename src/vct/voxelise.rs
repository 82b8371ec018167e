//! Conservative voxelisation: every level-0 voxel that any part of a triangle or a sphere's
//! surface touches becomes a fragment, with a point of the surface near the voxel's centre
//! where the light it sends out is evaluated (`inject`).
//!
//! Conservative means no gaps: a surface crossing a voxel only at a corner or an edge still
//! marks it, so a thin surface running diagonally through the grid leaves a connected wall
//! of voxels that cones cannot slip through. Each triangle is tested against the voxels of
//! its bounding box with the separating-axis test (`overlap`); the box is enlarged by a
//! relative 1e-4 so rounding never drops a voxel the surface touches.

use glam::Vec3;

use super::grid::GridFrame;
use super::overlap::{sphere_surface_box_overlap, triangle_box_overlap};
use crate::shading::SpawnPoint;

/// Relative enlargement of a voxel's box in the overlap tests.
const BOX_SLACK: f32 = 1e-4;

/// A surface touching one voxel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fragment {
    /// Level-0 voxel index (`GridFrame::index`).
    pub voxel: u32,
    /// The surface point nearest the voxel's centre (for triangles: the centre projected on
    /// the plane and clamped into the triangle), with its rounding-error bound.
    pub point: SpawnPoint,
    /// Unit geometric normal (either side; `inject` picks the lit one).
    pub normal: Vec3,
    /// Index into the scene's materials.
    pub material: u32,
}

/// The voxel range `lo..=hi` (clamped to the grid) covering the world box `(a, b)`, or
/// `None` when it lies outside the grid.
fn voxel_range(frame: &GridFrame, a: Vec3, b: Vec3) -> Option<([u32; 3], [u32; 3])> {
    let lo = frame.to_voxel(a).floor();
    let hi = frame.to_voxel(b).floor();
    let mut out_lo = [0u32; 3];
    let mut out_hi = [0u32; 3];
    for axis in 0..3 {
        let max = frame.dims[axis] as f32 - 1.0;
        if hi[axis] < 0.0 || lo[axis] > max || !lo[axis].is_finite() || !hi[axis].is_finite() {
            return None;
        }
        out_lo[axis] = lo[axis].clamp(0.0, max) as u32;
        out_hi[axis] = hi[axis].clamp(0.0, max) as u32;
    }
    Some((out_lo, out_hi))
}

/// The level-0 voxels `tri` touches, as `(x, y, z)`.
pub fn triangle_voxels(frame: &GridFrame, tri: [Vec3; 3], mut visit: impl FnMut([u32; 3])) {
    let a = tri[0].min(tri[1]).min(tri[2]);
    let b = tri[0].max(tri[1]).max(tri[2]);
    let Some((lo, hi)) = voxel_range(frame, a, b) else {
        return;
    };
    let half = Vec3::splat(0.5 * frame.voxel_size * (1.0 + BOX_SLACK));
    for z in lo[2]..=hi[2] {
        for y in lo[1]..=hi[1] {
            for x in lo[0]..=hi[0] {
                if triangle_box_overlap(frame.voxel_center(x, y, z), half, tri) {
                    visit([x, y, z]);
                }
            }
        }
    }
}

/// Barycentrics `(u, v)` (weights of `tri[1]`, `tri[2]`) of the point of `tri` nearest
/// `c` within its plane, clamped into the triangle; `None` for a degenerate triangle.
fn clamped_barycentrics(tri: [Vec3; 3], c: Vec3) -> Option<(f32, f32)> {
    let (e1, e2, q) = (tri[1] - tri[0], tri[2] - tri[0], c - tri[0]);
    let (d00, d01, d11) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let (d20, d21) = (q.dot(e1), q.dot(e2));
    let denom = d00 * d11 - d01 * d01;
    if denom <= f32::MIN_POSITIVE || !denom.is_finite() {
        return None;
    }
    let mut u = ((d11 * d20 - d01 * d21) / denom).max(0.0);
    let mut v = ((d00 * d21 - d01 * d20) / denom).max(0.0);
    if u + v > 1.0 {
        let s = u + v;
        u /= s;
        v /= s;
    }
    Some((u, v))
}

/// The fragments of triangle `tri` of material `material`, appended to `out`.
pub fn triangle_fragments(
    frame: &GridFrame,
    tri: [Vec3; 3],
    material: u32,
    out: &mut Vec<Fragment>,
) {
    let normal = (tri[1] - tri[0]).cross(tri[2] - tri[0]).normalize_or_zero();
    if normal == Vec3::ZERO {
        return;
    }
    triangle_voxels(frame, tri, |[x, y, z]| {
        let Some((u, v)) = clamped_barycentrics(tri, frame.voxel_center(x, y, z)) else {
            return;
        };
        out.push(Fragment {
            voxel: frame.index(x, y, z) as u32,
            point: SpawnPoint::on_triangle(tri, u, v),
            normal,
            material,
        });
    });
}

/// The fragments of the sphere (`center`, `radius`) of material `material`.
pub fn sphere_fragments(
    frame: &GridFrame,
    center: Vec3,
    radius: f32,
    material: u32,
    out: &mut Vec<Fragment>,
) {
    let r = Vec3::splat(radius);
    let Some((lo, hi)) = voxel_range(frame, center - r, center + r) else {
        return;
    };
    let half = Vec3::splat(0.5 * frame.voxel_size * (1.0 + BOX_SLACK));
    for z in lo[2]..=hi[2] {
        for y in lo[1]..=hi[1] {
            for x in lo[0]..=hi[0] {
                let c = frame.voxel_center(x, y, z);
                if !sphere_surface_box_overlap(center, radius, c - half, c + half) {
                    continue;
                }
                let (point, normal) = SpawnPoint::on_sphere(center, radius, c);
                out.push(Fragment {
                    voxel: frame.index(x, y, z) as u32,
                    point,
                    normal,
                    material,
                });
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeSet;

    fn unit_frame(n: u32) -> GridFrame {
        GridFrame {
            origin: Vec3::ZERO,
            voxel_size: 1.0,
            dims: [n; 3],
        }
    }

    #[test]
    fn axis_aligned_triangle_marks_exactly_the_voxels_it_covers() {
        // In the plane z = 2.5 (inside voxel layer 2, touching no face), legs from (0.2, 0.2)
        // to x = 3.3 and y = 3.3: the hypotenuse x + y = 3.5 passes through voxels with
        // i + j = 3 and misses those with i + j = 4 (whose nearest corner has x + y = 4).
        let tri = [
            Vec3::new(0.2, 0.2, 2.5),
            Vec3::new(3.3, 0.2, 2.5),
            Vec3::new(0.2, 3.3, 2.5),
        ];
        let mut got = BTreeSet::new();
        triangle_voxels(&unit_frame(8), tri, |v| {
            got.insert(v);
        });
        let mut expect = BTreeSet::new();
        for i in 0..4u32 {
            for j in 0..4u32 {
                if i + j <= 3 {
                    expect.insert([i, j, 2]);
                }
            }
        }
        assert_eq!(got, expect);
    }

    #[test]
    fn thin_diagonal_triangle_leaves_no_gaps() {
        // A sliver along the grid's main diagonal, far thinner than a voxel. Every voxel one
        // of its points lies in must be marked (conservative), and the marked voxels must be
        // 26-connected from one end to the other.
        let n = 16;
        let tri = [
            Vec3::new(0.1, 0.1, 0.1),
            Vec3::new(15.9, 15.9, 15.9),
            Vec3::new(15.9, 15.88, 15.9),
        ];
        let mut marked = BTreeSet::new();
        triangle_voxels(&unit_frame(n), tri, |v| {
            marked.insert(v);
        });
        // Dense point sampling of the triangle.
        let samples = 4000;
        for i in 0..=samples {
            for j in [0.0f32, 0.5, 1.0] {
                let s = i as f32 / samples as f32;
                let p = tri[0]
                    + (tri[1] - tri[0]) * s * (1.0 - 0.5 * j)
                    + (tri[2] - tri[0]) * s * 0.5 * j;
                let v = p.floor();
                let key = [v.x as u32, v.y as u32, v.z as u32];
                assert!(
                    marked.contains(&key),
                    "point {p} lies in unmarked voxel {key:?}"
                );
            }
        }
        // Connectivity: flood fill from the first voxel.
        let start = [0u32, 0, 0];
        assert!(marked.contains(&start));
        let mut seen = BTreeSet::from([start]);
        let mut stack = vec![start];
        while let Some([x, y, z]) = stack.pop() {
            for dz in -1i64..=1 {
                for dy in -1i64..=1 {
                    for dx in -1i64..=1 {
                        let q = [x as i64 + dx, y as i64 + dy, z as i64 + dz];
                        if q.iter().any(|&c| c < 0) {
                            continue;
                        }
                        let q = q.map(|c| c as u32);
                        if marked.contains(&q) && seen.insert(q) {
                            stack.push(q);
                        }
                    }
                }
            }
        }
        assert!(seen.contains(&[15, 15, 15]));
        assert_eq!(seen.len(), marked.len());
    }

    #[test]
    fn sphere_fragments_lie_on_the_sphere_in_their_voxels_shell() {
        let frame = unit_frame(10);
        let mut out = Vec::new();
        sphere_fragments(&frame, Vec3::splat(5.0), 3.0, 0, &mut out);
        assert!(!out.is_empty());
        for f in &out {
            assert!((f.point.position.distance(Vec3::splat(5.0)) - 3.0).abs() < 1e-4);
        }
        // The voxel holding the centre is inside the sphere, not on its surface.
        let centre = frame.index(5, 5, 5) as u32;
        assert!(out.iter().all(|f| f.voxel != centre));
    }
}
