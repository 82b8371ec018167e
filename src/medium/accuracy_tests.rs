//! The closed forms against adaptive quadrature in f64, over random and delicate segments,
//! and their inverses against bisection. Each test prints the worst relative error it found
//! (`cargo test --lib medium::accuracy_tests -- --nocapture`).

use glam::DVec3;

use super::*;
use crate::test_rng::{unit_f64, xorshift64_star};

/// Adaptive Simpson quadrature of `f` over `[a, b]`, to a relative tolerance of about
/// `tolerance` of the estimate (Lyness's criterion `|S2 - S1| <= 15 eps`, with Richardson's
/// correction). A kink (the linear density's clamp) is resolved by subdividing around it.
///
/// A panel also stops when its two halves agree to `noise` relative to its own integral:
/// where the density itself carries rounding noise (evaluated at coordinates of 1e6, where
/// an ulp is 1e-10), halving the tolerance at every level would otherwise never stop. A
/// kink does not trigger this rule (Simpson's error on a panel holding a kink is a fixed
/// fraction of the panel, whatever its width), so kinks are still resolved to `tolerance`.
fn adaptive_simpson(f: &dyn Fn(f64) -> f64, a: f64, b: f64, tolerance: f64, noise: f64) -> f64 {
    fn simpson(fa: f64, fm: f64, fb: f64, a: f64, b: f64) -> f64 {
        (b - a) / 6.0 * (fa + 4.0 * fm + fb)
    }
    #[allow(clippy::too_many_arguments)]
    fn recurse(
        f: &dyn Fn(f64) -> f64,
        a: f64,
        b: f64,
        fa: f64,
        fm: f64,
        fb: f64,
        whole: f64,
        eps: f64,
        noise: f64,
        depth: u32,
    ) -> f64 {
        let m = 0.5 * (a + b);
        let (lm, rm) = (0.5 * (a + m), 0.5 * (m + b));
        let (flm, frm) = (f(lm), f(rm));
        let left = simpson(fa, flm, fm, a, m);
        let right = simpson(fm, frm, fb, m, b);
        let delta = left + right - whole;
        let settled =
            delta.abs() <= 15.0 * eps || delta.abs() <= noise * (left.abs() + right.abs());
        if depth == 0 || settled || m <= a || m >= b {
            return left + right + delta / 15.0;
        }
        recurse(f, a, m, fa, flm, fm, left, 0.5 * eps, noise, depth - 1)
            + recurse(f, m, b, fm, frm, fb, right, 0.5 * eps, noise, depth - 1)
    }
    let (fa, fb, fm) = (f(a), f(b), f(0.5 * (a + b)));
    let whole = simpson(fa, fm, fb, a, b);
    // A first pass fixes the scale the tolerance is relative to.
    let rough = recurse(
        f,
        a,
        b,
        fa,
        fm,
        fb,
        whole,
        whole.abs() * 1e-6 + 1e-300,
        1e-6,
        30,
    );
    recurse(
        f,
        a,
        b,
        fa,
        fm,
        fb,
        whole,
        rough.abs() * tolerance + 1e-300,
        noise,
        60,
    )
}

/// Deterministic xorshift64* numbers.
struct Random(u64);

impl Random {
    fn uniform(&mut self) -> f64 {
        unit_f64(xorshift64_star(&mut self.0))
    }
    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.uniform()
    }
    fn log_range(&mut self, lo: f64, hi: f64) -> f64 {
        (lo.ln() + (hi.ln() - lo.ln()) * self.uniform()).exp()
    }
    fn direction(&mut self) -> DVec3 {
        loop {
            let v = DVec3::new(
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
            );
            let l = v.length();
            if l > 0.1 && l <= 1.0 {
                return v / l;
            }
        }
    }
}

/// The density at distance `t` along `line`, written independently of the closed forms.
/// The linear density is expanded about the line's origin, `sigma * max(0, h(o) - t (n . w))`:
/// evaluated at the point `o + t w` instead, a point 1e-9 from the plane at coordinates of
/// order 1 keeps only 7 digits of its height (ulp(2) = 4e-16), and the reference, not the
/// closed form, would be what is inaccurate.
fn density_along(density: &Density, line: &Line, t: f64) -> f64 {
    match density {
        Density::Linear(l) => {
            let height_at_origin = -(l.normal.dot(line.origin) + l.offset);
            l.sigma * (height_at_origin - t * l.normal.dot(line.direction)).max(0.0)
        }
        _ => density.density_at(line.at(t)),
    }
}

/// The relative error of `closed` against the quadrature of the density over `[t0, t1]`.
fn relative_error(density: &Density, line: &Line, t0: f64, t1: f64, noise: f64) -> (f64, f64, f64) {
    let closed = density.optical_depth(line, t0, t1);
    let reference = adaptive_simpson(&|t| density_along(density, line, t), t0, t1, 1e-14, noise);
    let error = if closed == reference {
        0.0
    } else {
        (closed - reference).abs() / reference.abs().max(f64::MIN_POSITIVE)
    };
    (error, closed, reference)
}

/// Worst relative error over `cases`, with the case, printed and returned.
fn worst_over(
    name: &str,
    noise: f64,
    cases: impl IntoIterator<Item = (Density, Line, f64, f64)>,
) -> f64 {
    let mut worst = (0.0, String::new());
    let mut count = 0;
    for (density, line, t0, t1) in cases {
        let (error, closed, reference) = relative_error(&density, &line, t0, t1, noise);
        assert!(
            closed.is_finite() && closed >= 0.0,
            "{density:?} {line:?} {t0} {t1}: {closed}"
        );
        if error > worst.0 || error.is_nan() {
            worst = (
                error,
                format!(
                    "{density:?} {line:?} [{t0}, {t1}]: closed {closed:e} quadrature {reference:e}"
                ),
            );
        }
        count += 1;
    }
    println!(
        "{name}: worst relative error {:.3e} over {count} segments ({})",
        worst.0, worst.1
    );
    worst.0
}

fn linear(sigma: f64, plane: [f64; 4]) -> Density {
    Density::Linear(LinearDensity::from_plane(sigma, plane).unwrap())
}

fn exponential(sigma: f64, height: f64, falloff: f64) -> Density {
    Density::Exponential(ExponentialDensity {
        sigma,
        height,
        falloff,
    })
}

/// Random segments: origins in a 20-unit cube, lengths from 1e-6 to `max_length`
/// (log-uniform), starting anywhere in [0, 5].
fn random_segments(seed: u64, n: usize, max_length: f64) -> Vec<(Line, f64, f64)> {
    let mut r = Random(seed);
    (0..n)
        .map(|_| {
            let line = Line {
                origin: DVec3::new(
                    r.range(-10.0, 10.0),
                    r.range(-10.0, 10.0),
                    r.range(-10.0, 10.0),
                ),
                direction: r.direction(),
            };
            let t0 = r.range(0.0, 5.0);
            (line, t0, t0 + r.log_range(1e-6, max_length))
        })
        .collect()
}

/// The closed forms must agree with quadrature to this relative error.
const TOLERANCE: f64 = 1e-10;
/// Rounding noise of the density evaluated at ordinary coordinates (|p| <= 1e6).
const ORDINARY_NOISE: f64 = 1e-13;
/// At coordinates of 1e6..1e8 the density, evaluated at `o + t w`, is only known to about
/// ulp(1e6) / h ~ 1e-10 relative: the quadrature's reference cannot be better than that.
const LARGE_COORDINATE_NOISE: f64 = 1e-9;
const LARGE_COORDINATE_TOLERANCE: f64 = 1e-8;

#[test]
fn constant_density_matches_quadrature() {
    let cases = random_segments(1, 300, 1e6)
        .into_iter()
        .map(|(line, t0, t1)| {
            (
                Density::Constant(ConstantDensity { sigma: 0.04 }),
                line,
                t0,
                t1,
            )
        });
    assert!(worst_over("constant", ORDINARY_NOISE, cases) < TOLERANCE);
}

#[test]
fn linear_density_matches_quadrature_on_random_segments() {
    let mut r = Random(2);
    let cases: Vec<_> = random_segments(3, 400, 1e6)
        .into_iter()
        .map(|(line, t0, t1)| {
            let plane = [
                r.range(-1.0, 1.0),
                r.range(-1.0, 1.0),
                r.range(-1.0, 1.0),
                r.range(-5.0, 5.0),
            ];
            (linear(r.log_range(1e-3, 1.0), plane), line, t0, t1)
        })
        .collect();
    assert!(worst_over("linear, random", ORDINARY_NOISE, cases) < TOLERANCE);
}

#[test]
fn linear_density_stays_accurate_where_it_is_delicate() {
    let plane = [0.0, 1.0, 0.0, -2.0];
    let fog = linear(0.5, plane);
    let mut cases = Vec::new();
    // Parallel to the plane, inside and outside, and nearly parallel (the crossing far away).
    for (y, dy) in [
        (1.0, 0.0),
        (3.0, 0.0),
        (1.0, 1e-12),
        (1.0, -1e-12),
        (2.0, 1e-9),
        (1.999_999, 1e-7),
    ] {
        let line = Line {
            origin: DVec3::new(0.0, y, 0.0),
            direction: DVec3::new(1.0, dy, 0.0).normalize(),
        };
        for length in [1e-6, 1.0, 1e3, 1e6] {
            cases.push((fog, line, 0.0, length));
        }
    }
    // Crossing the plane (the clamp inside the segment), from either side, at shallow angles.
    for (y, dy) in [
        (0.0, 1.0),
        (4.0, -1.0),
        (1.9, 0.001),
        (2.1, -0.001),
        (2.0 - 1e-9, 1e-6),
    ] {
        let line = Line {
            origin: DVec3::new(0.0, y, 0.0),
            direction: DVec3::new(1.0, dy, 0.0).normalize(),
        };
        for length in [1e-6, 1e-3, 10.0, 1e4, 1e6] {
            cases.push((fog, line, 0.0, length));
        }
    }
    // Very large coordinates: far along x, and a plane far from the origin.
    let mut large = Vec::new();
    let far = linear(0.5, [0.0, 1.0, 0.0, -1e6]);
    for (x, y) in [(1e7, 1e6 - 3.0), (-1e8, 1e6 - 0.5), (1e6, 1e6 + 1.0)] {
        let line = Line {
            origin: DVec3::new(x, y, 1e6),
            direction: DVec3::new(0.6, 0.0, 0.8),
        };
        large.push((far, line, 0.0, 1e-6));
        large.push((far, line, 0.0, 1e6));
        let crossing = Line {
            direction: DVec3::new(0.6, 0.1, 0.8).normalize(),
            ..line
        };
        large.push((far, crossing, 0.0, 100.0));
    }
    assert!(worst_over("linear, delicate", ORDINARY_NOISE, cases) < TOLERANCE);
    let worst = worst_over("linear, large coordinates", LARGE_COORDINATE_NOISE, large);
    assert!(worst < LARGE_COORDINATE_TOLERANCE);
}

#[test]
fn exponential_density_matches_quadrature_on_random_segments() {
    let mut r = Random(4);
    // Lengths up to 1e3, cut to 100 / falloff so the density spans at most e^100 (beyond,
    // depths overflow f64 and both sides are infinite).
    let cases: Vec<_> = random_segments(5, 400, 1e3)
        .into_iter()
        .map(|(line, t0, t1)| {
            let falloff = r.log_range(1e-3, 2.0);
            let fog = exponential(r.log_range(1e-3, 1.0), r.range(-5.0, 5.0), falloff);
            (fog, line, t0, t0 + (t1 - t0).min(100.0 / falloff))
        })
        .collect();
    assert!(worst_over("exponential, random", ORDINARY_NOISE, cases) < TOLERANCE);
}

#[test]
fn exponential_density_stays_accurate_where_it_is_delicate() {
    let fog = exponential(0.3, 1.0, 0.5);
    let mut cases = Vec::new();
    // b * dy near 0: horizontal, and tilted by 1e-15 .. 1e-3.
    for dy in [0.0, 1e-15, -1e-15, 1e-12, -1e-9, 1e-6, -1e-3] {
        let line = Line {
            origin: DVec3::new(0.0, 2.0, 0.0),
            direction: DVec3::new(1.0, dy, 0.0).normalize(),
        };
        for length in [1e-6, 1.0, 1e3, 1e6] {
            cases.push((fog, line, 0.0, length));
        }
    }
    // A tiny falloff (nearly constant) and a steep one.
    for falloff in [1e-12, 1e-6, 20.0] {
        let line = Line {
            origin: DVec3::new(0.0, 0.5, 0.0),
            direction: DVec3::new(0.6, 0.8, 0.0),
        };
        for length in [1e-6, 1.0, 30.0] {
            cases.push((exponential(0.3, 1.0, falloff), line, 0.0, length));
        }
    }
    // Very large coordinates: far in x and z, the fog layer far up.
    let mut large = Vec::new();
    let far = exponential(0.3, 1e6, 0.5);
    for y in [1e6 - 2.0, 1e6 + 3.0] {
        let line = Line {
            origin: DVec3::new(1e8, y, -1e8),
            direction: DVec3::new(0.6, 0.0, 0.8),
        };
        large.push((far, line, 0.0, 1e-6));
        large.push((far, line, 0.0, 1e6));
        let tilted = Line {
            direction: DVec3::new(0.6, 0.05, 0.8).normalize(),
            ..line
        };
        large.push((far, tilted, 0.0, 50.0));
    }
    assert!(worst_over("exponential, delicate", ORDINARY_NOISE, cases) < TOLERANCE);
    let worst = worst_over(
        "exponential, large coordinates",
        LARGE_COORDINATE_NOISE,
        large,
    );
    assert!(worst < LARGE_COORDINATE_TOLERANCE);
}

/// Bisection on the closed-form depth (monotone in `t`) for the distance where it reaches
/// `tau`.
fn bisect(density: &Density, line: &Line, t0: f64, t1: f64, tau: f64) -> f64 {
    let (mut lo, mut hi) = (t0, t1);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if density.optical_depth(line, t0, mid) < tau {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

#[test]
fn inverses_match_bisection() {
    let mut r = Random(6);
    let mut worst = [0.0f64; 3];
    for (i, (line, t0, t1)) in random_segments(7, 900, 1e3).into_iter().enumerate() {
        let density = match i % 3 {
            0 => Density::Constant(ConstantDensity {
                sigma: r.log_range(1e-3, 1.0),
            }),
            1 => linear(
                r.log_range(1e-3, 1.0),
                [
                    r.range(-1.0, 1.0),
                    r.range(-1.0, 1.0),
                    r.range(-1.0, 1.0),
                    r.range(-5.0, 5.0),
                ],
            ),
            _ => exponential(
                r.log_range(1e-3, 1.0),
                r.range(-5.0, 5.0),
                r.log_range(1e-3, 2.0),
            ),
        };
        // As above: keep the exponential's dynamic range within e^100.
        let t1 = match density {
            Density::Exponential(e) => t0 + (t1 - t0).min(100.0 / e.falloff),
            _ => t1,
        };
        let total = density.optical_depth(&line, t0, t1);
        if total <= 0.0 {
            // No fog on this segment: nothing positive is ever reached.
            assert_eq!(density.distance_at_optical_depth(&line, t0, t1, 1e-3), None);
            continue;
        }
        // Beyond the total: never reached.
        assert_eq!(
            density.distance_at_optical_depth(&line, t0, t1, total * 1.001 + 1e-300),
            None
        );
        let tau = total * r.range(0.01, 0.99);
        let t = density
            .distance_at_optical_depth(&line, t0, t1, tau)
            .unwrap_or_else(|| panic!("{density:?} {line:?} [{t0}, {t1}] tau {tau} of {total}"));
        let reference = bisect(&density, &line, t0, t1, tau);
        let error = (t - reference).abs() / (t1 - t0);
        worst[i % 3] = worst[i % 3].max(error);
        assert!(
            error < 1e-9,
            "{density:?} {line:?} [{t0}, {t1}]: {t} vs {reference}"
        );
    }
    println!(
        "inverse vs bisection: worst error / segment length: constant {:.3e}, linear {:.3e}, exponential {:.3e}",
        worst[0], worst[1], worst[2]
    );
}

/// Infinite segments: the finite limits against quadrature over a long stretch plus the
/// analytic tail.
#[test]
fn depths_to_infinity_are_the_limits() {
    let up = Line {
        origin: DVec3::new(0.0, 0.0, 0.0),
        direction: DVec3::new(0.6, 0.8, 0.0),
    };
    let fog = exponential(0.3, 1.0, 0.5);
    // sigma e^{falloff height} / (falloff * w.y)
    let expected = 0.3 * 0.5f64.exp() / (0.5 * 0.8);
    let tau = fog.optical_depth(&up, 0.0, f64::INFINITY);
    assert!(
        (tau - expected).abs() <= 1e-15 * expected,
        "{tau} {expected}"
    );
    let plane = linear(0.5, [0.0, 1.0, 0.0, -2.0]);
    // Leaves the fog at t = 2.5: 0.5 * 2.5 * (2 + 0) / 2.
    assert!((plane.optical_depth(&up, 0.0, f64::INFINITY) - 1.25).abs() < 1e-15);
}
