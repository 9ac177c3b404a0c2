//! What a material reads at a surface point besides its normals: texture coordinates, the vertex
//! colour (`COLOR_0`) and the tangent a normal map is expressed in. A mesh without vertex colours
//! or tangents carries none, and its materials pay nothing for them.

use std::sync::Arc;

use glam::{Vec2, Vec3, Vec4};

use super::ShadingFrame;
use crate::spectrum::{RgbSpectrum, SampledSpectrum};
use crate::texture::{DataTexture, UV_SETS};

/// The vertex colour at barycentric weights `w` of a triangle whose corners' reflectance spectra
/// are `corners`, at four wavelengths, nm (spectra interpolated by value, as texels are).
pub fn vertex_colour(corners: [&RgbSpectrum; 3], w: Vec3, lambda_nm: Vec4) -> SampledSpectrum {
    let [a, b, c] = corners.map(|s| s.eval_lanes(lambda_nm));
    a * w.x + b * w.y + c * w.z
}

/// A surface point's inputs to its material.
#[derive(Clone, Copy, Debug)]
pub struct SurfaceInputs {
    /// Texture coordinates, one pair per set (zero where the mesh has no such set).
    pub uv: [Vec2; UV_SETS],
    /// `COLOR_0` at the path's wavelengths, multiplying the base colour (1 where the mesh has
    /// none: a multiplication costs less than a larger struct moved at every hit).
    pub colour: SampledSpectrum,
    /// World-space tangent (xyz) and handedness (w: the bitangent is `w n x t`); zero where the
    /// mesh has none.
    pub tangent: Vec4,
}

/// A tangent-space normal map (glTF `normalTexture`): RGB in [0, 1] to a normal in [-1, 1], x
/// and y scaled by `scale`.
#[derive(Clone, Debug)]
pub struct NormalMap {
    /// The image.
    pub texture: Arc<DataTexture>,
    /// glTF's `normalTexture.scale`.
    pub scale: f32,
}

impl Default for SurfaceInputs {
    /// A point with texture coordinates 0, no vertex colour and no tangent.
    fn default() -> Self {
        SurfaceInputs { uv: [Vec2::ZERO; UV_SETS], colour: SampledSpectrum::ONE, tangent: Vec4::ZERO }
    }
}

impl NormalMap {
    /// The shading frame with its normal bent by the map (the geometric normal unchanged). Without
    /// a tangent, or where the map's normal would face away from the surface, the frame is kept.
    pub fn apply(&self, inputs: &SurfaceInputs, frame: ShadingFrame) -> ShadingFrame {
        let t = inputs.tangent.truncate();
        if t == Vec3::ZERO {
            return frame;
        }
        let n = frame.n;
        // Gram-Schmidt: the interpolated tangent made perpendicular to the shading normal.
        let t = (t - n * n.dot(t)).normalize_or_zero();
        let b = n.cross(t) * inputs.tangent.w.signum();
        let texel = self.texture.eval(&inputs.uv) * 2.0 - Vec4::ONE;
        let local = Vec3::new(texel.x * self.scale, texel.y * self.scale, texel.z);
        let bent = (t * local.x + b * local.y + n * local.z).normalize_or_zero();
        if bent == Vec3::ZERO || !bent.is_finite() || bent.dot(frame.ng) * n.dot(frame.ng) <= 0.0 {
            return frame;
        }
        ShadingFrame { n: bent, ng: frame.ng }
    }
}
