//! Explicit (height) patches traced by ray marching, the way seed 004 renders them
//! ("Rectangular Bezier Patches", "The Rendering": "For the ray marching case ...").
//!
//! A height patch is `y = H(x, z)` over a rectangle `[x0, x1] x [z0, z1]` of the y = 0
//! plane, with `H` a bicubic Bezier function of `u = (x - x0) / (x1 - x0)` and
//! `v = (z - z0) / (z1 - z0)`: `H = sum_ij B_i(u) B_j(v) h_ij` (seed 004's "Bezier
//! Rectangle" with one-dimensional control points). Its heights lie between the smallest
//! and largest `h_ij` (convex hull property), which bounds the patch by a box.
//!
//! Marching (seed 004: "I did a raytrace of that bounding box to get a minimum and maximum
//! distance ... raymarching from that min time to the max time ... considering the ray as
//! hitting the surface whenever ... rayPos.y - bezierRectangle.y changed sign"): the ray is
//! clipped to the box and sampled every [`HeightPatch::march_step`] world units; at the
//! first sign change of `g(t) = y(t) - H(x(t), z(t))` the root is refined in its bracket by
//! the Illinois variant of regula falsi (a secant step that halves the stale end's weight,
//! so it converges like the secant method and never leaves the bracket like bisection) to
//! [`ROOT_TOLERANCE`] in `t`. The normal is the exact one, `P_u x P_v` of the height
//! function's derivatives (the seed took finite differences).
//!
//! What marching misses: a ray that enters and leaves the surface between two samples
//! (a grazing ray over a bump narrower than the step) shows no sign change and passes
//! through. The same surface as a general bicubic patch ([`HeightPatch::to_bezier`]: the
//! x and z of a control point are the rectangle's thirds, which is exactly linear in u and
//! v) is traced exactly by `super::intersect`, and the two are compared in tests and in
//! `conetrace accuracy --mode patches`.

use glam::{DVec3, Vec2, Vec3};

use super::intersect::PatchRay;
use super::{bernstein3, BezierPatch};

/// The bracketed root is refined until its bracket is below this in `t` (relative to the
/// larger of 1 and `|t|`).
pub const ROOT_TOLERANCE: f64 = 1e-10;
/// Most refinement steps of one bracket.
const REFINEMENT_STEPS: u32 = 100;

/// A bicubic height field over a rectangle, traced by marching.
#[derive(Clone, Debug, PartialEq)]
pub struct HeightPatch {
    /// `(x0, z0)`: the rectangle's corner at `u = v = 0`.
    pub min: Vec2,
    /// `(x1, z1)`: the corner at `u = v = 1`.
    pub max: Vec2,
    /// `h_ij` at `heights[4 j + i]` (`i` along x, `j` along z).
    pub heights: [f32; 16],
    /// Index into `SceneDescription::materials`.
    pub material: usize,
    /// Distance between samples along the ray, world units.
    pub march_step: f32,
}

/// Where a marched ray meets a height patch.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MarchHit {
    /// Distance along the ray's direction (in units of its length).
    pub t: f64,
    pub u: f64,
    pub v: f64,
    /// `P_u x P_v` (not normalised), the same orientation as [`HeightPatch::to_bezier`]'s.
    pub normal: DVec3,
}

impl HeightPatch {
    /// The height `H(u, v)` and its derivatives `dH/du`, `dH/dv`.
    pub fn height(&self, u: f64, v: f64) -> (f64, f64, f64) {
        let (bu, du, _) = bernstein3(u);
        let (bv, dv, _) = bernstein3(v);
        let (mut h, mut hu, mut hv) = (0.0, 0.0, 0.0);
        for j in 0..4 {
            for i in 0..4 {
                let c = f64::from(self.heights[4 * j + i]);
                h += c * bu[i] * bv[j];
                hu += c * du[i] * bv[j];
                hv += c * bu[i] * dv[j];
            }
        }
        (h, hu, hv)
    }

    /// The same surface as a bicubic Bezier patch (exact: x and z are linear in u and v).
    pub fn to_bezier(&self) -> BezierPatch {
        let mut control = [Vec3::ZERO; 16];
        for j in 0..4 {
            for i in 0..4 {
                let (s, t) = (i as f32 / 3.0, j as f32 / 3.0);
                control[4 * j + i] = Vec3::new(
                    self.min.x + (self.max.x - self.min.x) * s,
                    self.heights[4 * j + i],
                    self.min.y + (self.max.y - self.min.y) * t,
                );
            }
        }
        BezierPatch {
            control,
            corner_st: None,
            material: self.material,
        }
    }

    /// The box containing the patch.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let low = self.heights.iter().copied().fold(f32::INFINITY, f32::min);
        let high = self
            .heights
            .iter()
            .copied()
            .fold(f32::NEG_INFINITY, f32::max);
        (
            Vec3::new(self.min.x, low, self.min.y),
            Vec3::new(self.max.x, high, self.max.y),
        )
    }

    /// [`HeightPatch::bounds`] grown in y by a millionth of its largest coordinate, the
    /// interval the march samples. The heights' own box has no thickness when they are all
    /// equal (a flat tile): the clipped ray would then be a single point, with no sign change
    /// of `g` to find. Grown, `g` is positive where the march starts and negative where it
    /// ends for every ray that crosses the surface.
    fn march_box(&self) -> (DVec3, DVec3) {
        let (low, high) = self.bounds();
        let (low, high) = (low.as_dvec3(), high.as_dvec3());
        let size = low.abs().max(high.abs()).max(high - low).max_element();
        let grow = DVec3::new(0.0, 1e-6 * size, 0.0);
        (low - grow, high + grow)
    }

    /// Why the patch cannot be traced, if it cannot: an empty or non-finite rectangle,
    /// non-finite heights, or a step that is not a positive distance.
    pub fn problem(&self) -> Option<String> {
        if !(self.min.is_finite() && self.max.is_finite()) {
            return Some("the rectangle is not finite".to_string());
        }
        if !(self.max.x > self.min.x && self.max.y > self.min.y) {
            return Some(format!(
                "the rectangle from {} to {} is empty (max must exceed min in x and z)",
                self.min, self.max
            ));
        }
        if self.heights.iter().any(|h| !h.is_finite()) {
            return Some("a height is not finite".to_string());
        }
        if !(self.march_step.is_finite() && self.march_step > 0.0) {
            return Some(format!(
                "march_step {} must be a positive distance",
                self.march_step
            ));
        }
        None
    }

    /// `g(t) = y(t) - H(x(t), z(t))` along `ray` (outside the rectangle, where `H` is not
    /// defined, the clamped parameters are used; the march stays inside it).
    fn gap(&self, ray: &PatchRay, t: f64) -> f64 {
        let p = ray.origin + ray.direction * t;
        let (u, v) = self.parameters(p);
        p.y - self.height(u, v).0
    }

    fn parameters(&self, p: DVec3) -> (f64, f64) {
        let (min, max) = (self.min.as_dvec2(), self.max.as_dvec2());
        (
            ((p.x - min.x) / (max.x - min.x)).clamp(0.0, 1.0),
            ((p.z - min.y) / (max.y - min.y)).clamp(0.0, 1.0),
        )
    }

    /// The first crossing of `ray` with the surface found by marching at `march_step`
    /// (with `any_hit`, the same: marching finds crossings in order).
    pub fn march(&self, ray: &PatchRay) -> Option<MarchHit> {
        self.march_accepting(ray, &mut |_, _, _| true)
    }

    /// As [`HeightPatch::march`], counting only crossings `(t, u, v)` that `accept` keeps
    /// (an alpha cut-out): the march goes on behind a rejected one.
    // `!(start <= end)` also stops at a NaN bound, which `start > end` would let through.
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    pub fn march_accepting(
        &self,
        ray: &PatchRay,
        accept: &mut dyn FnMut(f64, f64, f64) -> bool,
    ) -> Option<MarchHit> {
        let length = ray.direction.length();
        if !(length > 0.0 && length.is_finite() && ray.origin.is_finite()) {
            return None;
        }
        let (low, high) = self.march_box();
        let (t0, t1) = super::hull_tree::ray_box(ray.origin, ray.direction, low, high)?;
        let (start, end) = (t0.max(ray.tnear), t1.min(ray.tfar));
        if !(start <= end) {
            return None;
        }
        let dt = f64::from(self.march_step) / length;
        let mut t = start;
        let mut g = self.gap(ray, t);
        while t < end {
            let next = (t + dt).min(end);
            let g_next = self.gap(ray, next);
            let root = if g == 0.0 && t > ray.tnear {
                Some(t)
            } else if (g < 0.0) != (g_next < 0.0) || g_next == 0.0 {
                Some(refine(|t| self.gap(ray, t), (t, g), (next, g_next)))
            } else {
                None
            };
            if let Some(hit) = root
                .filter(|root| *root > ray.tnear && *root < ray.tfar)
                .and_then(|root| self.hit(ray, root))
            {
                if accept(hit.t, hit.u, hit.v) {
                    return Some(hit);
                }
            }
            t = next;
            g = g_next;
        }
        None
    }

    fn hit(&self, ray: &PatchRay, t: f64) -> Option<MarchHit> {
        let p = ray.origin + ray.direction * t;
        let (u, v) = self.parameters(p);
        let (_, hu, hv) = self.height(u, v);
        let (wx, wz) = (
            f64::from(self.max.x - self.min.x),
            f64::from(self.max.y - self.min.y),
        );
        // P_u = (wx, H_u, 0), P_v = (0, H_v, wz).
        let normal = DVec3::new(hu * wz, -wx * wz, wx * hv);
        (t.is_finite() && normal.is_finite()).then_some(MarchHit { t, u, v, normal })
    }
}

/// A root of `g` in the bracket `[a, b]` (`g(a)` and `g(b)` of opposite signs, or one of
/// them zero) by the Illinois method.
fn refine(g: impl Fn(f64) -> f64, (mut a, mut ga): (f64, f64), (mut b, mut gb): (f64, f64)) -> f64 {
    if gb == 0.0 {
        return b;
    }
    // Which end was kept by the last step (-1: a, 1: b), to halve its weight when kept twice.
    let mut kept = 0i8;
    for _ in 0..REFINEMENT_STEPS {
        if (b - a).abs() <= ROOT_TOLERANCE * a.abs().max(1.0) {
            break;
        }
        let mut c = (a * gb - b * ga) / (gb - ga);
        if !(c > a.min(b) && c < a.max(b)) {
            c = 0.5 * (a + b);
        }
        let gc = g(c);
        if gc == 0.0 {
            return c;
        }
        if (gc < 0.0) == (ga < 0.0) {
            a = c;
            ga = gc;
            if kept == 1 {
                gb *= 0.5;
            }
            kept = 1;
        } else {
            b = c;
            gb = gc;
            if kept == -1 {
                ga *= 0.5;
            }
            kept = -1;
        }
    }
    0.5 * (a + b)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::patch::intersect::PatchIntersector;
    use crate::test_rng::{unit_f64, xorshift64};

    /// Hills and a valley over [-2, 2] x [-1.5, 1.5].
    fn hills(step: f32) -> HeightPatch {
        let heights = [
            0.0, 0.3, -0.2, 0.1, //
            0.4, 1.2, 0.8, -0.3, //
            -0.5, 0.9, -0.9, 0.6, //
            0.2, -0.1, 0.5, 0.0,
        ];
        HeightPatch {
            min: Vec2::new(-2.0, -1.5),
            max: Vec2::new(2.0, 1.5),
            heights,
            material: 0,
            march_step: step,
        }
    }

    #[test]
    fn the_bezier_form_is_the_same_surface() {
        let patch = hills(0.01);
        let bezier = patch.to_bezier();
        for k in 0..50 {
            let (u, v) = ((k as f64 * 0.137) % 1.0, (k as f64 * 0.291) % 1.0);
            let p = bezier.evaluate(u, v).position;
            let x = -2.0 + 4.0 * u;
            let z = -1.5 + 3.0 * v;
            assert!(
                (p.x - x).abs() < 1e-6 && (p.z - z).abs() < 1e-6,
                "{p} at ({u}, {v})"
            );
            assert!((p.y - patch.height(u, v).0).abs() < 1e-6);
        }
    }

    /// Random rays from above the patch, at least 20 degrees above the horizon: the marched
    /// hit (step 0.01) is the exact intersector's within 1e-6 in t, and both agree on which
    /// rays miss.
    #[test]
    fn marching_agrees_with_exact_intersection_at_random_rays() {
        assert_marching_matches_exact(&hills(0.01));
    }

    /// A flat tile (all heights equal, so its height box has no thickness) and a nearly flat
    /// one are found by marching as by the exact intersector. The flat one was missed by
    /// every ray: the march interval clipped to the box was a single point.
    #[test]
    fn flat_and_nearly_flat_tiles_are_found_by_marching() {
        let mut flat = hills(0.01);
        flat.heights = [0.3; 16];
        assert_marching_matches_exact(&flat);
        flat.heights[5] += 1e-7;
        assert_marching_matches_exact(&flat);
        flat.heights = [0.0; 16];
        assert_marching_matches_exact(&flat);
    }

    fn assert_marching_matches_exact(patch: &HeightPatch) {
        let exact = PatchIntersector::new(&patch.to_bezier().control);
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = || unit_f64(xorshift64(&mut state));
        let (mut hits, mut largest) = (0, 0.0f64);
        for _ in 0..2000 {
            let origin = DVec3::new(-3.0 + 6.0 * next(), 3.0 + 2.0 * next(), -2.5 + 5.0 * next());
            let target = DVec3::new(-2.2 + 4.4 * next(), 0.0, -1.7 + 3.4 * next());
            let direction = target - origin;
            let elevation = (-direction.y / direction.length()).asin();
            if elevation < 20f64.to_radians() {
                continue;
            }
            let ray = PatchRay {
                origin,
                direction,
                tnear: 0.0,
                tfar: f64::INFINITY,
            };
            let marched = patch.march(&ray);
            let traced = exact.intersect(&ray, false);
            match (marched, traced) {
                (Some(m), Some(e)) => {
                    hits += 1;
                    largest = largest.max((m.t - e.t).abs());
                    assert!((m.t - e.t).abs() < 1e-6, "t {} against {}", m.t, e.t);
                    assert!((m.u - e.u).abs() < 1e-5 && (m.v - e.v).abs() < 1e-5);
                    let angle = m.normal.normalize().dot(e.normal.normalize());
                    assert!(angle > 1.0 - 1e-9, "normals differ: {angle}");
                }
                (None, None) => {}
                (m, e) => panic!("marched {m:?}, exact {e:?} for {ray:?}"),
            }
        }
        eprintln!("{hits} hits, largest |t_march - t_exact| {largest:e}");
        assert!(hits > 500, "only {hits} rays hit");
    }
}
