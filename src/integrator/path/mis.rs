//! Multiple importance sampling between light sampling and BSDF sampling: Veach's power
//! heuristic with exponent 2 (Veach 1997, thesis section 9.2.4; pbrt-v4, section 2.2.3).

/// Weight of a sample drawn by the strategy of density `pdf_chosen`, when the other
/// strategy would have drawn it with density `pdf_other` (one sample each):
/// `p_chosen^2 / (p_chosen^2 + p_other^2)`. Zero when the chosen density is zero. Samples
/// of delta lights are not weighted at all: integrators branch on
/// `SceneLights::is_delta`, and no density stands for a delta here.
#[inline]
pub fn power_heuristic(pdf_chosen: f32, pdf_other: f32) -> f32 {
    if pdf_chosen.is_nan() || pdf_chosen <= 0.0 {
        return 0.0;
    }
    let (a, b) = (
        pdf_chosen * pdf_chosen,
        pdf_other.max(0.0) * pdf_other.max(0.0),
    );
    if b.is_infinite() {
        return 0.0;
    }
    // a / (a + b), written so that a huge `a` does not overflow to inf / inf.
    1.0 / (1.0 + b / a)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weights_of_the_two_strategies_sum_to_one() {
        for (a, b) in [
            (1.0, 1.0),
            (0.3, 7.0),
            (1e-20, 3.0),
            (1e30, 1e-30),
            (2.0, 0.0),
        ] {
            let sum = power_heuristic(a, b) + power_heuristic(b, a);
            assert!((sum - 1.0).abs() < 1e-6, "{a} {b}: {sum}");
        }
        assert_eq!(power_heuristic(1.0, 1.0), 0.5);
        // p^2 / (p^2 + q^2) with p = 1, q = 3: 0.1.
        assert!((power_heuristic(1.0, 3.0) - 0.1).abs() < 1e-7);
    }

    #[test]
    fn degenerate_densities() {
        assert_eq!(power_heuristic(0.0, 1.0), 0.0);
        assert_eq!(power_heuristic(f32::NAN, 1.0), 0.0);
        assert_eq!(power_heuristic(1.0, f32::INFINITY), 0.0);
        // A density whose square overflows takes all the weight from a finite one.
        assert_eq!(power_heuristic(1e30, 1e10), 1.0);
    }
}
