//! The rendering methods `conetrace accuracy` compares: a footprint strategy, a texture
//! filter and a sample count per pixel.
//!
//! Nine rows trace one sample per pixel with a footprint strategy crossed with the filters
//! it can drive; three rows are plain supersampling (`mip0` + `bilinear` at 4, 16 and 64
//! stratified samples). The ground truth is `mip0` + `bilinear` at many stratified samples.

use crate::footprint::LodStrategy;
use crate::texture::FilterMode;

/// One way to render a scene: strategy x filter x samples per pixel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Method {
    /// The footprint strategy that drives the texture level of detail.
    pub lod: LodStrategy,
    /// The texture filter.
    pub filter: FilterMode,
    /// Stratified samples per pixel (1 = the pixel centre).
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

/// The twelve methods every scene is rendered with, in report order: the nine one-sample
/// strategy x filter pairs, then `mip0` + `bilinear` at 4, 16 and 64 samples per pixel.
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
    methods
}

/// The reference every method is compared with: `mip0` + `bilinear` at `spp` stratified
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
    fn twelve_methods_with_unique_labels() {
        let methods = compared_methods();
        assert_eq!(methods.len(), 12);
        let mut labels: Vec<String> = methods.iter().map(Method::label).collect();
        labels.sort();
        labels.dedup();
        assert_eq!(labels.len(), 12);
        assert_eq!(methods.iter().filter(|m| m.is_single_sample()).count(), 9);
        assert_eq!(methods[5].label(), "cone+ewa 1spp");
        assert_eq!(methods[11].label(), "mip0+bilinear 64spp");
    }
}
