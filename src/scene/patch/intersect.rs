//! Exact ray-patch intersection: subdivision against the control hull's bounds, then
//! Newton iteration on the patch itself.
//!
//! The ray is written as the intersection of two planes through it (Kajiya 1982; the set-up
//! of Bezier clipping, Nishita, Sederberg and Kakimoto 1990). Projecting the control points
//! onto the planes' normals gives a 2D Bezier patch `f(u, v)` whose zeros are where the ray
//! meets the surface; the third coordinate, the depth along the ray, is `t`. Because a
//! Bezier patch lies in the convex hull of its control points (seed 004, "Another Way To
//! Render"), a sub-patch whose control points' box does not contain the 2D origin, or lies
//! beyond the closest hit so far, holds no hit. Sub-patches are split at their middle by de
//! Casteljau's algorithm until they are nearly bilinear; from the middle of each such
//! sub-patch, Newton iteration on the full patch's `f` (2x2 Jacobian `[f_u f_v]`) finds the
//! root (Martin et al. 2000 seed Newton the same way, from a tessellation).
//!
//! The splits down to nearly bilinear sub-patches do not depend on the ray, so they are made
//! once per patch ([`super::hull_tree`]); a ray walks that hierarchy's world-space boxes and
//! starts the search above at each leaf it crosses (the leaf's box in the ray's frame, then
//! Newton, then further splits where Newton leads away), instead of splitting the whole
//! patch again.
//!
//! Tolerances (all in f64): a root is accepted when `|f|` is below
//! [`DISTANCE_TOLERANCE`] times the patch's extent (the distance from the ray to the
//! surface point) and the last Newton step is below [`PARAMETER_TOLERANCE`] in u and v, with
//! `(u, v)` inside `[0, 1]^2` (up to the same parameter tolerance, then clamped). A hit
//! needs `tnear < t < tfar`.
//!
//! Hard cases: at a silhouette the Jacobian becomes singular and the boxes straddle the
//! ray; subdivision goes on to [`MAX_DEPTH`] and Newton then either converges (a hit) or
//! leaves the sub-patch (a miss), never returns a non-finite value. Collapsed edges (the
//! teapot's lid and bottom, converted Bezier triangles) have `dP/dv = 0` along the edge;
//! Newton works beside it, and [`geometric_normal`] takes the normal from just inside.

use glam::{DVec2, DVec3, Vec3};

use super::hull_tree::{ray_box, HullContent, HullLeaf, HullTree};
use super::{control_f64, evaluate};

/// Newton stops when its step is below this in u and v.
pub const PARAMETER_TOLERANCE: f64 = 1e-10;
/// A root's distance from the ray, relative to the patch's extent, must be below this.
pub const DISTANCE_TOLERANCE: f64 = 1e-9;
/// Deepest subdivision (a sub-patch of 2^-14 of the parameter square per side).
pub const MAX_DEPTH: u32 = 14;
/// A sub-patch is handed to Newton once its control points are within this fraction of its
/// size from the bilinear patch through its corners.
pub(super) const FLATNESS: f64 = 0.05;
const NEWTON_ITERATIONS: u32 = 24;

/// A ray in f64: `origin + t direction` for `t` in `(tnear, tfar)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PatchRay {
    pub origin: DVec3,
    pub direction: DVec3,
    pub tnear: f64,
    pub tfar: f64,
}

/// Where a ray meets a patch.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PatchHit {
    /// Distance along the ray's direction (in units of its length).
    pub t: f64,
    pub u: f64,
    pub v: f64,
    /// `dP/du x dP/dv` (not normalised), taken from just inside a collapsed edge.
    pub normal: DVec3,
}

/// A patch ready for intersection: its control points in f64, its size, and its
/// subdivision hierarchy (built once, walked by every ray).
#[derive(Clone, Debug, PartialEq)]
pub struct PatchIntersector {
    control: [DVec3; 16],
    extent: f64,
    tree: HullTree,
}

/// Control net of a sub-patch in the ray's frame (x, y across the ray, z = t along it),
/// with its parameter range.
#[derive(Clone, Copy)]
struct Node {
    net: [DVec3; 16],
    u0: f64,
    u1: f64,
    v0: f64,
    v1: f64,
}

/// Splits a cubic at its middle (de Casteljau).
#[inline]
fn split_curve(p: [DVec3; 4]) -> ([DVec3; 4], [DVec3; 4]) {
    let p01 = (p[0] + p[1]) * 0.5;
    let p12 = (p[1] + p[2]) * 0.5;
    let p23 = (p[2] + p[3]) * 0.5;
    let a = (p01 + p12) * 0.5;
    let b = (p12 + p23) * 0.5;
    let m = (a + b) * 0.5;
    ([p[0], p01, a, m], [m, b, p23, p[3]])
}

pub(super) fn split_u(net: &[DVec3; 16]) -> ([DVec3; 16], [DVec3; 16]) {
    let (mut left, mut right) = ([DVec3::ZERO; 16], [DVec3::ZERO; 16]);
    for j in 0..4 {
        let (l, r) = split_curve([net[4 * j], net[4 * j + 1], net[4 * j + 2], net[4 * j + 3]]);
        left[4 * j..4 * j + 4].copy_from_slice(&l);
        right[4 * j..4 * j + 4].copy_from_slice(&r);
    }
    (left, right)
}

pub(super) fn split_v(net: &[DVec3; 16]) -> ([DVec3; 16], [DVec3; 16]) {
    let (mut low, mut high) = ([DVec3::ZERO; 16], [DVec3::ZERO; 16]);
    for i in 0..4 {
        let (l, r) = split_curve([net[i], net[4 + i], net[8 + i], net[12 + i]]);
        for j in 0..4 {
            low[4 * j + i] = l[j];
            high[4 * j + i] = r[j];
        }
    }
    (low, high)
}

pub(super) fn net_bounds(net: &[DVec3; 16]) -> (DVec3, DVec3) {
    let mut lo = net[0];
    let mut hi = net[0];
    for p in &net[1..] {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    (lo, hi)
}

/// Largest distance of a control point from the bilinear patch through the corners.
pub(super) fn bilinear_deviation(net: &[DVec3; 16]) -> f64 {
    let (c00, c30, c03, c33) = (net[0], net[3], net[12], net[15]);
    let mut worst: f64 = 0.0;
    for j in 0..4 {
        for i in 0..4 {
            let (s, t) = (i as f64 / 3.0, j as f64 / 3.0);
            let bilinear = c00 * ((1.0 - s) * (1.0 - t))
                + c30 * (s * (1.0 - t))
                + c03 * ((1.0 - s) * t)
                + c33 * (s * t);
            worst = worst.max((net[4 * j + i] - bilinear).length());
        }
    }
    worst
}

impl PatchIntersector {
    pub fn new(control: &[Vec3; 16]) -> PatchIntersector {
        let control = control_f64(control);
        let (lo, hi) = net_bounds(&control);
        let extent = (hi - lo).max_element().max(f64::MIN_POSITIVE);
        PatchIntersector {
            tree: HullTree::build(&control, DISTANCE_TOLERANCE * extent),
            control,
            extent,
        }
    }

    /// Memory of the subdivision hierarchy, in bytes.
    pub fn hierarchy_bytes(&self) -> usize {
        self.tree.bytes()
    }

    /// The largest side of the control points' box.
    pub fn extent(&self) -> f64 {
        self.extent
    }

    /// The closest hit of `ray` (or, with `any_hit`, the first found), if any.
    pub fn intersect(&self, ray: &PatchRay, any_hit: bool) -> Option<PatchHit> {
        self.intersect_accepting(ray, any_hit, &mut |_, _, _| true)
    }

    /// As [`PatchIntersector::intersect`], counting only roots `(t, u, v)` that `accept`
    /// keeps (an alpha cut-out): a rejected root is passed over and the search goes on
    /// behind it.
    pub fn intersect_accepting(
        &self,
        ray: &PatchRay,
        any_hit: bool,
        accept: &mut dyn FnMut(f64, f64, f64) -> bool,
    ) -> Option<PatchHit> {
        let length = ray.direction.length();
        if !(length > 0.0 && length.is_finite() && ray.origin.is_finite()) {
            return None;
        }
        let dir = ray.direction / length;
        // Two unit normals across the ray and the ray itself make an orthonormal frame.
        let (n1, n2) = dir.any_orthonormal_pair();
        let to_frame = |p: DVec3| {
            let q = p - ray.origin;
            DVec3::new(n1.dot(q), n2.dot(q), dir.dot(q) / length)
        };
        let mut search = Search {
            frame: [DVec3::ZERO; 16],
            framed: false,
            tnear: ray.tnear,
            best: None,
            tbest: ray.tfar,
            any_hit,
            tolerance: DISTANCE_TOLERANCE * self.extent,
            accept,
        };
        // The hierarchy stands in for the splits above its leaves; each leaf the ray's
        // world-space walk reaches goes on in the ray's frame as the search always did.
        let mut leaf_search = |search: &mut Search, leaf: &HullLeaf| {
            // Newton needs the whole patch in the ray's frame: made once, at the first leaf
            // (rays that reach none never need it).
            if !search.framed {
                search.frame = self.control.map(to_frame);
                search.framed = true;
            }
            search.visit(
                Node {
                    net: leaf.net.map(to_frame),
                    u0: leaf.u0,
                    u1: leaf.u1,
                    v0: leaf.v0,
                    v1: leaf.v1,
                },
                leaf.depth,
                Some(leaf.flat),
            )
        };
        search.walk(&self.tree, 0, ray, &mut leaf_search);
        let (t, u, v) = search.best?;
        Some(PatchHit {
            t,
            u,
            v,
            normal: geometric_normal(&self.control, u, v),
        })
    }
}

/// `dP/du x dP/dv` at `(u, v)`; where an edge collapses (the cross product vanishes) it is
/// taken a little way inside the patch, towards its middle.
pub fn geometric_normal(control: &[DVec3; 16], u: f64, v: f64) -> DVec3 {
    let p = evaluate(control, u, v);
    let n = p.dpdu.cross(p.dpdv);
    let scale = p.dpdu.length_squared().max(p.dpdv.length_squared());
    if n.length_squared() > 1e-20 * scale * scale && n.is_finite() {
        return n;
    }
    for step in [1e-6, 1e-4, 1e-2] {
        let inside_u = u + (0.5 - u).signum() * step;
        let inside_v = v + (0.5 - v).signum() * step;
        let q = evaluate(control, inside_u, inside_v);
        let n = q.dpdu.cross(q.dpdv);
        if n.length_squared() > 0.0 && n.is_finite() {
            return n;
        }
    }
    DVec3::ZERO
}

/// Position, `dP/du` and `dP/dv` of the bicubic patch `c` at `(u, v)`: what Newton needs,
/// without the second derivatives of [`evaluate`].
#[inline]
fn position_and_tangents(c: &[DVec3; 16], u: f64, v: f64) -> (DVec3, DVec3, DVec3) {
    let (s, t) = (1.0 - u, 1.0 - v);
    let bu = [s * s * s, 3.0 * u * s * s, 3.0 * u * u * s, u * u * u];
    let du = [
        -3.0 * s * s,
        3.0 * s * s - 6.0 * u * s,
        6.0 * u * s - 3.0 * u * u,
        3.0 * u * u,
    ];
    let bv = [t * t * t, 3.0 * v * t * t, 3.0 * v * v * t, v * v * v];
    let dv = [
        -3.0 * t * t,
        3.0 * t * t - 6.0 * v * t,
        6.0 * v * t - 3.0 * v * v,
        3.0 * v * v,
    ];
    let (mut position, mut dpdu, mut dpdv) = (DVec3::ZERO, DVec3::ZERO, DVec3::ZERO);
    for j in 0..4 {
        // Each row's curve in u and its u-derivative, then the sums over rows in v.
        let row = &c[4 * j..4 * j + 4];
        let curve = row[0] * bu[0] + row[1] * bu[1] + row[2] * bu[2] + row[3] * bu[3];
        let tangent = row[0] * du[0] + row[1] * du[1] + row[2] * du[2] + row[3] * du[3];
        position += curve * bv[j];
        dpdv += curve * dv[j];
        dpdu += tangent * bv[j];
    }
    (position, dpdu, dpdv)
}

struct Search<'a> {
    /// The whole patch in the ray's frame, for Newton (once `framed`).
    frame: [DVec3; 16],
    framed: bool,
    tnear: f64,
    tbest: f64,
    best: Option<(f64, f64, f64)>,
    any_hit: bool,
    tolerance: f64,
    /// Whether a root counts (an alpha test); see [`PatchIntersector::intersect_accepting`].
    accept: &'a mut dyn FnMut(f64, f64, f64) -> bool,
}

impl Search<'_> {
    fn done(&self) -> bool {
        self.any_hit && self.best.is_some()
    }

    /// Walks the hierarchy from node `index`, nearest box first, skipping boxes the ray
    /// misses or reaches only beyond the closest hit so far; calls `at_leaf` at each leaf.
    fn walk(
        &mut self,
        tree: &HullTree,
        index: u32,
        ray: &PatchRay,
        at_leaf: &mut impl FnMut(&mut Self, &HullLeaf),
    ) {
        if self.done() {
            return;
        }
        match tree.nodes[index as usize].content {
            HullContent::Leaf { index } => at_leaf(self, &tree.leaves[index as usize]),
            HullContent::Split { first } => {
                let mut order = [(0.0, 0u32); 4];
                let mut count = 0;
                for child in first..first + 4 {
                    let node = &tree.nodes[child as usize];
                    let Some((t0, t1)) = ray_box(ray.origin, ray.direction, node.lower, node.upper)
                    else {
                        continue;
                    };
                    if t1 < self.tnear || t0 > self.tbest {
                        continue;
                    }
                    order[count] = (t0, child);
                    count += 1;
                }
                order[..count].sort_by(|a, b| a.0.total_cmp(&b.0));
                for &(t0, child) in &order[..count] {
                    if t0 > self.tbest {
                        break;
                    }
                    self.walk(tree, child, ray, at_leaf);
                }
            }
        }
    }

    /// Searches sub-patch `node` (`depth` splits from the whole patch); `flat` is its
    /// flatness when already known (a hierarchy leaf's).
    fn visit(&mut self, node: Node, depth: u32, flat: Option<bool>) {
        if self.done() {
            return;
        }
        let (lo, hi) = net_bounds(&node.net);
        // The ray is the 2D origin of the frame; depth is z.
        let slack = self.tolerance;
        if lo.x > slack || hi.x < -slack || lo.y > slack || hi.y < -slack {
            return;
        }
        if hi.z <= self.tnear || lo.z >= self.tbest {
            return;
        }
        let size = (hi - lo).truncate().max_element().max(hi.z - lo.z);
        let flat = flat.unwrap_or_else(|| bilinear_deviation(&node.net) <= FLATNESS * size);
        let leaf = depth >= MAX_DEPTH || size <= self.tolerance;
        // A flat sub-patch is settled when Newton finds its root; otherwise (Newton led
        // away, e.g. across a collapsed edge to the mirror-image parameters) it is split on.
        if leaf || (depth >= 1 && flat) {
            let settled = self.newton(&node);
            if settled || leaf {
                return;
            }
        }
        let (left, right) = split_u(&node.net);
        let um = 0.5 * (node.u0 + node.u1);
        let vm = 0.5 * (node.v0 + node.v1);
        let (ll, lh) = split_v(&left);
        let (rl, rh) = split_v(&right);
        let children = [
            Node {
                net: ll,
                u0: node.u0,
                u1: um,
                v0: node.v0,
                v1: vm,
            },
            Node {
                net: rl,
                u0: um,
                u1: node.u1,
                v0: node.v0,
                v1: vm,
            },
            Node {
                net: lh,
                u0: node.u0,
                u1: um,
                v0: vm,
                v1: node.v1,
            },
            Node {
                net: rh,
                u0: um,
                u1: node.u1,
                v0: vm,
                v1: node.v1,
            },
        ];
        // Nearest first, so later children are pruned by the closest hit (sorting indices,
        // not the nets).
        let near = children.map(|n| n.net.iter().fold(f64::INFINITY, |a, p| a.min(p.z)));
        let mut order = [0usize, 1, 2, 3];
        order.sort_unstable_by(|&a, &b| near[a].total_cmp(&near[b]));
        for index in order {
            self.visit(children[index], depth + 1, None);
        }
    }

    /// Newton iteration on the whole patch from the middle of `node`; keeps the root if it
    /// is a hit nearer than the best so far. Returns whether the root lies in `node` (so
    /// the sub-patch needs no further search).
    fn newton(&mut self, node: &Node) -> bool {
        let mut u = 0.5 * (node.u0 + node.u1);
        let mut v = 0.5 * (node.v0 + node.v1);
        // The iterate may wander beyond its sub-patch (it is evaluated on the whole patch),
        // but not far: a root elsewhere belongs to another sub-patch's search.
        let reach_u = 2.0 * (node.u1 - node.u0);
        let reach_v = 2.0 * (node.v1 - node.v0);
        for _ in 0..NEWTON_ITERATIONS {
            let (position, dpdu, dpdv) = position_and_tangents(&self.frame, u, v);
            let f = DVec2::new(position.x, position.y);
            let (a, b, c, d) = (dpdu.x, dpdv.x, dpdu.y, dpdv.y);
            let det = a * d - b * c;
            if det == 0.0 || !det.is_finite() {
                return false;
            }
            // [du dv] = -J^-1 f
            let du = -(d * f.x - b * f.y) / det;
            let dv = -(-c * f.x + a * f.y) / det;
            u += du;
            v += dv;
            if !(u.is_finite() && v.is_finite())
                || u < node.u0 - reach_u
                || u > node.u1 + reach_u
                || v < node.v0 - reach_v
                || v > node.v1 + reach_v
            {
                return false;
            }
            if du.abs() < PARAMETER_TOLERANCE && dv.abs() < PARAMETER_TOLERANCE {
                break;
            }
        }
        let inside = |x: f64| (-PARAMETER_TOLERANCE..=1.0 + PARAMETER_TOLERANCE).contains(&x);
        if !(inside(u) && inside(v)) {
            return false;
        }
        let (u, v) = (u.clamp(0.0, 1.0), v.clamp(0.0, 1.0));
        let p = position_and_tangents(&self.frame, u, v).0;
        let miss = p.x.hypot(p.y);
        if miss.is_nan() || miss > self.tolerance {
            return false;
        }
        let t = p.z;
        if t > self.tnear && t < self.tbest && t.is_finite() && (self.accept)(t, u, v) {
            self.tbest = t;
            self.best = Some((t, u, v));
        }
        let margin_u = 0.01 * (node.u1 - node.u0) + PARAMETER_TOLERANCE;
        let margin_v = 0.01 * (node.v1 - node.v0) + PARAMETER_TOLERANCE;
        (node.u0 - margin_u..=node.u1 + margin_u).contains(&u)
            && (node.v0 - margin_v..=node.v1 + margin_v).contains(&v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::patch::basis::elevate_to_bicubic;

    fn ray(origin: DVec3, direction: DVec3) -> PatchRay {
        PatchRay {
            origin,
            direction,
            tnear: 0.0,
            tfar: f64::INFINITY,
        }
    }

    /// A bilinear saddle elevated to bicubic: z = (2u - 1)(2v - 1) over [-1, 1]^2.
    fn saddle() -> PatchIntersector {
        let corners = [
            Vec3::new(-1.0, -1.0, 1.0),
            Vec3::new(1.0, -1.0, -1.0),
            Vec3::new(-1.0, 1.0, -1.0),
            Vec3::new(1.0, 1.0, 1.0),
        ];
        PatchIntersector::new(&elevate_to_bicubic(1, 1, &corners).unwrap())
    }

    #[test]
    fn rays_down_onto_a_saddle_hit_its_height() {
        let patch = saddle();
        for &(x, y) in &[(0.3, -0.2), (-0.9, 0.8), (0.0, 0.0), (0.99, 0.99)] {
            let hit = patch
                .intersect(
                    &ray(DVec3::new(x, y, 5.0), DVec3::new(0.0, 0.0, -1.0)),
                    false,
                )
                .expect("a ray straight down hits the saddle");
            let z = x * y;
            assert!(
                (hit.t - (5.0 - z)).abs() < 1e-9,
                "t {} at ({x}, {y})",
                hit.t
            );
            assert!(
                (hit.u - (x + 1.0) / 2.0).abs() < 1e-8,
                "u {} at ({x}, {y})",
                hit.u
            );
            assert!(hit.normal.z > 0.0);
        }
        assert!(patch
            .intersect(
                &ray(DVec3::new(1.1, 0.0, 5.0), DVec3::new(0.0, 0.0, -1.0)),
                false
            )
            .is_none());
    }

    #[test]
    fn the_closest_of_two_hits_is_returned() {
        // A half-cylinder-like arch: a ray along its axis direction from below the arch
        // crosses it twice when tilted; the first is the nearer.
        let patch = saddle();
        let r = ray(DVec3::new(-2.0, 0.5, 0.0), DVec3::new(1.0, 0.0, 0.0));
        // z = x * 0.5 along the line y = 0.5: meets z = 0 at x = 0 only.
        let hit = patch.intersect(&r, false).unwrap();
        assert!((hit.t - 2.0).abs() < 1e-9, "{}", hit.t);
        let far = PatchRay { tfar: 1.5, ..r };
        assert!(patch.intersect(&far, false).is_none());
        assert!(patch.intersect(&r, true).is_some());
    }
}

#[cfg(test)]
mod collapsed_edge_tests {
    use super::*;

    /// The teapot's first lid patch (z up): its row v = 0 collapses onto the apex.
    fn lid() -> PatchIntersector {
        let text = std::fs::read_to_string(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/assets/models/teapot.bpt"
        ))
        .unwrap();
        let patches = crate::scene::patch::bpt::parse_bpt(&text).unwrap();
        PatchIntersector::new(&patches[20])
    }

    #[test]
    fn rays_beside_the_apex_hit_the_lid() {
        let lid = lid();
        for offset in [0.0, 1e-7, 1e-5, 1e-3, 1e-2, 0.1] {
            for (dx, dy) in [(1.0, 0.0), (0.7, -0.7), (0.0, -1.0), (0.01, -0.99)] {
                let r = PatchRay {
                    origin: DVec3::new(dx * offset, dy * offset, 5.0),
                    direction: DVec3::NEG_Z,
                    tnear: 0.0,
                    tfar: f64::INFINITY,
                };
                let hit = lid.intersect(&r, false);
                eprintln!("offset {offset} ({dx}, {dy}): {hit:?}");
                let hit = hit.expect("the lid is hit");
                assert!(hit.normal.is_finite() && hit.normal.length() > 0.0);
            }
        }
    }
}
