//! The eye pass (DESIGN.md step 2): a camera ray per pixel, followed through delta bounces to the
//! first non-delta surface, where direct light is estimated by next-event estimation and a
//! visible point is left for the photons to be gathered at.

use glam::{Vec2, Vec3};

use super::{PassSamples, PassStats, Renderer, MAX_DEPTH};
use crate::geometry::offset_origin;
use crate::materials::{Bsdf, ShadingFrame, Transport};
use crate::sampling::{stream, Sampler, Stream};
use crate::scene::NOT_A_LIGHT;

/// Where a pixel's camera path met its first non-delta surface.
#[derive(Clone, Copy, Debug)]
pub struct VisiblePoint {
    /// Position.
    pub p: Vec3,
    /// Normals there.
    pub frame: ShadingFrame,
    /// Unit direction back along the path.
    pub wo: Vec3,
    /// The BSDF at the pass wavelength.
    pub bsdf: Bsdf,
    /// Path throughput from the camera to here.
    pub beta: f32,
}

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
    let (mut origin, mut direction) = scene.camera.ray(film, width as f32 / height as f32);
    let mut result = EyeResult { radiance: 0.0, point: None };
    let mut stats = PassStats::default();
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
        let bsdf = material.bsdf(material.reflectance(surface.uv, pass.lambda_nm), rng.next_1d());
        if bsdf == Bsdf::Black {
            break;
        }
        if !bsdf.is_delta() {
            let point = VisiblePoint { p: surface.p, frame: surface.frame, wo, bsdf, beta };
            let direct = light_sampled(renderer, pass, &point, &mut rng, &mut stats)
                + bsdf_sampled(renderer, pass, &point, &mut rng, &mut stats);
            result.radiance += beta * direct;
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

/// Veach's power heuristic for two strategies with densities `p` (this one) and `q`.
fn power_heuristic(p: f32, q: f32) -> f32 {
    if p.is_infinite() {
        return 1.0;
    }
    let (p2, q2) = (p * p, q * q);
    if p2 + q2 > 0.0 {
        p2 / (p2 + q2)
    } else {
        0.0
    }
}

/// Direct light by sampling a light (chosen by power) and a point on it, weighted by multiple
/// importance sampling against BSDF sampling (Veach 1997, chapter 9).
fn light_sampled(
    renderer: &Renderer,
    pass: &PassSamples,
    point: &VisiblePoint,
    rng: &mut Sampler,
    stats: &mut PassStats,
) -> f32 {
    let Some((index, p_choice)) = renderer.light_choice.sample(rng.next_1d()) else { return 0.0 };
    let light = &renderer.scene.lights[index];
    let Some(sample) = light.sample_incident(point.p, rng.next_2d(), pass.lambda_nm) else { return 0.0 };
    let ShadingFrame { n, ng } = point.frame;
    if ng.dot(sample.wi) * ng.dot(point.wo) <= 0.0 {
        return 0.0;
    }
    let f = point.bsdf.eval(n, point.wo, sample.wi);
    if f <= 0.0 {
        return 0.0;
    }
    stats.shadow_rays += 1;
    if !renderer.unoccluded(point.p, ng, sample.wi, sample.distance) {
        return 0.0;
    }
    let weight = if sample.pdf > 0.0 {
        power_heuristic(p_choice * sample.pdf, point.bsdf.pdf(n, point.wo, sample.wi))
    } else {
        1.0
    };
    f * n.dot(sample.wi).abs() * sample.radiance_over_pdf / p_choice * weight
}

/// Direct light by sampling the BSDF and looking at what emits along the sampled ray, weighted
/// by multiple importance sampling against light sampling.
fn bsdf_sampled(
    renderer: &Renderer,
    pass: &PassSamples,
    point: &VisiblePoint,
    rng: &mut Sampler,
    stats: &mut PassStats,
) -> f32 {
    let scene = renderer.scene;
    let (u, u_lobe) = (rng.next_2d(), rng.next_1d());
    let Some(sample) = point.bsdf.sample(point.frame, point.wo, u, u_lobe, Transport::Radiance) else {
        return 0.0;
    };
    if sample.pdf <= 0.0 || point.frame.ng.dot(sample.wi) * point.frame.ng.dot(point.wo) <= 0.0 {
        return 0.0;
    }
    stats.shadow_rays += 1;
    let origin = offset_origin(point.p, point.frame.ng, sample.wi);
    let light_pdf = |index: usize, q: Vec3| {
        renderer.light_choice.probability(index) * scene.lights[index].pdf_incident(point.p, sample.wi, q)
    };
    let Some(hit) = renderer.accel.intersect(origin, sample.wi, f32::INFINITY) else {
        return scene
            .distant_lights
            .iter()
            .map(|&i| {
                let radiance = scene.lights[i].escaped_radiance(sample.wi, pass.lambda_nm);
                sample.weight * radiance * power_heuristic(sample.pdf, light_pdf(i, Vec3::ZERO))
            })
            .sum();
    };
    let light = scene.triangle_lights[hit.triangle as usize];
    if light == NOT_A_LIGHT {
        return 0.0;
    }
    let surface = scene.surface(hit.triangle, hit.barycentric);
    let material = &scene.materials[surface.material as usize];
    let radiance = material.emitted(pass.lambda_nm, surface.frame.ng, -sample.wi);
    sample.weight * radiance * power_heuristic(sample.pdf, light_pdf(light as usize, surface.p))
}
