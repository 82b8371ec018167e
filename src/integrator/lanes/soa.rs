//! Vectors stored one array per coordinate, so that a loop over lanes reads and writes
//! consecutive floats of each coordinate and the compiler can run 8 or 16 lanes per
//! instruction (`crate::simd::dispatch`).

use glam::{Vec2, Vec3};

use super::LaneArray;

/// One 3-vector per lane: `x[lane]`, `y[lane]`, `z[lane]`.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct Vec3Lanes {
    pub x: Vec<f32>,
    pub y: Vec<f32>,
    pub z: Vec<f32>,
}

impl Vec3Lanes {
    pub(crate) fn clear(&mut self) {
        self.x.clear();
        self.y.clear();
        self.z.clear();
    }

    /// Cleared and filled with `len` zero vectors, reusing the allocations.
    pub(crate) fn refill(&mut self, len: usize) {
        for coordinate in [&mut self.x, &mut self.y, &mut self.z] {
            super::refill(coordinate, len, 0.0);
        }
    }

    /// Resized to `len` lanes, for a stage that writes every lane (what the lanes held
    /// before is left where it is not overwritten by the resize).
    pub(crate) fn resize(&mut self, len: usize) {
        for coordinate in [&mut self.x, &mut self.y, &mut self.z] {
            coordinate.resize_lanes(len, 0.0);
        }
    }

    #[inline(always)]
    pub(crate) fn get(&self, lane: usize) -> Vec3 {
        Vec3::new(self.x[lane], self.y[lane], self.z[lane])
    }

    #[inline(always)]
    pub(crate) fn set(&mut self, lane: usize, value: Vec3) {
        self.x[lane] = value.x;
        self.y[lane] = value.y;
        self.z[lane] = value.z;
    }

    /// The first `len` lanes as slices of exactly that length, so a loop over `0..len`
    /// indexes them without bounds checks.
    #[inline(always)]
    pub(crate) fn lanes(&self, len: usize) -> Vec3Slices<'_> {
        Vec3Slices {
            x: &self.x[..len],
            y: &self.y[..len],
            z: &self.z[..len],
        }
    }

    /// The lanes `range` as slices of its length.
    #[inline(always)]
    pub(crate) fn range(&self, range: std::ops::Range<usize>) -> Vec3Slices<'_> {
        Vec3Slices {
            x: &self.x[range.clone()],
            y: &self.y[range.clone()],
            z: &self.z[range],
        }
    }

    /// The lanes `range`, writable.
    #[inline(always)]
    pub(crate) fn range_mut(&mut self, range: std::ops::Range<usize>) -> Vec3SlicesMut<'_> {
        Vec3SlicesMut {
            x: &mut self.x[range.clone()],
            y: &mut self.y[range.clone()],
            z: &mut self.z[range],
        }
    }

    /// The first `len` lanes, writable.
    #[inline(always)]
    pub(crate) fn lanes_mut(&mut self, len: usize) -> Vec3SlicesMut<'_> {
        Vec3SlicesMut {
            x: &mut self.x[..len],
            y: &mut self.y[..len],
            z: &mut self.z[..len],
        }
    }
}

/// The first `len` lanes of a triangle's three corners (written out rather than through
/// `array::map`, which the compiler may leave out of line, hiding the slices' lengths from
/// the loops that index them).
#[inline(always)]
pub(crate) fn corner_lanes(corners: &[Vec3Lanes; 3], len: usize) -> [Vec3Slices<'_>; 3] {
    [
        corners[0].lanes(len),
        corners[1].lanes(len),
        corners[2].lanes(len),
    ]
}

/// [`corner_lanes`] of 2-vectors.
#[inline(always)]
pub(crate) fn corner_lanes_2(corners: &[Vec2Lanes; 3], len: usize) -> [[&[f32]; 2]; 3] {
    [
        corners[0].lanes(len),
        corners[1].lanes(len),
        corners[2].lanes(len),
    ]
}

/// `v.normalize_or(fallback)` (glam's, the same operations) with the choice made per
/// coordinate: the compiler vectorises a select of floats, not one of whole vectors.
#[inline(always)]
pub(crate) fn normalize_or(v: Vec3, fallback: Vec3) -> Vec3 {
    let rcp = v.length_recip();
    let usable = rcp.is_finite() && rcp > 0.0;
    select(usable, v * rcp, fallback)
}

/// `if condition { a } else { b }`, per coordinate (see [`normalize_or`]).
#[inline(always)]
pub(crate) fn select(condition: bool, a: Vec3, b: Vec3) -> Vec3 {
    Vec3::new(
        if condition { a.x } else { b.x },
        if condition { a.y } else { b.y },
        if condition { a.z } else { b.z },
    )
}

/// Read-only lanes of a [`Vec3Lanes`], all of one length.
#[derive(Clone, Copy)]
pub(crate) struct Vec3Slices<'a> {
    pub x: &'a [f32],
    pub y: &'a [f32],
    pub z: &'a [f32],
}

impl Vec3Slices<'_> {
    #[inline(always)]
    pub(crate) fn get(&self, lane: usize) -> Vec3 {
        Vec3::new(self.x[lane], self.y[lane], self.z[lane])
    }
}

/// Writable lanes of a [`Vec3Lanes`], all of one length.
pub(crate) struct Vec3SlicesMut<'a> {
    pub x: &'a mut [f32],
    pub y: &'a mut [f32],
    pub z: &'a mut [f32],
}

impl Vec3SlicesMut<'_> {
    #[inline(always)]
    pub(crate) fn set(&mut self, lane: usize, value: Vec3) {
        self.x[lane] = value.x;
        self.y[lane] = value.y;
        self.z[lane] = value.z;
    }
}

/// One 2-vector per lane: `x[lane]`, `y[lane]`.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct Vec2Lanes {
    pub x: Vec<f32>,
    pub y: Vec<f32>,
}

impl Vec2Lanes {
    /// Cleared and filled with `len` zero vectors, reusing the allocations.
    pub(crate) fn refill(&mut self, len: usize) {
        super::refill(&mut self.x, len, 0.0);
        super::refill(&mut self.y, len, 0.0);
    }

    /// Resized to `len` lanes, for a stage that writes every lane.
    pub(crate) fn resize(&mut self, len: usize) {
        self.x.resize_lanes(len, 0.0);
        self.y.resize_lanes(len, 0.0);
    }

    /// The first `len` lanes as slices of exactly that length.
    #[inline(always)]
    pub(crate) fn lanes(&self, len: usize) -> [&[f32]; 2] {
        [&self.x[..len], &self.y[..len]]
    }

    /// The first `len` lanes, writable.
    #[inline(always)]
    pub(crate) fn x_y_mut(&mut self, len: usize) -> [&mut [f32]; 2] {
        [&mut self.x[..len], &mut self.y[..len]]
    }

    #[inline(always)]
    pub(crate) fn get(&self, lane: usize) -> Vec2 {
        Vec2::new(self.x[lane], self.y[lane])
    }

    #[inline(always)]
    pub(crate) fn set(&mut self, lane: usize, value: Vec2) {
        self.x[lane] = value.x;
        self.y[lane] = value.y;
    }
}
