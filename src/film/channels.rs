//! The channel groups a film can hold and their conventional OpenEXR channel names.
//!
//! Names follow OpenEXR conventions where they exist (`R G B A` for colour, `Z` for depth,
//! a `layer.channel` prefix for everything else, so `N.X` is channel `X` of layer `N`) and
//! the texture-filtering diagnostics get their own prefixes (`tex.`, `texcolor.`, `lod`,
//! `footprint`) so they can be compared against OpenImageIO in tests.

/// A group of channels stored together in the film.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Layer {
    /// Linear radiance and coverage: `R G B A` (colour premultiplied by alpha, as OpenEXR).
    Color,
    /// Distance along the primary ray: `Z`.
    Depth,
    /// World-space shading normal: `N.X N.Y N.Z`.
    Normal,
    /// Diffuse albedo of the first hit: `albedo.R albedo.G albedo.B`.
    Albedo,
    /// Texture coordinates of the first hit: `uv.U uv.V`.
    Uv,
    /// Texture coordinates and their screen-space derivatives:
    /// `tex.s tex.t tex.dsdx tex.dtdx tex.dsdy tex.dtdy`.
    TexFootprint,
    /// The filtered base-colour texture value `texcolor.R texcolor.G texcolor.B`, and
    /// `texcolor.A` = 1 where a texture lookup happened (0 elsewhere).
    TexColor,
    /// Mip level of detail used for the lookup: `lod`.
    Lod,
    /// Footprint size (e.g. ray-cone width) at the first hit: `footprint`.
    Footprint,
    /// The exact fixed-point sums of a partial render's samples (`super::sample_sum`): six
    /// 24-bit digits per colour channel, `sum.R.0` (least significant) to `sum.B.5`. Only
    /// renders of a sample range write it; `conetrace merge` consumes and removes it.
    SampleSum,
}

impl Layer {
    /// Number of distinct layers.
    pub const COUNT: usize = 10;

    /// Every layer, in the canonical order used for channel listings.
    pub const ALL: [Layer; Layer::COUNT] = [
        Layer::Color,
        Layer::Depth,
        Layer::Normal,
        Layer::Albedo,
        Layer::Uv,
        Layer::TexFootprint,
        Layer::TexColor,
        Layer::Lod,
        Layer::Footprint,
        Layer::SampleSum,
    ];

    /// The layer's channel names in storage order.
    pub const fn channel_names(self) -> &'static [&'static str] {
        match self {
            Layer::Color => &["R", "G", "B", "A"],
            Layer::Depth => &["Z"],
            Layer::Normal => &["N.X", "N.Y", "N.Z"],
            Layer::Albedo => &["albedo.R", "albedo.G", "albedo.B"],
            Layer::Uv => &["uv.U", "uv.V"],
            Layer::TexFootprint => &[
                "tex.s", "tex.t", "tex.dsdx", "tex.dtdx", "tex.dsdy", "tex.dtdy",
            ],
            Layer::TexColor => &["texcolor.R", "texcolor.G", "texcolor.B", "texcolor.A"],
            Layer::Lod => &["lod"],
            Layer::Footprint => &["footprint"],
            Layer::SampleSum => &[
                "sum.R.0", "sum.R.1", "sum.R.2", "sum.R.3", "sum.R.4", "sum.R.5", "sum.G.0",
                "sum.G.1", "sum.G.2", "sum.G.3", "sum.G.4", "sum.G.5", "sum.B.0", "sum.B.1",
                "sum.B.2", "sum.B.3", "sum.B.4", "sum.B.5",
            ],
        }
    }

    /// How many values one pixel of this layer holds.
    #[inline]
    pub const fn channel_count(self) -> usize {
        self.channel_names().len()
    }

    /// Position of this layer in [`Layer::ALL`].
    #[inline]
    pub const fn index(self) -> usize {
        self as usize
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn indices_match_the_canonical_order_and_names_are_unique() {
        let mut names = Vec::new();
        for (i, layer) in Layer::ALL.iter().enumerate() {
            assert_eq!(layer.index(), i);
            names.extend_from_slice(layer.channel_names());
        }
        let count = names.len();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), count);
        assert_eq!(count, 4 + 1 + 3 + 3 + 2 + 6 + 4 + 1 + 1 + 18);
    }
}
