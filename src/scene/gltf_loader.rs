//! glTF 2.0 as Blender 5.0's exporter writes it, plus the `caustic` extras, into a
//! [`Description`]: meshes in their nodes' local space with their skins and morph targets, and
//! the node rig with its animation (translation, rotation, scale and morph target weights), and
//! the animated values of lights, materials and the camera (`KHR_animation_pointer`, which the
//! gltf crate cannot read, is taken out of the JSON first: [`super::pointers`]).
//!
//! Reads the default scene's node tree (nested transforms), triangle meshes with normals,
//! texture coordinates (sets 0 and 1), vertex colours and tangents (generated where a normal map
//! needs them), metallic-roughness materials ([`super::gltf_materials`]) with `KHR_materials_transmission`,
//! `KHR_materials_ior` (absent means 1.5) and `KHR_materials_emissive_strength`,
//! `KHR_materials_dispersion`, `KHR_lights_punctual`, the perspective camera the scene names (else the first), and the
//! extras schema in [`super::extras`].

use std::path::Path;

use std::sync::Arc;

use super::deform::{self, Deformation, Morph, MorphTarget, Skin, Skinning};
use super::instancing::{self, InstancedMesh};
use super::pointers::{self, floats, Animations, Keys, NodeProperty};
use super::pose::flatten;
use super::values::{CameraAnimation, LightAnimation, MaterialAnimation};
use super::{gltf_checks, gltf_unrendered, Geometry};

use glam::{Mat4, Quat, Vec2, Vec3, Vec4};
use gltf::animation::util::ReadOutputs;
use gltf::khr_lights_punctual::Kind;

use super::animation::{Interpolation, NodeMotion, Rig, Track};
use super::description::{
    CameraInstance, Description, LensSettings, MeshInstance, PunctualKind, PunctualLight, Shutter,
};
use super::extras::{self, NodeExtras, SceneExtras, ShutterExtras, ShutterPosition};
use super::gltf_materials::material;
use super::gltf_textures::Images;
use super::{shapes, tangents, SceneError, TriangleRef, VertexExtras};
use crate::camera::Projection;
use crate::geometry::Cone;
use crate::lights::{Beam, SphereLight, SpotFalloff, World};
use crate::materials::{BaseColour, Material, Spread};
use crate::spectrum::{Illuminant, RgbSpectrum};

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
        .map_err(|e| fail(gltf_checks::describe_import_error(e)))?;
    gltf_checks::check_indices(unchecked.document.as_json()).map_err(fail)?;
    let gltf::Gltf { document, blob } =
        gltf::Gltf::from_slice(&bytes).map_err(|e| fail(gltf_checks::describe_import_error(e)))?;
    gltf_checks::check_references(&document).map_err(fail)?;
    let base = path.parent().unwrap_or(Path::new("."));
    let buffers = gltf::import_buffers(&document, Some(base), blob)
        .map_err(|e| fail(gltf_checks::describe_import_error(e)))?;
    let mut image_warnings = Vec::new();
    let images = Images::load(&document, base, &buffers, &mut image_warnings).map_err(fail)?;
    gltf_checks::check_accessors(&document, &buffers).map_err(fail)?;
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
        .flat_map(|(m, loaded)| gltf_unrendered::material_warnings(&m, loaded))
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
        .map(|fog| {
            super::gltf_materials::medium(fog).map_err(|e| fail(format!("scene extras `caustic.fog.{e}")))
        })
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

/// The transforms of `node`'s instances within the node, if it has the extension.
fn instance_matrices(
    node: &gltf::Node,
    document: &gltf::Document,
    buffers: &[gltf::buffer::Data],
) -> Result<Option<Vec<Mat4>>, String> {
    let Some(extension) = node.extension_value(instancing::EXTENSION) else {
        return Ok(None);
    };
    let name = node.name().unwrap_or("unnamed");
    let in_node = |e: String| format!("node '{name}' {}: {e}", instancing::EXTENSION);
    let attribute = |key: &str, width: usize| -> Result<Option<Vec<f32>>, String> {
        let Some(index) = extension.pointer(&format!("/attributes/{key}")) else { return Ok(None) };
        let accessor = index
            .as_u64()
            .and_then(|i| document.accessors().nth(i as usize))
            .ok_or_else(|| in_node(format!("{key} names accessor {index}, which the file does not have")))?;
        if accessor.dimensions().multiplicity() != width {
            return Err(in_node(format!("{key} must hold {width} floats an instance")));
        }
        floats(accessor, buffers).map(Some).map_err(in_node)
    };
    let translations = attribute("TRANSLATION", 3)?;
    let rotations = attribute("ROTATION", 4)?;
    let scales = attribute("SCALE", 3)?;
    let counts: Vec<usize> = [(&translations, 3), (&rotations, 4), (&scales, 3)]
        .iter()
        .filter_map(|(values, width)| values.as_ref().map(|v| v.len() / width))
        .collect();
    let Some(&count) = counts.first() else {
        return Err(in_node("it has no TRANSLATION, ROTATION or SCALE attribute".into()));
    };
    if counts.iter().any(|&c| c != count) {
        return Err(in_node(format!("its attributes give different instance counts ({counts:?})")));
    }
    let all = [&translations, &rotations, &scales];
    if all.iter().any(|values| values.as_ref().is_some_and(|v| !v.iter().all(|x| x.is_finite()))) {
        return Err(in_node("its attributes hold values that are not finite numbers".into()));
    }
    let matrix = |k: usize| {
        let t = translations.as_ref().map_or(Vec3::ZERO, |v| Vec3::from_slice(&v[3 * k..]));
        let r = rotations.as_ref().map_or(Quat::IDENTITY, |v| Quat::from_slice(&v[4 * k..]).normalize());
        let s = scales.as_ref().map_or(Vec3::ONE, |v| Vec3::from_slice(&v[3 * k..]));
        Mat4::from_scale_rotation_translation(s, r, t)
    };
    Ok(Some((0..count).map(matrix).collect()))
}

/// `lines` without repeats (a mesh drawn by several nodes warns once), in their first order.
fn unique(lines: Vec<String>) -> Vec<String> {
    let mut seen = std::collections::HashSet::new();
    lines.into_iter().filter(|line| seen.insert(line.clone())).collect()
}

/// Every node's parent, rest transform and animation tracks.
fn rig(
    document: &gltf::Document,
    buffers: &[gltf::buffer::Data],
    pointed: &[(usize, NodeProperty, Keys)],
    warnings: &mut Vec<String>,
) -> Result<Rig, String> {
    let mut nodes: Vec<NodeMotion> = document
        .nodes()
        .map(|n| {
            let (t, r, s) = n.transform().decomposed();
            let finite = t.iter().chain(&r).chain(&s).all(|v| v.is_finite());
            finite
                .then(|| NodeMotion {
                    rest: (Vec3::from(t), Quat::from_array(r).normalize(), Vec3::from(s)),
                    ..Default::default()
                })
                .ok_or_else(|| {
                    format!(
                        "node '{}': its transform has values that are not finite numbers",
                        n.name().unwrap_or("unnamed")
                    )
                })
        })
        .collect::<Result<_, _>>()?;
    for node in document.nodes() {
        for child in node.children() {
            nodes[child.index()].parent = Some(node.index());
        }
    }
    let channels: Vec<_> = document.animations().flat_map(|a| a.channels().collect::<Vec<_>>()).collect();
    let mut keyed = Vec::new();
    for channel in &channels {
        let (property, keys) = channel_keys(channel, buffers)?;
        keyed.push((channel.target().node().index(), property, keys));
    }
    for (index, property, keys) in keyed.into_iter().chain(pointed.iter().cloned()) {
        let node = document.nodes().nth(index).expect("checked node index");
        let in_node = |e: String| format!("animation of node '{}': {e}", node.name().unwrap_or("unnamed"));
        let motion = &mut nodes[index];
        match property {
            NodeProperty::Translation => {
                motion.translation = Some(pointers::track(keys, 3).map_err(in_node)?)
            }
            NodeProperty::Scale => motion.scale = Some(pointers::track(keys, 3).map_err(in_node)?),
            NodeProperty::Rotation => {
                let track = pointers::track(keys, 4).map_err(in_node)?;
                motion.rotation = Some(Track { is_rotation: true, ..track });
            }
            NodeProperty::Weights => {
                let count = morph_target_count(&node);
                if count == 0 {
                    // Blender's exporter writes this for shape keys under modifiers it applied.
                    warnings.push(in_node(
                        "it animates morph target weights, but the node's mesh has no morph targets (shape \
                         keys dropped by modifiers applied on export?): the mesh is rendered unanimated"
                            .into(),
                    ));
                    continue;
                }
                pointers::check(&keys, count).map_err(in_node)?;
                let groups = deform::weight_groups(&keys.values, count);
                let track = |values| Track {
                    times: keys.times.clone(),
                    values,
                    interpolation: keys.interpolation,
                    is_rotation: false,
                };
                motion.weights = groups.into_iter().map(track).collect();
                motion.weight_count = count;
            }
        }
    }
    Ok(Rig { nodes })
}

/// What an animation channel sets and its keys, as floats.
fn channel_keys(
    channel: &gltf::animation::Channel,
    buffers: &[gltf::buffer::Data],
) -> Result<(NodeProperty, Keys), String> {
    let target = channel.target();
    let name = target.node().name().unwrap_or("unnamed").to_string();
    let reader = channel.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
    let times: Vec<f32> =
        reader.read_inputs().ok_or(format!("animation of node '{name}': no key times"))?.collect();
    let interpolation = match channel.sampler().interpolation() {
        gltf::animation::Interpolation::Step => Interpolation::Step,
        gltf::animation::Interpolation::Linear => Interpolation::Linear,
        gltf::animation::Interpolation::CubicSpline => Interpolation::CubicSpline,
    };
    let (property, values): (NodeProperty, Vec<f32>) = match reader.read_outputs() {
        Some(ReadOutputs::Translations(v)) => (NodeProperty::Translation, v.flatten().collect()),
        Some(ReadOutputs::Scales(v)) => (NodeProperty::Scale, v.flatten().collect()),
        Some(ReadOutputs::Rotations(r)) => (NodeProperty::Rotation, r.into_f32().flatten().collect()),
        Some(ReadOutputs::MorphTargetWeights(w)) => (NodeProperty::Weights, w.into_f32().collect()),
        None => return Err(format!("animation of node '{name}': no key values")),
    };
    Ok((property, Keys { times, values, interpolation }))
}

/// How many morph targets the mesh on `node` has (glTF asks every primitive for the same number).
fn morph_target_count(node: &gltf::Node) -> usize {
    let primitives = node.mesh().into_iter().flat_map(|m| m.primitives().collect::<Vec<_>>());
    primitives.map(|p| p.morph_targets().len()).max().unwrap_or(0)
}

/// The shutter in frames relative to the frame, from Blender's length and position.
fn shutter(extras: Option<&ShutterExtras>) -> Result<Shutter, String> {
    let Some(s) = extras else { return Ok(Shutter::CLOSED) };
    if !(s.length_frames >= 0.0 && s.length_frames.is_finite()) {
        return Err(format!(
            "scene extras `caustic.shutter.length_frames`: expected a length >= 0, got {}",
            s.length_frames
        ));
    }
    let open = match s.position {
        ShutterPosition::Start => 0.0,
        ShutterPosition::Center => -s.length_frames / 2.0,
        ShutterPosition::End => -s.length_frames,
    };
    Ok(Shutter { open, length: s.length_frames })
}

/// The world from the scene extras; an image path is relative to the glTF file's folder. An image
/// that cannot be read is a magenta world, as Cycles shows a missing environment image, and a
/// warning says why.
fn world(w: &extras::WorldExtras, gltf_path: &Path, warnings: &mut Vec<String>) -> Result<World, String> {
    match &w.image {
        Some(image) => {
            gltf_checks::check_relative(image)
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
fn world_area(local: &[[Vec3; 3]], rig: &Rig, node: usize) -> f32 {
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
fn light_temperature(extras: &NodeExtras, name: &str) -> Result<Option<f32>, String> {
    match extras.temperature_k {
        None => Ok(None),
        Some(t) if t.is_finite() && t >= 100.0 => Ok(Some(t)),
        Some(t) => Err(format!(
            "node '{name}' extras `caustic.temperature_k`: expected a temperature of 100 K or more, got {t}"
        )),
    }
}

/// An orthographic camera from glTF's half extents: the film's half height is `ymag` (its width
/// follows the image's aspect).
fn orthographic_projection(xmag: f32, ymag: f32, name: &str) -> Result<Projection, String> {
    if !(ymag > 0.0 && ymag.is_finite() && xmag > 0.0 && xmag.is_finite()) {
        return Err(format!(
            "camera node '{name}': an orthographic camera needs positive xmag and ymag, got {xmag} and {ymag}"
        ));
    }
    Ok(Projection::Orthographic { half_height: ymag })
}

/// A panorama's projection from its extras, refused where its ranges are empty or beyond the sphere.
fn panorama_projection(panorama: &extras::PanoramaExtras, name: &str) -> Result<Projection, String> {
    let [lon0, lon1] = panorama.longitude_deg;
    let [lat0, lat1] = panorama.latitude_deg;
    let valid = lon0 < lon1 && lon1 - lon0 <= 360.0 && -90.0 <= lat0 && lat0 < lat1 && lat1 <= 90.0;
    if !valid {
        return Err(format!(
            "camera node '{name}' extras `caustic.panorama`: expected longitudes from low to high spanning at most \
             360 degrees and latitudes from low to high within [-90, 90], got {:?} and {:?}",
            panorama.longitude_deg, panorama.latitude_deg
        ));
    }
    Ok(Projection::Equirectangular {
        longitude: [lon0.to_radians(), lon1.to_radians()],
        latitude: [lat0.to_radians(), lat1.to_radians()],
    })
}

/// Blender's sun angle is the full angular diameter; without one the sun is a delta light.
fn sun_disc(extras: &NodeExtras) -> Cone {
    extras.sun_angle_deg.map_or(Cone::default(), |deg| Cone::from_half_angle(deg.to_radians() / 2.0))
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

    /// Adds the camera of a node: its glTF camera, or the panorama of its extras (which wins).
    fn add_camera(
        &mut self,
        camera: Option<&gltf::Camera>,
        node: usize,
        name: &str,
        extras: &NodeExtras,
    ) -> Result<(), String> {
        match &self.wanted_camera {
            Some(wanted) if wanted != name => return Ok(()),
            None if self.camera.is_some() => {
                self.warnings.push(format!("camera node '{name}' ignored: the first camera is used"));
                return Ok(());
            }
            _ => {}
        }
        let lens = extras.lens.as_ref();
        if let Some(lens) = lens {
            if !(lens.fstop >= 0.0 && lens.focus_distance >= 0.0 && lens.fstop.is_finite()) {
                return Err(format!(
                    "camera node '{name}' extras `caustic.lens`: f-stop and focus distance must be >= 0"
                ));
            }
        }
        let (projection, aspect_ratio) = match (&extras.panorama, camera.map(|c| c.projection())) {
            (Some(panorama), _) => {
                if lens.is_some_and(|l| l.fstop > 0.0) {
                    self.warnings
                        .push(format!("camera node '{name}': depth of field is not rendered on a panorama"));
                }
                (panorama_projection(panorama, name)?, None)
            }
            (None, Some(gltf::camera::Projection::Perspective(p))) => {
                (Projection::Perspective { tan_half_fov_y: (p.yfov() / 2.0).tan() }, p.aspect_ratio())
            }
            (None, Some(gltf::camera::Projection::Orthographic(o))) => {
                (orthographic_projection(o.xmag(), o.ymag(), name)?, Some(o.xmag() / o.ymag()))
            }
            (None, None) => return Err(format!("camera node '{name}' has neither a camera nor a panorama")),
        };
        let shift = extras.shift.map_or(Vec2::ZERO, Vec2::from);
        if !shift.is_finite() {
            return Err(format!(
                "camera node '{name}' extras `caustic.shift`: expected two numbers, got {shift}"
            ));
        }
        // Blender's sensor fit: a 36 mm sensor across the wider side of the image.
        let aspect = aspect_ratio.unwrap_or(1.0).max(1e-6);
        let tan_half_wide = match projection {
            Projection::Perspective { tan_half_fov_y } => tan_half_fov_y * aspect.max(1.0),
            _ => 1.0,
        };
        let focal_length_mm = lens.and_then(|l| l.focal_length_mm).unwrap_or(18.0 / tan_half_wide);
        let tracks = camera.and_then(|c| self.animations.cameras.get(&c.index()));
        let animation = tracks.map(|tracks| Box::new(CameraAnimation { tracks: tracks.clone() }));
        if animation.is_some() && !matches!(projection, Projection::Perspective { .. }) {
            self.warnings.push(format!(
                "camera node '{name}': its animated field of view is rendered for perspective cameras only"
            ));
        }
        self.camera = Some(CameraInstance {
            animation,
            node,
            projection,
            shift,
            aspect_ratio,
            focal_length_mm,
            lens: lens.map(|l| LensSettings {
                fstop: l.fstop,
                focus_distance: l.focus_distance,
                blades: l.blades,
                blade_rotation_deg: l.blade_rotation_deg,
            }),
        });
        Ok(())
    }

    /// A `KHR_lights_punctual` light, a black body's of `kelvin` if given.
    fn add_punctual_light(
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
    fn add_area_light(
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

    /// The material animations, each also on the thin-wall copy of its material (a holdout
    /// copy stays black).
    fn material_animations_with_copies(&self) -> Vec<(usize, MaterialAnimation)> {
        let thin = |m: usize| self.thin_materials.get(&(m as u32)).map(|&c| c as usize);
        let all = self.material_animations.iter().flat_map(|(m, animation)| {
            std::iter::once(*m).chain(thin(*m)).map(move |c| (c, animation.clone()))
        });
        all.collect()
    }

    /// The triangles `local` on `node` emitting from their front faces with `material`.
    fn add_light_mesh(&mut self, node: usize, material: Material, local: &[[Vec3; 3]]) {
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

    fn add_mesh(
        &mut self,
        mesh: &gltf::Mesh,
        node: &gltf::Node,
        rig: &Rig,
        holdout: bool,
    ) -> Result<(), String> {
        let name = mesh.name().unwrap_or("unnamed");
        let first = self.meshes.len();
        let skin = node.skin().map(|skin| self.skin(&skin, node.name().unwrap_or("unnamed"))).transpose()?;
        self.add_primitives(mesh, node, skin, name)?;
        self.thin_walls_of_open_glass(first, name);
        if let Some(matrices) = instance_matrices(node, self.document, self.buffers)? {
            let name = node.name().unwrap_or("unnamed");
            let moves = rig.moves_within(node.index(), f32::MIN, f32::MAX);
            if !moves && !holdout && self.may_share(first) {
                let mut geometry = Geometry::default();
                for mesh in self.meshes.drain(first..) {
                    flatten(&mesh, Mat4::IDENTITY, &mut geometry);
                }
                self.instanced.push(InstancedMesh { node: node.index(), geometry, matrices });
            } else {
                self.add_instances(first, &matrices, name)?;
            }
        }
        Ok(())
    }

    /// Whether the mesh instances from `first` on can be drawn by a two-level BVH: they do not
    /// deform, their materials neither emit nor change nor are light surfaces, and they close up
    /// (open meshes keep their open edges, which only flattened triangles have).
    fn may_share(&self, first: usize) -> bool {
        let meshes = &self.meshes[first..];
        let animated = |m: u32| self.animations.materials.contains_key(&(m as usize));
        let plain = |m: u32| {
            let material = &self.materials[m as usize];
            material.emission.is_none() && !material.light_surface && !material.holdout && !animated(m)
        };
        meshes.iter().all(|m| m.deformation.is_none() && m.triangles.iter().all(|t| plain(t.material)))
            && is_closed(meshes)
    }

    /// Replaces the mesh instances from `first` on with one copy per instance transform of
    /// `matrices` (`EXT_mesh_gpu_instancing` on node `name`).
    fn add_instances(&mut self, first: usize, matrices: &[Mat4], name: &str) -> Result<(), String> {
        if self.meshes[first..].iter().any(|m| m.deformation.is_some()) {
            self.warnings.push(format!(
                "node '{name}': instances of a deforming mesh are not rendered (one is drawn, without {})",
                instancing::EXTENSION
            ));
            return Ok(());
        }
        let triangles: usize = self.meshes[first..].iter().map(|m| m.triangles.len()).sum();
        let total = triangles.saturating_mul(matrices.len());
        if total > instancing::MAX_EXPANDED_TRIANGLES {
            return Err(format!(
                "node '{name}' {}: {} instances of {triangles} triangles make {total} triangles, more than the {} Caustic expands instances into",
                instancing::EXTENSION,
                matrices.len(),
                instancing::MAX_EXPANDED_TRIANGLES
            ));
        }
        let originals: Vec<MeshInstance> = self.meshes.drain(first..).collect();
        for &m in matrices {
            self.meshes.extend(originals.iter().map(|mesh| mesh.transformed(m)));
        }
        Ok(())
    }

    /// Glass on an open mesh (a pane modelled as a plane) has no inside to refract into: its
    /// transmissive primitives get a thin-wall copy of their material, as glTF reads transmission
    /// without a volume.
    fn thin_walls_of_open_glass(&mut self, first: usize, name: &str) {
        let is_glass = |b: &Self, t: &TriangleRef| b.materials[t.material as usize].transmission > 0.0;
        let instances = &self.meshes[first..];
        if !instances.iter().any(|m| m.triangles.iter().any(|t| is_glass(self, t))) || is_closed(instances) {
            return;
        }
        for i in first..self.meshes.len() {
            for t in 0..self.meshes[i].triangles.len() {
                let material = self.meshes[i].triangles[t].material;
                if self.materials[material as usize].transmission > 0.0 {
                    self.meshes[i].triangles[t].material = self.thin_material(material);
                }
            }
        }
        self.warnings.push(format!(
            "mesh '{name}': its glass is an open surface, rendered as a thin wall (no refraction); close the mesh for solid glass"
        ));
    }

    /// Makes the mesh instances from `first` on holdouts: each triangle gets its material's
    /// holdout copy.
    fn hold_out(&mut self, first: usize) {
        for i in first..self.meshes.len() {
            for t in 0..self.meshes[i].triangles.len() {
                let material = self.meshes[i].triangles[t].material;
                self.meshes[i].triangles[t].material = self.holdout_material(material);
            }
        }
    }

    /// The holdout copy of `material`.
    fn holdout_material(&mut self, material: u32) -> u32 {
        if self.materials[material as usize].holdout {
            return material;
        }
        if let Some(&copy) = self.holdout_materials.get(&material) {
            return copy;
        }
        let copy = Material { holdout: true, ..self.materials[material as usize].clone() };
        self.materials.push(copy);
        let index = self.materials.len() as u32 - 1;
        self.holdout_materials.insert(material, index);
        index
    }

    /// The thin-wall copy of `material`.
    fn thin_material(&mut self, material: u32) -> u32 {
        if let Some(&thin) = self.thin_materials.get(&material) {
            return thin;
        }
        let mut copy = self.materials[material as usize].clone();
        copy.thin = true;
        self.materials.push(copy);
        let thin = self.materials.len() as u32 - 1;
        self.thin_materials.insert(material, thin);
        thin
    }

    /// The skin `skin` of node `node` (read once, shared by every mesh it deforms).
    fn skin(&mut self, skin: &gltf::Skin, node: &str) -> Result<Arc<Skin>, String> {
        if let Some(read) = self.skins.get(&skin.index()) {
            return Ok(Arc::clone(read));
        }
        let name = format!("node '{node}': skin {} ('{}')", skin.index(), skin.name().unwrap_or("unnamed"));
        let joints: Vec<usize> = skin.joints().map(|j| j.index()).collect();
        let reader = skin.reader(|b| self.buffers.get(b.index()).map(|d| &d.0[..]));
        let inverse_bind: Vec<Mat4> = match reader.read_inverse_bind_matrices() {
            Some(matrices) => matrices.map(|m| Mat4::from_cols_array_2d(&m)).collect(),
            None => vec![Mat4::IDENTITY; joints.len()],
        };
        if joints.is_empty() || joints.len() > usize::from(u16::MAX) {
            return Err(format!("{name}: expected 1 to 65535 joints, found {}", joints.len()));
        }
        if inverse_bind.len() != joints.len() {
            return Err(format!(
                "{name}: expected {} inverse bind matrices (one per joint), found {}",
                joints.len(),
                inverse_bind.len()
            ));
        }
        if !inverse_bind.iter().all(|m| m.is_finite()) {
            return Err(format!("{name}: its inverse bind matrices have values that are not finite numbers"));
        }
        let read = Arc::new(Skin { joints, inverse_bind });
        self.skins.insert(skin.index(), Arc::clone(&read));
        Ok(read)
    }

    /// Adds each triangle primitive of `mesh` as a mesh instance of `node` (deformed by `skin`
    /// and its morph targets, if any).
    fn add_primitives(
        &mut self,
        mesh: &gltf::Mesh,
        gltf_node: &gltf::Node,
        skin: Option<Arc<Skin>>,
        name: &str,
    ) -> Result<(), String> {
        let node = gltf_node.index();
        for primitive in mesh.primitives() {
            if primitive.mode() != gltf::mesh::Mode::Triangles {
                self.warnings.push(format!(
                    "mesh '{name}': a primitive of mode {:?} skipped (only triangles render)",
                    primitive.mode()
                ));
                continue;
            }
            let reader = primitive.reader(|b| self.buffers.get(b.index()).map(|d| &d.0[..]));
            let positions: Vec<Vec3> = reader
                .read_positions()
                .ok_or_else(|| format!("mesh '{name}': a primitive has no POSITION attribute"))?
                .map(Vec3::from)
                .collect();
            let count = positions.len();
            let normals: Vec<Vec3> = reader
                .read_normals()
                .map(|n| n.map(|n| Vec3::from(n).normalize_or_zero()).collect())
                .unwrap_or_else(|| vec![Vec3::ZERO; count]);
            let uvs: Vec<Vec2> = reader
                .read_tex_coords(0)
                .map(|t| t.into_f32().map(Vec2::from).collect())
                .unwrap_or_else(|| vec![Vec2::ZERO; count]);
            // Attributes must have one entry per position; a mismatched one is dropped, not read past.
            let material = primitive.material().index().map_or(self.material_offset, |i| i as u32);
            let (cuts, reads_colours) = {
                let m = &self.materials[material as usize];
                (m.alpha.cuts(), m.reads_vertex_colours)
            };
            let warnings = &mut self.warnings;
            let (normals, uvs) = (
                matching_attribute(normals, count, "NORMAL", name, warnings),
                matching_attribute(uvs, count, "TEXCOORD_0", name, warnings),
            );
            let extras = vertex_extras(&reader, count, name, cuts, reads_colours, warnings);
            let indices: Vec<u32> = match reader.read_indices() {
                Some(indices) => indices.into_u32().collect(),
                None => (0..count as u32).collect(),
            };
            let mut triangles = Vec::with_capacity(indices.len() / 3);
            let mut skipped = 0;
            for chunk in indices.chunks_exact(3) {
                let vertices = [chunk[0], chunk[1], chunk[2]];
                if let Some(&bad) = vertices.iter().find(|&&i| i as usize >= count) {
                    return Err(format!("mesh '{name}': index {bad} out of range ({count} vertices)"));
                }
                if is_valid_triangle(&vertices.map(|i| positions[i as usize])) {
                    triangles.push(TriangleRef { vertices, material });
                } else {
                    skipped += 1;
                }
            }
            if skipped > 0 {
                self.warnings.push(format!(
                    "mesh '{name}': skipped {skipped} degenerate triangles (zero area or non-finite coordinates)"
                ));
            }
            let default_weights = gltf_node.weights().or(mesh.weights());
            let deformation = deformation(&reader, skin.clone(), default_weights, count, name)?;
            let mesh = MeshInstance {
                node,
                name: name.to_string(),
                positions,
                normals,
                uvs,
                extras,
                triangles,
                deformation,
            };
            let mesh = self.with_tangents(mesh, material);
            self.meshes.push(mesh);
        }
        Ok(())
    }

    /// `mesh` with tangents for its material's normal map: the file's, else MikkTSpace's; without
    /// either (no normals or texture coordinates) the map is not applied, with a warning.
    fn with_tangents(&mut self, mesh: MeshInstance, material: u32) -> MeshInstance {
        let Some(map) = &self.materials[material as usize].normal_map else { return mesh };
        if !mesh.extras.tangents.is_empty() {
            return mesh;
        }
        match tangents::with_generated_tangents(&mesh, map.texture.set()) {
            Some(mesh) => mesh,
            None => {
                self.warnings.push(format!(
                    "mesh '{}': its normal map is not applied (the mesh has no normals or texture coordinates for tangents)",
                    mesh.name
                ));
                mesh
            }
        }
    }
}

/// The skin and morph targets of a primitive of `count` vertices, if it has either: `skin` is
/// its node's; `default_weights` the node's or the mesh's `weights`.
fn deformation<'a, 's, F>(
    reader: &gltf::mesh::Reader<'a, 's, F>,
    skin: Option<Arc<Skin>>,
    default_weights: Option<&[f32]>,
    count: usize,
    name: &str,
) -> Result<Option<Box<Deformation>>, String>
where
    F: Clone + Fn(gltf::Buffer<'a>) -> Option<&'s [u8]>,
{
    let skin = skin.map(|skin| skinning(reader, skin, count, name)).transpose()?;
    let targets = morph_targets(reader, count, name)?;
    let morph = match targets.is_empty() {
        true => None,
        false => {
            let weights = default_weights.map_or_else(|| vec![0.0; targets.len()], <[f32]>::to_vec);
            if weights.len() != targets.len() || !weights.iter().all(|w| w.is_finite()) {
                return Err(format!(
                    "mesh '{name}': expected {} finite default morph target weights, found {:?}",
                    targets.len(),
                    weights
                ));
            }
            Some(Morph { targets, weights })
        }
    };
    Ok((skin.is_some() || morph.is_some()).then(|| Box::new(Deformation { skin, morph })))
}

/// How the `count` vertices of a primitive hang from `skin`: every `JOINTS_n`/`WEIGHTS_n` set,
/// weights normalised to sum to one (the specification asks files for that; exporters round).
fn skinning<'a, 's, F>(
    reader: &gltf::mesh::Reader<'a, 's, F>,
    skin: Arc<Skin>,
    count: usize,
    name: &str,
) -> Result<Skinning, String>
where
    F: Clone + Fn(gltf::Buffer<'a>) -> Option<&'s [u8]>,
{
    let mut sets: Vec<(Vec<[u16; 4]>, Vec<[f32; 4]>)> = Vec::new();
    while let (Some(joints), Some(weights)) =
        (reader.read_joints(sets.len() as u32), reader.read_weights(sets.len() as u32))
    {
        let set = sets.len();
        let (joints, weights): (Vec<[u16; 4]>, Vec<[f32; 4]>) =
            (joints.into_u16().collect(), weights.into_f32().collect());
        if joints.len() != count || weights.len() != count {
            return Err(format!(
                "mesh '{name}': JOINTS_{set} and WEIGHTS_{set} need {count} entries (one per vertex), found {} and {}",
                joints.len(),
                weights.len()
            ));
        }
        if let Some(bad) = joints.iter().flatten().find(|&&j| usize::from(j) >= skin.joints.len()) {
            return Err(format!(
                "mesh '{name}': JOINTS_{set} names joint {bad}, but its skin has {} joints",
                skin.joints.len()
            ));
        }
        if !weights.iter().flatten().all(|w| w.is_finite() && *w >= 0.0) {
            return Err(format!(
                "mesh '{name}': WEIGHTS_{set} has weights that are negative or not finite numbers"
            ));
        }
        sets.push((joints, weights));
    }
    if sets.is_empty() {
        return Err(format!("mesh '{name}': its node has a skin, but it has no JOINTS_0 and WEIGHTS_0"));
    }
    let per_vertex = 4 * sets.len();
    let mut joints = Vec::with_capacity(per_vertex * count);
    let mut weights = Vec::with_capacity(per_vertex * count);
    for v in 0..count {
        let influences: Vec<(u16, f32)> = sets.iter().flat_map(|(j, w)| j[v].into_iter().zip(w[v])).collect();
        let sum: f32 = influences.iter().map(|(_, w)| w).sum();
        let scale = if sum > 0.0 { sum.recip() } else { 0.0 };
        joints.extend(influences.iter().map(|(j, _)| j));
        weights.extend(influences.iter().map(|(_, w)| w * scale));
    }
    Ok(Skinning { skin, per_vertex, joints, weights })
}

/// The morph targets of a primitive of `count` vertices (refused where an offset list has
/// another length or values that are not finite).
fn morph_targets<'a, 's, F>(
    reader: &gltf::mesh::Reader<'a, 's, F>,
    count: usize,
    name: &str,
) -> Result<Vec<MorphTarget>, String>
where
    F: Clone + Fn(gltf::Buffer<'a>) -> Option<&'s [u8]>,
{
    let read = |offsets: Option<gltf::accessor::Iter<'s, [f32; 3]>>| -> Vec<Vec3> {
        offsets.map(|o| o.map(Vec3::from).collect()).unwrap_or_default()
    };
    let mut targets = Vec::new();
    for (k, (positions, normals, tangents)) in reader.read_morph_targets().enumerate() {
        let target =
            MorphTarget { positions: read(positions), normals: read(normals), tangents: read(tangents) };
        for (what, offsets) in
            [("POSITION", &target.positions), ("NORMAL", &target.normals), ("TANGENT", &target.tangents)]
        {
            if !offsets.is_empty() && (offsets.len() != count || !offsets.iter().all(|o| o.is_finite())) {
                return Err(format!(
                    "mesh '{name}': morph target {k}'s {what} offsets need {count} finite entries, found {}",
                    offsets.len()
                ));
            }
        }
        targets.push(target);
    }
    Ok(targets)
}

/// `TEXCOORD_1`, `COLOR_0` (fitted to reflectance spectra; only where the material `reads_colours`)
/// and `TANGENT` of a primitive of `count` vertices; each empty where the primitive has none or a
/// mismatched one (warned). The colours' alpha is kept where it is below 1 somewhere on a
/// material whose alpha `cuts`.
fn vertex_extras<'a, 's, F>(
    reader: &gltf::mesh::Reader<'a, 's, F>,
    count: usize,
    name: &str,
    cuts: bool,
    reads_colours: bool,
    warnings: &mut Vec<String>,
) -> VertexExtras
where
    F: Clone + Fn(gltf::Buffer<'a>) -> Option<&'s [u8]>,
{
    let uvs1: Vec<Vec2> =
        reader.read_tex_coords(1).map(|t| t.into_f32().map(Vec2::from).collect()).unwrap_or_default();
    let colours: Vec<Vec4> = match reader.read_colors(0) {
        Some(colours) if reads_colours => colours.into_rgba_f32().map(Vec4::from).collect(),
        _ => Vec::new(),
    };
    let tangents: Vec<Vec4> = reader.read_tangents().map(|t| t.map(Vec4::from).collect()).unwrap_or_default();
    let tangents = optional_attribute(tangents, count, "TANGENT", name, warnings);
    let finite = tangents.iter().all(|t| t.is_finite());
    if !finite {
        warnings.push(format!("mesh '{name}': TANGENT has values that are not finite numbers; ignored"));
    }
    let colours = optional_attribute(colours, count, "COLOR_0", name, warnings);
    let alphas = match cuts && colours.iter().any(|c| c.w < 1.0) {
        true => colours.iter().map(|c| c.w.clamp(0.0, 1.0)).collect(),
        false => Vec::new(),
    };
    VertexExtras {
        uvs1: optional_attribute(uvs1, count, "TEXCOORD_1", name, warnings),
        colours: reflectances(&colours),
        alphas,
        tangents: if finite { tangents } else { Vec::new() },
    }
}

/// An attribute only some meshes have: `values` when it has `count` entries, else none (with a
/// warning when the file gave a mismatched one).
fn optional_attribute<T: Default + Clone>(
    values: Vec<T>,
    count: usize,
    attribute: &str,
    mesh: &str,
    warnings: &mut Vec<String>,
) -> Vec<T> {
    if values.is_empty() || values.len() == count {
        return values;
    }
    warnings.push(mismatch(values.len(), count, attribute, mesh));
    Vec::new()
}

/// The warning for an attribute of `len` entries on a mesh of `count` positions.
fn mismatch(len: usize, count: usize, attribute: &str, mesh: &str) -> String {
    format!("mesh '{mesh}': {attribute} has {len} entries for {count} positions; ignored")
}

/// Linear RGB colours as reflectance spectra, fitted once per colour at 10 bits a channel.
fn reflectances(colours: &[Vec4]) -> Vec<RgbSpectrum> {
    let mut cache = std::collections::HashMap::new();
    colours
        .iter()
        .map(|c| {
            let key =
                c.truncate().clamp(Vec3::ZERO, Vec3::ONE).to_array().map(|v| (v * 1023.0).round() as u16);
            *cache
                .entry(key)
                .or_insert_with(|| RgbSpectrum::reflectance(Vec3::from(key.map(|v| f32::from(v) / 1023.0))))
        })
        .collect()
}

/// `values` when it has `count` entries (one per position); otherwise zeros, with a warning.
fn matching_attribute<T: Default + Clone>(
    values: Vec<T>,
    count: usize,
    attribute: &str,
    mesh: &str,
    warnings: &mut Vec<String>,
) -> Vec<T> {
    if values.len() == count {
        return values;
    }
    warnings.push(mismatch(values.len(), count, attribute, mesh));
    vec![T::default(); count]
}

/// Whether the triangles of `instances` close up: every edge (matched by its end positions,
/// rounded to a millionth of the mesh's size, so that seams whose vertices differ in their last
/// bits still match) is shared by an even number of triangles.
fn is_closed(instances: &[MeshInstance]) -> bool {
    let corners = || {
        instances
            .iter()
            .flat_map(|m| m.triangles.iter().flat_map(|t| t.vertices.map(|v| m.positions[v as usize])))
    };
    let Some((lo, hi)) = corners().map(|p| (p, p)).reduce(|(a, b), (c, d)| (a.min(c), b.max(d))) else {
        return true;
    };
    let quantum = ((hi - lo).max_element() * 1e-6).max(f32::MIN_POSITIVE);
    let key = |p: Vec3| ((p - lo) / quantum).round().as_i64vec3().to_array();
    let mut edges: std::collections::HashMap<([i64; 3], [i64; 3]), u32> = Default::default();
    for m in instances {
        for t in &m.triangles {
            let [a, b, c] = t.vertices.map(|v| key(m.positions[v as usize]));
            for (p, q) in [(a, b), (b, c), (c, a)] {
                *edges.entry(if p < q { (p, q) } else { (q, p) }).or_default() += 1;
            }
        }
    }
    edges.values().all(|n| n % 2 == 0)
}

fn is_valid_triangle(c: &[Vec3; 3]) -> bool {
    let area2 = (c[1] - c[0]).cross(c[2] - c[0]).length_squared();
    c.iter().all(|v| v.is_finite()) && area2 > 0.0 && area2.is_finite()
}
