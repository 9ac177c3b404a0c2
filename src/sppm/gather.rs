//! The gather (DESIGN.md step 4): at each visible point, the photons within the pass radius,
//! weighted by a smooth kernel and the BSDF.
//!
//! The kernel is the normalised 2-D biweight `K(t) = 3 / (pi r^2) (1 - t^2)^2`, `t = d / r`
//! (Silverman 1986; integrates to 1 over the disc of radius r). Its 2-D Laplacian with respect to
//! the gather position is `-8 * 3 / (pi r^4) (1 - 2 t^2)`; the same photon sum with it in place
//! of `K` estimates the Laplacian of the radiance, which the error bound's bias term needs
//! (Hachisuka, Jarosz & Jensen 2010).

use glam::{Vec3, Vec3A};
use rayon::prelude::*;
use std::f32::consts::PI;

use super::grid::PhotonGrid;
use super::photons::Photon;
use super::renderer::{PixelEstimate, VisiblePoint};
use super::visible::EyeResult;
use crate::error::K2;
use crate::spectrum::{SampledSpectrum, LANES};

/// Photons on surfaces whose normal is within this cosine of perpendicular to the visible
/// point's (past it on the far side: the back of a thin wall) mark an edge.
const EDGE_COSINE: f32 = 0.5;

/// The biweight kernel of one radius and its Laplacian.
#[derive(Clone, Copy)]
struct Kernel {
    r2: f32,
    scale: f32,
    laplacian_scale: f32,
}

impl Kernel {
    fn new(radius: f32) -> Self {
        let r2 = radius * radius;
        let scale = 3.0 / (PI * r2);
        Kernel { r2, scale, laplacian_scale: -8.0 * scale / r2 }
    }

    /// What `photon`, at squared distance `d2 < r^2` from `vp`, adds there (kernel-weighted
    /// reflected flux, and the same with the Laplacian), or `None` when it is on the other side;
    /// a photon on a surface meeting the point's at an edge adds only its edge term, to the second.
    fn weigh(&self, photon: &Photon, d2: f32, vp: &VisiblePoint) -> Option<[SampledSpectrum; 2]> {
        let t2 = d2 / self.r2;
        let facing = photon.ng.dot(vp.frame.ng) * vp.frame.ng.dot(vp.wo).signum();
        if facing <= 0.0 {
            return (facing > -EDGE_COSINE).then(|| [SampledSpectrum::ZERO, self.edge_term(photon, vp, t2)]);
        }
        let weighted = pair_flux(photon, vp) * vp.bsdf.eval(vp.frame.n, vp.wo, photon.wi);
        Some([
            weighted * self.scale * (1.0 - t2) * (1.0 - t2),
            weighted * self.laplacian_scale * (1.0 - 2.0 * t2),
        ])
    }

    /// A photon on a surface meeting the visible point's at an edge stands for the photons the
    /// disc misses beyond that edge: what it would add there (its direction mirrored to the
    /// visible point's side), as a negative bias in Laplacian units (`bias = k2 r^2 / 2 * term`).
    fn edge_term(&self, photon: &Photon, vp: &VisiblePoint, t2: f32) -> SampledSpectrum {
        let n = vp.frame.n;
        let wi = if photon.wi.dot(n) * vp.wo.dot(n) < 0.0 {
            photon.wi - 2.0 * photon.wi.dot(n) * n
        } else {
            photon.wi
        };
        let missed =
            pair_flux(photon, vp) * vp.bsdf.eval(n, vp.wo, wi) * self.scale * (1.0 - t2) * (1.0 - t2);
        -missed / (0.5 * K2 as f32 * self.r2)
    }
}

/// `photon`'s flux as the path joining it to `vp` carries it: both halves scale their hero lane
/// by the lanes' count when they drop the others, and the joined path must do so once.
fn pair_flux(photon: &Photon, vp: &VisiblePoint) -> SampledSpectrum {
    if photon.hero_only && vp.hero_only {
        photon.flux / LANES as f32
    } else {
        photon.flux
    }
}

/// The box around `points` grown by `radius` (`None` when there are none).
fn reach(points: impl Iterator<Item = Vec3>, radius: f32) -> Option<(Vec3, Vec3)> {
    let (lo, hi) = points.map(|p| (p, p)).reduce(|(a, b), (c, d)| (a.min(c), b.max(d)))?;
    Some((lo - Vec3::splat(radius), hi + Vec3::splat(radius)))
}

fn within((lo, hi): (Vec3, Vec3), p: Vec3) -> bool {
    !(p.cmplt(lo).any() || p.cmpgt(hi).any())
}

/// Photons bucketed for gathering at one radius (a copy, sorted by bucket, so that a gather
/// reads each bucket's photons from consecutive memory). Their positions are kept apart as well:
/// most photons of the cells around a point are out of reach, and the distance test then reads
/// 16 bytes a photon instead of a whole photon.
pub struct PhotonSet {
    sorted: Vec<Photon>,
    positions: Vec<Vec3A>,
    grid: PhotonGrid,
    reach: Option<(Vec3, Vec3)>,
    kernel: Kernel,
}

impl PhotonSet {
    /// Buckets `photons` for gathers of radius `radius`.
    pub fn new(photons: &[Photon], radius: f32) -> Self {
        let positions: Vec<Vec3> = photons.par_iter().with_min_len(4096).map(|p| p.p).collect();
        let (grid, order) = PhotonGrid::build(&positions, radius);
        let sorted: Vec<Photon> = order.par_iter().with_min_len(4096).map(|&i| photons[i as usize]).collect();
        let reach = reach(positions.iter().copied(), radius);
        let positions = sorted.par_iter().with_min_len(4096).map(|p| Vec3A::from(p.p)).collect();
        PhotonSet { sorted, positions, grid, reach, kernel: Kernel::new(radius) }
    }

    /// The kernel-weighted sum of the photons' reflected flux at `vp`, and the same with the
    /// kernel's Laplacian, before the path throughput.
    pub fn sum_at(&self, vp: &VisiblePoint) -> [SampledSpectrum; 2] {
        let mut sums = [SampledSpectrum::ZERO; 2];
        if self.reach.is_some_and(|r| within(r, vp.p)) {
            let p = Vec3A::from(vp.p);
            self.grid.for_each_near(vp.p, |range| {
                for (i, position) in range.clone().zip(&self.positions[range]) {
                    let d2 = position.distance_squared(p);
                    if d2 >= self.kernel.r2 {
                        continue;
                    }
                    if let Some([k, l]) = self.kernel.weigh(&self.sorted[i], d2, vp) {
                        sums = [sums[0] + k, sums[1] + l];
                    }
                }
            });
        }
        sums
    }
}

/// A pixel's estimate from its eye result and the photon sums at its visible point.
pub fn estimate(eye: &EyeResult, [sum, laplacian]: [SampledSpectrum; 2]) -> PixelEstimate {
    match eye.point {
        Some(vp) => PixelEstimate { radiance: eye.radiance + vp.beta * sum, laplacian: vp.beta * laplacian },
        None => PixelEstimate { radiance: eye.radiance, laplacian: SampledSpectrum::ZERO },
    }
}

/// Every pixel's estimate from its eye result and the pass's photons.
pub fn gather(eye: &[EyeResult], set: &PhotonSet) -> Vec<PixelEstimate> {
    eye.par_iter()
        .with_min_len(64)
        .map(|e| estimate(e, e.point.map_or([SampledSpectrum::ZERO; 2], |vp| set.sum_at(&vp))))
        .collect()
}
