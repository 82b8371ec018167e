//! Tessellation of patches into triangles: the fast alternative to exact tracing (seed 004,
//! "One way is to tessellate it").
//!
//! Each patch gets its own regular grid of `n_u x n_v` quads (two triangles each), as fine as
//! its second derivatives require for a world-space error bound `epsilon`: linear
//! interpolation over a cell of size `h_u x h_v` is within
//! `(h_u^2 max|P_uu| + 2 h_u h_v max|P_uv| + h_v^2 max|P_vv|) / 8` of the surface (the
//! remainder of the first-order Taylor expansion, e.g. de Boor, "A Practical Guide to
//! Splines", ch. 2). The maxima are bounded by the control points: `P_uu` is a Bezier patch
//! with control points `6 (P_(i+2)j - 2 P_(i+1)j + P_ij)`, `P_uv` one with
//! `9 (P_(i+1)(j+1) - P_(i+1)j - P_i(j+1) + P_ij)`, and a Bezier patch is bounded by its
//! largest control point. Each of the three terms is held to `epsilon / 3`. Flat directions
//! get one cell; a direction never gets more than [`MAX_CELLS`].
//!
//! Texture coordinates count too. Bilinear corner `st` (`BezierPatch::corner_st`) have the
//! constant twist `T = st_00 - st_10 - st_01 + st_11`, and linear interpolation over a cell's
//! two triangles is within `h_u h_v |T| / 4` of them. Times the patch's world size per
//! texture unit `W` (its bounding-box diagonal over its `st` diagonal), that is how far the
//! texture slides on the surface; it shares the mixed term's `epsilon / 3`. Without it a flat
//! patch got one cell and its texture a visible seam along the diagonal.
//!
//! Vertices carry the patch's exact unit normal (as shading normals) and texture
//! coordinates; triangles that collapse to zero area at a collapsed edge are dropped.

use glam::{DVec3, Vec3};

use super::intersect::geometric_normal;
use super::{control_f64, evaluate, BezierPatch};
use crate::scene::TriangleMesh;

/// Most cells per direction of one patch.
pub const MAX_CELLS: usize = 512;

/// What tessellating a scene's patches produced.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TessellationReport {
    pub patches: usize,
    pub triangles: usize,
    pub seconds: f64,
}

/// Cells `(n_u, n_v)` that keep `patch`'s linear interpolation within `epsilon`.
pub fn cells_for(patch: &BezierPatch, epsilon: f32) -> (usize, usize) {
    let c = control_f64(&patch.control);
    let at = |i: usize, j: usize| c[4 * j + i];
    let mut uu: f64 = 0.0;
    let mut vv: f64 = 0.0;
    let mut uv: f64 = 0.0;
    for j in 0..4 {
        for i in 0..2 {
            uu = uu.max(6.0 * (at(i + 2, j) - 2.0 * at(i + 1, j) + at(i, j)).length());
            vv = vv.max(6.0 * (at(j, i + 2) - 2.0 * at(j, i + 1) + at(j, i)).length());
        }
    }
    for j in 0..3 {
        for i in 0..3 {
            uv = uv.max(9.0 * (at(i + 1, j + 1) - at(i + 1, j) - at(i, j + 1) + at(i, j)).length());
        }
    }
    let texture = texture_twist_in_world(patch);
    let budget = f64::from(epsilon.max(f32::MIN_POSITIVE)) / 3.0;
    // h^2 M / 8 <= budget  <=>  n >= sqrt(M / (8 budget)).
    let cells = |m: f64| ((m / (8.0 * budget)).sqrt().ceil() as usize).clamp(1, MAX_CELLS);
    let (mut nu, mut nv) = (cells(uu), cells(vv));
    // The mixed term and the texture's slide: (2 uv / 8 + T W / 4) / (nu nv) <= budget.
    let mixed = (2.0 * uv / 8.0 + texture / 4.0) / budget;
    while ((nu * nv) as f64) < mixed && (nu < MAX_CELLS || nv < MAX_CELLS) {
        if nu <= nv && nu < MAX_CELLS {
            nu += 1;
        } else {
            nv = (nv + 1).min(MAX_CELLS);
        }
    }
    (nu, nv)
}

/// `|T| W` of the module doc: the twist of `patch`'s bilinear texture coordinates in world
/// units (0 without corner `st`, or when they have no twist).
fn texture_twist_in_world(patch: &BezierPatch) -> f64 {
    let Some(corners) = patch.corner_st else {
        return 0.0;
    };
    let [a, b, c, d] = corners.map(|st| st.as_dvec2());
    let twist = (a - b - c + d).length();
    let st_low = a.min(b).min(c.min(d));
    let st_high = a.max(b).max(c.max(d));
    let st_size = (st_high - st_low).length();
    if !(twist > 0.0 && st_size > 0.0) {
        return 0.0;
    }
    let (low, high) = patch.bounds();
    let world_size = (high.as_dvec3() - low.as_dvec3()).length();
    twist * world_size / st_size
}

/// `patch` as a triangle mesh within `epsilon` of it (see the module doc).
pub fn tessellate(patch: &BezierPatch, epsilon: f32) -> TriangleMesh {
    let (nu, nv) = cells_for(patch, epsilon);
    let c = control_f64(&patch.control);
    let mut mesh = TriangleMesh {
        name: "tessellated patch".to_string(),
        material: patch.material,
        ..TriangleMesh::default()
    };
    for j in 0..=nv {
        for i in 0..=nu {
            let (u, v) = (i as f64 / nu as f64, j as f64 / nv as f64);
            mesh.positions.push(evaluate(&c, u, v).position.as_vec3());
            let n = geometric_normal(&c, u, v)
                .try_normalize()
                .unwrap_or(DVec3::Z);
            mesh.normals.push(n.as_vec3());
            mesh.st.push(patch.st(u as f32, v as f32).0);
        }
    }
    let index = |i: usize, j: usize| (j * (nu + 1) + i) as u32;
    // A triangle at a collapsed edge has two corners a rounding apart: drop it when its
    // area is negligible against its longest edge.
    let proper = |t: [u32; 3], p: &[Vec3]| {
        let [a, b, c] = t.map(|k| p[k as usize]);
        let longest = (b - a)
            .length_squared()
            .max((c - a).length_squared())
            .max((c - b).length_squared());
        (b - a).cross(c - a).length() > 1e-7 * longest
    };
    for j in 0..nv {
        for i in 0..nu {
            for t in [
                [index(i, j), index(i + 1, j), index(i + 1, j + 1)],
                [index(i, j), index(i + 1, j + 1), index(i, j + 1)],
            ] {
                if proper(t, &mesh.positions) {
                    mesh.triangles.push(t);
                }
            }
        }
    }
    mesh
}

/// Replaces every patch of `patches` by its tessellation, appended to `meshes`.
pub fn tessellate_all(
    patches: &mut Vec<BezierPatch>,
    meshes: &mut Vec<TriangleMesh>,
    epsilon: f32,
) -> TessellationReport {
    let started = std::time::Instant::now();
    let mut report = TessellationReport {
        patches: patches.len(),
        ..TessellationReport::default()
    };
    for patch in patches.drain(..) {
        let mesh = tessellate(&patch, epsilon);
        report.triangles += mesh.triangles.len();
        meshes.push(mesh);
    }
    report.seconds = started.elapsed().as_secs_f64();
    report
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec2;

    fn dome() -> BezierPatch {
        let mut control = [Vec3::ZERO; 16];
        for j in 0..4 {
            for i in 0..4 {
                let (x, y) = (i as f32 - 1.5, j as f32 - 1.5);
                control[4 * j + i] = Vec3::new(x, y, 2.0 - 0.4 * (x * x + y * y));
            }
        }
        BezierPatch {
            control,
            corner_st: Some([Vec2::ZERO, Vec2::X, Vec2::Y, Vec2::ONE]),
            material: 0,
        }
    }

    /// Distance from a point of the patch to the tessellation's triangle over it, and the
    /// slide of its texture (texture-coordinate error times world size per texture unit), at
    /// many (u, v): never above the bound.
    #[test]
    fn the_error_bound_holds() {
        assert_error_bound_holds(&dome());
    }

    /// A flat patch whose corner texture coordinates twist (st = (3, 3) at u = v = 1): it
    /// used to get one cell, its texture off by 0.5 texture units along the diagonal.
    #[test]
    fn twisted_texture_coordinates_are_tessellated_within_the_bound() {
        let mut flat = dome();
        for p in &mut flat.control {
            p.z = 0.0;
        }
        flat.corner_st = Some([Vec2::ZERO, Vec2::X, Vec2::Y, Vec2::splat(3.0)]);
        assert!(cells_for(&flat, 1e-3) != (1, 1));
        assert_error_bound_holds(&flat);
    }

    fn assert_error_bound_holds(patch: &BezierPatch) {
        let c = control_f64(&patch.control);
        let world_per_texture = {
            let twist = texture_twist_in_world(patch);
            let [a, b, c, d] = patch.corner_st.unwrap().map(|st| st.as_dvec2());
            let raw = (a - b - c + d).length();
            if raw > 0.0 {
                twist / raw
            } else {
                0.0
            }
        };
        for epsilon in [1e-1f32, 1e-2, 1e-3] {
            let (nu, nv) = cells_for(patch, epsilon);
            let mesh = tessellate(patch, epsilon);
            let (mut worst, mut worst_slide): (f64, f64) = (0.0, 0.0);
            for a in 0..=97 {
                for b in 0..=89 {
                    let (u, v) = (a as f64 / 97.0, b as f64 / 89.0);
                    let exact = evaluate(&c, u, v).position;
                    // The cell and the barycentrics of (u, v) in its triangle.
                    let (fu, fv) = (u * nu as f64, v * nv as f64);
                    let (i, j) = ((fu as usize).min(nu - 1), (fv as usize).min(nv - 1));
                    let (s, t) = (fu - i as f64, fv - j as f64);
                    let weights = if s >= t {
                        [((i, j), 1.0 - s), ((i + 1, j), s - t), ((i + 1, j + 1), t)]
                    } else {
                        [((i, j), 1.0 - t), ((i + 1, j + 1), s), ((i, j + 1), t - s)]
                    };
                    let at = |(i, j): (usize, usize)| j * (nu + 1) + i;
                    let approx: DVec3 = weights
                        .iter()
                        .map(|&(k, w)| mesh.positions[at(k)].as_dvec3() * w)
                        .sum();
                    worst = worst.max((exact - approx).length());
                    let approx_st: glam::DVec2 = weights
                        .iter()
                        .map(|&(k, w)| mesh.st[at(k)].as_dvec2() * w)
                        .sum();
                    let exact_st = patch.st(u as f32, v as f32).0.as_dvec2();
                    worst_slide =
                        worst_slide.max((exact_st - approx_st).length() * world_per_texture);
                }
            }
            assert!(
                worst <= f64::from(epsilon),
                "epsilon {epsilon}: {worst} with {nu}x{nv}"
            );
            assert!(
                worst_slide <= f64::from(epsilon),
                "epsilon {epsilon}: the texture slides {worst_slide} with {nu}x{nv}"
            );
            assert_eq!(mesh.triangles.len(), 2 * nu * nv);
        }
    }

    #[test]
    fn flat_patches_need_one_cell_and_collapsed_edges_drop_slivers() {
        let mut flat = dome();
        for p in &mut flat.control {
            p.z = 0.0;
        }
        assert_eq!(cells_for(&flat, 1e-3), (1, 1));
        let mut fan = dome();
        for i in 0..4 {
            fan.control[i] = Vec3::new(0.0, -1.5, 2.0); // row v = 0 collapses
        }
        let mesh = tessellate(&fan, 1e-2);
        let (nu, nv) = cells_for(&fan, 1e-2);
        assert_eq!(mesh.triangles.len(), 2 * nu * nv - nu);
        assert!(mesh
            .normals
            .iter()
            .all(|n| n.is_finite() && (n.length() - 1.0).abs() < 1e-4));
    }
}
