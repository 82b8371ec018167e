//! Triangulating a planar polygon face (an OBJ `f` with more than three vertices) by ear
//! clipping, so that concave faces and faces with holes are covered exactly: a fan from the
//! first vertex, which is right only for convex faces, covers area outside a concave one.
//!
//! The polygon is projected onto the coordinate plane most nearly parallel to it (dropping
//! the largest component of its Newell normal) and oriented counter-clockwise there. An ear
//! is three consecutive corners forming a convex corner whose triangle lies inside the
//! polygon; cutting ears one at a time leaves triangles that tile the polygon (the two-ears
//! theorem: every simple polygon with more than three corners has two). The triangles keep
//! the face's winding, so their normals agree with the face's.
//!
//! A face with a hole is written as a weakly simple polygon: the outer ring and the hole's
//! ring joined by a zero-width slit (a bridge) walked once each way, so some corners repeat,
//! by index or only by position. The simple-polygon ear test (no other corner in or on the
//! triangle) finds no ear where the slit's repeated corners touch every candidate, so ears
//! are looked for in three passes, each used only when the previous finds none in a full
//! round: that test; then the test a weakly simple polygon needs, that no boundary edge
//! enters the triangle's interior (Eberly 2002, "Triangulation by Ear Clipping", section
//! "Polygons with a Hole": coincident bridge corners do not block an ear); then zero-area
//! corners (slit tips and collinear corners left behind) are dropped. A face none of this
//! cuts (self-intersecting) has its remaining corners fanned.

use glam::{DVec2, DVec3, Vec3};

/// Twice the signed area of the triangle (o, p, q): positive when counter-clockwise.
fn cross(o: DVec2, p: DVec2, q: DVec2) -> f64 {
    (p - o).perp_dot(q - o)
}

/// Whether some point of the segment from `x` to `y` lies strictly inside the
/// counter-clockwise triangle `corners`. Each edge's signed distance is linear along the
/// segment, so the points strictly left of all three edges form one interval of the
/// segment's parameter (Liang and Barsky 1984's clipping, with open half-planes). A segment
/// that only touches the triangle's boundary, such as a slit edge lying along one of its
/// sides or an edge leaving one of its corners outwards, does not enter it: corners shared
/// by position give exact zeros here.
fn segment_enters_triangle(x: DVec2, y: DVec2, corners: [DVec2; 3]) -> bool {
    // The parameter interval [low, high] of the segment, open at an end whose flag is set.
    let (mut low, mut high) = (0.0_f64, 1.0_f64);
    let (mut low_open, mut high_open) = (false, false);
    for side in 0..3 {
        let (a, b) = (corners[side], corners[(side + 1) % 3]);
        let (at_x, at_y) = (cross(a, b, x), cross(a, b, y));
        if at_x == at_y {
            if at_x <= 0.0 {
                return false;
            }
            continue;
        }
        // Where the segment crosses this edge's line.
        let root = at_x / (at_x - at_y);
        if at_y > at_x {
            if root > low || (root == low && !low_open) {
                (low, low_open) = (root, true);
            }
        } else if root < high || (root == high && !high_open) {
            (high, high_open) = (root, true);
        }
    }
    low < high || (low == high && !low_open && !high_open)
}

/// How an ear is recognised; each pass is tried when the one before finds no ear.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Pass {
    /// No other corner in or on the triangle (simple polygons).
    Simple,
    /// No boundary edge enters the triangle (corners may touch it).
    Touching,
    /// A corner in line with its neighbours: cut without a triangle.
    ZeroArea,
}

/// The triangles of the polygon whose corners are `positions[face[k]]`, in the face's
/// winding.
pub(crate) fn triangulate(positions: &[Vec3], face: &[u32]) -> Vec<[u32; 3]> {
    let n = face.len();
    if n < 3 {
        return Vec::new();
    }
    if n == 3 {
        return fan(face);
    }
    match projected(positions, face) {
        Some(flat) => clip_ears(&flat, face),
        None => fan(face),
    }
}

fn fan(corners: &[u32]) -> Vec<[u32; 3]> {
    (1..corners.len() - 1)
        .map(|k| [corners[0], corners[k], corners[k + 1]])
        .collect()
}

/// The face's corners in the coordinate plane most nearly parallel to it, oriented
/// counter-clockwise; `None` when the face has no area.
fn projected(positions: &[Vec3], face: &[u32]) -> Option<Vec<DVec2>> {
    let n = face.len();
    let point = |index: u32| positions[index as usize].as_dvec3();
    // Newell's normal: twice the vector area of the polygon.
    let normal: DVec3 = (0..n)
        .map(|k| point(face[k]).cross(point(face[(k + 1) % n])))
        .sum();
    let axis = normal.abs().max_element();
    if !(axis.is_finite() && axis > 0.0) {
        return None;
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
    Some(
        face.iter()
            .map(|&i| {
                let p = point(i);
                if sign > 0.0 {
                    DVec2::new(p[a], p[b])
                } else {
                    DVec2::new(p[b], p[a])
                }
            })
            .collect(),
    )
}

/// Whether the corner `remaining[k]` is an ear under `pass`.
fn is_ear(flat: &[DVec2], remaining: &[usize], k: usize, pass: Pass) -> bool {
    let m = remaining.len();
    let (previous, current, next) = (
        remaining[(k + m - 1) % m],
        remaining[k],
        remaining[(k + 1) % m],
    );
    let (p, c, q) = (flat[previous], flat[current], flat[next]);
    let area = cross(p, c, q);
    if pass == Pass::ZeroArea {
        return area == 0.0;
    }
    if area <= 0.0 {
        return false;
    }
    // Every other corner strictly outside at least one edge.
    let clear_of_corners = || {
        remaining
            .iter()
            .filter(|&&other| other != previous && other != current && other != next)
            .all(|&other| {
                let x = flat[other];
                cross(p, c, x) < 0.0 || cross(c, q, x) < 0.0 || cross(q, p, x) < 0.0
            })
    };
    // Every edge but the ear's own two: (remaining[j], remaining[j + 1]) for j other than
    // k - 1 and k.
    let clear_of_edges = || {
        (0..m).filter(|&j| j != (k + m - 1) % m && j != k).all(|j| {
            let (x, y) = (flat[remaining[j]], flat[remaining[(j + 1) % m]]);
            !segment_enters_triangle(x, y, [p, c, q])
        })
    };
    (pass == Pass::Touching || clear_of_corners()) && clear_of_edges()
}

/// Ear clipping of the counter-clockwise polygon `flat` (corner k is `face[k]`).
fn clip_ears(flat: &[DVec2], face: &[u32]) -> Vec<[u32; 3]> {
    let n = face.len();
    // Corners still to cut, as indices into `face`.
    let mut remaining: Vec<usize> = (0..n).collect();
    let mut triangles = Vec::with_capacity(n - 2);
    let mut pass = Pass::Simple;
    let mut misses = 0;
    // Starting at the second corner, a convex face is cut into the fan from its first corner
    // (ears (0 1 2), (0 2 3), ...): convex faces triangulate as they always did.
    let mut k = 1;
    while remaining.len() > 3 {
        let m = remaining.len();
        k %= m;
        if is_ear(flat, &remaining, k, pass) {
            if pass != Pass::ZeroArea {
                let corner = |j: usize| face[remaining[j % m]];
                triangles.push([corner(k + m - 1), corner(k), corner(k + 1)]);
            } else {
                // Back to real ears; a polygon that needed the touching test still does.
                pass = Pass::Touching;
            }
            remaining.remove(k);
            misses = 0;
            continue;
        }
        misses += 1;
        k += 1;
        if misses >= m {
            misses = 0;
            pass = match pass {
                Pass::Simple => Pass::Touching,
                Pass::Touching => Pass::ZeroArea,
                Pass::ZeroArea => {
                    // No ear at all: not a weakly simple polygon. Fan what is left.
                    let rest: Vec<u32> = remaining.iter().map(|&r| face[r]).collect();
                    triangles.extend(fan(&rest));
                    return triangles;
                }
            };
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

    /// Segments that only touch the triangle (along a side, out of a corner, to a corner from
    /// outside) or miss it (crossing a side's line beyond the side) do not enter it; one from
    /// a corner inwards, one crossing it, one inside it and one through a corner do.
    #[test]
    fn segments_enter_a_triangle_only_through_its_interior() {
        let v = |x: f64, y: f64| DVec2::new(x, y);
        let triangle = [v(0.0, 0.0), v(4.0, 0.0), v(0.0, 4.0)];
        let touching = [
            (v(4.0, 0.0), v(0.0, 0.0)),
            (v(1.0, 0.0), v(3.0, 0.0)),
            (v(0.0, 0.0), v(-1.0, -1.0)),
            (v(-1.0, 5.0), v(1.0, 3.0)),
            (v(4.0, 0.0), v(0.0, 4.0)),
            (v(5.0, -2.0), v(5.0, 2.0)),
        ];
        for (x, y) in touching {
            assert!(!segment_enters_triangle(x, y, triangle), "{x} - {y}");
            assert!(!segment_enters_triangle(y, x, triangle), "{y} - {x}");
        }
        let entering = [
            (v(0.0, 0.0), v(1.0, 1.0)),
            (v(-1.0, 1.0), v(5.0, 1.0)),
            (v(1.0, 1.0), v(1.5, 1.0)),
            (v(4.0, 0.0), v(-4.0, 4.0)),
        ];
        for (x, y) in entering {
            assert!(segment_enters_triangle(x, y, triangle), "{x} - {y}");
            assert!(segment_enters_triangle(y, x, triangle), "{y} - {x}");
        }
    }

    /// How a face repeats the corners its slits pass twice.
    #[derive(Clone, Copy, Debug)]
    enum Repeat {
        /// The same vertex index again.
        Index,
        /// A new vertex at the same position, as exporters often write it.
        Position,
    }

    /// A face with holes as exporters write one (issue 33): the outer ring, counter-clockwise
    /// in xy, then for each hole a slit from the outer ring's first corner to the hole's first
    /// corner, around the hole the other way, and back along the slit. Returns the positions
    /// and the face.
    fn bridged(
        outer: &[(f32, f32)],
        holes: &[&[(f32, f32)]],
        repeat: Repeat,
    ) -> (Vec<Vec3>, Vec<u32>) {
        let mut positions: Vec<Vec3> = Vec::new();
        let mut face = Vec::new();
        let mut corner = |(x, y): (f32, f32), first_index: Option<u32>| {
            let index = match (repeat, first_index) {
                (Repeat::Index, Some(index)) => index,
                _ => {
                    positions.push(Vec3::new(x, y, 0.0));
                    positions.len() as u32 - 1
                }
            };
            face.push(index);
            index
        };
        let start = corner(outer[0], None);
        for &o in &outer[1..] {
            corner(o, None);
        }
        for hole in holes {
            corner(outer[0], Some(start));
            let entry = corner(hole[0], None);
            for &p in hole[1..].iter().rev() {
                corner(p, None);
            }
            corner(hole[0], Some(entry));
        }
        (positions, face)
    }

    fn point_in_triangle(x: DVec2, [a, b, c]: [DVec2; 3]) -> bool {
        let sides = [cross(a, b, x), cross(b, c, x), cross(c, a, x)];
        sides.iter().all(|&s| s > 0.0) || sides.iter().all(|&s| s < 0.0)
    }

    /// The triangles of `face` (in the xy plane) cover `area` in all, face the face's way,
    /// and cover each point of a 40 x 40 grid over [0, 4]^2 exactly once where `inside` holds
    /// and never elsewhere: nothing outside, nothing in a hole, no overlap.
    fn assert_tiles(
        positions: &[Vec3],
        face: &[u32],
        inside: impl Fn(f64, f64) -> bool,
        expected_area: f64,
        what: &str,
    ) {
        let triangles = triangulate(positions, face);
        let flat = |i: u32| positions[i as usize].truncate().as_dvec2();
        let face_sign = (0..face.len())
            .map(|k| flat(face[k]).perp_dot(flat(face[(k + 1) % face.len()])))
            .sum::<f64>()
            .signum();
        let mut total = 0.0;
        for t in &triangles {
            let signed = 0.5 * cross(flat(t[0]), flat(t[1]), flat(t[2]));
            assert!(
                signed * face_sign >= 0.0,
                "{what}: {t:?} faces the wrong way"
            );
            total += signed.abs();
        }
        assert!(
            (total - expected_area).abs() < 1e-9,
            "{what}: triangles cover {total}, the face {expected_area}: {triangles:?}"
        );
        for i in 0..40 {
            for j in 0..40 {
                // Offsets keep the samples off every edge of the shapes below.
                let x = DVec2::new((i as f64 + 0.37) * 0.1, (j as f64 + 0.61) * 0.1);
                let covers = triangles
                    .iter()
                    .filter(|t| point_in_triangle(x, t.map(flat)))
                    .count();
                let expected = usize::from(inside(x.x, x.y));
                assert_eq!(covers, expected, "{what}: ({x}) covered {covers} times");
            }
        }
    }

    fn in_box(x: f64, y: f64, (x0, y0): (f64, f64), (x1, y1): (f64, f64)) -> bool {
        x0 < x && x < x1 && y0 < y && y < y1
    }

    /// [`assert_tiles`] for the face with `holes` in `outer`, with its repeated corners
    /// repeated by index and by position, each way round, starting at every corner.
    fn assert_every_variant(
        outer: &[(f32, f32)],
        holes: &[&[(f32, f32)]],
        inside: impl Fn(f64, f64) -> bool + Copy,
        expected_area: f64,
        name: &str,
    ) {
        for repeat in [Repeat::Index, Repeat::Position] {
            let (positions, mut face) = bridged(outer, holes, repeat);
            for reversed in [false, true] {
                if reversed {
                    face.reverse();
                }
                for shift in 0..face.len() {
                    let mut shifted = face.clone();
                    shifted.rotate_left(shift);
                    let what = format!("{name}, {repeat:?}, reversed {reversed}, shift {shift}");
                    assert_tiles(&positions, &shifted, inside, expected_area, &what);
                }
            }
        }
    }

    /// The case: a 4 x 4 square with a 2 x 2 hole, bridged corner to corner (the slit
    /// is in line with the square's diagonal, so corners of both rings lie on every diagonal
    /// through it). Every corner of the square starts the slit in turn. Before the touching
    /// pass no ear was found, and the fan covered the hole (16 units^2, not 12).
    #[test]
    fn a_bridged_square_hole_is_left_uncovered() {
        let square = [(0.0, 0.0), (4.0, 0.0), (4.0, 4.0), (0.0, 4.0)];
        let hole = [(1.0, 1.0), (3.0, 1.0), (3.0, 3.0), (1.0, 3.0)];
        let inside = |x, y| !in_box(x, y, (1.0, 1.0), (3.0, 3.0));
        for turn in 0..4 {
            let outer: Vec<_> = (0..4).map(|k| square[(k + turn) % 4]).collect();
            let inner: Vec<_> = (0..4).map(|k| hole[(k + turn) % 4]).collect();
            let name = format!("slit from corner {turn}");
            assert_every_variant(&outer, &[&inner], inside, 12.0, &name);
        }
    }

    /// Holes of other shapes: a diamond reached by a horizontal slit from a corner in the
    /// middle of the square's left side, a triangle, a concave L, and two holes bridged from
    /// the same corner (which the face then passes three times; the slits leave it in
    /// clockwise order, so that the face does not overlap itself there).
    #[test]
    fn holes_of_several_shapes_are_left_uncovered() {
        let square = [(0.0, 0.0), (4.0, 0.0), (4.0, 4.0), (0.0, 4.0)];
        let left_middle = [(0.0, 2.0), (0.0, 0.0), (4.0, 0.0), (4.0, 4.0), (0.0, 4.0)];
        let diamond = [(1.0, 2.0), (2.0, 1.0), (3.0, 2.0), (2.0, 3.0)];
        let outside_diamond = |x: f64, y: f64| (x - 2.0).abs() + (y - 2.0).abs() > 1.0;
        assert_every_variant(&left_middle, &[&diamond], outside_diamond, 14.0, "diamond");

        let triangle = [(1.0, 1.0), (3.0, 1.0), (1.0, 3.0)];
        let outside_triangle = |x: f64, y: f64| !(x > 1.0 && y > 1.0 && x + y < 4.0);
        assert_every_variant(&square, &[&triangle], outside_triangle, 14.0, "triangle");

        let l_shape = [
            (1.0, 1.0),
            (3.0, 1.0),
            (3.0, 2.0),
            (2.0, 2.0),
            (2.0, 3.0),
            (1.0, 3.0),
        ];
        let outside_l =
            |x, y| !(in_box(x, y, (1.0, 1.0), (3.0, 2.0)) || in_box(x, y, (1.0, 1.0), (2.0, 3.0)));
        assert_every_variant(&square, &[&l_shape], outside_l, 13.0, "L");

        let upper = [(0.5, 2.0), (3.0, 2.0), (3.0, 3.5), (0.5, 3.5)];
        let lower = [(1.0, 0.5), (3.5, 0.5), (3.5, 1.5), (1.0, 1.5)];
        let outside_both =
            |x, y| !(in_box(x, y, (1.0, 0.5), (3.5, 1.5)) || in_box(x, y, (0.5, 2.0), (3.0, 3.5)));
        let area = 16.0 - 2.5 - 3.75;
        assert_every_variant(&square, &[&upper, &lower], outside_both, area, "two holes");
    }

    /// A ring around the origin of `n` corners at radii in [`lower`, `upper`], the first at
    /// angle 0, the others jittered by up to 0.15 of their spacing, counter-clockwise.
    fn jittered_ring(
        n: usize,
        lower: f64,
        upper: f64,
        random: &mut impl FnMut() -> f64,
    ) -> Vec<(f32, f32)> {
        (0..n)
            .map(|k| {
                let jitter = if k == 0 { 0.0 } else { 0.3 * (random() - 0.5) };
                let angle = (k as f64 + jitter) * std::f64::consts::TAU / n as f64;
                let radius = lower + random() * (upper - lower);
                ((radius * angle.cos()) as f32, (radius * angle.sin()) as f32)
            })
            .collect()
    }

    /// 2000 random rings (4-15 corners, radii 3-4) with random holes (3-14 corners, radii
    /// 0.5-1.5), bridged along the positive x axis: the triangles cover the ring's area minus
    /// the hole's, all facing the face's way.
    #[test]
    fn random_rings_with_holes_are_tiled() {
        // A linear congruential generator (Knuth's MMIX constants): the same cases every run.
        let mut state = 12345u64;
        let mut random = move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let shoelace = |ring: &[(f32, f32)]| {
            0.5 * (0..ring.len())
                .map(|k| {
                    let (a, b) = (ring[k], ring[(k + 1) % ring.len()]);
                    f64::from(a.0) * f64::from(b.1) - f64::from(b.0) * f64::from(a.1)
                })
                .sum::<f64>()
        };
        for case in 0..2000 {
            let outer_corners = 4 + (random() * 12.0) as usize;
            let hole_corners = 3 + (random() * 12.0) as usize;
            let outer = jittered_ring(outer_corners, 3.0, 4.0, &mut random);
            let hole = jittered_ring(hole_corners, 0.5, 1.5, &mut random);
            let expected = shoelace(&outer) - shoelace(&hole);
            for repeat in [Repeat::Index, Repeat::Position] {
                let (positions, mut face) = bridged(&outer, &[&hole], repeat);
                let start = case % face.len();
                face.rotate_left(start);
                let flat = |i: u32| positions[i as usize].truncate().as_dvec2();
                let areas: Vec<f64> = triangulate(&positions, &face)
                    .iter()
                    .map(|t| 0.5 * cross(flat(t[0]), flat(t[1]), flat(t[2])))
                    .collect();
                let total: f64 = areas.iter().sum();
                assert!(
                    areas.iter().all(|&a| a >= 0.0) && (total - expected).abs() < 1e-9 * expected,
                    "case {case}, {repeat:?}: triangle areas {areas:?} sum to {total}, not {expected}"
                );
            }
        }
    }
}
