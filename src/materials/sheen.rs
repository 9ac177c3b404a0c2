//! `KHR_materials_sheen` (Blender's Principled Sheen): a layer of fibres over everything else,
//! bright at grazing angles (velvet, cloth, dust).
//!
//! Its BRDF is Cycles' (Blender 4.0 on): Zeltner, Burley and Chiang's microfiber sheen
//! ("Practical Multiple-Scattering Sheen Using Linearly Transformed Cosines", 2022), a volume of
//! fibres whose multiply-scattered reflection is fitted, per viewing cosine and roughness, by a
//! linearly transformed cosine (LTC) times a directional albedo. The fits are the authors'
//! closed forms (published with the paper) of the tables Cycles reads: a velvet cushion's mean
//! radiance is within 1.5% of Cycles' (the parity scene `sheen`). The glTF specification's own
//! sheen ("Charlie", Estevez and Kulla 2017) reflects several times more head-on: the cushion
//! came out a fifth to three quarters brighter than Cycles'.
//!
//! It is layered as Cycles layers its sheen: the layers under it are scaled by `1 - c E(wo)`, `c`
//! the colour's largest value and `E` the directional albedo. A path picks the sheen or what lies
//! under it (as under a clear coat, `clearcoat.rs`), and photons are re-weighted to the camera
//! side's attenuation. The lobe is sampled exactly (a cosine sample, transformed), so a sample
//! weighs the colour times the albedo. Like Cycles' it is fitted per viewing direction and is
//! not reciprocal; photons scattering off a sheen use it as it is, with their arrival direction
//! for the view (the layer is a thin share of most materials' light).

use std::f32::consts::{FRAC_1_PI, PI};
use std::sync::Arc;

use glam::{Vec2, Vec3, Vec4};

use super::{face_toward, BsdfSample, ShadingFrame};
use crate::sampling::square_to_cosine_hemisphere;
use crate::spectrum::{RgbSpectrum, SampledSpectrum, Wavelengths};
use crate::texture::{DataTexture, Texture};

/// Sheen roughness is kept above this, the lower end of the range the fits were made over (the
/// sheen's albedo is nil there anyway).
const MIN_ROUGHNESS: f32 = 0.01;

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
    /// Its roughness.
    pub roughness: f32,
    /// The normals it follows.
    pub frame: ShadingFrame,
}

/// The directional albedo of a white sheen of roughness `r` seen at cosine `mu`: the authors'
/// Gaussian fit over the cosine, its width, centre and offset rational in the roughness.
pub fn albedo(mu: f32, r: f32) -> f32 {
    let (mu, r) = (mu.clamp(0.0, 1.0), r.clamp(MIN_ROUGHNESS, 1.0));
    let width = r * (0.0206607 + 1.58491 * r) / (0.0379424 + r * (1.32227 + r));
    let centre = r * (-0.193854 + r * (-1.14885 + r * (1.7932 - 0.95943 * r * r))) / (0.046391 + r);
    let offset = r * (0.000654023 + (-0.0207818 + 0.119681 * r) * r) / (1.26264 + r * (-1.92021 + r));
    let gaussian = (-0.5 * ((mu - centre) / width).powi(2)).exp() / (width * (2.0 * PI).sqrt());
    (gaussian + offset).clamp(0.0, 1.0)
}

/// The sheen's lobe seen from one direction: the distribution of `wi` (cosine included) whose
/// inverse transform `[[a, 0, b], [0, a, 0], [0, 0, 1]]` turns it into a clamped cosine, in a
/// frame whose first axis leans toward the viewer.
struct Ltc {
    /// The frame: toward the viewer along the surface, across, the normal.
    frame: [Vec3; 3],
    /// The inverse transform's diagonal.
    a: f32,
    /// Its skew, which tilts the lobe toward or away from the viewer.
    b: f32,
}

impl Ltc {
    /// The lobe at roughness `r` seen from `wo`, `n` facing it: the authors' rational fits.
    fn new(r: f32, n: Vec3, wo: Vec3) -> Ltc {
        let mu = n.dot(wo).clamp(0.0, 1.0);
        let toward = (wo - n * mu).try_normalize().unwrap_or_else(|| n.any_orthonormal_vector());
        let a = (2.58126 * mu + 0.813703 * r) * r / (1.0 + 0.310327 * mu * mu + 2.60994 * mu * r);
        let b = (1.0 - mu).sqrt() * (r - 1.0) * r.powi(3)
            / (0.0000254053 + 1.71228 * mu - 1.71506 * mu * r + 1.34174 * r * r);
        Ltc { frame: [toward, n.cross(toward), n], a, b }
    }

    /// The density of `wi` per solid angle: the clamped cosine at the inverse-transformed
    /// direction times the transform's Jacobian.
    fn density(&self, wi: Vec3) -> f32 {
        let [x, y, n] = self.frame;
        let z = wi.dot(n);
        if z <= 0.0 {
            return 0.0;
        }
        let original = Vec3::new(self.a * wi.dot(x) + self.b * z, self.a * wi.dot(y), z);
        z * FRAC_1_PI * (self.a / original.length_squared()).powi(2)
    }

    /// A direction drawn from the lobe: a cosine-distributed one, transformed.
    fn sample(&self, u: Vec2) -> Vec3 {
        let cosine = square_to_cosine_hemisphere(u);
        let [x, y, n] = self.frame;
        let local = Vec3::new((cosine.x - self.b * cosine.z) / self.a, cosine.y / self.a, cosine.z);
        (x * local.x + y * local.y + n * local.z).normalize()
    }
}

/// `f(wo, wi)` of a sheen of `colour` and roughness `r` at shading normal `n`: the colour times
/// the albedo times the lobe, over the cosine.
pub fn eval(colour: SampledSpectrum, r: f32, n: Vec3, wo: Vec3, wi: Vec3) -> SampledSpectrum {
    let n = face_toward(n, wo);
    let cos_i = n.dot(wi);
    if cos_i <= 0.0 {
        return Vec4::ZERO;
    }
    colour * (albedo(n.dot(wo), r) * Ltc::new(r, n, wo).density(wi) / cos_i)
}

/// The density with which [`sample`] picks `wi`: the lobe's own.
pub fn pdf(r: f32, n: Vec3, wo: Vec3, wi: Vec3) -> f32 {
    let n = face_toward(n, wo);
    Ltc::new(r, n, wo).density(wi)
}

/// A direction drawn from the lobe, weighted by the colour times the albedo.
pub fn sample(colour: SampledSpectrum, r: f32, n: Vec3, wo: Vec3, u: Vec2) -> Option<BsdfSample> {
    let n = face_toward(n, wo);
    let ltc = Ltc::new(r, n, wo);
    let wi = ltc.sample(u);
    let pdf = ltc.density(wi);
    let albedo = albedo(n.dot(wo), r);
    if pdf <= 0.0 || albedo <= 0.0 {
        return None;
    }
    Some(BsdfSample { wi, weight: colour * albedo, pdf, is_delta: false })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The sheen reflects less than everything from every direction, more toward grazing, and
    /// more the rougher it is.
    #[test]
    fn a_white_sheen_reflects_less_than_everything() {
        for r in [0.1, 0.3, 0.6, 1.0] {
            let (head_on, grazing) = (albedo(1.0, r), albedo(0.1, r));
            assert!(head_on >= 0.0 && head_on < grazing && grazing < 1.0, "r {r}: {head_on} {grazing}");
        }
        assert!(albedo(0.5, 0.3) < albedo(0.5, 0.6) && albedo(0.5, 0.6) < albedo(0.5, 1.0));
    }

    /// The lobe is a distribution: it integrates to 1 over the hemisphere, seen from anywhere.
    #[test]
    fn the_lobe_is_normalised() {
        for r in [0.05f32, 0.3, 0.7, 1.0] {
            for mu in [1.0f32, 0.6, 0.1] {
                let ltc = Ltc::new(r, Vec3::Z, Vec3::new((1.0 - mu * mu).sqrt(), 0.0, mu));
                let n = 400;
                let mut sum = 0.0f64;
                for i in 0..n {
                    for j in 0..n {
                        // dwi = dz dphi over z in (0, 1), by the midpoint rule.
                        let z = (i as f32 + 0.5) / n as f32;
                        let phi = 2.0 * PI * (j as f32 + 0.5) / n as f32;
                        let s = (1.0 - z * z).sqrt();
                        let wi = Vec3::new(s * phi.cos(), s * phi.sin(), z);
                        sum += f64::from(ltc.density(wi)) * 2.0 * std::f64::consts::PI / (n * n) as f64;
                    }
                }
                assert!((sum - 1.0).abs() < 0.01, "r {r}, mu {mu}: {sum}");
            }
        }
    }
}
