//! Fog bounded by a closed triangle mesh: the parts of a line that lie inside it.
//!
//! A `[[fog]]` volume may fill a closed mesh instead of a box (`bounds = { mesh = ... }`).
//! Its density is integrated in closed form exactly as in a box; only the clipping differs:
//! a line may enter and leave a non-convex mesh several times, so a segment's inside is a
//! list of intervals rather than one.
//!
//! The intervals come from the winding number along the line. Every crossing of the
//! surface changes it by one: up where the line enters (its direction against the outward
//! normal), down where it leaves. Inside is where the count is positive. The crossings of
//! the whole infinite line are gathered, so the count at the segment's start is known
//! whether the segment starts inside or outside, and the intervals are then cut to the
//! segment. Triangles are tested in f64 (Moller-Trumbore with closed edges) through a
//! bounding-volume hierarchy; a line through a shared edge or vertex reports several
//! triangles at one distance, and such a cluster counts as one crossing, of the sign of its
//! sum (a line grazing a silhouette edge sums to zero: no crossing).
//!
//! Loading checks that the mesh can bound anything: every edge must be used once in each
//! direction (closed and consistently oriented) and the enclosed volume must not be zero.
//! A mesh wound inside out is turned outward.

use glam::DVec3;

use super::segment::{FogBox, Line};

/// Why a triangle mesh cannot bound fog.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum MeshBoundsError {
    #[error("has no triangles of non-zero area")]
    Empty,
    #[error("has a non-finite vertex")]
    NonFinite,
    #[error(
        "is not closed and consistently oriented: {unmatched} edge(s) are not used once in \
         each direction"
    )]
    NotClosed { unmatched: usize },
    #[error("encloses no volume")]
    NoVolume,
}

/// Triangles per leaf of the hierarchy, at most.
const LEAF_SIZE: usize = 4;

/// A node of the hierarchy: a box and either two children (`count == 0`, the first child
/// right after the node, the second at `first`) or `count` triangles from `first`.
#[derive(Clone, Debug, PartialEq)]
struct Node {
    bounds: FogBox,
    first: u32,
    count: u32,
}

/// A closed, consistently oriented triangle mesh in f64, outward-facing, with a hierarchy
/// over its triangles.
#[derive(Clone, Debug, PartialEq)]
pub struct ClosedMesh {
    triangles: Vec<[DVec3; 3]>,
    nodes: Vec<Node>,
    /// Distances closer than this (plus the same share of the distance itself) are one
    /// crossing: the rounding of one point seen through adjacent triangles.
    tolerance: f64,
}

impl ClosedMesh {
    /// Checks and builds the mesh from triangles given by their corners. Triangles of zero
    /// area are dropped first (they bound nothing).
    pub fn new(triangles: &[[DVec3; 3]]) -> Result<ClosedMesh, MeshBoundsError> {
        if triangles.iter().flatten().any(|p| !p.is_finite()) {
            return Err(MeshBoundsError::NonFinite);
        }
        let mut triangles: Vec<[DVec3; 3]> = triangles
            .iter()
            .copied()
            .filter(|[a, b, c]| (*b - *a).cross(*c - *a) != DVec3::ZERO)
            .collect();
        if triangles.is_empty() {
            return Err(MeshBoundsError::Empty);
        }
        let unmatched = unmatched_edges(&triangles);
        if unmatched > 0 {
            return Err(MeshBoundsError::NotClosed { unmatched });
        }
        let (lo, hi) = corners_bounds(triangles.iter().flatten());
        let center = (lo + hi) * 0.5;
        // Six times the signed volume, by the divergence theorem, about the centre for
        // fewer cancellations.
        let volume6: f64 = triangles
            .iter()
            .map(|[a, b, c]| (*a - center).dot((*b - center).cross(*c - center)))
            .sum();
        let extent = hi - lo;
        let scale = extent
            .max_element()
            .max(lo.abs().max(hi.abs()).max_element());
        if volume6.abs() <= 6e-12 * extent.x * extent.y * extent.z {
            return Err(MeshBoundsError::NoVolume);
        }
        if volume6 < 0.0 {
            for t in &mut triangles {
                t.swap(1, 2);
            }
        }
        let mut mesh = ClosedMesh {
            triangles,
            nodes: Vec::new(),
            tolerance: 1e-10 * scale,
        };
        mesh.build();
        Ok(mesh)
    }

    /// The parts of `[t0, t1]` (`t1` may be infinite) where `line` is inside the mesh, in
    /// order, each of positive length.
    pub fn inside_parts(&self, line: &Line, t0: f64, t1: f64) -> Vec<(f64, f64)> {
        if t1 <= t0 || slab(&self.nodes[0].bounds, line).is_none() {
            return Vec::new();
        }
        // Rounding can lose a crossing where the line passes exactly through an edge or a
        // vertex that no triangle then claims; the winding count then fails to return to
        // zero. The line is then moved aside by a few rounding units of the mesh, in turn
        // along two directions across it, which avoids the exact edge.
        let across = line.direction.any_orthonormal_pair();
        let nudges = [
            DVec3::ZERO,
            across.0 * self.tolerance,
            across.1 * self.tolerance,
            (across.0 + across.1) * (10.0 * self.tolerance),
        ];
        let mut whole = Vec::new();
        for nudge in nudges {
            let moved = Line {
                origin: line.origin + nudge,
                direction: line.direction,
            };
            let balanced;
            (whole, balanced) = self.whole_line_parts(&moved);
            if balanced {
                break;
            }
        }
        whole
            .into_iter()
            .filter_map(|(u0, u1)| {
                let (u0, u1) = (u0.max(t0), u1.min(t1));
                (u0 < u1).then_some((u0, u1))
            })
            .collect()
    }

    /// The parts of the infinite `line` inside the mesh, and whether the crossings
    /// balanced (the count never fell below zero and ended at zero).
    fn whole_line_parts(&self, line: &Line) -> (Vec<(f64, f64)>, bool) {
        let mut crossings = self.crossings(line);
        crossings.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut parts = Vec::new();
        let mut winding = 0i32;
        let mut balanced = true;
        let mut entered = f64::NEG_INFINITY;
        let mut index = 0;
        while index < crossings.len() {
            // One cluster: the crossings at one distance, up to rounding.
            let t = crossings[index].0;
            let mut sum = 0i32;
            while index < crossings.len()
                && crossings[index].0 - t <= self.tolerance + 1e-12 * t.abs()
            {
                sum += crossings[index].1;
                index += 1;
            }
            let before = winding;
            winding += sum.signum();
            balanced &= winding >= 0;
            if before <= 0 && winding > 0 {
                entered = t;
            } else if before > 0 && winding <= 0 {
                parts.push((entered, t));
            }
        }
        (parts, balanced && winding == 0)
    }

    /// Whether `p` lies inside the mesh (on the surface counts either way).
    pub fn contains(&self, p: DVec3) -> bool {
        // Any direction will do; one with no simple relation to the axes avoids running
        // along the faces and edges of axis-aligned meshes.
        let line = Line {
            origin: p,
            direction: DVec3::new(0.5417, 0.6823, 0.4909).normalize(),
        };
        self.inside_parts(&line, f64::NEG_INFINITY, f64::INFINITY)
            .iter()
            .any(|&(u0, u1)| u0 <= 0.0 && 0.0 <= u1)
    }

    /// Every crossing of the infinite `line` with a triangle: its distance and `+1` where
    /// the line enters (runs against the outward normal), `-1` where it leaves.
    fn crossings(&self, line: &Line) -> Vec<(f64, i32)> {
        let mut found = Vec::new();
        let mut stack = vec![0usize];
        while let Some(index) = stack.pop() {
            let node = &self.nodes[index];
            if slab(&node.bounds, line).is_none() {
                continue;
            }
            if node.count == 0 {
                stack.push(index + 1);
                stack.push(node.first as usize);
                continue;
            }
            let range = node.first as usize..(node.first + node.count) as usize;
            for triangle in &self.triangles[range] {
                if let Some(hit) = line_crossing(triangle, line) {
                    found.push(hit);
                }
            }
        }
        found
    }

    /// Builds the hierarchy by median splits along the longest axis of the centroids,
    /// reordering the triangles so that each leaf's are contiguous.
    fn build(&mut self) {
        let count = self.triangles.len();
        self.nodes.clear();
        self.build_range(0, count);
    }

    fn build_range(&mut self, first: usize, end: usize) -> usize {
        let index = self.nodes.len();
        let (lo, hi) = corners_bounds(self.triangles[first..end].iter().flatten());
        // Padded so that a flat box (a face lying in an axis plane) is still hit.
        let pad = DVec3::splat(self.tolerance);
        self.nodes.push(Node {
            bounds: FogBox {
                min: lo - pad,
                max: hi + pad,
            },
            first: first as u32,
            count: (end - first) as u32,
        });
        if end - first <= LEAF_SIZE {
            return index;
        }
        let centroid = |t: &[DVec3; 3]| (t[0] + t[1] + t[2]) / 3.0;
        let (clo, chi) = self.triangles[first..end].iter().map(centroid).fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), c| (lo.min(c), hi.max(c)),
        );
        let extent = chi - clo;
        let axis = if extent.x >= extent.y && extent.x >= extent.z {
            0
        } else if extent.y >= extent.z {
            1
        } else {
            2
        };
        let middle = first + (end - first) / 2;
        self.triangles[first..end].select_nth_unstable_by(middle - first, |a, b| {
            centroid(a)[axis].total_cmp(&centroid(b)[axis])
        });
        self.build_range(first, middle);
        let second = self.build_range(middle, end);
        self.nodes[index].first = second as u32;
        self.nodes[index].count = 0;
        index
    }
}

/// The distances at which the infinite `line` is inside `bounds` (faces included), or
/// `None` if it misses.
fn slab(bounds: &FogBox, line: &Line) -> Option<(f64, f64)> {
    let mut near = f64::NEG_INFINITY;
    let mut far = f64::INFINITY;
    for axis in 0..3 {
        let (o, d) = (line.origin[axis], line.direction[axis]);
        let (lo, hi) = (bounds.min[axis], bounds.max[axis]);
        if d == 0.0 {
            if o < lo || o > hi {
                return None;
            }
            continue;
        }
        let (a, b) = ((lo - o) / d, (hi - o) / d);
        near = near.max(a.min(b));
        far = far.min(a.max(b));
        if near > far {
            return None;
        }
    }
    Some((near, far))
}

/// Where the infinite `line` crosses `triangle` (closed edges), with `+1` if it runs
/// against the triangle's normal `(b - a) x (c - a)` and `-1` if along it; `None` if it
/// misses or lies in the triangle's plane.
fn line_crossing([a, b, c]: &[DVec3; 3], line: &Line) -> Option<(f64, i32)> {
    let e1 = *b - *a;
    let e2 = *c - *a;
    let p = line.direction.cross(e2);
    // det = -direction . ((b - a) x (c - a)): positive when entering.
    let det = e1.dot(p);
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let inverse = 1.0 / det;
    let s = line.origin - *a;
    let u = s.dot(p) * inverse;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = line.direction.dot(q) * inverse;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let t = e2.dot(q) * inverse;
    Some((t, if det > 0.0 { 1 } else { -1 }))
}

/// The box around `points`.
fn corners_bounds<'a>(points: impl Iterator<Item = &'a DVec3>) -> (DVec3, DVec3) {
    points.fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    )
}

/// How many undirected edges are not used exactly as often in one direction as in the
/// other, with corners welded by exact position.
fn unmatched_edges(triangles: &[[DVec3; 3]]) -> usize {
    use std::collections::HashMap;
    let key = |p: DVec3| (p.x.to_bits(), p.y.to_bits(), p.z.to_bits());
    let mut ids: HashMap<(u64, u64, u64), u32> = HashMap::new();
    let mut balance: HashMap<(u32, u32), i32> = HashMap::new();
    for triangle in triangles {
        let corner = triangle.map(|p| {
            let next = ids.len() as u32;
            *ids.entry(key(p)).or_insert(next)
        });
        for (from, to) in [(0, 1), (1, 2), (2, 0)] {
            let (i, j) = (corner[from], corner[to]);
            if i < j {
                *balance.entry((i, j)).or_default() += 1;
            } else {
                *balance.entry((j, i)).or_default() -= 1;
            }
        }
    }
    balance.values().filter(|&&b| b != 0).count()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_rng::{unit_f64, xorshift64};

    /// The 12 triangles of the box `[lo, hi]`, outward-facing.
    fn cube(lo: DVec3, hi: DVec3) -> Vec<[DVec3; 3]> {
        let p = |i: usize| {
            DVec3::new(
                if i & 1 == 0 { lo.x } else { hi.x },
                if i & 2 == 0 { lo.y } else { hi.y },
                if i & 4 == 0 { lo.z } else { hi.z },
            )
        };
        // Quads as corner indices, counter-clockwise seen from outside.
        let quads = [
            [0, 4, 6, 2], // -x
            [1, 3, 7, 5], // +x
            [0, 1, 5, 4], // -y
            [2, 6, 7, 3], // +y
            [0, 2, 3, 1], // -z
            [4, 5, 7, 6], // +z
        ];
        quads
            .iter()
            .flat_map(|q| [[p(q[0]), p(q[1]), p(q[2])], [p(q[0]), p(q[2]), p(q[3])]])
            .collect()
    }

    /// A U shape: three unit cubes along x at y in [0, 1], plus two cubes on the ends at
    /// y in [1, 2] (a gap over the middle), as one closed surface.
    fn u_shape() -> Vec<[DVec3; 3]> {
        // Built as a union of boxes sharing faces would leave internal faces; instead the
        // outline is extruded: the U's cross-section in (x, y) extruded along z in [0, 1].
        let outline = [
            (0.0, 0.0),
            (1.0, 0.0),
            (2.0, 0.0),
            (3.0, 0.0),
            (3.0, 2.0),
            (2.0, 2.0),
            (2.0, 1.0),
            (1.0, 1.0),
            (1.0, 2.0),
            (0.0, 2.0),
        ];
        let at = |(x, y): (f64, f64), z: f64| DVec3::new(x, y, z);
        let mut triangles = Vec::new();
        // Side walls: the outline runs counter-clockwise seen from +z.
        for i in 0..outline.len() {
            let (a, b) = (outline[i], outline[(i + 1) % outline.len()]);
            triangles.push([at(a, 0.0), at(b, 0.0), at(b, 1.0)]);
            triangles.push([at(a, 0.0), at(b, 1.0), at(a, 1.0)]);
        }
        // Caps: the U split into three rectangles, each fanned from a corner, with every
        // vertex on its edges included so that each edge is shared.
        let caps: [&[(f64, f64)]; 3] = [
            &[(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (1.0, 2.0), (0.0, 2.0)],
            &[(1.0, 0.0), (2.0, 0.0), (2.0, 1.0), (1.0, 1.0)],
            &[(3.0, 0.0), (3.0, 2.0), (2.0, 2.0), (2.0, 1.0), (2.0, 0.0)],
        ];
        for cap in caps {
            for i in 1..cap.len() - 1 {
                triangles.push([at(cap[0], 1.0), at(cap[i], 1.0), at(cap[i + 1], 1.0)]);
                triangles.push([at(cap[0], 0.0), at(cap[i + 1], 0.0), at(cap[i], 0.0)]);
            }
        }
        triangles
    }

    fn line(origin: [f64; 3], direction: [f64; 3]) -> Line {
        Line {
            origin: DVec3::from(origin),
            direction: DVec3::from(direction).normalize(),
        }
    }

    fn close(a: &[(f64, f64)], b: &[(f64, f64)]) -> bool {
        a.len() == b.len()
            && a.iter()
                .zip(b)
                .all(|(x, y)| (x.0 - y.0).abs() < 1e-12 && (x.1 - y.1).abs() < 1e-12)
    }

    #[test]
    fn a_cube_mesh_clips_like_its_box() {
        let (lo, hi) = (DVec3::splat(-1.0), DVec3::splat(1.0));
        let mesh = ClosedMesh::new(&cube(lo, hi)).unwrap();
        let boxed = FogBox { min: lo, max: hi };
        let mut state = 7u64;
        let mut uniform = move || unit_f64(xorshift64(&mut state));
        for _ in 0..2000 {
            let origin = [0, 1, 2].map(|_| uniform() * 6.0 - 3.0);
            let direction = [0, 1, 2].map(|_| uniform() * 2.0 - 1.0);
            let l = line(origin, direction);
            let (t0, t1) = (uniform() * 2.0 - 1.0, uniform() * 6.0);
            let expected: Vec<_> = boxed.clip(&l, t0, t1).into_iter().collect();
            let got = mesh.inside_parts(&l, t0, t1);
            assert!(
                close(&got, &expected),
                "{l:?} [{t0}, {t1}]: {got:?} vs {expected:?}"
            );
        }
    }

    /// Lines through the cube's edges and corners, and along its diagonal, where several
    /// triangles report one crossing.
    #[test]
    fn edges_and_corners_count_once() {
        let mesh = ClosedMesh::new(&cube(DVec3::splat(-1.0), DVec3::splat(1.0))).unwrap();
        // Through the face diagonal's shared edge: x = y plane through the cube, along z.
        let through_edge = line([0.25, 0.25, -5.0], [0.0, 0.0, 1.0]);
        assert!(close(
            &mesh.inside_parts(&through_edge, 0.0, 10.0),
            &[(4.0, 6.0)]
        ));
        // Through two opposite corners, where rounding may leave the corner to no
        // triangle: within the nudge.
        let diagonal = line([-2.0, -2.0, -2.0], [1.0, 1.0, 1.0]);
        let r3 = 3f64.sqrt();
        let parts = mesh.inside_parts(&diagonal, 0.0, 10.0);
        assert_eq!(parts.len(), 1, "{parts:?}");
        assert!((parts[0].0 - r3).abs() < 1e-8 && (parts[0].1 - 3.0 * r3).abs() < 1e-8);
        // Grazing along an outer edge of the cube: touching, never inside for a length.
        let grazing = line([1.0, 1.0, -5.0], [0.0, 0.0, 1.0]);
        let parts = mesh.inside_parts(&grazing, 0.0, 10.0);
        assert!(parts.iter().all(|(a, b)| b - a <= 2.0 + 1e-9), "{parts:?}");
        assert!(mesh.contains(DVec3::ZERO));
        assert!(!mesh.contains(DVec3::new(1.5, 0.0, 0.0)));
    }

    #[test]
    fn a_non_convex_mesh_gives_two_parts() {
        let mesh = ClosedMesh::new(&u_shape()).unwrap();
        // Across both arms of the U at y = 1.5, z = 0.5.
        let across = line([-1.0, 1.5, 0.5], [1.0, 0.0, 0.0]);
        assert!(close(
            &mesh.inside_parts(&across, 0.0, 10.0),
            &[(1.0, 2.0), (3.0, 4.0)]
        ));
        // Starting inside the first arm, ending inside the second.
        assert!(close(
            &mesh.inside_parts(&across, 1.5, 3.5),
            &[(1.5, 2.0), (3.0, 3.5)]
        ));
        // Through the gap only.
        assert!(mesh.inside_parts(&across, 2.1, 2.9).is_empty());
        assert!(mesh.contains(DVec3::new(0.5, 1.5, 0.5)));
        assert!(!mesh.contains(DVec3::new(1.5, 1.5, 0.5)));
        assert!(mesh.contains(DVec3::new(1.5, 0.5, 0.5)));
    }

    #[test]
    fn inside_out_meshes_are_turned_outward() {
        let flipped: Vec<_> = u_shape().into_iter().map(|[a, b, c]| [a, c, b]).collect();
        let mesh = ClosedMesh::new(&flipped).unwrap();
        let across = line([-1.0, 1.5, 0.5], [1.0, 0.0, 0.0]);
        assert!(close(
            &mesh.inside_parts(&across, 0.0, 10.0),
            &[(1.0, 2.0), (3.0, 4.0)]
        ));
    }

    #[test]
    fn meshes_that_bound_nothing_are_refused() {
        let mut open = cube(DVec3::ZERO, DVec3::ONE);
        open.pop();
        assert_eq!(
            ClosedMesh::new(&open),
            Err(MeshBoundsError::NotClosed { unmatched: 3 })
        );
        let mut twisted = cube(DVec3::ZERO, DVec3::ONE);
        twisted[0].swap(1, 2);
        assert!(matches!(
            ClosedMesh::new(&twisted),
            Err(MeshBoundsError::NotClosed { .. })
        ));
        // A sheet seen from both sides is closed but encloses nothing.
        let sheet = [
            [DVec3::ZERO, DVec3::X, DVec3::Y],
            [DVec3::ZERO, DVec3::Y, DVec3::X],
        ];
        assert_eq!(ClosedMesh::new(&sheet), Err(MeshBoundsError::NoVolume));
        assert_eq!(ClosedMesh::new(&[]), Err(MeshBoundsError::Empty));
        let mut nan = cube(DVec3::ZERO, DVec3::ONE);
        nan[3][1].x = f64::NAN;
        assert_eq!(ClosedMesh::new(&nan), Err(MeshBoundsError::NonFinite));
    }

    /// A finely tessellated sphere (thousands of triangles, a deep hierarchy): chords
    /// through it match the analytic sphere to the tessellation's sag.
    #[test]
    fn a_tessellated_sphere_matches_its_chords() {
        let (rings, segments) = (48usize, 96usize);
        let vertex = |i: usize, j: usize| {
            if i == 0 || i == rings {
                return DVec3::new(0.0, if i == 0 { 1.0 } else { -1.0 }, 0.0);
            }
            let theta = std::f64::consts::PI * i as f64 / rings as f64;
            let phi = std::f64::consts::TAU * (j % segments) as f64 / segments as f64;
            DVec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            )
        };
        let mut triangles = Vec::new();
        for i in 0..rings {
            for j in 0..segments {
                let (a, b, c, d) = (
                    vertex(i, j),
                    vertex(i + 1, j),
                    vertex(i + 1, j + 1),
                    vertex(i, j + 1),
                );
                triangles.push([a, c, b]);
                triangles.push([a, d, c]);
            }
        }
        let mesh = ClosedMesh::new(&triangles).unwrap();
        assert!(mesh.nodes.len() > 1000);
        for k in 0..200 {
            let offset = (k as f64 / 200.0) * 0.9;
            let chord = line([-3.0, offset, 0.1], [1.0, 0.0, 0.0]);
            let half = (1.0 - offset * offset - 0.01).sqrt();
            let parts = mesh.inside_parts(&chord, 0.0, 10.0);
            assert_eq!(parts.len(), 1, "{offset}: {parts:?}");
            assert!((parts[0].0 - (3.0 - half)).abs() < 2e-3, "{parts:?}");
            assert!((parts[0].1 - (3.0 + half)).abs() < 2e-3, "{parts:?}");
        }
    }
}
