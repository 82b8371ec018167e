//! The first two dimensions of the Sobol sequence in base 2, as 32-bit fixed-point
//! fractions (the value is `bits / 2^32`).
//!
//! Together they form a (0,2)-sequence: every aligned block of 2^k consecutive points is a
//! (0,k,2)-net, one point in each elementary interval of area 2^-k (Sobol 1967; Niederreiter,
//! "Random Number Generation and Quasi-Monte Carlo Methods", 1992, section 4.5). That is all a
//! sampler that pads 2D projections needs (see `super`), so no table of direction numbers for
//! higher dimensions is used.
//!
//! Dimension 0 is the van der Corput radical inverse in base 2 (its generator matrix is the
//! identity). Dimension 1 uses the primitive polynomial x + 1 (degree 1) with initial
//! direction number m_1 = 1; the recurrence m_k = 2 m_{k-1} XOR m_{k-1} gives
//! m = 1, 3, 5, 15, 17, 51, 85, 255, ... (Bratley & Fox, ACM TOMS 14(1), 1988, Algorithm 659;
//! Joe & Kuo, "Remark on Algorithm 659", 2003), and the direction numbers are
//! v_k = m_k / 2^k.

/// The 32 direction numbers of dimension 1 as fixed-point fractions: `m_k << (32 - k)`.
#[cfg_attr(not(test), allow(dead_code))]
const DIMENSION_1_DIRECTIONS: [u32; 32] = dimension_1_directions();

#[cfg_attr(not(test), allow(dead_code))]
const fn dimension_1_directions() -> [u32; 32] {
    let mut directions = [0u32; 32];
    // m_k as a k-bit odd integer; the recurrence m_k = (m_{k-1} << 1) ^ m_{k-1} keeps it
    // below 2^k, so `m << (32 - k)` never loses bits.
    let mut m: u64 = 1;
    let mut k = 1;
    while k <= 32 {
        directions[k - 1] = (m << (32 - k)) as u32;
        m = (m << 1) ^ m;
        k += 1;
    }
    directions
}

/// Point `index` of Sobol dimension 0: the bits of `index` mirrored about the binary point.
/// (The sampler scrambles mirrored bits, so it uses `index` itself; this and [`dimension_1`]
/// are the definitions its mirrored forms are tested against.)
#[cfg_attr(not(test), allow(dead_code))]
#[inline]
pub fn dimension_0(index: u32) -> u32 {
    index.reverse_bits()
}

/// Point `index` of Sobol dimension 1: the XOR of the direction numbers of `index`'s set
/// bits (the generator matrix applied to the bits of `index`).
#[cfg_attr(not(test), allow(dead_code))]
#[inline]
pub fn dimension_1(index: u32) -> u32 {
    let mut bits = index;
    let mut value = 0u32;
    while bits != 0 {
        let k = bits.trailing_zeros();
        value ^= DIMENSION_1_DIRECTIONS[k as usize];
        bits &= bits - 1;
    }
    value
}

/// Point `index` of Sobol dimension 1 with its bits mirrored: `dimension_1(index).reverse_bits()`
/// without the loop over set bits, for the scramble, which works on mirrored bits
/// (`super::scramble::scramble_mirrored`).
///
/// Why this is the same number: m_k is the GF(2) polynomial (1 + x)^(k-1), whose binomial
/// coefficients are symmetric, so mirroring v_k = m_k << (32 - k) about the 32 bits gives
/// (1 + x)^(k-1) back in the low bits. The mirrored point is therefore the index's bits
/// read as a polynomial i(y) and evaluated at y = 1 + x over GF(2). Splitting i into halves,
/// i = A + y^s B, and using (1 + x)^s = 1 + x^s for s a power of two, gives
/// i(1 + x) = A' + B' + x^s B': inside each aligned block of 2s bits the low half takes the
/// XOR of both transformed halves. Five such steps (s = 1, 2, 4, 8, 16, innermost first)
/// evaluate the whole polynomial.
#[inline]
pub fn dimension_1_mirrored(index: u32) -> u32 {
    let mut bits = index;
    bits ^= (bits >> 1) & 0x5555_5555;
    bits ^= (bits >> 2) & 0x3333_3333;
    bits ^= (bits >> 4) & 0x0f0f_0f0f;
    bits ^= (bits >> 8) & 0x00ff_00ff;
    bits ^= (bits >> 16) & 0x0000_ffff;
    bits
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mirrored_dimension_1_is_dimension_1_mirrored() {
        // Every single bit, then a spread of indices (the sampler feeds scrambled, so
        // arbitrary, 32-bit indices).
        for b in 0..32 {
            let index = 1u32 << b;
            assert_eq!(
                dimension_1_mirrored(index),
                dimension_1(index).reverse_bits(),
                "bit {b}"
            );
        }
        let mut index = 0x9e37_79b9u32;
        for i in 0..200_000u32 {
            index = index.wrapping_mul(747_796_405).wrapping_add(2_891_336_453) ^ i;
            assert_eq!(
                dimension_1_mirrored(index),
                dimension_1(index).reverse_bits(),
                "{index:#x}"
            );
            assert_eq!(
                dimension_1_mirrored(i),
                dimension_1(i).reverse_bits(),
                "{i}"
            );
        }
    }

    fn fraction(bits: u32) -> f64 {
        bits as f64 / 4_294_967_296.0
    }

    #[test]
    fn the_first_points_are_the_published_ones() {
        // Bratley & Fox's table of the two-dimensional Sobol sequence.
        let first_0 = [0.0, 0.5, 0.25, 0.75, 0.125, 0.625, 0.375, 0.875];
        let first_1 = [0.0, 0.5, 0.75, 0.25, 0.625, 0.125, 0.375, 0.875];
        for i in 0..8 {
            assert_eq!(
                fraction(dimension_0(i)),
                first_0[i as usize],
                "dim 0, point {i}"
            );
            assert_eq!(
                fraction(dimension_1(i)),
                first_1[i as usize],
                "dim 1, point {i}"
            );
        }
        let m: Vec<u32> = (1..=8)
            .map(|k| DIMENSION_1_DIRECTIONS[k - 1] >> (32 - k))
            .collect();
        assert_eq!(m, [1, 3, 5, 15, 17, 51, 85, 255]);
    }

    #[test]
    fn every_aligned_block_is_a_net() {
        // (0,2)-sequence: the block [b 2^k, (b+1) 2^k) puts one point in every 2^-a x 2^-(k-a)
        // elementary interval, for every split a.
        for k in [2u32, 4, 5, 8] {
            for block in [0u32, 1, 7, 1000] {
                for a in 0..=k {
                    let mut cells = vec![0u32; 1 << k];
                    for i in block << k..(block + 1) << k {
                        let cx = (dimension_0(i) as u64 >> (32 - a)) as u32;
                        let cy = (dimension_1(i) as u64 >> (32 - (k - a))) as u32;
                        cells[(cy << a | cx) as usize] += 1;
                    }
                    assert!(cells.iter().all(|&c| c == 1), "k {k} block {block} a {a}");
                }
            }
        }
    }
}
