//! Conductors: a perfect mirror, and GGX microfacet reflection (Walter et al. 2007), both with
//! Schlick's Fresnel from the base colour (the glTF metallic BRDF).

use glam::{Vec2, Vec3, Vec4};

use super::{face_toward, microfacet, BsdfSample};
use crate::sampling::basis;
use crate::spectrum::SampledSpectrum;

/// Mirror reflection of `wo` about `n`.
pub fn reflect(wo: Vec3, n: Vec3) -> Vec3 {
    2.0 * wo.dot(n) * n - wo
}

/// The perfect mirror: `wi` is `wo` reflected, weight `F(cos)`.
pub fn sample_smooth(f0: SampledSpectrum, n: Vec3, wo: Vec3) -> Option<BsdfSample> {
    let n = face_toward(n, wo);
    let weight = microfacet::schlick(f0, n.dot(wo));
    Some(BsdfSample { wi: reflect(wo, n), weight, pdf: 0.0, is_delta: true })
}

/// `wo` and `wi` in the frame of `n` (flipped to the side of `wo`).
fn to_local(n: Vec3, wo: Vec3, wi: Vec3) -> (Vec3, Vec3, [Vec3; 3]) {
    let n = face_toward(n, wo);
    let (t, b) = basis(n);
    let local = |w: Vec3| Vec3::new(w.dot(t), w.dot(b), w.dot(n));
    (local(wo), local(wi), [t, b, n])
}

/// GGX reflection `D G F / (4 |wo.n| |wi.n|)`.
pub fn eval_rough(f0: SampledSpectrum, alpha: f32, n: Vec3, wo: Vec3, wi: Vec3) -> SampledSpectrum {
    let (wo, wi, _) = to_local(n, wo, wi);
    if wo.z <= 0.0 || wi.z <= 0.0 {
        return Vec4::ZERO;
    }
    let h = (wo + wi).normalize();
    let d = microfacet::distribution(alpha, h);
    let g = microfacet::masking_shadowing(alpha, wo, wi);
    d * g * microfacet::schlick(f0, wo.dot(h)) / (4.0 * wo.z * wi.z)
}

/// The density of visible-normal sampling: `D(h) G1(wo) / (4 wo.z)` (Heitz 2018, eq. 17 with
/// the reflection Jacobian `1 / (4 wo.h)`).
pub fn pdf_rough(alpha: f32, n: Vec3, wo: Vec3, wi: Vec3) -> f32 {
    let (wo, wi, _) = to_local(n, wo, wi);
    if wo.z <= 0.0 || wi.z <= 0.0 {
        return 0.0;
    }
    let h = (wo + wi).normalize();
    microfacet::distribution(alpha, h) * microfacet::masking(alpha, wo) / (4.0 * wo.z)
}

/// Visible-normal sampling: the weight is `F G2 / G1(wo)`.
pub fn sample_rough(f0: SampledSpectrum, alpha: f32, n: Vec3, wo: Vec3, u: Vec2) -> Option<BsdfSample> {
    let (wo_local, _, [t, b, n]) = to_local(n, wo, wo);
    if wo_local.z <= 0.0 {
        return None;
    }
    let h = microfacet::sample_visible_normal(alpha, wo_local, u);
    let wi_local = reflect(wo_local, h);
    if wi_local.z <= 0.0 {
        return None;
    }
    let weight = microfacet::schlick(f0, wo_local.dot(h))
        * microfacet::masking_shadowing(alpha, wo_local, wi_local)
        / microfacet::masking(alpha, wo_local);
    let wi = t * wi_local.x + b * wi_local.y + n * wi_local.z;
    Some(BsdfSample {
        wi: wi.normalize(),
        weight,
        pdf: microfacet::distribution(alpha, h) * microfacet::masking(alpha, wo_local) / (4.0 * wo_local.z),
        is_delta: false,
    })
}
