//! Overlap tests between primitives and axis-aligned voxels, the core of conservative
//! voxelisation: a voxel is marked whenever any part of a surface touches it.

use glam::Vec3;

/// Whether triangle `tri` overlaps (or touches) the box of centre `center` and half-size
/// `half`: Akenine-Möller's separating-axis test ("Fast 3D Triangle-Box Overlap Testing",
/// JGT 6(1), 2001). The two sets are disjoint exactly when one of 13 axes separates them:
/// the 9 cross products of the triangle's edges with the box axes, the 3 box axes (the
/// triangle's bounding box against the box) and the triangle's normal.
pub fn triangle_box_overlap(center: Vec3, half: Vec3, tri: [Vec3; 3]) -> bool {
    let v = [tri[0] - center, tri[1] - center, tri[2] - center];
    let edges = [v[1] - v[0], v[2] - v[1], v[0] - v[2]];
    // Nine edge-cross-axis tests: project the triangle and the box on `a = axis x edge`.
    for edge in edges {
        for axis in [Vec3::X, Vec3::Y, Vec3::Z] {
            let a = axis.cross(edge);
            let p = [a.dot(v[0]), a.dot(v[1]), a.dot(v[2])];
            let radius = half.dot(a.abs());
            let lo = p[0].min(p[1]).min(p[2]);
            let hi = p[0].max(p[1]).max(p[2]);
            if lo > radius || hi < -radius {
                return false;
            }
        }
    }
    // The box's own axes: the triangle's bounding box against the box.
    let lo = v[0].min(v[1]).min(v[2]);
    let hi = v[0].max(v[1]).max(v[2]);
    if lo.cmpgt(half).any() || hi.cmplt(-half).any() {
        return false;
    }
    // The triangle's plane: the box's extent along the normal must reach it.
    let normal = edges[0].cross(edges[1]);
    let distance = normal.dot(v[0]);
    distance.abs() <= half.dot(normal.abs())
}

/// Whether the surface of the sphere (`center`, `radius`) passes through the box `lo..hi`:
/// the box's nearest point is inside the sphere and its farthest corner outside (or on it).
pub fn sphere_surface_box_overlap(center: Vec3, radius: f32, lo: Vec3, hi: Vec3) -> bool {
    let nearest = center.clamp(lo, hi);
    let farthest = Vec3::select((center - lo).cmpgt(hi - center), lo, hi);
    let r2 = radius * radius;
    center.distance_squared(nearest) <= r2 && center.distance_squared(farthest) >= r2
}

#[cfg(test)]
mod tests {
    use super::*;

    const H: Vec3 = Vec3::splat(0.5);

    #[test]
    fn triangle_inside_crossing_and_beside_the_box() {
        let inside = [
            Vec3::new(-0.1, -0.1, 0.0),
            Vec3::new(0.1, -0.1, 0.0),
            Vec3::new(0.0, 0.1, 0.0),
        ];
        assert!(triangle_box_overlap(Vec3::ZERO, H, inside));
        // A large triangle whose plane cuts the box though no vertex is inside.
        let big = [
            Vec3::new(-10.0, -10.0, 0.2),
            Vec3::new(10.0, -10.0, 0.2),
            Vec3::new(0.0, 10.0, 0.2),
        ];
        assert!(triangle_box_overlap(Vec3::ZERO, H, big));
        // The same plane above the box.
        let above = big.map(|p| p + Vec3::Z);
        assert!(!triangle_box_overlap(Vec3::ZERO, H, above));
        // Beside a box corner, separated only by an edge-cross-axis plane: its bounding box
        // overlaps the box, its plane cuts it, yet it misses.
        let diagonal = [
            Vec3::new(0.9, 0.2, 0.0),
            Vec3::new(0.2, 0.9, 0.0),
            Vec3::new(0.9, 0.9, 0.0),
        ];
        assert!(!triangle_box_overlap(Vec3::ZERO, H, diagonal));
        // Touching the box along its edge x = y = 0.5 only: touching counts.
        let touching = [
            Vec3::new(0.5, 0.5, -1.0),
            Vec3::new(0.5, 0.5, 1.0),
            Vec3::new(1.5, -0.5, 0.0),
        ];
        assert!(triangle_box_overlap(Vec3::ZERO, H, touching));
    }

    #[test]
    fn sphere_shell_against_boxes() {
        let (lo, hi) = (Vec3::splat(-0.5), Vec3::splat(0.5));
        assert!(sphere_surface_box_overlap(Vec3::ZERO, 0.6, lo, hi));
        // Box entirely inside the sphere: the surface does not pass through it.
        assert!(!sphere_surface_box_overlap(Vec3::ZERO, 2.0, lo, hi));
        // A small sphere inside the box: its whole surface is in the box.
        assert!(sphere_surface_box_overlap(Vec3::ZERO, 0.2, lo, hi));
        // Far away.
        assert!(!sphere_surface_box_overlap(Vec3::splat(3.0), 1.0, lo, hi));
    }
}
