//! Marching one cone through the voxel pyramid: seed 003's loop and blend equation.
//!
//! From `start` (the voxel offset that skips the surface's own voxel) the cone advances in
//! steps of [`STEP_FRACTION`] of its diameter. At each step the diameter `D = 2 d tan(a)`
//! (at least one voxel) picks the level `log2(D / voxel)`, the same footprint reasoning as
//! a texture's level of detail: one lookup whose texel is as wide as the cone there. The
//! quadrilinear sample is blended front to back, `Lv <- Lv + (1 - Lv.alpha) Lv_step`,
//! until the accumulated opacity reaches 1, the level passes the pyramid's top or the cone
//! leaves the grid.
//!
//! A voxel's opacity is what a path one voxel long loses; a step of length `s` through
//! voxels of edge `l` (the level's) loses `1 - (1 - alpha)^(s / l)` (Crassin et al. 2011,
//! sec. 3.2, opacity correction). As `l` is the cone's diameter, which grows along the
//! step, `s / l` is taken as the integral of `dt / D(t)` over the step, so the result
//! does not depend on the step size in uniform regions.

use glam::Vec3;

use super::grid::VoxelPyramid;

/// Step length as a fraction of the cone's diameter (`docs/vct.md` measures the choice).
pub const STEP_FRACTION: f32 = 0.5;
/// A safety bound on the steps of one cone (a grid of 1024 voxels needs about 2100 steps at
/// the narrowest aperture).
const MAX_STEPS: u32 = 8192;

/// The radiance a cone gathers and how much of its view the voxels block.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ConeResult {
    /// Radiance gathered front to back.
    pub radiance: Vec3,
    /// Accumulated opacity in [0, 1]: `1 - alpha` of the cone sees past the grid.
    pub alpha: f32,
    /// Lookups made.
    pub steps: u32,
}

/// A cone from `origin` along the unit `direction` with half-angle `aperture`, marched from
/// distance `start` to at most `max_distance` (infinite: until it leaves the grid).
pub fn trace_cone(
    pyramid: &VoxelPyramid,
    origin: Vec3,
    direction: Vec3,
    aperture: f32,
    start: f32,
    max_distance: f32,
) -> ConeResult {
    trace_cone_stepped(
        pyramid,
        origin,
        direction,
        aperture,
        start,
        max_distance,
        STEP_FRACTION,
    )
}

/// [`trace_cone`] with steps of `step_fraction` diameters (for measuring the choice).
pub fn trace_cone_stepped(
    pyramid: &VoxelPyramid,
    origin: Vec3,
    direction: Vec3,
    aperture: f32,
    start: f32,
    max_distance: f32,
    step_fraction: f32,
) -> ConeResult {
    let voxel = pyramid.frame.voxel_size;
    let spread = 2.0 * aperture.tan();
    let max_level = pyramid.max_level();
    let mut acc = [0.0f32; 4];
    let mut distance = start;
    let mut steps = 0;
    while acc[3] < 1.0 && steps < MAX_STEPS && distance < max_distance {
        let diameter = (spread * distance).max(voxel);
        let level = (diameter / voxel).log2();
        let position = origin + direction * distance;
        if level >= max_level || !pyramid.frame.contains(position) {
            break;
        }
        let step = (diameter * step_fraction).min(max_distance - distance);
        let sample = pyramid.sample(position, level);
        steps += 1;
        let alpha = sample[3].clamp(0.0, 1.0);
        if alpha > 0.0 {
            // Opacity correction: the step's length in units of the voxels it samples. Where
            // the footprint grows with distance that is the integral of dt / (spread t) over
            // the step, ln(1 + step / distance) / spread, exact for a uniform medium; where
            // it is clamped to one voxel, step / voxel.
            let depth = if spread * distance > voxel {
                (step / distance).ln_1p() / spread
            } else {
                step / diameter
            };
            let corrected = 1.0 - (1.0 - alpha).powf(depth);
            let scale = corrected / alpha;
            let remaining = 1.0 - acc[3];
            for c in 0..3 {
                acc[c] += remaining * sample[c] * scale;
            }
            acc[3] += remaining * corrected;
        }
        distance += step;
    }
    ConeResult {
        radiance: Vec3::new(acc[0], acc[1], acc[2]),
        alpha: acc[3].min(1.0),
        steps,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vct::grid::{GridFrame, VoxelLevel};
    use crate::vct::mipmap::build_pyramid;

    /// A grid filled with voxels of opacity `alpha` and radiance `radiance`.
    fn uniform(n: u32, alpha: f32, radiance: f32) -> VoxelPyramid {
        let frame = GridFrame {
            origin: Vec3::ZERO,
            voxel_size: 0.5,
            dims: [n; 3],
        };
        let mut level = VoxelLevel::empty(frame.dims);
        level
            .voxels
            .fill([alpha * radiance, alpha * radiance, alpha * radiance, alpha]);
        build_pyramid(frame, level)
    }

    #[test]
    fn narrow_cone_through_a_uniform_slab_has_the_analytic_transmittance() {
        // A needle (level 0 throughout) along x through uniform voxels of opacity a: a
        // path of length L keeps (1 - a)^(L / voxel), and the radiance gathered is
        // L_voxel times the opacity accumulated.
        let a = 0.2;
        let p = uniform(32, a, 3.0);
        let origin = Vec3::new(1.0, 8.0, 8.0);
        for length in [0.8f32, 2.5, 5.0] {
            let r = trace_cone(&p, origin, Vec3::X, 1e-4, 0.0, length);
            let expect = 1.0 - (1.0 - a).powf(length / 0.5);
            assert!(
                (r.alpha - expect).abs() < 1e-5,
                "L={length}: {} vs {expect}",
                r.alpha
            );
            assert!((r.radiance.x - 3.0 * expect).abs() < 1e-4);
        }
    }

    #[test]
    fn wide_cone_through_a_uniform_region_follows_the_integral_of_its_footprint() {
        // With the diameter growing as D = 2 d tan(a), the optical depth in units of the
        // sampled voxel size is the integral of dd / D(d) = ln(d1 / d0) / (2 tan a)
        // (while D is more than one voxel), so T = (1 - alpha)^that, whatever the steps;
        // the mip levels of a uniform grid are uniform inside.
        let a = 0.1;
        let p = uniform(64, a, 1.0);
        let aperture = 0.2f32;
        let (d0, d1) = (4.0f32, 12.0f32);
        let origin = Vec3::new(1.0, 16.0, 16.0);
        let r = trace_cone(&p, origin, Vec3::X, aperture, d0, d1);
        let depth = (d1 / d0).ln() / (2.0 * aperture.tan());
        let expect = 1.0 - (1.0 - a).powf(depth);
        assert!(
            (r.alpha - expect).abs() < 1e-3 * expect,
            "{} vs {expect}",
            r.alpha
        );
    }

    #[test]
    fn opaque_voxels_stop_the_cone_and_empty_ones_let_it_out() {
        let empty = uniform(16, 0.0, 0.0);
        let r = trace_cone(&empty, Vec3::splat(4.0), Vec3::Y, 0.5, 0.5, f32::INFINITY);
        assert_eq!(r.alpha, 0.0);
        assert!(r.steps > 0);
        let full = uniform(16, 1.0, 2.0);
        let r = trace_cone(&full, Vec3::splat(4.0), Vec3::Y, 0.5, 0.5, f32::INFINITY);
        assert_eq!(r.alpha, 1.0);
        assert_eq!(r.steps, 1);
        assert!((r.radiance.y - 2.0).abs() < 1e-6);
    }
}

/// Half-angle of each of the six diffuse cones (seed 003).
pub const DIFFUSE_APERTURE: f32 = std::f32::consts::PI / 6.0;
/// Where the cones of a surface point start, in level-0 voxels: the origin moved along the
/// normal, then the first sample along the cone, past the surface's own voxel, whose light
/// is the surface's own (`docs/vct.md` measures the choice).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConeStart {
    /// Distance of the cones' origin from the surface along its normal.
    pub normal_voxels: f32,
    /// Distance along each cone of its first sample.
    pub along_voxels: f32,
}

/// The start every integrator cone and every bounce cone uses.
pub const CONE_START: ConeStart = ConeStart {
    normal_voxels: 1.5,
    along_voxels: 1.0,
};

/// What seed 003's six diffuse cones gather at a surface point.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DiffuseGather {
    /// `sum_j W_j L_v(x, w_j, pi/6)` (to be multiplied by the diffuse albedo `k_d`).
    pub radiance: Vec3,
    /// `sum_j W_j (1 - alpha_j)`: the cosine-weighted share of directions the voxels leave
    /// open (what sees the environment).
    pub open: f32,
    pub steps: u64,
}

/// The six diffuse cones at point `p` with unit normal `n`.
pub fn gather_diffuse(
    pyramid: &VoxelPyramid,
    p: Vec3,
    n: Vec3,
    start: ConeStart,
    step_fraction: f32,
) -> DiffuseGather {
    let voxel = pyramid.frame.voxel_size;
    let origin = p + n * (start.normal_voxels * voxel);
    let mut out = DiffuseGather::default();
    for (direction, weight) in diffuse_cones(n) {
        let r = trace_cone_stepped(
            pyramid,
            origin,
            direction,
            DIFFUSE_APERTURE,
            start.along_voxels * voxel,
            f32::INFINITY,
            step_fraction,
        );
        out.radiance += weight * r.radiance;
        out.open += weight * (1.0 - r.alpha);
        out.steps += u64::from(r.steps);
    }
    out
}

/// Seed 003's six diffuse cones about the unit normal `n`: one along `n` with weight 1/4
/// (the cosine-weighted share of the cap of half-angle pi/6, `(1/pi) int cos sin = 1/4`)
/// and five at 60 degrees from it, 72 degrees apart in azimuth, with weight 3/20 each (the
/// rest of the hemisphere shared equally).
pub fn diffuse_cones(n: Vec3) -> [(Vec3, f32); 6] {
    let (t, b) = crate::shading::bsdf::orthonormal_basis(n);
    let (sin60, cos60) = (60f32.to_radians().sin(), 0.5);
    let mut cones = [(n, 0.25); 6];
    for (k, cone) in cones.iter_mut().enumerate().skip(1) {
        let phi = (k - 1) as f32 * 72f32.to_radians();
        let d = n * cos60 + (t * phi.cos() + b * phi.sin()) * sin60;
        *cone = (d.normalize(), 3.0 / 20.0);
    }
    cones
}

#[cfg(test)]
mod diffuse_cone_tests {
    use super::*;

    #[test]
    fn six_cones_cover_the_hemisphere_with_weights_summing_to_one() {
        let n = Vec3::new(0.3, -0.8, 0.52).normalize();
        let cones = diffuse_cones(n);
        let total: f32 = cones.iter().map(|c| c.1).sum();
        assert!((total - 1.0).abs() < 1e-6);
        for (d, _) in &cones[1..] {
            assert!((d.dot(n) - 0.5).abs() < 1e-5);
            assert!((d.length() - 1.0).abs() < 1e-5);
        }
        // Neighbouring side cones are 72 degrees apart around the normal.
        let (a, b) = (cones[1].0 - n * 0.5, cones[2].0 - n * 0.5);
        let angle = a.normalize().dot(b.normalize()).acos().to_degrees();
        assert!((angle - 72.0).abs() < 1e-2);
    }
}
