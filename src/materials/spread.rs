//! Blender's area light Spread, as Cycles models it: a soft box's grid of slats in front of the
//! light, which lets through the share `1 - tan(theta) / tan(s / 2)` of the light leaving at
//! `theta` from the normal (none beyond half the spread `s`), scaled so that the light keeps its
//! power: the radiance at `theta` is `L (tan(s / 2) - tan(theta)) / (tan(s / 2) - s / 2)`.

use glam::{Vec2, Vec3};

use crate::sampling::square_to_disc;

/// The narrowest spread rendered, in radians (1 degree): a narrower one is rendered as this.
pub const NARROWEST_SPREAD: f32 = std::f32::consts::PI / 180.0;

/// An area light's spread below 180 degrees.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spread {
    /// Tangent of half the spread.
    tan_half: f32,
    /// `1 / (tan(s / 2) - s / 2)`: the radiance along the normal over the light's without spread
    /// is `tan(s / 2)` times this.
    normalisation: f32,
    /// Sine of half the spread (the radius of the disc of directions it lets through).
    sin_half: f32,
}

impl Spread {
    /// The spread of `angle` radians (clamped to [`NARROWEST_SPREAD`] and above); `None` from
    /// 180 degrees on, where it changes nothing.
    pub fn new(angle: f32) -> Option<Spread> {
        if !(angle < std::f32::consts::PI) {
            return None;
        }
        let half = f64::from(angle.max(NARROWEST_SPREAD)) / 2.0;
        Some(Spread {
            tan_half: half.tan() as f32,
            normalisation: (1.0 / (half.tan() - half)) as f32,
            sin_half: half.sin() as f32,
        })
    }

    /// Cosine of half the spread: no light leaves farther from the normal.
    pub fn cos_half(&self) -> f32 {
        (1.0 - self.sin_half * self.sin_half).max(0.0).sqrt()
    }

    /// The factor on the radiance leaving at `cos` from the normal.
    pub fn attenuation(&self, cos: f32) -> f32 {
        if cos <= 0.0 {
            return 0.0;
        }
        let tan = (1.0 - cos * cos).max(0.0).sqrt() / cos;
        ((self.tan_half - tan) * self.normalisation).max(0.0)
    }

    /// A direction leaving the light, in its local frame (normal +z), for a photon: cosine-
    /// weighted within the cone the slats let through, with the factor on the flux that a
    /// cosine-weighted direction over the hemisphere carries (its mean is 1).
    pub fn sample(&self, u: Vec2) -> (Vec3, f32) {
        let d = square_to_disc(u) * self.sin_half;
        let cos = (1.0 - d.length_squared()).max(0.0).sqrt();
        (Vec3::new(d.x, d.y, cos), self.attenuation(cos) * self.sin_half * self.sin_half)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The mean of `f` over `n * n` stratified points of the unit square.
    fn mean(n: usize, f: impl Fn(Vec2) -> f64) -> f64 {
        let points = (0..n * n)
            .map(|i| Vec2::new(((i % n) as f32 + 0.5) / n as f32, ((i / n) as f32 + 0.5) / n as f32));
        points.map(f).sum::<f64>() / (n * n) as f64
    }

    #[test]
    fn a_spread_light_keeps_its_power_and_photons_carry_it() {
        for degrees in [1.0f32, 10.0, 45.0, 90.0, 170.0] {
            let spread = Spread::new(degrees.to_radians()).unwrap();
            // Power over the hemisphere (the integral of the attenuation times 2 cos sin over the
            // angle, by the midpoint rule), and the photons' mean weight.
            let steps = 100_000;
            let step = std::f64::consts::FRAC_PI_2 / steps as f64;
            let power: f64 = (0..steps)
                .map(|i| {
                    let theta = (i as f64 + 0.5) * step;
                    f64::from(spread.attenuation(theta.cos() as f32)) * (2.0 * theta).sin() * step
                })
                .sum();
            let photons = mean(400, |u| f64::from(spread.sample(u).1));
            assert!((photons - 1.0).abs() < 2e-3, "{degrees} degrees: photons carry {photons}");
            assert!((power - 1.0).abs() < 2e-3, "{degrees} degrees: power {power}");
        }
    }

    #[test]
    fn light_leaves_only_within_half_the_spread() {
        let spread = Spread::new(60f32.to_radians()).unwrap();
        assert_eq!(spread.attenuation(29.0f32.to_radians().cos()) > 0.0, true);
        assert_eq!(spread.attenuation(31.0f32.to_radians().cos()), 0.0);
        assert!(Spread::new(std::f32::consts::PI).is_none());
        let along_normal = spread.attenuation(1.0);
        let half = 30f32.to_radians();
        assert!((along_normal - half.tan() / (half.tan() - half)).abs() < 1e-4);
    }
}
