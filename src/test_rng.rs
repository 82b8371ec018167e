//! Deterministic pseudo-random numbers for unit tests: no extra crate, and every test sees
//! the same data on every run. Marsaglia's xorshift generators ("Xorshift RNGs", 2003) and
//! Vigna's xorshift64* ("An experimental exploration of Marsaglia's xorshift generators,
//! scrambled", 2016), plus the maps from their words to uniform numbers in [0, 1).

/// One step of the 32-bit xorshift (shifts 13, 17, 5); returns the new state.
pub(crate) fn xorshift32(state: &mut u32) -> u32 {
    *state ^= *state << 13;
    *state ^= *state >> 17;
    *state ^= *state << 5;
    *state
}

/// One step of the 64-bit xorshift (shifts 13, 7, 17); returns the new state.
pub(crate) fn xorshift64(state: &mut u64) -> u64 {
    *state ^= *state << 13;
    *state ^= *state >> 7;
    *state ^= *state << 17;
    *state
}

/// One step of xorshift64* (shifts 12, 25, 27, then a multiplication); returns its output.
pub(crate) fn xorshift64_star(state: &mut u64) -> u64 {
    *state ^= *state >> 12;
    *state ^= *state << 25;
    *state ^= *state >> 27;
    state.wrapping_mul(0x2545_f491_4f6c_dd1d)
}

/// The top 24 bits of a 32-bit word as an `f32` in [0, 1).
pub(crate) fn unit_f32(word: u32) -> f32 {
    (word >> 8) as f32 / (1u32 << 24) as f32
}

/// The top 24 bits of a 64-bit word as an `f32` in [0, 1).
pub(crate) fn unit_f32_of_u64(word: u64) -> f32 {
    (word >> 40) as f32 / (1u64 << 24) as f32
}

/// The top 53 bits of a 64-bit word as an `f64` in [0, 1).
pub(crate) fn unit_f64(word: u64) -> f64 {
    (word >> 11) as f64 / (1u64 << 53) as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn generators_follow_their_published_recurrences() {
        // Marsaglia's paper: xorshift32 from 2463534242 first gives 723471715.
        let mut s32 = 2_463_534_242u32;
        assert_eq!(xorshift32(&mut s32), 723_471_715);
        // Marsaglia's paper: xorshift64 from 88172645463325252 first gives
        // 8748534153485358512.
        let mut s64 = 88_172_645_463_325_252u64;
        assert_eq!(xorshift64(&mut s64), 8_748_534_153_485_358_512);
        // xorshift64* outputs the state times the constant.
        let mut star = 1u64;
        let out = xorshift64_star(&mut star);
        assert_eq!(out, star.wrapping_mul(0x2545_f491_4f6c_dd1d));
        assert!(unit_f32(u32::MAX) < 1.0 && unit_f32_of_u64(u64::MAX) < 1.0);
        assert!(unit_f64(u64::MAX) < 1.0 && unit_f64(0) == 0.0);
    }
}
