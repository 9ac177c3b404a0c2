//! How a layer over a material (a clear coat, a sheen) is combined with what lies under it, as
//! Cycles' Principled BSDF combines them: the layer's own reflection, plus everything under it
//! scaled by what the layer does not reflect toward the viewer, `1 - R(wo)`. A path picks one of
//! the two per hit, each with a probability near its share of the light, and carries one over
//! that probability; a visible point then holds one small lobe.
//!
//! `R` depends on the direction toward the camera. Photons travel the other way: a photon that
//! goes under a layer is re-weighted once its outgoing direction, where a camera path would look
//! from, is known ([`Over::importance_correction`]).

use glam::Vec3;

use super::clearcoat::CoatAt;
use super::sheen::SheenAt;

/// A layer a path went under.
#[derive(Clone, Copy, Debug)]
pub enum Over {
    /// A clear coat.
    Coat(CoatAt),
    /// A sheen.
    Sheen(SheenAt),
}

impl Over {
    /// The share of light the layer reflects seen from `w`.
    pub fn reflected(&self, w: Vec3) -> f32 {
        match self {
            Over::Coat(coat) => coat.reflected(w),
            Over::Sheen(sheen) => sheen.reflected(w),
        }
    }

    /// For a photon that arrived from `wo` and scatters under the layer toward `wi`: the factor
    /// that turns the attenuation it was weighed with at the pick (seen from `wo`) into the one
    /// seen from `wi`.
    pub fn importance_correction(&self, wo: Vec3, wi: Vec3) -> f32 {
        (1.0 - self.reflected(wi)) / (1.0 - self.reflected(wo)).max(1e-6)
    }
}

/// The layer or what lies under it.
#[derive(Clone, Copy, Debug)]
pub enum Choice {
    /// The layer's own reflection, times `weight`.
    Layer {
        /// The factor on the path's throughput.
        weight: f32,
    },
    /// What lies under the layer, times `weight`, with `u` a uniform number in [0, 1) left over
    /// for the choices under it.
    Under {
        /// The factor on the path's throughput.
        weight: f32,
        /// A uniform number in [0, 1).
        u: f32,
    },
}

/// Picks, by the uniform `u`, a layer that reflects the share `reflected` toward the viewer (its
/// own reflection scaled by `scale`, a clear coat's factor) or what lies under it, whose mean
/// albedo is near `under`.
pub fn pick(reflected: f32, scale: f32, under: f32, u: f32) -> Choice {
    let rest = (1.0 - reflected) * under.clamp(0.0, 1.0);
    let p = (reflected / (reflected + rest).max(1e-6)).clamp(0.05, 0.95);
    if u < p {
        Choice::Layer { weight: scale / p }
    } else {
        let u = ((u - p) / (1.0 - p)).min(1.0 - f32::EPSILON);
        Choice::Under { weight: (1.0 - reflected) / (1.0 - p), u }
    }
}
