//! A local shading frame: the microfacet lobes work in coordinates where the surface
//! normal is `+z`, so cosines are plain `z` components and the distribution's formulas stay
//! those of the papers; directions go in and out of world space through this frame.

use glam::Vec3;

use super::bsdf::orthonormal_basis;

/// An orthonormal frame `(t, b, n)` about the unit normal `n`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadingFrame {
    pub t: Vec3,
    pub b: Vec3,
    pub n: Vec3,
}

impl ShadingFrame {
    /// The frame about the unit normal `n` (tangents from [`orthonormal_basis`]).
    #[inline]
    pub fn from_normal(n: Vec3) -> ShadingFrame {
        let (t, b) = orthonormal_basis(n);
        ShadingFrame { t, b, n }
    }

    /// World-space `w` in the frame's coordinates (`z` along the normal).
    #[inline]
    pub fn to_local(&self, w: Vec3) -> Vec3 {
        Vec3::new(w.dot(self.t), w.dot(self.b), w.dot(self.n))
    }

    /// Local `w` back in world space.
    #[inline]
    pub fn to_world(&self, w: Vec3) -> Vec3 {
        self.t * w.x + self.b * w.y + self.n * w.z
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shading::bsdf::tests::Uniforms;

    #[test]
    fn local_and_world_coordinates_round_trip() {
        let mut u = Uniforms(41);
        for _ in 0..200 {
            let n = Vec3::new(u.next() - 0.5, u.next() - 0.5, u.next() - 0.5).normalize();
            let w = Vec3::new(u.next() - 0.5, u.next() - 0.5, u.next() - 0.5);
            let frame = ShadingFrame::from_normal(n);
            let local = frame.to_local(w);
            assert!((local.z - w.dot(n)).abs() < 1e-6);
            assert!((frame.to_world(local) - w).length() < 1e-5);
        }
    }
}
