//! `KHR_materials_clearcoat` (Blender's Principled Coat): a smooth or GGX dielectric layer of
//! index 1.5 over the whole material, with its own roughness and its own normal.
//!
//! As in Cycles' Principled BSDF (and the glTF specification's `fresnel_coat`), the coat reflects
//! `factor` times its microfacet BRDF, and everything under it is scaled by what the coat does not
//! reflect toward the viewer, `1 - factor E(wo)`, with `E` the coat's directional albedo
//! ([`super::layer_albedo`]), combined with what lies under it as `layering.rs` says. A white
//! Lambertian base under any coat therefore reflects exactly everything.
//!
//! Without a clearcoat normal texture the coat follows the interpolated normal, not the base's
//! normal map (glTF; Blender 5.0's Cycles likewise reads an unconnected Coat Normal as the
//! interpolated normal).

use std::sync::Arc;

use glam::{Vec3, Vec4};

use super::inputs::SurfaceInputs;
use super::normal_map::NormalMap;
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
    pub coat: Coat,
}

impl CoatAt {
    /// The coat's own reflection as a BSDF: a mirror when smooth, else the microfacet layer over
    /// a black base.
    pub fn bsdf(&self, wo: Vec3) -> Bsdf {
        match self.coat.alpha {
            0.0 => Bsdf::Mirror { weight: self.coat.fresnel(self.frame.n().dot(wo).abs().min(1.0)) },
            _ => Plastic { base: Vec4::ZERO, coat: self.coat }.bsdf(),
        }
    }
}
