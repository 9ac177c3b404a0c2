//! The CIE tables from `spectra/`, baked at 1 nm by `spectra/build.rs`.
//!
//! `d65` is normalised to luminance 1 (its integral against y-bar is 1), and the XYZ to Rec.709
//! matrix maps that D65 to exactly (1, 1, 1): a white light of radiance 1 renders as RGB 1.

use glam::{DVec3, Vec3};

/// The tables as `spectra/build.rs` wrote them (generated code, digits as the sources give them).
#[allow(clippy::excessive_precision)]
mod baked {
    include!(concat!(env!("OUT_DIR"), "/tables.rs"));
}
pub use baked::*;

/// Linear interpolation in a 1 nm table starting at `LAMBDA_MIN_NM`; zero outside the range.
fn lookup(table: &[f32], lambda_nm: f32) -> f32 {
    let x = lambda_nm - LAMBDA_MIN_NM;
    if !(0.0..=(table.len() - 1) as f32).contains(&x) {
        return 0.0;
    }
    let i = (x as usize).min(table.len() - 2);
    let t = x - i as f32;
    table[i] + t * (table[i + 1] - table[i])
}

/// The CIE 1931 2-degree colour-matching functions (x-bar, y-bar, z-bar) at `lambda_nm`.
pub fn cmf(lambda_nm: f32) -> Vec3 {
    Vec3::new(lookup(&CIE_X, lambda_nm), lookup(&CIE_Y, lambda_nm), lookup(&CIE_Z, lambda_nm))
}

/// CIE illuminant D65 at `lambda_nm`, normalised to luminance 1.
pub fn d65(lambda_nm: f32) -> f32 {
    lookup(&D65_NORMALISED, lambda_nm)
}

/// XYZ to linear Rec.709 RGB (white D65, with D65 mapping to exactly 1, 1, 1).
pub fn xyz_to_linear_rec709(xyz: DVec3) -> DVec3 {
    let m = XYZ_TO_LINEAR_REC709.map(f64::from);
    DVec3::new(
        m[0] * xyz.x + m[1] * xyz.y + m[2] * xyz.z,
        m[3] * xyz.x + m[4] * xyz.y + m[5] * xyz.z,
        m[6] * xyz.x + m[7] * xyz.y + m[8] * xyz.z,
    )
}

/// Linear Rec.709 RGB to XYZ (the inverse of [`xyz_to_linear_rec709`]).
pub fn linear_rec709_to_xyz(rgb: DVec3) -> DVec3 {
    let columns = [DVec3::X, DVec3::Y, DVec3::Z].map(xyz_to_linear_rec709);
    glam::DMat3::from_cols(columns[0], columns[1], columns[2]).inverse() * rgb
}

/// The XYZ of the normalised D65 (its integral against the colour-matching functions).
pub fn d65_xyz() -> DVec3 {
    table_wavelengths().map(|l| (cmf(l) * d65(l)).as_dvec3()).sum()
}

/// The wavelengths of the baked tables, one per nanometre.
pub fn table_wavelengths() -> impl Iterator<Item = f32> {
    (0..CIE_Y.len()).map(|i| LAMBDA_MIN_NM + i as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn d65_is_white_with_luminance_one() {
        let xyz = d65_xyz();
        assert!((xyz.y - 1.0).abs() < 1e-4, "Y = {}", xyz.y);
        let rgb = xyz_to_linear_rec709(xyz);
        assert!((rgb - DVec3::ONE).abs().max_element() < 1e-4, "{rgb}");
    }

    #[test]
    fn y_bar_integrates_to_its_published_value() {
        // The CIE's 1 nm table of y-bar sums to 106.856895 (CIE 015:2018).
        let sum: f64 = CIE_Y.iter().map(|&y| f64::from(y)).sum();
        assert!((sum - 106.856895).abs() < 1e-4, "{sum}");
    }

    #[test]
    fn y_bar_peaks_at_555_nm() {
        assert!((cmf(555.0).y - 1.0).abs() < 1e-3);
        assert_eq!(cmf(200.0), Vec3::ZERO);
    }
}
