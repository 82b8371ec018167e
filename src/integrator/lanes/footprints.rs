//! Stage 3: footprints at the hits and the texture gradients they give, for the lanes that
//! read a texture (`footprint::Footprint::texture_gradients` over lane arrays: the cone's
//! circle projected onto the tangent plane as an ellipse, whose axes map to st through the
//! triangle's barycentric derivatives, on spheres through dP/ds and dP/dt, on patches
//! through the patch's own derivatives).

use std::ops::Range;

use glam::{Vec2, Vec3};

use super::differentials::{differential_axes, LaneDifferential};
use super::patches::{derivatives, patch_st_axes};
use super::soa::corner_lanes_2;
use super::{LaneArray, LaneSections, WaveLanes};
use crate::footprint::robust::{unit_direction, unit_normal, unit_or};
use crate::footprint::{
    general_st_offset, lat_long_frame, project_cone_to_ellipse, Footprint, RayDifferential,
    TextureGradients,
};
use crate::simd;

/// A footprint at a hit as the lanes take it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum LaneFootprint {
    /// No footprint: texture lookups are point samples at level 0.
    Point,
    /// A cone-like footprint (distance metric, one cone, the two-cone envelope) this wide
    /// at the hit.
    Cone(f32),
    /// A ray differential, moved to the hit once the lanes hold its normal
    /// (`differentials::differentials_at_hits`).
    Differential(LaneDifferential),
}

/// `footprint` moved `t` along its ray (`Footprint::propagated`) as the lanes take it: a
/// cone's width there, or a differential still to be transferred.
#[inline]
pub(crate) fn lane_footprint(footprint: &Footprint, t: f32) -> LaneFootprint {
    match (footprint, footprint.propagated(t)) {
        (Footprint::Differential(d), _) => {
            LaneFootprint::Differential(LaneDifferential::Carried(*d))
        }
        (_, Some(Footprint::Distance(f))) => LaneFootprint::Cone(f.width()),
        (_, Some(Footprint::Cone1(c))) => LaneFootprint::Cone(c.abs_width()),
        (_, Some(Footprint::Cone(e))) => LaneFootprint::Cone(e.width()),
        _ => LaneFootprint::Point,
    }
}

/// Texture gradients of every lane into `lanes.gradients`: zero (a point sample) for lanes
/// without a footprint (`lanes.cone_width` `None` and no differential), or without texture
/// coordinates; otherwise the footprint's world-space axes mapped to st: a cone's ellipse,
/// its stretch clamped to `max_aniso`, or a differential's dP/dx, dP/dy at the hit (after
/// `differentials::differentials_at_hits`; the texture filter clamps their anisotropy).
///
/// One vector loop ([`barycentric_gradients`]) does every lane on a triangle with usable
/// barycentric offsets, another ([`sphere_gradients`]) every sphere lane; the few on
/// degenerate triangles are done again, lane by lane, through dP/ds and dP/dt. Patch lanes
/// take theirs lane by lane ([`patch_gradients`]).
// Not inlined: one call per wave, and `perf` attributes each stage's time to it.
#[inline(never)]
pub(crate) fn texture_gradients(lanes: &mut WaveLanes, max_aniso: f32) {
    let len = lanes.len();
    if !lanes.differential.is_empty() {
        // A render's footprints follow one strategy: every footprint of this wave is a
        // differential.
        let carried = std::mem::take(&mut lanes.differential);
        let at_hit = std::mem::take(&mut lanes.differential_at_hit);
        let source = DifferentialAxes {
            carried: &carried[..len],
            at_hit: &at_hit[..len],
        };
        gradients_from(lanes, source);
        lanes.differential = carried;
        lanes.differential_at_hit = at_hit;
        return;
    }
    if lanes.cone_width[..len].iter().all(Option::is_none) {
        // Point samples only (mip0, or no textured lane): no ellipse is projected.
        super::refill(&mut lanes.gradients, len, [0.0; 4]);
        return;
    }
    // Out of the lanes while the stage writes them (the allocation goes back at the end).
    let cone_width = std::mem::take(&mut lanes.cone_width);
    let source = ConeAxes {
        width: &cone_width[..len],
        max_aniso,
    };
    gradients_from(lanes, source);
    lanes.cone_width = cone_width;
}

/// The gradients of every lane, its footprint's axes taken from `source`.
#[inline(always)]
fn gradients_from(lanes: &mut WaveLanes, source: impl FootprintAxes) {
    let len = lanes.len();
    let LaneSections {
        triangles,
        spheres,
        patches,
    } = lanes.sections();
    lanes.gradients.resize_lanes(len, [0.0; 4]);
    lanes.degenerate.resize_lanes(len, false);
    simd::run_at(
        lanes.level(),
        #[inline(always)]
        || {
            barycentric_gradients(lanes, source.slice(triangles.clone()));
            sphere_gradients(lanes, source.slice(spheres.clone()), spheres.clone());
        },
    );
    patch_gradients(lanes, source.slice(patches.clone()), patches);
    for lane in 0..len {
        if lanes.degenerate[lane] {
            let d = unit_direction(lanes.direction.get(lane));
            let n = unit_normal(lanes.geometric_normal.get(lane), d);
            let (dpdx, dpdy) = source.axes(lane, d, n);
            let g = if triangles.contains(&lane) {
                triangle_gradients(lanes, lane, dpdx, dpdy)
            } else {
                unframed_sphere_gradients(lanes, lane, dpdx, dpdy)
            };
            lanes.gradients[lane] = [g.dsdx, g.dtdx, g.dsdy, g.dtdy];
        }
    }
}

/// Where the gradient loops take each lane's footprint from: which lanes have one, and its
/// world-space axes on the tangent plane, given the lane's unit direction `d` and unit
/// normal `n` facing it.
trait FootprintAxes: Copy {
    /// The source's lanes `range` (of the lanes it was made for), indexed from 0.
    fn slice(self, range: Range<usize>) -> Self;
    fn len(&self) -> usize;
    fn has_footprint(&self, lane: usize) -> bool;
    fn axes(&self, lane: usize, d: Vec3, n: Vec3) -> (Vec3, Vec3);
}

/// Cone-like footprints: each lane's width at the hit, its circle projected as an ellipse
/// (`project_cone_to_ellipse`).
#[derive(Clone, Copy)]
struct ConeAxes<'a> {
    width: &'a [Option<f32>],
    max_aniso: f32,
}

impl FootprintAxes for ConeAxes<'_> {
    #[inline(always)]
    fn slice(self, range: Range<usize>) -> Self {
        ConeAxes {
            width: &self.width[range],
            ..self
        }
    }

    #[inline(always)]
    fn len(&self) -> usize {
        self.width.len()
    }

    #[inline(always)]
    fn has_footprint(&self, lane: usize) -> bool {
        self.width[lane].is_some()
    }

    #[inline(always)]
    fn axes(&self, lane: usize, d: Vec3, n: Vec3) -> (Vec3, Vec3) {
        let width = self.width[lane].unwrap_or(0.0);
        project_cone_to_ellipse(width, d, n, self.max_aniso)
    }
}

/// Ray differentials: each lane's, moved to its hit.
#[derive(Clone, Copy)]
struct DifferentialAxes<'a> {
    carried: &'a [Option<LaneDifferential>],
    at_hit: &'a [RayDifferential],
}

impl FootprintAxes for DifferentialAxes<'_> {
    #[inline(always)]
    fn slice(self, range: Range<usize>) -> Self {
        DifferentialAxes {
            carried: &self.carried[range.clone()],
            at_hit: &self.at_hit[range],
        }
    }

    #[inline(always)]
    fn len(&self) -> usize {
        self.carried.len()
    }

    #[inline(always)]
    fn has_footprint(&self, lane: usize) -> bool {
        self.carried[lane].is_some()
    }

    #[inline(always)]
    fn axes(&self, lane: usize, _d: Vec3, _n: Vec3) -> (Vec3, Vec3) {
        differential_axes(self.at_hit, lane)
    }
}

/// The gradients of every lane whose triangle gives barycentric offsets for the
/// footprint's first axis (`triangle_gradients`' first case, without branches), and in
/// `lanes.degenerate` the textured lanes whose triangle does not.
#[inline(always)]
fn barycentric_gradients(lanes: &mut WaveLanes, source: impl FootprintAxes) {
    let len = source.len();
    let direction = lanes.direction.lanes(len);
    let normal = lanes.geometric_normal.lanes(len);
    let (e1, e2) = (lanes.edge1.lanes(len), lanes.edge2.lanes(len));
    let area_normal = lanes.area_normal.lanes(len);
    let [[s0, t0], [s1, t1], [s2, t2]] = corner_lanes_2(&lanes.st_vertices, len);
    let has_st = &lanes.has_st[..len];
    let gradients = &mut lanes.gradients[..len];
    let degenerate = &mut lanes.degenerate[..len];
    for lane in 0..len {
        let textured = source.has_footprint(lane) && has_st[lane];
        let d = unit_direction(direction.get(lane));
        let n = unit_normal(normal.get(lane), d);
        let (dpdx, dpdy) = source.axes(lane, d, n);
        let frame = BarycentricFrame {
            e1: e1.get(lane),
            e2: e2.get(lane),
            n: area_normal.get(lane),
        };
        let st0 = Vec2::new(s0[lane], t0[lane]);
        let st1 = Vec2::new(s1[lane], t1[lane]);
        let st2 = Vec2::new(s2[lane], t2[lane]);
        let along = |b: Vec2| (st1 - st0) * b.x + (st2 - st0) * b.y;
        let x_offsets = frame.offsets(dpdx);
        let ddx = x_offsets.map_or(Vec2::ZERO, along);
        let ddy = frame.offsets(dpdy).map_or(Vec2::ZERO, along);
        let g = TextureGradients::from_axes(ddx, ddy);
        let barycentric = textured && x_offsets.is_some();
        gradients[lane] = if barycentric {
            [g.dsdx, g.dtdx, g.dsdy, g.dtdy]
        } else {
            [0.0; 4]
        };
        degenerate[lane] = textured && x_offsets.is_none();
    }
}

/// The gradients of every sphere lane `spheres` (`source` holding their footprints) with
/// dP/ds or dP/dt
/// (`footprint::surface_gradients` on a sphere, its first case), and in `lanes.degenerate`
/// the textured lanes without either.
#[inline(always)]
fn sphere_gradients(lanes: &mut WaveLanes, source: impl FootprintAxes, spheres: Range<usize>) {
    let direction = lanes.direction.range(spheres.clone());
    let normal = lanes.geometric_normal.range(spheres.clone());
    let (dpds, dpdt) = (
        lanes.dpds.range(spheres.clone()),
        lanes.dpdt.range(spheres.clone()),
    );
    let has_st = &lanes.has_st[spheres.clone()];
    let gradients = &mut lanes.gradients[spheres.clone()];
    let degenerate = &mut lanes.degenerate[spheres];
    for k in 0..source.len() {
        let textured = source.has_footprint(k) && has_st[k];
        let d = unit_direction(direction.get(k));
        let n = unit_normal(normal.get(k), d);
        let (dpdx, dpdy) = source.axes(k, d, n);
        let (dpds, dpdt) = (dpds.get(k), dpdt.get(k));
        let framed = dpds != Vec3::ZERO || dpdt != Vec3::ZERO;
        let g = TextureGradients::from_axes(
            general_st_offset(dpds, dpdt, dpdx),
            general_st_offset(dpds, dpdt, dpdy),
        );
        gradients[k] = if textured && framed {
            [g.dsdx, g.dtdx, g.dsdy, g.dtdy]
        } else {
            [0.0; 4]
        };
        degenerate[k] = textured && !framed;
    }
}

/// The gradients of every patch lane `patches` (`source` holding their footprints) with
/// texture coordinates: the footprint's axes mapped to st through the patch's derivatives
/// at the hit (`footprint::surface_gradients` on a curved patch). A patch always has them,
/// so no lane is left to the degenerate case.
fn patch_gradients(lanes: &mut WaveLanes, source: impl FootprintAxes, patches: Range<usize>) {
    for (k, lane) in patches.enumerate() {
        lanes.degenerate[lane] = false;
        lanes.gradients[lane] = if source.has_footprint(k) && lanes.has_st[lane] {
            let d = unit_direction(lanes.direction.get(lane));
            let n = unit_normal(lanes.geometric_normal.get(lane), d);
            let (dpdx, dpdy) = source.axes(k, d, n);
            let [ddx, ddy] = patch_st_axes(derivatives(lanes, lane), dpdx, dpdy);
            let g = TextureGradients::from_axes(ddx, ddy);
            [g.dsdx, g.dtdx, g.dsdy, g.dtdy]
        } else {
            [0.0; 4]
        };
    }
}

/// The st axes of the world-space footprint axes `dpdx`, `dpdy` on lane `lane`'s sphere
/// when its hit has neither dP/ds nor dP/dt: the lat-long frame at its point
/// (`footprint::surface_gradients`' fallback).
fn unframed_sphere_gradients(
    lanes: &WaveLanes,
    lane: usize,
    dpdx: Vec3,
    dpdy: Vec3,
) -> TextureGradients {
    let n = unit_or(
        lanes.sphere_point.get(lane) - lanes.center.get(lane),
        Vec3::Y,
    );
    let (_, dpds, dpdt) = lat_long_frame(n, lanes.radius[lane]);
    TextureGradients::from_axes(
        general_st_offset(dpds, dpdt, dpdx),
        general_st_offset(dpds, dpdt, dpdy),
    )
}

/// The st axes of the world-space footprint axes `dpdx`, `dpdy` on lane `lane`'s triangle:
/// barycentric, or through dP/ds, dP/dt where the triangle is degenerate
/// (`footprint::surface_gradients`).
fn triangle_gradients(lanes: &WaveLanes, lane: usize, dpdx: Vec3, dpdy: Vec3) -> TextureGradients {
    let frame = BarycentricFrame {
        e1: lanes.edge1.get(lane),
        e2: lanes.edge2.get(lane),
        n: lanes.area_normal.get(lane),
    };
    let st = [0, 1, 2].map(|i| lanes.st_vertices[i].get(lane));
    let (ddx, ddy) = match frame.offsets(dpdx) {
        Some(bx) => {
            let along = |b: Vec2| (st[1] - st[0]) * b.x + (st[2] - st[0]) * b.y;
            (along(bx), frame.offsets(dpdy).map_or(Vec2::ZERO, along))
        }
        None => {
            let p = [0, 1, 2].map(|i| lanes.p[i].get(lane));
            let (dpds, dpdt) = crate::render::prepared::triangle_position_derivatives(p, st);
            (
                general_st_offset(dpds, dpdt, dpdx),
                general_st_offset(dpds, dpdt, dpdy),
            )
        }
    };
    TextureGradients::from_axes(ddx, ddy)
}

/// A triangle's edges `e1 = p1 - p0`, `e2 = p2 - p0` and `n = e1 x e2`, from which
/// barycentric offsets follow (`footprint::barycentric_offsets`, whose operations these are,
/// with the edges interpolation already computed).
struct BarycentricFrame {
    e1: Vec3,
    e2: Vec3,
    n: Vec3,
}

impl BarycentricFrame {
    /// Barycentric offsets (du, dv) of the displacement `d`; `None` for a degenerate
    /// triangle or non-finite offsets.
    #[inline(always)]
    fn offsets(&self, d: Vec3) -> Option<Vec2> {
        let (e1, e2, n) = (self.e1, self.e2, self.n);
        let nn = n.length_squared();
        let scale = e1.length_squared() * e2.length_squared();
        if !(nn.is_finite() && scale.is_finite()) || nn <= 1.0e-12 * scale || nn < 1.0e-36 {
            return None;
        }
        let inv = nn.recip();
        let du = d.cross(e2).dot(n) * inv;
        let dv = e1.cross(d).dot(n) * inv;
        (du.is_finite() && dv.is_finite()).then_some(Vec2::new(du, dv))
    }
}
