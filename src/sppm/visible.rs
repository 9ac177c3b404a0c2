//! The eye pass (DESIGN.md step 2): a camera ray per pixel, followed through delta bounces to the
//! first non-delta surface, where direct light is estimated by next-event estimation and a
//! visible point is left for the photons to be gathered at (direct light: [`DirectLight`]).

use glam::Vec2;

use super::direct::DirectLight;
use super::{PassSamples, PassStats, Renderer, VisiblePoint, MAX_DEPTH};
use crate::geometry::offset_origin;
use crate::materials::{Bsdf, Transport};
use crate::sampling::{stream, Stream};

/// A pixel's eye path: the radiance found along it, and its visible point if it has one.
#[derive(Clone, Copy, Debug)]
pub struct EyeResult {
    /// Emission seen along the path plus direct light at the visible point, times throughput.
    pub radiance: f32,
    /// Where photons are gathered.
    pub point: Option<VisiblePoint>,
}

/// Traces pixel `pixel`'s camera path for `pass`.
pub fn trace_eye_path(renderer: &Renderer, pass: &PassSamples, pixel: usize) -> (EyeResult, PassStats) {
    let settings = &renderer.settings;
    let scene = renderer.scene;
    let mut rng = stream(settings.seed, Stream::Eye, pass.index, pixel as u64);
    let (width, height) = (settings.width as usize, settings.height as usize);
    let film = (Vec2::new((pixel % width) as f32, (pixel / width) as f32) + rng.next_2d())
        / Vec2::new(width as f32, height as f32);
    let mut stats = PassStats::default();
    let aspect = width as f32 / height as f32;
    let (mut origin, mut direction) = match scene.camera.lens {
        Some(_) => {
            stats.lens_samples += 1;
            scene.camera.ray_through_lens(film, aspect, rng.next_2d())
        }
        None => scene.camera.ray(film, aspect),
    };
    let mut result = EyeResult { radiance: 0.0, point: None };
    let mut beta = 1.0f32;
    for _ in 0..MAX_DEPTH {
        stats.eye_rays += 1;
        let Some(hit) = renderer.accel.intersect(origin, direction, f32::INFINITY) else {
            result.radiance += beta * scene.escaped_radiance(direction, pass.lambda_nm);
            break;
        };
        let surface = scene.surface(hit.triangle, hit.barycentric);
        let material = &scene.materials[surface.material as usize];
        let wo = -direction;
        result.radiance += beta * material.emitted(pass.lambda_nm, surface.frame.ng, wo);
        let bsdf = material.bsdf(surface.uv, pass.lambda_nm, rng.next_1d());
        if bsdf == Bsdf::Black {
            break;
        }
        if !bsdf.is_delta() {
            let point = VisiblePoint { p: surface.p, frame: surface.frame, wo, bsdf, beta };
            let direct = DirectLight { renderer, lambda_nm: pass.lambda_nm, point: &point };
            result.radiance += beta * direct.estimate(&mut rng, &mut stats);
            result.point = Some(point);
            break;
        }
        let Some(sample) = bsdf.sample(surface.frame, wo, rng.next_2d(), rng.next_1d(), Transport::Radiance)
        else {
            break;
        };
        beta *= sample.weight;
        origin = offset_origin(surface.p, surface.frame.ng, sample.wi);
        direction = sample.wi;
    }
    (result, stats)
}
