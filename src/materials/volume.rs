//! What fills a transmissive material, or the world: a homogeneous medium that absorbs and may
//! scatter.
//!
//! Absorption comes either from `KHR_materials_volume`, by Beer–Lambert's law: light that travels
//! a distance `d` inside keeps `attenuationColor^(d / attenuationDistance)` of itself at each
//! wavelength (the colour upsampled to a reflectance spectrum `c(λ)`, the coefficient
//! `-ln c(λ) / attenuationDistance`); or from a `caustic` medium's coefficients per world unit,
//! upsampled as smooth spectra whose colour under D65 is the RGB given. A medium that scatters
//! has a scattering coefficient too, and a Henyey–Greenstein anisotropy (`phase.rs`). Inside a
//! closed mesh the path's own segments give the distances (`sppm/media.rs` keeps the stack of
//! volumes a path is in); through a thin wall (an open mesh) the thickness factor does, over the
//! cosine of the crossing, and only absorption counts there.

use glam::{Vec3, Vec4};

use crate::spectrum::{RgbSpectrum, SampledSpectrum, Wavelengths};

/// Attenuation colours are kept above this, so that a black one absorbs strongly but finitely.
const DARKEST: f32 = 1e-6;

/// A homogeneous medium.
#[derive(Clone, Debug)]
pub struct Volume {
    absorption: Absorption,
    scattering: Option<Scattering>,
    /// `thicknessFactor`: the wall's thickness where the mesh is open.
    pub thickness: f32,
}

/// How a volume absorbs.
#[derive(Clone, Debug)]
enum Absorption {
    /// `KHR_materials_volume`'s attenuation colour (a reflectance spectrum) reached at `distance`
    /// (positive, finite).
    Attenuation { colour: RgbSpectrum, distance: f32 },
    /// A coefficient per world unit (grey: the same at every wavelength).
    Coefficient(RgbSpectrum),
}

impl Absorption {
    /// Absorption of the coefficient `rgb` per world unit (each at least 0), as the transmittance
    /// it gives over the length at which its strongest channel keeps 1/e, upsampled as a
    /// reflectance and taken back to a coefficient: light through that length keeps the colour
    /// per-channel Beer-Lambert gives (as Cycles absorbs), and near it nearly so. Upsampling the
    /// coefficient itself kept the colour of neither (a tinted slab passed 11% too much blue).
    fn of_coefficient(rgb: Vec3) -> Self {
        let strongest = rgb.max_element();
        if !(strongest > 0.0) || rgb.max_element() - rgb.min_element() <= 1e-6 * strongest {
            return Absorption::Coefficient(RgbSpectrum::constant(strongest.max(0.0)));
        }
        let distance = 1.0 / strongest;
        let colour = (-rgb * distance).exp();
        Absorption::Attenuation { colour: RgbSpectrum::reflectance(colour), distance }
    }
}

/// How a volume scatters.
#[derive(Clone, Debug)]
struct Scattering {
    /// The coefficient per world unit.
    coefficient: RgbSpectrum,
    /// Henyey–Greenstein's `g`, in (-1, 1).
    anisotropy: f32,
}

impl Volume {
    /// The volume of attenuation colour `colour` (linear, in [0, 1]) at `distance` (positive) and
    /// `thickness` (non-negative); the caller checks the values.
    pub fn new(colour: Vec3, distance: f32, thickness: f32) -> Self {
        let colour = RgbSpectrum::reflectance(colour);
        Volume { absorption: Absorption::Attenuation { colour, distance }, scattering: None, thickness }
    }

    /// The medium of absorption and scattering coefficients `absorption` and `scattering` (per
    /// world unit, linear RGB, each at least 0) and Henyey–Greenstein anisotropy `anisotropy` (in
    /// (-1, 1)); the caller checks the values.
    pub fn medium(absorption: Vec3, scattering: Vec3, anisotropy: f32, thickness: f32) -> Self {
        let scattering = (scattering.max_element() > 0.0)
            .then(|| Scattering { coefficient: RgbSpectrum::illuminant(scattering), anisotropy });
        Volume { absorption: Absorption::of_coefficient(absorption), scattering, thickness }
    }

    /// The absorption coefficient at the wavelengths `lambda`, per world unit.
    pub fn absorption(&self, lambda: &Wavelengths) -> SampledSpectrum {
        match &self.absorption {
            Absorption::Attenuation { colour, distance } => {
                let colour = colour.eval_lanes(lambda.nm).clamp(Vec4::splat(DARKEST), Vec4::ONE);
                -colour.ln() / *distance
            }
            Absorption::Coefficient(coefficient) => coefficient.eval_lanes(lambda.nm).max(Vec4::ZERO),
        }
    }

    /// The scattering coefficient at `lambda` and the anisotropy, where the volume scatters.
    pub fn scattering(&self, lambda: &Wavelengths) -> Option<(SampledSpectrum, f32)> {
        let s = self.scattering.as_ref()?;
        Some((s.coefficient.eval_lanes(lambda.nm).max(Vec4::ZERO), s.anisotropy))
    }

    /// Whether it scatters light (else it only absorbs).
    pub fn scatters(&self) -> bool {
        self.scattering.is_some()
    }

    /// The extinction coefficient (absorption plus scattering) at `lambda`, per world unit.
    pub fn extinction(&self, lambda: &Wavelengths) -> SampledSpectrum {
        self.absorption(lambda) + self.scattering(lambda).map_or(Vec4::ZERO, |(s, _)| s)
    }

    /// The share of light at `lambda` that travels `length` through it unabsorbed and unscattered
    /// (0 at an infinite length where anything is absorbed or scattered).
    pub fn transmittance(&self, lambda: &Wavelengths, length: f32) -> SampledSpectrum {
        transmittance(self.extinction(lambda), length)
    }
}

/// `exp(-coefficient * length)`, with an infinite length taking all (where the coefficient is
/// positive) or nothing (where it is 0) rather than giving NaN.
pub fn transmittance(coefficient: SampledSpectrum, length: f32) -> SampledSpectrum {
    if length.is_finite() {
        (-coefficient * length).exp()
    } else {
        Vec4::select(coefficient.cmpgt(Vec4::ZERO), Vec4::ZERO, Vec4::ONE)
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

    #[test]
    fn a_medium_takes_what_it_absorbs_and_scatters() {
        let lambda = Wavelengths::sampled(0.3);
        let grey = Volume::medium(Vec3::splat(0.5), Vec3::splat(1.5), 0.3, 0.0);
        let through = grey.transmittance(&lambda, 2.0);
        assert!((through - Vec4::splat((-4.0f32).exp())).abs().max_element() < 1e-5, "{through}");
        let (scattering, g) = grey.scattering(&lambda).unwrap();
        assert!((scattering - Vec4::splat(1.5)).abs().max_element() < 1e-4 && g == 0.3, "{scattering}");
        let clear = Volume::medium(Vec3::splat(0.2), Vec3::ZERO, 0.0, 0.0);
        assert!(!clear.scatters() && clear.scattering(&lambda).is_none());
        let blue = Volume::medium(Vec3::ZERO, Vec3::new(0.0, 0.0, 4.0), 0.0, 0.0);
        let lambda = Wavelengths { nm: Vec4::new(450.0, 530.0, 610.0, 650.0), ..lambda };
        let (s, _) = blue.scattering(&lambda).unwrap();
        assert!(s.x > 1.0 && s.z < 0.5 * s.x, "blue fog scatters blue most: {s}");
    }

    /// The colour (under D65) of white light through `volume` over `length`.
    fn colour_through(volume: &Volume, length: f32) -> Vec3 {
        crate::spectrum::rgb::colour_under_d65_of(|nm| {
            let lambda = Wavelengths { nm: Vec4::splat(nm), ..Wavelengths::sampled(0.5) };
            volume.transmittance(&lambda, length).x
        })
    }

    /// A medium's absorption passes the colour per-channel Beer-Lambert gives (Cycles' absorption):
    /// within 0.1% per channel at the length where its strongest channel keeps 1/e, and within
    /// 1.5% from a quarter of that length up, on absorptions across the gamut (the slab of a
    /// Volume Absorption of colour (0.85, 0.55, 0.25) and density 8 among them: 11% too much blue
    /// came through it before). Beyond that length one spectrum drifts from per-channel
    /// Beer-Lambert, because Rec.709's channels overlap in wavelength: at twice it by up to 18% in
    /// a channel that keeps under 2% of the light, at four times by more.
    #[test]
    fn absorption_keeps_the_colour_per_channel_beer_lambert_gives() {
        let absorptions = [
            Vec3::new(1.2, 3.6, 6.0),
            Vec3::new(0.5, 1.0, 2.0),
            Vec3::new(2.0, 0.7, 0.4),
            Vec3::new(0.4, 0.3, 1.0),
            Vec3::new(1.0, 2.0, 1.0),
        ];
        for absorption in absorptions {
            let volume = Volume::medium(absorption, Vec3::ZERO, 0.0, 0.0);
            let reference = 1.0 / absorption.max_element();
            for (scale, tolerance) in [(0.25, 0.015), (0.5, 0.015), (1.0, 0.001)] {
                let length = scale * reference;
                let got = colour_through(&volume, length);
                let want = (-absorption * length).exp();
                let off = (got / want - Vec3::ONE).abs().max_element();
                assert!(
                    off < tolerance,
                    "{absorption} over {length}: {got}, Beer-Lambert {want} ({off:.3} off)"
                );
            }
        }
    }
}
