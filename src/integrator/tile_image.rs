//! The pixels of one tile as an integrator produces them: colour, alpha and the AOVs.

pub use crate::film::TileRect;

/// Which AOVs to fill (colour and alpha are always filled).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct AovSelection {
    /// Z, N, albedo, uv.
    pub surface: bool,
    /// tex.s/t/dsdx/dtdx/dsdy/dtdy and texcolor.R/G/B/A of the first textured camera hit.
    pub texture_footprint: bool,
    /// lod and footprint.
    pub lod: bool,
}

/// Per-pixel values of a tile; AOVs are empty vectors when not selected.
/// AOVs describe the first camera sample of each pixel (the pixel centre at 1 spp).
#[derive(Clone, Debug, Default)]
pub struct TileImage {
    /// Linear RGB radiance, averaged over samples.
    pub color: Vec<[f32; 3]>,
    /// 1 for a rendered pixel (the environment is part of the image).
    pub alpha: Vec<f32>,
    /// Camera-space depth of the first hit (f32::MAX where the camera ray missed).
    pub depth: Vec<f32>,
    pub normal: Vec<[f32; 3]>,
    pub albedo: Vec<[f32; 3]>,
    pub uv: Vec<[f32; 2]>,
    /// s, t, dsdx, dtdx, dsdy, dtdy of the first texture lookup on the camera path.
    pub tex: Vec<[f32; 6]>,
    /// Filtered RGB of that lookup and A = 1 where a lookup happened.
    pub texcolor: Vec<[f32; 4]>,
    /// Mip level used by that lookup (0 where none happened).
    pub lod: Vec<f32>,
    /// World-space footprint width at that hit (0 where none happened).
    pub footprint: Vec<f32>,
    /// Marks pixels whose first-lookup AOVs are already set.
    pub lookup_done: Vec<bool>,
}

impl TileImage {
    /// A zeroed image for `tile` with the selected AOVs.
    pub fn new(tile: TileRect, aovs: AovSelection) -> TileImage {
        let n = tile.area();
        let take = |on: bool| if on { n } else { 0 };
        TileImage {
            color: vec![[0.0; 3]; n],
            alpha: vec![0.0; n],
            depth: vec![f32::MAX; take(aovs.surface)],
            normal: vec![[0.0; 3]; take(aovs.surface)],
            albedo: vec![[0.0; 3]; take(aovs.surface)],
            uv: vec![[0.0; 2]; take(aovs.surface)],
            tex: vec![[0.0; 6]; take(aovs.texture_footprint)],
            texcolor: vec![[0.0; 4]; take(aovs.texture_footprint)],
            lod: vec![0.0; take(aovs.lod)],
            footprint: vec![0.0; take(aovs.lod)],
            lookup_done: vec![false; take(aovs.texture_footprint || aovs.lod)],
        }
    }
}
