//! Stage 5: the punctual lights seen from the lanes' points, one light at a time over all
//! lanes (`shading::sample_li`), and the shadow rays towards them
//! (`shading::shadow_ray_towards`, from the point offset past its error bound).
//!
//! The loops read and write one array per coordinate and run at the level
//! `simd::dispatch` picks, with the scalar functions' operations in their order.

use std::ops::Range;

use glam::Vec3;

use super::soa::Vec3Slices;
use super::{LaneArray, WaveLanes};
use crate::scene::Light;
use crate::shading::{self, SpawnPoint};
use crate::simd;

/// Every light's direction and irradiance scale at the point of every lane with an opaque
/// lobe, light-major (`lanes.light_direction.x[light * lanes + lane]`). The lanes of a
/// material without one (a perfect mirror, clear glass) reflect no light towards the
/// viewer: their entries are left as they were, and `bsdf::eval_lights` leaves them unlit.
// Not inlined: one call per wave, and `perf` attributes each stage's time to it.
#[inline(never)]
pub(crate) fn sample_lights(lanes: &mut WaveLanes, lights: &[Light]) {
    let len = lanes.len();
    lanes.light_direction.resize(len * lights.len());
    lanes.light_scale.resize(len * lights.len());
    simd::run_at(
        lanes.level(),
        #[inline(always)]
        || {
            for (index, light) in lights.iter().enumerate() {
                for run in 0..lanes.material_runs.len() {
                    if let Some(range) = lanes.opaque_run(run) {
                        sample_light(lanes, light, index * len, range);
                    }
                }
            }
        },
    );
}

/// One light at the lanes `range`, into the per-light arrays starting at `first`. Point
/// lights, the common case, get a loop of their own, without the match on the light's kind.
#[inline(always)]
fn sample_light(lanes: &mut WaveLanes, light: &Light, first: usize, lanes_range: Range<usize>) {
    let len = lanes_range.len();
    let position = lanes.position.range(lanes_range.clone());
    let range = first + lanes_range.start..first + lanes_range.end;
    let [dx, dy, dz] = [
        &mut lanes.light_direction.x[range.clone()],
        &mut lanes.light_direction.y[range.clone()],
        &mut lanes.light_direction.z[range.clone()],
    ];
    let [sx, sy, sz] = [
        &mut lanes.light_scale.x[range.clone()],
        &mut lanes.light_scale.y[range.clone()],
        &mut lanes.light_scale.z[range],
    ];
    let mut store = |lane: usize, sample: shading::LightSample| {
        (dx[lane], dy[lane], dz[lane]) = sample.direction_to_light.into();
        (sx[lane], sy[lane], sz[lane]) = sample.radiance_scale.into();
    };
    match light {
        Light::Point {
            position: at,
            color,
            intensity,
        } => {
            let radiant_intensity = *color * *intensity;
            for lane in 0..len {
                let p = position.get(lane);
                store(
                    lane,
                    shading::lights::point_sample(*at, p, radiant_intensity),
                );
            }
        }
        _ => {
            for lane in 0..len {
                store(lane, shading::sample_li(light, position.get(lane)));
            }
        }
    }
}

/// The shadow rays of the lit lanes and lights (after [`super::bsdf::eval_lights`]): their
/// origins per lane, and per lane and light the direction and far end into
/// `shadow_direction` and `shadow_tfar`; a lane whose ray has no direction is unlit. The
/// lanes of a material without an opaque lobe, unlit, get no segment.
// Not inlined: one call per wave, and `perf` attributes each stage's time to it.
#[inline(never)]
pub(crate) fn shadow_rays(lanes: &mut WaveLanes, lights: &[Light]) {
    let len = lanes.len();
    lanes.shadow_origin.resize(len);
    lanes.shadow_direction.resize(len * lights.len());
    lanes.shadow_tfar.resize_lanes(len * lights.len(), 0.0);
    simd::run_at(
        lanes.level(),
        #[inline(always)]
        || {
            shadow_origins(lanes);
            for (index, light) in lights.iter().enumerate() {
                for run in 0..lanes.material_runs.len() {
                    if let Some(range) = lanes.opaque_run(run) {
                        shadow_segments(lanes, light, index * len, range);
                    }
                }
            }
        },
    );
}

/// Each lane's point moved past its error bound to the viewer's side.
#[inline(always)]
fn shadow_origins(lanes: &mut WaveLanes) {
    let len = lanes.len();
    let position = lanes.position.lanes(len);
    let error = lanes.error.lanes(len);
    let normal = lanes.incident_geometric.lanes(len);
    let mut origin = lanes.shadow_origin.lanes_mut(len);
    for lane in 0..len {
        let spawn = SpawnPoint {
            position: position.get(lane),
            error: error.get(lane),
        };
        origin.set(lane, spawn.offset_origin(normal.get(lane)));
    }
}

/// The segments towards one light of the lanes `lanes_range` it lights, per-light arrays
/// from `first`.
#[inline(always)]
fn shadow_segments(lanes: &mut WaveLanes, light: &Light, first: usize, lanes_range: Range<usize>) {
    let len = lanes_range.len();
    let target = shading::light_position(light).map(|p| (p.as_dvec3(), 0.0));
    let origin: Vec3Slices = lanes.shadow_origin.range(lanes_range.clone());
    let range = first + lanes_range.start..first + lanes_range.end;
    let to_light = Vec3Slices {
        x: &lanes.light_direction.x[range.clone()],
        y: &lanes.light_direction.y[range.clone()],
        z: &lanes.light_direction.z[range.clone()],
    };
    let [dx, dy, dz] = [
        &mut lanes.shadow_direction.x[range.clone()],
        &mut lanes.shadow_direction.y[range.clone()],
        &mut lanes.shadow_direction.z[range.clone()],
    ];
    let tfar = &mut lanes.shadow_tfar[range.clone()];
    let lit = &mut lanes.lit[range];
    for lane in 0..len {
        let segment = shading::shadow_ray_towards(origin.get(lane), target, to_light.get(lane));
        let (direction, end) = segment.unwrap_or((Vec3::ZERO, 0.0));
        (dx[lane], dy[lane], dz[lane]) = direction.into();
        tfar[lane] = end;
        lit[lane] &= segment.is_some();
    }
}
