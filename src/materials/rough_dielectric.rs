//! A rough dielectric boundary (frosted glass, rough water): GGX microfacet reflection and
//! transmission (Walter et al. 2007, "Microfacet models for refraction through rough surfaces"),
//! sampled by visible normals (Heitz 2018), as Cycles' Principled BSDF renders a transmissive
//! material with roughness.
//!
//! The lobe is worked in the frame of the shading normal turned to the side `wo` is on (which
//! side that is, the geometric normal decides, as for the smooth boundary in `dielectric.rs`), with
//! `eta` the index of the far side over the near one. A sampled microfacet reflects with its
//! Fresnel reflectance's probability and refracts otherwise, so both weights are `G2 / G1(wo)`,
//! refraction's scaled by `1 / eta^2` for radiance (camera paths) but not for importance
//! (photons): the BTDF is not symmetric (Veach 1997, 5.2; pbrt-v4 section 9.7). Refraction
//! is multiplied by the material's transmission tint. A dispersive path follows its hero
//! wavelength's index through the same microfacet normal.
//!
//! Single scattering loses the light that bounces between microfacets: at roughness 0.5 (alpha
//! 0.25) and index 1.5, 1% seen head on from outside, 4% at 60 degrees, 9% at grazing and 7% to
//! 20% from inside; at roughness 1, 11% to 58%. As Cycles' Multiscatter GGX glass does, the
//! boundary is divided by its single-scattering albedo `E(wo)` (`dielectric_albedo.rs`), which
//! gives that light back spread like the single-scattered light (`a_rough_dielectric_conserves_energy`).
//! The scaled BSDF depends on `wo` alone through `E`, so it is no longer reciprocal: photons,
//! arriving from `wo`, keep their flux exactly; camera paths, leaving toward `wo`, are scaled
//! for the direction they see (Cycles' choice). The single-scattering term itself is reciprocal
//! up to the indices (`single_scattering`).

use glam::{Vec2, Vec3};

use super::dielectric::{fresnel_dielectric, refract, side};
use super::dielectric_albedo::glass_albedo;
use super::microfacet::{self, distribution, masking, masking_shadowing, reflect};
use super::{face_toward, BsdfSample, ShadingFrame, Transport};
use crate::spectrum::SampledSpectrum;

/// A rough dielectric at a path's wavelengths.
#[derive(Clone, Copy, Debug)]
pub struct RoughDielectric {
    /// Index of refraction of the inside relative to the outside (the hero wavelength's).
    pub ior: f32,
    /// GGX alpha (roughness squared).
    pub alpha: f32,
    /// What refraction transmits at each wavelength.
    pub tint: SampledSpectrum,
}

/// The microfacet normal through which `wi` refracts from `wo` (local, `wo.z > 0 > wi.z`), if it
/// faces both.
fn refracting_normal(eta: f32, wo: Vec3, wi: Vec3) -> Option<Vec3> {
    let h = face_toward((wo + wi * eta).normalize_or_zero(), Vec3::Z);
    (h != Vec3::ZERO && h.dot(wo) > 0.0 && h.dot(wi) < 0.0).then_some(h)
}

/// The factor on refracted light for `mode`.
fn refraction_scale(eta: f32, mode: Transport) -> f32 {
    match mode {
        Transport::Radiance => 1.0 / (eta * eta),
        Transport::Importance => 1.0,
    }
}

/// Albedos below this are not divided by (a grazing view of a very rough boundary from inside,
/// which scatters almost nothing once), so that no weight grows without bound.
const SMALLEST_ALBEDO: f32 = 0.1;

impl RoughDielectric {
    /// The BSDF value for radiance arriving from `wi`, leaving toward `wo`: the single-scattering
    /// value over the boundary's albedo seen from `wo`.
    pub fn eval(&self, frame: ShadingFrame, wo: Vec3, wi: Vec3) -> SampledSpectrum {
        self.single_scattering(frame, wo, wi) * self.compensation(frame, wo)
    }

    /// `1 / E(wo)`: what gives back the light single scattering loses between microfacets.
    pub fn compensation(&self, frame: ShadingFrame, wo: Vec3) -> f32 {
        let (n, eta) = side(self.ior, frame, wo);
        1.0 / glass_albedo(self.alpha, eta, n.dot(wo).abs()).max(SMALLEST_ALBEDO)
    }

    /// The single-scattering BSDF (Walter et al. 2007) for radiance arriving from `wi`, leaving
    /// toward `wo`.
    pub fn single_scattering(&self, frame: ShadingFrame, wo: Vec3, wi: Vec3) -> SampledSpectrum {
        let (n, eta) = side(self.ior, frame, wo);
        let (wo, wi, _) = microfacet::to_frame(n, wo, wi);
        if wo.z <= 0.0 || wi.z == 0.0 {
            return SampledSpectrum::ZERO;
        }
        if wi.z > 0.0 {
            return match microfacet::reflection(self.alpha, wo, wi) {
                Some((value, cos_h)) => SampledSpectrum::splat(value * fresnel_dielectric(cos_h, eta)),
                None => SampledSpectrum::ZERO,
            };
        }
        let Some(h) = refracting_normal(eta, wo, wi) else {
            return SampledSpectrum::ZERO;
        };
        let (cos_o, cos_i) = (wo.dot(h), wi.dot(h));
        let denom = (cos_i + cos_o / eta).powi(2);
        let transmitted = 1.0 - fresnel_dielectric(cos_o, eta);
        let value = transmitted
            * distribution(self.alpha, h)
            * masking_shadowing(self.alpha, wo, wi)
            * (cos_i * cos_o / (wi.z * wo.z * denom)).abs();
        self.tint * (value * refraction_scale(eta, Transport::Radiance))
    }

    /// The density with which [`RoughDielectric::sample`] picks `wi`.
    pub fn pdf(&self, frame: ShadingFrame, wo: Vec3, wi: Vec3) -> f32 {
        let (n, eta) = side(self.ior, frame, wo);
        let (wo, wi, _) = microfacet::to_frame(n, wo, wi);
        if wo.z <= 0.0 || wi.z == 0.0 {
            return 0.0;
        }
        if wi.z > 0.0 {
            let reflected = fresnel_dielectric(wo.dot((wo + wi).normalize()), eta);
            return microfacet::reflection_pdf(self.alpha, wo, wi) * reflected;
        }
        let Some(h) = refracting_normal(eta, wo, wi) else {
            return 0.0;
        };
        let (cos_o, cos_i) = (wo.dot(h), wi.dot(h));
        let visible = masking(self.alpha, wo) * distribution(self.alpha, h) * cos_o / wo.z;
        let jacobian = cos_i.abs() / (cos_i + cos_o / eta).powi(2);
        visible * jacobian * (1.0 - fresnel_dielectric(cos_o, eta))
    }

    /// Samples a visible microfacet normal with `u`, then reflection through it with its Fresnel
    /// reflectance's probability (`u_lobe`), else refraction.
    pub fn sample(
        &self,
        frame: ShadingFrame,
        wo: Vec3,
        u: Vec2,
        u_lobe: f32,
        mode: Transport,
    ) -> Option<BsdfSample> {
        let (n, eta) = side(self.ior, frame, wo);
        let (wo_local, _, [t, b, n]) = microfacet::to_frame(n, wo, wo);
        if wo_local.z <= 0.0 {
            return None;
        }
        let h = microfacet::sample_visible_normal(self.alpha, wo_local, u);
        let reflected = fresnel_dielectric(wo_local.dot(h), eta);
        let (wi, weight) = if u_lobe < reflected {
            let wi = reflect(wo_local, h);
            (wi.z > 0.0).then_some((wi, SampledSpectrum::ONE))?
        } else {
            let wi = refract(wo_local, h, eta)?;
            (wi.z < 0.0).then_some((wi, self.tint * refraction_scale(eta, mode)))?
        };
        let g = masking_shadowing(self.alpha, wo_local, wi) / masking(self.alpha, wo_local);
        let world = (t * wi.x + b * wi.y + n * wi.z).normalize();
        let weight = weight * (g * self.compensation(frame, wo));
        Some(BsdfSample { wi: world, weight, pdf: self.pdf(frame, wo, world), is_delta: false })
    }
}
