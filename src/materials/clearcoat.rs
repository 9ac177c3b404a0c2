//! `KHR_materials_clearcoat` (Blender's Principled Coat): a smooth or GGX dielectric layer of
//! index 1.5 over the whole material, with its own roughness and its own normal.
//!
//! As in Cycles' Principled BSDF (and the glTF specification's `fresnel_coat`), the coat reflects
//! `factor` times its microfacet BRDF, and everything under it is scaled by what the coat does not
//! reflect toward the viewer, `1 - factor E(wo)`, with `E` the coat's directional albedo
//! ([`super::layer_albedo`]). A white Lambertian base under any coat therefore reflects exactly
//! everything. The layers are not summed in one BSDF: a path picks the coat or what lies under it
//! ([`CoatAt::pick`]) and carries that choice's weight, so a visible point stays one small lobe.
//!
//! The attenuation is seen from the camera's side. Photons travel the other way: a photon that
//! scatters under the coat is re-weighted once its outgoing direction is known
//! ([`CoatAt::importance_correction`]), so photon and camera paths see the same BSDF.
//!
//! Without a clearcoat normal texture the coat follows the interpolated normal, not the base's
//! normal map (glTF; Blender 5.0's Cycles likewise reads an unconnected Coat Normal as the
//! interpolated normal).

use std::sync::Arc;

use glam::{Vec3, Vec4};

use super::inputs::{NormalMap, SurfaceInputs};
use super::plastic::{Coat, Plastic};
use super::{Bsdf, ShadingFrame, SMOOTH_ROUGHNESS};
use crate::texture::DataTexture;

/// The coat's index of refraction (fixed by `KHR_materials_clearcoat`).
pub const COAT_IOR: f32 = 1.5;

/// The coat's normal-incidence reflectance, `((n - 1) / (n + 1))^2` at [`COAT_IOR`].
const COAT_F0: f32 = 0.04;

/// A clearcoat as the file gives it.
#[derive(Clone, Debug, Default)]
pub struct Clearcoat {
    /// `clearcoatFactor` in [0, 1].
    pub factor: f32,
    /// `clearcoatTexture`: its red channel scales the factor.
    pub factor_texture: Option<Arc<DataTexture>>,
    /// `clearcoatRoughnessFactor` in [0, 1] (perceptual).
    pub roughness: f32,
    /// `clearcoatRoughnessTexture`: its green channel scales the roughness.
    pub roughness_texture: Option<Arc<DataTexture>>,
    /// `clearcoatNormalTexture`.
    pub normal_map: Option<NormalMap>,
}

impl Clearcoat {
    /// The coat at a surface point whose interpolated (unmapped) frame is `frame`, or `None`
    /// where its factor is zero.
    pub fn at(&self, inputs: &SurfaceInputs, frame: ShadingFrame) -> Option<CoatAt> {
        let channel = |texture: &Option<Arc<DataTexture>>, pick: fn(Vec4) -> f32| {
            texture.as_ref().map_or(1.0, |t| pick(t.eval(&inputs.uv)))
        };
        let factor = (self.factor * channel(&self.factor_texture, |t| t.x)).clamp(0.0, 1.0);
        if factor <= 0.0 {
            return None;
        }
        let roughness = (self.roughness * channel(&self.roughness_texture, |t| t.y)).clamp(0.0, 1.0);
        let frame = self.normal_map.as_ref().map_or(frame, |map| map.apply(inputs, frame));
        let alpha = if roughness < SMOOTH_ROUGHNESS { 0.0 } else { roughness * roughness };
        Some(CoatAt { factor, frame, coat: Coat::new(Vec4::splat(COAT_F0), COAT_IOR, alpha) })
    }
}

/// The coat resolved at a surface point.
#[derive(Clone, Copy, Debug)]
pub struct CoatAt {
    /// How much coat there is, in (0, 1].
    pub factor: f32,
    /// The coat's normals.
    pub frame: ShadingFrame,
    /// The dielectric layer itself.
    coat: Coat,
}

/// Which layer a path meets under a coat, with the factor on its throughput.
#[derive(Clone, Copy, Debug)]
pub enum CoatChoice {
    /// The coat's own reflection: this BSDF (in the coat's frame), times the weight.
    Coat(Bsdf, f32),
    /// What lies under the coat, its BSDF times `weight`, with `u` a uniform number left over
    /// for the choices under it.
    Under {
        /// The factor on the path's throughput.
        weight: f32,
        /// A uniform number in [0, 1).
        u: f32,
    },
}

impl CoatAt {
    /// The share of light the coat reflects seen from `w` (all of its lobe, delta or not).
    pub fn reflected(&self, w: Vec3) -> f32 {
        let mu = self.frame.n.dot(w).abs().min(1.0);
        let albedo = if self.coat.alpha > 0.0 { self.coat.albedo(mu) } else { self.coat.fresnel(mu) };
        self.factor * albedo.x
    }

    /// Picks the coat or what lies under it, seen from `wo`, by `u`: the coat with probability
    /// near its share of the light reflected toward `wo`, given `under` (the layers' mean albedo
    /// under it), each choice weighted by one over its probability.
    pub fn pick(&self, wo: Vec3, under: f32, u: f32) -> CoatChoice {
        let coat = self.reflected(wo);
        let rest = (1.0 - coat) * under.clamp(0.0, 1.0);
        let p = (coat / (coat + rest).max(1e-6)).clamp(0.05, 0.95);
        if u < p {
            CoatChoice::Coat(self.bsdf(wo), self.factor / p)
        } else {
            let u = ((u - p) / (1.0 - p)).min(1.0 - f32::EPSILON);
            CoatChoice::Under { weight: (1.0 - coat) / (1.0 - p), u }
        }
    }

    /// The coat's own reflection as a BSDF: a mirror when smooth, else the microfacet layer over
    /// a black base.
    fn bsdf(&self, wo: Vec3) -> Bsdf {
        match self.coat.alpha {
            0.0 => Bsdf::Mirror { weight: self.coat.fresnel(self.frame.n.dot(wo).abs().min(1.0)) },
            _ => Plastic { base: Vec4::ZERO, coat: self.coat }.bsdf(),
        }
    }

    /// For a photon that arrived from `wo` and scatters under the coat toward `wi`: the factor
    /// that turns the attenuation [`CoatAt::pick`] weighed it with (seen from `wo`) into the one
    /// seen from `wi`, where a camera path would look from.
    pub fn importance_correction(&self, wo: Vec3, wi: Vec3) -> f32 {
        (1.0 - self.reflected(wi)) / (1.0 - self.reflected(wo)).max(1e-6)
    }
}
