//! The Henyey–Greenstein phase function of a scattering medium: the share of light scattered
//! through each angle, `p(cos) = (1 - g^2) / (4 pi (1 + g^2 - 2 g cos)^(3/2))` per steradian,
//! where `cos` is the cosine between the light's direction of travel before and after (`g > 0`
//! scatters forward, `g < 0` back, `0` evenly; the mean cosine is `g`). With `wo` and `wi` both
//! pointing away from the scattering point (as at a surface), light travels along `-wi` and then
//! along `wo`, so `cos = -wo . wi`: the function is symmetric in the two, and photons (which
//! travel the other way) use it unchanged.

use glam::{Vec2, Vec3, Vec3A};
use std::f32::consts::{FRAC_1_PI, PI};

/// Below this |g| the function is taken as isotropic (its sampling formula divides by `g`).
const ISOTROPIC: f32 = 1e-3;

/// The phase function's value for `wo` and `wi`.
#[inline(never)]
pub fn eval(g: f32, wo: Vec3, wi: Vec3) -> f32 {
    of_cosine(g, -wo.dot(wi))
}

/// Its value at the cosine `cos` between the directions of travel.
pub fn of_cosine(g: f32, cos: f32) -> f32 {
    let denominator = 1.0 + g * g - 2.0 * g * cos;
    0.25 * FRAC_1_PI * (1.0 - g * g) / (denominator * denominator.max(0.0).sqrt()).max(f32::MIN_POSITIVE)
}

/// A direction `wi` drawn in proportion to the function for `wo`, from the uniform pair `u` (the
/// function itself is its density). Kept out of line, as [`eval`] is: surfaces' BSDF matches,
/// which every path runs, stay as small as they were without media.
#[inline(never)]
pub fn sample(g: f32, wo: Vec3, u: Vec2) -> Vec3 {
    let cos = if g.abs() < ISOTROPIC {
        1.0 - 2.0 * u.x
    } else {
        let ratio = (1.0 - g * g) / (1.0 - g + 2.0 * g * u.x);
        ((1.0 + g * g - ratio * ratio) / (2.0 * g)).clamp(-1.0, 1.0)
    };
    let sin = (1.0 - cos * cos).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    let forward = Vec3A::from(-wo);
    let (t, b) = forward.any_orthonormal_pair();
    Vec3::from(forward * cos + (t * phi.cos() + b * phi.sin()) * sin)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn integrates_to_one_with_mean_cosine_g() {
        for g in [-0.8f32, -0.3, 0.0, 0.5, 0.9] {
            // Over the sphere: 2 pi times the integral over cos in [-1, 1] (midpoint rule).
            let n = 200_000;
            let (mut total, mut mean) = (0.0f64, 0.0f64);
            for i in 0..n {
                let cos = -1.0 + 2.0 * (i as f32 + 0.5) / n as f32;
                let p = f64::from(of_cosine(g, cos)) * 2.0 * std::f64::consts::PI * 2.0 / n as f64;
                total += p;
                mean += p * f64::from(cos);
            }
            assert!((total - 1.0).abs() < 1e-3, "g {g}: integral {total}");
            assert!((mean - f64::from(g)).abs() < 1e-3, "g {g}: mean cosine {mean}");
        }
    }

    #[test]
    fn samples_follow_the_function() {
        // A histogram of the sampled cosines against the function's mass in each bin (chi-square).
        let wo = Vec3::new(0.3, -0.5, 0.81).normalize();
        for g in [-0.6f32, 0.0, 0.7] {
            let (bins, n) = (20usize, 200_000usize);
            let mut counts = vec![0usize; bins];
            for i in 0..n {
                let u = Vec2::new((i as f32 + 0.5) / n as f32, ((i * 7919) % n) as f32 / n as f32);
                let wi = sample(g, wo, u);
                assert!((wi.length() - 1.0).abs() < 1e-4);
                let cos = -wo.dot(wi);
                counts[(((cos + 1.0) / 2.0 * bins as f32) as usize).min(bins - 1)] += 1;
            }
            let mut chi2 = 0.0;
            for (b, &count) in counts.iter().enumerate() {
                let steps = 1000;
                let mass: f64 = (0..steps)
                    .map(|k| {
                        let cos = -1.0 + 2.0 * (b as f32 + (k as f32 + 0.5) / steps as f32) / bins as f32;
                        f64::from(of_cosine(g, cos)) * 2.0 * std::f64::consts::PI * 2.0
                            / (bins * steps) as f64
                    })
                    .sum();
                let expected = mass * n as f64;
                chi2 += (count as f64 - expected).powi(2) / expected;
            }
            // 19 degrees of freedom: the 99.9th percentile is 43.8.
            assert!(chi2 < 43.8, "g {g}: chi-square {chi2}, counts {counts:?}");
        }
    }

    #[test]
    fn is_symmetric_and_forward_for_positive_g() {
        let (wo, wi) = (Vec3::new(0.0, 0.0, 1.0), Vec3::new(0.6, 0.0, -0.8));
        assert_eq!(eval(0.4, wo, wi), eval(0.4, wi, wo));
        // Light going on straight (wi = -wo) is favoured by g > 0.
        assert!(eval(0.5, wo, -wo) > eval(0.5, wo, wo) * 10.0);
    }
}
