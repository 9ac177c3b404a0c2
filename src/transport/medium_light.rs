//! Direct light scattered toward the eye along an eye segment through a medium that scatters
//! (single scattering), by next-event estimation: a light chosen by power, a point on the segment
//! drawn by equiangular sampling toward the light's centre (`free_flight.rs`), and a point on the
//! light seen from there through the medium. Light that has scattered before is the photons',
//! gathered along the same segment as a beam (`beams.rs`).
//!
//! Equiangular sampling follows the inverse square of the distance to a point, spot or sphere
//! light, so a beam in thin fog near its lamp is found where its light is; for an area or an
//! emitting triangle it aims at the centre. A light at infinity (a sun, the world) lights nothing
//! through a medium that fills all space (as in Cycles: a world volume hides them), and from
//! inside a closed mesh the mesh's surface lies between: such lights add nothing here.

use glam::Vec3;

use super::context::Renderer;
use super::free_flight::equiangular;
use super::shadow::ShadowRay;
use crate::materials::{Bsdf, ShadingFrame, Volume};
use crate::spectrum::{SampledSpectrum, Wavelengths};

/// The direct light `volume` scatters toward `-direction` along the segment from `origin` of
/// `length` (infinite where it leaves the scene), per unit of throughput, at `lambda`, from the
/// uniform numbers `u` (drawn by the caller, all of them, so that what follows on the path does
/// not depend on where this estimate stopped). Out of line, so that the eye path's loop, which
/// scenes without media run, stays as small as it was.
#[inline(never)]
pub fn in_scattered(
    renderer: &Renderer,
    lambda: &Wavelengths,
    (origin, direction, length): (Vec3, Vec3, f32),
    volume: &Volume,
    u: [f32; 4],
) -> SampledSpectrum {
    let (u_light, u_along, u_point) = (u[0], u[1], glam::Vec2::new(u[2], u[3]));
    let Some((scattering, anisotropy)) = volume.scattering(lambda) else { return SampledSpectrum::ZERO };
    let Some((index, p_choice)) = renderer.light_choice.sample(u_light) else { return SampledSpectrum::ZERO };
    let light = &renderer.scene.lights[index];
    let Some(centre) = light.centre() else { return SampledSpectrum::ZERO };
    let Some((t, density)) = equiangular(origin, direction, length, centre, u_along) else {
        return SampledSpectrum::ZERO;
    };
    let x = origin + direction * t;
    let Some(sample) = light.sample_incident(x, u_point, lambda) else { return SampledSpectrum::ZERO };
    let wo = -direction;
    let phase = Bsdf::Medium { scattering, anisotropy }.eval(ShadingFrame::new(wo, wo), wo, sample.wi);
    let through = ShadowRay::within(x, sample.wi, sample.distance).visibility(renderer, lambda);
    if through <= 0.0 {
        return SampledSpectrum::ZERO;
    }
    let kept = volume.transmittance(lambda, t) * volume.transmittance(lambda, sample.distance);
    phase * sample.radiance_over_pdf * kept * (through / (p_choice * density))
}
