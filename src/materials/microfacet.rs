//! The GGX (Trowbridge-Reitz) microfacet distribution with Smith's height-correlated masking, and
//! visible-normal sampling (Heitz 2018, "Sampling the GGX Distribution of Visible Normals").
//!
//! All functions work in a local frame whose +z is the shading normal.

use glam::{Vec2, Vec3, Vec4};

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
