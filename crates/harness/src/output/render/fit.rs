//! The exponent `b` of a power law `y = a·N^b`, fitted by ordinary least squares on
//! `ln y = ln a + b·ln N`, with a 95 % confidence interval from the slope's standard error and
//! Student's t with n − 2 degrees of freedom. Theory for a ray query predicts `b ≈ 0` (log N:
//! trees on well-behaved scenes), 1/3 (a uniform grid's cells stepped along a ray) or 1 (brute
//! force); a size sweep says which one a structure follows.

/// A fitted exponent and the half-width of its 95 % confidence interval.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PowerFit {
    pub exponent: f64,
    /// `exponent ± half_width` covers the true exponent with 95 % confidence, if the
    /// residuals on the log–log scale are independent and normal.
    pub half_width: f64,
    /// Points the fit used.
    pub points: usize,
}

impl PowerFit {
    /// "0.33 ± 0.02" (a slope that rounds to zero is "0.00", never "-0.00").
    pub fn text(&self) -> String {
        let b = if self.exponent.abs() < 0.005 {
            0.0
        } else {
            self.exponent
        };
        format!("{b:.2} ± {:.2}", self.half_width)
    }
}

/// Fits `points` (N, y); points with a non-positive or non-finite coordinate are left out.
/// `None` with fewer than three usable points (no residual degree of freedom left to estimate
/// the error) or when every N is the same.
pub fn fit_power(points: &[(f64, f64)]) -> Option<PowerFit> {
    let logs: Vec<(f64, f64)> = points
        .iter()
        .filter(|&&(x, y)| x.is_finite() && y.is_finite() && x > 0.0 && y > 0.0)
        .map(|&(x, y)| (x.ln(), y.ln()))
        .collect();
    let n = logs.len();
    if n < 3 {
        return None;
    }
    let mean_x = logs.iter().map(|p| p.0).sum::<f64>() / n as f64;
    let mean_y = logs.iter().map(|p| p.1).sum::<f64>() / n as f64;
    let sxx: f64 = logs.iter().map(|p| (p.0 - mean_x).powi(2)).sum();
    if sxx <= 0.0 {
        return None;
    }
    let sxy: f64 = logs.iter().map(|p| (p.0 - mean_x) * (p.1 - mean_y)).sum();
    let slope = sxy / sxx;
    let intercept = mean_y - slope * mean_x;
    let ssr: f64 = logs
        .iter()
        .map(|p| (p.1 - intercept - slope * p.0).powi(2))
        .sum();
    let df = n - 2;
    let standard_error = (ssr / df as f64 / sxx).sqrt();
    Some(PowerFit {
        exponent: slope,
        half_width: student_t_975(df) * standard_error,
        points: n,
    })
}

/// The 97.5 % quantile of Student's t with `df` degrees of freedom (two-sided 95 %): the
/// table value up to 30, beyond that the Cornish–Fisher expansion around the normal quantile
/// (within 0.001 of the table from 30 on).
pub fn student_t_975(df: usize) -> f64 {
    const TABLE: [f64; 30] = [
        12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228, 2.201, 2.179, 2.160,
        2.145, 2.131, 2.120, 2.110, 2.101, 2.093, 2.086, 2.080, 2.074, 2.069, 2.064, 2.060, 2.056,
        2.052, 2.048, 2.045, 2.042,
    ];
    match df {
        0 => f64::INFINITY,
        1..=30 => TABLE[df - 1],
        _ => {
            let z: f64 = 1.959_964;
            let v = df as f64;
            z + (z.powi(3) + z) / (4.0 * v)
                + (5.0 * z.powi(5) + 16.0 * z.powi(3) + 3.0 * z) / (96.0 * v * v)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_exact_power_law_gives_its_exponent_and_no_uncertainty() {
        let pts: Vec<(f64, f64)> = [1e3, 4e3, 1.6e4, 6.4e4, 2.56e5]
            .iter()
            .map(|&n: &f64| (n, 7.0 * n.powf(1.0 / 3.0)))
            .collect();
        let fit = fit_power(&pts).unwrap();
        assert!((fit.exponent - 1.0 / 3.0).abs() < 1e-12, "{fit:?}");
        assert!(fit.half_width < 1e-6, "{fit:?}");
        assert_eq!(fit.points, 5);
        assert_eq!(fit.text(), "0.33 ± 0.00");
        let flat = fit_power(&[(1.0, 12.0), (10.0, 12.0), (100.0, 12.0)]).unwrap();
        assert_eq!(flat.text(), "0.00 ± 0.00");
    }

    /// ln y = 0, 1, 1, 3 at ln N = 0, 1, 2, 3: slope 0.9, intercept -0.1, residuals
    /// 0.1, 0.2, -0.7, 0.4, SSR 0.7, Sxx 5, se = sqrt(0.7 / 2 / 5), t(2) = 4.303.
    #[test]
    fn the_interval_is_the_slopes_standard_error_times_student_t() {
        let pts: Vec<(f64, f64)> = [(0.0, 0.0), (1.0, 1.0), (2.0, 1.0), (3.0, 3.0)]
            .iter()
            .map(|&(lx, ly): &(f64, f64)| (lx.exp(), ly.exp()))
            .collect();
        let fit = fit_power(&pts).unwrap();
        assert!((fit.exponent - 0.9).abs() < 1e-12, "{fit:?}");
        let expected = 4.303 * (0.7f64 / 2.0 / 5.0).sqrt();
        assert!((fit.half_width - expected).abs() < 1e-9, "{fit:?}");
    }

    #[test]
    fn too_few_or_degenerate_points_give_no_fit() {
        assert_eq!(fit_power(&[(1.0, 1.0), (10.0, 2.0)]), None);
        assert_eq!(fit_power(&[(5.0, 1.0), (5.0, 2.0), (5.0, 3.0)]), None);
        // A zero or NaN is left out, leaving two points.
        assert_eq!(
            fit_power(&[(1.0, 1.0), (10.0, 2.0), (100.0, 0.0), (f64::NAN, 1.0)]),
            None
        );
    }

    #[test]
    fn student_t_matches_the_table_and_tends_to_the_normal() {
        assert_eq!(student_t_975(1), 12.706);
        assert_eq!(student_t_975(5), 2.571);
        assert!((student_t_975(40) - 2.021).abs() < 1e-3);
        assert!((student_t_975(120) - 1.980).abs() < 1e-3);
        assert!((student_t_975(100_000) - 1.960).abs() < 1e-3);
        assert!(student_t_975(0).is_infinite());
    }
}
