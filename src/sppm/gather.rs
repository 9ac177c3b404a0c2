//! The gather (DESIGN.md step 4): at each visible point, the photons within the pass radius,
//! weighted by a smooth kernel and the BSDF.
//!
//! The kernel is the normalised 2-D biweight `K(t) = 3 / (pi r^2) (1 - t^2)^2`, `t = d / r`
//! (Silverman 1986; integrates to 1 over the disc of radius r). Its 2-D Laplacian with respect to
//! the gather position is `-8 * 3 / (pi r^4) (1 - 2 t^2)`; the same photon sum with it in place
//! of `K` estimates the Laplacian of the radiance, which the error bound's bias term needs
//! (Hachisuka, Jarosz & Jensen 2010).

use rayon::prelude::*;
use std::f32::consts::PI;

use super::grid::PhotonGrid;
use super::visible::EyeResult;
use super::{Photon, PixelEstimate};

/// Every pixel's estimate from its eye result and the pass's photons.
pub fn gather(eye: &[EyeResult], photons: &[Photon], radius: f32) -> Vec<PixelEstimate> {
    let grid = PhotonGrid::build(photons.iter().map(|p| p.p), photons.len(), radius);
    let r2 = radius * radius;
    let kernel_scale = 3.0 / (PI * r2);
    let laplacian_scale = -8.0 * kernel_scale / r2;
    eye.par_iter()
        .with_min_len(64)
        .map(|e| {
            let Some(vp) = e.point else {
                return PixelEstimate { radiance: e.radiance, laplacian: 0.0 };
            };
            let (mut sum, mut laplacian) = (0.0f32, 0.0f32);
            grid.for_each_near(vp.p, |i| {
                let photon = &photons[i];
                let d2 = photon.p.distance_squared(vp.p);
                if d2 >= r2 || photon.ng.dot(vp.frame.ng) * vp.frame.ng.dot(vp.wo) <= 0.0 {
                    return;
                }
                let t2 = d2 / r2;
                let weighted = photon.flux * vp.bsdf.eval(vp.frame.n, vp.wo, photon.wi);
                sum += weighted * kernel_scale * (1.0 - t2) * (1.0 - t2);
                laplacian += weighted * laplacian_scale * (1.0 - 2.0 * t2);
            });
            PixelEstimate { radiance: e.radiance + vp.beta * sum, laplacian: vp.beta * laplacian }
        })
        .collect()
}
