//! `KHR_animation_pointer`, read from the raw JSON (the gltf crate fails on a channel without a
//! node), and the add-on's `caustic.tracks`, which use the same pointers for what glTF cannot
//! animate (an area light's power). Each pointer becomes a track on a light, a material, a camera,
//! an area light or a node's transform ([`super::values`]); a pointer Caustic does not render is
//! named in a warning, and a pointer to an object the file does not have is refused.
//!
//! Pointers read: `/nodes/N/{translation,rotation,scale,weights}`,
//! `/nodes/N/extras/caustic/area_light/{power,color}`,
//! `/extensions/KHR_lights_punctual/lights/N/{color,intensity,spot/innerConeAngle,spot/outerConeAngle}`,
//! `/materials/N/pbrMetallicRoughness/{baseColorFactor,metallicFactor,roughnessFactor}`,
//! `/materials/N/emissiveFactor`,
//! `/materials/N/extensions/KHR_materials_emissive_strength/emissiveStrength`,
//! `/materials/N/extensions/KHR_materials_transmission/transmissionFactor` and
//! `/cameras/N/perspective/yfov`.

use std::borrow::Cow;
use std::collections::HashMap;

use glam::Vec4;
use serde_json::Value;

use super::animation::{Interpolation, Track};
use super::values::{CameraProperty, LightProperty, MaterialProperty, Tracks};

/// The extension's name.
const EXTENSION: &str = "KHR_animation_pointer";

/// A channel whose target is a pointer.
#[derive(Clone, Debug)]
pub struct PointerChannel {
    /// Its animation's index.
    pub animation: usize,
    /// Its sampler's index within the animation.
    pub sampler: usize,
    /// The JSON pointer it animates.
    pub pointer: String,
}

/// A node property a pointer animates (as an ordinary channel would).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NodeProperty {
    /// Translation.
    Translation,
    /// Rotation (a quaternion).
    Rotation,
    /// Scale.
    Scale,
    /// Morph target weights.
    Weights,
}

/// Every animated value the file holds, by the glTF index of what it animates.
#[derive(Debug, Default)]
pub struct Animations {
    /// Punctual lights, by light index.
    pub lights: HashMap<usize, Tracks<LightProperty>>,
    /// Materials, by material index.
    pub materials: HashMap<usize, Tracks<MaterialProperty>>,
    /// Cameras, by camera index.
    pub cameras: HashMap<usize, Tracks<CameraProperty>>,
    /// Area lights (the extras), by node index; power as the emissive strength.
    pub area_lights: HashMap<usize, Tracks<MaterialProperty>>,
    /// Node transforms and weights, with their keys as flat floats.
    pub nodes: Vec<(usize, NodeProperty, Keys)>,
    /// Pointers that are not rendered.
    pub warnings: Vec<String>,
}

/// Key times and their values (flat: several floats per key for a vector).
#[derive(Clone, Debug)]
pub struct Keys {
    /// Times in seconds.
    pub times: Vec<f32>,
    /// Values, flat.
    pub values: Vec<f32>,
    /// Interpolation.
    pub interpolation: Interpolation,
}

/// The extensions Caustic reads from the raw JSON, which the gltf crate would refuse as required.
const READ_RAW: [&str; 2] = [EXTENSION, super::instancing::EXTENSION];

/// The file's bytes as the gltf crate reads them, and the pointer channels: without pointer
/// channels, with the extensions Caustic reads raw out of `extensionsRequired`, and with a view of
/// zeros for every accessor that has neither a `bufferView` nor `sparse` (glTF reads it as zeros;
/// Blender's exporter writes one for a shape key's normals; the gltf crate refuses it). The bytes
/// are borrowed unchanged where there is nothing to change.
pub fn prepare(bytes: &[u8]) -> Result<(Cow<'_, [u8]>, Vec<PointerChannel>), String> {
    let names = |name: &str| bytes.windows(name.len()).any(|w| w == name.as_bytes());
    let is_glb = bytes.starts_with(b"glTF");
    // A GLB that cannot be read is left to the gltf crate, which says why.
    let glb = if is_glb { gltf::Glb::from_slice(bytes).ok() } else { None };
    let json = glb.as_ref().map_or(bytes, |glb| &glb.json);
    if !READ_RAW.iter().any(|name| names(name)) && !has_accessors_without_data(json) {
        return Ok((Cow::Borrowed(bytes), Vec::new()));
    }
    if is_glb {
        let glb = glb.map_or_else(|| gltf::Glb::from_slice(bytes), Ok);
        let glb = glb.map_err(|e| format!("not a valid GLB file: {e}"))?;
        let (json, channels) = prepare_json(&glb.json)?;
        let out = gltf::Glb { json: Cow::Owned(json), ..glb };
        let bytes = out.to_vec().map_err(|e| format!("cannot rewrite the GLB container: {e}"))?;
        return Ok((Cow::Owned(bytes), channels));
    }
    let (json, channels) = prepare_json(bytes)?;
    Ok((Cow::Owned(json), channels))
}

/// `json` as [`prepare`] leaves it, and the pointer channels.
fn prepare_json(json: &[u8]) -> Result<(Vec<u8>, Vec<PointerChannel>), String> {
    let mut root: Value =
        serde_json::from_slice(json).map_err(|e| format!("not a valid glTF file (malformed JSON): {e}"))?;
    let mut found = Vec::new();
    if let Some(animations) = root.get_mut("animations").and_then(Value::as_array_mut) {
        for (a, animation) in animations.iter_mut().enumerate() {
            let Some(channels) = animation.get_mut("channels").and_then(Value::as_array_mut) else {
                continue;
            };
            let mut kept = Vec::new();
            for (c, channel) in channels.drain(..).enumerate() {
                if channel.pointer("/target/path").and_then(Value::as_str) != Some("pointer") {
                    kept.push(channel);
                    continue;
                }
                let at = format!("animation {a} channel {c}");
                let pointer = channel
                    .pointer(&format!("/target/extensions/{EXTENSION}/pointer"))
                    .and_then(Value::as_str)
                    .ok_or(format!(
                        "{at}: its target's path is \"pointer\" but it has no {EXTENSION} pointer"
                    ))?;
                let sampler = channel.get("sampler").and_then(Value::as_u64);
                let sampler = sampler.ok_or(format!("{at}: no sampler"))? as usize;
                found.push(PointerChannel { animation: a, sampler, pointer: pointer.to_string() });
            }
            *channels = kept;
        }
    }
    if let Some(names) = root.get_mut("extensionsRequired").and_then(Value::as_array_mut) {
        names.retain(|n| !READ_RAW.iter().any(|raw| n.as_str() == Some(raw)));
    }
    give_zeros_to_accessors_without_data(&mut root)?;
    let bytes = serde_json::to_vec(&root).map_err(|e| format!("cannot rewrite the JSON: {e}"))?;
    Ok((bytes, found))
}

/// Whether some accessor of the glTF JSON `json` has neither a `bufferView` nor `sparse` (false
/// where the JSON cannot be read: the gltf crate says why).
fn has_accessors_without_data(json: &[u8]) -> bool {
    #[derive(serde::Deserialize)]
    struct Root {
        #[serde(default)]
        accessors: Vec<Accessor>,
    }
    #[derive(serde::Deserialize)]
    struct Accessor {
        #[serde(rename = "bufferView")]
        view: Option<serde::de::IgnoredAny>,
        sparse: Option<serde::de::IgnoredAny>,
    }
    let root = serde_json::from_slice::<Root>(json);
    root.is_ok_and(|root| root.accessors.iter().any(|a| a.view.is_none() && a.sparse.is_none()))
}

/// The most bytes of zeros given to accessors without data (64 MiB): more is a hostile count.
const MOST_ZEROS: u64 = 1 << 26;

/// Gives every accessor without a `bufferView` or `sparse` a view of one new buffer of zeros (a
/// data URI), as long as the longest of them.
fn give_zeros_to_accessors_without_data(root: &mut Value) -> Result<(), String> {
    let Some(accessors) = root.get("accessors").and_then(Value::as_array) else { return Ok(()) };
    let mut lengths = Vec::new();
    for (i, accessor) in accessors.iter().enumerate() {
        if accessor.get("bufferView").is_some() || accessor.get("sparse").is_some() {
            continue;
        }
        let count = accessor["count"].as_u64().unwrap_or(0);
        let components: u64 = match accessor["type"].as_str() {
            Some("VEC2") => 2,
            Some("VEC3") => 3,
            Some("VEC4" | "MAT2") => 4,
            Some("MAT3") => 9,
            Some("MAT4") => 16,
            _ => 1,
        };
        // Four bytes a component covers every component type and its column padding.
        let length = count.saturating_mul(components * 4);
        if length > MOST_ZEROS {
            return Err(format!(
                "accessor {i} has no data and claims {count} elements (glTF reads them as zeros)"
            ));
        }
        lengths.push((i, length.max(4)));
    }
    let Some(longest) = lengths.iter().map(|&(_, length)| length).max() else { return Ok(()) };
    use base64::Engine;
    let zeros = base64::engine::general_purpose::STANDARD.encode(vec![0u8; longest as usize]);
    let buffers = root["buffers"].as_array().map_or(0, Vec::len);
    let uri = format!("data:application/octet-stream;base64,{zeros}");
    push(root, "buffers", serde_json::json!({"byteLength": longest, "uri": uri}));
    for (i, length) in lengths {
        let view = root["bufferViews"].as_array().map_or(0, Vec::len);
        push(root, "bufferViews", serde_json::json!({"buffer": buffers, "byteLength": length}));
        root["accessors"][i]["bufferView"] = view.into();
    }
    Ok(())
}

/// Appends `value` to the array at `key` in `root`, made where there is none.
fn push(root: &mut Value, key: &str, value: Value) {
    match root.get_mut(key).and_then(Value::as_array_mut) {
        Some(array) => array.push(value),
        None => root[key] = Value::Array(vec![value]),
    }
}

/// Reads `channels`' keys from `document` and `tracks` (the scene's `caustic.tracks`) into
/// [`Animations`].
pub fn read(
    document: &gltf::Document,
    buffers: &[gltf::buffer::Data],
    channels: &[PointerChannel],
    tracks: &[TrackExtras],
) -> Result<Animations, String> {
    let mut animations = Animations::default();
    for channel in channels {
        let at = format!("animation {} pointer '{}'", channel.animation, channel.pointer);
        let keys = channel_keys(document, buffers, channel).map_err(|e| format!("{at}: {e}"))?;
        animations.add(document, &channel.pointer, keys).map_err(|e| format!("{at}: {e}"))?;
    }
    for track in tracks {
        let at = format!("scene extras `caustic.tracks` pointer '{}'", track.pointer);
        let interpolation = match track.interpolation.as_deref() {
            None | Some("LINEAR") => Interpolation::Linear,
            Some("STEP") => Interpolation::Step,
            Some(other) => return Err(format!("{at}: interpolation must be LINEAR or STEP, got {other}")),
        };
        let keys = Keys { times: track.times.clone(), values: track.values.clone(), interpolation };
        animations.add(document, &track.pointer, keys).map_err(|e| format!("{at}: {e}"))?;
    }
    Ok(animations)
}

/// One track of the scene's `caustic.tracks` extras: keys on a pointer.
#[derive(Clone, Debug, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TrackExtras {
    /// A JSON pointer, as `KHR_animation_pointer` writes them.
    pub pointer: String,
    /// Key times in seconds.
    pub times: Vec<f32>,
    /// Values, flat (three per key for a colour).
    pub values: Vec<f32>,
    /// LINEAR (the default) or STEP.
    #[serde(default)]
    pub interpolation: Option<String>,
}

/// The keys of a pointer channel's sampler: float times and float values.
fn channel_keys(
    document: &gltf::Document,
    buffers: &[gltf::buffer::Data],
    channel: &PointerChannel,
) -> Result<Keys, String> {
    let animation = document.animations().nth(channel.animation).ok_or("no such animation")?;
    let sampler = animation.samplers().nth(channel.sampler).ok_or(format!(
        "its channel names sampler {}, but the animation has {}",
        channel.sampler,
        animation.samplers().count()
    ))?;
    let interpolation = match sampler.interpolation() {
        gltf::animation::Interpolation::Step => Interpolation::Step,
        gltf::animation::Interpolation::Linear => Interpolation::Linear,
        gltf::animation::Interpolation::CubicSpline => Interpolation::CubicSpline,
    };
    Ok(Keys {
        times: floats(sampler.input(), buffers)?,
        values: floats(sampler.output(), buffers)?,
        interpolation,
    })
}

/// Every float of `accessor` (a float scalar or vector in a buffer view, not sparse), flat.
pub fn floats(accessor: gltf::Accessor, buffers: &[gltf::buffer::Data]) -> Result<Vec<f32>, String> {
    let index = accessor.index();
    let bad = || format!("accessor {index} must hold float scalars or vectors in a buffer view (not sparse)");
    let view = accessor.view().filter(|_| accessor.sparse().is_none()).ok_or_else(bad)?;
    if accessor.data_type() != gltf::accessor::DataType::F32 || accessor.dimensions().multiplicity() > 4 {
        return Err(bad());
    }
    let width = accessor.dimensions().multiplicity();
    let stride = view.stride().unwrap_or(4 * width);
    let data = buffers.get(view.buffer().index()).ok_or_else(bad)?;
    let start = view.offset() + accessor.offset();
    let read = |at: usize| data.get(at..at + 4).map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]));
    (0..accessor.count())
        .flat_map(|k| (0..width).map(move |c| start + k * stride + 4 * c))
        .map(|at| read(at).ok_or(format!("accessor {index} runs past its buffer")))
        .collect()
}

/// The target of a pointer: an object's kind, its index and the rest of the pointer.
fn split(pointer: &str) -> Option<(&str, usize, &str)> {
    let rest = pointer.strip_prefix('/')?;
    let (kind, rest) = match rest.strip_prefix("extensions/KHR_lights_punctual/lights/") {
        Some(rest) => ("light", rest),
        None => rest.split_once('/')?,
    };
    let (index, property) = rest.split_once('/')?;
    Some((kind, index.parse().ok()?, property))
}

impl Animations {
    /// Adds `keys` on `pointer`, or a warning where Caustic does not render what it animates.
    fn add(&mut self, document: &gltf::Document, pointer: &str, keys: Keys) -> Result<(), String> {
        let Some((kind, index, property)) = split(pointer) else {
            self.warnings.push(format!("animation pointer '{pointer}' is not rendered"));
            return Ok(());
        };
        let count = match kind {
            "nodes" => document.nodes().count(),
            "materials" => document.materials().count(),
            "cameras" => document.cameras().count(),
            "light" => document.lights().map_or(0, |l| l.count()),
            _ => usize::MAX,
        };
        if index >= count {
            return Err(format!("it names {kind} {index}, but the file has {count}"));
        }
        use MaterialProperty as M;
        let node = |p| Some(Target::Node(p));
        let material = |p| Some(Target::Material(p));
        let target = match (kind, property) {
            ("nodes", "translation") => node(NodeProperty::Translation),
            ("nodes", "rotation") => node(NodeProperty::Rotation),
            ("nodes", "scale") => node(NodeProperty::Scale),
            ("nodes", "weights") => node(NodeProperty::Weights),
            ("nodes", "extras/caustic/area_light/power") => Some(Target::AreaLight(M::EmissiveStrength)),
            ("nodes", "extras/caustic/area_light/color") => Some(Target::AreaLight(M::Emissive)),
            ("light", "color") => Some(Target::Light(LightProperty::Colour)),
            ("light", "intensity") => Some(Target::Light(LightProperty::Intensity)),
            ("light", "spot/outerConeAngle") => Some(Target::Light(LightProperty::OuterCone)),
            ("light", "spot/innerConeAngle") => Some(Target::Light(LightProperty::InnerCone)),
            ("materials", "pbrMetallicRoughness/baseColorFactor") => material(M::BaseColour),
            ("materials", "pbrMetallicRoughness/metallicFactor") => material(M::Metallic),
            ("materials", "pbrMetallicRoughness/roughnessFactor") => material(M::Roughness),
            ("materials", "emissiveFactor") => material(M::Emissive),
            ("materials", "extensions/KHR_materials_emissive_strength/emissiveStrength") => {
                material(M::EmissiveStrength)
            }
            ("materials", "extensions/KHR_materials_transmission/transmissionFactor") => {
                material(M::Transmission)
            }
            ("cameras", "perspective/yfov") => Some(Target::Camera(CameraProperty::Yfov)),
            _ => None,
        };
        let Some(target) = target else {
            self.warnings.push(format!("animation pointer '{pointer}' is not rendered"));
            return Ok(());
        };
        match target {
            Target::Node(property) => self.nodes.push((index, property, keys)),
            Target::Light(p) => self.lights.entry(index).or_default().set(p, track(keys, width_of_light(p))?),
            Target::Material(p) => {
                self.materials.entry(index).or_default().set(p, track(keys, width_of_material(p))?)
            }
            Target::AreaLight(p) => {
                self.area_lights.entry(index).or_default().set(p, track(keys, width_of_material(p))?)
            }
            Target::Camera(p) => self.cameras.entry(index).or_default().set(p, track(keys, 1)?),
        }
        Ok(())
    }
}

/// What a pointer animates.
enum Target {
    Node(NodeProperty),
    Light(LightProperty),
    Material(MaterialProperty),
    AreaLight(MaterialProperty),
    Camera(CameraProperty),
}

/// Floats per key of a light property.
fn width_of_light(p: LightProperty) -> usize {
    if p == LightProperty::Colour {
        3
    } else {
        1
    }
}

/// Floats per key of a material property.
fn width_of_material(p: MaterialProperty) -> usize {
    match p {
        MaterialProperty::BaseColour => 4,
        MaterialProperty::Emissive => 3,
        _ => 1,
    }
}

/// Refuses keys that are not `width` floats a key at increasing finite times.
pub fn check(keys: &Keys, width: usize) -> Result<(), String> {
    let per_key = if keys.interpolation == Interpolation::CubicSpline { 3 } else { 1 };
    let expected = keys.times.len() * per_key * width;
    if keys.times.is_empty() || keys.values.len() != expected {
        return Err(format!(
            "{} key times need {expected} values, found {}",
            keys.times.len(),
            keys.values.len()
        ));
    }
    if !keys.times.windows(2).all(|w| w[0] < w[1])
        || !keys.times.iter().chain(&keys.values).all(|v| v.is_finite())
    {
        return Err("key times must increase and every key must be a finite number".into());
    }
    Ok(())
}

/// `keys` of `width` (at most 4) floats a key as a track, checked.
pub fn track(keys: Keys, width: usize) -> Result<Track, String> {
    check(&keys, width)?;
    let values = keys
        .values
        .chunks(width)
        .map(|c| {
            let mut v = [0.0; 4];
            v[..width].copy_from_slice(c);
            Vec4::from(v)
        })
        .collect();
    Ok(Track { times: keys.times, values, interpolation: keys.interpolation, is_rotation: false })
}
