//! (placeholder until the texture module lands)
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum ColorSpace { #[default] Srgb, Linear }
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum WrapMode { #[default] Periodic, Clamp, Black, Mirror }
