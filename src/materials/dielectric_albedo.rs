//! How much of the light a rough dielectric boundary receives it scatters once (reflected or
//! refracted, flux counted, so without refraction's `1 / eta^2`): its directional albedo
//! `E(mu, alpha, eta)`, tabulated once (on first use) against the cosine `mu` of the direction
//! light arrives from, the roughness and the index of the far side over the near one (`eta`
//! from 1/3 to 3: from inside or outside). The rest bounces between microfacets, which single
//! scattering loses; dividing the boundary's BSDF by `E` gives it back, as Cycles' Multiscatter
//! GGX glass does (its energy-preserving albedo scaling), so that frosted glass neither darkens
//! nor glows in a white furnace.
//!
//! Each entry is the mean over visible normals (Heitz 2018), on the same stratified grid as the
//! layer albedo tables (`layer_albedo.rs`), of `F G2 / G1` reflected plus `(1 - F) G2 / G1`
//! refracted.

use std::sync::LazyLock;

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use super::dielectric::{fresnel_dielectric, refract};
use super::layer_albedo::{alpha_at, blend, lerp_index, mu_at, MU_NODES, ROUGHNESS_NODES, STRATA};
use super::microfacet::{self, reflect};

/// Table nodes over `t = (eta - 1) / (eta + 1)` in [-T_MAX, T_MAX] (eta from 1/3 to 3).
const ETA_NODES: usize = 33;
const T_MAX: f32 = 0.5;

/// `E[t][roughness][mu]`.
static TABLE: LazyLock<Vec<f32>> = LazyLock::new(|| {
    (0..ETA_NODES * ROUGHNESS_NODES * MU_NODES)
        .into_par_iter()
        .map(|i| {
            let (t, r, m) = (i / (ROUGHNESS_NODES * MU_NODES), i / MU_NODES % ROUGHNESS_NODES, i % MU_NODES);
            albedo(alpha_at(r), eta_at(t), mu_at(m))
        })
        .collect()
});

fn eta_at(t: usize) -> f32 {
    let t = (t as f32 / (ETA_NODES - 1) as f32 * 2.0 - 1.0) * T_MAX;
    (1.0 + t) / (1.0 - t)
}

/// The single-scattering albedo at one roughness, index and cosine, by stratified sampling.
fn albedo(alpha: f32, eta: f32, mu: f32) -> f32 {
    let wo = Vec3::new((1.0 - mu * mu).sqrt(), 0.0, mu);
    let mut sum = 0.0f64;
    for i in 0..STRATA * STRATA {
        let u = (Vec2::new((i % STRATA) as f32, (i / STRATA) as f32) + 0.5) / STRATA as f32;
        let h = microfacet::sample_visible_normal(alpha, wo, u);
        let reflected = fresnel_dielectric(wo.dot(h), eta);
        let g = |wi: Vec3| microfacet::masking_shadowing(alpha, wo, wi) / microfacet::masking(alpha, wo);
        let wi = reflect(wo, h);
        if wi.z > 0.0 {
            sum += f64::from(reflected * g(wi));
        }
        if let Some(wi) = refract(wo, h, eta).filter(|wi| wi.z < 0.0) {
            sum += f64::from((1.0 - reflected) * g(wi));
        }
    }
    (sum / (STRATA * STRATA) as f64) as f32
}

/// `E(mu, alpha, eta)`: what a white rough dielectric boundary of GGX `alpha` scatters once of
/// the flux arriving at cosine `mu`, `eta` the index of the far side over the near one.
pub fn glass_albedo(alpha: f32, eta: f32, mu: f32) -> f32 {
    let table = &*TABLE;
    let r = lerp_index(alpha.max(0.0).sqrt(), ROUGHNESS_NODES);
    let t = lerp_index(((eta - 1.0) / (eta + 1.0) / T_MAX + 1.0) / 2.0, ETA_NODES);
    let m = lerp_index(mu.max(0.0).sqrt(), MU_NODES);
    blend(t, |t| blend(r, |r| blend(m, |m| table[(t * ROUGHNESS_NODES + r) * MU_NODES + m])))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{stream, Stream};

    /// The table against a converged integral, between its nodes, from outside and inside.
    #[test]
    fn the_table_matches_the_integral() {
        let mut rng = stream(3, Stream::Eye, 0, 0);
        for (alpha, eta, mu) in
            [(0.05f32, 1.5f32, 0.9f32), (0.3, 1.33, 0.5), (0.6, 1.0 / 1.5, 0.7), (0.2, 0.42, 0.3)]
        {
            let wo = Vec3::new((1.0 - mu * mu).sqrt(), 0.0, mu);
            let n = 400_000;
            let mut sum = 0.0f64;
            for _ in 0..n {
                let h = microfacet::sample_visible_normal(alpha, wo, rng.next_2d());
                let f = fresnel_dielectric(wo.dot(h), eta);
                let (wi, weight) = if rng.next_1d() < f {
                    (Some(reflect(wo, h)).filter(|w| w.z > 0.0), 1.0)
                } else {
                    (refract(wo, h, eta).filter(|w| w.z < 0.0), 1.0)
                };
                if let Some(wi) = wi {
                    sum += f64::from(
                        weight * microfacet::masking_shadowing(alpha, wo, wi)
                            / microfacet::masking(alpha, wo),
                    );
                }
            }
            let (table, exact) = (glass_albedo(alpha, eta, mu), (sum / n as f64) as f32);
            assert!((table - exact).abs() < 0.006, "{alpha} {eta} {mu}: {table} vs {exact}");
        }
    }
}
