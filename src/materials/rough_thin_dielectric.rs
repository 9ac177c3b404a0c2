//! A rough thin dielectric wall (a frosted pane modelled as a plane): GGX microfacets on a wall
//! whose two faces are parallel, so what passes comes out unbent by the wall but spread by its
//! microfacets. A visible microfacet normal is sampled, then the wall's reflection at that
//! microfacet (both faces, inner reflections and absorption included: `dielectric::ThinWall`) is
//! chosen with its share, else transmission, whose direction is the reflected one mirrored
//! through the wall's plane. Both are `D G2 / (4 |cos_o cos_i|)` times what the wall reflects or
//! passes at the microfacet, so the BSDF is symmetric (the wall's two refractions cancel: no
//! `1 / eta^2`). Transmission is multiplied by the material's tint.
//!
//! Single scattering loses what bounces between microfacets: as much as GGX reflection with a
//! Fresnel term of 1 loses (12% head on at alpha 0.3), since transmission only mirrors reflected
//! directions. The wall is divided by that albedo seen from `wo` (`layer_albedo.rs`), as rough
//! glass is by its own (`rough_dielectric.rs`), so a clear wall passes or reflects all it
//! receives; the single-scattering term itself is symmetric (`single_scattering`).
//!
//! This is the thin-walled reading of roughness that renderers without solid geometry for a pane
//! use; a closed mesh of rough glass refracts through each rough boundary instead
//! (`rough_dielectric.rs`).

use glam::{Vec2, Vec3};

use super::dielectric::ThinWall;
use super::layer_albedo::white_ggx_albedo;
use super::microfacet::{self, masking, masking_shadowing, reflect};
use super::{BsdfSample, ShadingFrame};
use crate::spectrum::SampledSpectrum;

/// A rough thin wall at a path's wavelengths.
#[derive(Clone, Copy, Debug)]
pub struct RoughThinDielectric {
    /// Index of refraction of the wall (the hero wavelength's).
    pub ior: f32,
    /// GGX alpha (roughness squared).
    pub alpha: f32,
    /// What passing through transmits at each wavelength.
    pub tint: SampledSpectrum,
    /// What the wall's inside absorbs across it (absorption coefficient times thickness).
    pub depth: SampledSpectrum,
}

/// `w` mirrored through the wall's plane (local frame: the wall's normal is z).
fn mirrored(w: Vec3) -> Vec3 {
    Vec3::new(w.x, w.y, -w.z)
}

/// Albedos below this are not divided by, so that no weight grows without bound.
const SMALLEST_ALBEDO: f32 = 0.1;

impl RoughThinDielectric {
    /// The BSDF value for light arriving from `wi`, leaving toward `wo`: the single-scattering
    /// value over the microfacets' albedo seen from `wo`.
    pub fn eval(&self, frame: ShadingFrame, wo: Vec3, wi: Vec3) -> SampledSpectrum {
        self.single_scattering(frame, wo, wi) * self.compensation(frame, wo)
    }

    /// `1 / E(wo)`: what gives back the light single scattering loses between microfacets.
    fn compensation(&self, frame: ShadingFrame, wo: Vec3) -> f32 {
        1.0 / white_ggx_albedo(self.alpha, frame.n().dot(wo).abs()).0.max(SMALLEST_ALBEDO)
    }

    /// The single-scattering BSDF for light arriving from `wi`, leaving toward `wo`.
    pub fn single_scattering(&self, frame: ShadingFrame, wo: Vec3, wi: Vec3) -> SampledSpectrum {
        let (wo, wi, _) = microfacet::to_local(frame.n(), wo, wi);
        let through = wi.z < 0.0;
        let side = if through { mirrored(wi) } else { wi };
        let Some((value, cos_h)) = microfacet::reflection(self.alpha, wo, side) else {
            return SampledSpectrum::ZERO;
        };
        let wall = ThinWall::at(self.ior, self.depth, cos_h);
        match through {
            true => wall.through * self.tint * value,
            false => wall.reflected * value,
        }
    }

    /// The density with which [`RoughThinDielectric::sample`] picks `wi`.
    pub fn pdf(&self, frame: ShadingFrame, wo: Vec3, wi: Vec3) -> f32 {
        let (wo, wi, _) = microfacet::to_local(frame.n(), wo, wi);
        let through = wi.z < 0.0;
        let side = if through { mirrored(wi) } else { wi };
        let pdf = microfacet::reflection_pdf(self.alpha, wo, side);
        if pdf <= 0.0 {
            return 0.0;
        }
        let wall = ThinWall::at(self.ior, self.depth, wo.dot((wo + side).normalize()));
        pdf * if through { 1.0 - wall.p_reflect } else { wall.p_reflect }
    }

    /// Samples a visible microfacet normal with `u`, then the wall's reflection there with its
    /// share (`u_lobe`), else transmission.
    pub fn sample(&self, frame: ShadingFrame, wo: Vec3, u: Vec2, u_lobe: f32) -> Option<BsdfSample> {
        let (wo_local, _, [t, b, n]) = microfacet::to_local(frame.n(), wo, wo);
        if wo_local.z <= 0.0 {
            return None;
        }
        let h = microfacet::sample_visible_normal(self.alpha, wo_local, u);
        let side = reflect(wo_local, h);
        if side.z <= 0.0 {
            return None;
        }
        let wall = ThinWall::at(self.ior, self.depth, wo_local.dot(h));
        let g = masking_shadowing(self.alpha, wo_local, side) / masking(self.alpha, wo_local);
        let (wi, weight, p_lobe) = if u_lobe < wall.p_reflect {
            (side, wall.reflected / wall.p_reflect, wall.p_reflect)
        } else {
            (mirrored(side), wall.through * self.tint / (1.0 - wall.p_reflect), 1.0 - wall.p_reflect)
        };
        let world = (t * wi.x + b * wi.y + n * wi.z).normalize();
        let weight = weight * (g * self.compensation(frame, wo));
        let pdf = microfacet::reflection_pdf(self.alpha, wo_local, side) * p_lobe;
        Some(BsdfSample { wi: world, weight, pdf, is_delta: false })
    }
}
