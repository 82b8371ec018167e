//! Choosing one of `n` items with fixed probabilities in constant time: Walker's alias
//! method with Vose's construction (Vose 1991, "A Linear Algorithm for Generating Random
//! Numbers with a Given Distribution"; pbrt-v4, section A.1 describes the same table).
//!
//! The table has one bin per item, each of probability `1/n`: bin `i` keeps its own item
//! with probability `keep[i]` and hands the rest to `alias[i]`. One uniform number picks a
//! bin (its integer part after scaling by `n`) and the choice within it (its fraction).
//! Vose's construction fills the bins from two work lists, items below and above the mean,
//! so it never fails on rounding the way Walker's original sorting one may.

/// Walker/Vose alias table over `n` items.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AliasTable {
    /// Probability that bin `i` keeps item `i`.
    keep: Vec<f32>,
    /// The item bin `i` hands over to otherwise.
    alias: Vec<u32>,
    /// Normalised probability of each item.
    pmf: Vec<f32>,
}

impl AliasTable {
    /// A table choosing item `i` with probability `weights[i] / sum(weights)`; negative and
    /// non-finite weights count as zero. Empty (nothing to choose) when no weight is
    /// positive.
    pub fn new(weights: &[f32]) -> AliasTable {
        let clean: Vec<f64> = weights
            .iter()
            .map(|&w| {
                if w.is_finite() && w > 0.0 {
                    w as f64
                } else {
                    0.0
                }
            })
            .collect();
        let total: f64 = clean.iter().sum();
        if total <= 0.0 {
            return AliasTable::default();
        }
        let n = clean.len();
        let pmf: Vec<f32> = clean.iter().map(|&w| (w / total) as f32).collect();
        // Each item's probability in units of one bin (mean 1).
        let mut scaled: Vec<f64> = clean.iter().map(|&w| w / total * n as f64).collect();
        let mut keep = vec![1.0f32; n];
        let mut alias: Vec<u32> = (0..n as u32).collect();
        let (mut small, mut large): (Vec<usize>, Vec<usize>) =
            (0..n).partition(|&i| scaled[i] < 1.0);
        while let (Some(&s), Some(&l)) = (small.last(), large.last()) {
            small.pop();
            // Bin `s` keeps its own share and is topped up by the large item `l`.
            keep[s] = scaled[s] as f32;
            alias[s] = l as u32;
            scaled[l] -= 1.0 - scaled[s];
            if scaled[l] < 1.0 {
                large.pop();
                small.push(l);
            }
        }
        // Whatever is left is 1 up to rounding: those bins keep their item (an item of
        // weight zero left here by rounding is never kept, its bin goes to a neighbour).
        for i in small.into_iter().chain(large) {
            keep[i] = if clean[i] > 0.0 { 1.0 } else { 0.0 };
            if clean[i] <= 0.0 {
                alias[i] = clean.iter().position(|&w| w > 0.0).unwrap_or(0) as u32;
            }
        }
        AliasTable { keep, alias, pmf }
    }

    /// Number of items (0 when nothing can be chosen).
    pub fn len(&self) -> usize {
        self.pmf.len()
    }

    /// True when nothing can be chosen.
    pub fn is_empty(&self) -> bool {
        self.pmf.is_empty()
    }

    /// Probability of choosing item `index` (0 outside the table).
    #[inline]
    pub fn pmf(&self, index: usize) -> f32 {
        self.pmf.get(index).copied().unwrap_or(0.0)
    }

    /// The item the uniform number `u` in [0, 1) chooses, with its probability; `None` when
    /// nothing can be chosen. Values of `u` at or above 1 act as just below 1.
    #[inline]
    pub fn sample(&self, u: f32) -> Option<(usize, f32)> {
        let n = self.keep.len();
        if n == 0 {
            return None;
        }
        let scaled = u.clamp(0.0, 1.0) * n as f32;
        let bin = (scaled as usize).min(n - 1);
        let within = (scaled - bin as f32).clamp(0.0, 1.0);
        let index = if within < self.keep[bin] {
            bin
        } else {
            self.alias[bin] as usize
        };
        Some((index, self.pmf[index]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shading::bsdf::tests::Uniforms;

    #[test]
    fn frequencies_match_the_weights() {
        let table = AliasTable::new(&[1.0, 0.0, 3.0, 4.0, 0.5]);
        let total: f32 = (0..5).map(|i| table.pmf(i)).sum();
        assert!((total - 1.0).abs() < 1e-6);
        let mut u = Uniforms(5);
        let mut counts = [0usize; 5];
        let count = 170_000;
        for _ in 0..count {
            let (i, p) = table.sample(u.next()).expect("weights");
            assert_eq!(p, table.pmf(i));
            counts[i] += 1;
        }
        assert_eq!(counts[1], 0, "an item of weight zero was chosen");
        for i in [0, 2, 3, 4] {
            let share = counts[i] as f32 / count as f32;
            assert!((share - table.pmf(i)).abs() < 0.006, "{i}: {share}");
        }
    }

    #[test]
    fn a_stratified_sweep_gives_exact_frequencies() {
        // Each bin spans 1/n of [0, 1): a fine sweep reproduces the pmf to the sweep step.
        let weights = [2.0, 7.0, 1.0, 0.0, 6.0];
        let table = AliasTable::new(&weights);
        let steps = 100_000;
        let mut counts = [0usize; 5];
        for k in 0..steps {
            let u = (k as f32 + 0.5) / steps as f32;
            counts[table.sample(u).unwrap().0] += 1;
        }
        for i in 0..5 {
            let expected = weights[i] / 16.0;
            assert!(
                (counts[i] as f32 / steps as f32 - expected).abs() < 1e-3,
                "{i}"
            );
        }
        assert_eq!(table.sample(1.0).map(|s| s.1 > 0.0), Some(true));
    }

    #[test]
    fn nothing_to_choose_without_weight() {
        let table = AliasTable::new(&[0.0, -1.0, f32::NAN]);
        assert!(table.is_empty());
        assert_eq!(table.sample(0.3), None);
        assert_eq!(table.pmf(0), 0.0);
    }
}
