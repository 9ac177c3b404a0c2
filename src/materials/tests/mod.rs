//! The BSDFs' tests, a file per lobe as Mitsuba keeps them, with the checks they share here:
//! every sample's weight against `eval` and `pdf`, Pearson's chi-square test of where samples
//! fall, and albedos by sampling.

mod conductor;
mod dielectric;
mod diffuse;
mod layering;
mod plastic;
mod sheen;

use super::*;
use crate::sampling::{square_to_sphere, stream, Sampler, Stream};
use crate::spectrum::{Dispersion, RgbSpectrum, Wavelengths};
use glam::DVec4;

pub(super) const FRAME: ShadingFrame = ShadingFrame::new(Vec3::Z, Vec3::Z);

/// Every sample's weight is `f cos / pdf` as `eval` and `pdf` say, the samples fall where the
/// density says ([`chi_square`]), and the mean weight (the importance-sampled albedo) matches
/// the albedo integrated with uniform directions.
pub(super) fn check_sampling_against_eval(bsdf: Bsdf, wo: Vec3) {
    let n = 200_000;
    let mut rng = stream(3, Stream::Eye, 0, 0);
    let sampled = check_sampling_density(bsdf, wo, n, &mut rng);
    let uniform: DVec4 = (0..n)
        .map(|_| {
            let wi = square_to_sphere(rng.next_2d());
            (bsdf.eval(FRAME, wo, wi) * wi.z.abs() * 4.0 * std::f32::consts::PI).as_dvec4()
        })
        .sum();
    let (sampled, uniform) = (sampled / n as f64, uniform / n as f64);
    let tolerance = 0.02 * uniform.max(DVec4::splat(0.1));
    assert!((sampled - uniform).abs().cmple(tolerance).all(), "{bsdf:?}: {sampled} vs {uniform}");
}

/// Every one of `n` samples' weight is `f cos / pdf` as `eval` and `pdf` say, and the samples
/// fall where the density says ([`chi_square`]); the sum of their weights.
pub(super) fn check_sampling_density(bsdf: Bsdf, wo: Vec3, n: usize, rng: &mut Sampler) -> DVec4 {
    let mut sampled = DVec4::ZERO;
    let mut directions = Vec::with_capacity(n);
    for _ in 0..n {
        let Some(s) = bsdf.sample(FRAME, wo, rng.next_2d(), rng.next_1d(), Transport::Radiance) else {
            continue;
        };
        directions.push(s.wi);
        let (f, pdf) = (bsdf.eval(FRAME, wo, s.wi), bsdf.pdf(FRAME, wo, s.wi));
        assert!((s.pdf / pdf - 1.0).abs() < 1e-3, "{bsdf:?}: pdf {} vs {pdf}", s.pdf);
        let expected = f * s.wi.z.abs() / pdf;
        assert!((s.weight / expected - Vec4::ONE).abs().max_element() < 1e-3, "{bsdf:?}: weight");
        sampled += s.weight.as_dvec4();
    }
    chi_square(bsdf, wo, &directions, n);
    sampled
}

/// Pearson's chi-square test of where `bsdf` sends `draws` samples (`directions`, those not
/// refused) against its density, as Mitsuba tests its BSDFs: a 10 x 20 grid over theta and
/// phi, each cell expecting the density integrated over it (Simpson's rule on a 64 x 64 grid:
/// a narrow lobe at grazing needs it), the cells expecting under 5 samples pooled into one;
/// rejected below a p-value of 1e-4 (the seeds are fixed: it passes or fails the same way
/// every run).
pub(super) fn chi_square(bsdf: Bsdf, wo: Vec3, directions: &[Vec3], draws: usize) {
    use statrs::distribution::{ChiSquared, ContinuousCDF};
    use std::f64::consts::PI;
    const THETA: usize = 10;
    const PHI: usize = 20;
    const SUB: usize = 64;
    let (d_theta, d_phi) = (PI / THETA as f64, 2.0 * PI / PHI as f64);
    let cell = |w: Vec3| {
        let theta = f64::from(w.z.clamp(-1.0, 1.0)).acos();
        let phi = f64::from(w.y).atan2(f64::from(w.x)) + PI;
        let index = |x: f64, step: f64, count: usize| ((x / step) as usize).min(count - 1);
        index(theta, d_theta, THETA) * PHI + index(phi, d_phi, PHI)
    };
    let mut observed = vec![0.0f64; THETA * PHI];
    for &w in directions {
        observed[cell(w)] += 1.0;
    }
    let simpson = |k: usize| match k {
        0 | SUB => 1.0,
        k if k % 2 == 1 => 4.0,
        _ => 2.0,
    };
    let expected: Vec<f64> = (0..THETA * PHI)
        .map(|c| {
            let (theta_0, phi_0) = ((c / PHI) as f64 * d_theta, (c % PHI) as f64 * d_phi);
            let (h_theta, h_phi) = (d_theta / SUB as f64, d_phi / SUB as f64);
            let mut sum = 0.0;
            for i in 0..=SUB {
                for j in 0..=SUB {
                    // Just inside the cell's edges: the density may jump at the horizon.
                    let inside = |k: usize| (k as f64).clamp(1e-6, SUB as f64 - 1e-6);
                    let (theta, phi) = (theta_0 + inside(i) * h_theta, phi_0 + inside(j) * h_phi - PI);
                    let w = Vec3::new(
                        (theta.sin() * phi.cos()) as f32,
                        (theta.sin() * phi.sin()) as f32,
                        theta.cos() as f32,
                    );
                    sum += simpson(i) * simpson(j) * f64::from(bsdf.pdf(FRAME, wo, w)) * theta.sin();
                }
            }
            sum * h_theta * h_phi / 9.0 * draws as f64
        })
        .collect();
    let mut cells: Vec<(f64, f64)> = expected.into_iter().zip(observed).collect();
    cells.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (mut pooled, mut statistic, mut count) = ((0.0, 0.0), 0.0, 0);
    for (e, o) in cells {
        if e < 5.0 {
            pooled = (pooled.0 + e, pooled.1 + o);
            continue;
        }
        statistic += (o - e).powi(2) / e;
        count += 1;
    }
    if pooled.0 + pooled.1 > 0.0 {
        // Samples where the density says there are none fail the test outright.
        statistic += (pooled.1 - pooled.0).powi(2) / pooled.0.max(1e-9);
        count += 1;
    }
    let p = 1.0 - ChiSquared::new((count - 1) as f64).unwrap().cdf(statistic);
    assert!(p > 1e-4, "{bsdf:?} seen from {wo}: chi-square {statistic:.1} over {count} cells, p {p:.2e}");
}

/// The directional albedo `int f cos dwi` for `wo`, by sampling the BSDF.
pub(super) fn albedo(bsdf: Bsdf, wo: Vec3) -> Vec4 {
    scattered(bsdf, wo, Transport::Radiance)
}

/// The share of what arrives from `wo` that `bsdf` scatters, for `mode`, by sampling.
pub(super) fn scattered(bsdf: Bsdf, wo: Vec3, mode: Transport) -> Vec4 {
    let mut rng = stream(5, Stream::Eye, 0, 0);
    let n = 400_000;
    let sum: DVec4 = (0..n)
        .filter_map(|_| bsdf.sample(FRAME, wo, rng.next_2d(), rng.next_1d(), mode))
        .map(|s| s.weight.as_dvec4())
        .sum();
    (sum / n as f64).as_vec4()
}

/// The directional albedo of a whole material seen from `wo`: layer choices and BSDF samples
/// together, as a camera path meets them.
pub(super) fn material_albedo(material: &Material, wo: Vec3) -> f32 {
    let at = Wavelengths::single(550.0, 1.0);
    let mut rng = stream(7, Stream::Eye, 0, 0);
    let n = 400_000;
    let sum: f64 = (0..n)
        .filter_map(|_| {
            let lobe = material.lobe(&SurfaceInputs::default(), FRAME, wo, &at, rng.next_1d());
            let u_lobe = lobe.bsdf.lobe_number(|| rng.next_1d());
            let sample = lobe.bsdf.sample(lobe.frame, wo, rng.next_2d(), u_lobe, Transport::Radiance)?;
            Some(f64::from(sample.weight.x * lobe.weight))
        })
        .sum();
    (sum / n as f64) as f32
}
