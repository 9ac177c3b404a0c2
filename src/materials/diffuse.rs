//! Lambertian reflection: `f = albedo / pi` on the side of `wo`.

use glam::{Vec2, Vec3, Vec3A, Vec4};
use std::f32::consts::FRAC_1_PI;

use super::{face_toward, BsdfSample};
use crate::sampling::square_to_cosine_hemisphere;
use crate::spectrum::SampledSpectrum;

/// `albedo / pi` when `wo` and `wi` are on the same side of `n`, else zero.
pub fn eval(albedo: SampledSpectrum, n: Vec3, wo: Vec3, wi: Vec3) -> SampledSpectrum {
    if n.dot(wo) * n.dot(wi) > 0.0 {
        albedo * FRAC_1_PI
    } else {
        Vec4::ZERO
    }
}

/// The cosine-weighted density of `wi` on the side of `wo`.
pub fn pdf(n: Vec3, wo: Vec3, wi: Vec3) -> f32 {
    if n.dot(wo) * n.dot(wi) > 0.0 {
        n.dot(wi).abs() * FRAC_1_PI
    } else {
        0.0
    }
}

/// Cosine-weighted reflection on the side of `wo`: the weight is the albedo.
pub fn sample(albedo: SampledSpectrum, n: Vec3, wo: Vec3, u: Vec2) -> Option<BsdfSample> {
    let n = Vec3A::from(face_toward(n, wo));
    let (t, b) = n.any_orthonormal_pair();
    let local = square_to_cosine_hemisphere(u);
    // Unit to rounding (an orthonormal basis, a unit local direction): not normalised again.
    let wi = Vec3::from(t * local.x + b * local.y + n * local.z);
    Some(BsdfSample { pdf: local.z * FRAC_1_PI, wi, weight: albedo, is_delta: false })
}
