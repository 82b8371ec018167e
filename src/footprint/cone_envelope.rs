//! The envelope of two ray cones (seed 000, "Tracking Two Cones").
//!
//! A single cone that converges (after a thin lens, a concave mirror or a refraction) reaches
//! zero width at its apex, which asks for "infinite detail" there. Tracking a second cone
//! with a different apex and using the larger of the two widths removes those contours.
//! The pairs per camera (seed 000's table): thin lens + pinhole; pinhole + thin lens of
//! one-pixel width; orthographic + thin lens of one-pixel width. For pinhole and orthographic
//! cameras the extra cone blurs first hits near (pinhole) or far beyond (orthographic) the
//! image plane, so it is ignored until the ray first bounces.

use super::ray_cone::RayCone;

/// Two cones travelling together; the footprint is the wider of the two.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ConeEnvelope {
    /// The cone of the camera model.
    pub primary: RayCone,
    /// The extra cone that keeps the envelope from collapsing.
    pub secondary: RayCone,
    /// True while the secondary cone is ignored: the camera ray's first hit of a pinhole or
    /// orthographic camera. Cleared by any bounce.
    pub secondary_ignored: bool,
}

impl ConeEnvelope {
    /// An envelope of `primary` and `secondary`; `ignore_on_first_hit` selects the seed's
    /// first-hit special case (pinhole and orthographic cameras).
    #[inline]
    pub fn new(primary: RayCone, secondary: RayCone, ignore_on_first_hit: bool) -> ConeEnvelope {
        ConeEnvelope {
            primary,
            secondary,
            secondary_ignored: ignore_on_first_hit,
        }
    }

    /// Both cones moved `distance` along the ray.
    #[inline]
    pub fn propagate(self, distance: f32) -> ConeEnvelope {
        ConeEnvelope {
            primary: self.primary.propagate(distance),
            secondary: self.secondary.propagate(distance),
            ..self
        }
    }

    /// Both cones after a mirror reflection off curvature `k` (seed 000).
    #[inline]
    pub fn reflect(self, curvature: f32) -> ConeEnvelope {
        self.bounce(|c| c.reflect(curvature))
    }

    /// Both cones after refraction with `eta` = n_incident / n_transmitted (seed 000).
    #[inline]
    pub fn refract(self, curvature: f32, eta: f32) -> ConeEnvelope {
        self.bounce(|c| c.refract(curvature, eta))
    }

    #[inline]
    fn bounce(self, f: impl Fn(RayCone) -> RayCone) -> ConeEnvelope {
        ConeEnvelope {
            primary: f(self.primary),
            secondary: f(self.secondary),
            secondary_ignored: false,
        }
    }

    /// The envelope's width: the larger |w| of the active cones (never negative).
    #[inline]
    pub fn width(&self) -> f32 {
        if self.secondary_ignored {
            self.primary.abs_width()
        } else {
            self.primary.abs_width().max(self.secondary.abs_width())
        }
    }

    /// The envelope's spread angle: the larger angle of the active cones, which bounds how
    /// fast the envelope widens (and is what an infinitely distant environment sees).
    #[inline]
    pub fn angle(&self) -> f32 {
        if self.secondary_ignored {
            self.primary.angle
        } else {
            self.primary.angle.max(self.secondary.angle)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn envelope_never_collapses_where_one_cone_does() {
        // A thin-lens cone focusing at distance 10 and a pinhole cone from the same origin.
        let lens = RayCone::new(0.1, -0.01);
        let pinhole = RayCone::new(0.0, 0.001);
        let envelope = ConeEnvelope::new(lens, pinhole, false);
        let at_focus = envelope.propagate(10.0);
        assert!(at_focus.primary.width.abs() < 1e-6);
        assert!((at_focus.width() - 0.01).abs() < 1e-6);
    }

    #[test]
    fn secondary_is_ignored_until_the_first_bounce() {
        let envelope = ConeEnvelope::new(RayCone::new(0.0, 0.001), RayCone::new(0.5, -0.001), true);
        let hit = envelope.propagate(10.0);
        assert!((hit.width() - 0.01).abs() < 1e-6);
        let bounced = hit.reflect(0.0);
        assert!(!bounced.secondary_ignored);
        assert!((bounced.width() - 0.49).abs() < 1e-5);
    }
}
