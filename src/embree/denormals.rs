//! Flush-to-zero / denormals-are-zero on the current thread, as Embree asks of every thread
//! that traces rays (denormal floats slow traversal down by orders of magnitude).
//!
//! MXCSR is per thread and Rust leaves it at the default, so the renderer calls
//! [`enable_flush_denormals`] on each tracing thread (e.g. from rayon's `start_handler`).

/// MXCSR bit 15: flush denormal results to zero.
#[cfg(target_arch = "x86_64")]
const MXCSR_FLUSH_TO_ZERO: u32 = 1 << 15;
/// MXCSR bit 6: treat denormal inputs as zero.
#[cfg(target_arch = "x86_64")]
const MXCSR_DENORMALS_ARE_ZERO: u32 = 1 << 6;

#[cfg(target_arch = "x86_64")]
#[inline]
fn read_mxcsr() -> u32 {
    let mut csr: u32 = 0;
    // SAFETY: `stmxcsr` stores the 32-bit MXCSR register into the 4 bytes at the given
    // address, which is a live, aligned, writable local `u32`; it has no other effects.
    unsafe {
        core::arch::asm!("stmxcsr [{}]", in(reg) &mut csr, options(nostack, preserves_flags));
    }
    csr
}

/// Sets the flush-to-zero and denormals-are-zero bits of MXCSR on the calling thread.
/// A no-op on other architectures.
pub fn enable_flush_denormals() {
    #[cfg(target_arch = "x86_64")]
    {
        let csr = read_mxcsr() | MXCSR_FLUSH_TO_ZERO | MXCSR_DENORMALS_ARE_ZERO;
        // SAFETY: `ldmxcsr` loads MXCSR from the 4 bytes at the address of a live local
        // `u32`. The value is the current MXCSR with only FTZ and DAZ added, both valid
        // control bits on every x86_64 CPU (reserved bits are left as read), so it cannot
        // fault; it only changes how this thread rounds denormals.
        unsafe {
            core::arch::asm!("ldmxcsr [{}]", in(reg) &csr, options(nostack, preserves_flags));
        }
    }
}

/// True when both flush-to-zero and denormals-are-zero are set on the calling thread.
pub fn flush_denormals_enabled() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        let both = MXCSR_FLUSH_TO_ZERO | MXCSR_DENORMALS_ARE_ZERO;
        read_mxcsr() & both == both
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    #[cfg(target_arch = "x86_64")]
    fn bits_are_set_and_denormals_flush() {
        // A fresh thread starts with Rust's default MXCSR (FTZ and DAZ off).
        let result = std::thread::spawn(|| {
            let before = flush_denormals_enabled();
            let tiny = std::hint::black_box(f32::MIN_POSITIVE);
            let denormal_before = std::hint::black_box(tiny * 0.25);
            enable_flush_denormals();
            let after = flush_denormals_enabled();
            let denormal_after = std::hint::black_box(tiny) * std::hint::black_box(0.25f32);
            (before, denormal_before, after, denormal_after)
        })
        .join()
        .expect("test thread");
        assert!(!result.0);
        assert!(result.1 > 0.0, "without FTZ the product is a denormal");
        assert!(result.2);
        assert_eq!(
            result.3, 0.0,
            "with FTZ the denormal product is flushed to zero"
        );
    }
}
