//! Light of a colour temperature (Blender's `use_temperature`), and the spectrum of every light.
//!
//! A light's spectrum ([`Illuminant`]) is its colour's smooth spectrum times the white it is a
//! colour of: D65, or, with a colour temperature, a black body's spectrum by Planck's law. Blender
//! tints the light by the black body's colour in linear Rec.709 at luminance 1 (as Cycles
//! normalises its blackbody colour: the temperature tints a light without changing its power);
//! Caustic renders the black body's own spectrum, scaled to that luminance, so that glass
//! disperses and media absorb its light by wavelength as they would a real lamp's.

use glam::{DVec3, Vec3, Vec4};

use super::rgb::RgbSpectrum;
use super::tables::{cmf, table_wavelengths, xyz_to_linear_rec709};
use super::wavelength::{SampledSpectrum, Wavelengths};

/// Planck's spectral radiance at `lambda_nm` for temperature `kelvin`, up to a constant factor.
fn planck(lambda_nm: f64, kelvin: f64) -> f64 {
    // The second radiation constant h c / k, in nm K.
    const C2: f64 = 1.438_776_877e7;
    let l = lambda_nm / 1000.0;
    1.0 / (l.powi(5) * ((C2 / (lambda_nm * kelvin)).exp_m1()))
}

/// The spectrum of a light: a colour's smooth spectrum ([`RgbSpectrum::illuminant`]) times D65,
/// or times a black body's spectrum scaled to the luminance of the colour times the black body's
/// colour (Blender's light colour with a temperature).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Illuminant {
    shape: RgbSpectrum,
    /// The black body's temperature, or 0 for D65.
    kelvin: f32,
    /// The factor on Planck's law.
    scale: f32,
}

impl Illuminant {
    /// Light of linear Rec.709 `colour` (W / (m^2 sr) or W / sr for white), white being D65.
    pub fn d65(colour: Vec3) -> Self {
        Illuminant { shape: RgbSpectrum::illuminant(colour), kelvin: 0.0, scale: 1.0 }
    }

    /// Light of `colour` from a black body at `kelvin`: as bright as Blender's `colour` times
    /// [`blackbody_colour`] (their luminances equal), of a black body's spectrum.
    pub fn blackbody(colour: Vec3, kelvin: f32) -> Self {
        let shape = RgbSpectrum::illuminant(colour);
        let kelvin = kelvin.max(1.0);
        let target = luminance_of(colour * blackbody_colour(kelvin));
        let unscaled: f64 = table_wavelengths()
            .map(|l| f64::from(shape.eval(l)) * planck(f64::from(l), f64::from(kelvin)) * f64::from(cmf(l).y))
            .sum();
        let scale = if unscaled > 0.0 { (target / unscaled) as f32 } else { 0.0 };
        Illuminant { shape, kelvin, scale }
    }

    /// Light of `colour`, from a black body at `kelvin` if given, else D65.
    pub fn new(colour: Vec3, kelvin: Option<f32>) -> Self {
        kelvin.map_or_else(|| Illuminant::d65(colour), |k| Illuminant::blackbody(colour, k))
    }

    /// Its value at the wavelengths `lambda`.
    pub fn eval(&self, lambda: &Wavelengths) -> SampledSpectrum {
        let shape = self.shape.eval_lanes(lambda.nm);
        if self.kelvin == 0.0 {
            return shape * lambda.d65;
        }
        let kelvin = f64::from(self.kelvin);
        let white = Vec4::from(lambda.nm.to_array().map(|l| planck(f64::from(l), kelvin) as f32));
        shape * white * self.scale
    }

    /// Its luminance Y (1 for white light of 1).
    pub fn luminance(&self) -> f64 {
        if self.kelvin == 0.0 {
            return self.shape.luminance();
        }
        let kelvin = f64::from(self.kelvin);
        table_wavelengths()
            .map(|l| {
                f64::from(self.shape.eval(l) * cmf(l).y)
                    * planck(f64::from(l), kelvin)
                    * f64::from(self.scale)
            })
            .sum()
    }
}

/// The luminance of a linear Rec.709 colour.
fn luminance_of(c: Vec3) -> f64 {
    f64::from(0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z)
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

    /// The colour of the spectrum a light of a colour temperature renders with: for white light,
    /// Blender's black body colour (it is that spectrum's colour), and the luminance Blender gives
    /// a coloured light times it.
    #[test]
    fn a_black_bodys_light_has_blenders_colour_and_luminance() {
        let colour_of = |light: &Illuminant| -> Vec3 {
            let xyz: DVec3 = table_wavelengths()
                .map(|l| {
                    let lambda = Wavelengths::single(l, 1.0);
                    cmf(l).as_dvec3() * f64::from(light.eval(&lambda).x)
                })
                .sum();
            xyz_to_linear_rec709(xyz).as_vec3()
        };
        for kelvin in [2700.0, 4000.0, 9000.0] {
            let white = colour_of(&Illuminant::blackbody(Vec3::splat(2.0), kelvin));
            let expected = 2.0 * blackbody_colour(kelvin);
            assert!(
                (white - expected).abs().max_element() < 2e-3 * 2.0,
                "{kelvin} K: {white} against {expected}"
            );
        }
        let tinted = Illuminant::blackbody(Vec3::new(1.0, 0.5, 0.2), 3000.0);
        let expected = luminance_of(Vec3::new(1.0, 0.5, 0.2) * blackbody_colour(3000.0));
        assert!(
            (tinted.luminance() / expected - 1.0).abs() < 1e-4,
            "{} against {expected}",
            tinted.luminance()
        );
    }
}
