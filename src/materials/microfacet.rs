//! The GGX (Trowbridge-Reitz) microfacet distribution with Smith's height-correlated masking, and
//! visible-normal sampling (Heitz 2018, "Sampling the GGX Distribution of Visible Normals").
//!
//! All functions work in a local frame whose +z is the shading normal.

use glam::{Vec2, Vec3, Vec4};

use super::face_toward;
use crate::sampling::basis;
use crate::spectrum::SampledSpectrum;
use std::f32::consts::PI;

/// The normal distribution D(h).
pub fn distribution(alpha: f32, h: Vec3) -> f32 {
    let a2 = alpha * alpha;
    let d = h.z * h.z * (a2 - 1.0) + 1.0;
    a2 / (PI * d * d)
}

/// Smith's Lambda(w).
fn lambda(alpha: f32, w: Vec3) -> f32 {
    let tan2 = (w.x * w.x + w.y * w.y) / (w.z * w.z);
    ((1.0 + alpha * alpha * tan2).sqrt() - 1.0) / 2.0
}

/// Smith's masking G1(w).
pub fn masking(alpha: f32, w: Vec3) -> f32 {
    1.0 / (1.0 + lambda(alpha, w))
}

/// Height-correlated masking-shadowing G2(wo, wi).
pub fn masking_shadowing(alpha: f32, wo: Vec3, wi: Vec3) -> f32 {
    1.0 / (1.0 + lambda(alpha, wo) + lambda(alpha, wi))
}

/// A visible normal for `wo` (with `wo.z > 0`); its density is `G1(wo) max(0, wo.h) D(h) / wo.z`.
pub fn sample_visible_normal(alpha: f32, wo: Vec3, u: Vec2) -> Vec3 {
    let wh = Vec3::new(alpha * wo.x, alpha * wo.y, wo.z).normalize();
    let t1 = if wh.z < 0.9999 { Vec3::Z.cross(wh).normalize() } else { Vec3::X };
    let t2 = wh.cross(t1);
    let r = u.x.sqrt();
    let phi = 2.0 * PI * u.y;
    let (p1, p2) = (r * phi.cos(), r * phi.sin());
    let s = 0.5 * (1.0 + wh.z);
    let p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * p2;
    let nh = t1 * p1 + t2 * p2 + wh * (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt();
    Vec3::new(alpha * nh.x, alpha * nh.y, nh.z.max(1e-6)).normalize()
}

/// Schlick's Fresnel approximation.
pub fn schlick(f0: SampledSpectrum, cos_theta: f32) -> SampledSpectrum {
    f0 + (Vec4::ONE - f0) * (1.0 - cos_theta.clamp(0.0, 1.0)).powi(5)
}

/// Mirror reflection of `wo` about `n`.
pub fn reflect(wo: Vec3, n: Vec3) -> Vec3 {
    2.0 * wo.dot(n) * n - wo
}

/// `wo` and `wi` in the frame of `n` (flipped to the side of `wo`), and that frame.
pub fn to_local(n: Vec3, wo: Vec3, wi: Vec3) -> (Vec3, Vec3, [Vec3; 3]) {
    to_frame(face_toward(n, wo), wo, wi)
}

/// `wo` and `wi` in the frame of `n` as it is, and that frame.
pub fn to_frame(n: Vec3, wo: Vec3, wi: Vec3) -> (Vec3, Vec3, [Vec3; 3]) {
    let (t, b) = basis(n);
    let local = |w: Vec3| Vec3::new(w.dot(t), w.dot(b), w.dot(n));
    (local(wo), local(wi), [t, b, n])
}

/// GGX reflection in a local frame without its Fresnel term: `D G2 / (4 wo.z wi.z)` and the
/// cosine `wo.h` the Fresnel term takes, or `None` below the surface.
pub fn reflection(alpha: f32, wo: Vec3, wi: Vec3) -> Option<(f32, f32)> {
    if wo.z <= 0.0 || wi.z <= 0.0 {
        return None;
    }
    let h = (wo + wi).normalize();
    let value = distribution(alpha, h) * masking_shadowing(alpha, wo, wi) / (4.0 * wo.z * wi.z);
    Some((value, wo.dot(h)))
}

/// The density of visible-normal sampling in a local frame: `D(h) G1(wo) / (4 wo.z)` (Heitz
/// 2018, eq. 17 with the reflection Jacobian `1 / (4 wo.h)`).
pub fn reflection_pdf(alpha: f32, wo: Vec3, wi: Vec3) -> f32 {
    if wo.z <= 0.0 || wi.z <= 0.0 {
        return 0.0;
    }
    let h = (wo + wi).normalize();
    distribution(alpha, h) * masking(alpha, wo) / (4.0 * wo.z)
}

/// A reflected direction by visible-normal sampling in a local frame.
pub struct ReflectionSample {
    /// The direction, local.
    pub wi: Vec3,
    /// `G2 / G1(wo)`: the weight without the Fresnel term.
    pub weight: f32,
    /// The cosine `wo.h` the Fresnel term takes.
    pub cos_h: f32,
    /// The density of `wi`.
    pub pdf: f32,
}

/// Samples GGX reflection in a local frame (`None` when the reflection points below).
pub fn sample_reflection(alpha: f32, wo: Vec3, u: Vec2) -> Option<ReflectionSample> {
    if wo.z <= 0.0 {
        return None;
    }
    let h = sample_visible_normal(alpha, wo, u);
    let wi = reflect(wo, h);
    if wi.z <= 0.0 {
        return None;
    }
    let g1 = masking(alpha, wo);
    Some(ReflectionSample {
        wi,
        weight: masking_shadowing(alpha, wo, wi) / g1,
        cos_h: wo.dot(h),
        pdf: distribution(alpha, h) * g1 / (4.0 * wo.z),
    })
}
