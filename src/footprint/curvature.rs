//! Surface curvature seen by a ray cone at a hit (seed 000, "Computing Curvature").
//!
//! Curvature is the deflection of the unit normal per unit distance along the surface:
//! positive where the surface bulges towards the side the normals point to (the outside of a
//! sphere), negative where it is hollow. A ray arriving from the other side of the surface
//! (inside a sphere, the back of a mesh) sees the opposite sign, which is what makes a
//! concave mirror focus a cone.

use glam::Vec3;

use crate::hit::{Patch, SurfaceHit};

/// Curvature of a triangle from its vertex normals: the minimum-magnitude edge curvature
/// `k_ab = (N_b - N_a).(B - A) / (B - A).(B - A)`, or 0 when the edge curvatures have mixed
/// signs (seed 000). Vertex normals are normalised first; a degenerate edge, a zero or
/// non-finite normal gives 0 (flat).
pub fn triangle_curvature(p: [Vec3; 3], n: [Vec3; 3]) -> f32 {
    let mut unit = [Vec3::ZERO; 3];
    for (u, v) in unit.iter_mut().zip(n.iter()) {
        let len2 = v.length_squared();
        if !(len2.is_finite() && len2 > 1.0e-30) {
            return 0.0;
        }
        *u = *v * len2.sqrt().recip();
    }
    let mut k = [0.0f32; 3];
    for (i, ki) in k.iter_mut().enumerate() {
        let j = (i + 1) % 3;
        let edge = p[j] - p[i];
        let len2 = edge.length_squared();
        if !(len2.is_finite() && len2 > 1.0e-30) {
            return 0.0;
        }
        *ki = (unit[j] - unit[i]).dot(edge) / len2;
        if !ki.is_finite() {
            return 0.0;
        }
    }
    let all_positive = k.iter().all(|&x| x >= 0.0);
    let all_negative = k.iter().all(|&x| x <= 0.0);
    if !(all_positive || all_negative) {
        return 0.0;
    }
    let mut best = k[0];
    for &x in &k[1..] {
        if x.abs() < best.abs() {
            best = x;
        }
    }
    best
}

/// Curvature of a sphere of `radius` seen from outside: 1/r (0 for a degenerate radius).
#[inline]
pub fn sphere_curvature(radius: f32) -> f32 {
    let k = radius.abs().recip();
    if k.is_finite() {
        k
    } else {
        0.0
    }
}

/// Curvature at `hit` for a ray travelling along `dir`, signed for the side the ray arrives
/// from: a ray hitting the back of the surface (inside a sphere) sees the negated curvature.
/// Triangles without vertex normals are flat.
#[inline]
pub fn curvature_at(hit: &SurfaceHit, dir: Vec3) -> f32 {
    let k = match &hit.patch {
        Patch::Triangle { p, n: Some(n), .. } => triangle_curvature(*p, *n),
        Patch::Triangle { n: None, .. } => 0.0,
        Patch::Sphere { radius, .. } => sphere_curvature(*radius),
        Patch::Curved { frame, .. } => {
            // Signed for P_u x P_v; the hit's geometric normal may be its opposite.
            let k = frame.cone_curvature();
            if frame.normal().dot(hit.geometric_normal) >= 0.0 {
                k
            } else {
                -k
            }
        }
    };
    if hit.is_front_face(dir) {
        k
    } else {
        -k
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn on_sphere(d: Vec3, r: f32) -> (Vec3, Vec3) {
        let n = d.normalize();
        (n * r, n)
    }

    #[test]
    fn triangle_on_a_sphere_has_curvature_close_to_inverse_radius() {
        let r = 2.0;
        let (a, na) = on_sphere(Vec3::new(0.0, 0.0, 1.0), r);
        let (b, nb) = on_sphere(Vec3::new(0.05, 0.0, 1.0), r);
        let (c, nc) = on_sphere(Vec3::new(0.0, 0.05, 1.0), r);
        let k = triangle_curvature([a, b, c], [na, nb, nc]);
        assert!((k - 0.5).abs() < 1e-2, "{k}");
        // Flipped normals (the inside of the sphere) give negative curvature.
        let k_in = triangle_curvature([a, b, c], [-na, -nb, -nc]);
        assert!((k_in + 0.5).abs() < 1e-2, "{k_in}");
    }

    #[test]
    fn mixed_signs_and_degenerate_input_are_flat() {
        // A saddle: normals tilt outwards along x, inwards along y.
        let p = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let n = [Vec3::Z, Vec3::new(0.1, 0.0, 1.0), Vec3::new(0.0, -0.1, 1.0)];
        assert_eq!(triangle_curvature(p, n), 0.0);
        let collapsed = [Vec3::ONE; 3];
        assert_eq!(triangle_curvature(collapsed, [Vec3::Z; 3]), 0.0);
        assert_eq!(triangle_curvature(p, [Vec3::ZERO, Vec3::Z, Vec3::Z]), 0.0);
        assert_eq!(
            triangle_curvature(p, [Vec3::splat(f32::NAN), Vec3::Z, Vec3::Z]),
            0.0
        );
        assert_eq!(triangle_curvature(p, [Vec3::Z; 3]), 0.0);
    }

    #[test]
    fn minimum_magnitude_edge_is_chosen() {
        let p = [Vec3::ZERO, Vec3::X, Vec3::Y];
        // Edge 0-1 bends by 0.2 per unit, edge 0-2 by 0.1, edge 1-2 by (0.1 + 0.2) / 2.
        let n = [Vec3::Z, Vec3::new(0.2, 0.0, 1.0), Vec3::new(0.0, 0.1, 1.0)];
        let k = triangle_curvature(p, n);
        assert!(k > 0.0 && k < 0.11, "{k}");
    }

    #[test]
    fn sphere_curvature_is_inverse_radius() {
        assert_eq!(sphere_curvature(4.0), 0.25);
        assert_eq!(sphere_curvature(0.0), 0.0);
    }
}
