//! The glTF BRDF of a non-metal (glTF 2.0 appendix B with `KHR_materials_specular`): a GGX
//! dielectric specular layer, the coat, over a Lambertian base that takes what the coat does not
//! reflect.
//!
//! The coat reflects `D G2 F / (4 |wo.n| |wi.n|)` with Cycles' tinted dielectric Fresnel
//! `F = f0 + (1 - f0) s(wo.h)` ([`super::layer_albedo`]). The base is
//! `base / pi * (1 - E(wo)) (1 - E(wi)) / (1 - E_avg)`, with `E` the coat's directional albedo
//! and `E_avg` its cosine-weighted mean: it is reciprocal, and a white base under any coat
//! reflects exactly what enters it, so a white furnace stays at 1 (Kelemen & Szirmay-Kalos 2001;
//! Cycles scales its base by `1 - E(wo)` alone, which differs by `(1 - E(wi)) / (1 - E_avg)`,
//! within 3% at IOR 1.5 away from grazing). Multiple scattering between microfacets is left out:
//! with a dielectric's Fresnel it returns under 0.5% of the light at IOR 1.5 and roughness 1.
//!
//! A smooth coat is a delta mirror, and a narrow one a lobe that eye paths sample through rather
//! than gather photons in: [`choose_layer`] picks it or the base once per hit, each with the share
//! of light it reflects.

use std::f32::consts::FRAC_1_PI;

use glam::{Vec2, Vec3, Vec4};

use super::layer_albedo::{fresnel_remap, LayerAlbedo};
use super::{microfacet, Bsdf, BsdfSample, ShadingFrame, Transport};
use crate::sampling::square_to_cosine_hemisphere;
use crate::spectrum::SampledSpectrum;

/// A dielectric specular layer: GGX of `alpha` (0 for smooth) with Fresnel from `f0` and `eta`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Coat {
    /// Normal-incidence reflectance at each wavelength (tint times the index's reflectance).
    pub f0: SampledSpectrum,
    /// The index whose Fresnel curve the reflectance follows from `f0` to 1.
    pub eta: f32,
    /// GGX alpha; 0 for a smooth coat.
    pub alpha: f32,
}

impl Coat {
    /// A coat of normal-incidence reflectance `f0`, index `eta` and GGX `alpha`.
    pub fn new(f0: SampledSpectrum, eta: f32, alpha: f32) -> Self {
        Coat { f0, eta, alpha }
    }

    /// The Fresnel term at microfacet cosine `cos_h`.
    pub fn fresnel(&self, cos_h: f32) -> SampledSpectrum {
        self.f0 + (Vec4::ONE - self.f0) * fresnel_remap(cos_h, self.eta)
    }

    /// The coat's albedo tables at its roughness and index (looked up where they are read, so
    /// that a BSDF stays small: visible points keep one per pixel).
    fn tables(&self) -> LayerAlbedo {
        LayerAlbedo::new(self.alpha, self.eta)
    }

    /// The coat's directional albedo seen at cosine `mu`.
    pub fn albedo(&self, mu: f32) -> SampledSpectrum {
        self.mix(self.tables().at(mu))
    }

    /// The coat seen at cosine `mu_o`: its tables and albedo there, found once for all a BSDF
    /// call reads of them.
    fn seen_at(&self, mu_o: f32) -> SeenCoat {
        let tables = self.tables();
        SeenCoat { albedo: self.mix(tables.at(mu_o)), tables }
    }

    /// The share of light the coat seen as `seen` lets through to the base and back, from cosine
    /// `mu_i`: `(1 - E(wo)) (1 - E(wi)) / (1 - E_avg)`.
    fn through(&self, seen: &SeenCoat, mu_i: f32) -> SampledSpectrum {
        let entering = (Vec4::ONE - self.mix(seen.tables.means)).max(Vec4::splat(1e-4));
        (Vec4::ONE - seen.albedo) * (Vec4::ONE - self.mix(seen.tables.at(mu_i))) / entering
    }

    /// `f0 E1 + (1 - f0) Es` for the pair `e = (E1, Es)`.
    fn mix(&self, e: Vec2) -> SampledSpectrum {
        self.f0 * e.x + (Vec4::ONE - self.f0) * e.y
    }
}

/// A coat seen from one direction: its albedo tables, and its albedo toward that direction.
struct SeenCoat {
    tables: LayerAlbedo,
    albedo: SampledSpectrum,
}

/// A Lambertian base under a coat (the coat's own reflection left out when it is smooth).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plastic {
    /// The base's albedo at each wavelength.
    pub base: SampledSpectrum,
    /// The coat over it.
    pub coat: Coat,
}

/// A share of `part` in `part + rest` by their means over wavelengths.
fn share(part: SampledSpectrum, rest: SampledSpectrum) -> f32 {
    let (p, r) = (part.element_sum(), rest.element_sum());
    if p + r > 0.0 {
        p / (p + r)
    } else {
        0.0
    }
}

impl Plastic {
    /// A base of albedo `base` under a coat of reflectance `f0`, index `eta` and GGX `alpha`.
    pub fn new(base: SampledSpectrum, f0: SampledSpectrum, eta: f32, alpha: f32) -> Self {
        Plastic { base, coat: Coat::new(f0, eta, alpha) }
    }

    /// As a [`Bsdf`].
    pub fn bsdf(self) -> Bsdf {
        let Coat { f0, eta, alpha } = self.coat;
        Bsdf::Plastic { base: self.base, f0, eta, alpha }
    }

    /// Whether the coat's reflection is part of this BSDF (a rough coat).
    pub fn has_rough_coat(&self) -> bool {
        self.coat.alpha > 0.0
    }

    /// The base's reflection for local `wo` and `wi` above the surface (`wo` may lie below a
    /// bent normal, which reflects the base alone: see `normal_map.rs`).
    fn base_value(&self, seen: &SeenCoat, mu_i: f32) -> SampledSpectrum {
        self.base * FRAC_1_PI * self.coat.through(seen, mu_i)
    }

    /// The coat seen from local `wo` (below a bent normal, from its mirror image).
    fn seen_from(&self, wo: Vec3) -> SeenCoat {
        self.coat.seen_at(wo.z.abs())
    }

    /// The probability of sampling the coat, by its share of the light reflected toward `wo`
    /// (0 below the shading normal, where the coat reflects nothing).
    fn coat_probability(&self, seen: &SeenCoat, mu_o: f32) -> f32 {
        if !self.has_rough_coat() || mu_o <= 0.0 {
            return 0.0;
        }
        if self.base == Vec4::ZERO {
            return 1.0;
        }
        share(seen.albedo, self.base * (Vec4::ONE - seen.albedo)).clamp(0.1, 0.9)
    }

    /// `f(wo, wi)` in `frame`, light arriving from `wi` (the base's share shadowed by a normal
    /// map's bend: [`ShadingFrame::diffuse_shadowing`]). Where a normal map bent the normal so
    /// far that the coat takes another ([`ShadingFrame::for_glossy`]), the coat's reflection
    /// carries its own normal's cosine, over the shading normal's that the caller multiplies by.
    pub fn eval(&self, frame: ShadingFrame, wo: Vec3, wi: Vec3) -> SampledSpectrum {
        let (base, coat) = normals(frame, wo);
        let (wo_coat, wi_coat, _) = microfacet::to_frame(coat, wo, wi);
        let seen = self.seen_from(wo_coat);
        if base == coat {
            if wi_coat.z <= 0.0 {
                return Vec4::ZERO;
            }
            return self.base_value(&seen, wi_coat.z) * frame.diffuse_shadowing(wi)
                + self.coat_value(wo_coat, wi_coat);
        }
        // The caller's cosine can be tiny where the coat's is not: f is large there, f cos not.
        let cos_shading = base.dot(wi).abs();
        if cos_shading < 1e-20 {
            return Vec4::ZERO;
        }
        self.projected(&seen, (wo_coat, wi_coat), base.dot(wi), frame.diffuse_shadowing(wi)) / cos_shading
    }

    /// `f cos` toward `wi` summed over the layers, each by its own normal's cosine: the coat's
    /// from local directions in its frame, the base's (`cos_base` the cosine to its normal,
    /// `shadowing` its normal map's shadowing).
    fn projected(
        &self,
        seen: &SeenCoat,
        (wo, wi): (Vec3, Vec3),
        cos_base: f32,
        shadowing: f32,
    ) -> SampledSpectrum {
        let coat = if wi.z > 0.0 { self.coat_value(wo, wi) * wi.z } else { Vec4::ZERO };
        if cos_base <= 0.0 {
            return coat;
        }
        self.base_value(seen, wi.z) * (shadowing * cos_base) + coat
    }

    fn coat_value(&self, wo: Vec3, wi: Vec3) -> SampledSpectrum {
        if !self.has_rough_coat() {
            return Vec4::ZERO;
        }
        match microfacet::reflection(self.coat.alpha, wo, wi) {
            Some((value, cos_h)) => self.coat.fresnel(cos_h) * value,
            None => Vec4::ZERO,
        }
    }

    /// The density with which [`Plastic::sample`] picks `wi`.
    pub fn pdf(&self, frame: ShadingFrame, wo: Vec3, wi: Vec3) -> f32 {
        let (base, coat) = normals(frame, wo);
        let (wo_coat, wi_coat, _) = microfacet::to_frame(coat, wo, wi);
        self.mixture_pdf(&self.seen_from(wo_coat), (wo_coat, wi_coat), base.dot(wi))
    }

    /// The mixture's density at `wi`: the coat's, from local directions in the coat's frame, by
    /// its probability, and the base's cosine lobe about the base's normal (`cos_base` the
    /// cosine to it).
    fn mixture_pdf(&self, seen: &SeenCoat, (wo, wi): (Vec3, Vec3), cos_base: f32) -> f32 {
        let p = self.coat_probability(seen, wo.z);
        let coat =
            if p > 0.0 && wi.z > 0.0 { p * microfacet::reflection_pdf(self.coat.alpha, wo, wi) } else { 0.0 };
        coat + (1.0 - p) * cos_base.max(0.0) * FRAC_1_PI
    }

    /// Samples the coat with its probability, else the base's cosine lobe; the weight is the
    /// whole BSDF over the mixture's density (for `mode`'s side of the light: the base's
    /// shadowing follows the direction light arrives from).
    pub fn sample(
        &self,
        frame: ShadingFrame,
        wo: Vec3,
        u: Vec2,
        u_lobe: f32,
        mode: Transport,
    ) -> Option<BsdfSample> {
        let (base, coat) = normals(frame, wo);
        let (wo_coat, _, [t, b, n]) = microfacet::to_frame(coat, wo, wo);
        let seen = self.seen_from(wo_coat);
        let wi = if u_lobe < self.coat_probability(&seen, wo_coat.z) {
            let wi_local = microfacet::sample_reflection(self.coat.alpha, wo_coat, u)?.wi;
            (t * wi_local.x + b * wi_local.y + n * wi_local.z).normalize()
        } else {
            let (_, _, [t, b, n]) = microfacet::to_frame(base, wo, wo);
            let wi_local = square_to_cosine_hemisphere(u);
            (t * wi_local.x + b * wi_local.y + n * wi_local.z).normalize()
        };
        // Density and value from the world direction, as `eval` and `pdf` compute them: a narrow
        // lobe's peak would otherwise differ by rounding between the two.
        let (wo_coat, wi_coat, _) = microfacet::to_frame(coat, wo, wi);
        let seen = self.seen_from(wo_coat);
        let cos_base = base.dot(wi);
        let pdf = self.mixture_pdf(&seen, (wo_coat, wi_coat), cos_base);
        if pdf <= 0.0 {
            return None;
        }
        let light_side = if mode == Transport::Radiance { wi } else { wo };
        let projected =
            self.projected(&seen, (wo_coat, wi_coat), cos_base, frame.diffuse_shadowing(light_side));
        Some(BsdfSample { wi, weight: projected / pdf, pdf, is_delta: false })
    }
}

/// The normals a plastic's layers take seen from `wo`, each on `wo`'s side: the base's (the
/// shading normal) and the coat's (the same, or where a normal map bent it so far that `wo`'s
/// mirror image would go below the surface, tilted back: [`ShadingFrame::for_glossy`]).
fn normals(frame: ShadingFrame, wo: Vec3) -> (Vec3, Vec3) {
    (frame.toward(wo), frame.for_glossy(wo).toward(wo))
}

/// Under a smooth or narrow coat (GGX alpha below [`super::NARROW_COAT_ALPHA`]), the coat's own
/// reflection or the base, picked by `u` with their shares of the light reflected toward `wo` (at
/// shading normal `n`), each weighted by one over its probability: the BSDF and the factor on the
/// path's throughput. The base alone is attenuated as under a smooth coat (the directional albedo
/// of so narrow a GGX lobe differs from Fresnel's by under 0.5%).
pub fn choose_layer(plastic: Plastic, n: Vec3, wo: Vec3, u: f32) -> (Bsdf, f32) {
    let mu_o = n.dot(wo).abs().min(1.0);
    let smooth = plastic.coat.alpha == 0.0;
    let coat = if smooth { plastic.coat.fresnel(mu_o) } else { plastic.coat.albedo(mu_o) };
    let p = share(coat, plastic.base * (Vec4::ONE - plastic.coat.albedo(mu_o)));
    if u < p {
        if smooth {
            return (Bsdf::Mirror { weight: coat / p }, 1.0);
        }
        return (Plastic { base: Vec4::ZERO, ..plastic }.bsdf(), 1.0 / p);
    }
    let coat = Coat { alpha: 0.0, ..plastic.coat };
    (Plastic { base: plastic.base / (1.0 - p), coat }.bsdf(), 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{square_to_sphere, stream, Stream};
    use glam::DVec4;

    /// Under a normal bent 65 degrees (a normal map at a high strength), seen from where the
    /// coat takes a normal of its own: every sample's weight is `f |n.wi| / pdf` as `eval` and
    /// `pdf` say, and the mean weight matches `f |n.wi|` integrated over uniform directions
    /// within 2%, so that both layers' light counts once whichever way a path finds it.
    #[test]
    fn a_plastic_under_a_steeply_bent_normal_samples_what_it_evaluates() {
        let smooth = Vec3::Z;
        let bent = Vec3::new(0.9, 0.0, 0.42).normalize();
        let frame = ShadingFrame::bent(bent, Vec3::Z, smooth);
        let plastic = Plastic::new(Vec4::splat(0.6), Vec4::splat(0.04), 1.5, 0.3);
        for wo in [Vec3::new(-0.8, 0.0, 0.6), Vec3::new(-0.3, 0.5, 0.81), Vec3::new(0.5, 0.1, 0.86)] {
            let wo = wo.normalize();
            let mut rng = stream(5, Stream::Eye, 0, 0);
            let n = 200_000;
            let mut sampled = DVec4::ZERO;
            for _ in 0..n {
                let Some(s) = plastic.sample(frame, wo, rng.next_2d(), rng.next_1d(), Transport::Radiance)
                else {
                    continue;
                };
                let (f, pdf) = (plastic.eval(frame, wo, s.wi), plastic.pdf(frame, wo, s.wi));
                assert!((s.pdf / pdf - 1.0).abs() < 1e-3, "{wo}: pdf {} vs {pdf}", s.pdf);
                let expected = f * bent.dot(s.wi).abs() / pdf;
                assert!(
                    (s.weight - expected).abs().max_element() < 1e-3 * expected.max_element().max(1.0),
                    "{wo}: wi {} weight {} expected {expected} f {f} pdf {pdf}",
                    s.wi,
                    s.weight
                );
                sampled += s.weight.as_dvec4();
            }
            let uniform: DVec4 = (0..n)
                .map(|_| {
                    let wi = square_to_sphere(rng.next_2d());
                    (plastic.eval(frame, wo, wi) * bent.dot(wi).abs() * 4.0 * std::f32::consts::PI).as_dvec4()
                })
                .sum();
            let (sampled, uniform) = (sampled / n as f64, uniform / n as f64);
            assert!(
                (sampled / uniform - DVec4::ONE).abs().max_element() < 0.02,
                "{wo}: {sampled} vs {uniform}"
            );
        }
    }
}
