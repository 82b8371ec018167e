//! Which integrator renders a scene, and why: `--integrator whitted|path|auto` and
//! `[render] integrator = "..."` (the command line wins), with `auto` the default.
//!
//! `vct` (voxel cone tracing, seed 003) is only ever chosen by name.
//!
//! `auto` picks the path tracer when the scene calls for global illumination: emissive
//! geometry (area lights), rough or glossy materials (the metallic-roughness model's
//! microfacet lobes, `MaterialFeatures::rough`; the classic Blinn-Phong highlight does not
//! count, so classic ray-tracing scenes stay with Whitted), or `[render] gi = true`.
//! Otherwise Whitted renders it. What each material does comes from
//! `crate::shading::MaterialFeatures`.
//!
//! Only the voxel cone tracer needs work before rendering (its voxel scene, built by
//! [`select`]); Whitted and the path tracer build nothing extra.
//!
//! [`SelectedIntegrator`] is the one integrator value every render goes through: it
//! implements [`Integrator`] by handing each tile to the chosen one, so the render loop,
//! split renders and their cost estimates stay generic. A new kind is a new arm in
//! [`IntegratorKind`], [`SelectedIntegrator`] and [`SelectedState`].

use std::fmt;
use std::str::FromStr;
use std::sync::atomic::AtomicBool;

use crate::film::{PixelRect, TileImage};
use crate::integrator::path::{PathTracer, PathWaves};
use crate::integrator::vct::Vct;
use crate::integrator::whitted::{Waves, Whitted};
use crate::render::context::{RenderContext, WorkerState};
use crate::render::{Integrator, RenderControl, RenderError, RenderResult};
use crate::scene::{RenderSettings, SceneDescription};
use crate::shading::{material_features, MaterialFeatures};
use crate::vct::build::pyramid_bytes_for;
use crate::vct::{build_voxel_scene, VctBuildStats, VctError, VctSettings};

/// A light-transport algorithm the renderer has.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum IntegratorKind {
    Whitted,
    Path,
    Vct,
}

impl IntegratorKind {
    /// How many samples of a pixel the integrator traces together, its camera rays in
    /// one packet ([`crate::integrator::for_each_camera_run`]).
    pub fn samples_in_flight(self) -> u32 {
        match self {
            // The voxel cone tracer renders its tiles with Whitted's waves.
            IntegratorKind::Whitted | IntegratorKind::Vct => {
                crate::integrator::whitted::SAMPLES_IN_FLIGHT
            }
            IntegratorKind::Path => crate::integrator::path::SAMPLES_IN_FLIGHT,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            IntegratorKind::Whitted => "whitted",
            IntegratorKind::Path => "path",
            IntegratorKind::Vct => "vct",
        }
    }
}

/// Samples per pixel the path tracer takes when neither the caller nor the scene gives a
/// count: pbrt-v4's default. One path per pixel is salt-and-pepper noise on any scene that
/// needs the path tracer; 16 gives a usable first image.
pub const PATH_DEFAULT_SPP: u32 = 16;

/// Samples per pixel for `kind` when neither the caller nor the scene gives a count. Whitted
/// and the voxel cone tracer are deterministic apart from antialiasing, and their footprint
/// filtering gives a clean image at one sample.
pub fn default_spp(kind: IntegratorKind) -> u32 {
    match kind {
        IntegratorKind::Path => PATH_DEFAULT_SPP,
        IntegratorKind::Whitted | IntegratorKind::Vct => 1,
    }
}

/// What a scene or the command line asks for: one integrator, or the scene's choice.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum IntegratorChoice {
    #[default]
    Auto,
    Fixed(IntegratorKind),
}

/// A name that is not an integrator.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("unknown integrator '{0}' (expected whitted, path, vct or auto)")]
pub struct UnknownIntegrator(pub String);

impl FromStr for IntegratorChoice {
    type Err = UnknownIntegrator;

    fn from_str(name: &str) -> Result<Self, Self::Err> {
        match name {
            "auto" => Ok(IntegratorChoice::Auto),
            "whitted" => Ok(IntegratorChoice::Fixed(IntegratorKind::Whitted)),
            "path" => Ok(IntegratorChoice::Fixed(IntegratorKind::Path)),
            "vct" => Ok(IntegratorChoice::Fixed(IntegratorKind::Vct)),
            _ => Err(UnknownIntegrator(name.to_string())),
        }
    }
}

impl fmt::Display for IntegratorChoice {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            IntegratorChoice::Auto => f.write_str("auto"),
            IntegratorChoice::Fixed(kind) => f.write_str(kind.name()),
        }
    }
}

/// The integrator chosen for a scene and the reason, as the summary line and `--stats`
/// print it ("path: emissive geometry (12 triangles)").
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Resolution {
    pub kind: IntegratorKind,
    pub reason: String,
}

impl fmt::Display for Resolution {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.kind.name(), self.reason)
    }
}

/// The integrator for `scene` under `choice` (see the module doc), with the reason.
pub fn resolve(choice: IntegratorChoice, scene: &SceneDescription) -> Resolution {
    if let IntegratorChoice::Fixed(kind) = choice {
        return Resolution {
            kind,
            reason: "requested".to_string(),
        };
    }
    let mut reasons = Vec::new();
    if let Some(emitters) = emissive_geometry(scene) {
        reasons.push(format!("emissive geometry ({emitters})"));
    }
    // Only materials some geometry uses: a rough material nothing wears changes no image.
    let used = scene.worn_materials();
    let rough: Vec<&str> = scene
        .materials
        .iter()
        .zip(&used)
        .filter(|(m, &worn)| worn && MaterialFeatures::of(m).rough)
        .map(|(m, _)| m.name.as_str())
        .collect();
    if !rough.is_empty() {
        reasons.push(format!(
            "rough or glossy materials ({} with roughness)",
            rough.len()
        ));
    }
    if scene.settings.gi {
        reasons.push("[render] gi = true".to_string());
    }
    if reasons.is_empty() {
        Resolution {
            kind: IntegratorKind::Whitted,
            reason: "no emissive geometry, rough materials or gi".to_string(),
        }
    } else {
        Resolution {
            kind: IntegratorKind::Path,
            reason: reasons.join("; "),
        }
    }
}

/// The scene's emissive geometry counted by kind ("12 triangles, 1 sphere"), or `None`
/// when nothing emits.
fn emissive_geometry(scene: &SceneDescription) -> Option<String> {
    let emissive = |material: usize| {
        scene
            .materials
            .get(material)
            .is_some_and(material_features::emits)
    };
    let triangles: usize = scene
        .meshes
        .iter()
        .filter(|m| emissive(m.material))
        .map(|m| m.triangles.len())
        .sum();
    let spheres = scene
        .spheres
        .iter()
        .filter(|s| emissive(s.material))
        .count();
    let patches = scene
        .patches
        .iter()
        .filter(|p| emissive(p.material))
        .count()
        + scene
            .height_patches
            .iter()
            .filter(|p| emissive(p.material))
            .count();
    let counted = [
        (triangles, "triangle"),
        (spheres, "sphere"),
        (patches, "patch"),
    ]
    .iter()
    .filter(|(n, _)| *n > 0)
    .map(|(n, what)| {
        let plural = match (*n, *what) {
            (1, _) => "",
            (_, "patch") => "es",
            _ => "s",
        };
        format!("{n} {what}{plural}")
    })
    .collect::<Vec<_>>();
    (!counted.is_empty()).then(|| counted.join(", "))
}

/// The note for a scene whose emissive geometry `kind` does not use as light (Whitted, which
/// samples punctual lights and the environment only) or uses only approximately (the voxel
/// cone tracer, which gathers emitters through its voxels): stronger when nothing else
/// lights the scene.
fn unlit_emitters_note(kind: IntegratorKind, scene: &SceneDescription) -> Option<String> {
    let emitters = emissive_geometry(scene)?;
    let environment_lights = match &scene.environment {
        crate::scene::Environment::Color(c) => c.max_element() > 0.0,
        crate::scene::Environment::LatLong { intensity, .. } => *intensity > 0.0,
    };
    let only_emitters = scene.lights.is_empty() && !environment_lights;
    let how = match kind {
        IntegratorKind::Whitted => {
            "Whitted's recursion lights surfaces by point, spot and directional lights and the \
             environment only; emitters are seen, and seen in mirrors, but light nothing"
        }
        IntegratorKind::Vct => {
            "the voxel cone tracer gathers emitters' light only through its voxels, an \
             approximation that misses part of it (docs/vct.md)"
        }
        IntegratorKind::Path => return None,
    };
    let name = kind.name();
    Some(if only_emitters && kind == IntegratorKind::Vct {
        format!(
            "{name}: the scene is lit only by emissive geometry ({emitters}): {how}; \
             --integrator path renders all of its light"
        )
    } else if only_emitters {
        format!(
            "{name}: the scene is lit only by emissive geometry ({emitters}), so it renders \
             nearly black: {how}; --integrator path renders its light"
        )
    } else {
        let lights = if kind == IntegratorKind::Vct {
            "lights the scene only approximately"
        } else {
            "does not light the scene"
        };
        format!(
            "{name}: emissive geometry ({emitters}) {lights}: {how}; --integrator path \
             renders its light"
        )
    })
}

/// What the integrator of `kind` leaves out of `scene`, one note each (the summary line and
/// `--stats` print them): emissive geometry it does not use as light
/// ([`unlit_emitters_note`]), and fog under the voxel cone tracer, which renders as if the
/// fog were not there (Whitted blends it, the path tracer simulates it as a medium).
pub fn unsupported_effects(kind: IntegratorKind, scene: &SceneDescription) -> Vec<String> {
    let mut notes: Vec<String> = unlit_emitters_note(kind, scene).into_iter().collect();
    if kind == IntegratorKind::Vct && !scene.fog.is_empty() {
        notes.push(format!(
            "{}: fog is not simulated by this integrator (rendered without it; \
             --integrator whitted or path renders it)",
            kind.name()
        ));
    }
    notes
}

/// The chosen integrator, with its settings from the scene.
#[derive(Clone, Debug)]
pub enum SelectedIntegrator {
    Whitted(Whitted),
    Path(PathTracer),
    Vct(Vct),
}

impl SelectedIntegrator {
    /// The voxel scene's build statistics (vct only).
    pub fn vct_stats(&self) -> Option<&VctBuildStats> {
        match self {
            SelectedIntegrator::Vct(vct) => Some(&vct.voxels.stats),
            _ => None,
        }
    }
}

/// Build the integrator of `kind` for `context` with the settings its scene gives it:
/// the voxel scene for vct (which can fail: a grid too large), nothing for the others.
pub fn select(
    kind: IntegratorKind,
    context: &RenderContext,
) -> Result<SelectedIntegrator, VctError> {
    let settings = &context.scene.settings;
    Ok(match kind {
        IntegratorKind::Whitted => SelectedIntegrator::Whitted(Whitted::default()),
        IntegratorKind::Path => SelectedIntegrator::Path(PathTracer::for_settings(settings)),
        IntegratorKind::Vct => SelectedIntegrator::Vct(Vct::new(build_voxel_scene(
            context,
            &vct_settings(settings),
        )?)),
    })
}

/// The voxel cone tracer's settings from the scene's.
fn vct_settings(settings: &RenderSettings) -> VctSettings {
    VctSettings {
        resolution: settings.vct_resolution,
        bounces: settings.vct_bounces,
        voxels: settings.vct_voxels,
    }
}

/// The bytes the integrator `choice` resolves to needs for `scene` beyond the film, tiles
/// and textures: the voxel pyramid for vct (known from the scene's bounds and settings
/// before anything is built, so a memory limit can refuse it first), nothing for the others.
pub fn integrator_memory(
    choice: IntegratorChoice,
    scene: &SceneDescription,
) -> Result<u64, VctError> {
    match resolve(choice, scene).kind {
        IntegratorKind::Vct => pyramid_bytes_for(scene, &vct_settings(&scene.settings)),
        IntegratorKind::Whitted | IntegratorKind::Path => Ok(0),
    }
}

/// The per-thread state of the chosen integrator.
// One per worker thread for a whole render: the variants' sizes do not matter.
#[allow(clippy::large_enum_variant)]
pub enum SelectedState {
    /// Whitted's waves, also the voxel cone tracer's (it shades through Whitted's).
    Whitted(Waves),
    Path(PathWaves),
}

impl Integrator for SelectedIntegrator {
    type ThreadState = SelectedState;

    fn thread_state(&self, context: &RenderContext) -> SelectedState {
        match self {
            SelectedIntegrator::Whitted(i) => SelectedState::Whitted(i.thread_state(context)),
            SelectedIntegrator::Path(i) => SelectedState::Path(i.thread_state(context)),
            SelectedIntegrator::Vct(i) => SelectedState::Whitted(i.thread_state(context)),
        }
    }

    fn render_tile(
        &self,
        context: &RenderContext,
        tile: PixelRect,
        image: &mut TileImage,
        worker: &mut WorkerState,
        state: &mut SelectedState,
        stop: Option<&AtomicBool>,
    ) -> bool {
        match (self, state) {
            (SelectedIntegrator::Whitted(i), SelectedState::Whitted(s)) => {
                i.render_tile(context, tile, image, worker, s, stop)
            }
            (SelectedIntegrator::Path(i), SelectedState::Path(s)) => {
                i.render_tile(context, tile, image, worker, s, stop)
            }
            (SelectedIntegrator::Vct(i), SelectedState::Whitted(s)) => {
                i.render_tile(context, tile, image, worker, s, stop)
            }
            // A state is only ever made by its own integrator's `thread_state`.
            (integrator, state) => {
                *state = integrator.thread_state(context);
                integrator.render_tile(context, tile, image, worker, state, stop)
            }
        }
    }
}

/// Why a render through [`render`] failed: building the integrator, or rendering.
#[derive(Debug, thiserror::Error)]
pub enum SelectedRenderError {
    #[error(transparent)]
    Build(#[from] VctError),
    #[error(transparent)]
    Render(#[from] RenderError),
}

/// Render `context` with the integrator `choice` resolves to for its scene; the statistics
/// name the integrator and the reason (and the voxel scene's build, for vct).
pub fn render(
    context: &RenderContext,
    choice: IntegratorChoice,
    control: &RenderControl,
) -> Result<RenderResult, SelectedRenderError> {
    let resolution = resolve(choice, &context.scene);
    let integrator = select(resolution.kind, context)?;
    let mut result = crate::render::render(context, &integrator, control)?;
    result.stats.integrator = Some(resolution.to_string());
    result
        .stats
        .notes
        .extend(unsupported_effects(resolution.kind, &context.scene));
    if let Some(vct) = integrator.vct_stats() {
        result.stats.counters.vct_voxels_built = vct.occupied_voxels;
        result.stats.vct = Some(vct.clone());
    }
    Ok(result)
}
