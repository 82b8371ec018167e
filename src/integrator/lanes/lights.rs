//! Stage 5: the punctual lights seen from the lanes' points, one light at a time over all
//! lanes (`shading::sample_li`), and the shadow rays towards them
//! (`shading::shadow_ray_towards`, from the point offset past its error bound).

use glam::Vec3;

use super::{refill, WaveLanes};
use crate::scene::Light;
use crate::shading::{self, SpawnPoint};

/// Every light's direction and irradiance scale at every lane's point, light-major
/// (`lanes.light_direction[light * lanes + lane]`).
// Not inlined: one call per wave, and `perf` attributes each stage's time to it.
#[inline(never)]
pub(crate) fn sample_lights(lanes: &mut WaveLanes, lights: &[Light]) {
    let len = lanes.len();
    refill(&mut lanes.light_direction, len * lights.len(), Vec3::ZERO);
    refill(&mut lanes.light_scale, len * lights.len(), Vec3::ZERO);
    for (index, light) in lights.iter().enumerate() {
        let first = index * len;
        for lane in 0..len {
            let sample = shading::sample_li(light, lanes.position[lane]);
            lanes.light_direction[first + lane] = sample.direction_to_light;
            lanes.light_scale[first + lane] = sample.radiance_scale;
        }
    }
}

/// The shadow rays of the lit lanes and lights (after [`super::bsdf::eval_lights`]): their
/// origins per lane, and per lane and light the direction and far end into
/// `shadow_direction` and `shadow_tfar`; a lane whose ray has no direction is unlit.
// Not inlined: one call per wave, and `perf` attributes each stage's time to it.
#[inline(never)]
pub(crate) fn shadow_rays(lanes: &mut WaveLanes, lights: &[Light]) {
    let len = lanes.len();
    refill(&mut lanes.shadow_origin, len, Vec3::ZERO);
    for lane in 0..len {
        let spawn = SpawnPoint {
            position: lanes.position[lane],
            error: lanes.error[lane],
        };
        lanes.shadow_origin[lane] = spawn.offset_origin(lanes.incident_geometric[lane]);
    }
    refill(&mut lanes.shadow_direction, len * lights.len(), Vec3::ZERO);
    refill(&mut lanes.shadow_tfar, len * lights.len(), 0.0);
    for (index, light) in lights.iter().enumerate() {
        let target = shading::light_position(light).map(|p| (p.as_dvec3(), 0.0));
        let first = index * len;
        for lane in 0..len {
            let at = first + lane;
            if !lanes.lit[at] {
                continue;
            }
            let origin = lanes.shadow_origin[lane];
            match shading::shadow_ray_towards(origin, target, lanes.light_direction[at]) {
                Some((direction, tfar)) => {
                    lanes.shadow_direction[at] = direction;
                    lanes.shadow_tfar[at] = tfar;
                }
                None => lanes.lit[at] = false,
            }
        }
    }
}
