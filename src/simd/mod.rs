//! Lane loops compiled for the widest vector instructions the processor has, chosen at run
//! time.
//!
//! The binary is built for baseline x86-64 (SSE2), so it runs on any x86-64 processor. SSE2
//! has no 32-bit lane multiply, no per-lane variable shift and no byte shuffle, which the
//! sampler's hashing and bit reversals need; AVX2 has all three and twice the width, and
//! AVX-512 twice that again. [`dispatch`] runs a closure inside a function compiled for the
//! best level the processor supports ([`Level::detected`], checked once), so the closure's
//! code, inlined there, is compiled for that level. On other architectures every level runs
//! the baseline code.
//!
//! Every level gives the same bits: the lane loops are exactly specified integer and IEEE
//! float operations, and Rust never contracts `a * b + c` into a fused multiply-add (only
//! `mul_add` asks for one, and that is one rounding on every level), so enabling FMA changes
//! no result. The tests of each wrapped loop compare every supported level with the
//! baseline.
//!
//! `CONETRACE_SIMD=baseline|avx2|avx512` ([`LEVEL_VARIABLE`]) runs a lower level than the
//! detected one, to measure what the vector code gains on the same binary.
//!
//! # Wrapping a loop
//!
//! Only code inlined into a level's function is compiled for that level: a function it
//! calls keeps the baseline. Each level calls the kernel from its own function, so a
//! kernel of any size is only inlined when the closure is marked `#[inline(always)]`, and
//! so must be every function of the loop that the compiler might leave out of line.
//!
//! ```
//! use conetrace::simd;
//!
//! #[inline(always)]
//! fn scaled<const N: usize>(values: &[f32; N], scale: f32) -> [f32; N] {
//!     std::array::from_fn(|lane| values[lane] * scale)
//! }
//!
//! let values = [1.0f32; 16];
//! let out = simd::dispatch(
//!     #[inline(always)]
//!     || scaled(&values, 0.5),
//! );
//! assert_eq!(out, [0.5; 16]);
//! // A test forces each level the processor has and compares with the baseline.
//! for level in simd::Level::supported() {
//!     assert_eq!(simd::run_at(level, #[inline(always)] || scaled(&values, 0.5)), out);
//! }
//! ```

use std::sync::OnceLock;

#[cfg(target_arch = "x86_64")]
mod x86;

/// The environment variable that lowers the level lane loops run at.
pub const LEVEL_VARIABLE: &str = "CONETRACE_SIMD";

/// A set of vector instructions lane loops are compiled for, in increasing order.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Level {
    /// Whatever the build targets: SSE2 on x86-64 (and all code on other architectures).
    Baseline,
    /// x86-64-v3: AVX2, FMA, BMI1/2, LZCNT, MOVBE, F16C (and SSE3 to SSE4.2, POPCNT).
    Avx2,
    /// x86-64-v4: x86-64-v3 and AVX-512 F, BW, CD, DQ and VL.
    Avx512,
}

impl Level {
    /// Every level, lowest first.
    pub const ALL: [Level; 3] = [Level::Baseline, Level::Avx2, Level::Avx512];

    /// The name [`LEVEL_VARIABLE`] takes and `--stats` writes.
    pub fn name(self) -> &'static str {
        match self {
            Level::Baseline => "baseline",
            Level::Avx2 => "avx2",
            Level::Avx512 => "avx512",
        }
    }

    /// The level called `name` ([`Level::name`]).
    pub fn from_name(name: &str) -> Option<Level> {
        Level::ALL.into_iter().find(|level| level.name() == name)
    }

    /// The best level this processor supports, detected on the first call.
    pub fn detected() -> Level {
        static DETECTED: OnceLock<Level> = OnceLock::new();
        *DETECTED.get_or_init(detect)
    }

    /// Whether this processor can run code compiled for the level.
    pub fn is_supported(self) -> bool {
        self <= Level::detected()
    }

    /// The levels this processor supports, lowest first.
    pub fn supported() -> impl Iterator<Item = Level> {
        Level::ALL.into_iter().filter(|level| level.is_supported())
    }
}

#[cfg(target_arch = "x86_64")]
fn detect() -> Level {
    if x86::has_avx512() {
        Level::Avx512
    } else if x86::has_avx2() {
        Level::Avx2
    } else {
        Level::Baseline
    }
}

#[cfg(not(target_arch = "x86_64"))]
fn detect() -> Level {
    Level::Baseline
}

/// The level [`LEVEL_VARIABLE`]'s value `value` asks for (`None` when unset), or why it
/// cannot be run on this processor.
pub fn requested_level(value: Option<&str>) -> Result<Option<Level>, String> {
    let Some(value) = value else {
        return Ok(None);
    };
    let names = Level::ALL.map(Level::name).join(", ");
    let level = Level::from_name(value.trim())
        .ok_or_else(|| format!("{LEVEL_VARIABLE}={value:?} is not a level (one of {names})"))?;
    if !level.is_supported() {
        return Err(format!(
            "{LEVEL_VARIABLE}={value}: this processor supports at most {}",
            Level::detected().name()
        ));
    }
    Ok(Some(level))
}

/// The level [`LEVEL_VARIABLE`] asks for, read from the environment; an error says why it
/// cannot be used (the command line refuses to start with it).
pub fn level_from_environment() -> Result<Option<Level>, String> {
    match std::env::var(LEVEL_VARIABLE) {
        Ok(value) => requested_level(Some(&value)),
        Err(std::env::VarError::NotPresent) => Ok(None),
        Err(std::env::VarError::NotUnicode(_)) => {
            Err(format!("{LEVEL_VARIABLE} is not valid UTF-8"))
        }
    }
}

/// The level [`dispatch`] runs at: [`LEVEL_VARIABLE`]'s when it names a supported level,
/// else the detected one. Fixed on the first call.
pub fn active() -> Level {
    static ACTIVE: OnceLock<Level> = OnceLock::new();
    *ACTIVE.get_or_init(|| {
        level_from_environment()
            .ok()
            .flatten()
            .unwrap_or_else(Level::detected)
    })
}

/// Runs `kernel` compiled for the [`active`] level. Mark the closure `#[inline(always)]`
/// (see the module's example): code behind a call that is not inlined keeps the baseline.
#[inline]
pub fn dispatch<R>(kernel: impl FnOnce() -> R) -> R {
    run_at(active(), kernel)
}

/// Runs `kernel` compiled for `level`, or for the best level below it that this processor
/// supports.
#[inline]
pub fn run_at<R>(level: Level, kernel: impl FnOnce() -> R) -> R {
    #[cfg(target_arch = "x86_64")]
    match level.min(Level::detected()) {
        Level::Avx512 => return x86::run_avx512(kernel),
        Level::Avx2 => return x86::run_avx2(kernel),
        Level::Baseline => {}
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = level;
    kernel()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn level_names_round_trip_and_are_ordered() {
        for level in Level::ALL {
            assert_eq!(Level::from_name(level.name()), Some(level));
        }
        assert!(Level::Baseline < Level::Avx2 && Level::Avx2 < Level::Avx512);
        assert_eq!(Level::from_name("sse2"), None);
        assert!(Level::Baseline.is_supported());
        assert_eq!(Level::supported().last(), Some(Level::detected()));
    }

    #[test]
    fn the_variable_is_checked_against_the_processor() {
        assert_eq!(requested_level(None), Ok(None));
        assert_eq!(requested_level(Some("baseline")), Ok(Some(Level::Baseline)));
        let error = requested_level(Some("avx3")).unwrap_err();
        assert!(
            error.contains("CONETRACE_SIMD=\"avx3\" is not a level"),
            "{error}"
        );
        for level in Level::ALL {
            let result = requested_level(Some(level.name()));
            if level.is_supported() {
                assert_eq!(result, Ok(Some(level)));
            } else {
                assert!(result.unwrap_err().contains("supports at most"));
            }
        }
    }

    #[test]
    fn every_level_runs_the_kernel_once_and_returns_its_value() {
        for level in Level::ALL {
            let mut calls = 0;
            let value = run_at(level, || {
                calls += 1;
                level.name().len()
            });
            assert_eq!((value, calls), (level.name().len(), 1));
        }
    }

    /// Integer and float lane work of the kinds the wrapped loops do (multiplies, variable
    /// shifts, bit reversal, division, square root, min/max with NaN and signed zeros), the
    /// same bits at every level.
    #[inline(always)]
    fn mixed_lanes(values: &[u32; 64]) -> [u32; 64] {
        std::array::from_fn(|lane| {
            let v = values[lane];
            let hashed = (v.wrapping_mul(747_796_405) >> ((v >> 28) + 4)).reverse_bits();
            let x = f32::from_bits(v);
            let y = f32::from_bits(hashed);
            let float = (x / y).sqrt().max(x * y + 0.5).min(y - x);
            hashed ^ float.to_bits()
        })
    }

    #[test]
    fn every_supported_level_gives_the_baseline_bits() {
        let mut state = 0x9e37_79b9u32;
        let specials = [0u32, 0x8000_0000, 0x7f80_0000, 0xff80_0000, 0x7fc0_0000, 1];
        for round in 0..200 {
            let values: [u32; 64] = std::array::from_fn(|lane| {
                state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                if round % 4 == 0 {
                    specials[lane % specials.len()]
                } else {
                    state
                }
            });
            let baseline = mixed_lanes(&values);
            for level in Level::supported() {
                assert_eq!(
                    run_at(
                        level,
                        #[inline(always)]
                        || mixed_lanes(&values)
                    ),
                    baseline,
                    "{level:?}"
                );
            }
        }
    }
}
