//! Marching one cone through the voxel pyramid: seed 003's loop and blend equation.
//!
//! From `start` (the voxel offset that skips the surface's own voxel) the cone advances in
//! steps of [`STEP_FRACTION`] of its diameter. At each step the diameter `D = 2 d tan(a)`
//! (at least one voxel) picks the level `log2(D / voxel)`, the same footprint reasoning as
//! a texture's level of detail: one lookup whose texel is as wide as the cone there. The
//! quadrilinear sample is blended front to back, `Lv <- Lv + (1 - Lv.alpha) Lv_step`,
//! until the accumulated opacity reaches 1, the level passes the pyramid's top or the
//! cone's footprint leaves the grid (a sample just outside it still reads the voxels on its
//! edge, where a scene's bounding surfaces lie). Directional voxels are read as seen along
//! the cone's direction.
//!
//! A voxel's opacity is what a path one voxel long loses; a step of length `s` through
//! voxels of edge `l` (the level's) loses `1 - (1 - alpha)^(s / l)` (Crassin et al. 2011,
//! sec. 3.2, opacity correction). As `l` is the cone's diameter, which grows along the
//! step, `s / l` is taken as the integral of `dt / D(t)` over the step, so the result
//! does not depend on the step size in uniform regions.

use glam::Vec3;

use super::grid::{VoxelKind, VoxelPyramid};

/// Step length as a fraction of the cone's diameter (`docs/vct.md` measures the choice).
pub const STEP_FRACTION: f32 = 0.5;
/// Accumulated opacity at which a cone stops: optical depth never makes it exactly 1.
const OPAQUE: f32 = 0.999;
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

/// Sampled voxels are kept at most this many times smaller than the height of the cone's
/// axis above the surface it leaves, so that neither level of a lookup (the upper one twice
/// as coarse, its trilinear reach one voxel) reaches back into that surface's own voxels.
pub const CLEARANCE_VOXELS: f32 = 3.0;

/// How the cone's axis rises above the tangent plane of the surface it leaves: at distance
/// `t` along the cone it is `height + slope * t` above it (`slope` the cosine between the
/// cone's direction and the surface's normal).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Clearance {
    pub height: f32,
    pub slope: f32,
}

/// One cone to march.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cone {
    pub origin: Vec3,
    /// Unit direction of the axis.
    pub direction: Vec3,
    /// Half-angle, radians.
    pub aperture: f32,
    /// Distance of the first sample from `origin`.
    pub start: f32,
    /// Where marching stops (infinite: when the cone leaves the grid).
    pub max_distance: f32,
    /// The surface the cone leaves, if any (see [`CLEARANCE_VOXELS`]).
    pub clearance: Option<Clearance>,
}

/// A cone from `origin` along the unit `direction` with half-angle `aperture`, marched from
/// distance `start` to at most `max_distance` (infinite: until it leaves the grid), leaving
/// no surface.
pub fn trace_cone(
    pyramid: &VoxelPyramid,
    origin: Vec3,
    direction: Vec3,
    aperture: f32,
    start: f32,
    max_distance: f32,
) -> ConeResult {
    let cone = Cone {
        origin,
        direction,
        aperture,
        start,
        max_distance,
        clearance: None,
    };
    trace_cone_stepped(pyramid, &cone, STEP_FRACTION)
}

/// The width of the voxels a cone samples at distance `t`, as `a + b t` over the step that
/// starts there: its footprint `spread t`, at most the clearance's bound, at least one
/// voxel.
#[inline]
fn sampled_width(cone: &Cone, spread: f32, voxel: f32, t: f32) -> (f32, f32) {
    let mut width = (0.0, spread);
    if let Some(c) = cone.clearance {
        let bound = (
            c.height / CLEARANCE_VOXELS,
            c.slope.max(0.0) / CLEARANCE_VOXELS,
        );
        if bound.0 + bound.1 * t < spread * t {
            width = bound;
        }
    }
    if width.0 + width.1 * t <= voxel {
        width = (voxel, 0.0);
    }
    width
}

/// `cone` marched with steps of `step_fraction` sampled voxel widths (for measuring the
/// choice).
pub fn trace_cone_stepped(pyramid: &VoxelPyramid, cone: &Cone, step_fraction: f32) -> ConeResult {
    let voxel = pyramid.frame.voxel_size;
    let spread = 2.0 * cone.aperture.tan();
    let max_level = pyramid.max_level();
    let directional = pyramid.kind == VoxelKind::Directional;
    let mut acc = [0.0f32; 4];
    let mut distance = cone.start;
    let mut steps = 0;
    while acc[3] < OPAQUE && steps < MAX_STEPS && distance < cone.max_distance {
        let (a, b) = sampled_width(cone, spread, voxel, distance);
        let width = a + b * distance;
        let level = (width / voxel).log2();
        let position = cone.origin + cone.direction * distance;
        // Past one sampled width outside the grid, neither level's trilinear reach (half a
        // voxel of the lower, one of the upper) touches its edge voxels.
        if level >= max_level || pyramid.frame.distance_outside(position) >= width {
            break;
        }
        let step = (width * step_fraction).min(cone.max_distance - distance);
        // Optical depth per sampled voxel, and radiance premultiplied by it.
        let sample = pyramid.sample(position, level, cone.direction);
        steps += 1;
        let tau = sample[3];
        if tau > 0.0 {
            // Opacity correction (Crassin et al. 2011, sec. 3.2): the step's length in
            // units of the voxels sampled. A directional voxel's opacity is that of its own
            // width (composed along it), so the sample's width is the unit. An isotropic
            // voxel keeps its children's opacity whatever its size, so the unit grows with
            // the width along the step: the integral of dt / (a + b t), exact for a uniform
            // medium.
            let length = if directional || b == 0.0 {
                step / width
            } else {
                ((a + b * (distance + step)) / width).ln() / b
            };
            let alpha = 1.0 - (-tau * length).exp();
            let scale = alpha / tau;
            let remaining = 1.0 - acc[3];
            for c in 0..3 {
                acc[c] += remaining * sample[c] * scale;
            }
            acc[3] += remaining * alpha;
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
    use crate::vct::grid::{GridFrame, VoxelKind, VoxelLevel};
    use crate::vct::mipmap::build_pyramid;

    const KINDS: [VoxelKind; 2] = [VoxelKind::Directional, VoxelKind::Isotropic];

    /// A grid filled with voxels of opacity `alpha` and radiance `radiance`.
    fn uniform(n: u32, alpha: f32, radiance: f32, kind: VoxelKind) -> VoxelPyramid {
        let frame = GridFrame {
            origin: Vec3::ZERO,
            voxel_size: 0.5,
            dims: [n; 3],
        };
        let mut level = VoxelLevel::empty(frame.dims);
        level
            .voxels
            .fill([alpha * radiance, alpha * radiance, alpha * radiance, alpha]);
        build_pyramid(frame, level, kind)
    }

    #[test]
    fn narrow_cone_through_a_uniform_slab_has_the_analytic_transmittance() {
        // A needle (level 0 throughout) along x through uniform voxels of opacity a: a
        // path of length L keeps (1 - a)^(L / voxel), and the radiance gathered is
        // L_voxel times the opacity accumulated.
        let a = 0.2;
        for kind in KINDS {
            let p = uniform(32, a, 3.0, kind);
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
    }

    #[test]
    fn wide_isotropic_cone_follows_the_integral_of_its_footprint() {
        // Isotropic levels of a uniform grid keep the voxels' opacity a whatever their
        // size, so with the diameter growing as D = 2 d tan(a) the optical depth in units
        // of the sampled voxel is the integral of dd / D(d) = ln(d1 / d0) / (2 tan a)
        // (while D is more than one voxel), and T = (1 - alpha)^that, whatever the steps.
        let a = 0.1;
        let p = uniform(64, a, 1.0, VoxelKind::Isotropic);
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
    fn wide_directional_cone_through_a_uniform_medium_keeps_the_physical_transmittance() {
        // Composed front to back, a level-l voxel of a uniform medium is 2^l voxels thick:
        // opacity 1 - (1 - a)^(2^l). The cone then loses what a ray of the same length
        // does, (1 - a)^((d1 - d0) / voxel), up to the linear blend between levels.
        let a = 0.01;
        let p = uniform(128, a, 1.0, VoxelKind::Directional);
        let origin = Vec3::new(1.0, 32.0, 32.0);
        for aperture in [0.05f32, 0.2, 0.5] {
            let (d0, d1) = (4.0f32, 24.0f32);
            let r = trace_cone(&p, origin, Vec3::X, aperture, d0, d1);
            let expect = 1.0 - (1.0 - a).powf((d1 - d0) / 0.5);
            assert!(
                (r.alpha - expect).abs() < 0.05 * expect,
                "aperture {aperture}: {} vs {expect}",
                r.alpha
            );
        }
    }

    #[test]
    fn opaque_voxels_stop_the_cone_and_empty_ones_let_it_out() {
        for kind in KINDS {
            let empty = uniform(16, 0.0, 0.0, kind);
            let r = trace_cone(&empty, Vec3::splat(4.0), Vec3::Y, 0.5, 0.5, f32::INFINITY);
            assert_eq!(r.alpha, 0.0);
            assert!(r.steps > 0);
            // Optical depth never makes a cone exactly opaque: it stops past OPAQUE, within
            // a few steps.
            let full = uniform(16, 1.0, 2.0, kind);
            let r = trace_cone(&full, Vec3::splat(4.0), Vec3::Y, 0.5, 0.5, f32::INFINITY);
            assert!(r.alpha >= OPAQUE, "{}", r.alpha);
            assert!(r.steps <= 3, "{}", r.steps);
            assert!((r.radiance.y - 2.0 * r.alpha).abs() < 1e-5);
        }
    }

    /// A `n x h x n` grid of unit voxels whose top layer is an opaque emitter of radiance
    /// `radiance` and, when `walls`, whose four sides are too, over a black floor: a point
    /// on the floor sees nothing but emitters above it.
    fn emitter_box(n: u32, h: u32, radiance: f32, walls: bool, kind: VoxelKind) -> VoxelPyramid {
        let frame = GridFrame {
            origin: Vec3::ZERO,
            voxel_size: 1.0,
            dims: [n, h, n],
        };
        let mut level = VoxelLevel::empty(frame.dims);
        let lit = [radiance, radiance, radiance, 1.0];
        for z in 0..n {
            for y in 0..h {
                for x in 0..n {
                    let side = x == 0 || z == 0 || x == n - 1 || z == n - 1;
                    if y == h - 1 || (walls && side) {
                        level.voxels[frame.index(x, y, z)] = lit;
                    } else if y == 0 {
                        // The black floor the point stands on.
                        level.voxels[frame.index(x, y, z)] = [0.0, 0.0, 0.0, 1.0];
                    }
                }
            }
        }
        build_pyramid(frame, level, kind)
    }

    #[test]
    fn a_cone_looking_at_a_wide_emitter_sees_its_radiance() {
        // The emitter fills the cone's whole footprint, at the grid's top edge: the cone
        // must gather its radiance and become opaque, however coarse the level it reads
        // it at (here about level 5).
        // Started from the floor, the cone keeps its samples off the floor's voxels.
        let p = emitter_box(128, 48, 2.0, false, VoxelKind::Directional);
        let (at, n) = (Vec3::new(64.0, 0.5, 64.0), Vec3::Y);
        let cone = surface_cone(&p, at, n, n, DIFFUSE_APERTURE, CONE_START);
        let r = trace_cone_stepped(&p, &cone, STEP_FRACTION);
        // Interpolated opacity let a sixth of a one-voxel opaque layer through (0.84
        // measured); interpolated optical depth keeps the layer opaque.
        assert!(r.alpha >= OPAQUE, "opacity {}", r.alpha);
        assert!(
            (r.radiance.y - 2.0 * r.alpha).abs() < 1e-3,
            "radiance {}",
            r.radiance.y
        );
        // Isotropic voxels dilute the one-voxel emitter at the level it is read at.
        let iso = emitter_box(128, 48, 2.0, false, VoxelKind::Isotropic);
        let r_iso = trace_cone_stepped(&iso, &cone, STEP_FRACTION);
        assert!(
            r_iso.alpha < 0.5 * r.alpha,
            "isotropic opacity {}",
            r_iso.alpha
        );
    }

    #[test]
    fn diffuse_cones_under_an_enclosing_emitter_gather_its_radiance() {
        // Every direction above the floor point ends on an emitter of radiance L, so the
        // irradiance is pi L and the cones' weighted sum (irradiance over pi) must be L.
        // With interpolated opacity each side cone ended with opacity about 0.75, the rest
        // seen through the one-voxel walls (1.55 of 2.0 gathered); interpolated optical
        // depth keeps the walls opaque.
        let p = emitter_box(64, 40, 2.0, true, VoxelKind::Directional);
        let at = Vec3::new(32.0, 0.5, 32.0);
        let g = gather_diffuse(&p, at, Vec3::Y, CONE_START, STEP_FRACTION);
        assert!(g.radiance.y > 0.97 * 2.0, "gathered {}", g.radiance.y);
        assert!(
            (g.radiance.y - 2.0 * (1.0 - g.open)).abs() < 1e-3,
            "the floor was seen"
        );
        // Halving the step changes the gathered light by less than 3 % of the emitter's.
        let half = gather_diffuse(&p, at, Vec3::Y, CONE_START, 0.5 * STEP_FRACTION);
        assert!((half.radiance.y - g.radiance.y).abs() < 0.03 * 2.0);
    }
}

/// Half-angle of seed 003's diffuse cones, and of the cone along the normal in
/// [`DIFFUSE_BANDS`].
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

/// What the diffuse cones ([`diffuse_cones`]) gather at a surface point.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DiffuseGather {
    /// `sum_j W_j L_v(x, w_j, pi/6)` (to be multiplied by the diffuse albedo `k_d`).
    pub radiance: Vec3,
    /// `sum_j W_j (1 - alpha_j)`: the cosine-weighted share of directions the voxels leave
    /// open (what sees the environment).
    pub open: f32,
    pub steps: u64,
}

/// The diffuse cones at point `p` with unit normal `n`.
pub fn gather_diffuse(
    pyramid: &VoxelPyramid,
    p: Vec3,
    n: Vec3,
    start: ConeStart,
    step_fraction: f32,
) -> DiffuseGather {
    let mut out = DiffuseGather::default();
    for DiffuseCone {
        direction,
        aperture,
        weight,
    } in diffuse_cones(n)
    {
        let cone = surface_cone(pyramid, p, n, direction, aperture, start);
        let r = trace_cone_stepped(pyramid, &cone, step_fraction);
        out.radiance += weight * r.radiance;
        out.open += weight * (1.0 - r.alpha);
        out.steps += u64::from(r.steps);
    }
    out
}

/// The cone of half-angle `aperture` along `direction` leaving the surface point `p` of
/// unit normal `n`, started as `start` says.
pub fn surface_cone(
    pyramid: &VoxelPyramid,
    p: Vec3,
    n: Vec3,
    direction: Vec3,
    aperture: f32,
    start: ConeStart,
) -> Cone {
    let voxel = pyramid.frame.voxel_size;
    let height = start.normal_voxels * voxel;
    Cone {
        origin: p + n * height,
        direction,
        aperture,
        start: start.along_voxels * voxel,
        max_distance: f32::INFINITY,
        clearance: Some(Clearance {
            height,
            slope: direction.dot(n),
        }),
    }
}

/// One cone of the diffuse cone set: its direction, half-angle and weight.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DiffuseCone {
    pub direction: Vec3,
    pub aperture: f32,
    pub weight: f32,
}

/// The diffuse cone set as bands of polar angle about the normal: `(upper edge in degrees,
/// cones in the band)`, from the normal outwards. The first band is the cap around the
/// normal (one cone); each later band holds cones evenly spaced in azimuth, their axes at
/// the band's middle and their half-angle half its width. Seed 003's six cones are the
/// bands `(30, 1), (90, 5)`; its one side band leaves five near-ray samples (the clearance
/// narrows cones near the surface) at 60 degrees, which all miss a ceiling whose edge is
/// 51-60 degrees out (an open 10x10 room 4 high got 64 % of its light). Splitting the side
/// band in three, with more cones towards the horizon, is what `docs/vct.md` measured.
pub const DIFFUSE_BANDS: [(f32, u32); 4] = [(30.0, 1), (55.0, 5), (75.0, 6), (90.0, 6)];

/// How many cones [`diffuse_cones`] returns.
pub const DIFFUSE_CONE_COUNT: usize = 18;

/// The diffuse cones about the unit normal `n`. Each weighs its share of the cosine-weighted
/// hemisphere: a band of polar angles `[a, b]` holds `(1/pi) int cos = sin^2 b - sin^2 a`
/// of it, split equally among its cones, so the weights sum to 1 and a constant radiance
/// `L` gathers exactly `L`.
pub fn diffuse_cones(n: Vec3) -> [DiffuseCone; DIFFUSE_CONE_COUNT] {
    let (t, b) = crate::shading::bsdf::orthonormal_basis(n);
    let mut cones = [DiffuseCone {
        direction: n,
        aperture: 0.0,
        weight: 0.0,
    }; DIFFUSE_CONE_COUNT];
    let mut next = 0;
    let mut from = 0f32;
    for (to_degrees, count) in DIFFUSE_BANDS {
        let to = to_degrees.to_radians();
        let share = (to.sin().powi(2) - from.sin().powi(2)) / count as f32;
        // The cap's cone is the normal itself; a band's cones sit at its middle.
        let (polar, aperture) = if from == 0.0 {
            (0.0f32, to)
        } else {
            (0.5 * (from + to), 0.5 * (to - from))
        };
        for k in 0..count {
            let phi = k as f32 * std::f32::consts::TAU / count as f32;
            let d = n * polar.cos() + (t * phi.cos() + b * phi.sin()) * polar.sin();
            cones[next] = DiffuseCone {
                direction: d.normalize(),
                aperture,
                weight: share,
            };
            next += 1;
        }
        from = to;
    }
    debug_assert_eq!(next, DIFFUSE_CONE_COUNT);
    cones
}

#[cfg(test)]
mod diffuse_cone_tests {
    use super::*;

    #[test]
    fn diffuse_cones_weigh_their_share_of_the_cosine_weighted_hemisphere() {
        let n = Vec3::new(0.3, -0.8, 0.52).normalize();
        let cones = diffuse_cones(n);
        let total: f32 = cones.iter().map(|c| c.weight).sum();
        assert!((total - 1.0).abs() < 1e-6, "{total}");
        assert_eq!(cones[0].direction, n);
        assert!((cones[0].weight - 0.25).abs() < 1e-6);
        // Every cone is a unit vector in the upper hemisphere, and a band's cones share
        // its middle polar angle and weight.
        let mut first = 1;
        let mut from = DIFFUSE_BANDS[0].0;
        for &(to, count) in &DIFFUSE_BANDS[1..] {
            let band = &cones[first..first + count as usize];
            let cos = (0.5 * (from + to)).to_radians().cos();
            let share = to.to_radians().sin().powi(2) - from.to_radians().sin().powi(2);
            for c in band {
                assert!((c.direction.length() - 1.0).abs() < 1e-5);
                assert!((c.direction.dot(n) - cos).abs() < 1e-5);
                assert!((c.weight * count as f32 - share).abs() < 1e-6);
            }
            first += count as usize;
            from = to;
        }
        assert_eq!(first, DIFFUSE_CONE_COUNT);
    }
}
