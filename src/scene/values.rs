//! Animated values other than node transforms: a light's colour, intensity and cone, a
//! material's colour, emission and factors, an area light's power, a camera's field of view. Each
//! object keeps its value at rest and the tracks that change it (from `KHR_animation_pointer` or
//! the `caustic.tracks` extras: [`super::pointers`]); posing at a time rebuilds only what a track
//! sets, so an object without tracks pays nothing.

use glam::{Vec3, Vec4};

use super::animation::Track;
use crate::camera::Projection;
use crate::geometry::Cone;
use crate::materials::{BaseColour, Material};
use crate::spectrum::{Illuminant, RgbSpectrum};

/// Tracks on the properties `P` of one object.
#[derive(Clone, Debug)]
pub struct Tracks<P> {
    tracks: Vec<(P, Track)>,
}

impl<P> Default for Tracks<P> {
    fn default() -> Self {
        Tracks { tracks: Vec::new() }
    }
}

impl<P: PartialEq + Copy> Tracks<P> {
    /// Adds (or replaces) the track on `property`.
    pub fn set(&mut self, property: P, track: Track) {
        self.tracks.retain(|(p, _)| *p != property);
        self.tracks.push((property, track));
    }

    /// The value of `property` at `time`, if a track sets it.
    pub fn at(&self, property: P, time: f32) -> Option<Vec4> {
        self.tracks.iter().find(|(p, _)| *p == property).map(|(_, t)| t.sample(time))
    }

    /// The largest key value of `property`, component by component, if a track sets it.
    pub fn peak(&self, property: P) -> Option<Vec4> {
        self.tracks.iter().find(|(p, _)| *p == property).map(|(_, t)| t.peak())
    }

    /// Whether any value changes within [t0, t1].
    pub fn vary_within(&self, t0: f32, t1: f32) -> bool {
        self.tracks.iter().any(|(_, t)| t.varies_within(t0, t1))
    }

    /// The properties the tracks set.
    pub fn properties(&self) -> Vec<P> {
        self.tracks.iter().map(|(p, _)| *p).collect()
    }
}

/// What a track sets on a punctual light (glTF's `KHR_lights_punctual` properties).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum LightProperty {
    /// Linear RGB colour.
    Colour,
    /// Candela (point, spot) or lux (sun), as glTF writes them.
    Intensity,
    /// A spot's outer cone half-angle, radians.
    OuterCone,
    /// A spot's inner cone half-angle, radians (glTF's falloff only).
    InnerCone,
}

/// A punctual light's animation: its values at rest and the tracks that change them.
#[derive(Clone, Debug)]
pub struct LightAnimation {
    /// Colour at rest.
    pub colour: Vec3,
    /// Intensity at rest, in glTF's units.
    pub intensity: f32,
    /// What converts colour times intensity into W/sr (or W/m^2 for a sun).
    pub per_unit: f32,
    /// The black body's temperature, if the light has one.
    pub kelvin: Option<f32>,
    /// The tracks.
    pub tracks: Tracks<LightProperty>,
}

/// A punctual light's values at one time (or at its peak).
#[derive(Clone, Copy, Debug)]
pub struct LightValues {
    /// What it emits (W/sr, or W/m^2 for a sun).
    pub emitted: Illuminant,
    /// A spot's outer cone, if animated.
    pub outer: Option<Cone>,
    /// A spot's inner cone (glTF's falloff), if animated.
    pub inner: Option<Cone>,
}

impl LightAnimation {
    /// The light's values at `time`.
    pub fn at(&self, time: f32) -> LightValues {
        self.values(|p| self.tracks.at(p, time))
    }

    /// The light's values with every animated one at its largest key (each colour component at
    /// its own): a light at least as strong as at any time, whose power chooses it for photons
    /// the same way whatever frames a render covers.
    pub fn peak(&self) -> LightValues {
        self.values(|p| self.tracks.peak(p))
    }

    /// The values `value` gives (the values at rest where it gives none).
    fn values(&self, value: impl Fn(LightProperty) -> Option<Vec4>) -> LightValues {
        let colour = value(LightProperty::Colour).map_or(self.colour, Vec4::truncate);
        let intensity = value(LightProperty::Intensity).map_or(self.intensity, |v| v.x);
        let cone = |p| value(p).map(|v: Vec4| Cone::from_half_angle(v.x));
        LightValues {
            emitted: Illuminant::new(
                colour.max(Vec3::ZERO) * intensity.max(0.0) * self.per_unit,
                self.kelvin,
            ),
            outer: cone(LightProperty::OuterCone),
            inner: cone(LightProperty::InnerCone),
        }
    }
}

/// What a track sets on a material.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum MaterialProperty {
    /// The base colour factor (RGB; its alpha is not animated).
    BaseColour,
    /// The emissive factor (RGB).
    Emissive,
    /// `KHR_materials_emissive_strength`, or an area light's power in watts.
    EmissiveStrength,
    /// The metallic factor.
    Metallic,
    /// The roughness factor.
    Roughness,
    /// `KHR_materials_transmission`'s factor.
    Transmission,
}

/// A material's animation: its emission at rest and the tracks that change it.
#[derive(Clone, Debug)]
pub struct MaterialAnimation {
    /// The emissive colour at rest.
    pub emissive: Vec3,
    /// The emission's strength at rest (an area light's power).
    pub strength: f32,
    /// What converts colour times strength into radiance (1 for glTF's emission; 1 / (pi A) for
    /// an area light of area A).
    pub per_unit: f32,
    /// The black body's temperature, if the emission has one.
    pub kelvin: Option<f32>,
    /// The tracks.
    pub tracks: Tracks<MaterialProperty>,
}

impl MaterialAnimation {
    /// An animation of a glTF material whose emission at rest is `emissive` times `strength`.
    pub fn gltf(emissive: Vec3, strength: f32) -> Self {
        MaterialAnimation { emissive, strength, per_unit: 1.0, kelvin: None, tracks: Tracks::default() }
    }

    /// Whether the material may emit at some time (so its triangles may be lights).
    pub fn may_emit(&self) -> bool {
        let sets = |p| self.tracks.tracks.iter().any(|(q, _)| *q == p);
        sets(MaterialProperty::Emissive) || sets(MaterialProperty::EmissiveStrength)
    }

    /// `material` with the animated values at `time`.
    pub fn apply(&self, material: &mut Material, time: f32) {
        self.set(material, |p| self.tracks.at(p, time));
    }

    /// `material` emitting as it does at its largest keys (see [`LightAnimation::peak`]).
    pub fn peak(&self, material: &mut Material) {
        self.set(material, |p| self.tracks.peak(p));
    }

    /// `material` with the values `value` gives (the values at rest where it gives none).
    fn set(&self, material: &mut Material, value: impl Fn(MaterialProperty) -> Option<Vec4>) {
        use MaterialProperty as P;
        let scalar = |p| value(p).map(|v| v.x.clamp(0.0, 1.0));
        if let Some(colour) = value(P::BaseColour) {
            if let BaseColour::Constant(_) = material.base_colour {
                let colour = colour.truncate().clamp(Vec3::ZERO, Vec3::ONE);
                material.base_colour = BaseColour::Constant(RgbSpectrum::reflectance(colour));
            }
        }
        if let Some(metallic) = scalar(P::Metallic) {
            material.metallic = metallic;
        }
        if let Some(roughness) = scalar(P::Roughness) {
            material.roughness = roughness;
        }
        if let Some(transmission) = scalar(P::Transmission) {
            material.transmission = transmission;
        }
        if self.may_emit() && material.emission_texture.is_none() {
            let colour = value(P::Emissive).map_or(self.emissive, Vec4::truncate);
            let strength = value(P::EmissiveStrength).map_or(self.strength, |v| v.x);
            // Dark or not, the material stays an emitter, so that its triangles are lights at
            // every time and light indices agree between the frames of a block.
            let radiance = colour.max(Vec3::ZERO) * strength.max(0.0) * self.per_unit;
            material.emission = Some(Illuminant::new(radiance, self.kelvin));
        }
    }
}

/// What a track sets on a camera.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum CameraProperty {
    /// A perspective camera's vertical field of view, radians.
    Yfov,
}

/// A camera's animation.
#[derive(Clone, Debug, Default)]
pub struct CameraAnimation {
    /// The tracks.
    pub tracks: Tracks<CameraProperty>,
}

impl CameraAnimation {
    /// `projection` at `time`, and the ratio of the focal length then to the focal length at rest
    /// (`rest`'s), by which the aperture of a lens of fixed f-number grows.
    pub fn projection(&self, rest: Projection, time: f32) -> (Projection, f32) {
        match (rest, self.tracks.at(CameraProperty::Yfov, time)) {
            (Projection::Perspective { tan_half_fov_y }, Some(yfov)) => {
                let tan = (yfov.x.clamp(1e-4, 3.1) / 2.0).tan();
                (Projection::Perspective { tan_half_fov_y: tan }, tan_half_fov_y / tan)
            }
            _ => (rest, 1.0),
        }
    }
}
