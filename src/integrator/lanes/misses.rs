//! A wave's rays that leave the scene, their environment radiance looked up together: the
//! lat-long map read in one batch per filter (`Texture::sample_batch`), a constant colour
//! filled in, each miss's radiance with the bits of `texturing::environment_lookup` (or,
//! for a miss that finds the environment as a light, `texturing::environment_light_lookup`).
//!
//! What a miss adds to its pixel stays the integrator's, added in the wave's order, so film
//! sums are those of the scalar path.

use glam::{Vec3, Vec4};

use super::LaneArray;
use crate::footprint::{direction_to_lat_long, Footprint};
use crate::render::context::{RenderContext, WorkerState};
use crate::render::tracer::TraceHit;
use crate::scene::Environment;
use crate::texture::{FilterMode, FilterOptions, TextureQuery};

/// `MissLanes::miss_of_ray` for a ray that is not a miss the lanes take.
const NOT_A_MISS: u32 = u32::MAX;

/// The misses of the wave being shaded, reused from wave to wave.
#[derive(Default)]
pub(crate) struct MissLanes {
    /// Per ray of the wave: its miss, or [`NOT_A_MISS`].
    miss_of_ray: Vec<u32>,
    /// Per miss: the unit direction it leaves along.
    direction: Vec<Vec3>,
    /// Whether it reads the environment as a light does (the nearest level-0 texel), as a
    /// ray a non-delta lobe sampled does, rather than through its footprint.
    as_light: Vec<bool>,
    /// The footprint's gradients in the map (`Footprint::environment_gradients`), zero
    /// when footprints are off or the miss reads it as a light.
    gradients: Vec<[f32; 4]>,
    /// The environment's radiance along each miss.
    radiance: Vec<Vec3>,
    // One batch's queries, the misses they are for, and their texels.
    queries: Vec<TextureQuery>,
    batch: Vec<u32>,
    texels: Vec<Vec4>,
}

impl MissLanes {
    /// Forget the previous wave's misses; the wave has `rays` rays.
    fn clear(&mut self, rays: usize) {
        self.miss_of_ray.clear();
        self.miss_of_ray.resize_lanes(rays, NOT_A_MISS);
        self.direction.clear();
        self.as_light.clear();
        self.gradients.clear();
    }

    /// Take the wave's ray `ray`, which left the scene along `direction`: as a light's
    /// lookup (`as_light`), or through the footprint gradients `gradients`.
    #[inline]
    fn push(&mut self, ray: usize, direction: Vec3, as_light: bool, gradients: [f32; 4]) {
        self.miss_of_ray[ray] = self.as_light.len() as u32;
        self.direction.push(direction);
        self.as_light.push(as_light);
        self.gradients.push(gradients);
    }

    /// The environment's radiance along the wave's ray `ray`, if the lanes took it.
    #[inline]
    pub(crate) fn radiance_of(&self, ray: usize) -> Option<Vec3> {
        let miss = self.miss_of_ray[ray];
        (miss != NOT_A_MISS).then(|| self.radiance[miss as usize])
    }

    fn len(&self) -> usize {
        self.as_light.len()
    }
}

/// What a miss of the wave needs for its lookup: its unit direction, its footprint, and
/// whether it finds the environment as a light (a ray a non-delta lobe sampled, which reads
/// the nearest level-0 texel as light sampling does) rather than seeing it whole through
/// its footprint.
pub(crate) struct Escape<'a> {
    pub direction: Vec3,
    pub footprint: &'a Footprint,
    pub as_light: bool,
}

/// Take the misses among a wave's `rays` (`hits` in the same order) into `misses`, none
/// unless `takes`, and look up the environment along all of them; `escape(index, ray)`
/// tells what the miss of the wave's ray `index` needs for its lookup, or `None` to leave
/// it to the integrator's scalar path.
// Not inlined: one call per wave, and `perf` attributes each stage's time to it.
#[inline(never)]
pub(crate) fn look_up_misses<'a, R>(
    context: &RenderContext,
    misses: &mut MissLanes,
    (rays, hits): (&'a [R], &[TraceHit]),
    takes: bool,
    escape: impl Fn(usize, &'a R) -> Option<Escape<'a>>,
    worker: &mut WorkerState,
) {
    misses.clear(rays.len());
    if !takes {
        return;
    }
    // `texturing::environment_lookup`: a constant colour reads no texture, so no
    // footprint gradients either.
    let filtered = context.effects.footprints
        && matches!(context.scene.environment, Environment::LatLong { .. });
    for (index, (ray, hit)) in rays.iter().zip(hits).enumerate() {
        if hit.is_hit() {
            continue;
        }
        let Some(escape) = escape(index, ray) else {
            continue;
        };
        let gradients = if filtered && !escape.as_light {
            let g = escape.footprint.environment_gradients(escape.direction);
            [g.dsdx, g.dtdx, g.dsdy, g.dtdy]
        } else {
            [0.0; 4]
        };
        misses.push(index, escape.direction, escape.as_light, gradients);
    }
    if misses.len() > 0 {
        worker.counters.lane_misses += misses.len() as u64;
        environment_radiances(context, misses, worker);
    }
}

/// The environment's radiance along every miss, into `misses.radiance`.
fn environment_radiances(
    context: &RenderContext,
    misses: &mut MissLanes,
    worker: &mut WorkerState,
) {
    let len = misses.len();
    misses.radiance.clear();
    match &context.scene.environment {
        Environment::Color(c) => misses.radiance.resize_lanes(len, *c),
        Environment::LatLong { texture, intensity } => {
            misses.radiance.resize_lanes(len, Vec3::ZERO);
            worker.counters.texture_lookups += len as u64;
            let filtered = context.texture_filters[*texture];
            let closest = FilterOptions {
                filter: FilterMode::Closest,
                ..filtered
            };
            for (as_light, options) in [(false, filtered), (true, closest)] {
                let lookup = MapLookup {
                    texture: *texture,
                    intensity: *intensity,
                    options,
                };
                look_up_batch(context, misses, as_light, &lookup);
            }
        }
    }
}

/// One batch of lookups into the environment's lat-long map.
struct MapLookup {
    texture: usize,
    intensity: f32,
    options: FilterOptions,
}

/// The radiance of the misses whose `as_light` is `as_light`, read from the map with
/// `lookup.options` (`render::prepared::environment_radiance`'s lookup and its clamp).
fn look_up_batch(
    context: &RenderContext,
    misses: &mut MissLanes,
    as_light: bool,
    lookup: &MapLookup,
) {
    let MissLanes {
        direction,
        as_light: reads_as_light,
        gradients,
        radiance,
        queries,
        batch,
        texels,
        ..
    } = misses;
    batch.clear();
    batch.extend(
        (0..reads_as_light.len() as u32).filter(|&m| reads_as_light[m as usize] == as_light),
    );
    if batch.is_empty() {
        return;
    }
    queries.clear();
    queries.extend(batch.iter().map(|&m| {
        let st = direction_to_lat_long(direction[m as usize]);
        let g = gradients[m as usize];
        TextureQuery {
            s: st.x,
            t: st.y,
            dsdx: g[0],
            dtdx: g[1],
            dsdy: g[2],
            dtdy: g[3],
        }
    }));
    texels.clear();
    texels.resize_lanes(queries.len(), Vec4::ZERO);
    match context.external_textures.as_deref() {
        Some(external) => {
            for (query, texel) in queries.iter().zip(texels.iter_mut()) {
                *texel = crate::render::external_textures::sample_external(
                    external,
                    lookup.texture,
                    query,
                    &lookup.options,
                );
            }
        }
        // The scalar lookup records no texture tiles: neither does the batch.
        None => {
            context.textures[lookup.texture].sample_batch(queries, &lookup.options, None, texels)
        }
    }
    for (&m, texel) in batch.iter().zip(texels.iter()) {
        // Radiance is never negative (`environment_radiance`'s clamp).
        let value = (texel.truncate() * lookup.intensity).max(Vec3::ZERO);
        radiance[m as usize] = value;
    }
}
