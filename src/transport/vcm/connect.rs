//! Connections at a camera vertex: to a point on a light (next-event estimation) and to each
//! vertex of the light subpath paired with the pixel, both weighted against every other
//! technique.

use glam::Vec3;

use super::light_paths::{joined, LightVertex};
use super::merge::CameraVertex;
use super::mis::{connection, DirectWeight, End, PassWeights};
use super::{finite, visibility};
use crate::sampling::PixelSampler;
use crate::spectrum::SampledSpectrum;
use crate::transport::context::{PassSamples, PassStats, Renderer};
use crate::transport::shadow::kept;

/// Whether light arriving at `camera` from `wi` can leave toward its way back.
fn reaches(camera: &CameraVertex, wi: Vec3) -> bool {
    camera.bsdf.leaves_toward(camera.frame.ng(), camera.wo, wi)
}

/// Next-event estimation at `camera` (on a triangle whose largest coordinate is `scale`): one
/// light and a point on it, weighted radiance times the camera throughput.
pub fn direct_light(
    renderer: &Renderer,
    pass: &PassSamples,
    (camera, scale): (&CameraVertex, f32),
    rng: &mut PixelSampler,
    stats: &mut PassStats,
) -> SampledSpectrum {
    let n = camera.frame.n();
    let Some((index, p_choice)) = renderer.choose_light(camera.p, n, rng.next_1d()) else {
        return SampledSpectrum::ZERO;
    };
    let light = &renderer.scene.lights[index];
    let Some(sample) = light.sample_surface_incident(camera.p, rng.next_2d(), &pass.wavelengths) else {
        return SampledSpectrum::ZERO;
    };
    if !reaches(camera, sample.wi) {
        return SampledSpectrum::ZERO;
    }
    let f = camera.bsdf.eval(camera.frame, camera.wo, sample.wi);
    let q = camera.p + sample.wi * sample.distance;
    let Some(density) = light.emission_density(q, -sample.wi) else { return SampledSpectrum::ZERO };
    if f.max_element() <= 0.0 {
        return SampledSpectrum::ZERO;
    }
    let direct = match (density.delta, density.finite) {
        (false, _) => sample.pdf,
        (true, true) => sample.distance * sample.distance,
        (true, false) => 1.0,
    };
    let cos_here = n.dot(sample.wi).abs();
    let mis = DirectWeight {
        p_choice,
        direct,
        bsdf_forward: if density.delta { 0.0 } else { camera.bsdf.pdf(camera.frame, camera.wo, sample.wi) },
        bsdf_reverse: camera.bsdf.pdf(camera.frame, sample.wi, camera.wo),
        emission: density.emission * renderer.light_choice.probability(index),
        cos_light: density.cos,
        cos_here,
    };
    let weight = match camera.segments {
        1 => mis.weight(&camera.partials.without_light_tracing()),
        _ => mis.weight(&camera.partials),
    };
    let through =
        visibility(renderer, pass, (camera.p, camera.frame.ng(), scale), sample.wi, sample.distance, stats);
    if through <= 0.0 {
        return SampledSpectrum::ZERO;
    }
    let kept = kept(
        renderer,
        &pass.wavelengths,
        camera.media,
        (camera.frame.ng(), camera.wo),
        sample.wi,
        sample.distance,
    );
    finite(camera.beta * f * kept * sample.radiance_over_pdf * (cos_here * weight * through / p_choice))
}

/// Connections from `camera` (on a triangle whose largest coordinate is `scale`) to each vertex
/// of `light_path`, for paths of at most `max_segments`: weighted radiance times the camera
/// throughput.
pub fn connect(
    renderer: &Renderer,
    pass: &PassSamples,
    weights: &PassWeights,
    (camera, scale): (&CameraVertex, f32),
    light_path: &[LightVertex],
    max_segments: u32,
    stats: &mut PassStats,
) -> SampledSpectrum {
    let mut sum = SampledSpectrum::ZERO;
    for light in light_path {
        if light.segments + camera.segments + 1 > max_segments {
            break;
        }
        let offset = light.p - camera.p;
        let distance2 = offset.length_squared();
        let distance = distance2.sqrt();
        if !(distance > 0.0) {
            continue;
        }
        let w = offset / distance;
        if !reaches(camera, w) || !light.reaches(-w) {
            continue;
        }
        let f_camera = camera.bsdf.eval(camera.frame, camera.wo, w);
        let f_light = light.eval_toward(-w);
        let (cos_camera, cos_light) = (camera.frame.n().dot(w).abs(), light.lobe.frame.n().dot(w).abs());
        let value = f_camera * f_light * (cos_camera * cos_light / distance2);
        if value.max_element() <= 0.0 {
            continue;
        }
        let (bsdf, frame) = (&light.lobe.bsdf, light.lobe.frame);
        let (light_partials, light_merged) = light.partials_seen_from(camera.merging);
        let light_end = End {
            partials: light_partials,
            forward: bsdf.pdf(frame, light.wo, -w),
            reverse: bsdf.pdf(frame, -w, light.wo),
            cos: cos_light,
            merged: light_merged,
        };
        let camera_end = End {
            partials: camera.partials,
            forward: camera.bsdf.pdf(camera.frame, camera.wo, w),
            reverse: camera.bsdf.pdf(camera.frame, w, camera.wo),
            cos: cos_camera,
            merged: camera.merging.merges(),
        };
        let weight = connection(weights, &light_end, &camera_end, distance2);
        let through = visibility(renderer, pass, (camera.p, camera.frame.ng(), scale), w, distance, stats);
        let throughput = joined(camera.beta, camera.hero_only, light.throughput, light.hero_only);
        let kept =
            kept(renderer, &pass.wavelengths, camera.media, (camera.frame.ng(), camera.wo), w, distance);
        let radiance = throughput * value * kept * (weight * through);
        if through > 0.0 && radiance.is_finite() {
            sum += radiance;
        }
    }
    sum
}
