//! Lambertian reflection: `f = albedo / pi` on the side of `wo`.

use glam::{Vec2, Vec3, Vec3A, Vec4};
use std::f32::consts::FRAC_1_PI;

use super::{BsdfSample, ShadingFrame, Transport};
use crate::sampling::square_to_cosine_hemisphere;
use crate::spectrum::SampledSpectrum;

/// `albedo / pi` where `wi` is in front of the shading normal on `wo`'s side
/// ([`ShadingFrame::toward`]), light arriving from `wi` (shadowed by a normal map's bend:
/// [`ShadingFrame::diffuse_shadowing`]), else zero.
pub fn eval(albedo: SampledSpectrum, frame: ShadingFrame, wo: Vec3, wi: Vec3) -> SampledSpectrum {
    if frame.toward(wo).dot(wi) > 0.0 {
        albedo * (FRAC_1_PI * frame.diffuse_shadowing(wi))
    } else {
        Vec4::ZERO
    }
}

/// The cosine-weighted density of `wi` in front of `n` (the shading normal on `wo`'s side).
pub fn pdf(n: Vec3, wi: Vec3) -> f32 {
    n.dot(wi).max(0.0) * FRAC_1_PI
}

/// Cosine-weighted reflection in front of the shading normal on `wo`'s side: the weight is the
/// albedo (shadowed, for `mode`'s side of the light, by a normal map's bend).
pub fn sample(
    albedo: SampledSpectrum,
    frame: ShadingFrame,
    wo: Vec3,
    u: Vec2,
    mode: Transport,
) -> Option<BsdfSample> {
    let n = Vec3A::from(frame.toward(wo));
    let (t, b) = n.any_orthonormal_pair();
    let local = square_to_cosine_hemisphere(u);
    // Unit to rounding (an orthonormal basis, a unit local direction): not normalised again.
    let wi = Vec3::from(t * local.x + b * local.y + n * local.z);
    let light_side = if mode == Transport::Radiance { wi } else { wo };
    let weight = albedo * frame.diffuse_shadowing(light_side);
    Some(BsdfSample { pdf: local.z * FRAC_1_PI, wi, weight, is_delta: false })
}
