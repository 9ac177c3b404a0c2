//! Point and spot lights as Blender has them: a sphere of `radius` (a point when it is 0) of the
//! same radiance seen from every side, `I / (pi r^2)` for a radiant intensity `I`, shining into
//! a beam (a spot's cone, with its falloff) or every way (a point light).
//!
//! As Cycles renders them, the sphere lights what is around it with soft shadows, is seen in
//! reflections and, when the light is visible to the camera, by the camera; it casts no shadow and
//! hides nothing behind it. A spot's falloff is taken along each ray's own direction, so the
//! sphere softens the edge of the pool of light too.
//!
//! With Blender's Soft Falloff (its default), Cycles makes the light a disc of the same radius and
//! radiance that faces whatever looks at it: a surface at distance d then receives `I cos / (d^2 +
//! r^2)` rather than the sphere's `I cos / d^2` (measured in Cycles: within 0.1% for r / d from 0.1
//! to 1). Rays meet that disc, and photons, which leave the sphere, have their flux scaled by
//! `d^2 / (d^2 + r^2)` at the first surface they meet, so that what they light there is the
//! disc's.

use glam::{Vec2, Vec3};
use std::f32::consts::PI;

use super::{direction_and_distance, EmittedPhoton, LightSample};
use crate::geometry::{one_minus_cos_between, Cone};
use crate::sampling::{basis, square_to_cone, square_to_disc};
use crate::spectrum::{Illuminant, SampledSpectrum, Wavelengths};

/// A point or spot light, with or without a radius.
#[derive(Clone, Debug)]
pub struct SphereLight {
    /// Its centre.
    pub position: Vec3,
    /// Radiant intensity (on the axis, for a spot), W/sr.
    pub intensity: Illuminant,
    /// The radius of its sphere, or 0 for a point.
    pub radius: f32,
    /// A spot's beam; `None` for a point light, which shines every way.
    pub beam: Option<Beam>,
    /// Whether the camera sees the sphere (Blender's Ray Visibility > Camera); it is seen in
    /// reflections either way.
    pub seen_by_camera: bool,
    /// Blender's Soft Falloff: the light is a disc facing each point it lights.
    pub soft_falloff: bool,
}

/// What Soft Falloff does to a photon from a light with a radius: its flux is scaled by
/// `d^2 / (d^2 + r^2)` at the first surface it meets, at distance d from the light's centre.
#[derive(Clone, Copy, Debug)]
pub struct SoftFalloff {
    /// The light's centre.
    centre: Vec3,
    /// Its radius, squared.
    radius2: f32,
}

impl SoftFalloff {
    /// The factor on the flux of a photon that first meets a surface at `p`.
    pub fn at(&self, p: Vec3) -> f32 {
        let d2 = p.distance_squared(self.centre);
        d2 / (d2 + self.radius2)
    }
}

/// The cone a spot light shines into.
#[derive(Clone, Copy, Debug)]
pub struct Beam {
    /// Unit axis of the cone (the direction light travels).
    pub axis: Vec3,
    /// How it falls off toward the cone's edge.
    pub falloff: SpotFalloff,
    /// The outer cone (no light outside).
    pub outer: Cone,
}

/// How a spot light dims toward the edge of its cone.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SpotFalloff {
    /// glTF's: the square of a linear ramp in cosine from the outer cone to this inner one.
    Gltf {
        /// The inner cone (full intensity inside).
        inner: Cone,
    },
    /// Blender's Spot Blend, as Cycles renders it: a smoothstep in cosine over the last `blend`
    /// of the cone's `1 - cos` (0: a hard edge).
    Blender {
        /// Blender's Spot Blend, in [0, 1].
        blend: f32,
    },
}

/// The spot falloff for a direction whose `1 - cos` from the axis is `one_minus_cos`.
fn spot_falloff(one_minus_cos: f32, falloff: SpotFalloff, outer: Cone) -> f32 {
    let width = match falloff {
        SpotFalloff::Gltf { inner } => outer.one_minus_cos - inner.one_minus_cos,
        SpotFalloff::Blender { blend } => outer.one_minus_cos * blend,
    };
    if width <= 0.0 {
        return if one_minus_cos <= outer.one_minus_cos { 1.0 } else { 0.0 };
    }
    let t = ((outer.one_minus_cos - one_minus_cos) / width).clamp(0.0, 1.0);
    match falloff {
        SpotFalloff::Gltf { .. } => t * t,
        SpotFalloff::Blender { .. } => t * t * (3.0 - 2.0 * t),
    }
}

/// The cone of every direction.
const EVERY_WAY: Cone = Cone { one_minus_cos: 2.0 };

impl SphereLight {
    /// The share of its intensity the light sends along the unit `direction` (the beam's falloff).
    fn falloff(&self, direction: Vec3) -> f32 {
        match self.beam {
            Some(beam) => spot_falloff(one_minus_cos_between(direction, beam.axis), beam.falloff, beam.outer),
            None => 1.0,
        }
    }

    /// The cone it shines into, about its axis.
    fn cone(&self) -> (Vec3, Cone) {
        self.beam.map_or((Vec3::Z, EVERY_WAY), |beam| (beam.axis, beam.outer))
    }

    /// Total emitted luminous power (before the falloff).
    pub fn power(&self) -> f64 {
        f64::from(self.cone().1.solid_angle()) * self.intensity.luminance()
    }

    /// The cone of directions from `p` in which the sphere lies, toward its centre at
    /// `distance` (its `1 - cos`); `None` for a point or from inside.
    fn seen_from(&self, distance: f32) -> Option<Cone> {
        if !(self.radius > 0.0 && distance > self.radius) {
            return None;
        }
        let sin2_max = (self.radius / distance).powi(2);
        Some(Cone { one_minus_cos: sin2_max / (1.0 + (1.0 - sin2_max).sqrt()) })
    }

    /// Whether it is a disc facing what looks at it (a radius and Soft Falloff).
    fn is_disc(&self) -> bool {
        self.soft_falloff && self.radius > 0.0
    }

    /// For photons: Soft Falloff's factor on their flux where they first meet a surface.
    pub fn photon_falloff(&self) -> Option<SoftFalloff> {
        self.is_disc().then_some(SoftFalloff { centre: self.position, radius2: self.radius * self.radius })
    }

    /// Samples light arriving at `p`: a direction uniform over the solid angle the sphere covers
    /// (toward the centre for a point, or from inside the sphere), or a uniform point of the disc
    /// facing `p`.
    pub fn sample_incident(&self, p: Vec3, u: Vec2, lambda: &Wavelengths) -> Option<LightSample> {
        let (to_centre, centre_distance) = direction_and_distance(p, self.position)?;
        if self.is_disc() {
            let (t, b) = basis(to_centre);
            let d = square_to_disc(u) * self.radius;
            let (wi, distance) = direction_and_distance(p, self.position + t * d.x + b * d.y)?;
            let pdf = self.disc_pdf(to_centre, wi, distance);
            let radiance_over_pdf = self.radiance(-wi, lambda) / pdf;
            return (pdf.is_finite() && radiance_over_pdf.max_element() > 0.0).then_some(LightSample {
                wi,
                distance,
                radiance_over_pdf,
                pdf,
            });
        }
        let sample = match self.seen_from(centre_distance) {
            Some(cone) => self.sample_cone((to_centre, centre_distance), cone, u, lambda),
            None => LightSample {
                wi: to_centre,
                distance: centre_distance,
                radiance_over_pdf: self.intensity.eval(lambda)
                    * (self.falloff(-to_centre) / (centre_distance * centre_distance)),
                pdf: 0.0,
            },
        };
        (sample.radiance_over_pdf.max_element() > 0.0).then_some(sample)
    }

    /// Samples light arriving at `p` from the sphere's own surface, as vertex connection and
    /// merging meets a light with a radius (`transport/vcm/`): a direction uniform over the solid angle
    /// the sphere covers, times Soft Falloff's factor at `p` where the light has it (which makes
    /// the sphere light `p` as the disc facing it does, exactly where the light is wholly above
    /// `p`'s horizon and unblocked). `None` for a point and from inside the sphere, which it does
    /// not light.
    pub fn sample_surface(&self, p: Vec3, u: Vec2, lambda: &Wavelengths) -> Option<LightSample> {
        let (to_centre, centre_distance) = direction_and_distance(p, self.position)?;
        let cone = self.seen_from(centre_distance)?;
        let mut sample = self.sample_cone((to_centre, centre_distance), cone, u, lambda);
        sample.radiance_over_pdf *= self.receiver_factor(p);
        (sample.radiance_over_pdf.max_element() > 0.0).then_some(sample)
    }

    /// A direction uniform over `cone`, the sphere seen from a point outside it in the direction
    /// `to_centre` at `centre_distance` from its centre.
    fn sample_cone(
        &self,
        (to_centre, centre_distance): (Vec3, f32),
        cone: Cone,
        u: Vec2,
        lambda: &Wavelengths,
    ) -> LightSample {
        let local = square_to_cone(u, cone.one_minus_cos);
        let (t, b) = basis(to_centre);
        let wi = (t * local.x + b * local.y + to_centre * local.z).normalize();
        let along = centre_distance * local.z;
        let chord = self.radius * self.radius - centre_distance * centre_distance * (1.0 - local.z * local.z);
        let solid_angle = cone.solid_angle();
        LightSample {
            wi,
            distance: along - chord.max(0.0).sqrt(),
            radiance_over_pdf: self.radiance(-wi, lambda) * solid_angle,
            pdf: 1.0 / solid_angle,
        }
    }

    /// Soft Falloff's factor on the light the sphere sends to `p` (1 without Soft Falloff).
    pub fn receiver_factor(&self, p: Vec3) -> f32 {
        self.photon_falloff().map_or(1.0, |soft| soft.at(p))
    }

    /// The density with which [`SphereLight::sample_surface`] from `receiver` picks the point
    /// `q` of the sphere, per area of the sphere (0 from inside it or for a point).
    pub fn surface_density(&self, receiver: Vec3, q: Vec3) -> f32 {
        let Some(cone) = self.seen_from(receiver.distance(self.position)) else { return 0.0 };
        let offset = receiver - q;
        let distance2 = offset.length_squared();
        let cos = self.normal_at(q).dot(offset) / distance2.sqrt();
        if cos > 0.0 {
            cos / (distance2 * cone.solid_angle())
        } else {
            0.0
        }
    }

    /// How densely [`SphereLight::emit_photon`] starts a photon at the point `q` of the sphere
    /// (per area) travelling along the unit `direction` (per solid angle), and the cosine there
    /// between the sphere's normal and `direction`; `None` where it does not emit that way.
    pub fn surface_emission(&self, q: Vec3, direction: Vec3) -> Option<(f32, f32)> {
        let (axis, cone) = self.cone();
        let cos = self.normal_at(q).dot(direction);
        let inside = cone.contains(axis, direction) && cos > 0.0;
        inside.then(|| (cos / (PI * self.radius * self.radius * cone.solid_angle()), cos))
    }

    /// The sphere's outward unit normal at its point `q`.
    pub fn normal_at(&self, q: Vec3) -> Vec3 {
        (q - self.position).normalize_or_zero()
    }

    /// The density per solid angle of the direction `wi` toward a point `distance` away on the
    /// disc facing a point in the direction `to_centre` from it (uniform over the disc's area).
    fn disc_pdf(&self, to_centre: Vec3, wi: Vec3, distance: f32) -> f32 {
        let cos_light = to_centre.dot(wi);
        distance * distance / (PI * self.radius * self.radius * cos_light)
    }

    /// The density per solid angle with which [`SphereLight::sample_incident`] picks the
    /// direction `wi` from `p` that meets the light at `q`; zero for a point.
    pub fn pdf_incident(&self, p: Vec3, wi: Vec3, q: Vec3) -> f32 {
        if self.is_disc() {
            let to_centre = (self.position - p).normalize_or_zero();
            return self.disc_pdf(to_centre, wi, p.distance(q));
        }
        self.seen_from(p.distance(self.position)).map_or(0.0, |cone| 1.0 / cone.solid_angle())
    }

    /// The radiance its surface sends along the unit `direction`.
    pub fn radiance(&self, direction: Vec3, lambda: &Wavelengths) -> SampledSpectrum {
        self.intensity.eval(lambda) * (self.falloff(direction) / (PI * self.radius * self.radius))
    }

    /// The distance along the ray from `origin` along the unit `direction` to where it meets the
    /// sphere from outside (or the disc facing `origin`), if it does before `t_max`.
    pub fn hit(&self, origin: Vec3, direction: Vec3, t_max: f32) -> Option<f32> {
        if self.is_disc() {
            let to_centre = self.position - origin;
            let normal = -to_centre.normalize_or_zero();
            let t = to_centre.dot(normal) / direction.dot(normal);
            let inside = (origin + direction * t).distance_squared(self.position) < self.radius * self.radius;
            return (t > 0.0 && t < t_max && inside).then_some(t);
        }
        self.surface_hit(origin, direction, t_max)
    }

    /// The distance along the ray from `origin` along the unit `direction` to where it meets the
    /// sphere itself from outside (Soft Falloff or not), if it does before `t_max`.
    pub fn surface_hit(&self, origin: Vec3, direction: Vec3, t_max: f32) -> Option<f32> {
        let to_centre = self.position - origin;
        let r2 = self.radius * self.radius;
        let along = to_centre.dot(direction);
        let gap2 = (to_centre - direction * along).length_squared();
        if self.radius <= 0.0 || along <= 0.0 || gap2 >= r2 || to_centre.length_squared() <= r2 {
            return None;
        }
        let t = along - (r2 - gap2).sqrt();
        (t < t_max).then_some(t)
    }

    /// Samples a photon leaving the light: a direction within its cone, starting on the sphere's
    /// surface at a uniform point of the disc it shows that way (the sphere emits the same
    /// intensity every way, from its projected disc).
    pub fn emit_photon(&self, u_position: Vec2, u_direction: Vec2, lambda: &Wavelengths) -> EmittedPhoton {
        let (axis, cone) = self.cone();
        let (t, b) = basis(axis);
        let local = square_to_cone(u_direction, cone.one_minus_cos);
        let direction = (t * local.x + b * local.y + axis * local.z).normalize();
        let falloff = self.falloff(direction);
        EmittedPhoton {
            origin: self.position + self.point_facing(direction, u_position),
            direction,
            flux: self.intensity.eval(lambda) * (falloff * cone.solid_angle()),
        }
    }

    /// Where on the sphere, about its centre, a photon leaving along `direction` starts.
    fn point_facing(&self, direction: Vec3, u: Vec2) -> Vec3 {
        if self.radius <= 0.0 {
            return Vec3::ZERO;
        }
        let (t, b) = basis(direction);
        let d = square_to_disc(u);
        self.radius * (t * d.x + b * d.y + direction * (1.0 - d.length_squared()).max(0.0).sqrt())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blenders_spot_blend_is_a_smoothstep_over_the_cones_last_share() {
        let outer = Cone::from_half_angle(0.6);
        let blender = SpotFalloff::Blender { blend: 0.5 };
        let at = |share: f32| spot_falloff(outer.one_minus_cos * share, blender, outer);
        assert_eq!(at(1.01), 0.0);
        assert_eq!(at(0.4), 1.0);
        // Halfway through the blended last half of 1 - cos: smoothstep(0.5) = 0.5; a quarter: 0.15625.
        assert!((at(0.75) - 0.5).abs() < 1e-5, "{}", at(0.75));
        assert!((at(0.875) - 0.15625).abs() < 1e-5, "{}", at(0.875));
        assert_eq!(spot_falloff(outer.one_minus_cos * 0.99, SpotFalloff::Blender { blend: 0.0 }, outer), 1.0);
    }

    fn ball(radius: f32) -> SphereLight {
        SphereLight {
            position: Vec3::new(0.0, 0.0, 3.0),
            intensity: Illuminant::d65(Vec3::ONE),
            radius,
            beam: None,
            seen_by_camera: true,
            soft_falloff: false,
        }
    }

    /// The irradiance at the origin, on a plane facing the light (+z), from `n * n` samples,
    /// checking that each sample's direction meets the light where it says, with the density
    /// `pdf_incident` gives.
    fn irradiance(light: &SphereLight, n: usize) -> f32 {
        let lambda = Wavelengths::single(555.0, 1.0);
        let mut irradiance = 0.0;
        for i in 0..n * n {
            let u = Vec2::new(((i % n) as f32 + 0.5) / n as f32, ((i / n) as f32 + 0.5) / n as f32);
            let s = light.sample_incident(Vec3::ZERO, u, &lambda).unwrap();
            irradiance += s.radiance_over_pdf.x * s.wi.z / (n * n) as f32;
            if light.radius > 0.0 {
                let t = light.hit(Vec3::ZERO, s.wi, f32::INFINITY).unwrap();
                assert!((t - s.distance).abs() < 1e-3 * s.distance, "{t} vs {}", s.distance);
                let pdf = light.pdf_incident(Vec3::ZERO, s.wi, s.wi * t);
                assert!((s.pdf - pdf).abs() < 1e-3 * s.pdf, "{} vs {pdf}", s.pdf);
            }
        }
        irradiance / crate::spectrum::d65(555.0)
    }

    #[test]
    fn a_sphere_lights_a_point_outside_it_as_a_point_of_its_intensity_does() {
        // Irradiance from a uniform sphere on a plane facing it is I / d^2 (Nusselt), whatever its
        // radius; the samples' directions all meet the sphere at the distance they report.
        for radius in [0.0, 0.5, 2.0] {
            let e = irradiance(&ball(radius), 200);
            assert!((e * 9.0 - 1.0).abs() < 2e-3, "radius {radius}: {e} vs 1 / 9");
        }
    }

    #[test]
    fn with_soft_falloff_a_light_is_a_disc_facing_what_it_lights() {
        // A disc of radiance I / (pi r^2) facing the point: irradiance I / (d^2 + r^2).
        for radius in [0.5, 2.0] {
            let light = SphereLight { soft_falloff: true, ..ball(radius) };
            let e = irradiance(&light, 200);
            let expected = 1.0 / (9.0 + radius * radius);
            assert!((e / expected - 1.0).abs() < 2e-3, "radius {radius}: {e} vs {expected}");
            let photons = light.photon_falloff().unwrap();
            assert!((photons.at(Vec3::ZERO) - 9.0 / (9.0 + radius * radius)).abs() < 1e-6);
        }
        assert!(ball(0.5).photon_falloff().is_none());
    }

    #[test]
    fn sampled_on_its_sphere_a_light_lights_as_its_disc_and_knows_the_density_of_each_point() {
        // Irradiance on a plane facing the light 3 away: I / (d^2 + r^2) with Soft Falloff (the
        // disc's), I / d^2 without; each sample's point is on the sphere, where the ray from the
        // receiver meets it, with the density per area `surface_density` gives.
        let lambda = Wavelengths::single(555.0, 1.0);
        for (soft_falloff, radius) in [(true, 0.5), (true, 2.0), (false, 1.0)] {
            let light = SphereLight { soft_falloff, ..ball(radius) };
            let n = 200;
            let mut irradiance = 0.0;
            for i in 0..n * n {
                let u = Vec2::new(((i % n) as f32 + 0.5) / n as f32, ((i / n) as f32 + 0.5) / n as f32);
                let s = light.sample_surface(Vec3::ZERO, u, &lambda).unwrap();
                irradiance += s.radiance_over_pdf.x * s.wi.z / (n * n) as f32;
                let q = s.wi * s.distance;
                assert!((q.distance(light.position) - radius).abs() < 1e-4 * radius, "{q} is off the sphere");
                assert_eq!(
                    light.surface_hit(Vec3::ZERO, s.wi, f32::INFINITY).map(|t| (t - s.distance).abs() < 1e-4),
                    Some(true)
                );
                let cos = (q - light.position).normalize().dot(-s.wi);
                let area = light.surface_density(Vec3::ZERO, q);
                assert!((area - s.pdf * cos / (s.distance * s.distance)).abs() < 1e-3 * area, "{area}");
            }
            let expected = if soft_falloff { 1.0 / (9.0 + radius * radius) } else { 1.0 / 9.0 };
            let e = irradiance / crate::spectrum::d65(555.0);
            assert!((e / expected - 1.0).abs() < 2e-3, "radius {radius}: {e} vs {expected}");
        }
        assert!(ball(1.0).sample_surface(Vec3::new(0.0, 0.0, 2.5), Vec2::splat(0.5), &lambda).is_none());
    }

    #[test]
    fn a_photons_start_has_the_density_the_light_says() {
        // The emission density per area and solid angle checked against the photons' own
        // distribution: E[cos^2 / density] over photons is the integral of cos^2 over the pairs
        // of a point of the sphere and a direction it faces, 4 pi r^2 * 2 pi / 3.
        let light = ball(0.5);
        let lambda = Wavelengths::single(555.0, 1.0);
        let n = 300;
        let mut measure = 0.0f64;
        for i in 0..n * n {
            let a = Vec2::new(((i % n) as f32 + 0.5) / n as f32, ((i / n) as f32 + 0.5) / n as f32);
            let b =
                Vec2::new(((i * 7 % n) as f32 + 0.5) / n as f32, ((i * 13 / n % n) as f32 + 0.5) / n as f32);
            let photon = light.emit_photon(a, b, &lambda);
            if let Some((density, cos)) = light.surface_emission(photon.origin, photon.direction) {
                assert!(cos > 0.0 && cos <= 1.0 + 1e-5);
                measure += f64::from(cos * cos / density) / (n * n) as f64;
            }
        }
        let expected = 4.0 * std::f64::consts::PI * 0.25 * 2.0 * std::f64::consts::PI / 3.0;
        assert!((measure / expected - 1.0).abs() < 0.02, "{measure} vs {expected}");
    }

    #[test]
    fn rays_meet_the_sphere_only_from_outside_and_before_their_end() {
        let light = ball(1.0);
        assert_eq!(light.hit(Vec3::ZERO, Vec3::Z, f32::INFINITY), Some(2.0));
        assert_eq!(light.hit(Vec3::ZERO, Vec3::Z, 1.5), None);
        assert_eq!(light.hit(Vec3::ZERO, -Vec3::Z, f32::INFINITY), None);
        assert_eq!(light.hit(Vec3::new(0.0, 0.0, 3.5), Vec3::Z, f32::INFINITY), None);
        assert_eq!(light.hit(Vec3::new(1.5, 0.0, 0.0), Vec3::Z, f32::INFINITY), None);
        assert_eq!(ball(0.0).hit(Vec3::ZERO, Vec3::Z, f32::INFINITY), None);
        let disc = SphereLight { soft_falloff: true, ..ball(1.0) };
        assert_eq!(disc.hit(Vec3::ZERO, Vec3::Z, f32::INFINITY), Some(3.0));
        assert_eq!(disc.hit(Vec3::ZERO, -Vec3::Z, f32::INFINITY), None);
    }
}
