//! The global radius sequence of Knaus & Zwicker 2011 ("Progressive Photon Mapping: A
//! Probabilistic Approach", equation 15):
//! `r_i^2 = r_1^2 * prod_{k=1..i-1} ((k + alpha) / k) / i`.
//!
//! The product is `Gamma(i + alpha) / (Gamma(1 + alpha) Gamma(i))`, so
//! `ln r_i^2 = ln r_1^2 + lnGamma(i + alpha) - lnGamma(1 + alpha) - lnGamma(i + 1)`, evaluated in
//! f64: it depends only on the pass index (passes stay independent and mergeable), costs O(1) for
//! any i, and shrinks like i^(alpha - 1), so it never underflows (r_i^2 / r_1^2 is about 5e-3 at
//! i = 10^7 with alpha = 2/3, and about 1e-7 with alpha = 0.01).
//!
//! For large i the two log-gammas are each near 1.6e8 at i = 10^7 while their difference changes
//! by only (1 - alpha) / i per pass, below f64's resolution of them; so past `STIRLING_FROM` the
//! difference is taken from Stirling's series with `ln_1p`, which keeps every term O(1).

/// Passes from which `ln Gamma(i + alpha) - ln Gamma(i + 1)` comes from Stirling's series.
const STIRLING_FROM: f64 = 64.0;

/// `ln Gamma(i + alpha) - ln Gamma(i + 1)`, accurate to f64 precision for every i >= 1.
fn log_gamma_ratio(i: f64, alpha: f64) -> f64 {
    if i < STIRLING_FROM {
        return libm::lgamma(i + alpha) - libm::lgamma(i + 1.0);
    }
    // ln Gamma(z) = (z - 1/2) ln z - z + ln(2 pi) / 2 + 1 / (12 z) - 1 / (360 z^3) + O(z^-5),
    // with ln(i + a) written as ln i + ln_1p(a / i) so that the large terms cancel exactly.
    let series = |z: f64| 1.0 / (12.0 * z) - 1.0 / (360.0 * z * z * z);
    (alpha - 1.0) * i.ln() + (i + alpha - 0.5) * (alpha / i).ln_1p()
        - (i + 0.5) * (1.0 / i).ln_1p()
        - (alpha - 1.0)
        + series(i + alpha)
        - series(i + 1.0)
}

/// The squared radius of pass `i` (1-based) from the first pass's squared radius.
pub fn radius_squared(r1_squared: f64, alpha: f64, i: u64) -> f64 {
    let i = i.max(1) as f64;
    (r1_squared.ln() + log_gamma_ratio(i, alpha) - libm::lgamma(1.0 + alpha)).exp()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_the_running_product() {
        let alpha = 2.0 / 3.0;
        let mut product = 1.0f64;
        for i in 1..=100_000u64 {
            if i > 1 {
                product *= ((i - 1) as f64 + alpha) / (i - 1) as f64;
            }
            let expected = 0.25 * product / i as f64;
            let got = radius_squared(0.25, alpha, i);
            assert!((got / expected - 1.0).abs() < 1e-10, "pass {i}: {got} vs {expected}");
        }
    }

    #[test]
    fn never_underflows() {
        for alpha in [0.01, 2.0 / 3.0, 0.99] {
            let r2 = radius_squared(1e-6, alpha, 10_000_000);
            assert!(r2 > 0.0 && r2.is_finite() && (r2 as f32) > 0.0, "alpha {alpha}: {r2}");
            assert!(r2 < radius_squared(1e-6, alpha, 9_999_999));
        }
    }
}
