//! Spectral bins (`--spectral-bins`), and the colour a single wavelength is shown in.

use glam::DVec3;

use crate::spectrum::{cmf, linear_rec709_to_xyz, xyz_to_linear_rec709, LAMBDA_MAX_NM, LAMBDA_MIN_NM};

/// The most spectral bins (5 nm wide over 360..830 nm, so their names stay distinct).
pub const MAX_SPECTRAL_BINS: usize = 94;

/// Per-pixel sums of spectral radiance in equal wavelength bands over 360..830 nm.
#[derive(Clone, Debug, Default)]
pub struct SpectralBins {
    /// Number of bands.
    pub count: usize,
    /// `count` sums per pixel, pixel-major.
    pub sums: Vec<f64>,
}

impl SpectralBins {
    pub(super) fn width_nm(&self) -> f64 {
        f64::from(LAMBDA_MAX_NM - LAMBDA_MIN_NM) / self.count as f64
    }

    /// The band holding `lambda_nm`.
    pub(super) fn band(&self, lambda_nm: f32) -> usize {
        (((f64::from(lambda_nm - LAMBDA_MIN_NM)) / self.width_nm()) as usize).min(self.count - 1)
    }

    /// The channel name of band `k`: its centre wavelength.
    pub fn channel_name(&self, k: usize) -> String {
        format!("Spectral.{:.0}nm", f64::from(LAMBDA_MIN_NM) + (k as f64 + 0.5) * self.width_nm())
    }
}

/// The XYZ, of luminance 1, of the colour shown for light of one wavelength: the spectral colour
/// with just enough white added to bring it into the Rec.709 gamut.
pub fn display_xyz(lambda_nm: f32) -> DVec3 {
    let xyz = cmf(lambda_nm).as_dvec3();
    if xyz.y <= 0.0 {
        return DVec3::ZERO;
    }
    let rgb = xyz_to_linear_rec709(xyz / xyz.y);
    let lowest = rgb.min_element().min(0.0);
    // Rec.709 (1, 1, 1) has luminance 1, so this keeps the luminance at 1.
    linear_rec709_to_xyz((rgb - DVec3::splat(lowest)) / (1.0 - lowest))
}
