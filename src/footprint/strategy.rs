//! The texture level-of-detail strategies a render can use.

use std::fmt;
use std::str::FromStr;

/// How texture footprints are tracked (the `--lod` option).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum LodStrategy {
    /// No footprint: every lookup is a point sample of mip level 0.
    Mip0,
    /// The distance metric: the camera's pixel spread times the total path length.
    Distance,
    /// A single ray cone (seed 000 without the envelope).
    Cone1,
    /// The two-cone envelope (seed 000, "Tracking Two Cones").
    #[default]
    Cone,
    /// Ray differentials (seed 002).
    Differential,
}

impl LodStrategy {
    /// Every strategy, in the order of the `--lod` help.
    pub const ALL: [LodStrategy; 5] = [
        LodStrategy::Mip0,
        LodStrategy::Distance,
        LodStrategy::Cone1,
        LodStrategy::Cone,
        LodStrategy::Differential,
    ];

    /// The name used on the command line and in reports.
    pub fn name(self) -> &'static str {
        match self {
            LodStrategy::Mip0 => "mip0",
            LodStrategy::Distance => "distance",
            LodStrategy::Cone1 => "cone1",
            LodStrategy::Cone => "cone",
            LodStrategy::Differential => "differential",
        }
    }
}

impl fmt::Display for LodStrategy {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A name that is not one of the strategies.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("unknown LOD strategy '{0}' (expected mip0, distance, cone1, cone or differential)")]
pub struct UnknownLodStrategy(pub String);

impl FromStr for LodStrategy {
    type Err = UnknownLodStrategy;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let lower = s.trim().to_ascii_lowercase();
        LodStrategy::ALL
            .into_iter()
            .find(|l| l.name() == lower)
            .ok_or_else(|| UnknownLodStrategy(s.to_string()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        for l in LodStrategy::ALL {
            assert_eq!(l.to_string().parse::<LodStrategy>(), Ok(l));
        }
        assert_eq!("Cone".parse::<LodStrategy>(), Ok(LodStrategy::Cone));
        assert!("cones".parse::<LodStrategy>().is_err());
        assert_eq!(LodStrategy::default(), LodStrategy::Cone);
    }
}
