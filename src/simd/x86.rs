//! The x86-64 levels: detection, and one function per level compiled for its instructions.
//!
//! Calling a function compiled for instructions the processor lacks is undefined
//! behaviour, so the call is `unsafe`; each `run_` function checks the features first and
//! is the only caller of its level's function.

/// Whether the processor has x86-64-v3 (the features `v3` is compiled for).
pub(super) fn has_avx2() -> bool {
    is_x86_feature_detected!("avx")
        && is_x86_feature_detected!("avx2")
        && is_x86_feature_detected!("bmi1")
        && is_x86_feature_detected!("bmi2")
        && is_x86_feature_detected!("fma")
        && is_x86_feature_detected!("f16c")
        && is_x86_feature_detected!("lzcnt")
        && is_x86_feature_detected!("movbe")
        && is_x86_feature_detected!("popcnt")
        && is_x86_feature_detected!("sse3")
        && is_x86_feature_detected!("ssse3")
        && is_x86_feature_detected!("sse4.1")
        && is_x86_feature_detected!("sse4.2")
}

/// Whether the processor has x86-64-v4 (the features `v4` is compiled for).
pub(super) fn has_avx512() -> bool {
    has_avx2()
        && is_x86_feature_detected!("avx512f")
        && is_x86_feature_detected!("avx512bw")
        && is_x86_feature_detected!("avx512cd")
        && is_x86_feature_detected!("avx512dq")
        && is_x86_feature_detected!("avx512vl")
}

/// Runs `kernel` compiled for x86-64-v3.
#[inline]
pub(super) fn run_avx2<R>(kernel: impl FnOnce() -> R) -> R {
    assert!(
        super::Level::Avx2.is_supported(),
        "the processor lacks AVX2"
    );
    // SAFETY: the processor has every feature `v3` enables (`has_avx2`, checked above).
    unsafe { v3(kernel) }
}

/// Runs `kernel` compiled for x86-64-v4.
#[inline]
pub(super) fn run_avx512<R>(kernel: impl FnOnce() -> R) -> R {
    assert!(
        super::Level::Avx512.is_supported(),
        "the processor lacks AVX-512"
    );
    // SAFETY: the processor has every feature `v4` enables (`has_avx512`, checked above).
    unsafe { v4(kernel) }
}

#[target_feature(
    enable = "avx,avx2,bmi1,bmi2,fma,f16c,lzcnt,movbe,popcnt,sse3,ssse3,sse4.1,sse4.2"
)]
fn v3<R>(kernel: impl FnOnce() -> R) -> R {
    kernel()
}

#[target_feature(
    enable = "avx,avx2,bmi1,bmi2,fma,f16c,lzcnt,movbe,popcnt,sse3,ssse3,sse4.1,sse4.2,avx512f,avx512bw,avx512cd,avx512dq,avx512vl"
)]
fn v4<R>(kernel: impl FnOnce() -> R) -> R {
    kernel()
}
