//! Denoising guides, as Cycles defines its Denoising Albedo and Denoising Normal passes: what the
//! camera ray sees first past mirrors, clear glass and cut-away surfaces (their tint carried
//! along): the albedo of that surface and its shading normal, in the camera's view space (x
//! right, y up, z toward the viewer, as Blender's view space). The world, where the ray leaves
//! the scene, has albedo 1 and no normal.
//!
//! The albedo is the surface's directional albedo seen from the ray, estimated with one sample
//! of its BSDF per pass (so every lobe, layer and texture is covered by one definition and the
//! mean over passes converges to it). Guides are traced only when asked for
//! (`--denoising-passes`), from the pass's own camera samples: a pass without them is unchanged.

use glam::Vec3;

use super::context::{collect_counting, PassSamples, Renderer, MAX_DEPTH};
use crate::geometry::offset_origin;
use crate::materials::{Bsdf, Transport};
use crate::spectrum::SampledSpectrum;
use crate::transport::eye::start_eye_path;

/// One pixel's guides for one pass.
#[derive(Clone, Copy, Debug, Default)]
pub struct Guide {
    /// Albedo at the pass's wavelengths.
    pub albedo: SampledSpectrum,
    /// Unit shading normal in view space, or zero.
    pub normal: Vec3,
}

impl Renderer<'_> {
    /// Every pixel's guides for `pass`, in row-major order.
    pub fn trace_guides(&self, pass: &PassSamples) -> Vec<Guide> {
        let pixels = (self.settings.width * self.settings.height) as usize;
        collect_counting(pixels, |pixel| (trace_guide(self, pass, pixel), Default::default())).0
    }
}

/// Follows pixel `pixel`'s camera ray of `pass` through delta lobes to the surface it sees.
fn trace_guide(renderer: &Renderer, pass: &PassSamples, pixel: usize) -> Guide {
    let scene = renderer.scene;
    let (mut state, _) = start_eye_path(renderer, pass, pixel);
    let camera = &scene.camera;
    let to_view = |n: Vec3| Vec3::new(n.dot(camera.right), n.dot(camera.up), -n.dot(camera.forward));
    for _ in 0..MAX_DEPTH {
        let direction = Vec3::from(state.direction);
        let Some(hit) = renderer.accel.intersect(state.origin.into(), direction, f32::INFINITY) else {
            return Guide { albedo: state.beta, normal: Vec3::ZERO };
        };
        let surface = scene.surface(&hit, &pass.wavelengths);
        let material = &scene.materials[surface.material as usize];
        let wo = -direction;
        let rng = &mut state.rng;
        let lobe = material.lobe(&surface.inputs, surface.frame, wo, &pass.wavelengths, rng.next_1d());
        if lobe.bsdf == Bsdf::PassThrough {
            state.origin = offset_origin(surface.p, surface.frame.ng(), direction, surface.scale).into();
            continue;
        }
        let normal = to_view(lobe.frame.n());
        let u_lobe = lobe.bsdf.lobe_number(|| rng.next_1d());
        let sample = lobe.bsdf.sample(lobe.frame, wo, rng.next_2d(), u_lobe, Transport::Radiance);
        let Some(sample) = sample.filter(|_| lobe.bsdf.is_delta()) else {
            let albedo = sample.map_or(SampledSpectrum::ZERO, |s| s.weight * lobe.weight);
            return Guide { albedo: state.beta * albedo, normal };
        };
        state.beta *= sample.weight * lobe.weight;
        state.origin = offset_origin(surface.p, surface.frame.ng(), sample.wi, surface.scale).into();
        state.direction = sample.wi.into();
    }
    Guide::default()
}
