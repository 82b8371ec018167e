//! Summaries of repeated timings for the benchmark and accuracy commands: quantiles by linear
//! interpolation between the closest ranks, so an even count's median is the mean of the two
//! middle values.

/// The `q`-quantile (0 to 1) of `values`; NaN when there are none.
pub fn quantile(values: &[f64], q: f64) -> f64 {
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    if sorted.is_empty() {
        return f64::NAN;
    }
    let x = (sorted.len() - 1) as f64 * q.clamp(0.0, 1.0);
    let (i, f) = (x.floor() as usize, x - x.floor());
    let next = sorted[(i + 1).min(sorted.len() - 1)];
    if f == 0.0 {
        sorted[i]
    } else {
        sorted[i] + (next - sorted[i]) * f
    }
}

/// The median of `values`; NaN when there are none.
pub fn median(values: &[f64]) -> f64 {
    quantile(values, 0.5)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn medians_and_quartiles_of_odd_and_even_counts() {
        assert_eq!(median(&[3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&[4.0, 1.0, 3.0, 2.0]), 2.5);
        assert!(median(&[]).is_nan());
        let five = [5.0, 1.0, 4.0, 2.0, 3.0];
        assert_eq!(quantile(&five, 0.25), 2.0);
        assert_eq!(quantile(&five, 0.75), 4.0);
        assert_eq!(quantile(&[1.0, 2.0], 0.25), 1.25);
        assert_eq!(quantile(&five, 0.0), 1.0);
        assert_eq!(quantile(&five, 1.0), 5.0);
    }
}
