//! Triangulating a planar polygon face (an OBJ `f` with more than three vertices) by ear
//! clipping, so that concave faces are covered exactly: a fan from the first vertex, which
//! is right only for convex faces, covers area outside a concave one.
//!
//! The polygon is projected onto the coordinate plane most nearly parallel to it (dropping
//! the largest component of its Newell normal) and oriented counter-clockwise there. An ear
//! is three consecutive corners forming a convex corner with no other corner inside or on
//! the triangle; cutting ears one at a time leaves `n - 2` triangles that tile the polygon
//! (the two-ears theorem: every simple polygon with more than three corners has two). The
//! triangles keep the face's winding, so their normals agree with the face's. A face that is
//! not simple (self-intersecting) or degenerate may run out of ears; its remaining corners
//! are then fanned, as before.

use glam::{DVec2, DVec3, Vec3};

/// The triangles of the polygon whose corners are `positions[face[k]]`, in the face's
/// winding.
pub(crate) fn triangulate(positions: &[Vec3], face: &[u32]) -> Vec<[u32; 3]> {
    let n = face.len();
    if n < 3 {
        return Vec::new();
    }
    let fan = |corners: &[u32]| -> Vec<[u32; 3]> {
        (1..corners.len() - 1)
            .map(|k| [corners[0], corners[k], corners[k + 1]])
            .collect()
    };
    if n == 3 {
        return fan(face);
    }
    let point = |index: u32| positions[index as usize].as_dvec3();
    // Newell's normal: twice the vector area of the polygon.
    let normal: DVec3 = (0..n)
        .map(|k| point(face[k]).cross(point(face[(k + 1) % n])))
        .sum();
    let axis = normal.abs().max_element();
    if !(axis.is_finite() && axis > 0.0) {
        return fan(face);
    }
    // Drop the dominant axis; swap the two kept ones when that flips the orientation, so the
    // projected polygon is counter-clockwise.
    let (a, b, sign) = if normal.x.abs() == axis {
        (1, 2, normal.x)
    } else if normal.y.abs() == axis {
        (2, 0, normal.y)
    } else {
        (0, 1, normal.z)
    };
    let flat: Vec<DVec2> = face
        .iter()
        .map(|&i| {
            let p = point(i);
            if sign > 0.0 {
                DVec2::new(p[a], p[b])
            } else {
                DVec2::new(p[b], p[a])
            }
        })
        .collect();
    let cross = |o: DVec2, p: DVec2, q: DVec2| (p - o).perp_dot(q - o);

    // Corners still to cut, as indices into `face`.
    let mut remaining: Vec<usize> = (0..n).collect();
    let mut triangles = Vec::with_capacity(n - 2);
    let mut misses = 0;
    // Starting at the second corner, a convex face is cut into the fan from its first corner
    // (ears (0 1 2), (0 2 3), ...): convex faces triangulate as they always did.
    let mut k = 1;
    while remaining.len() > 3 {
        let m = remaining.len();
        let (previous, current, next) = (
            remaining[(k + m - 1) % m],
            remaining[k % m],
            remaining[(k + 1) % m],
        );
        let (p, c, q) = (flat[previous], flat[current], flat[next]);
        let convex = cross(p, c, q) > 0.0;
        let is_ear = convex
            && remaining.iter().all(|&other| {
                if other == previous || other == current || other == next {
                    return true;
                }
                let x = flat[other];
                // Strictly outside at least one edge.
                cross(p, c, x) < 0.0 || cross(c, q, x) < 0.0 || cross(q, p, x) < 0.0
            });
        if is_ear {
            triangles.push([face[previous], face[current], face[next]]);
            remaining.remove(k % m);
            misses = 0;
            k %= remaining.len();
        } else {
            misses += 1;
            k = (k + 1) % m;
            if misses >= m {
                // No ear: not a simple polygon. Fan what is left.
                let rest: Vec<u32> = remaining.iter().map(|&r| face[r]).collect();
                triangles.extend(fan(&rest));
                return triangles;
            }
        }
    }
    triangles.push([face[remaining[0]], face[remaining[1]], face[remaining[2]]]);
    triangles
}

#[cfg(test)]
mod tests {
    use super::*;

    fn area(positions: &[Vec3], triangles: &[[u32; 3]]) -> (f32, Vec3) {
        let mut total = 0.0;
        let mut normal = Vec3::ZERO;
        for t in triangles {
            let [a, b, c] = t.map(|i| positions[i as usize]);
            let n = (b - a).cross(c - a);
            total += 0.5 * n.length();
            normal += n;
        }
        (total, normal)
    }

    /// A U shape (the notch is x in (-0.5, 0.5), y above -0.5): the triangles tile it, none
    /// covers the notch, and all face the polygon's way. A fan from the first corner covered
    /// part of the notch.
    #[test]
    fn a_concave_face_is_tiled_without_covering_its_notch() {
        let u = [
            (-1.0, -1.0),
            (1.0, -1.0),
            (1.0, 1.0),
            (0.5, 1.0),
            (0.5, -0.5),
            (-0.5, -0.5),
            (-0.5, 1.0),
            (-1.0, 1.0),
        ];
        for (plane, flip) in [(0, false), (1, true), (2, false)] {
            let positions: Vec<Vec3> = u
                .iter()
                .map(|&(x, y)| match plane {
                    0 => Vec3::new(x, y, 0.0),
                    1 => Vec3::new(y, 0.0, x),
                    _ => Vec3::new(0.0, x, y),
                })
                .collect();
            let mut face: Vec<u32> = (0..8).collect();
            if flip {
                face.reverse();
            }
            let triangles = triangulate(&positions, &face);
            assert_eq!(triangles.len(), 6);
            let (total, normal) = area(&positions, &triangles);
            // 4 - 1 x 1.5 of notch.
            assert!((total - 2.5).abs() < 1e-5, "area {total}");
            // Every triangle faces the polygon's way: their areas add up as vectors too.
            assert!((normal.length() / 2.0 - total).abs() < 1e-5);
            // The notch's middle is in none of them.
            let notch = positions[5].lerp(positions[3], 0.5);
            for t in &triangles {
                let [a, b, c] = t.map(|i| positions[i as usize]);
                let n = (b - a).cross(c - a);
                let inside = [(a, b), (b, c), (c, a)]
                    .iter()
                    .all(|&(p, q)| (q - p).cross(notch - p).dot(n) > 0.0);
                assert!(!inside, "{t:?} covers the notch");
            }
        }
    }

    #[test]
    fn convex_and_degenerate_faces_still_triangulate() {
        let square = [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y];
        let triangles = triangulate(&square, &[0, 1, 2, 3]);
        // The fan from the first corner, as convex faces were always cut.
        assert_eq!(triangles, [[0, 1, 2], [0, 2, 3]]);
        assert!((area(&square, &triangles).0 - 1.0).abs() < 1e-6);
        // All corners on one line: no area, still n - 2 triangles (fanned).
        let line = [Vec3::ZERO, Vec3::X, Vec3::X * 2.0, Vec3::X * 3.0];
        assert_eq!(triangulate(&line, &[0, 1, 2, 3]).len(), 2);
    }
}
