//! Shadow rays, for both methods: a ray from a surface point (offset off its triangle) or a
//! point in a medium toward a light or another path's vertex, stopped short of its end so that
//! the surface it aims at does not block it; what reaches the end past surfaces alpha cuts away
//! (`see_through.rs`); and what the volumes it runs through keep of the light.

use glam::Vec3;

use super::context::Renderer;
use super::media::Media;
use super::see_through;
use crate::geometry::offset_origin;
use crate::spectrum::{SampledSpectrum, Wavelengths};

/// A shadow ray stops this share of its length short of its end (the surface it aims at).
const SHORT_OF_END: f32 = 1e-4;

/// A ray that must reach its end for a direct-light term or a connection to count.
#[derive(Clone, Copy, Debug)]
pub struct ShadowRay {
    /// Where it starts (already offset from the surface).
    pub origin: Vec3,
    /// Its unit direction.
    pub direction: Vec3,
    /// How far it must be free.
    pub t_max: f32,
}

impl ShadowRay {
    /// The ray leaving point `p` of a triangle of geometric normal `ng` whose largest coordinate
    /// is `scale`, along `direction`, toward what lies `distance` away (infinite: a distant light).
    pub fn leaving(p: Vec3, (ng, scale): (Vec3, f32), direction: Vec3, distance: f32) -> Self {
        ShadowRay { origin: offset_origin(p, ng, direction, scale), direction, t_max: short_of(distance) }
    }

    /// The ray from `x`, a point in a medium (no surface to leave), along `direction`, toward
    /// what lies `distance` away.
    pub fn within(x: Vec3, direction: Vec3, distance: f32) -> Self {
        ShadowRay { origin: x, direction, t_max: short_of(distance) }
    }

    /// How much of the light along it reaches its end: 0 or 1, or between where surfaces that
    /// alpha cuts away lie along it.
    pub fn visibility(&self, renderer: &Renderer, lambda: &Wavelengths) -> f32 {
        see_through::visibility(renderer, lambda, self.origin, self.direction, self.t_max)
    }
}

/// `distance` less [`SHORT_OF_END`] of it (infinite stays infinite).
fn short_of(distance: f32) -> f32 {
    if distance.is_finite() {
        distance * (1.0 - SHORT_OF_END)
    } else {
        f32::INFINITY
    }
}

/// What the volume a segment leaving a vertex toward `w` runs through keeps of light over
/// `length` (all of it where nothing absorbs): the volumes `media` the path arrived in, crossed
/// into the inside of the surface's `material` (geometric normal `ng`, arrived from `wo`) where
/// `w` goes in.
pub fn kept(
    renderer: &Renderer,
    lambda: &Wavelengths,
    (media, material): (Media, u32),
    (ng, wo): (Vec3, Vec3),
    w: Vec3,
    length: f32,
) -> SampledSpectrum {
    if !renderer.has_volumes {
        return SampledSpectrum::ONE;
    }
    let scene = renderer.scene;
    media
        .crossed(scene, material, ng, wo, w)
        .transmittance(scene, lambda, length)
        .unwrap_or(SampledSpectrum::ONE)
}
