//! A patch's subdivision hierarchy, built once: the boxes of its sub-patches' control
//! points down to nearly bilinear leaves, so a ray starts its search at the leaves it
//! crosses instead of subdividing the whole patch again.
//!
//! The exact intersector ([`super::intersect`]) splits a patch at its middle (de Casteljau)
//! until the sub-patches are nearly bilinear and then runs Newton iteration. Those splits
//! do not depend on the ray, only the culling does; so the splits are made here once per
//! patch, in world space, and stored as a small tree of boxes (each box contains its
//! sub-patch: a Bezier patch lies in the convex hull of its control points, seed 004,
//! "Another Way To Render"). A ray walks the tree with slab tests, nearest box first, and
//! at each leaf it meets hands the leaf's control net to the intersector, which goes on as
//! before: the leaf's box in the ray's own frame, Newton from its middle, further splits
//! where Newton leads away.
//!
//! A leaf is a sub-patch within [`super::intersect::FLATNESS`] of bilinear (after at least
//! one split, as in the intersector) or one at [`TREE_DEPTH`], which bounds the memory: at
//! most `4^TREE_DEPTH` leaves of 16 control points per patch (the teapot's 32 patches have
//! 7,658 leaves, 3.8 MB with the inner boxes).

use glam::DVec3;

use super::intersect::{bilinear_deviation, net_bounds, split_u, split_v, FLATNESS};

/// Deepest level the tree is built to; below it the intersector splits per ray.
pub const TREE_DEPTH: u32 = 5;

/// A sub-patch at the bottom of the tree: its control net (world space) and parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct HullLeaf {
    pub net: [DVec3; 16],
    pub u0: f64,
    pub u1: f64,
    pub v0: f64,
    pub v1: f64,
    /// Number of splits from the whole patch.
    pub depth: u32,
    /// Whether the sub-patch is within `FLATNESS` of bilinear (a leaf at [`TREE_DEPTH`]
    /// may not be).
    pub flat: bool,
}

/// What a tree node holds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum HullContent {
    /// Four children at `nodes[first .. first + 4]`.
    Split { first: u32 },
    /// `leaves[index]`.
    Leaf { index: u32 },
}

/// A box of the tree, enlarged by the intersector's distance tolerance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HullNode {
    pub lower: DVec3,
    pub upper: DVec3,
    pub content: HullContent,
}

/// The subdivision hierarchy of one patch; node 0 is the whole patch.
#[derive(Clone, Debug, PartialEq)]
pub struct HullTree {
    pub nodes: Vec<HullNode>,
    pub leaves: Vec<HullLeaf>,
}

impl HullTree {
    /// Builds the tree of the patch with control net `control` (f64, world space); boxes
    /// grow by `slack` on every side, the distance a hit may lie off the surface.
    pub fn build(control: &[DVec3; 16], slack: f64) -> HullTree {
        let mut tree = HullTree {
            nodes: Vec::new(),
            leaves: Vec::new(),
        };
        tree.nodes.push(placeholder());
        tree.fill(0, *control, (0.0, 1.0, 0.0, 1.0), 0, slack);
        tree
    }

    /// Memory held by the tree, in bytes.
    pub fn bytes(&self) -> usize {
        self.nodes.len() * std::mem::size_of::<HullNode>()
            + self.leaves.len() * std::mem::size_of::<HullLeaf>()
    }

    fn fill(
        &mut self,
        slot: usize,
        net: [DVec3; 16],
        (u0, u1, v0, v1): (f64, f64, f64, f64),
        depth: u32,
        slack: f64,
    ) {
        let (lo, hi) = net_bounds(&net);
        let size = (hi - lo).max_element();
        let flat = depth >= 1 && bilinear_deviation(&net) <= FLATNESS * size;
        let (lower, upper) = (lo - DVec3::splat(slack), hi + DVec3::splat(slack));
        if flat || depth >= TREE_DEPTH {
            self.nodes[slot] = HullNode {
                lower,
                upper,
                content: HullContent::Leaf {
                    index: self.leaves.len() as u32,
                },
            };
            self.leaves.push(HullLeaf {
                net,
                u0,
                u1,
                v0,
                v1,
                depth,
                flat,
            });
            return;
        }
        let first = self.nodes.len();
        self.nodes[slot] = HullNode {
            lower,
            upper,
            content: HullContent::Split {
                first: first as u32,
            },
        };
        self.nodes.extend([placeholder(); 4]);
        let (um, vm) = (0.5 * (u0 + u1), 0.5 * (v0 + v1));
        let (left, right) = split_u(&net);
        let (ll, lh) = split_v(&left);
        let (rl, rh) = split_v(&right);
        self.fill(first, ll, (u0, um, v0, vm), depth + 1, slack);
        self.fill(first + 1, rl, (um, u1, v0, vm), depth + 1, slack);
        self.fill(first + 2, lh, (u0, um, vm, v1), depth + 1, slack);
        self.fill(first + 3, rh, (um, u1, vm, v1), depth + 1, slack);
    }
}

fn placeholder() -> HullNode {
    HullNode {
        lower: DVec3::ZERO,
        upper: DVec3::ZERO,
        content: HullContent::Leaf { index: 0 },
    }
}

/// The parameter interval `[t0, t1]` in which the ray `origin + t direction` is inside the
/// box (slab test), if it meets the box at all. An axis the ray runs parallel to bounds
/// nothing when the origin lies within the slab, and rejects the ray otherwise.
#[inline]
pub fn ray_box(origin: DVec3, direction: DVec3, lower: DVec3, upper: DVec3) -> Option<(f64, f64)> {
    let mut t0 = f64::NEG_INFINITY;
    let mut t1 = f64::INFINITY;
    for axis in 0..3 {
        let (o, d) = (origin[axis], direction[axis]);
        if d == 0.0 {
            if o < lower[axis] || o > upper[axis] {
                return None;
            }
            continue;
        }
        let inverse = 1.0 / d;
        let (a, b) = ((lower[axis] - o) * inverse, (upper[axis] - o) * inverse);
        t0 = t0.max(a.min(b));
        t1 = t1.min(a.max(b));
    }
    (t0 <= t1).then_some((t0, t1))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::patch::{control_f64, evaluate};

    fn teapot() -> Vec<[glam::Vec3; 16]> {
        let text = std::fs::read_to_string(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/assets/models/teapot.bpt"
        ))
        .expect("assets/models/teapot.bpt is part of the repository");
        crate::scene::patch::bpt::parse_bpt(&text).expect("the teapot parses")
    }

    /// Every leaf's box contains its piece of the surface, the leaves tile the parameter
    /// square, and each inner box contains its children's.
    #[test]
    fn leaves_tile_the_patch_and_boxes_contain_the_surface() {
        let mut leaves = 0;
        for patch in teapot() {
            let control = control_f64(&patch);
            let tree = HullTree::build(&control, 0.0);
            let area: f64 = tree
                .leaves
                .iter()
                .map(|l| (l.u1 - l.u0) * (l.v1 - l.v0))
                .sum();
            assert!((area - 1.0).abs() < 1e-12, "leaves cover {area}");
            for node in &tree.nodes {
                match node.content {
                    HullContent::Leaf { index } => {
                        let leaf = &tree.leaves[index as usize];
                        for k in 0..=8 {
                            for l in 0..=8 {
                                let u = leaf.u0 + (leaf.u1 - leaf.u0) * k as f64 / 8.0;
                                let v = leaf.v0 + (leaf.v1 - leaf.v0) * l as f64 / 8.0;
                                let p = evaluate(&control, u, v).position;
                                let inside = p.cmpge(node.lower - 1e-12).all()
                                    && p.cmple(node.upper + 1e-12).all();
                                assert!(inside, "{p} outside its leaf box at ({u}, {v})");
                            }
                        }
                    }
                    HullContent::Split { first } => {
                        for child in &tree.nodes[first as usize..first as usize + 4] {
                            assert!(child.lower.cmpge(node.lower).all());
                            assert!(child.upper.cmple(node.upper).all());
                        }
                    }
                }
            }
            leaves += tree.leaves.len();
        }
        eprintln!("teapot: {leaves} leaves");
        assert!(leaves > 32);
    }

    #[test]
    fn slab_test_handles_axis_parallel_rays() {
        let (lo, hi) = (DVec3::splat(-1.0), DVec3::splat(1.0));
        let (t0, t1) = ray_box(DVec3::new(0.0, 0.0, 5.0), DVec3::NEG_Z, lo, hi).unwrap();
        assert_eq!((t0, t1), (4.0, 6.0));
        assert!(ray_box(DVec3::new(2.0, 0.0, 5.0), DVec3::NEG_Z, lo, hi).is_none());
        let (t0, t1) = ray_box(DVec3::new(1.0, 1.0, 5.0), DVec3::NEG_Z, lo, hi).unwrap();
        assert_eq!(
            (t0, t1),
            (4.0, 6.0),
            "a ray along the box's edge touches it"
        );
    }
}
