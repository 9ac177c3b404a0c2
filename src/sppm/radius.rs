//! The global radius sequence of Knaus & Zwicker 2011 ("Progressive Photon Mapping: A
//! Probabilistic Approach", equation 15):
//! `r_i^2 = r_1^2 * prod_{k=1..i-1} ((k + alpha) / k) / i`.
//!
//! The product is `Gamma(i + alpha) / (Gamma(1 + alpha) Gamma(i))`, so
//! `ln r_i^2 = ln r_1^2 + lnGamma(i + alpha) - lnGamma(1 + alpha) - lnGamma(i + 1)`, evaluated in
//! f64: it depends only on the pass index (passes stay independent and mergeable), costs O(1) for
//! any i, and shrinks like i^(alpha - 1), so it never underflows (r_i^2 / r_1^2 is about 5e-3 at
//! i = 10^7 with alpha = 2/3, and about 1e-7 with alpha = 0.01).

/// The squared radius of pass `i` (1-based) from the first pass's squared radius.
pub fn radius_squared(r1_squared: f64, alpha: f64, i: u64) -> f64 {
    let i = i.max(1) as f64;
    let ln = r1_squared.ln() + libm::lgamma(i + alpha) - libm::lgamma(1.0 + alpha) - libm::lgamma(i + 1.0);
    ln.exp()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_the_running_product() {
        let alpha = 2.0 / 3.0;
        let mut product = 1.0f64;
        for i in 1..=2000u64 {
            if i > 1 {
                product *= ((i - 1) as f64 + alpha) / (i - 1) as f64;
            }
            let expected = 0.25 * product / i as f64;
            let got = radius_squared(0.25, alpha, i);
            assert!((got / expected - 1.0).abs() < 1e-9, "pass {i}: {got} vs {expected}");
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
