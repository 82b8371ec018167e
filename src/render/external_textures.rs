//! A hook that lets code outside the renderer answer the scene's texture lookups.
//!
//! When a [`RenderContext`](crate::render::RenderContext) carries an [`ExternalTextures`],
//! the material base-colour and environment lookups call it with the query our footprint
//! produced (st and the four derivatives) instead of filtering the built-in
//! [`Texture`](crate::texture::Texture); so does the environment's mean (the ambient term),
//! asked for as one lookup whose footprint covers the whole map. The C API uses it to hand
//! lookups to a C callback (e.g. OpenImageIO's TextureSystem).
//!
//! [`prepare_with_external`] decodes only the textures the built-in system still reads with
//! such a hook: alpha cut-out masks (looked up inside Embree's intersection filters), and
//! every texture when the `lod` AOV is asked for (it reports the level of the built-in
//! pyramid). A texture the hook serves is never read from its file, so a file the built-in
//! decoder cannot open (gone since the scene was loaded, or in a format only the external
//! system reads) is no error.
//!
//! This module must not know about C: it is the Rust side of the hook only.

use std::sync::Arc;

use glam::{Vec3, Vec4};

use crate::render::prepared::{self, PrepareError};
use crate::render::{RenderContext, RenderOptions};
use crate::scene::{Environment, SceneDescription};
use crate::texture::{FilterMode, FilterOptions, Texture, TextureQuery};

/// A texture system that serves lookups for a prepared scene.
///
/// `sample` runs on the render's worker threads and may be called concurrently.
pub trait ExternalTextures: Send + Sync {
    /// The filtered RGBA of texture `texture_index` (an index into the scene's
    /// [`SceneDescription::textures`](crate::scene::SceneDescription::textures)) for `query`,
    /// with the filter and wrap modes the renderer would have used.
    ///
    /// An `Err` makes the lookup black; the implementation is responsible for recording the
    /// message and stopping the render (e.g. through the render's cancel flag).
    fn sample(
        &self,
        texture_index: usize,
        query: &TextureQuery,
        options: &FilterOptions,
    ) -> Result<Vec4, String>;
}

/// `external`'s answer for one lookup, black when it reports an error.
#[inline]
pub fn sample_external(
    external: &dyn ExternalTextures,
    texture_index: usize,
    query: &TextureQuery,
    options: &FilterOptions,
) -> Vec4 {
    external
        .sample(texture_index, query, options)
        .unwrap_or(Vec4::ZERO)
}

/// Like [`prepare`](crate::render::prepare), with every base-colour and environment lookup
/// (and the environment's mean) served by `external`; textures only `external` reads are not
/// decoded (see the module docs).
pub fn prepare_with_external(
    scene: Arc<SceneDescription>,
    options: RenderOptions,
    external: Arc<dyn ExternalTextures>,
) -> Result<RenderContext, PrepareError> {
    let textures = textures_read_by_the_renderer(&scene, options.aovs.lod)?;
    let mut context = crate::render::prepare_with_textures(scene, options, textures)?;
    context.environment_mean = environment_mean(&context.scene.environment, external.as_ref());
    context.external_textures = Some(external);
    Ok(context)
}

/// One entry per scene texture: decoded where the built-in system reads it despite the
/// external hook (alpha cut-out masks; all of them for the `lod` AOV), elsewhere a one-texel
/// stand-in that no lookup reaches (every lookup of it goes to the hook).
fn textures_read_by_the_renderer(
    scene: &SceneDescription,
    lod_aov: bool,
) -> Result<Vec<Arc<Texture>>, PrepareError> {
    let mut alpha_masks = vec![false; scene.textures.len()];
    for material in &scene.materials {
        if let (Some(_), Some(binding)) = (material.alpha_cutoff, &material.alpha_texture) {
            alpha_masks[binding.texture] = true;
        }
    }
    let stand_in = Arc::new(Texture::from_rgba_f32(1, 1, vec![[0.0; 4]])?);
    scene
        .textures
        .iter()
        .zip(alpha_masks)
        .map(|(desc, alpha_mask)| {
            if !(alpha_mask || lod_aov) {
                return Ok(stand_in.clone());
            }
            let why = if alpha_mask {
                "an alpha cut-out mask"
            } else {
                "the lod AOV needs the built-in pyramid"
            };
            prepared::decode_texture(desc)
                .map(Arc::new)
                .map_err(|e| PrepareError::Invalid {
                    source_label: scene.source.clone(),
                    message: format!(
                        "{e} ({why}: read by the renderer itself, even with a texture callback)"
                    ),
                })
        })
        .collect()
}

/// Average radiance of the environment as `external` sees it: the same whole-map trilinear
/// lookup as [`prepared::environment_mean`] (a footprint of one full period in s and t reads
/// the coarsest level, the mean of the map).
pub fn environment_mean(environment: &Environment, external: &dyn ExternalTextures) -> Vec3 {
    match environment {
        Environment::Color(c) => *c,
        Environment::LatLong { texture, intensity } => {
            let query = TextureQuery {
                s: 0.5,
                t: 0.5,
                dsdx: 1.0,
                dtdx: 0.0,
                dsdy: 0.0,
                dtdy: 1.0,
            };
            let options = FilterOptions {
                filter: FilterMode::Trilinear,
                ..FilterOptions::default()
            };
            sample_external(external, *texture, &query, &options).truncate() * *intensity
        }
    }
}
