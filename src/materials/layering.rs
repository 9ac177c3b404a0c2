//! How a layer over a material (a clear coat, a sheen) is combined with what lies under it, as
//! Cycles' Principled BSDF combines them: the layer's own reflection, plus everything under it
//! scaled by what the layer does not reflect toward the viewer, `1 - R(wo)`. A path picks one of
//! the two per hit, each with a probability near its share of the light, and carries one over
//! that probability; a visible point then holds one small lobe.
//!
//! `R` depends on the direction toward the camera. Photons travel the other way: a photon that
//! goes under a layer is re-weighted once its outgoing direction, where a camera path would look
//! from, is known ([`Over::importance_correction`]).

use glam::{Vec3, Vec4};

use super::clearcoat::CoatAt;
use super::plastic::Coat;
use super::sheen::{self, SheenAt};

/// A layer a path went under, as much of it as its share of the light needs (a lobe carries two,
/// and is moved at every hit: 32 bytes each, not the 96 of the whole layer).
#[derive(Clone, Copy, Debug)]
pub struct Over {
    /// The layer's normal.
    pub n: Vec3,
    /// What the layer is.
    pub layer: Layer,
}

/// A layer's kind and its parameters at one surface point, at the hero wavelength.
#[derive(Clone, Copy, Debug)]
pub enum Layer {
    /// A clear coat of `factor`, normal-incidence reflectance `f0`, index `eta` and GGX `alpha`.
    Coat {
        /// How much coat there is.
        factor: f32,
        /// Normal-incidence reflectance.
        f0: f32,
        /// Index.
        eta: f32,
        /// GGX alpha (0: smooth).
        alpha: f32,
    },
    /// A sheen of `colour` (its largest value) and `roughness`.
    Sheen {
        /// The colour's largest value.
        colour: f32,
        /// Roughness.
        roughness: f32,
    },
}

impl From<&CoatAt> for Over {
    fn from(coat: &CoatAt) -> Self {
        let Coat { f0, eta, alpha } = coat.coat;
        Over { n: coat.frame.n(), layer: Layer::Coat { factor: coat.factor, f0: f0.x, eta, alpha } }
    }
}

impl From<&SheenAt> for Over {
    fn from(sheen: &SheenAt) -> Self {
        let layer = Layer::Sheen { colour: sheen.colour.max_element(), roughness: sheen.roughness };
        Over { n: sheen.frame.n(), layer }
    }
}

impl Over {
    /// The share of light the layer reflects seen from `w` (all of its lobe, delta or not).
    pub fn reflected(&self, w: Vec3) -> f32 {
        let mu = self.n.dot(w).abs().min(1.0);
        match self.layer {
            Layer::Coat { factor, f0, eta, alpha } => {
                let coat = Coat::new(Vec4::splat(f0), eta, alpha);
                let albedo = if alpha > 0.0 { coat.albedo(mu) } else { coat.fresnel(mu) };
                factor * albedo.x
            }
            Layer::Sheen { colour, roughness } => colour * sheen::albedo(mu, roughness),
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
