//! Direct light at a visible point: a light sample and a BSDF sample, combined by multiple
//! importance sampling with the power heuristic (Veach 1997, chapter 9), so neither small bright
//! lights nor emitters right beside the point (a lamp on a wall) give fireflies.

use glam::Vec3;

use crate::geometry::offset_origin;
use crate::materials::{BsdfSample, Transport};
use crate::sampling::PixelSampler;
use crate::scene::NOT_A_LIGHT;
use crate::spectrum::{SampledSpectrum, Wavelengths};
use crate::transport::context::{PassStats, Renderer, VisiblePoint};
use crate::transport::media::Media;
use crate::transport::see_through;
use crate::transport::shadow::{self, ShadowRay};

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

/// Direct light at one visible point at the pass's wavelengths.
pub struct DirectLight<'a> {
    /// The scene, its BVH and its light choice.
    pub renderer: &'a Renderer<'a>,
    /// The pass's wavelengths.
    pub wavelengths: &'a Wavelengths,
    /// Where the light arrives.
    pub point: &'a VisiblePoint,
    /// The volumes the path that reached the point is in.
    pub media: Media,
    /// The point's material.
    pub material: u32,
}

/// One direct-light estimate, and the ray it travelled (`None` when the term is zero whatever
/// else is in the scene).
#[derive(Clone, Copy, Debug)]
pub struct DirectTerm {
    /// The weighted radiance it adds.
    pub value: SampledSpectrum,
    /// What must be free for it to count.
    pub ray: Option<ShadowRay>,
}

impl DirectTerm {
    /// A term that is zero whatever else is in the scene.
    pub const ZERO: DirectTerm = DirectTerm { value: SampledSpectrum::ZERO, ray: None };
}

impl DirectLight<'_> {
    /// What the volume a ray leaving the point toward `wi` runs through keeps of light over
    /// `length` (all of it outside volumes).
    fn kept(&self, wi: Vec3, length: f32) -> SampledSpectrum {
        let ends = (self.point.frame.ng(), self.point.wo);
        shadow::kept(self.renderer, self.wavelengths, (self.media, self.material), ends, wi, length)
    }

    /// One light-sampled and one BSDF-sampled term, to be combined by MIS (their sum).
    pub fn estimate(&self, rng: &mut PixelSampler, stats: &mut PassStats) -> [DirectTerm; 2] {
        [self.light_sampled(rng, stats), self.bsdf_sampled(rng, stats)]
    }

    /// Direct light by sampling a light (chosen by power) and a point on it, weighted by multiple
    /// importance sampling against BSDF sampling (Veach 1997, chapter 9).
    fn light_sampled(&self, rng: &mut PixelSampler, stats: &mut PassStats) -> DirectTerm {
        let (renderer, point, wavelengths) = (self.renderer, self.point, self.wavelengths);
        let Some((index, p_choice)) = renderer.choose_light(point.p, point.frame.n(), rng.next_1d()) else {
            return DirectTerm::ZERO;
        };
        let light = &renderer.scene.lights[index];
        let Some(sample) = light.sample_incident(point.p, rng.next_2d(), wavelengths) else {
            return DirectTerm::ZERO;
        };
        let (n, ng) = (point.frame.n(), point.frame.ng());
        if !point.bsdf.leaves_toward(ng, point.wo, sample.wi) {
            return DirectTerm::ZERO;
        }
        let f = point.bsdf.eval(point.frame, point.wo, sample.wi);
        if f.max_element() <= 0.0 {
            return DirectTerm::ZERO;
        }
        stats.shadow_rays += 1;
        let ray = ShadowRay::leaving(point.p, (ng, point.scale()), sample.wi, sample.distance);
        let through = ray.visibility(renderer, wavelengths);
        if through <= 0.0 {
            return DirectTerm::ZERO;
        }
        let through = self.kept(sample.wi, sample.distance) * through;
        let weight = if sample.pdf > 0.0 {
            power_heuristic(p_choice * sample.pdf, point.bsdf.pdf(point.frame, point.wo, sample.wi))
        } else {
            1.0
        };
        let value = f * n.dot(sample.wi).abs() * sample.radiance_over_pdf / p_choice * weight * through;
        DirectTerm { value, ray: Some(ray) }
    }

    /// Direct light by sampling the BSDF and looking at what emits along the sampled ray, weighted
    /// by multiple importance sampling against light sampling.
    fn bsdf_sampled(&self, rng: &mut PixelSampler, stats: &mut PassStats) -> DirectTerm {
        let (renderer, point, wavelengths) = (self.renderer, self.point, self.wavelengths);
        let scene = renderer.scene;
        let u = rng.next_2d();
        let u_lobe = point.bsdf.lobe_number(|| rng.next_1d());
        let Some(sample) = point.bsdf.sample(point.frame, point.wo, u, u_lobe, Transport::Radiance) else {
            return DirectTerm::ZERO;
        };
        if sample.pdf <= 0.0 || !point.bsdf.leaves_toward(point.frame.ng(), point.wo, sample.wi) {
            return DirectTerm::ZERO;
        }
        stats.shadow_rays += 1;
        let origin = offset_origin(point.p, point.frame.ng(), sample.wi, point.scale());
        let light_pdf = |index: usize, q: Vec3| {
            let p_choice = renderer.light_probability(point.p, point.frame.n(), index);
            p_choice * scene.lights[index].pdf_incident(point.p, sample.wi, q)
        };
        let (hit, through) = if renderer.has_cut_away_surfaces {
            see_through::first_hit(renderer, wavelengths, origin, sample.wi)
        } else {
            (renderer.accel.intersect(origin, sample.wi, f32::INFINITY), 1.0)
        };
        // From the origin to the surface hit, across any cut-away surfaces before it.
        let t_max = match hit {
            Some(h) if renderer.has_cut_away_surfaces => (h.p - origin).dot(sample.wi).max(h.t),
            Some(h) => h.t,
            None => f32::INFINITY,
        };
        // Sphere lights on the way hide nothing behind them: what they add needs the ray free to
        // the farthest of them.
        let (spheres, reach) = scene.spheres_met(origin, sample.wi, t_max).fold(
            (SampledSpectrum::ZERO, 0.0f32),
            |(sum, reach), (i, sphere, t)| {
                let weight = power_heuristic(sample.pdf, light_pdf(i, origin + sample.wi * t)) * through;
                let radiance = sphere.radiance(-sample.wi, wavelengths) * self.kept(sample.wi, t);
                (sum + sample.weight * radiance * weight, reach.max(t))
            },
        );
        let sample = BsdfSample { weight: sample.weight * through * self.kept(sample.wi, t_max), ..sample };
        let ray = Some(ShadowRay { origin, direction: sample.wi, t_max });
        let Some(hit) = hit else {
            let value = scene
                .distant_lights
                .iter()
                .map(|&i| {
                    let radiance = scene.lights[i].escaped_radiance(sample.wi, wavelengths);
                    sample.weight * radiance * power_heuristic(sample.pdf, light_pdf(i, Vec3::ZERO))
                })
                .sum::<SampledSpectrum>();
            return DirectTerm { value: value + spheres, ray };
        };
        let light = scene.triangle_light(hit.triangle);
        if light == NOT_A_LIGHT {
            let ray = Some(ShadowRay { origin, direction: sample.wi, t_max: reach });
            return if reach > 0.0 { DirectTerm { value: spheres, ray } } else { DirectTerm::ZERO };
        }
        let surface = scene.surface(&hit, wavelengths);
        let material = &scene.materials[surface.material as usize];
        let radiance = material.emitted(&surface.inputs, wavelengths, surface.frame.ng(), -sample.wi);
        let value =
            sample.weight * radiance * power_heuristic(sample.pdf, light_pdf(light as usize, surface.p));
        DirectTerm { value: value + spheres, ray }
    }
}
