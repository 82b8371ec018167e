//! Exact conversions of seed 004's curved surfaces to the bicubic Bezier basis.
//!
//! Every surface here is a tensor product of cubic (or lower) polynomials, so one 4x4 matrix
//! `M` per basis turns a curve's four control values into its four Bezier control values,
//! and a patch's 4x4 grid `G` (rows along v, u fastest) into `M G M^T`. Conversions run in
//! f64 and round once to f32 at the end.
//!
//! - Bezier of degree `(m, n)` with `m, n <= 3` (seed 004, "Rectangular Bezier Patches":
//!   the degrees may differ per direction): degree elevation, `Q_i = i/(d+1) P_(i-1) +
//!   (1 - i/(d+1)) P_i`, repeated up to 3.
//! - Cubic Hermite rectangles (seed 004, "Cubic Hermite Rectangles"): per row, the curve
//!   through `p1` and `p2` with slopes `(p2 - p0) / 2` and `(p3 - p1) / 2` (the seed's
//!   `CubicHermite` polynomial `a t^3 + b t^2 + c t + d`). Its Bezier points are
//!   `p1, p1 + (p2 - p0) / 6, p2 - (p3 - p1) / 6, p2` (a cubic's inner Bezier points sit a
//!   third of the end slopes from its ends). The seed's listing interpolates its third row
//!   twice (`uValues[3]` reads `p[2]`); here every row is used, as its text describes.
//! - Lagrange rectangles (seed 004, "Lagrange Rectangles", there biquadratic): here the
//!   bicubic interpolant through a 4x4 grid at parameters `0, 1/3, 2/3, 1`. With
//!   `B(t_k)` the Bernstein matrix at those nodes, the Bezier points are `B^-1 p`:
//!   `p0, (-5 p0 + 18 p1 - 9 p2 + 2 p3) / 6, (2 p0 - 9 p1 + 18 p2 - 5 p3) / 6, p3`.
//! - Cubic Bezier triangles (seed 004's Bezier triangle, 10 control points): substituting
//!   barycentrics `a = u (1 - v)`, `b = u v`, `c = 1 - u` makes every term
//!   `a^i b^j c^k` (`i + j + k = 3`) a polynomial of degree 3 in u and at most 3 in v, so
//!   the triangle is exactly a bicubic patch whose edge `u = 0` collapses onto the corner
//!   `c = 1`. Its Bezier points follow from sampling it on the 4x4 Lagrange grid.

use glam::{DVec3, Vec3};

/// A 4x4 change of basis applied to rows and to columns: `M G M^T`.
fn tensor_convert(grid: &[DVec3; 16], m: &[[f64; 4]; 4]) -> [DVec3; 16] {
    let mut rows = [DVec3::ZERO; 16];
    for j in 0..4 {
        for i in 0..4 {
            rows[4 * j + i] = (0..4).map(|k| grid[4 * j + k] * m[i][k]).sum();
        }
    }
    let mut out = [DVec3::ZERO; 16];
    for j in 0..4 {
        for i in 0..4 {
            out[4 * j + i] = (0..4).map(|k| rows[4 * k + i] * m[j][k]).sum();
        }
    }
    out
}

fn to_f32(points: [DVec3; 16]) -> [Vec3; 16] {
    points.map(|p| p.as_vec3())
}

fn to_f64(points: &[Vec3; 16]) -> [DVec3; 16] {
    points.map(|p| p.as_dvec3())
}

/// Cubic Hermite (Catmull-Rom form) values `p0..p3` to Bezier control values.
const HERMITE_TO_BEZIER: [[f64; 4]; 4] = [
    [0.0, 1.0, 0.0, 0.0],
    [-1.0 / 6.0, 1.0, 1.0 / 6.0, 0.0],
    [0.0, 1.0 / 6.0, 1.0, -1.0 / 6.0],
    [0.0, 0.0, 1.0, 0.0],
];

/// Values at `t = 0, 1/3, 2/3, 1` to the Bezier control values of the cubic through them.
const LAGRANGE_TO_BEZIER: [[f64; 4]; 4] = [
    [1.0, 0.0, 0.0, 0.0],
    [-5.0 / 6.0, 3.0, -1.5, 1.0 / 3.0],
    [1.0 / 3.0, -1.5, 3.0, -5.0 / 6.0],
    [0.0, 0.0, 0.0, 1.0],
];

/// A cubic Hermite rectangle's 4x4 grid (rows along v, u fastest) as a Bezier patch.
pub fn hermite_to_bezier(grid: &[Vec3; 16]) -> [Vec3; 16] {
    to_f32(tensor_convert(&to_f64(grid), &HERMITE_TO_BEZIER))
}

/// A bicubic Lagrange rectangle's 4x4 grid (interpolated at u, v = 0, 1/3, 2/3, 1) as a
/// Bezier patch.
pub fn lagrange_to_bezier(grid: &[Vec3; 16]) -> [Vec3; 16] {
    to_f32(tensor_convert(&to_f64(grid), &LAGRANGE_TO_BEZIER))
}

/// A Bezier curve of degree `points.len() - 1` (at most 3) elevated to degree 3.
fn elevate_curve(points: &[DVec3]) -> [DVec3; 4] {
    let mut current: Vec<DVec3> = points.to_vec();
    while current.len() < 4 {
        let d = current.len() as f64; // new degree = old degree + 1 = len
        let mut next = Vec::with_capacity(current.len() + 1);
        next.push(current[0]);
        for i in 1..current.len() {
            let a = i as f64 / d;
            next.push(current[i - 1] * a + current[i] * (1.0 - a));
        }
        next.push(current[current.len() - 1]);
        current = next;
    }
    [current[0], current[1], current[2], current[3]]
}

/// A Bezier patch of degree `(degree_u, degree_v)` (each 1 to 3) with
/// `(degree_u + 1) (degree_v + 1)` control points, row by row with u fastest, elevated
/// exactly to bicubic. `None` if the degrees or the count are wrong.
pub fn elevate_to_bicubic(degree_u: usize, degree_v: usize, points: &[Vec3]) -> Option<[Vec3; 16]> {
    if !(1..=3).contains(&degree_u) || !(1..=3).contains(&degree_v) {
        return None;
    }
    let (nu, nv) = (degree_u + 1, degree_v + 1);
    if points.len() != nu * nv {
        return None;
    }
    let rows: Vec<[DVec3; 4]> = (0..nv)
        .map(|j| {
            let row: Vec<DVec3> = points[j * nu..(j + 1) * nu]
                .iter()
                .map(|p| p.as_dvec3())
                .collect();
            elevate_curve(&row)
        })
        .collect();
    let mut out = [DVec3::ZERO; 16];
    for i in 0..4 {
        let column: Vec<DVec3> = rows.iter().map(|r| r[i]).collect();
        let column = elevate_curve(&column);
        for j in 0..4 {
            out[4 * j + i] = column[j];
        }
    }
    Some(to_f32(out))
}

/// The index of the control point `P_ijk` (`a^i b^j c^k`, `i + j + k = 3`) of a cubic Bezier
/// triangle in the order scenes list them: rows of increasing `j`, and within a row
/// increasing `i` (row 0 runs along the edge `b = 0` from the corner `c = 1` to `a = 1`).
pub fn triangle_index(i: usize, j: usize) -> usize {
    // Rows 0..j hold 4 + 3 + ... points: j (9 - j) / 2 of them.
    j * (9 - j) / 2 + i
}

/// The cubic Bezier triangle with control points `control` (see [`triangle_index`]) at
/// barycentrics `(a, b)`, `c = 1 - a - b`.
pub fn triangle_point(control: &[Vec3; 10], a: f64, b: f64) -> DVec3 {
    let c = 1.0 - a - b;
    let factorial = [1.0, 1.0, 2.0, 6.0];
    let mut sum = DVec3::ZERO;
    for j in 0..=3 {
        for i in 0..=3 - j {
            let k = 3 - i - j;
            let weight = 6.0 / (factorial[i] * factorial[j] * factorial[k])
                * a.powi(i as i32)
                * b.powi(j as i32)
                * c.powi(k as i32);
            sum += control[triangle_index(i, j)].as_dvec3() * weight;
        }
    }
    sum
}

/// The bicubic patch parameters `(u, v)` of barycentrics `(a, b)` on a converted triangle.
pub fn triangle_to_patch_parameters(a: f64, b: f64) -> (f64, f64) {
    let u = a + b;
    let v = if u > 0.0 { b / u } else { 0.0 };
    (u, v)
}

/// A cubic Bezier triangle as a bicubic Bezier patch with its edge `u = 0` collapsed onto
/// the corner `c = 1`: `a = u (1 - v)`, `b = u v`.
pub fn triangle_to_bezier(control: &[Vec3; 10]) -> [Vec3; 16] {
    let mut samples = [DVec3::ZERO; 16];
    for j in 0..4 {
        for i in 0..4 {
            let (u, v) = (i as f64 / 3.0, j as f64 / 3.0);
            samples[4 * j + i] = triangle_point(control, u * (1.0 - v), u * v);
        }
    }
    to_f32(tensor_convert(&samples, &LAGRANGE_TO_BEZIER))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::patch::{control_f64, evaluate};
    use crate::test_rng::{unit_f64, xorshift64};

    /// A small deterministic generator (xorshift) for random grids and parameters.
    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> f64 {
            unit_f64(xorshift64(&mut self.0))
        }
        fn point(&mut self) -> Vec3 {
            Vec3::new(self.next() as f32, self.next() as f32, self.next() as f32) * 4.0 - 2.0
        }
    }

    /// The seed's cubic Hermite polynomial through p1, p2 with slopes from p0, p3.
    fn cubic_hermite(p: [DVec3; 4], t: f64) -> DVec3 {
        let a = -p[0] / 2.0 + p[1] * 1.5 - p[2] * 1.5 + p[3] / 2.0;
        let b = p[0] - p[1] * 2.5 + p[2] * 2.0 - p[3] / 2.0;
        let c = -p[0] / 2.0 + p[2] / 2.0;
        a * t * t * t + b * t * t + c * t + p[1]
    }

    fn lagrange(p: [DVec3; 4], t: f64) -> DVec3 {
        let nodes = [0.0, 1.0 / 3.0, 2.0 / 3.0, 1.0];
        (0..4)
            .map(|k| {
                let w: f64 = (0..4)
                    .filter(|&m| m != k)
                    .map(|m| (t - nodes[m]) / (nodes[k] - nodes[m]))
                    .product();
                p[k] * w
            })
            .sum()
    }

    fn tensor(grid: &[Vec3; 16], u: f64, v: f64, curve: fn([DVec3; 4], f64) -> DVec3) -> DVec3 {
        let rows: Vec<DVec3> = (0..4)
            .map(|j| {
                let r = [0, 1, 2, 3].map(|i| grid[4 * j + i].as_dvec3());
                curve(r, u)
            })
            .collect();
        curve([rows[0], rows[1], rows[2], rows[3]], v)
    }

    #[test]
    fn hermite_and_lagrange_surfaces_are_unchanged_at_random_parameters() {
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
        let mut worst: f64 = 0.0;
        for _ in 0..50 {
            let grid: [Vec3; 16] = std::array::from_fn(|_| rng.point());
            let hermite = control_f64(&hermite_to_bezier(&grid));
            let lagrange_patch = control_f64(&lagrange_to_bezier(&grid));
            for _ in 0..20 {
                let (u, v) = (rng.next(), rng.next());
                let h = (evaluate(&hermite, u, v).position - tensor(&grid, u, v, cubic_hermite))
                    .length();
                let l = (evaluate(&lagrange_patch, u, v).position - tensor(&grid, u, v, lagrange))
                    .length();
                worst = worst.max(h).max(l);
            }
        }
        // Only the final rounding of the control points to f32 separates them.
        assert!(worst < 1e-5, "largest difference {worst}");
    }

    #[test]
    fn hermite_patches_pass_through_the_inner_points() {
        let mut rng = Rng(7);
        let grid: [Vec3; 16] = std::array::from_fn(|_| rng.point());
        let c = control_f64(&hermite_to_bezier(&grid));
        for (u, v, k) in [(0.0, 0.0, 5), (1.0, 0.0, 6), (0.0, 1.0, 9), (1.0, 1.0, 10)] {
            assert!((evaluate(&c, u, v).position - grid[k].as_dvec3()).length() < 1e-5);
        }
    }

    #[test]
    fn lower_degrees_are_elevated_exactly() {
        let mut rng = Rng(99);
        for (du, dv) in [(1, 1), (2, 2), (1, 3), (3, 2), (3, 3)] {
            let points: Vec<Vec3> = (0..(du + 1) * (dv + 1)).map(|_| rng.point()).collect();
            let c = control_f64(&elevate_to_bicubic(du, dv, &points).unwrap());
            let bern = |d: usize, i: usize, t: f64| {
                let binom = [
                    [1.0, 0.0, 0.0, 0.0],
                    [1.0, 1.0, 0.0, 0.0],
                    [1.0, 2.0, 1.0, 0.0],
                    [1.0, 3.0, 3.0, 1.0],
                ];
                binom[d][i] * t.powi(i as i32) * (1.0 - t).powi((d - i) as i32)
            };
            for _ in 0..10 {
                let (u, v) = (rng.next(), rng.next());
                let mut direct = DVec3::ZERO;
                for j in 0..=dv {
                    for i in 0..=du {
                        direct +=
                            points[j * (du + 1) + i].as_dvec3() * (bern(du, i, u) * bern(dv, j, v));
                    }
                }
                let d = (evaluate(&c, u, v).position - direct).length();
                assert!(d < 1e-5, "degree ({du}, {dv}): {d}");
            }
        }
        assert!(elevate_to_bicubic(3, 3, &[Vec3::ZERO; 15]).is_none());
        assert!(elevate_to_bicubic(4, 1, &[Vec3::ZERO; 10]).is_none());
    }

    #[test]
    fn triangles_become_collapsed_patches_with_the_same_points() {
        let mut rng = Rng(1234);
        let control: [Vec3; 10] = std::array::from_fn(|_| rng.point());
        let c = control_f64(&triangle_to_bezier(&control));
        for _ in 0..50 {
            let (mut a, mut b) = (rng.next(), rng.next());
            if a + b > 1.0 {
                (a, b) = (1.0 - a, 1.0 - b);
            }
            let (u, v) = triangle_to_patch_parameters(a, b);
            let d = (evaluate(&c, u, v).position - triangle_point(&control, a, b)).length();
            assert!(d < 1e-5, "{d} at ({a}, {b})");
        }
        // The corners: c = 1 at u = 0, a = 1 at (1, 0), b = 1 at (1, 1).
        let corner = |u, v| evaluate(&c, u, v).position;
        assert!((corner(0.0, 0.5) - control[triangle_index(0, 0)].as_dvec3()).length() < 1e-5);
        assert!((corner(1.0, 0.0) - control[triangle_index(3, 0)].as_dvec3()).length() < 1e-5);
        assert!((corner(1.0, 1.0) - control[triangle_index(0, 3)].as_dvec3()).length() < 1e-5);
    }
}
