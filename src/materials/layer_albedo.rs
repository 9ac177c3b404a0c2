//! How much a GGX dielectric specular layer reflects: its directional albedo `E(mu)` against the
//! cosine `mu` of the direction it is seen from, tabulated once (on first use) against roughness
//! and index, for the layer's base below it to take what the layer does not reflect (glTF 2.0
//! appendix B's energy conservation; Cycles' Principled BSDF scales its base by the same albedo).
//!
//! The layer's Fresnel term is `F = f0 + (1 - f0) s(mu_h)` (Cycles' generalised Schlick for a
//! tinted dielectric), where `s` is the exact dielectric Fresnel at index `eta` remapped to run
//! from 0 at normal incidence to 1 at grazing. `F` is linear in `f0`, so the albedo is
//! `f0 E1 + (1 - f0) Es`, with `E1` the albedo of GGX with `F = 1` and `Es` that with `F = s`:
//! two scalar tables serve every tint and specular level. `E1` also gives a metal's
//! multiple-scattering compensation (`conductor.rs`).
//!
//! Each entry is the mean of `F G2 / G1` over visible normals (Heitz 2018) on a stratified
//! 32 x 32 grid of samples, within 0.5% of a converged integral (tested).

use std::sync::LazyLock;

use glam::{Vec2, Vec3};

use super::dielectric::fresnel_dielectric;
use super::microfacet;
use super::microfacet::reflect;

/// Table nodes over `sqrt(mu)`, `mu` the cosine of the viewing direction (denser toward grazing,
/// where the albedo changes fastest).
pub(super) const MU_NODES: usize = 32;
/// Table nodes over perceptual roughness `sqrt(alpha)` in [0, 1].
pub(super) const ROUGHNESS_NODES: usize = 32;
/// Table nodes over `t = (eta - 1) / (eta + 1)` in [0, T_MAX] (eta from 1 to 4).
const ETA_NODES: usize = 16;
const T_MAX: f32 = 0.6;
/// Strata per side of the sample grid of each entry.
pub(super) const STRATA: usize = 32;

/// The albedo tables: `E1[roughness][mu]`, `Es[t][roughness][mu]`, and their cosine-weighted
/// hemispherical means.
struct Tables {
    e1: Vec<f32>,
    es: Vec<f32>,
    e1_mean: Vec<f32>,
    es_mean: Vec<f32>,
}

static TABLES: LazyLock<Tables> = LazyLock::new(Tables::compute);

/// The Fresnel remap `s(cos)`: 0 at normal incidence, 1 at grazing, exact Fresnel in between.
pub fn fresnel_remap(cos_h: f32, eta: f32) -> f32 {
    let f0 = f0_of_eta(eta);
    if f0 >= 1.0 {
        return 1.0;
    }
    ((fresnel_dielectric(cos_h, eta) - f0) / (1.0 - f0)).clamp(0.0, 1.0)
}

/// Normal-incidence reflectance of index `eta`.
pub fn f0_of_eta(eta: f32) -> f32 {
    let t = (eta - 1.0) / (eta + 1.0);
    t * t
}

/// The index whose normal-incidence reflectance is `f0` (below 1).
pub fn eta_of_f0(f0: f32) -> f32 {
    let t = f0.clamp(0.0, 0.99).sqrt();
    (1.0 + t) / (1.0 - t)
}

impl Tables {
    /// The tables, their roughness rows shared among as many threads as the render's pool has (a
    /// million samples of 17 Fresnel terms each: 0.14 s on one core, paid by every render of a
    /// scene with a glTF dielectric or a rough metal). Plain threads, not the pool's: a pool worker
    /// waiting for a row could take up render work that reads the tables being built.
    fn compute() -> Self {
        let threads = rayon::current_num_threads().clamp(1, ROUGHNESS_NODES);
        let rows: Vec<(usize, Vec<(f32, [f32; ETA_NODES])>)> = std::thread::scope(|scope| {
            let workers: Vec<_> = (0..threads)
                .map(|first| {
                    scope.spawn(move || {
                        let row = |r| (0..MU_NODES).map(|m| entry(alpha_at(r), mu_at(m))).collect();
                        (first..ROUGHNESS_NODES).step_by(threads).map(|r| (r, row(r))).collect::<Vec<_>>()
                    })
                })
                .collect();
            workers.into_iter().flat_map(|w| w.join().expect("an albedo table row")).collect()
        });
        let mut e1 = vec![0.0; ROUGHNESS_NODES * MU_NODES];
        let mut es = vec![0.0; ETA_NODES * ROUGHNESS_NODES * MU_NODES];
        for (r, row) in rows {
            for (m, (one, remapped)) in row.into_iter().enumerate() {
                e1[r * MU_NODES + m] = one;
                for (t, value) in remapped.into_iter().enumerate() {
                    es[(t * ROUGHNESS_NODES + r) * MU_NODES + m] = value;
                }
            }
        }
        let e1_mean = e1.chunks(MU_NODES).map(hemispherical_mean).collect();
        let es_mean = es.chunks(MU_NODES).map(hemispherical_mean).collect();
        Tables { e1, es, e1_mean, es_mean }
    }
}

pub(super) fn mu_at(m: usize) -> f32 {
    // The grazing node sits just above zero, where the albedo is still defined.
    (m as f32 / (MU_NODES - 1) as f32).powi(2).max(1e-4)
}

pub(super) fn alpha_at(r: usize) -> f32 {
    let roughness = (r as f32 / (ROUGHNESS_NODES - 1) as f32).max(0.02);
    roughness * roughness
}

fn eta_at(t: usize) -> f32 {
    let t = t as f32 / (ETA_NODES - 1) as f32 * T_MAX;
    (1.0 + t) / (1.0 - t)
}

/// `E1` and, for each index node, `Es` at one roughness and viewing cosine.
fn entry(alpha: f32, mu: f32) -> (f32, [f32; ETA_NODES]) {
    let wo = Vec3::new((1.0 - mu * mu).sqrt(), 0.0, mu);
    let (mut one, mut remapped) = (0.0f64, [0.0f64; ETA_NODES]);
    for i in 0..STRATA * STRATA {
        let u = (Vec2::new((i % STRATA) as f32, (i / STRATA) as f32) + 0.5) / STRATA as f32;
        let h = microfacet::sample_visible_normal(alpha, wo, u);
        let wi = reflect(wo, h);
        if wi.z <= 0.0 {
            continue;
        }
        let weight = microfacet::masking_shadowing(alpha, wo, wi) / microfacet::masking(alpha, wo);
        one += f64::from(weight);
        for (t, sum) in remapped.iter_mut().enumerate() {
            *sum += f64::from(weight * fresnel_remap(wo.dot(h), eta_at(t)));
        }
    }
    let n = (STRATA * STRATA) as f64;
    ((one / n) as f32, remapped.map(|s| (s / n) as f32))
}

/// `2 int E(mu) mu dmu = 4 int E x^3 dx` (with `mu = x^2`) by the trapezoid rule over the
/// table's nodes.
fn hemispherical_mean(e: &[f32]) -> f32 {
    let h = 1.0 / (MU_NODES - 1) as f32;
    let term = |m: usize| e[m] * (m as f32 * h).powi(3);
    ((0..MU_NODES - 1).map(|m| (term(m) + term(m + 1)) * h / 2.0).sum::<f32>() * 4.0).min(1.0)
}

/// Linear interpolation weights for `x` in [0, 1] over `nodes` evenly spaced nodes.
pub(super) fn lerp_index(x: f32, nodes: usize) -> (usize, f32) {
    let f = x.clamp(0.0, 1.0) * (nodes - 1) as f32;
    let i = (f as usize).min(nodes - 2);
    (i, f - i as f32)
}

/// A GGX dielectric layer's albedo at one roughness and index: `E1` and `Es` against `mu`, and
/// their means, with the table rows and weights found once per BSDF.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LayerAlbedo {
    /// Roughness node and the weight of the next one.
    r: (usize, f32),
    /// Index node and the weight of the next one.
    t: (usize, f32),
    /// Cosine-weighted means of `E1` and `Es`.
    pub means: Vec2,
}

impl LayerAlbedo {
    /// The layer of GGX `alpha` and index `eta`.
    pub fn new(alpha: f32, eta: f32) -> Self {
        let r = lerp_index(alpha.max(0.0).sqrt(), ROUGHNESS_NODES);
        let t = lerp_index((eta - 1.0) / (eta + 1.0) / T_MAX, ETA_NODES);
        let tables = &*TABLES;
        let e1 = blend(r, |r| tables.e1_mean[r]);
        let es = blend(t, |t| blend(r, |r| tables.es_mean[t * ROUGHNESS_NODES + r]));
        LayerAlbedo { r, t, means: Vec2::new(e1, es) }
    }

    /// `E1(mu)` and `Es(mu)`.
    pub fn at(&self, mu: f32) -> Vec2 {
        let tables = &*TABLES;
        let m = lerp_index(mu.max(0.0).sqrt(), MU_NODES);
        let e1 = blend(self.r, |r| blend(m, |m| tables.e1[r * MU_NODES + m]));
        let es = blend(self.t, |t| {
            blend(self.r, |r| blend(m, |m| tables.es[(t * ROUGHNESS_NODES + r) * MU_NODES + m]))
        });
        Vec2::new(e1, es)
    }
}

/// The albedo of GGX of `alpha` with `F = 1` seen from cosine `mu`, and its cosine-weighted mean
/// over the hemisphere: `E1(mu)` and `E1_avg`.
pub fn white_ggx_albedo(alpha: f32, mu: f32) -> (f32, f32) {
    let tables = &*TABLES;
    let r = lerp_index(alpha.max(0.0).sqrt(), ROUGHNESS_NODES);
    let m = lerp_index(mu.max(0.0).sqrt(), MU_NODES);
    let e = blend(r, |r| blend(m, |m| tables.e1[r * MU_NODES + m]));
    (e, blend(r, |r| tables.e1_mean[r]))
}

/// `value` interpolated linearly between node `i` and `i + 1` with weight `f` on the second.
pub(super) fn blend((i, f): (usize, f32), value: impl Fn(usize) -> f32) -> f32 {
    value(i) * (1.0 - f) + value(i + 1) * f
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{stream, Stream};

    /// The tables against a converged integral of `F G2 / G1` over visible normals, between
    /// their nodes.
    #[test]
    fn tables_match_the_integral() {
        let mut rng = stream(1, Stream::Eye, 0, 0);
        for (alpha, eta, mu) in
            [(0.05f32, 1.5f32, 0.9f32), (0.3, 1.33, 0.5), (0.7, 2.4, 0.2), (0.15, 1.9, 0.05)]
        {
            let wo = Vec3::new((1.0 - mu * mu).sqrt(), 0.0, mu);
            let n = 400_000;
            let (mut one, mut remapped) = (0.0f64, 0.0f64);
            for _ in 0..n {
                let h = microfacet::sample_visible_normal(alpha, wo, rng.next_2d());
                let wi = reflect(wo, h);
                if wi.z > 0.0 {
                    let g = microfacet::masking_shadowing(alpha, wo, wi) / microfacet::masking(alpha, wo);
                    one += f64::from(g);
                    remapped += f64::from(g * fresnel_remap(wo.dot(h), eta));
                }
            }
            let table = LayerAlbedo::new(alpha, eta).at(mu);
            let exact = Vec2::new((one / n as f64) as f32, (remapped / n as f64) as f32);
            assert!((table - exact).abs().max_element() < 0.005, "{alpha} {eta} {mu}: {table} vs {exact}");
        }
    }

    #[test]
    fn index_and_normal_reflectance_invert() {
        for eta in [1.0, 1.33, 1.5, 2.4] {
            assert!((eta_of_f0(f0_of_eta(eta)) - eta).abs() < 1e-4);
        }
        assert!((fresnel_remap(1.0, 1.5)).abs() < 1e-6 && (fresnel_remap(0.0, 1.5) - 1.0).abs() < 1e-6);
    }
}
