//! The rendering methods `conetrace accuracy` compares: a footprint strategy, a texture
//! filter and a sample count per pixel.
//!
//! Nine rows trace one sample per pixel with a footprint strategy crossed with the filters
//! it can drive; three rows are plain supersampling (`mip0` + `bilinear` at 4, 16 and 64
//! samples); four rows filter several samples per pixel (`cone` + `aniso` and
//! `differential` + `ewa` at 4 and 16 samples, each sample's footprint shrunk to its share
//! of the pixel, `crate::camera::sample_footprint_scale`). The ground truth is `mip0` +
//! `bilinear` at many samples, drawn with another seed ([`ground_truth_seed`]).

use crate::footprint::LodStrategy;
use crate::texture::FilterMode;

/// One way to render a scene: strategy x filter x samples per pixel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Method {
    /// The footprint strategy that drives the texture level of detail.
    pub lod: LodStrategy,
    /// The texture filter.
    pub filter: FilterMode,
    /// Samples per pixel (1 = the pixel centre).
    pub spp: u32,
}

impl Method {
    /// `strategy+filter`, e.g. `cone+ewa`.
    pub fn pair_name(&self) -> String {
        format!("{}+{}", self.lod, self.filter)
    }

    /// `strategy+filter Nspp`, e.g. `mip0+bilinear 16spp`: unique among [`compared_methods`].
    pub fn label(&self) -> String {
        format!("{} {}spp", self.pair_name(), self.spp)
    }

    /// True for the single-sample footprint rows (not supersampling).
    pub fn is_single_sample(&self) -> bool {
        self.spp == 1
    }
}

/// The sixteen methods every scene is rendered with, in report order: the nine one-sample
/// strategy x filter pairs, `mip0` + `bilinear` at 4, 16 and 64 samples per pixel, then
/// `cone` + `aniso` at 4 and 16 and `differential` + `ewa` at 4 and 16.
pub fn compared_methods() -> Vec<Method> {
    use FilterMode::{Aniso, Bilinear, Ewa, Trilinear};
    use LodStrategy::{Cone, Cone1, Differential, Distance, Mip0};
    let one_sample = [
        (Mip0, Bilinear),
        (Distance, Trilinear),
        (Cone1, Trilinear),
        (Cone, Trilinear),
        (Cone, Aniso),
        (Cone, Ewa),
        (Differential, Trilinear),
        (Differential, Aniso),
        (Differential, Ewa),
    ];
    let mut methods: Vec<Method> = one_sample
        .into_iter()
        .map(|(lod, filter)| Method {
            lod,
            filter,
            spp: 1,
        })
        .collect();
    methods.extend([4, 16, 64].map(|spp| Method {
        lod: Mip0,
        filter: Bilinear,
        spp,
    }));
    for (lod, filter) in [(Cone, Aniso), (Differential, Ewa)] {
        methods.extend([4, 16].map(|spp| Method { lod, filter, spp }));
    }
    methods
}

/// The seed of the ground truth's samples when the rows use `seed`: another one. Sample i
/// of a pixel is the same at every sample count (`crate::sampler`), so with the rows' seed a
/// 64-sample row would be the ground truth's first 64 samples, and its error against it
/// would look smaller than it is.
pub fn ground_truth_seed(seed: u32) -> u32 {
    !seed
}

/// The reference every method is compared with: `mip0` + `bilinear` at `spp`
/// samples per pixel.
pub fn ground_truth(spp: u32) -> Method {
    Method {
        lod: LodStrategy::Mip0,
        filter: FilterMode::Bilinear,
        spp,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sixteen_methods_with_unique_labels() {
        let methods = compared_methods();
        assert_eq!(methods.len(), 16);
        let mut labels: Vec<String> = methods.iter().map(Method::label).collect();
        labels.sort();
        labels.dedup();
        assert_eq!(labels.len(), 16);
        assert_eq!(methods.iter().filter(|m| m.is_single_sample()).count(), 9);
        assert_eq!(methods[5].label(), "cone+ewa 1spp");
        assert_eq!(methods[11].label(), "mip0+bilinear 64spp");
        assert_eq!(methods[12].label(), "cone+aniso 4spp");
        assert_eq!(methods[15].label(), "differential+ewa 16spp");
        assert_ne!(ground_truth_seed(0), 0);
        assert_ne!(ground_truth_seed(7), 7);
    }
}
