//! The gather in media: at a visible point where an eye path's free flight ended in a medium
//! that scatters, the photons stored in media within the pass's volume radius, weighted by a
//! smooth kernel and the medium's phase function (times its scattering coefficient).
//!
//! The kernel is the normalised 3-D biweight `K(t) = 105 / (32 pi r^3) (1 - t^2)^2`, `t = d / r`;
//! its Laplacian with respect to the gather position is `K(t)`'s factor times
//! `-4 / r^2 (3 - 5 t^2)`. The film turns a pass's Laplacian estimate into the error bound's bias
//! term with the disc's radius and the 2-D biweight's second moment (`r^2 / 8` per axis); the 3-D
//! kernel's is `r^2 / 9`, so the estimate here is scaled by `(8 / 9) (r_volume / r)^2` to give the
//! sphere's bias through the same term.
//!
//! A photon in a medium is stored with the flux that reached its event over the density of the
//! event's distance (`free_flight.rs`), so the photons' kernel-weighted sum estimates the radiance
//! arriving at the point from each direction; the phase function times the scattering coefficient
//! turns it into the radiance scattered toward the eye. Near a medium's boundary the sphere
//! reaches outside, where no medium photons are: the estimate there is low by the kernel mass
//! outside (not corrected, unlike the disc's edges on surfaces).

use glam::Vec3;
use rayon::prelude::*;
use std::f32::consts::PI;

use super::gather::{gather, PhotonSet};
use super::grid::PhotonGrid;
use super::photons::Photon;
use super::renderer::{PassSamples, PixelEstimate, VisiblePoint};
use super::visible::EyeResult;
use crate::materials::Bsdf;
use crate::spectrum::{SampledSpectrum, LANES};

/// A pass's photons stored in media, bucketed for gathers of one radius.
pub struct MediumPhotons {
    sorted: Vec<Photon>,
    grid: PhotonGrid,
    radius: f32,
    /// The kernel's normalisation, `105 / (32 pi r^3)`.
    kernel_scale: f32,
    /// The factor that turns the Laplacian sum into the film's bias term (see the module notes).
    laplacian_scale: f32,
}

impl MediumPhotons {
    /// Buckets `photons` for gathers of radius `radius` in a pass whose surface radius is
    /// `surface_radius`.
    pub fn new(photons: Vec<Photon>, radius: f32, surface_radius: f32) -> Self {
        let positions: Vec<Vec3> = photons.iter().map(|p| p.p).collect();
        let (grid, order) = PhotonGrid::build(&positions, radius);
        let sorted = order.iter().map(|&i| photons[i as usize]).collect();
        let r2 = radius * radius;
        let kernel_scale = 105.0 / (32.0 * PI * r2 * radius);
        let bias_term = 8.0 / 9.0 * (radius / surface_radius).powi(2);
        let laplacian_scale = kernel_scale * -4.0 / r2 * bias_term;
        MediumPhotons { sorted, grid, radius, kernel_scale, laplacian_scale }
    }

    /// The pixel's estimate at `vp`, a point in a medium.
    fn estimate(&self, eye: &EyeResult, vp: &VisiblePoint) -> PixelEstimate {
        let r2 = self.radius * self.radius;
        let hero_only_scale = if vp.hero_only() { 1.0 / LANES as f32 } else { 1.0 };
        let (mut kernel, mut laplacian) = (SampledSpectrum::ZERO, SampledSpectrum::ZERO);
        self.grid.for_each_near(vp.p, |range| {
            for photon in &self.sorted[range] {
                let d2 = photon.p.distance_squared(vp.p);
                if d2 >= r2 {
                    continue;
                }
                let flux = if photon.hero_only { photon.flux * hero_only_scale } else { photon.flux };
                let weighted = flux * vp.bsdf.eval(vp.frame, vp.wo, photon.wi);
                let t2 = d2 / r2;
                kernel += weighted * ((1.0 - t2) * (1.0 - t2));
                laplacian += weighted * (3.0 - 5.0 * t2);
            }
        });
        PixelEstimate {
            radiance: eye.radiance + vp.beta * kernel * self.kernel_scale,
            laplacian: vp.beta * laplacian * self.laplacian_scale,
            coverage: eye.coverage,
        }
    }
}

/// Whether a visible point lies in a medium rather than on a surface.
fn in_medium(vp: &VisiblePoint) -> bool {
    matches!(vp.bsdf, Bsdf::Medium { .. })
}

/// A pass's photons stored on surfaces, and those stored in media bucketed for its gathers.
#[inline(never)]
pub fn in_media(photons: Vec<Photon>, pass: &PassSamples) -> (Vec<Photon>, Option<MediumPhotons>) {
    let (surfaces, media): (Vec<Photon>, Vec<Photon>) = photons.into_iter().partition(|p| p.ng != Vec3::ZERO);
    (surfaces, Some(MediumPhotons::new(media, pass.volume_radius, pass.radius)))
}

/// Every pixel's estimate from its eye result, the pass's surface photons and its photons in
/// media: the surfaces' gather with the points in media left out, then theirs. (One call of the
/// surfaces' gather for both: a second path into its inner functions changed how they were
/// compiled for scenes without media, which measured 3% slower.)
#[inline(never)]
pub fn gather_with_media(
    eye: &[EyeResult],
    surfaces: &PhotonSet,
    media: &MediumPhotons,
) -> Vec<PixelEstimate> {
    let on_surfaces: Vec<EyeResult> = eye
        .iter()
        .map(|e| match e.point {
            Some(vp) if in_medium(&vp) => EyeResult { point: None, ..*e },
            _ => *e,
        })
        .collect();
    let mut estimates = gather(&on_surfaces, surfaces);
    estimates.par_iter_mut().zip(eye).with_min_len(64).for_each(|(estimate, e)| {
        if let Some(vp) = e.point.filter(in_medium) {
            *estimate = media.estimate(e, &vp);
        }
    });
    estimates
}
