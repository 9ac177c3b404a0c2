//! Conductors: a perfect mirror, and GGX microfacet reflection (Walter et al. 2007), both with
//! Schlick's Fresnel from the base colour (the glTF metallic BRDF).
//!
//! Rough reflection gets back the light single-scattering GGX loses between microfacets, as
//! Cycles' Multiscatter GGX (Blender's default) does: the lobe is scaled by
//! `1 + F_ms (1 - E) / E` (Kulla and Conty 2017, in Cycles' form), `E` the white lobe's albedo
//! seen from the viewer and `F_ms = F_avg E_avg / (1 - F_avg (1 - E_avg))` the Fresnel of the
//! lost light's further bounces, with `F_avg = f0 + (1 - f0) / 21` (Schlick's average over the
//! hemisphere). A white metal then reflects everything from every direction, and the parity
//! scene's textured gold went from 0.97-0.99 of Cycles to 1.00. The factor is fixed once per hit
//! by the viewing direction (for photons, the direction they arrived from, where Cycles would
//! take the other: a few percent on photons that bounce off rough metal).

use glam::{Vec2, Vec3, Vec4};

use super::layer_albedo::white_ggx_albedo;
use super::microfacet::{self, reflect};
use super::{face_toward, BsdfSample};
use crate::spectrum::SampledSpectrum;

/// The perfect mirror: `wi` is `wo` reflected, weight `F(cos)`.
pub fn sample_smooth(f0: SampledSpectrum, n: Vec3, wo: Vec3) -> Option<BsdfSample> {
    sample_mirror(microfacet::schlick(f0, face_toward(n, wo).dot(wo)), n, wo)
}

/// A mirror reflecting `weight`: `wi` is `wo` reflected about `n` (flipped to the side of `wo`).
pub fn sample_mirror(weight: SampledSpectrum, n: Vec3, wo: Vec3) -> Option<BsdfSample> {
    let n = face_toward(n, wo);
    Some(BsdfSample { wi: reflect(wo, n), weight, pdf: 0.0, is_delta: true })
}

/// The multiple-scattering compensation of GGX of `alpha` with normal-incidence reflectance `f0`,
/// seen from cosine `mu`: the factor on the single-scattering lobe.
pub fn multiple_scattering(f0: SampledSpectrum, alpha: f32, mu: f32) -> SampledSpectrum {
    let (e, e_avg) = white_ggx_albedo(alpha, mu);
    if e <= 0.0 {
        return Vec4::ONE;
    }
    let f_avg = f0 + (Vec4::ONE - f0) / 21.0;
    let f_ms = f_avg * e_avg / (Vec4::ONE - f_avg * (1.0 - e_avg));
    Vec4::ONE + f_ms * ((1.0 - e) / e)
}

/// GGX reflection `D G F / (4 |wo.n| |wi.n|)`.
pub fn eval_rough(f0: SampledSpectrum, alpha: f32, n: Vec3, wo: Vec3, wi: Vec3) -> SampledSpectrum {
    let (wo, wi, _) = microfacet::to_local(n, wo, wi);
    match microfacet::reflection(alpha, wo, wi) {
        Some((value, cos_h)) => microfacet::schlick(f0, cos_h) * value,
        None => Vec4::ZERO,
    }
}

/// The density of visible-normal sampling.
pub fn pdf_rough(alpha: f32, n: Vec3, wo: Vec3, wi: Vec3) -> f32 {
    let (wo, wi, _) = microfacet::to_local(n, wo, wi);
    microfacet::reflection_pdf(alpha, wo, wi)
}

/// Visible-normal sampling: the weight is `F G2 / G1(wo)`.
pub fn sample_rough(f0: SampledSpectrum, alpha: f32, n: Vec3, wo: Vec3, u: Vec2) -> Option<BsdfSample> {
    let (wo_local, _, [t, b, n]) = microfacet::to_local(n, wo, wo);
    let s = microfacet::sample_reflection(alpha, wo_local, u)?;
    let wi = t * s.wi.x + b * s.wi.y + n * s.wi.z;
    Some(BsdfSample {
        wi: wi.normalize(),
        weight: microfacet::schlick(f0, s.cos_h) * s.weight,
        pdf: s.pdf,
        is_delta: false,
    })
}
