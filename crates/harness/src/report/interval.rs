//! Confidence intervals for the ratios a run reports. Each round of a run times every
//! structure once (see `pipeline/rounds.rs`), so a structure's ratio to the reference is
//! measured once per round, and the reported ratio is the median of those. Its interval is the
//! distribution-free one for a median (the sign test inverted): with `n` ratios sorted,
//! `[x(k), x(n + 1 - k)]` holds the true median with probability
//! `1 - 2 P(Binomial(n, 1/2) < k)`, whatever the distribution of the noise, as long as rounds
//! are independent. `k` is the largest giving at least [`TARGET_LEVEL`]; with five rounds or
//! fewer no `k` reaches it, and the interval is then the full range with the level it has
//! (93.75 % for five rounds), which the report records. No bootstrap: its resampled medians
//! of so few rounds take only a handful of values, and the order-statistic interval is exact.

use serde::{Deserialize, Serialize};

/// The coverage an interval aims for.
pub const TARGET_LEVEL: f64 = 0.95;

/// A confidence interval for a median.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Interval {
    pub lo: f64,
    pub hi: f64,
    /// The probability that the interval holds the true median (0.9375 for five rounds,
    /// at least [`TARGET_LEVEL`] from six on).
    pub level: f64,
}

impl Interval {
    /// Whether `x` lies inside (bounds included).
    pub fn contains(&self, x: f64) -> bool {
        self.lo <= x && x <= self.hi
    }

    /// Half the width relative to `centre`, e.g. 0.03 for ±3 %.
    pub fn relative_half_width(&self, centre: f64) -> f64 {
        if centre > 0.0 {
            (self.hi - self.lo) / 2.0 / centre
        } else {
            f64::INFINITY
        }
    }
}

/// The median of `samples` and its interval; `None` for the interval with fewer than two
/// samples (or any that is not finite), `None` for both when there are none.
pub fn median_with_interval(samples: &[f64]) -> Option<(f64, Option<Interval>)> {
    if samples.is_empty() {
        return None;
    }
    let mut s = samples.to_vec();
    s.sort_by(f64::total_cmp);
    let n = s.len();
    let median = if n.is_multiple_of(2) {
        (s[n / 2 - 1] + s[n / 2]) / 2.0
    } else {
        s[n / 2]
    };
    if n < 2 || s.iter().any(|x| !x.is_finite()) {
        return Some((median, None));
    }
    let (k, level) = order_statistic(n);
    Some((
        median,
        Some(Interval {
            lo: s[k - 1],
            hi: s[n - k],
            level,
        }),
    ))
}

/// Per-round ratios `a[i] / b[i]` over the rounds both have (a sample list of one pass is a
/// structure timed once, in the first round).
pub fn paired_ratios(a: &[f64], b: &[f64]) -> Vec<f64> {
    a.iter()
        .zip(b)
        .filter(|(_, y)| **y > 0.0)
        .map(|(x, y)| x / y)
        .collect()
}

/// The 1-based rank `k` of the interval's lower end for `n` samples, and its coverage.
fn order_statistic(n: usize) -> (usize, f64) {
    // P(Binomial(n, 1/2) = i) in log space: 0.5^n underflows past n = 1074.
    let ln_half_n = -(n as f64) * std::f64::consts::LN_2;
    let mut ln_p = ln_half_n; // i = 0
    let mut below = 0.0; // P(B < k)
    let mut best = (1, 1.0 - 2.0 * ln_half_n.exp());
    for k in 1..=n.div_ceil(2) {
        below += ln_p.exp(); // now P(B < k)
        let level = 1.0 - 2.0 * below;
        if level < TARGET_LEVEL {
            break;
        }
        best = (k, level);
        ln_p += ((n - (k - 1)) as f64 / k as f64).ln(); // P(B = k)
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn five_rounds_give_the_full_range_at_93_75_percent() {
        let (m, i) = median_with_interval(&[1.3, 1.0, 1.2, 0.9, 1.1]).unwrap();
        assert_eq!(m, 1.1);
        let i = i.unwrap();
        assert_eq!((i.lo, i.hi), (0.9, 1.3));
        assert!((i.level - 0.9375).abs() < 1e-12);
    }

    #[test]
    fn more_rounds_narrow_the_ranks_and_keep_the_level() {
        // n = 6: k = 1 (96.9 %); n = 9: k = 2 (96.1 %); n = 20: k = 6 (95.9 %).
        for (n, k, level) in [(6, 1, 0.96875), (9, 2, 0.9609375), (20, 6, 0.9586105)] {
            let samples: Vec<f64> = (1..=n).map(|x| x as f64).collect();
            let (_, i) = median_with_interval(&samples).unwrap();
            let i = i.unwrap();
            assert_eq!(i.lo, k as f64, "n = {n}");
            assert_eq!(i.hi, (n + 1 - k) as f64, "n = {n}");
            assert!((i.level - level).abs() < 1e-6, "n = {n}: {}", i.level);
            assert!(i.level >= TARGET_LEVEL || n <= 5);
        }
    }

    #[test]
    fn a_thousand_rounds_do_not_underflow() {
        let samples: Vec<f64> = (0..1000).map(|x| x as f64).collect();
        let (_, i) = median_with_interval(&samples).unwrap();
        let i = i.unwrap();
        // The normal approximation: 500 ± 1.96 × sqrt(1000) / 2 ≈ 500 ± 31.
        assert!((465.0..=471.0).contains(&i.lo), "{i:?}");
        assert!(i.level >= TARGET_LEVEL && i.level < 0.96, "{i:?}");
    }

    #[test]
    fn one_sample_has_no_interval() {
        assert_eq!(median_with_interval(&[2.0]), Some((2.0, None)));
        assert_eq!(median_with_interval(&[]), None);
        assert_eq!(paired_ratios(&[2.0, 3.0, 4.0], &[1.0, 0.0]), vec![2.0]);
    }
}
