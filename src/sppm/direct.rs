//! Direct light at a visible point: a light sample and a BSDF sample, combined by multiple
//! importance sampling with the power heuristic (Veach 1997, chapter 9), so neither small bright
//! lights nor emitters right beside the point (a lamp on a wall) give fireflies.

use glam::Vec3;

use super::{PassStats, Renderer, VisiblePoint};
use crate::geometry::offset_origin;
use crate::materials::{ShadingFrame, Transport};
use crate::sampling::Sampler;
use crate::scene::NOT_A_LIGHT;

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

/// Direct light at one visible point at the pass wavelength.
pub struct DirectLight<'a> {
    /// The scene, its BVH and its light choice.
    pub renderer: &'a Renderer<'a>,
    /// The pass wavelength.
    pub lambda_nm: f32,
    /// Where the light arrives.
    pub point: &'a VisiblePoint,
}

impl DirectLight<'_> {
    /// One light-sampled and one BSDF-sampled estimate, combined by MIS.
    pub fn estimate(&self, rng: &mut Sampler, stats: &mut PassStats) -> f32 {
        self.light_sampled(rng, stats) + self.bsdf_sampled(rng, stats)
    }

    /// Direct light by sampling a light (chosen by power) and a point on it, weighted by multiple
    /// importance sampling against BSDF sampling (Veach 1997, chapter 9).
    fn light_sampled(&self, rng: &mut Sampler, stats: &mut PassStats) -> f32 {
        let (renderer, point, lambda_nm) = (self.renderer, self.point, self.lambda_nm);
        let Some((index, p_choice)) = renderer.light_choice.sample(rng.next_1d()) else { return 0.0 };
        let light = &renderer.scene.lights[index];
        let Some(sample) = light.sample_incident(point.p, rng.next_2d(), lambda_nm) else { return 0.0 };
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
    fn bsdf_sampled(&self, rng: &mut Sampler, stats: &mut PassStats) -> f32 {
        let (renderer, point, lambda_nm) = (self.renderer, self.point, self.lambda_nm);
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
                    let radiance = scene.lights[i].escaped_radiance(sample.wi, lambda_nm);
                    sample.weight * radiance * power_heuristic(sample.pdf, light_pdf(i, Vec3::ZERO))
                })
                .sum();
        };
        let light = scene.triangle_light(hit.triangle);
        if light == NOT_A_LIGHT {
            return 0.0;
        }
        let surface = scene.surface(hit.triangle, hit.barycentric);
        let material = &scene.materials[surface.material as usize];
        let radiance = material.emitted(lambda_nm, surface.frame.ng, -sample.wi);
        sample.weight * radiance * power_heuristic(sample.pdf, light_pdf(light as usize, surface.p))
    }
}
