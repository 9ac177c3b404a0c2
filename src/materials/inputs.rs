//! What a material reads at a surface point besides its normals: texture coordinates, the vertex
//! colour (`COLOR_0`) and the tangent a normal map (`normal_map.rs`) is expressed in. A mesh without vertex colours
//! or tangents carries none, and its materials pay nothing for them.

use glam::{Vec2, Vec3, Vec4};

use crate::spectrum::{RgbSpectrum, SampledSpectrum};
use crate::texture::UV_SETS;

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
    /// `COLOR_0`'s alpha, multiplying the material's (1 where no mesh's vertex alpha cuts).
    pub alpha: f32,
}

impl Default for SurfaceInputs {
    /// A point with texture coordinates 0, no vertex colour and no tangent.
    fn default() -> Self {
        SurfaceInputs {
            uv: [Vec2::ZERO; UV_SETS],
            colour: SampledSpectrum::ONE,
            tangent: Vec4::ZERO,
            alpha: 1.0,
        }
    }
}
