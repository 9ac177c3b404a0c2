//! Lights: `KHR_lights_punctual` with the extras' sizes and spreads, emissive meshes as area
//! lights, and the world.

use std::path::Path;

use super::checks;
use crate::scene::values::{LightAnimation, MaterialAnimation};

use super::{Builder, LUMENS_PER_WATT};
use glam::{Vec2, Vec3};
use gltf::khr_lights_punctual::Kind;

use crate::geometry::Cone;
use crate::lights::{Beam, SphereLight, SpotFalloff, World};
use crate::materials::{BaseColour, Material, Spread};
use crate::scene::animation::Rig;
use crate::scene::description::{MeshInstance, PunctualKind, PunctualLight};
use crate::scene::extras::{self, NodeExtras};
use crate::scene::{shapes, TriangleRef};
use crate::spectrum::{Illuminant, RgbSpectrum};

/// The world from the scene extras; an image path is relative to the glTF file's folder. An image
/// that cannot be read is a magenta world, as Cycles shows a missing environment image, and a
/// warning says why.
pub(super) fn world(
    w: &extras::WorldExtras,
    gltf_path: &Path,
    warnings: &mut Vec<String>,
) -> Result<World, String> {
    match &w.image {
        Some(image) => {
            checks::check_relative(image)
                .map_err(|why| format!("scene extras `caustic.world.image` '{image}': {why}"))?;
            let path = gltf_path.parent().unwrap_or(Path::new(".")).join(image);
            Ok(World::from_image(&path, w.strength, w.rotation_deg).unwrap_or_else(|e| {
                warnings.push(format!(
                    "the world's image (scene extras `caustic.world.image`): {e}; the world is rendered \
                     magenta, as Cycles renders a missing image"
                ));
                World::uniform(Vec3::new(1.0, 0.0, 1.0) * w.strength)
            }))
        }
        None => Ok(World::uniform(Vec3::from(w.color) * w.strength)),
    }
}

/// The area of `local` triangles on `node` at the scene's rest pose (at least the smallest
/// positive number, to divide by).
pub(super) fn world_area(local: &[[Vec3; 3]], rig: &Rig, node: usize) -> f32 {
    let world = rig.world(node, 0.0);
    let area: f32 = local
        .iter()
        .map(|t| t.map(|v| world.transform_point3(v)))
        .map(|[a, b, c]| (b - a).cross(c - a).length() / 2.0)
        .sum();
    area.max(f32::MIN_POSITIVE)
}

/// The colour temperature of a light from the node's extras (its light is then a black body's
/// spectrum, [`Illuminant::blackbody`]), or `None` (white is D65).
pub(super) fn light_temperature(extras: &NodeExtras, name: &str) -> Result<Option<f32>, String> {
    match extras.temperature_k {
        None => Ok(None),
        Some(t) if t.is_finite() && t >= 100.0 => Ok(Some(t)),
        Some(t) => Err(format!(
            "node '{name}' extras `caustic.temperature_k`: expected a temperature of 100 K or more, got {t}"
        )),
    }
}

/// Blender's sun angle is the full angular diameter; without one the sun is a delta light.
pub(super) fn sun_disc(extras: &NodeExtras) -> Cone {
    extras.sun_angle_deg.map_or(Cone::default(), |deg| Cone::from_half_angle(deg.to_radians() / 2.0))
}

impl Builder<'_> {
    /// A `KHR_lights_punctual` light, a black body's of `kelvin` if given.
    pub(super) fn add_punctual_light(
        &mut self,
        light: &gltf::khr_lights_punctual::Light,
        node: usize,
        extras: &NodeExtras,
        kelvin: Option<f32>,
    ) {
        let colour = Vec3::from(light.color()) * light.intensity() / LUMENS_PER_WATT;
        let spectrum = Illuminant::new(colour, kelvin);
        let sphere = |beam| {
            PunctualKind::Sphere(SphereLight {
                position: Vec3::ZERO,
                intensity: spectrum,
                radius: extras.radius.unwrap_or(0.0),
                beam,
                seen_by_camera: extras.visible_to_camera.unwrap_or(true),
                soft_falloff: extras.soft_falloff,
            })
        };
        let kind = match light.kind() {
            Kind::Point => sphere(None),
            Kind::Spot { inner_cone_angle, outer_cone_angle } => {
                let falloff = match extras.spot_blend {
                    Some(blend) => SpotFalloff::Blender { blend },
                    None => SpotFalloff::Gltf { inner: Cone::from_half_angle(inner_cone_angle) },
                };
                sphere(Some(Beam { axis: -Vec3::Z, falloff, outer: Cone::from_half_angle(outer_cone_angle) }))
            }
            Kind::Directional => PunctualKind::Sun(spectrum, sun_disc(extras)),
        };
        let animation = self.animations.lights.get(&light.index()).map(|tracks| {
            Box::new(LightAnimation {
                colour: Vec3::from(light.color()),
                intensity: light.intensity(),
                per_unit: 1.0 / LUMENS_PER_WATT,
                kelvin,
                tracks: tracks.clone(),
            })
        });
        self.lights.push(PunctualLight { node, kind, animation });
    }

    /// An area light becomes one-sided emitting triangles with radiance P / (pi A), A its area
    /// at the scene's rest pose, that every ray passes through unchanged, as Blender's lights do: they cast no shadow and hide nothing behind them.
    pub(super) fn add_area_light(
        &mut self,
        extras: &NodeExtras,
        node: usize,
        name: &str,
        rig: &Rig,
    ) -> Result<(), String> {
        let Some(area) = &extras.area_light else {
            return Ok(());
        };
        if !(area.size > 0.0 && area.power >= 0.0 && area.size.is_finite() && area.power.is_finite()) {
            return Err(format!("node '{name}' area light: size must be positive and power non-negative"));
        }
        let spread = area.spread_deg.unwrap_or(180.0);
        if !(0.0..=180.0).contains(&spread) {
            return Err(format!(
                "node '{name}' area light: expected a spread_deg from 0 to 180, got {spread}"
            ));
        }
        let local = shapes::area_light_triangles(area);
        let area_m2 = world_area(&local, rig, node);
        let per_unit = 1.0 / (std::f32::consts::PI * area_m2);
        let colour = Vec3::from(area.color) * area.power * per_unit;
        if let Some(tracks) = self.animations.area_lights.get(&node) {
            let animation = MaterialAnimation {
                emissive: Vec3::from(area.color),
                strength: area.power,
                per_unit,
                kelvin: light_temperature(extras, name)?,
                tracks: tracks.clone(),
            };
            self.material_animations.push((self.materials.len(), animation));
        }
        let material = Material {
            name: format!("area light '{name}'"),
            base_colour: BaseColour::Constant(RgbSpectrum::constant(0.0)),
            emission: Some(Illuminant::new(colour, light_temperature(extras, name)?)),
            emits_both_sides: false,
            emission_spread: Spread::new(spread.to_radians()),
            light_surface: true,
            seen_by_camera: extras.visible_to_camera.unwrap_or(true),
            ..Material::default_grey()
        };
        self.add_light_mesh(node, material, &local);
        Ok(())
    }

    /// The triangles `local` on `node` emitting from their front faces with `material`.
    pub(super) fn add_light_mesh(&mut self, node: usize, material: Material, local: &[[Vec3; 3]]) {
        let name = material.name.clone();
        self.materials.push(material);
        let material = self.materials.len() as u32 - 1;
        let normals = vec![-Vec3::Z; 3 * local.len()];
        let positions: Vec<Vec3> = local.iter().flatten().copied().collect();
        let triangles = (0..local.len() as u32)
            .map(|k| TriangleRef { vertices: [3 * k, 3 * k + 1, 3 * k + 2], material })
            .collect();
        self.meshes.push(MeshInstance {
            node,
            name,
            normals,
            uvs: vec![Vec2::ZERO; positions.len()],
            extras: Default::default(),
            positions,
            triangles,
            deformation: None,
        });
    }
}
