//! A smooth dielectric boundary: exact Fresnel reflectance, Snell refraction and total internal
//! reflection. Reflection or refraction is chosen with probability F, so the weight is 1, except
//! that radiance (camera paths) is scaled by 1 / eta^2 on refraction while importance (photons)
//! is not: the BTDF is not symmetric (Veach 1997, 5.2; pbrt-v4 section 9.5.2). Refraction is
//! multiplied by the material's transmission tint.

use glam::{Vec3, Vec4};

use super::volume::transmittance;
use super::{face_toward, microfacet::reflect, BsdfSample, ShadingFrame, Transport};
use crate::spectrum::SampledSpectrum;

/// Unpolarised Fresnel reflectance for `cos_i` (cosine on the incident side) and relative index
/// `eta` (transmitted over incident).
pub fn fresnel_dielectric(cos_i: f32, eta: f32) -> f32 {
    let cos_i = cos_i.clamp(0.0, 1.0);
    let sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let r_parallel = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_perpendicular = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    (r_parallel * r_parallel + r_perpendicular * r_perpendicular) / 2.0
}

/// The shading normal turned to the side `wo` is on (the geometric normal, pointing outside,
/// decides which side that is), and the index of the far side over the near one.
pub fn side(ior: f32, frame: ShadingFrame, wo: Vec3) -> (Vec3, f32) {
    let outward = face_toward(frame.n(), frame.ng());
    if frame.ng().dot(wo) > 0.0 {
        (outward, ior)
    } else {
        (-outward, 1.0 / ior)
    }
}

/// `wo` refracted through a surface of unit normal `n` on its side into relative index `eta`, or
/// `None` where it is totally reflected.
pub fn refract(wo: Vec3, n: Vec3, eta: f32) -> Option<Vec3> {
    let cos_i = wo.dot(n);
    let sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    (sin2_t < 1.0).then(|| (-wo / eta + (cos_i / eta - (1.0 - sin2_t).sqrt()) * n).normalize())
}

/// Reflects or refracts `wo` at a boundary with normals `frame`: the geometric normal (pointing
/// outside) decides which side `wo` is on, the shading normal bends the ray, so a tessellated
/// sphere focuses light like a smooth one.
pub fn sample(
    ior: f32,
    tint: SampledSpectrum,
    frame: ShadingFrame,
    wo: Vec3,
    u: f32,
    mode: Transport,
) -> Option<BsdfSample> {
    let (n, eta) = side(ior, frame, wo);
    let f = fresnel_dielectric(n.dot(wo).min(1.0), eta);
    if u < f {
        return Some(BsdfSample { wi: reflect(wo, n), weight: Vec4::ONE, pdf: 0.0, is_delta: true });
    }
    let wi = refract(wo, n, eta)?;
    let weight = match mode {
        Transport::Radiance => 1.0 / (eta * eta),
        Transport::Importance => 1.0,
    };
    Some(BsdfSample { wi, weight: tint * weight, pdf: 0.0, is_delta: true })
}

/// Reflects or transmits `wo` at a thin dielectric wall of index `ior` whose inside absorbs
/// `depth` (absorption coefficient times thickness; zero for a clear wall) along its normal: of
/// the light, `R + T^2 R a^2 / (1 - R^2 a^2)` is reflected by the two faces, inner reflections
/// included, and `T^2 a / (1 - R^2 a^2)` passes straight through, unbent (the wall's two
/// refractions cancel), times `tint`, where `a` is what one crossing of the wall at the refracted
/// angle keeps (pbrt-v4's ThinDielectricBxDF, with absorption). Reflection is chosen with its
/// share of what is not absorbed, so a clear wall's weights are 1.
pub fn sample_thin(
    ior: f32,
    tint: SampledSpectrum,
    depth: SampledSpectrum,
    frame: ShadingFrame,
    wo: Vec3,
    u: f32,
) -> Option<BsdfSample> {
    let n = face_toward(frame.n(), wo);
    let wall = ThinWall::at(ior, depth, n.dot(wo).min(1.0));
    let (wi, weight) = if u < wall.p_reflect {
        (reflect(wo, n), wall.reflected / wall.p_reflect)
    } else {
        (-wo, wall.through * tint / (1.0 - wall.p_reflect))
    };
    Some(BsdfSample { wi, weight, pdf: 0.0, is_delta: true })
}

/// What a thin wall of index `ior` whose inside absorbs `depth` across it does with light
/// arriving at cosine `cos_i` to its (micro)surface: what its two faces reflect, inner
/// reflections included, what passes, and the probability with which reflection is chosen.
pub struct ThinWall {
    /// `R + T^2 R a^2 / (1 - R^2 a^2)` at each wavelength.
    pub reflected: SampledSpectrum,
    /// `T^2 a / (1 - R^2 a^2)` at each wavelength.
    pub through: SampledSpectrum,
    /// Reflection's share of what is not absorbed (mean over the wavelengths).
    pub p_reflect: f32,
}

impl ThinWall {
    /// The wall at cosine `cos_i`.
    pub fn at(ior: f32, depth: SampledSpectrum, cos_i: f32) -> Self {
        let r = fresnel_dielectric(cos_i, ior);
        if r >= 1.0 {
            return ThinWall { reflected: Vec4::ONE, through: Vec4::ZERO, p_reflect: 1.0 };
        }
        let cos_t = (1.0 - (1.0 - cos_i * cos_i) / (ior * ior)).max(0.0).sqrt();
        let a = transmittance(depth, 1.0 / cos_t);
        let inner = Vec4::ONE / (Vec4::ONE - r * r * a * a);
        let reflected = r + (1.0 - r) * (1.0 - r) * r * a * a * inner;
        let through = (1.0 - r) * (1.0 - r) * a * inner;
        let p_reflect = reflected.element_sum() / (reflected + through).element_sum();
        ThinWall { reflected, through, p_reflect }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fresnel_at_normal_incidence_and_total_internal_reflection() {
        assert!((fresnel_dielectric(1.0, 1.5) - 0.04).abs() < 1e-6);
        assert_eq!(fresnel_dielectric(0.1, 1.0 / 1.5), 1.0);
        assert!(fresnel_dielectric(1.0, 1.0) < 1e-12);
    }

    #[test]
    fn a_thin_wall_transmits_unbent_and_reflects_both_faces() {
        let wo = Vec3::new(0.6, 0.0, 0.8);
        let frame = ShadingFrame::new(Vec3::Z, Vec3::Z);
        let through = sample_thin(1.5, Vec4::ONE, Vec4::ZERO, frame, wo, 0.999).unwrap();
        assert!((through.wi + wo).length() < 1e-6, "{:?}", through.wi);
        let back = sample_thin(1.5, Vec4::ONE, Vec4::ZERO, frame, wo, 0.0).unwrap();
        assert!((back.wi - Vec3::new(-0.6, 0.0, 0.8)).length() < 1e-6);
        // At normal incidence a 1.5 wall reflects 2R / (1 + R) with R = 0.04.
        let reflected = (0..10_000)
            .filter(|&i| {
                sample_thin(1.5, Vec4::ONE, Vec4::ZERO, frame, Vec3::Z, (i as f32 + 0.5) / 1e4).unwrap().wi.z
                    > 0.0
            })
            .count();
        assert!((reflected as f32 / 1e4 - 0.08 / 1.04).abs() < 2e-4, "{reflected}");
    }

    #[test]
    fn refraction_obeys_snell() {
        let wo = Vec3::new(0.6, 0.0, 0.8);
        let frame = ShadingFrame::new(Vec3::Z, Vec3::Z);
        let s = sample(1.5, Vec4::ONE, frame, wo, 0.99, Transport::Importance).unwrap();
        let sin_t = (1.0 - s.wi.z * s.wi.z).sqrt();
        assert!((sin_t * 1.5 - 0.6).abs() < 1e-5);
        assert!(s.wi.z < 0.0 && s.wi.x < 0.0);
    }
}
