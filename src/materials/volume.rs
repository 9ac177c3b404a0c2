//! What fills a transmissive material: absorption by Beer–Lambert's law, as
//! `KHR_materials_volume` gives it. Light that travels a distance `d` inside keeps
//! `attenuationColor^(d / attenuationDistance)` of itself, at each wavelength: the colour is
//! upsampled to a reflectance spectrum `c(λ)` and the absorption coefficient is
//! `-ln c(λ) / attenuationDistance` (world units). Inside a closed mesh the path's own segments
//! give `d` (`sppm/media.rs` keeps the stack of volumes a path is in); through a thin wall (an
//! open mesh) the thickness factor does, over the cosine of the crossing.

use glam::{Vec3, Vec4};

use crate::spectrum::{RgbSpectrum, SampledSpectrum, Wavelengths};

/// Attenuation colours are kept above this, so that a black one absorbs strongly but finitely.
const DARKEST: f32 = 1e-6;

/// An absorbing volume.
#[derive(Clone, Debug)]
pub struct Volume {
    /// `attenuationColor` as a reflectance spectrum.
    colour: RgbSpectrum,
    /// `attenuationDistance`, world units (positive, finite).
    distance: f32,
    /// `thicknessFactor`: the wall's thickness where the mesh is open.
    pub thickness: f32,
}

impl Volume {
    /// The volume of attenuation colour `colour` (linear, in [0, 1]) at `distance` (positive) and
    /// `thickness` (non-negative); the caller checks the values.
    pub fn new(colour: Vec3, distance: f32, thickness: f32) -> Self {
        Volume { colour: RgbSpectrum::reflectance(colour), distance, thickness }
    }

    /// The absorption coefficient at the wavelengths `lambda`, per world unit.
    pub fn absorption(&self, lambda: &Wavelengths) -> SampledSpectrum {
        let colour = self.colour.eval_lanes(lambda.nm).clamp(Vec4::splat(DARKEST), Vec4::ONE);
        -colour.ln() / self.distance
    }

    /// The share of light at `lambda` that travels `length` through it (0 at an infinite length
    /// where anything is absorbed).
    pub fn transmittance(&self, lambda: &Wavelengths, length: f32) -> SampledSpectrum {
        transmittance(self.absorption(lambda), length)
    }
}

/// `exp(-absorption * length)`, with an infinite length absorbing all (where the coefficient is
/// positive) or nothing (where it is 0) rather than giving NaN.
pub fn transmittance(absorption: SampledSpectrum, length: f32) -> SampledSpectrum {
    if length.is_finite() {
        (-absorption * length).exp()
    } else {
        Vec4::select(absorption.cmpgt(Vec4::ZERO), Vec4::ZERO, Vec4::ONE)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_grey_volume_keeps_its_colour_to_the_power_of_distances_travelled() {
        let lambda = Wavelengths::sampled(0.3);
        let volume = Volume::new(Vec3::splat(0.25), 2.0, 0.0);
        let through = volume.transmittance(&lambda, 3.0);
        assert!((through - Vec4::splat(0.25f32.powf(1.5))).abs().max_element() < 1e-5, "{through}");
        let clear = Volume::new(Vec3::ONE, 1.0, 0.0);
        assert_eq!(clear.transmittance(&lambda, f32::INFINITY), Vec4::ONE);
        assert_eq!(volume.transmittance(&lambda, f32::INFINITY), Vec4::ZERO);
    }

    #[test]
    fn a_coloured_volume_absorbs_most_where_its_colour_is_darkest() {
        let lambda = Wavelengths { nm: Vec4::new(450.0, 530.0, 610.0, 650.0), ..Wavelengths::sampled(0.5) };
        let red = Volume::new(Vec3::new(0.9, 0.1, 0.1), 1.0, 0.0).transmittance(&lambda, 1.0);
        assert!(red.w > 0.7 && red.x < 0.2 && red.y < 0.2, "{red}");
    }
}
