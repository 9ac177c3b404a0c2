//! Rays past surfaces that alpha cuts away (glTF `alphaMode` MASK and BLEND), for next-event
//! estimation: a shadow ray passes a surface in proportion to its transparency (ratio tracking:
//! the light is multiplied by `1 - opacity` at each, which needs no random number and is what
//! eye and photon paths, choosing to pass with that probability, give on average).
//!
//! Scenes without such materials test shadow rays with one any-hit query ([`visibility`]).

use glam::Vec3;

use super::context::Renderer;
use crate::accel::Hit;
use crate::geometry::offset_origin;
use crate::spectrum::Wavelengths;

/// More cut-away surfaces than this along one ray are taken as blocking it.
const MAX_CROSSINGS: u32 = 64;

/// How much of the light along a shadow ray from `origin` along `direction` reaches `t_max`:
/// 0 or 1 where no material's alpha cuts any surface away, else [`transmittance`].
pub fn visibility(
    renderer: &Renderer,
    lambda: &Wavelengths,
    origin: Vec3,
    direction: Vec3,
    t_max: f32,
) -> f32 {
    if renderer.has_cut_away_surfaces {
        transmittance(renderer, lambda, origin, direction, t_max)
    } else if renderer.accel.occluded(origin, direction, t_max) {
        0.0
    } else {
        1.0
    }
}

/// The share of light that reaches `t_max` along a ray from `origin` (0 where an opaque surface
/// blocks it), for shadow rays of scenes with cut-away surfaces.
fn transmittance(
    renderer: &Renderer,
    lambda: &Wavelengths,
    origin: Vec3,
    direction: Vec3,
    t_max: f32,
) -> f32 {
    let end = origin + direction * t_max;
    let mut through = 1.0;
    let mut origin = origin;
    for _ in 0..MAX_CROSSINGS {
        let remaining = if t_max.is_finite() { (end - origin).dot(direction) } else { f32::INFINITY };
        let Some(hit) = renderer.accel.intersect_opaque(origin, direction, remaining) else {
            return through;
        };
        through *= 1.0 - opacity(renderer, lambda, &hit);
        if through <= 0.0 {
            return 0.0;
        }
        origin = offset_origin(hit.p, hit.ng, direction, hit.scale);
    }
    0.0
}

/// The first surface along a ray that alpha does not cut away entirely, and the share of light
/// that passes the cut-away surfaces before it, for BSDF-sampled rays looking for emitters.
pub fn first_hit(
    renderer: &Renderer,
    lambda: &Wavelengths,
    origin: Vec3,
    direction: Vec3,
) -> (Option<Hit>, f32) {
    let mut through = 1.0;
    let mut origin = origin;
    for _ in 0..MAX_CROSSINGS {
        let Some(hit) = renderer.accel.intersect(origin, direction, f32::INFINITY) else {
            return (None, through);
        };
        let opacity = opacity(renderer, lambda, &hit);
        if opacity >= 1.0 || renderer.scene.triangle_light(hit.triangle) != crate::scene::NOT_A_LIGHT {
            return (Some(hit), through);
        }
        through *= 1.0 - opacity;
        origin = offset_origin(hit.p, hit.ng, direction, hit.scale);
    }
    (None, 0.0)
}

/// The probability that the surface hit is there.
fn opacity(renderer: &Renderer, lambda: &Wavelengths, hit: &Hit) -> f32 {
    let surface = renderer.scene.surface(hit, lambda);
    renderer.scene.materials[surface.material as usize].alpha.opacity(&surface.inputs)
}
