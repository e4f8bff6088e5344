//! Short numbers for axis ticks and chart labels: 1k, 10k, 4.1k, 1M, 1e-5, 0.1, 0.25, 12.
//!
//! Three significant digits at most, trailing zeros dropped, a k/M/G/T suffix from a thousand
//! up, and `1e-5` notation below 0.01 (where "0.00001" is hard to count) and from 10^15 up.

/// `v` as a tick label (see the module comment). Rounding is decimal and correct, because it
/// is done by Rust's `{:e}` formatting, not by scaling floats.
pub fn tick_label(v: f64) -> String {
    if v.is_nan() {
        return "NaN".into();
    }
    if v.is_infinite() {
        return if v > 0.0 { "∞" } else { "-∞" }.into();
    }
    if v == 0.0 {
        return "0".into();
    }
    if v < 0.0 {
        return format!("-{}", tick_label(-v));
    }
    // "1.23e4": three significant digits and the decimal exponent, rounded once.
    let sci = format!("{v:.2e}");
    let (mantissa, exp) = sci
        .split_once('e')
        .expect("`{:e}` always writes an exponent");
    let exp: i32 = exp.parse().expect("`{:e}` writes an integer exponent");
    let digits: String = mantissa.chars().filter(char::is_ascii_digit).collect();
    if !(-2..15).contains(&exp) {
        return format!("{}e{exp}", place_point(&digits, 0));
    }
    if exp >= 3 {
        let suffix = ["k", "M", "G", "T"][(exp / 3 - 1) as usize];
        return format!("{}{suffix}", place_point(&digits, exp % 3));
    }
    place_point(&digits, exp)
}

/// Tick values for an axis from `lo` to `hi` (both ends positive on a log axis): decades on a
/// log axis spanning three or more (thinned to at most ten), 1–2–5 in each decade over one or
/// more, and otherwise evenly spaced round values (steps of 1, 2, 2.5 or 5 times a power of
/// ten, about eight of them), as on a linear axis.
pub fn axis_ticks(lo: f64, hi: f64, log: bool) -> Vec<f64> {
    if !(lo.is_finite() && hi.is_finite() && lo < hi) || (log && lo <= 0.0) {
        return Vec::new();
    }
    let inside = |v: &f64| *v >= lo * (1.0 - 1e-9) && *v <= hi * (1.0 + 1e-9);
    if log {
        let decades = (hi / lo).log10();
        let (d0, d1) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
        if decades >= 3.0 {
            let powers: Vec<f64> = (d0..=d1).map(|d| 10f64.powi(d)).filter(inside).collect();
            let step = powers.len().div_ceil(10).max(1);
            return powers.into_iter().step_by(step).collect();
        }
        if decades >= 1.0 {
            return (d0..=d1)
                .flat_map(|d| [1.0, 2.0, 5.0].map(|m| m * 10f64.powi(d)))
                .filter(inside)
                .collect();
        }
    }
    let raw = (hi - lo) / 8.0;
    let magnitude = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 2.5, 5.0, 10.0]
        .iter()
        .map(|m| m * magnitude)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * magnitude);
    let first = (lo / step).ceil();
    let last = (hi / step).floor();
    // A span too small for f64 to step through (subnormal ends) gets no ticks, not a loop
    // over billions.
    if !(step > 0.0 && first.is_finite() && last.is_finite() && last - first <= 100.0) {
        return Vec::new();
    }
    (first as i64..=last as i64)
        .map(|k| k as f64 * step)
        .filter(|v| !log || *v > 0.0)
        .collect()
}

/// The three `digits` of a number whose first digit stands for 10^`exp` (`exp` ≥ -2, ≤ 2),
/// written plainly with trailing zeros after the point removed: ("123", 1) → "12.3".
fn place_point(digits: &str, exp: i32) -> String {
    let (int, frac) = if exp >= 0 {
        let split = (exp as usize + 1).min(digits.len());
        (digits[..split].to_string(), digits[split..].to_string())
    } else {
        let zeros = "0".repeat((-exp - 1) as usize);
        ("0".to_string(), format!("{zeros}{digits}"))
    };
    let frac = frac.trim_end_matches('0');
    if frac.is_empty() {
        int
    } else {
        format!("{int}.{frac}")
    }
}

/// `12345678` → `12,345,678`.
pub(crate) fn thousands(v: u64) -> String {
    let digits = v.to_string();
    let mut out = String::new();
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(c);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::{axis_ticks, thousands, tick_label};

    fn labels(lo: f64, hi: f64, log: bool) -> Vec<String> {
        axis_ticks(lo, hi, log)
            .into_iter()
            .map(tick_label)
            .collect()
    }

    #[test]
    fn a_log_axis_over_many_decades_ticks_at_powers_of_ten() {
        assert_eq!(
            labels(5e-6, 0.2, true),
            ["1e-5", "1e-4", "1e-3", "0.01", "0.1"]
        );
        assert_eq!(labels(700.0, 6e6, true), ["1k", "10k", "100k", "1M"]);
        let many = axis_ticks(1e-30, 1e30, true);
        assert!(many.len() <= 10 && many.len() >= 8, "{many:?}");
    }

    #[test]
    fn a_log_axis_over_one_or_two_decades_ticks_at_1_2_5() {
        assert_eq!(labels(15.0, 700.0, true), ["20", "50", "100", "200", "500"]);
    }

    #[test]
    fn a_narrow_axis_ticks_at_round_steps() {
        assert_eq!(
            labels(8.0, 24.0, true),
            ["8", "10", "12", "14", "16", "18", "20", "22", "24"]
        );
        assert_eq!(
            labels(0.0, 1.0, false),
            ["0", "0.2", "0.4", "0.6", "0.8", "1"]
        );
        assert!(axis_ticks(1.0, 1.0, true).is_empty());
        assert!(axis_ticks(0.0, 1.0, true).is_empty());
        assert!(axis_ticks(0.0, 5e-324, false).is_empty());
        assert!(axis_ticks(1.0, 1.0 + f64::EPSILON, false).len() <= 9);
    }

    #[test]
    fn whole_numbers_group_their_thousands() {
        assert_eq!(thousands(0), "0");
        assert_eq!(thousands(999), "999");
        assert_eq!(thousands(1000), "1,000");
        assert_eq!(thousands(12_345_678), "12,345,678");
    }

    #[test]
    fn thousands_and_millions_take_a_suffix() {
        assert_eq!(tick_label(1000.0), "1k");
        assert_eq!(tick_label(10_000.0), "10k");
        assert_eq!(tick_label(1024.0), "1.02k");
        assert_eq!(tick_label(4096.0), "4.1k");
        assert_eq!(tick_label(262_144.0), "262k");
        assert_eq!(tick_label(1e6), "1M");
        assert_eq!(tick_label(4_194_304.0), "4.19M");
        assert_eq!(tick_label(2.5e9), "2.5G");
        assert_eq!(tick_label(1e12), "1T");
    }

    #[test]
    fn rounding_up_moves_to_the_next_suffix() {
        assert_eq!(tick_label(999.6), "1k");
        assert_eq!(tick_label(999_999.0), "1M");
        assert_eq!(tick_label(9.996), "10");
    }

    #[test]
    fn small_numbers_are_plain_down_to_a_hundredth_then_scientific() {
        assert_eq!(tick_label(0.1), "0.1");
        assert_eq!(tick_label(0.25), "0.25");
        assert_eq!(tick_label(0.01), "0.01");
        assert_eq!(tick_label(0.0123), "0.0123");
        assert_eq!(tick_label(0.001), "1e-3");
        assert_eq!(tick_label(0.0025), "2.5e-3");
        assert_eq!(tick_label(1e-5), "1e-5");
        assert_eq!(tick_label(5e-324), "4.94e-324");
    }

    #[test]
    fn ordinary_numbers_keep_three_significant_digits() {
        assert_eq!(tick_label(0.0), "0");
        assert_eq!(tick_label(1.0), "1");
        assert_eq!(tick_label(12.0), "12");
        assert_eq!(tick_label(3.456), "3.46");
        assert_eq!(tick_label(123.4), "123");
        assert_eq!(tick_label(-0.5), "-0.5");
        assert_eq!(tick_label(-2000.0), "-2k");
    }

    #[test]
    fn huge_and_non_finite_values_still_have_a_label() {
        assert_eq!(tick_label(1e15), "1e15");
        assert_eq!(tick_label(1.7e308), "1.7e308");
        assert_eq!(tick_label(f64::INFINITY), "∞");
        assert_eq!(tick_label(f64::NAN), "NaN");
    }
}
