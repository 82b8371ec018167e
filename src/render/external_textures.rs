//! A hook that lets code outside the renderer answer the scene's texture lookups.
//!
//! When a [`RenderContext`](crate::render::RenderContext) carries an [`ExternalTextures`],
//! the material base-colour and environment lookups call it with the query our footprint
//! produced (st and the four derivatives) instead of filtering the built-in
//! [`Texture`](crate::texture::Texture). The C API uses it to hand lookups to a C callback
//! (e.g. OpenImageIO's TextureSystem). Opacity lookups inside Embree's filter callbacks and the
//! environment's mean (the ambient term) still use the built-in textures.
//!
//! This module must not know about C: it is the Rust side of the hook only.

use glam::Vec4;

use crate::texture::{FilterOptions, TextureQuery};

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
