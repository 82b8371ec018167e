//! Hashing and Owen scrambling: the randomisation that makes every pixel's and every
//! dimension's Sobol points an independent, uniformly distributed stratified set.
//!
//! Owen's nested uniform scramble (Owen 1995, "Randomly permuted (t,m,s)-nets and
//! (t,s)-sequences") flips each bit of a fraction with a random choice that depends only on
//! the bits above it. It keeps every (0,k,2)-net a net, and makes each point uniform on
//! [0, 1). It is computed here as in Laine & Karras 2011 ("Stratified sampling for stochastic
//! transparency", section 3.2): mirror the bits, apply a hash in which every output bit
//! depends only on input bits below it, mirror back. The hash is Vegdahl's improvement of
//! Laine and Karras's ("Building a better LK hash", 2021), whose multipliers are used below.
//!
//! Applied to a sample *index* instead of a value, the same scramble shuffles the order of a
//! sequence while mapping every aligned block of 2^k indices onto an aligned block of 2^k
//! indices (Burley 2020, "Practical Hash-based Owen Scrambling", section 4): the first 2^k
//! samples of a shuffled (0,2)-sequence are still a (0,k,2)-net.

/// A 32-bit integer hash with full avalanche: a PCG output permutation (O'Neill 2014,
/// "PCG: A Family of Simple Fast Space-Efficient Statistically Good Algorithms", RXS-M-XS).
#[inline]
pub fn hash_u32(value: u32) -> u32 {
    let state = value.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277_803_737);
    (word >> 22) ^ word
}

/// One hash of several words: each word is folded in after the previous ones have been
/// mixed, so swapping two words changes the result.
#[inline]
pub fn hash_words(words: &[u32]) -> u32 {
    words
        .iter()
        .fold(HASH_START, |h, &w| hash_u32(h ^ hash_u32(w)))
}

/// The state [`hash_words`] starts from.
pub const HASH_START: u32 = 0x6A09_E667;

/// A permutation of 32-bit words in which output bit b depends only on input bits 0..=b
/// (multiplying by an odd number, adding, and `x ^= x * even` all carry information only
/// upwards), different for each `seed`.
#[inline]
fn laine_karras_permutation(mut x: u32, seed: u32) -> u32 {
    x ^= x.wrapping_mul(0x3d20_adea);
    x = x.wrapping_add(seed);
    x = x.wrapping_mul((seed >> 16) | 1);
    x ^= x.wrapping_mul(0x0552_6c56);
    x ^= x.wrapping_mul(0x53a2_2864);
    x
}

/// Owen's nested uniform scramble of a 32-bit fraction (or a sample index), keyed by
/// `seed`: bit 31 (the coarsest) is flipped or not by the seed alone, each lower bit by the
/// seed and the bits above it.
#[inline]
pub fn nested_uniform_scramble(value: u32, seed: u32) -> u32 {
    laine_karras_permutation(value.reverse_bits(), seed).reverse_bits()
}

/// [`nested_uniform_scramble`] of the value whose bits mirrored are `mirrored`: the same
/// result without the first mirroring, for values (Sobol points) that are cheaper to
/// compute mirrored (`super::sobol::dimension_1_mirrored`; dimension 0 mirrored is the index).
#[inline]
pub fn scramble_mirrored(mirrored: u32, seed: u32) -> u32 {
    laine_karras_permutation(mirrored, seed).reverse_bits()
}

/// A 32-bit fraction as a float in [0, 1): its top 24 bits, which an `f32` holds exactly
/// (so the result never rounds up to 1).
#[inline]
pub fn unit_float(bits: u32) -> f32 {
    (bits >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_scramble_is_a_permutation_that_keeps_aligned_blocks() {
        // On 12-bit values (the top 12 bits of a fraction): a bijection, and every aligned
        // block of 2^k values goes to one aligned block of 2^k values.
        for seed in [0u32, 1, 0xDEAD_BEEF, hash_u32(7)] {
            let mut seen = vec![false; 1 << 12];
            for v in 0u32..1 << 12 {
                let top = (nested_uniform_scramble(v << 20, seed) >> 20) as usize;
                assert!(!seen[top], "seed {seed}: {v} collides");
                seen[top] = true;
            }
            // The index form: indices 0..2^k land in one aligned block of size 2^k.
            for k in [1u32, 3, 6] {
                let blocks: std::collections::BTreeSet<u32> = (0..1u32 << k)
                    .map(|i| nested_uniform_scramble(i, seed) >> k)
                    .collect();
                assert_eq!(blocks.len(), 1, "seed {seed} k {k}: {blocks:?}");
            }
        }
    }

    #[test]
    fn the_top_bit_is_flipped_by_half_of_the_seeds() {
        // Uniformity of the first digit: over many seeds, value 0 scrambles into the upper
        // half about half of the time.
        let upper = (0..4096u32)
            .filter(|&s| nested_uniform_scramble(0, hash_u32(s)) >> 31 == 1)
            .count();
        assert!((1848..=2248).contains(&upper), "{upper} of 4096");
    }

    #[test]
    fn hash_words_depends_on_order_and_every_word() {
        let base = hash_words(&[1, 2, 3]);
        for other in [&[2u32, 1, 3][..], &[1, 2, 4], &[1, 2], &[0, 2, 3]] {
            assert_ne!(base, hash_words(other), "{other:?}");
        }
    }

    #[test]
    fn unit_float_stays_below_one() {
        assert_eq!(unit_float(0), 0.0);
        assert!(unit_float(u32::MAX) < 1.0);
        assert_eq!(unit_float(1 << 31), 0.5);
    }
}
