//! The photon pass (DESIGN.md step 3): photons leave lights chosen by power, at the pass
//! wavelength, and random-walk with Russian roulette. A photon is stored at every non-delta
//! vertex from the second on: the first is direct light, which next-event estimation counts.

use glam::Vec3;

use super::{PassSamples, PassStats, Renderer, MAX_DEPTH};
use crate::geometry::offset_origin;
use crate::materials::Transport;
use crate::sampling::{stream, Stream};

/// A stored photon.
#[derive(Clone, Copy, Debug)]
pub struct Photon {
    /// Where it landed.
    pub p: Vec3,
    /// Unit direction back toward where it came from.
    pub wi: Vec3,
    /// Geometric normal of the surface it landed on, facing `wi`.
    pub ng: Vec3,
    /// Its flux at the pass wavelength, already divided by the photons per pass.
    pub flux: f32,
}

/// Traces photon path `k` of `pass`, appending what it stores to `out`.
pub fn trace_photon(renderer: &Renderer, pass: &PassSamples, k: u64, out: &mut Vec<Photon>) -> PassStats {
    let scene = renderer.scene;
    let mut rng = stream(renderer.settings.seed, Stream::Photon, pass.index, k);
    let mut stats = PassStats::default();
    let Some((index, p_light)) = renderer.light_choice.sample(rng.next_1d()) else {
        return stats;
    };
    let Some(emitted) = scene.lights[index].emit_photon(rng.next_2d(), rng.next_2d(), pass.lambda_nm) else {
        return stats;
    };
    let mut flux = emitted.flux / (p_light * renderer.settings.photons_per_pass as f32);
    let (mut origin, mut direction) = (emitted.origin, emitted.direction);
    for depth in 0..MAX_DEPTH {
        stats.photon_rays += 1;
        let Some(hit) = renderer.accel.intersect(origin, direction, f32::INFINITY) else {
            break;
        };
        let surface = scene.surface(hit.triangle, hit.barycentric);
        let material = &scene.materials[surface.material as usize];
        let wo = -direction;
        let bsdf = material.bsdf(surface.uv, pass.lambda_nm, rng.next_1d());
        if !bsdf.is_delta() && depth > 0 {
            let ng = if surface.frame.ng.dot(wo) < 0.0 { -surface.frame.ng } else { surface.frame.ng };
            out.push(Photon { p: surface.p, wi: wo, ng, flux });
            stats.photons_stored += 1;
        }
        let Some(sample) =
            bsdf.sample(surface.frame, wo, rng.next_2d(), rng.next_1d(), Transport::Importance)
        else {
            break;
        };
        // Russian roulette with the throughput's change as the survival probability keeps the
        // flux of surviving photons nearly constant.
        let survive = sample.weight.min(1.0);
        if rng.next_1d() >= survive {
            break;
        }
        flux *= sample.weight / survive;
        origin = offset_origin(surface.p, surface.frame.ng, sample.wi);
        direction = sample.wi;
    }
    stats
}
