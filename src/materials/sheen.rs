//! `KHR_materials_sheen` (Blender's Principled Sheen): a layer of fibres over everything else,
//! bright at grazing angles (velvet, cloth, dust).
//!
//! Its BRDF is the glTF specification's: `colour D V`, with Estevez and Kulla's "Charlie"
//! distribution `D = (2 + 1/a) sin(theta_h)^(1/a) / (2 pi)` (`a` the sheen roughness squared) and
//! their visibility term `V = 1 / ((1 + L(wo) + L(wi)) 4 |wo.n| |wi.n|)`, `L` their fitted
//! exponential curve. It is layered as Cycles layers its sheen: the layers under it are scaled by
//! `1 - c E(wo)`, `c` the colour's largest value and `E` the layer's directional albedo, tabulated
//! once (on first use) against the viewing cosine and the roughness. A path picks the sheen or
//! what lies under it (as under a clear coat, `clearcoat.rs`), and photons are re-weighted to the
//! camera side's attenuation.
//!
//! Cycles 5.0 itself renders sheen with a different fibre model (Zeltner, Burley and Chiang's
//! microfiber sheen, 2022); the two agree in shape, not in every value.

use std::f32::consts::{FRAC_1_PI, PI};
use std::sync::{Arc, LazyLock};

use glam::{Vec2, Vec3, Vec4};

use super::{face_toward, microfacet, BsdfSample, ShadingFrame};
use crate::sampling::square_to_cosine_hemisphere;
use crate::spectrum::{RgbSpectrum, SampledSpectrum, Wavelengths};
use crate::texture::{DataTexture, Texture};

/// Sheen roughness is kept above this (the glTF sample viewer's floor: `D` narrows to a spike
/// along the horizon as the roughness goes to 0).
const MIN_ROUGHNESS: f32 = 0.07;

/// A sheen as the file gives it.
#[derive(Clone, Debug)]
pub struct Sheen {
    /// `sheenColorFactor` as a reflectance spectrum.
    pub colour: RgbSpectrum,
    /// `sheenColorTexture` (sRGB) with the factor baked in, replacing `colour` where it is read.
    pub colour_texture: Option<Arc<Texture>>,
    /// `sheenRoughnessFactor` in [0, 1].
    pub roughness: f32,
    /// `sheenRoughnessTexture`: its alpha channel scales the roughness.
    pub roughness_texture: Option<Arc<DataTexture>>,
}

impl Sheen {
    /// The sheen at a surface point of texture coordinates `uv` and normals `frame`, at the
    /// wavelengths `lambda`, or `None` where its colour is black.
    pub fn at(
        &self,
        uv: &[Vec2; crate::texture::UV_SETS],
        frame: ShadingFrame,
        lambda: &Wavelengths,
    ) -> Option<SheenAt> {
        let colour = match &self.colour_texture {
            Some(texture) => texture.eval(uv, lambda.nm),
            None => self.colour.eval_lanes(lambda.nm),
        };
        let colour = colour.clamp(Vec4::ZERO, Vec4::ONE);
        if colour.max_element() <= 0.0 {
            return None;
        }
        let scale = self.roughness_texture.as_ref().map_or(1.0, |t| t.eval(uv).w);
        let roughness = (self.roughness * scale).clamp(MIN_ROUGHNESS, 1.0);
        Some(SheenAt { colour, roughness, frame })
    }
}

/// The sheen resolved at a surface point.
#[derive(Clone, Copy, Debug)]
pub struct SheenAt {
    /// Its colour at the path's wavelengths, in [0, 1].
    pub colour: SampledSpectrum,
    /// Its roughness (Charlie's `a` is its square).
    pub roughness: f32,
    /// The normals it follows.
    pub frame: ShadingFrame,
}

impl SheenAt {
    /// The share of light the sheen reflects seen from `w`, as it attenuates the layers under it:
    /// its colour's largest value times its directional albedo.
    pub fn reflected(&self, w: Vec3) -> f32 {
        let mu = self.frame.n.dot(w).abs().min(1.0);
        self.colour.max_element() * albedo(mu, self.roughness)
    }
}

/// Charlie's fitted curve `L(x)` at roughness `r` (Estevez and Kulla 2017, table 1, interpolated
/// by `(1 - r)^2`).
fn charlie_l(x: f32, r: f32) -> f32 {
    let t = (1.0 - r) * (1.0 - r);
    let mix = |at_0: f32, at_1: f32| at_1 + (at_0 - at_1) * t;
    let (a, b, c) = (mix(25.3245, 21.5473), mix(3.32435, 3.82987), mix(0.16801, 0.19823));
    let (d, e) = (mix(-1.27393, -1.97760), mix(-4.85967, -4.32054));
    a / (1.0 + b * x.powf(c)) + d * x + e
}

/// Charlie's `Lambda` at cosine `mu`.
fn charlie_lambda(mu: f32, r: f32) -> f32 {
    if mu < 0.5 {
        charlie_l(mu, r).exp()
    } else {
        (2.0 * charlie_l(0.5, r) - charlie_l(1.0 - mu, r)).exp()
    }
}

/// `D V` for local directions above the surface (`z` up), at roughness `r`.
fn local_value(wo: Vec3, wi: Vec3, r: f32) -> f32 {
    if wo.z <= 0.0 || wi.z <= 0.0 {
        return 0.0;
    }
    let h = (wo + wi).normalize_or_zero();
    if h == Vec3::ZERO {
        return 0.0;
    }
    let a = (r * r).max(1e-4);
    let sin_h = (1.0 - h.z * h.z).max(0.0).sqrt();
    let d = (2.0 + 1.0 / a) * sin_h.powf(1.0 / a) / (2.0 * PI);
    let v = 1.0 / ((1.0 + charlie_lambda(wo.z, r) + charlie_lambda(wi.z, r)) * 4.0 * wo.z * wi.z);
    d * v
}

/// `f(wo, wi)` of a sheen of `colour` and roughness `r` at shading normal `n`.
pub fn eval(colour: SampledSpectrum, r: f32, n: Vec3, wo: Vec3, wi: Vec3) -> SampledSpectrum {
    let (wo, wi, _) = microfacet::to_local(n, wo, wi);
    colour * local_value(wo, wi, r)
}

/// The cosine-weighted density of `wi` (the sheen is sampled as a diffuse surface is).
pub fn pdf(n: Vec3, wo: Vec3, wi: Vec3) -> f32 {
    let n = face_toward(n, wo);
    match n.dot(wi) {
        c if c > 0.0 => c * FRAC_1_PI,
        _ => 0.0,
    }
}

/// A cosine-weighted direction on the side of `wo`, weighted by the sheen over its density.
pub fn sample(colour: SampledSpectrum, r: f32, n: Vec3, wo: Vec3, u: Vec2) -> Option<BsdfSample> {
    let n = face_toward(n, wo);
    let (t, b) = n.any_orthonormal_pair();
    let local = square_to_cosine_hemisphere(u);
    let wi = (t * local.x + b * local.y + n * local.z).normalize();
    let pdf = pdf(n, wo, wi);
    if pdf <= 0.0 {
        return None;
    }
    let f = eval(colour, r, n, wo, wi);
    if f == Vec4::ZERO {
        return None;
    }
    Some(BsdfSample { wi, weight: f * n.dot(wi) / pdf, pdf, is_delta: false })
}

/// Table nodes over the viewing cosine and over the roughness, both in [0, 1].
const NODES: usize = 32;
/// Strata per side of each entry's sample grid.
const STRATA: usize = 32;

/// The directional albedo `E(mu, r)` of a white sheen, `NODES x NODES` over roughness then cosine.
static ALBEDO: LazyLock<Vec<f32>> = LazyLock::new(|| {
    let node = |i: usize| i as f32 / (NODES - 1) as f32;
    (0..NODES * NODES)
        .map(|k| integrate(node(k % NODES).powi(2).max(1e-3), node(k / NODES).max(MIN_ROUGHNESS)))
        .collect()
});

/// `int D V cos(wi) dwi` by the midpoint rule over `wi.z = t^2` and the azimuth: dense near
/// the horizon, where the fibres reflect the most (cosine-weighted strata leave out too much of
/// it: 7% of the albedo at roughness 0.3).
fn integrate(mu: f32, r: f32) -> f32 {
    let wo = Vec3::new((1.0 - mu * mu).sqrt(), 0.0, mu);
    let sum: f32 = (0..STRATA * STRATA)
        .map(|s| {
            let t = ((s % STRATA) as f32 + 0.5) / STRATA as f32;
            let phi = 2.0 * PI * ((s / STRATA) as f32 + 0.5) / STRATA as f32;
            let z = t * t;
            let sin = (1.0 - z * z).max(0.0).sqrt();
            let wi = Vec3::new(sin * phi.cos(), sin * phi.sin(), z);
            // dwi = dz dphi = 2 t dt dphi.
            local_value(wo, wi, r) * z * 2.0 * t * 2.0 * PI
        })
        .sum();
    sum / (STRATA * STRATA) as f32
}

/// The directional albedo of a white sheen of roughness `r` seen at cosine `mu`, bilinear in the
/// table.
pub fn albedo(mu: f32, r: f32) -> f32 {
    let table = &*ALBEDO;
    let at = |x: f32| {
        let x = x.clamp(0.0, 1.0) * (NODES - 1) as f32;
        let i = (x as usize).min(NODES - 2);
        (i, x - i as f32)
    };
    let ((i, fi), (j, fj)) = (at(mu.max(0.0).sqrt()), at(r));
    let e = |j: usize, i: usize| table[j * NODES + i];
    let row = |j: usize| e(j, i) * (1.0 - fi) + e(j, i + 1) * fi;
    row(j) * (1.0 - fj) + row(j + 1) * fj
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The sheen reflects less than everything from every direction, more toward grazing.
    #[test]
    fn a_white_sheen_reflects_less_than_everything() {
        for r in [0.1, 0.3, 0.6, 1.0] {
            let (head_on, grazing) = (albedo(1.0, r), albedo(0.1, r));
            assert!(head_on > 0.0 && head_on < 1.0 && grazing < 1.0, "r {r}: {head_on} {grazing}");
        }
        assert!(albedo(0.1, 0.5) > albedo(1.0, 0.5));
    }

    /// Charlie's `D` integrates to 1 over the hemisphere of normals weighted by their cosine.
    #[test]
    fn the_charlie_distribution_is_normalised() {
        for r in [0.2f32, 0.5, 1.0] {
            let a = r * r;
            let n = 20_000;
            let sum: f32 = (0..n)
                .map(|k| {
                    let cos = (k as f32 + 0.5) / n as f32;
                    let sin = (1.0 - cos * cos).sqrt();
                    (2.0 + 1.0 / a) * sin.powf(1.0 / a) / (2.0 * PI) * cos * 2.0 * PI / n as f32
                })
                .sum();
            assert!((sum - 1.0).abs() < 0.01, "r {r}: {sum}");
        }
    }
}
