//! Light of a colour temperature (Blender's `use_temperature`): the colour of a black body's
//! spectrum by Planck's law, integrated against the CIE 1931 colour-matching functions, in linear
//! Rec.709 with luminance 1 (as Cycles normalises its blackbody colour), so that a light's
//! temperature tints it without changing its power.

use glam::{DVec3, Vec3};

use super::tables::{cmf, table_wavelengths, xyz_to_linear_rec709};

/// Planck's spectral radiance at `lambda_nm` for temperature `kelvin`, up to a constant factor.
fn planck(lambda_nm: f64, kelvin: f64) -> f64 {
    // The second radiation constant h c / k, in nm K.
    const C2: f64 = 1.438_776_877e7;
    let l = lambda_nm / 1000.0;
    1.0 / (l.powi(5) * ((C2 / (lambda_nm * kelvin)).exp_m1()))
}

/// The linear Rec.709 colour of a black body at `kelvin` (above 0), of luminance 1.
pub fn blackbody_colour(kelvin: f32) -> Vec3 {
    let kelvin = f64::from(kelvin.max(1.0));
    let xyz: DVec3 = table_wavelengths().map(|l| cmf(l).as_dvec3() * planck(f64::from(l), kelvin)).sum();
    (xyz_to_linear_rec709(xyz) / xyz.y).as_vec3()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn warm_light_is_red_and_hot_light_is_blue_at_luminance_one() {
        let luminance = |c: Vec3| 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z;
        let warm = blackbody_colour(3000.0);
        assert!(warm.x > warm.y && warm.y > warm.z && (luminance(warm) - 1.0).abs() < 1e-3, "{warm}");
        let hot = blackbody_colour(12000.0);
        assert!(hot.z > hot.y && hot.y > hot.x, "{hot}");
        // Near D65's correlated colour temperature, nearly white.
        let white = blackbody_colour(6504.0);
        assert!((white - Vec3::ONE).abs().max_element() < 0.08, "{white}");
    }
}
