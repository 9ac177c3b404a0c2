//! Where a photon path scatters in a homogeneous medium that scatters: the distance to its next
//! event, drawn in proportion to the transmittance times the extinction (Beer–Lambert's free
//! flight), and points on an eye segment drawn toward a light (equiangular sampling). Eye paths
//! draw no events: they pass through media as beams (`beams.rs`).
//!
//! The extinction depends on the wavelength, and a path carries four. The distance is drawn at
//! one of them, chosen uniformly, and weighed by the density of the four mixed (Wilkie et al.
//! 2014's spectral multiple importance sampling, the one-sample balance heuristic): a medium that
//! scatters blue far more than red gives no lane a weight beyond four. A path carrying its hero
//! wavelength alone draws at it.

use glam::Vec3;

use crate::materials::{transmittance, Volume};
use crate::spectrum::{SampledSpectrum, Wavelengths, LANES};

/// Free flight through one medium at a path's wavelengths.
#[derive(Clone, Copy, Debug)]
pub struct Flight {
    extinction: SampledSpectrum,
    /// The lanes distances are drawn at: all, or the hero alone.
    lanes: usize,
}

/// What a path's segment of some length through a medium met.
#[derive(Clone, Copy, Debug)]
pub enum Crossing {
    /// An event at `t` along the segment, before its end: the path's throughput is to be
    /// multiplied by `weight` (the transmittance to `t` over the distance's density; the
    /// scattering coefficient is the event's to add).
    Event { t: f32, weight: SampledSpectrum },
    /// No event before the end: the throughput is to be multiplied by `weight` (the
    /// transmittance over the probability of passing).
    Passed { weight: SampledSpectrum },
}

impl Flight {
    /// Flight through `volume` at `lambda`, for a path that carries its hero wavelength alone
    /// or not.
    pub fn new(volume: &Volume, lambda: &Wavelengths, hero_only: bool) -> Self {
        Flight { extinction: volume.extinction(lambda), lanes: if hero_only { 1 } else { LANES } }
    }

    /// The distance to the next event, from the uniform number `u` (infinite where the lane drawn
    /// at does not scatter or absorb).
    fn draw(&self, u: f32) -> f32 {
        // One number picks the lane and, rescaled, the distance at it.
        let scaled = u * self.lanes as f32;
        let lane = (scaled as usize).min(self.lanes - 1);
        -(-(scaled - lane as f32)).ln_1p() / self.extinction[lane]
    }

    /// The weight of an event at `t`: the transmittance to it over the distance's density.
    fn event_weight(&self, t: f32) -> SampledSpectrum {
        let kept = transmittance(self.extinction, t);
        over(kept, self.mean(self.extinction * kept))
    }

    /// The weight of passing `length` without an event: the transmittance over its probability.
    fn pass_weight(&self, length: f32) -> SampledSpectrum {
        let kept = transmittance(self.extinction, length);
        over(kept, self.mean(kept))
    }

    /// The event a segment of `length` (infinite where it leaves the scene) meets, from the
    /// uniform number `u`.
    pub fn cross(&self, length: f32, u: f32) -> Crossing {
        match self.draw(u) {
            t if t < length => Crossing::Event { t, weight: self.event_weight(t) },
            _ => Crossing::Passed { weight: self.pass_weight(length) },
        }
    }

    /// The mean of the lanes distances are drawn at.
    fn mean(&self, v: SampledSpectrum) -> f32 {
        v.to_array()[..self.lanes].iter().sum::<f32>() / self.lanes as f32
    }
}

/// `v / p`, or zero where `p` is (a transmittance below f32's range at every lane).
fn over(v: SampledSpectrum, p: f32) -> SampledSpectrum {
    if p > 0.0 {
        v / p
    } else {
        SampledSpectrum::ZERO
    }
}

/// A point on the segment from `origin` along unit `direction` of `length` (possibly infinite)
/// drawn in proportion to the inverse square of its distance to `centre` (Kulla & Fajardo 2012,
/// "Importance sampling techniques for path tracing in participating media"), from the uniform
/// number `u`: its distance along the segment and its density there. `None` where the segment
/// runs through the centre, or is empty.
pub fn equiangular(origin: Vec3, direction: Vec3, length: f32, centre: Vec3, u: f32) -> Option<(f32, f32)> {
    let along = (centre - origin).dot(direction);
    let height = (centre - origin - direction * along).length();
    if !(height > 1e-6 * along.abs().max(1.0)) || !(length > 0.0) {
        return None;
    }
    let start = (-along).atan2(height);
    let end = if length.is_finite() { (length - along).atan2(height) } else { std::f32::consts::FRAC_PI_2 };
    let angle = start + u * (end - start);
    let t = (along + height * angle.tan()).clamp(0.0, length);
    let offset = t - along;
    let density = height / ((end - start) * (height * height + offset * offset));
    (density > 0.0 && density.is_finite()).then_some((t, density))
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{Vec3, Vec4};

    fn fog(extinction: Vec3) -> Volume {
        Volume::medium(Vec3::ZERO, extinction, 0.0, 0.0)
    }

    #[test]
    fn events_and_passes_weigh_to_the_transmittance() {
        // The mean weight of passing a segment (events weigh 0 toward it) is the transmittance, at
        // every wavelength, for a grey and a coloured medium.
        let lambda = Wavelengths { nm: Vec4::new(450.0, 530.0, 610.0, 650.0), ..Wavelengths::sampled(0.5) };
        for volume in [fog(Vec3::splat(0.7)), fog(Vec3::new(0.2, 0.5, 2.0))] {
            let length = 1.3;
            let n = 100_000;
            let mut passed = Vec4::ZERO;
            let mut event_mass = Vec4::ZERO;
            for i in 0..n {
                match Flight::new(&volume, &lambda, false).cross(length, (i as f32 + 0.5) / n as f32) {
                    Crossing::Passed { weight } => passed += weight,
                    // The events' weight times the extinction integrates to what does not pass.
                    Crossing::Event { weight, .. } => event_mass += weight * volume.extinction(&lambda),
                }
            }
            let expected = volume.transmittance(&lambda, length);
            let passed = passed / n as f32;
            let event_mass = event_mass / n as f32;
            assert!((passed - expected).abs().max_element() < 2e-3, "{passed} against {expected}");
            assert!(
                (event_mass - (Vec4::ONE - expected)).abs().max_element() < 2e-3,
                "{event_mass} against {}",
                Vec4::ONE - expected
            );
        }
    }

    #[test]
    fn an_endless_segment_always_meets_an_event() {
        let lambda = Wavelengths::sampled(0.3);
        for u in [0.0, 0.3, 0.999_999] {
            assert!(matches!(
                Flight::new(&fog(Vec3::splat(0.1)), &lambda, false).cross(f32::INFINITY, u),
                Crossing::Event { .. }
            ));
        }
    }

    #[test]
    fn equiangular_density_matches_its_histogram() {
        let (origin, direction, centre) = (Vec3::ZERO, Vec3::X, Vec3::new(0.7, 0.4, 0.1));
        for length in [2.5f32, f32::INFINITY] {
            let (bins, n, top) = (25usize, 200_000usize, 2.5f32);
            let mut counts = vec![0usize; bins];
            let mut beyond = 0;
            for i in 0..n {
                let (t, density) =
                    equiangular(origin, direction, length, centre, (i as f32 + 0.5) / n as f32).unwrap();
                assert!(density > 0.0 && t >= 0.0 && t <= length);
                match ((t / top * bins as f32) as usize).min(bins) {
                    b if b < bins => counts[b] += 1,
                    _ => beyond += 1,
                }
            }
            let mut chi2 = 0.0;
            let mut mass_within = 0.0;
            for (b, &count) in counts.iter().enumerate() {
                // The density's mass over the bin, by the midpoint rule at a fine step.
                let steps = 200;
                let width = top / bins as f32;
                let mass: f64 = (0..steps)
                    .map(|k| {
                        let t = (b as f32 + (k as f32 + 0.5) / steps as f32) * width;
                        let offset = t - 0.7;
                        let height2 = 0.4f32 * 0.4 + 0.1 * 0.1;
                        let end =
                            if length.is_finite() { (length - 0.7).atan2(height2.sqrt()) } else { 1.5707964 };
                        let span = end - (-0.7f32).atan2(height2.sqrt());
                        f64::from(
                            height2.sqrt() / (span * (height2 + offset * offset)) * width / steps as f32,
                        )
                    })
                    .sum();
                mass_within += mass;
                let expected = mass * n as f64;
                chi2 += (count as f64 - expected).powi(2) / expected;
            }
            // 24 degrees of freedom: the 99.9th percentile is 51.2.
            assert!(chi2 < 51.2, "length {length}: chi-square {chi2}");
            let beyond_expected = (1.0 - mass_within) * n as f64;
            assert!((beyond as f64 - beyond_expected).abs() < 5.0 * beyond_expected.sqrt() + 5.0);
        }
    }
}
