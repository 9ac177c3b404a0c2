//! Importance sampling of wavelengths toward the visible range.
//!
//! The density `p(lambda) = 0.0039398042 / cosh^2(0.0072 (lambda - 538))` on 360..830 nm roughly
//! follows the sum of the colour-matching functions (Radziszewski et al. 2009, as in pbrt-v4's
//! `SampleVisibleWavelengths`); its inverse CDF is closed form.

/// The wavelength for a uniform number `u` in [0, 1), with its density per nanometre.
pub fn sample_visible_wavelength(u: f32) -> (f32, f32) {
    let lambda_nm = 538.0 - 138.888_89 * (0.856_910_6 - 1.827_502 * u).atanh();
    let lambda_nm = lambda_nm.clamp(360.0, 830.0);
    (lambda_nm, visible_wavelength_pdf(lambda_nm))
}

/// The density of [`sample_visible_wavelength`] at `lambda_nm`.
pub fn visible_wavelength_pdf(lambda_nm: f32) -> f32 {
    if !(360.0..=830.0).contains(&lambda_nm) {
        return 0.0;
    }
    0.003_939_804_2 / (0.0072 * (lambda_nm - 538.0)).cosh().powi(2)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn density_integrates_to_one_and_matches_samples() {
        let integral: f32 = (0..47000).map(|i| visible_wavelength_pdf(360.0 + i as f32 * 0.01) * 0.01).sum();
        assert!((integral - 1.0).abs() < 2e-3, "{integral}");
        // The fraction of uniform u below 0.5 lands below the median of p.
        let (median, _) = sample_visible_wavelength(0.5);
        let below: f32 = (0..((median - 360.0) * 100.0) as usize)
            .map(|i| visible_wavelength_pdf(360.0 + i as f32 * 0.01) * 0.01)
            .sum();
        assert!((below - 0.5).abs() < 2e-3, "{below}");
    }
}
