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
use crate::shading::SceneLights;
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
    let wrap = match context.scene.environment {
        Environment::LatLong { texture, .. } => context.texture_filters[texture],
        Environment::Color(_) => FilterOptions::default(),
    };
    let mean = environment_mean(&context.scene.environment, external.as_ref(), &wrap);
    context.lights = SceneLights::with_area_lights(
        &context.scene.lights,
        mean,
        context.lights.scene_radius,
        context.lights.area.clone(),
    );
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

/// Latitude bands and longitude columns the environment's mean is gathered in through an
/// external texture system.
const ENVIRONMENT_MEAN_BANDS: usize = 256;
const ENVIRONMENT_MEAN_COLUMNS: usize = 512;

/// Average radiance of the environment as `external` sees it, weighted by solid angle like
/// [`prepared::environment_mean`]: the map is read on a grid of
/// [`ENVIRONMENT_MEAN_BANDS`] x [`ENVIRONMENT_MEAN_COLUMNS`] trilinear lookups, each with a
/// footprint of its grid cell (a filter that widens an elongated footprint to its longer side
/// would blur whole bands together), and each band weighted by its share of the sphere,
/// `(cos theta0 - cos theta1) / 2`. `wrap` is the texture's own filter options (its wrap
/// modes; a lat-long map clamps in t).
pub fn environment_mean(
    environment: &Environment,
    external: &dyn ExternalTextures,
    wrap: &FilterOptions,
) -> Vec3 {
    match environment {
        Environment::Color(c) => *c,
        Environment::LatLong { texture, intensity } => {
            let options = FilterOptions {
                filter: FilterMode::Trilinear,
                ..*wrap
            };
            let bands = ENVIRONMENT_MEAN_BANDS;
            let polar_angle = |band: usize| std::f64::consts::PI * band as f64 / bands as f64;
            let mut mean = [0.0f64; 3];
            let columns = ENVIRONMENT_MEAN_COLUMNS;
            for band in 0..bands {
                let share = (polar_angle(band).cos() - polar_angle(band + 1).cos()) / 2.0;
                let weight = share / columns as f64;
                for column in 0..columns {
                    let query = TextureQuery {
                        s: ((column as f64 + 0.5) / columns as f64) as f32,
                        t: ((band as f64 + 0.5) / bands as f64) as f32,
                        dsdx: 1.0 / columns as f32,
                        dtdx: 0.0,
                        dsdy: 0.0,
                        dtdy: 1.0 / bands as f32,
                    };
                    let value = sample_external(external, *texture, &query, &options);
                    for (sum, v) in mean.iter_mut().zip(value.to_array()) {
                        *sum += weight * f64::from(v);
                    }
                }
            }
            Vec3::new(mean[0] as f32, mean[1] as f32, mean[2] as f32) * *intensity
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::texture::WrapMode;

    /// An external system that filters with the library's own textures.
    struct Builtin(Vec<Arc<Texture>>);

    impl ExternalTextures for Builtin {
        fn sample(
            &self,
            texture_index: usize,
            query: &TextureQuery,
            options: &FilterOptions,
        ) -> Result<Vec4, String> {
            Ok(self.0[texture_index].sample(query, options))
        }
    }

    #[test]
    fn the_mean_through_a_callback_is_weighted_by_solid_angle_too() {
        // Dim everywhere, a bright band of rows near the +Y pole (t near 0).
        let (w, h) = (64u32, 32u32);
        let texels = (0..h)
            .flat_map(|y| (0..w).map(move |_| y))
            .map(|y| {
                if (2..4).contains(&y) {
                    [10.0, 0.5, 4.0, 1.0]
                } else {
                    [0.1, 0.2, 0.3, 1.0]
                }
            })
            .collect();
        let texture = Arc::new(Texture::from_rgba_f32(w, h, texels).unwrap());
        let environment = Environment::LatLong {
            texture: 0,
            intensity: 1.0,
        };
        let builtin = prepared::environment_mean(&environment, std::slice::from_ref(&texture));
        let wrap = FilterOptions {
            wrap_t: WrapMode::Clamp,
            ..FilterOptions::default()
        };
        let external = environment_mean(&environment, &Builtin(vec![texture]), &wrap);
        // The unweighted mean of the map would put the red channel at 1.44.
        for (e, b) in external.to_array().into_iter().zip(builtin.to_array()) {
            assert!(
                (e - b).abs() <= 0.02 * b,
                "callback {external} vs built-in {builtin}"
            );
        }
    }
}
