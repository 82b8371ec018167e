//! Stages 1 and 2 on curved and height patches: each patch lane's surface at its hit's
//! (u, v), evaluated as `render::patch_geometry::patch_surface_hit` evaluates it (the
//! patch's Bernstein sums in double precision, its normal, the point's error bound, texture
//! coordinates and dP/ds, dP/dt), into the lane arrays the later stages read, and the exact
//! first and second derivatives that the footprints map to st
//! (`footprint::curved_st_offset`).
//!
//! Lane by lane: a patch's evaluation is sixteen control points in f64, with a normal
//! found from just inside a collapsed edge, which no vector loop over lanes would run
//! faster. What the lanes save on patches is what follows the evaluation: no `SurfaceHit`
//! record, lookups batched per texture, lights and lobes over the lanes.

use glam::{Vec2, Vec3};

use super::WaveLanes;
use crate::hit::CurvedFrame;
use crate::render::patch_geometry::patch_surface_point;
use crate::scene::patch::height::HeightPatch;
use crate::scene::patch::BezierPatch;

/// A patch lane's exact derivatives at its hit (`hit::Patch::Curved` without the error
/// bound, which the lanes hold in `WaveLanes::error`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct PatchDerivatives {
    pub frame: CurvedFrame,
    /// The derivatives of the texture coordinates with respect to the patch's u and v.
    pub dstdu: Vec2,
    pub dstdv: Vec2,
}

/// Evaluate every patch lane's surface at its hit, after [`super::interpolate::interpolate`]
/// (which sizes the arrays for every lane): the spawn point and its error bound, the normal
/// (geometric and shading), and for lanes that want texture coordinates, those and dP/ds,
/// dP/dt (zero elsewhere); the derivatives into `lanes.patch_derivatives`.
// Not inlined: one call per wave, and `perf` attributes each stage's time to it.
#[inline(never)]
pub(crate) fn evaluate_patches(
    lanes: &mut WaveLanes,
    patches: &[BezierPatch],
    height_patches: &[HeightPatch],
) {
    let section = lanes.sections().patches;
    lanes.patch_derivatives.clear();
    for lane in section {
        let primitive = lanes.primitive[lane] as usize;
        let wants_st = lanes.wants_st[lane];
        let uv = (lanes.u[lane], lanes.v[lane]);
        // A height patch is shaded as the same surface made a Bezier patch, as the scalar
        // path shades it.
        let point = if lanes.height_patch[lane] {
            patch_surface_point(&height_patches[primitive].to_bezier(), uv, wants_st)
        } else {
            patch_surface_point(&patches[primitive], uv, wants_st)
        };
        lanes.has_st[lane] = wants_st;
        lanes.position.set(lane, point.spawn.position);
        lanes.error.set(lane, point.spawn.error);
        lanes.geometric_normal.set(lane, point.normal);
        lanes.shading_normal.set(lane, point.normal);
        lanes.st.set(lane, point.st);
        lanes.dpds.set(lane, point.dpds);
        lanes.dpdt.set(lane, point.dpdt);
        lanes.patch_derivatives.push(PatchDerivatives {
            frame: point.frame,
            dstdu: point.dstdu,
            dstdv: point.dstdv,
        });
    }
}

/// The derivatives of patch lane `lane`.
#[inline]
pub(crate) fn derivatives(lanes: &WaveLanes, lane: usize) -> &PatchDerivatives {
    &lanes.patch_derivatives[lane - lanes.patches_start]
}

/// The surface displacements `dpdx`, `dpdy` on a patch as st offsets
/// (`footprint::surface_gradients` on `Patch::Curved`).
#[inline]
pub(crate) fn patch_st_axes(derivatives: &PatchDerivatives, dpdx: Vec3, dpdy: Vec3) -> [Vec2; 2] {
    let PatchDerivatives {
        frame,
        dstdu,
        dstdv,
    } = derivatives;
    [dpdx, dpdy].map(|d| crate::footprint::curved_st_offset(frame, *dstdu, *dstdv, d))
}
