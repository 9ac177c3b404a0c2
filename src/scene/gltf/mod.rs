//! glTF 2.0 as Blender 5.0's exporter writes it, plus the `caustic` extras, into a
//! [`Description`]: meshes in their nodes' local space with their skins and morph targets, and
//! the node rig with its animation (translation, rotation, scale and morph target weights), and
//! the animated values of lights, materials and the camera (`KHR_animation_pointer`, which the
//! gltf crate cannot read, is taken out of the JSON first: [`super::super::pointers`]).
//!
//! Reads the default scene's node tree (nested transforms), triangle meshes with normals,
//! texture coordinates (sets 0 and 1), vertex colours and tangents (generated where a normal map
//! needs them), metallic-roughness materials ([`materials`]) with `KHR_materials_transmission`,
//! `KHR_materials_ior` (absent means 1.5) and `KHR_materials_emissive_strength`,
//! `KHR_materials_dispersion`, `KHR_lights_punctual`, the perspective camera the scene names (else the first), and the
//! extras schema in [`super::super::extras`].

mod cameras;
pub(super) mod checks;
mod holdouts;
mod instances;
mod lights;
mod materials;
mod meshes;
mod rigs;
mod textures;
pub(super) mod unrendered;

use std::path::Path;

use std::sync::Arc;

use crate::scene::deform::Skin;
use crate::scene::instancing::InstancedMesh;
use crate::scene::pointers::{self, Animations};
use crate::scene::values::MaterialAnimation;

use cameras::shutter;
use glam::Vec3;
use gltf::khr_lights_punctual::Kind;
use lights::{light_temperature, world};
use rigs::rig;

use crate::materials::Material;
use crate::scene::animation::Rig;
use crate::scene::description::{CameraInstance, Description, MeshInstance, PunctualLight};
use crate::scene::extras::{self, NodeExtras, SceneExtras};
use crate::scene::SceneError;
use materials::material;
use textures::Images;

/// glTF photometric units to watts: Blender writes W * 683 / (4 pi) candela and W/m^2 * 683 lux.
const LUMENS_PER_WATT: f32 = 683.0;

/// What the node walk gathers before the description is assembled.
struct Builder<'a> {
    document: &'a gltf::Document,
    buffers: &'a [gltf::buffer::Data],
    materials: Vec<Material>,
    meshes: Vec<MeshInstance>,
    lights: Vec<PunctualLight>,
    camera: Option<CameraInstance>,
    /// The camera node the scene names, if it names one.
    wanted_camera: Option<String>,
    warnings: Vec<String>,
    material_offset: u32,
    /// The thin-wall copy of each transmissive material that open meshes use.
    thin_materials: std::collections::HashMap<u32, u32>,
    /// The holdout copy of each material that has one.
    holdout_materials: std::collections::HashMap<u32, u32>,
    /// The skins read so far, by index.
    skins: std::collections::HashMap<usize, Arc<Skin>>,
    /// Animated values, by what they animate.
    animations: &'a Animations,
    /// The animated materials so far, by index.
    material_animations: Vec<(usize, MaterialAnimation)>,
    /// The meshes of still nodes' instances, kept once.
    instanced: Vec<InstancedMesh>,
}

/// Loads `path` into a [`Description`].
pub fn load(path: &Path) -> Result<Description, SceneError> {
    let fail = |message: String| SceneError { path: path.to_path_buf(), message };
    if !path.exists() {
        return Err(fail("no such file".into()));
    }
    // The references are checked before anything they name is read, and the mesh accessor
    // indices before the gltf crate validates the file (its validation indexes them unchecked).
    let bytes = std::fs::read(path).map_err(|e| fail(format!("cannot read the file: {e}")))?;
    // The pointer channels go before the gltf crate reads the file (it cannot parse them), and
    // accessors without data get zeros (it refuses them).
    let (bytes, pointer_channels) = pointers::prepare(&bytes).map_err(fail)?;
    let unchecked = gltf::Gltf::from_slice_without_validation(&bytes)
        .map_err(|e| fail(checks::describe_import_error(e)))?;
    checks::check_indices(unchecked.document.as_json()).map_err(fail)?;
    let gltf::Gltf { document, blob } =
        gltf::Gltf::from_slice(&bytes).map_err(|e| fail(checks::describe_import_error(e)))?;
    checks::check_references(&document).map_err(fail)?;
    let base = path.parent().unwrap_or(Path::new("."));
    let buffers = gltf::import_buffers(&document, Some(base), blob)
        .map_err(|e| fail(checks::describe_import_error(e)))?;
    let mut image_warnings = Vec::new();
    let images = Images::load(&document, base, &buffers, &mut image_warnings).map_err(fail)?;
    checks::check_accessors(&document, &buffers).map_err(fail)?;
    let gltf_scene = document
        .default_scene()
        .or_else(|| document.scenes().next())
        .ok_or_else(|| fail("the file has no scene".into()))?;
    let scene_extras: SceneExtras =
        extras::parse(gltf_scene.extras()).map_err(|e| fail(format!("scene extras `caustic`: {e}")))?;
    let mut materials: Vec<Material> = document
        .materials()
        .map(|m| material(&m, &document, &images))
        .collect::<Result<_, _>>()
        .map_err(fail)?;
    let material_offset = materials.len() as u32;
    materials.push(Material::default_grey());
    let animations =
        pointers::read(&document, &buffers, &pointer_channels, &scene_extras.tracks).map_err(fail)?;
    let mut rig_warnings = Vec::new();
    let rig = rig(&document, &buffers, &animations.nodes, &mut rig_warnings).map_err(fail)?;
    let mut unrendered: Vec<String> = document
        .materials()
        .zip(&materials)
        .flat_map(|(m, loaded)| unrendered::material_warnings(&m, loaded))
        .collect();
    unrendered.extend(animations.warnings.iter().cloned());
    unrendered.extend(image_warnings);
    unrendered.extend(rig_warnings);
    let mut builder = Builder {
        document: &document,
        buffers: &buffers,
        materials,
        meshes: Vec::new(),
        lights: Vec::new(),
        camera: None,
        wanted_camera: scene_extras.camera.clone(),
        warnings: unrendered,
        material_offset,
        thin_materials: Default::default(),
        holdout_materials: Default::default(),
        skins: Default::default(),
        animations: &animations,
        material_animations: gltf_material_animations(&document, &animations),
        instanced: Vec::new(),
    };
    for node in gltf_scene.nodes() {
        builder.visit(&node, &rig).map_err(fail)?;
    }
    let world = scene_extras
        .world
        .as_ref()
        .map(|w| world(w, path, &mut builder.warnings))
        .transpose()
        .map_err(fail)?;
    let fog = scene_extras
        .fog
        .as_ref()
        .map(|fog| materials::medium(fog).map_err(|e| fail(format!("scene extras `caustic.fog.{e}"))))
        .transpose()?;
    let material_animations = builder.material_animations_with_copies();
    let camera = builder.camera.ok_or_else(|| {
        fail(match &scene_extras.camera {
            Some(name) => format!("scene extras `caustic.camera` names node '{name}', which is not a camera"),
            None => "the scene has no camera: add a perspective camera".into(),
        })
    })?;
    let fps = scene_extras.fps.unwrap_or(24.0);
    if !(fps > 0.0 && fps.is_finite()) {
        return Err(fail(format!("scene extras `caustic.fps`: expected a positive frame rate, got {fps}")));
    }
    let shutter = shutter(scene_extras.shutter.as_ref()).map_err(fail)?;
    let mut description = Description {
        rig,
        meshes: builder.meshes,
        instanced: builder.instanced,
        lights: builder.lights,
        camera,
        material_animations,
        materials: builder.materials,
        world,
        fog,
        resolution: scene_extras.resolution,
        transparent_film: scene_extras.transparent_film,
        fps,
        shutter,
        warnings: unique(builder.warnings),
    };
    if description
        .meshes
        .iter()
        .all(|m| m.triangles.iter().all(|t| description.materials[t.material as usize].emission.is_none()))
        && description.lights.is_empty()
        && description.world.is_none()
    {
        description.warnings.push("the scene has no light: the image will be black".into());
    }
    Ok(description)
}

/// The animations of the file's materials, each with its emission at rest.
fn gltf_material_animations(
    document: &gltf::Document,
    animations: &Animations,
) -> Vec<(usize, MaterialAnimation)> {
    let mut list: Vec<(usize, MaterialAnimation)> = animations
        .materials
        .iter()
        .filter_map(|(&index, tracks)| {
            let m = document.materials().nth(index)?;
            let emissive = Vec3::from(m.emissive_factor());
            let animation = MaterialAnimation::gltf(emissive, m.emissive_strength().unwrap_or(1.0));
            Some((index, MaterialAnimation { tracks: tracks.clone(), ..animation }))
        })
        .collect();
    list.sort_by_key(|(index, _)| *index);
    list
}

/// `lines` without repeats (a mesh drawn by several nodes warns once), in their first order.
fn unique(lines: Vec<String>) -> Vec<String> {
    let mut seen = std::collections::HashSet::new();
    lines.into_iter().filter(|line| seen.insert(line.clone())).collect()
}

impl Builder<'_> {
    /// Adds a node and its children.
    fn visit(&mut self, node: &gltf::Node, rig: &Rig) -> Result<(), String> {
        let name = node.name().unwrap_or("unnamed");
        let extras: NodeExtras =
            extras::parse(node.extras()).map_err(|e| format!("node '{name}' extras `caustic`: {e}"))?;
        if let Some(mesh) = node.mesh() {
            let first_instance = self.meshes.len();
            self.add_mesh(&mesh, node, rig, extras.holdout)?;
            if extras.holdout {
                self.hold_out(first_instance);
            }
        }
        if let Some(camera) = node.camera() {
            self.add_camera(Some(&camera), node.index(), name, &extras)?;
        } else if extras.panorama.is_some() {
            self.add_camera(None, node.index(), name, &extras)?;
        }
        let kelvin = light_temperature(&extras, name)?;
        if let Some(blend) = extras.spot_blend.filter(|b| !(0.0..=1.0).contains(b)) {
            return Err(format!(
                "node '{name}' extras `caustic.spot_blend`: expected a blend from 0 to 1, got {blend}"
            ));
        }
        if let Some(light) = node.light() {
            match (light.kind(), extras.radius) {
                (_, Some(radius)) if !(radius >= 0.0 && radius.is_finite()) => {
                    return Err(format!(
                        "node '{name}' extras `caustic.radius`: expected a light radius of 0 or more, got {radius}"
                    ));
                }
                (Kind::Directional, Some(radius)) if radius > 0.0 => {
                    self.warnings.push(format!(
                        "node '{name}': a radius is rendered for point and spot lights only; this sun ignores it"
                    ));
                    self.add_punctual_light(&light, node.index(), &extras, kelvin);
                }
                _ => self.add_punctual_light(&light, node.index(), &extras, kelvin),
            }
        }
        self.add_area_light(&extras, node.index(), name, rig)?;
        for child in node.children() {
            self.visit(&child, rig)?;
        }
        Ok(())
    }
}
