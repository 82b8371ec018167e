//! Ray batches through Embree: the render stage's only door into `crate::embree`.
//!
//! The integrator works on slices of rays (a 4x4 tile of camera rays, a wave of secondary
//! rays, a batch of shadow rays); this file cuts them into packets of the device's native
//! width and copies hits back. Camera rays of a 4x4 pixel block sit in consecutive slots,
//! so a 16-wide packet is exactly one block.
//!
//! A batch whose traversal failed (an error Embree reported, or an alpha filter that
//! panicked) must never pass for misses: the tracer keeps the first such failure, raises
//! its failure flag (the render driver stops handing out tiles when it sees it) and the
//! render ends with that error ([`Tracer::take_failure`]).
//!
//! Alpha-test filters are installed as the render's effect set says ([`AlphaTests`]): none
//! when the scene has no cut-out, on cut-out meshes when it has, on every mesh for the
//! general path.

use glam::Vec3;

/// A ray to trace: unit direction, `t` in (0, tfar].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TraceRay {
    pub origin: Vec3,
    pub direction: Vec3,
    pub tfar: f32,
    /// Cone width at the origin and spread angle, for alpha-cutout callbacks.
    pub cone_width: f32,
    pub cone_spread: f32,
}

/// The closest hit of a [`TraceRay`], or a miss (`geometry == u32::MAX`).
///
/// `u` and `v` come first: a copied hit is written as 16 bytes plus 4, and the barycentrics,
/// read together as 8 bytes, must lie within one of those stores. Read across both they
/// cannot be forwarded from the store buffer, which stalled every hit reconstruction for
/// 2.5 % of the albedo plane's render time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TraceHit {
    pub u: f32,
    pub v: f32,
    pub t: f32,
    pub geometry: u32,
    pub primitive: u32,
}

impl TraceHit {
    pub const MISS: TraceHit = TraceHit {
        t: f32::INFINITY,
        geometry: u32::MAX,
        primitive: u32::MAX,
        u: 0.0,
        v: 0.0,
    };

    #[inline]
    pub fn is_hit(&self) -> bool {
        self.geometry != u32::MAX
    }
}

use std::cell::{Cell, RefCell};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

use crate::embree::{
    CommittedScene, Device, EmbreeError, FilterCandidate, Ray, RayHit, RayPacket, RayPayload,
    SceneBuilder, TraceOptions,
};
use crate::render::context::RenderOptions;
use crate::render::effects::EffectSet;
use crate::render::prepared::{GeometryRef, PrepareError};
use crate::render::stats::WorkCounters;
use crate::scene::SceneDescription;
use crate::texture::{FilterMode, FilterOptions, Texture, TextureQuery};

thread_local! {
    /// Alpha-filter callbacks run on this thread since the last trace call drained it.
    static FILTER_CALLS: Cell<u64> = const { Cell::new(0) };
}

/// Which triangle meshes run an alpha test (an Embree filter callback) on candidate hits.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AlphaTests {
    /// No mesh: the scene has no alpha cut-out (the analysis left the effect off).
    Off,
    /// Meshes whose material has an alpha cut-off over an alpha texture (the effect is on
    /// because the scene needs it).
    CutoutMeshes,
    /// Every triangle mesh: the general path of a renderer that does not analyse its scene.
    /// Cut-out meshes filter their mask; every other mesh tests its constant alpha, which
    /// keeps every hit, so the image is unchanged and the callbacks are pure cost.
    EveryMesh,
}

impl AlphaTests {
    /// The alpha tests a render with `effects` runs on a scene that needs `needed`.
    pub fn for_effects(effects: &EffectSet, needed: &EffectSet) -> AlphaTests {
        match (effects.alpha_cutout, needed.alpha_cutout) {
            (false, _) => AlphaTests::Off,
            (true, true) => AlphaTests::CutoutMeshes,
            (true, false) => AlphaTests::EveryMesh,
        }
    }
}

/// How analytic spheres are traced.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SphereTraversal {
    /// Embree's point geometry (`RTC_GEOMETRY_TYPE_SPHERE_POINT`) and its sphere test.
    EmbreePoints,
    /// A user geometry running our own test (`crate::render::sphere_geometry`): the
    /// default, measured faster on the path peer scene's bounce and shadow rays.
    UserGeometry,
}

/// How the rays of an incoherent wave (bounce, reflection, refraction and later shadow
/// rays) are handed to Embree.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum IncoherentLayout {
    /// AoS ray streams (`rtcIntersect1M` / `rtcOccluded1M`), which Embree regroups itself.
    Streams,
    /// The rays in wave order, cut in 16s, as 16-wide SoA packets without the coherent flag.
    Packets,
}

/// How to build a [`Tracer`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TracerSettings {
    pub alpha_tests: AlphaTests,
    /// Embree's robust (watertight) mode; off only to measure what it costs.
    pub robust: bool,
    /// Threads Embree may use to build the BVH (its `threads=N` device option).
    pub threads: usize,
    pub spheres: SphereTraversal,
    /// Streams by default: 16-wide packets were slower on bounce rays and tied on
    /// whole renders.
    pub incoherent: IncoherentLayout,
    /// Embree's high build quality (spatial splits) for scenes of at least this many
    /// triangles; medium quality below. Never by default: on both peer scenes it saved no
    /// measurable trace time (docs/benchmarks.md, "Traversal after the structure-of-arrays
    /// issue").
    pub high_quality_min_triangles: usize,
}

impl TracerSettings {
    /// The settings of a render of `scene` with `options`: alpha tests as the scene's
    /// analysis (or `--all-effects`) says, robust traversal, as many BVH-build threads as
    /// the current rayon pool has workers.
    pub fn for_render(scene: &SceneDescription, options: &RenderOptions) -> TracerSettings {
        let (needed, _) = EffectSet::analyse(scene, options.lod);
        let effects = if options.all_effects {
            EffectSet::all()
        } else {
            needed
        };
        TracerSettings::new(AlphaTests::for_effects(&effects, &needed))
    }

    /// The defaults of a render that runs `alpha_tests`: robust traversal, as many
    /// BVH-build threads as the current rayon pool has workers, and the sphere test, wave
    /// layout and build quality measured fastest (docs/benchmarks.md, "Traversal after the
    /// structure-of-arrays issue").
    pub fn new(alpha_tests: AlphaTests) -> TracerSettings {
        TracerSettings {
            alpha_tests,
            robust: true,
            threads: rayon::current_num_threads(),
            spheres: SphereTraversal::UserGeometry,
            incoherent: IncoherentLayout::Streams,
            high_quality_min_triangles: usize::MAX,
        }
    }
}

/// The first traversal failure of a render, shared by every worker.
#[derive(Default)]
struct FailureSlot {
    /// Raised with the first failure; the render driver polls it between tiles.
    raised: AtomicBool,
    first: Mutex<Option<EmbreeError>>,
}

impl FailureSlot {
    fn record(&self, error: EmbreeError) {
        let mut first = self.first.lock().unwrap_or_else(|p| p.into_inner());
        if first.is_none() {
            *first = Some(error);
        }
        self.raised.store(true, Ordering::Release);
    }
}

/// The committed Embree scene and how to trace slices of rays through it.
pub struct Tracer {
    scene: CommittedScene,
    settings: TracerSettings,
    failure: FailureSlot,
}

impl Tracer {
    /// Build and commit the Embree scene of `scene`: one triangle geometry per mesh, one
    /// sphere geometry (Embree's points or our user geometry) for all spheres, alpha-test filters as [`TracerSettings::for_render`]
    /// decides.
    pub fn build(
        scene: &Arc<SceneDescription>,
        textures: &[Arc<Texture>],
        options: &RenderOptions,
    ) -> Result<(Tracer, Vec<GeometryRef>), PrepareError> {
        let settings = TracerSettings::for_render(scene, options);
        Tracer::build_with(scene, textures, options, settings)
    }

    /// [`Tracer::build`] with explicit settings.
    pub fn build_with(
        scene: &Arc<SceneDescription>,
        textures: &[Arc<Texture>],
        options: &RenderOptions,
        settings: TracerSettings,
    ) -> Result<(Tracer, Vec<GeometryRef>), PrepareError> {
        let embree_error = |e: crate::embree::EmbreeError| PrepareError::Embree {
            source_label: scene.source.clone(),
            message: e.to_string(),
        };
        let device = Device::with_threads(settings.threads).map_err(embree_error)?;
        let mut builder = SceneBuilder::new(&device).map_err(embree_error)?;
        builder.set_robust(settings.robust).map_err(embree_error)?;
        let triangles: usize = scene.meshes.iter().map(|m| m.triangles.len()).sum();
        builder
            .set_high_build_quality(triangles >= settings.high_quality_min_triangles)
            .map_err(embree_error)?;
        let mut geometries = Vec::new();
        for (index, mesh) in scene.meshes.iter().enumerate() {
            let material = &scene.materials[mesh.material];
            // A cut-off over a constant alpha (no alpha texture, or no texture coordinates to
            // look it up with) keeps or drops the whole mesh: decided here, not per hit.
            let textured_cutout = material.alpha_texture.is_some() && !mesh.st.is_empty();
            let dropped = material
                .alpha_cutoff
                .is_some_and(|cutoff| !textured_cutout && material.alpha < cutoff);
            if mesh.triangles.is_empty() || dropped {
                continue;
            }
            let id = builder
                .add_triangle_mesh(&mesh.positions, &mesh.triangles)
                .map_err(embree_error)?;
            debug_assert_eq!(id as usize, geometries.len());
            geometries.push(GeometryRef::Mesh(index));
            let cutout = match (material.alpha_cutoff, &material.alpha_texture) {
                (Some(cutoff), Some(binding)) if textured_cutout => Some((cutoff, binding)),
                _ => None,
            };
            let filter = match (settings.alpha_tests, cutout) {
                (AlphaTests::Off, _) | (AlphaTests::CutoutMeshes, None) => None,
                (AlphaTests::CutoutMeshes | AlphaTests::EveryMesh, Some((cutoff, binding))) => {
                    Some(alpha_filter(
                        scene.clone(),
                        index,
                        textures[binding.texture].clone(),
                        binding.transform,
                        material.alpha,
                        cutoff,
                        crate::render::prepared::texture_filters(scene, &options.filter)
                            [binding.texture],
                    ))
                }
                (AlphaTests::EveryMesh, None) => {
                    Some(constant_alpha_filter(material.alpha, material.alpha_cutoff))
                }
            };
            if let Some(filter) = filter {
                builder.set_alpha_filter(id, filter).map_err(embree_error)?;
            }
        }
        if !scene.spheres.is_empty() {
            add_sphere_geometry(&mut builder, &scene.spheres, settings.spheres)
                .map_err(embree_error)?;
            geometries.push(GeometryRef::Spheres);
        }
        if !scene.patches.is_empty() {
            let patches = crate::render::patch_geometry::PatchGeometry::new(&scene.patches);
            let id = builder
                .add_user_geometry(Arc::new(patches))
                .map_err(embree_error)?;
            geometries.push(GeometryRef::Patches);
            if let Some(filter) =
                patch_alpha_filter(scene, &scene.patches, textures, options, settings)
            {
                builder
                    .set_user_alpha_filter(id, filter)
                    .map_err(embree_error)?;
            }
        }
        if !scene.height_patches.is_empty() {
            let marched = crate::render::patch_geometry::HeightPatchGeometry {
                patches: scene.height_patches.clone(),
            };
            let id = builder
                .add_user_geometry(Arc::new(marched))
                .map_err(embree_error)?;
            geometries.push(GeometryRef::HeightPatches);
            let as_bezier: Vec<_> = scene.height_patches.iter().map(|p| p.to_bezier()).collect();
            if let Some(filter) = patch_alpha_filter(scene, &as_bezier, textures, options, settings)
            {
                builder
                    .set_user_alpha_filter(id, filter)
                    .map_err(embree_error)?;
            }
        }
        let committed = builder.commit().map_err(embree_error)?;
        Ok((
            Tracer {
                scene: committed,
                settings,
                failure: FailureSlot::default(),
            },
            geometries,
        ))
    }

    /// The settings this tracer was built with.
    pub fn settings(&self) -> TracerSettings {
        self.settings
    }

    /// The Embree device the scene lives on.
    pub fn device(&self) -> &Device {
        self.scene.device()
    }

    /// Whether a traversal failed since the last [`Tracer::take_failure`].
    #[inline]
    pub fn failed(&self) -> bool {
        self.failure.raised.load(Ordering::Acquire)
    }

    /// The first traversal failure since the last call, clearing it.
    pub fn take_failure(&self) -> Option<EmbreeError> {
        let mut first = self.failure.first.lock().unwrap_or_else(|p| p.into_inner());
        self.failure.raised.store(false, Ordering::Release);
        first.take()
    }

    /// Keeps the first failure of a trace call; the rays' results stay as Embree left them.
    #[inline]
    fn note(&self, result: Result<(), EmbreeError>) {
        if let Err(error) = result {
            self.failure.record(error);
        }
    }

    /// Packet width of the device (16, 8, 4, or 1 for single rays).
    pub fn packet_width(&self) -> usize {
        self.scene.packet_width()
    }

    /// Closest hits of `rays` into `hits` (resized to match).
    ///
    /// Coherent rays (camera rays, 16 consecutive slots per 4x4 pixel block) go through
    /// 16-wide packets (split into 8- or 4-wide calls, or single rays, on devices without
    /// 16-wide support). Incoherent rays (reflection, refraction, shadow walks) go as the
    /// settings' [`IncoherentLayout`] says: Embree ray streams (`rtcIntersect1M`, single
    /// rays on devices without streams) or 16-wide packets without the coherent flag. A
    /// failed trace is recorded (see the module doc); the hits Embree produced are kept.
    pub fn intersect(
        &self,
        rays: &[TraceRay],
        hits: &mut Vec<TraceHit>,
        coherent: bool,
        counters: &mut WorkCounters,
    ) {
        hits.clear();
        hits.resize(rays.len(), TraceHit::MISS);
        if coherent {
            self.intersect_packets(rays.iter().copied(), TraceOptions::coherent(), hits);
        } else {
            self.intersect_incoherent_into(rays, hits);
        }
        counters.filter_callbacks += FILTER_CALLS.with(|c| c.replace(0));
    }

    /// [`Tracer::intersect`] of an incoherent batch cut into groups, each traced as its own
    /// stream (or its own run of packets): the rays of `rays[..group_ends[0]]`, then of `rays[group_ends[0]..group_ends[1]]`,
    /// and so on (the last end is `rays.len()`).
    ///
    /// Embree packs a stream's rays into packets of its own choosing (and the packet layout
    /// cuts the group in 16s), and which of two triangles hit at the same distance a ray
    /// reports can depend on its packet. The
    /// integrators trace each sample's rays as one group, so a ray's hit does not depend on
    /// which other samples are traced with it (`integrator::camera_sample::SampleRun`).
    pub fn intersect_grouped(
        &self,
        rays: &[TraceRay],
        group_ends: &[usize],
        hits: &mut Vec<TraceHit>,
        counters: &mut WorkCounters,
    ) {
        hits.clear();
        hits.resize(rays.len(), TraceHit::MISS);
        let mut start = 0;
        for &end in group_ends {
            if end > start {
                self.intersect_incoherent_into(&rays[start..end], &mut hits[start..end]);
            }
            start = end;
        }
        debug_assert_eq!(start, rays.len(), "the groups cover the batch");
        counters.filter_callbacks += FILTER_CALLS.with(|c| c.replace(0));
    }

    /// Closest hits of the incoherent `rays` as one stream (or run of packets,
    /// [`IncoherentLayout`]) into `hits` (resized to match), filled straight from the
    /// iterator: [`Tracer::intersect`] of a later wave without first collecting its rays. A
    /// failed trace is recorded as there.
    pub fn intersect_stream(
        &self,
        rays: impl Iterator<Item = TraceRay>,
        hits: &mut Vec<TraceHit>,
        counters: &mut WorkCounters,
    ) {
        hits.clear();
        match self.settings.incoherent {
            IncoherentLayout::Streams => {
                self.with_stream_of(rays, |ray_hits, payload| {
                    self.note(self.scene.intersect_stream(
                        ray_hits,
                        TraceOptions::incoherent().with_payload(payload),
                    ));
                    hits.extend(ray_hits.iter().map(|ray_hit| match ray_hit.hit() {
                        Some(hit) => trace_hit(&hit),
                        None => TraceHit::MISS,
                    }));
                })
            }
            IncoherentLayout::Packets => {
                self.trace_packets(rays, TraceOptions::incoherent(), false, |packet, lanes| {
                    hits.extend((0..lanes).map(|lane| match packet.hit(lane) {
                        Some(hit) => trace_hit(&hit),
                        None => TraceHit::MISS,
                    }));
                });
            }
        }
        counters.filter_callbacks += FILTER_CALLS.with(|c| c.replace(0));
    }

    /// Whether each of `rays` is blocked before its `tfar`, one incoherent stream (or run of
    /// packets, [`IncoherentLayout`]) filled straight from the iterator
    /// ([`Tracer::occluded`] of a slice).
    pub fn occluded_stream(
        &self,
        rays: impl Iterator<Item = TraceRay>,
        blocked: &mut Vec<bool>,
        counters: &mut WorkCounters,
    ) {
        blocked.clear();
        match self.settings.incoherent {
            IncoherentLayout::Streams => {
                self.with_stream_of(rays, |ray_hits, payload| {
                    self.note(self.scene.occluded_stream(
                        ray_hits,
                        TraceOptions::incoherent().with_payload(payload),
                    ));
                    blocked.extend(ray_hits.iter().map(|r| r.is_occluded()));
                })
            }
            IncoherentLayout::Packets => {
                self.trace_packets(rays, TraceOptions::incoherent(), true, |packet, lanes| {
                    blocked.extend((0..lanes).map(|lane| packet.is_occluded(lane)));
                });
            }
        }
        counters.filter_callbacks += FILTER_CALLS.with(|c| c.replace(0));
    }

    /// Runs `trace` on this thread's stream buffers filled with `rays`, and with their cones
    /// as payloads when an alpha test may read them (no filter callback runs otherwise).
    fn with_stream_of(
        &self,
        rays: impl Iterator<Item = TraceRay>,
        trace: impl FnOnce(&mut [RayHit], &[RayPayload]),
    ) {
        let cones = self.settings.alpha_tests != AlphaTests::Off;
        STREAM.with(|stream| {
            let mut stream = stream.borrow_mut();
            let (ray_hits, payload) = &mut *stream;
            ray_hits.clear();
            payload.clear();
            for ray in rays {
                ray_hits.push(RayHit::new(&embree_ray(&ray)));
                if cones {
                    payload.push(RayPayload {
                        cone_width: ray.cone_width,
                        cone_spread: ray.cone_spread,
                    });
                }
            }
            trace(ray_hits, payload);
        });
    }

    /// Closest hits of incoherent `rays` into `hits` (misses left as they are), laid out as
    /// the settings say ([`IncoherentLayout`]).
    fn intersect_incoherent_into(&self, rays: &[TraceRay], hits: &mut [TraceHit]) {
        match self.settings.incoherent {
            IncoherentLayout::Streams => self.intersect_stream_into(rays, hits),
            IncoherentLayout::Packets => {
                self.intersect_packets(rays.iter().copied(), TraceOptions::incoherent(), hits)
            }
        }
    }

    /// Closest hits of `rays` as one incoherent stream into `hits` (misses left as they are).
    fn intersect_stream_into(&self, rays: &[TraceRay], hits: &mut [TraceHit]) {
        self.with_stream_of(rays.iter().copied(), |ray_hits, payload| {
            self.note(
                self.scene
                    .intersect_stream(ray_hits, TraceOptions::incoherent().with_payload(payload)),
            );
            for (out, ray_hit) in hits.iter_mut().zip(ray_hits.iter()) {
                if let Some(hit) = ray_hit.hit() {
                    *out = trace_hit(&hit);
                }
            }
        });
    }

    /// The same closest-hit query as [`Tracer::intersect`], one `rtcIntersect1` call per ray
    /// (each with its own payload at index 0): the single-ray reference the packet path is
    /// tested against. A failed trace is recorded as for [`Tracer::intersect`].
    pub fn intersect_one_by_one(
        &self,
        rays: &[TraceRay],
        hits: &mut Vec<TraceHit>,
        counters: &mut WorkCounters,
    ) {
        hits.clear();
        hits.extend(rays.iter().map(|ray| {
            let payload = [RayPayload {
                cone_width: ray.cone_width,
                cone_spread: ray.cone_spread,
            }];
            let options = TraceOptions::incoherent().with_payload(&payload);
            match self.scene.intersect1(&embree_ray(ray), options) {
                Ok(Some(hit)) => trace_hit(&hit),
                Ok(None) => TraceHit::MISS,
                Err(error) => {
                    self.failure.record(error);
                    TraceHit::MISS
                }
            }
        }));
        counters.filter_callbacks += FILTER_CALLS.with(|c| c.replace(0));
    }

    /// Closest hits of `rays` into `hits` (misses left as they are), as 16-wide packets
    /// of consecutive rays traced with `options`' coherence.
    fn intersect_packets(
        &self,
        rays: impl Iterator<Item = TraceRay>,
        options: TraceOptions<'static>,
        hits: &mut [TraceHit],
    ) {
        let mut out = hits.iter_mut();
        self.trace_packets(rays, options, false, |packet, lanes| {
            for (lane, slot) in out.by_ref().take(lanes).enumerate() {
                if let Some(hit) = packet.hit(lane) {
                    *slot = trace_hit(&hit);
                }
            }
        });
    }

    /// Traces `rays` in order as 16-wide packets (the last one partly filled) with
    /// `options`' coherence and the rays' cones as payloads, for closest hits or, with
    /// `occlusion`, for occlusion; `read` gets each traced packet and its number of rays.
    fn trace_packets(
        &self,
        rays: impl Iterator<Item = TraceRay>,
        options: TraceOptions<'static>,
        occlusion: bool,
        mut read: impl FnMut(&RayPacket<16>, usize),
    ) {
        let mut rays = rays.peekable();
        let mut packet = RayPacket::<16>::new();
        let mut payload = [RayPayload::default(); 16];
        while rays.peek().is_some() {
            let lanes = fill_packet(&mut rays, &mut packet, &mut payload);
            let options = options.with_payload(&payload);
            self.note(if occlusion {
                self.scene.occluded_tile(&mut packet, options)
            } else {
                self.scene.intersect_tile(&mut packet, options)
            });
            read(&packet, lanes);
        }
    }

    /// [`Tracer::occluded`] of coherent rays, traced as 16-wide packets: the shadow rays of a
    /// camera wave, where a packet holds one pixel's samples (`integrator::camera_sample`)
    /// and its rays leave nearly one point for nearly one light point. Whether a ray is
    /// blocked does not depend on its packet: any hit blocks it, and the watertight test
    /// finds one whichever triangle of a shared edge comes first.
    pub fn occluded_coherent(
        &self,
        rays: &[TraceRay],
        blocked: &mut Vec<bool>,
        counters: &mut WorkCounters,
    ) {
        blocked.clear();
        self.trace_packets(
            rays.iter().copied(),
            TraceOptions::coherent(),
            true,
            |packet, lanes| blocked.extend((0..lanes).map(|lane| packet.is_occluded(lane))),
        );
        counters.filter_callbacks += FILTER_CALLS.with(|c| c.replace(0));
    }

    /// Whether each of `rays` is blocked before its `tfar`, traced as incoherent rays (shadow
    /// rays from a wave of hits), laid out as [`IncoherentLayout`] says.
    pub fn occluded(
        &self,
        rays: &[TraceRay],
        blocked: &mut Vec<bool>,
        counters: &mut WorkCounters,
    ) {
        self.occluded_stream(rays.iter().copied(), blocked, counters);
    }

    /// A wave's shadow rays: [`Tracer::occluded_coherent`] for a camera wave's (`coherent`),
    /// [`Tracer::occluded`] for a later wave's.
    pub fn occluded_wave(
        &self,
        rays: &[TraceRay],
        blocked: &mut Vec<bool>,
        coherent: bool,
        counters: &mut WorkCounters,
    ) {
        if coherent {
            self.occluded_coherent(rays, blocked, counters);
        } else {
            self.occluded(rays, blocked, counters);
        }
    }
}

/// Puts the next (up to) 16 of `rays` into `packet` and their cones into `payload`, lanes
/// past them switched off; returns how many it took.
fn fill_packet(
    rays: &mut impl Iterator<Item = TraceRay>,
    packet: &mut RayPacket<16>,
    payload: &mut [RayPayload; 16],
) -> usize {
    packet.reset_lanes();
    let mut lanes = 0;
    for (lane, ray) in rays.take(16).enumerate() {
        packet.put_ray(lane, &embree_ray(&ray));
        payload[lane] = RayPayload {
            cone_width: ray.cone_width,
            cone_spread: ray.cone_spread,
        };
        lanes = lane + 1;
    }
    lanes
}

thread_local! {
    /// Per-thread stream buffers, reused across calls so tracing allocates nothing.
    static STREAM: RefCell<(Vec<RayHit>, Vec<RayPayload>)> = const { RefCell::new((Vec::new(), Vec::new())) };
}

#[inline]
fn embree_ray(ray: &TraceRay) -> Ray {
    Ray::segment(ray.origin, ray.direction, 0.0, ray.tfar)
}

#[inline]
fn trace_hit(hit: &crate::embree::Hit) -> TraceHit {
    TraceHit {
        t: hit.t,
        geometry: hit.geom_id,
        primitive: hit.prim_id,
        u: hit.u,
        v: hit.v,
    }
}

/// Adds `spheres` as one geometry, traced as `traversal` says; returns its geometry id.
fn add_sphere_geometry(
    builder: &mut SceneBuilder,
    spheres: &[crate::scene::Sphere],
    traversal: SphereTraversal,
) -> Result<u32, EmbreeError> {
    let spheres: Vec<(glam::Vec3, f32)> = spheres.iter().map(|s| (s.center, s.radius)).collect();
    match traversal {
        SphereTraversal::EmbreePoints => builder.add_spheres(&spheres),
        SphereTraversal::UserGeometry => {
            // Refused as Embree's point geometry refuses them: a user geometry would give
            // such a sphere empty bounds and never hit it, without a word.
            let invalid = spheres
                .iter()
                .position(|(c, r)| !(c.is_finite() && r.is_finite() && *r >= 0.0));
            if let Some(index) = invalid {
                let radius = spheres[index].1;
                return Err(EmbreeError::InvalidSphere { index, radius });
            }
            builder.add_user_geometry(Arc::new(
                crate::render::sphere_geometry::SphereGeometry::new(&spheres),
            ))
        }
    }
}

/// The alpha test of a cut-out material on mesh `mesh_index`, run by Embree for every
/// candidate hit. The alpha texture is filtered over the ray cone's footprint at the hit
/// (an isotropic footprint of the cone's width mapped to st through the triangle's texel
/// density), so distant cut-outs are tested against averaged coverage and do not shimmer.
///
/// Where the footprint covers many texels, the filtered alpha is a coverage fraction; the
/// test then compares it with a per-ray threshold spread over (0, 1) instead of the fixed
/// cutoff, so the fraction of rays that hit equals the coverage. At magnification the fixed
/// cutoff is used (a crisp edge), with a smooth blend between the two regimes.
fn alpha_filter(
    scene: Arc<SceneDescription>,
    mesh_index: usize,
    texture: Arc<Texture>,
    transform: glam::Affine2,
    constant_alpha: f32,
    cutoff: f32,
    texture_filter: FilterOptions,
) -> crate::embree::AlphaFilter {
    // Coverage is filtered trilinearly with the texture's own wrap modes.
    let options = FilterOptions {
        filter: FilterMode::Trilinear,
        ..texture_filter
    };
    let texels = (texture.width() as f32) * (texture.height() as f32);
    Arc::new(move |candidate: &FilterCandidate| {
        FILTER_CALLS.with(|c| c.set(c.get() + 1));
        let mesh = &scene.meshes[mesh_index];
        let Some(&[i0, i1, i2]) = mesh.triangles.get(candidate.prim_id as usize) else {
            return true;
        };
        if mesh.st.is_empty() {
            return constant_alpha >= cutoff;
        }
        let (i0, i1, i2) = (i0 as usize, i1 as usize, i2 as usize);
        let (u, v) = (candidate.u, candidate.v);
        let st = mesh.st[i0] * (1.0 - u - v) + mesh.st[i1] * u + mesh.st[i2] * v;
        // Texel density: st area per world area of this triangle.
        let p = [mesh.positions[i0], mesh.positions[i1], mesh.positions[i2]];
        let world_area = (p[1] - p[0]).cross(p[2] - p[0]).length();
        let t = [
            transform.transform_point2(mesh.st[i0]),
            transform.transform_point2(mesh.st[i1]),
            transform.transform_point2(mesh.st[i2]),
        ];
        let st_area = ((t[1] - t[0]).perp_dot(t[2] - t[0])).abs();
        let width =
            (candidate.payload.cone_width + candidate.payload.cone_spread * candidate.t).abs();
        let st_width = if world_area > 0.0 && world_area.is_finite() {
            width * (st_area / world_area).sqrt()
        } else {
            0.0
        };
        let st_width = if st_width.is_finite() { st_width } else { 0.0 };
        let st = transform.transform_point2(st);
        let query = TextureQuery {
            s: st.x,
            t: st.y,
            dsdx: st_width,
            dtdx: 0.0,
            dsdy: 0.0,
            dtdy: st_width,
        };
        let alpha = texture.sample(&query, &options).w * constant_alpha;
        // Footprint size in texels decides between a crisp cutoff and coverage.
        let texels_covered = st_width * st_width * texels;
        let blend = ((texels_covered - 1.0) / 3.0).clamp(0.0, 1.0);
        let threshold = cutoff + (ray_threshold(candidate) - cutoff) * blend;
        alpha >= threshold
    })
}

/// The alpha test of a user geometry of curved patches (`patches[prim_id]`), or `None` when
/// no patch's material has an alpha cut-off or the render runs no alpha tests. As for
/// meshes ([`alpha_filter`]): a cut-off over a constant alpha keeps or drops the patch; an
/// alpha texture is filtered at the hit's (s, t) over the ray cone's footprint, mapped to
/// texture space by the patch's own texel density at (u, v), `|st_u x st_v| / |P_u x P_v|`.
fn patch_alpha_filter(
    scene: &Arc<SceneDescription>,
    patches: &[crate::scene::patch::BezierPatch],
    textures: &[Arc<Texture>],
    options: &RenderOptions,
    settings: TracerSettings,
) -> Option<crate::embree::AlphaFilter> {
    let cut = |p: &crate::scene::patch::BezierPatch| scene.materials[p.material].alpha_cutoff;
    if settings.alpha_tests == AlphaTests::Off || !patches.iter().any(|p| cut(p).is_some()) {
        return None;
    }
    let patches: Vec<crate::scene::patch::BezierPatch> = patches.to_vec();
    let scene = scene.clone();
    let textures: Vec<Arc<Texture>> = textures.to_vec();
    let filters = crate::render::prepared::texture_filters(&scene, &options.filter);
    Some(Arc::new(move |candidate: &FilterCandidate| {
        FILTER_CALLS.with(|c| c.set(c.get() + 1));
        let Some(patch) = patches.get(candidate.prim_id as usize) else {
            return true;
        };
        let material = &scene.materials[patch.material];
        let Some(cutoff) = material.alpha_cutoff else {
            return true;
        };
        let Some(binding) = &material.alpha_texture else {
            return material.alpha >= cutoff;
        };
        let texture = &textures[binding.texture];
        let (u, v) = (candidate.u.clamp(0.0, 1.0), candidate.v.clamp(0.0, 1.0));
        let point = patch.evaluate(f64::from(u), f64::from(v));
        let (st, dstdu, dstdv) = patch.st(u, v);
        let linear = binding.transform.matrix2;
        let st_area = (linear * dstdu).perp_dot(linear * dstdv).abs();
        let world_area = point.dpdu.cross(point.dpdv).length() as f32;
        let width =
            (candidate.payload.cone_width + candidate.payload.cone_spread * candidate.t).abs();
        let st_width = if world_area > 0.0 && world_area.is_finite() {
            width * (st_area / world_area).sqrt()
        } else {
            0.0
        };
        let st_width = if st_width.is_finite() { st_width } else { 0.0 };
        let st = binding.transform.transform_point2(st);
        let query = TextureQuery {
            s: st.x,
            t: st.y,
            dsdx: st_width,
            dtdx: 0.0,
            dsdy: 0.0,
            dtdy: st_width,
        };
        let filter = FilterOptions {
            filter: FilterMode::Trilinear,
            ..filters[binding.texture]
        };
        let alpha = texture.sample(&query, &filter).w * material.alpha;
        let texels = (texture.width() as f32) * (texture.height() as f32);
        let blend = ((st_width * st_width * texels - 1.0) / 3.0).clamp(0.0, 1.0);
        let threshold = cutoff + (ray_threshold(candidate) - cutoff) * blend;
        alpha >= threshold
    }))
}

/// The alpha test of a mesh without a textured cut-out, as the general path runs it on
/// every candidate hit: its constant alpha against its cut-off (no cut-off keeps every hit).
fn constant_alpha_filter(alpha: f32, cutoff: Option<f32>) -> crate::embree::AlphaFilter {
    Arc::new(move |_: &FilterCandidate| {
        FILTER_CALLS.with(|c| c.set(c.get() + 1));
        cutoff.is_none_or(|cutoff| alpha >= cutoff)
    })
}

/// A threshold in (0, 1) that is a fixed function of the ray (so packets and single rays
/// agree), spread uniformly over rays.
fn ray_threshold(candidate: &FilterCandidate) -> f32 {
    let mut h = candidate.origin.x.to_bits()
        ^ candidate.origin.y.to_bits().rotate_left(11)
        ^ candidate.origin.z.to_bits().rotate_left(22)
        ^ candidate.direction.x.to_bits().rotate_left(5)
        ^ candidate.direction.y.to_bits().rotate_left(16)
        ^ candidate.direction.z.to_bits().rotate_left(27);
    h ^= h >> 16;
    h = h.wrapping_mul(0x7feb_352d);
    h ^= h >> 15;
    h = h.wrapping_mul(0x846c_a68b);
    h ^= h >> 16;
    ((h >> 8) as f32 + 0.5) / (1u32 << 24) as f32
}
