//! Helpers shared by the integration tests: render through the library or the binary, read EXRs,
//! and write small analytic glTF scenes.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use base64::Engine;
use caustic::render::{self, RenderSettings};
use serde_json::{json, Value};

/// The repository's bundled scene `name`.
pub fn bundled_scene(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name)
}

/// Settings for a quiet render of `scene` into `out`.
pub fn settings(scene: &Path, out: &Path, passes: u64) -> RenderSettings {
    RenderSettings { passes: Some(passes), ..RenderSettings::new(scene, out) }
}

/// A rendered image: linear Rec.709, row-major from the top-left.
pub struct Image {
    pub width: usize,
    pub height: usize,
    pub rgb: Vec<[f64; 3]>,
}

impl Image {
    /// Mean colour over the pixels `x0..x1`, `y0..y1`.
    pub fn mean(&self, x0: usize, x1: usize, y0: usize, y1: usize) -> [f64; 3] {
        let mut sum = [0.0; 3];
        for y in y0..y1 {
            for x in x0..x1 {
                for c in 0..3 {
                    sum[c] += self.rgb[y * self.width + x][c];
                }
            }
        }
        sum.map(|s| s / ((x1 - x0) * (y1 - y0)) as f64)
    }

    /// Mean colour of the whole image.
    pub fn mean_all(&self) -> [f64; 3] {
        self.mean(0, self.width, 0, self.height)
    }

    /// Mean luminance (Rec.709 weights) over a window.
    pub fn luminance(&self, x0: usize, x1: usize, y0: usize, y1: usize) -> f64 {
        let [r, g, b] = self.mean(x0, x1, y0, y1);
        0.2126 * r + 0.7152 * g + 0.0722 * b
    }

    /// Root-mean-square difference from `other`, over every channel.
    pub fn rmse(&self, other: &Image) -> f64 {
        let sum: f64 = self
            .rgb
            .iter()
            .zip(&other.rgb)
            .map(|(a, b)| (0..3).map(|c| (a[c] - b[c]).powi(2)).sum::<f64>())
            .sum();
        (sum / (3 * self.rgb.len()) as f64).sqrt()
    }
}

/// Renders with the library on a pool of `threads` workers and returns the image.
pub fn render(settings: &RenderSettings, threads: usize) -> Image {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
    let report = pool.install(|| render::render(settings)).unwrap_or_else(|e| panic!("render failed: {e}"));
    read_exr(&report.frames[0].path)
}

/// Reads `Combined.R/G/B` of an EXR written by Caustic.
pub fn read_exr(path: &Path) -> Image {
    use exr::prelude::read_all_flat_layers_from_file;
    let image = read_all_flat_layers_from_file(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let layer = &image.layer_data[0];
    let size = layer.size;
    let channel = |name: &str| {
        let short = name.trim_start_matches("Combined.");
        let c = layer
            .channel_data
            .list
            .iter()
            .find(|c| c.name.to_string() == name || c.name.to_string() == short)
            .unwrap_or_else(|| panic!("{}: no channel {name}", path.display()));
        c.sample_data.values_as_f32().collect::<Vec<f32>>()
    };
    let (r, g, b) = (channel("Combined.R"), channel("Combined.G"), channel("Combined.B"));
    let rgb = (0..size.0 * size.1).map(|i| [r[i] as f64, g[i] as f64, b[i] as f64]).collect();
    Image { width: size.0, height: size.1, rgb }
}

/// Runs the `caustic` binary with `args`.
pub fn run_caustic(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_caustic")).args(args).output().expect("run caustic")
}

/// A minimal glTF 2.0 document built in memory, for scenes with analytic answers.
#[derive(Default)]
pub struct GltfBuilder {
    buffer: Vec<u8>,
    accessors: Vec<Value>,
    buffer_views: Vec<Value>,
    meshes: Vec<Value>,
    materials: Vec<Value>,
    nodes: Vec<Value>,
    cameras: Vec<Value>,
    lights: Vec<Value>,
    images: Vec<Value>,
    animations: Vec<Value>,
    skins: Vec<Value>,
    scene_extras: Option<Value>,
    /// Nodes that are children of others (not roots of the scene).
    children: std::collections::BTreeSet<usize>,
}

/// The quaternion (x, y, z, w) that turns local -z (where cameras and lights point) to `dir`.
pub fn look_rotation(dir: [f32; 3]) -> [f32; 4] {
    let q = glam::Quat::from_rotation_arc(-glam::Vec3::Z, glam::Vec3::from(dir).normalize());
    q.to_array()
}

impl GltfBuilder {
    fn add_accessor(&mut self, data: &[f32], components: usize, kind: &str) -> usize {
        let offset = self.buffer.len();
        for v in data {
            self.buffer.extend_from_slice(&v.to_le_bytes());
        }
        self.buffer_views.push(json!({"buffer": 0, "byteOffset": offset, "byteLength": data.len() * 4}));
        let count = data.len() / components;
        let mut accessor = json!({"bufferView": self.buffer_views.len() - 1, "componentType": 5126, "count": count, "type": kind});
        if kind == "VEC3" {
            let mut min = [f32::INFINITY; 3];
            let mut max = [f32::NEG_INFINITY; 3];
            // Exporters write the bounds of the finite values (JSON has no NaN or infinity).
            for p in data.chunks(3) {
                for k in (0..3).filter(|&k| p[k].is_finite()) {
                    min[k] = min[k].min(p[k]);
                    max[k] = max[k].max(p[k]);
                }
            }
            accessor["min"] = json!(min);
            accessor["max"] = json!(max);
        }
        self.accessors.push(accessor);
        self.accessors.len() - 1
    }

    /// Adds an accessor of unsigned shorts (glTF component type 5123).
    fn add_u16_accessor(&mut self, data: &[u16], components: usize, kind: &str) -> usize {
        let offset = self.buffer.len();
        for v in data {
            self.buffer.extend_from_slice(&v.to_le_bytes());
        }
        // Accessors of floats that follow stay aligned to four bytes.
        self.buffer.resize(self.buffer.len().div_ceil(4) * 4, 0);
        self.buffer_views.push(json!({"buffer": 0, "byteOffset": offset, "byteLength": data.len() * 2}));
        let count = data.len() / components;
        self.accessors.push(json!({"bufferView": self.buffer_views.len() - 1, "componentType": 5123, "count": count, "type": kind}));
        self.accessors.len() - 1
    }

    /// Sets the translation of `node`.
    pub fn set_node_translation(&mut self, node: usize, translation: [f32; 3]) {
        self.nodes[node]["translation"] = json!(translation);
    }

    /// Sets the default morph target weights of `node`.
    pub fn set_node_weights(&mut self, node: usize, weights: &[f32]) {
        self.nodes[node]["weights"] = json!(weights);
    }

    /// Adds a node (a glTF node object) and returns its index.
    pub fn node(&mut self, node: Value) -> usize {
        self.nodes.push(node);
        self.nodes.len() - 1
    }

    /// Gives `node` the skin of `joints` (nodes) with `inverse_bind` matrices (column-major, one
    /// per joint; none: identities), and the last mesh's primitive `JOINTS_0` and `WEIGHTS_0`
    /// (four per vertex).
    pub fn skin(
        &mut self,
        node: usize,
        joints: &[usize],
        inverse_bind: Option<&[[f32; 16]]>,
        vertex_joints: &[u16],
        weights: &[f32],
    ) {
        let mut skin = json!({"joints": joints});
        if let Some(matrices) = inverse_bind {
            let flat: Vec<f32> = matrices.iter().flatten().copied().collect();
            skin["inverseBindMatrices"] = json!(self.add_accessor(&flat, 16, "MAT4"));
        }
        self.skins.push(skin);
        self.nodes[node]["skin"] = json!(self.skins.len() - 1);
        let joints = self.add_u16_accessor(vertex_joints, 4, "VEC4");
        let weights = self.add_accessor(weights, 4, "VEC4");
        let primitive = &mut self.meshes.last_mut().unwrap()["primitives"][0];
        primitive["attributes"]["JOINTS_0"] = json!(joints);
        primitive["attributes"]["WEIGHTS_0"] = json!(weights);
    }

    /// Adds a morph target of position offsets (three per vertex) to the last mesh's primitive.
    pub fn morph_target(&mut self, offsets: &[f32]) {
        let accessor = self.add_accessor(offsets, 3, "VEC3");
        let primitive = &mut self.meshes.last_mut().unwrap()["primitives"][0];
        match primitive["targets"].as_array_mut() {
            Some(targets) => targets.push(json!({"POSITION": accessor})),
            None => primitive["targets"] = json!([{"POSITION": accessor}]),
        }
    }

    /// Adds a morph target to the last mesh as Blender's exporter can write one: its POSITION
    /// offsets a sparse accessor without a `bufferView` (every vertex listed among the sparse
    /// values), its NORMAL offsets an accessor with neither (zeros, as glTF reads it).
    pub fn sparse_morph_target(&mut self, offsets: &[f32]) {
        let values = self.add_accessor(offsets, 3, "VEC3");
        let values_view = self.accessors[values]["bufferView"].clone();
        let count = offsets.len() / 3;
        let offset = self.buffer.len();
        self.buffer.extend((0..count).map(|i| i as u8));
        self.buffer.resize(self.buffer.len().div_ceil(4) * 4, 0);
        self.buffer_views.push(json!({"buffer": 0, "byteOffset": offset, "byteLength": count}));
        let indices_view = self.buffer_views.len() - 1;
        let accessor = &mut self.accessors[values];
        accessor.as_object_mut().unwrap().remove("bufferView");
        accessor["sparse"] = json!({"count": count, "indices": {"bufferView": indices_view, "componentType": 5121},
            "values": {"bufferView": values_view}});
        self.accessors.push(json!({"componentType": 5126, "count": count, "type": "VEC3"}));
        let normals = self.accessors.len() - 1;
        let target = json!({"POSITION": values, "NORMAL": normals});
        let primitive = &mut self.meshes.last_mut().unwrap()["primitives"][0];
        match primitive["targets"].as_array_mut() {
            Some(targets) => targets.push(target),
            None => primitive["targets"] = json!([target]),
        }
    }

    /// Animates the morph target weights of `node` with keys at `times` and `weights` (every
    /// target's weight at each key, key after key), interpolated linearly.
    pub fn animate_weights(&mut self, node: usize, times: &[f32], weights: &[f32]) {
        let input = self.add_accessor(times, 1, "SCALAR");
        self.accessors[input]["min"] = json!([times[0]]);
        self.accessors[input]["max"] = json!([times[times.len() - 1]]);
        let output = self.add_accessor(weights, 1, "SCALAR");
        self.animations.push(json!({
            "channels": [{"sampler": 0, "target": {"node": node, "path": "weights"}}],
            "samplers": [{"input": input, "output": output, "interpolation": "LINEAR"}]
        }));
    }

    /// Adds a material (a glTF material object) and returns its index.
    pub fn material(&mut self, material: Value) -> usize {
        self.materials.push(material);
        self.materials.len() - 1
    }

    /// The index of the node added last.
    pub fn last_node(&self) -> usize {
        self.nodes.len() - 1
    }

    /// Animates `path` ("translation", "rotation" or "scale") of `node` with keys at `times`
    /// (seconds) and `values` (3 or 4 numbers each, three per key for CUBICSPLINE).
    pub fn animate(
        &mut self,
        node: usize,
        path: &str,
        times: &[f32],
        values: &[Vec<f32>],
        interpolation: &str,
    ) {
        let input = self.add_accessor(times, 1, "SCALAR");
        self.accessors[input]["min"] = json!([times[0]]);
        self.accessors[input]["max"] = json!([times[times.len() - 1]]);
        let width = values[0].len();
        let flat: Vec<f32> = values.iter().flatten().copied().collect();
        let output = self.add_accessor(&flat, width, if width == 4 { "VEC4" } else { "VEC3" });
        self.animations.push(json!({
            "channels": [{"sampler": 0, "target": {"node": node, "path": path}}],
            "samplers": [{"input": input, "output": output, "interpolation": interpolation}]
        }));
    }

    /// Animates the value at JSON `pointer` (`KHR_animation_pointer`) with keys at `times`
    /// (seconds), `values` a key each (one to four floats).
    pub fn animate_pointer(
        &mut self,
        pointer: &str,
        times: &[f32],
        values: &[Vec<f32>],
        interpolation: &str,
    ) {
        let input = self.add_accessor(times, 1, "SCALAR");
        let width = values[0].len();
        let flat: Vec<f32> = values.iter().flatten().copied().collect();
        let kind = ["SCALAR", "VEC2", "VEC3", "VEC4"][width - 1];
        let output = self.add_accessor(&flat, width, kind);
        self.animations.push(json!({
            "channels": [{"sampler": 0, "target": {"path": "pointer",
                "extensions": {"KHR_animation_pointer": {"pointer": pointer}}}}],
            "samplers": [{"input": input, "output": output, "interpolation": interpolation}]
        }));
    }

    /// Sets node `node`'s transform (`translation`, `rotation`, `scale` fields).
    pub fn set_node_transform(&mut self, node: usize, transform: Value) {
        for (key, value) in transform.as_object().unwrap() {
            self.nodes[node][key] = value.clone();
        }
    }

    /// Takes node `node`'s mesh away (the node stays).
    pub fn remove_mesh(&mut self, node: usize) {
        self.nodes[node].as_object_mut().unwrap().remove("mesh");
    }

    /// Adds `child` as a child of node `parent` (not a root of the scene) and returns its index.
    pub fn child_node(&mut self, parent: usize, child: Value) -> usize {
        self.nodes.push(child);
        let index = self.nodes.len() - 1;
        let children = self.nodes[parent]["children"].as_array().cloned().unwrap_or_default();
        self.nodes[parent]["children"] =
            json!(children.into_iter().chain([json!(index)]).collect::<Vec<_>>());
        self.children.insert(index);
        index
    }

    /// Makes node `node` draw its mesh once per instance (`EXT_mesh_gpu_instancing`), at each
    /// translation, rotation (quaternion) and scale within the node.
    pub fn instance(
        &mut self,
        node: usize,
        translations: &[[f32; 3]],
        rotations: &[[f32; 4]],
        scales: &[[f32; 3]],
    ) {
        let t = self.add_accessor(&translations.concat(), 3, "VEC3");
        let r = self.add_accessor(&rotations.concat(), 4, "VEC4");
        let s = self.add_accessor(&scales.concat(), 3, "VEC3");
        self.nodes[node]["extensions"] =
            json!({"EXT_mesh_gpu_instancing": {"attributes": {"TRANSLATION": t, "ROTATION": r, "SCALE": s}}});
    }

    /// Adds an image file (relative `uri`) as a texture and returns the texture's index.
    pub fn texture(&mut self, uri: &str) -> usize {
        self.image(json!({"uri": uri}))
    }

    /// Adds an image (its glTF object: `uri`, `name`, `extras`) as a texture and returns the
    /// texture's index.
    pub fn image(&mut self, image: Value) -> usize {
        self.images.push(image);
        self.images.len() - 1
    }

    /// Adds a non-indexed triangle mesh with texture coordinates (three per triangle).
    pub fn mesh_with_uvs(
        &mut self,
        name: &str,
        triangles: &[[[f32; 3]; 3]],
        uvs: &[[f32; 2]],
        material: usize,
    ) {
        self.mesh(name, triangles, material);
        let flat: Vec<f32> = uvs.iter().flatten().copied().collect();
        let uv = self.add_accessor(&flat, 2, "VEC2");
        self.meshes.last_mut().unwrap()["primitives"][0]["attributes"]["TEXCOORD_0"] = json!(uv);
    }

    /// Gives the last mesh's primitive the float attribute `name` (`components` per vertex, glTF
    /// accessor type `kind`).
    pub fn attribute(&mut self, name: &str, values: &[f32], components: usize, kind: &str) {
        let accessor = self.add_accessor(values, components, kind);
        self.meshes.last_mut().unwrap()["primitives"][0]["attributes"][name] = json!(accessor);
    }

    /// Adds a non-indexed triangle mesh (flat normals) with `material`.
    pub fn mesh(&mut self, name: &str, triangles: &[[[f32; 3]; 3]], material: usize) {
        let mut positions = Vec::new();
        let mut normals = Vec::new();
        for t in triangles {
            let [a, b, c] = t.map(glam::Vec3::from);
            let n = (b - a).cross(c - a).normalize();
            for v in [a, b, c] {
                positions.extend(v.to_array());
                normals.extend(n.to_array());
            }
        }
        let position = self.add_accessor(&positions, 3, "VEC3");
        let normal = self.add_accessor(&normals, 3, "VEC3");
        self.meshes.push(json!({"name": name, "primitives": [{"attributes": {"POSITION": position, "NORMAL": normal}, "material": material}]}));
        self.nodes.push(json!({"name": name, "mesh": self.meshes.len() - 1}));
    }

    /// Adds a UV sphere (`rings` x 2 `rings` facets) with smooth normals.
    pub fn sphere(&mut self, name: &str, centre: [f32; 3], radius: f32, rings: usize, material: usize) {
        let point = |ring: usize, segment: usize| {
            let theta = std::f32::consts::PI * ring as f32 / rings as f32;
            // The seam's last segment is the first again, so the mesh closes exactly.
            let phi = std::f32::consts::PI * (segment % (2 * rings)) as f32 / rings as f32;
            glam::Vec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin())
        };
        let (mut positions, mut normals) = (Vec::new(), Vec::new());
        for ring in 0..rings {
            for segment in 0..2 * rings {
                let [a, b, c, d] = [
                    point(ring, segment),
                    point(ring + 1, segment),
                    point(ring + 1, segment + 1),
                    point(ring, segment + 1),
                ];
                // The first ring's second triangle and the last ring's first meet at a pole.
                let first = if ring + 1 < rings { &[a, c, b][..] } else { &[][..] };
                let second = if ring > 0 { &[a, d, c][..] } else { &[][..] };
                for &n in first.iter().chain(second) {
                    positions.extend((glam::Vec3::from(centre) + n * radius).to_array());
                    normals.extend(n.to_array());
                }
            }
        }
        let position = self.add_accessor(&positions, 3, "VEC3");
        let normal = self.add_accessor(&normals, 3, "VEC3");
        self.meshes.push(json!({"name": name, "primitives": [{"attributes": {"POSITION": position, "NORMAL": normal}, "material": material}]}));
        self.nodes.push(json!({"name": name, "mesh": self.meshes.len() - 1}));
    }

    /// Adds an axis-aligned quad at height `y` spanning `[-half, half]` in x and z, facing `+y`
    /// (or `-y` when `up` is false).
    pub fn quad_y(&mut self, name: &str, y: f32, half: f32, up: bool, material: usize) {
        let [a, b, c, d] = [[-half, y, -half], [-half, y, half], [half, y, half], [half, y, -half]];
        let triangles = if up { [[a, b, c], [a, c, d]] } else { [[a, c, b], [a, d, c]] };
        self.mesh(name, &triangles, material);
    }

    /// Adds a perspective camera at `position` looking along `dir`.
    pub fn camera(&mut self, position: [f32; 3], dir: [f32; 3], yfov: f32) {
        self.camera_with_aspect(position, dir, yfov, 1.0);
    }

    /// Adds a perspective camera of aspect ratio `aspect` at `position` looking along `dir`.
    pub fn camera_with_aspect(&mut self, position: [f32; 3], dir: [f32; 3], yfov: f32, aspect: f32) {
        let camera = json!({"type": "perspective", "perspective": {"yfov": yfov, "znear": 0.01, "aspectRatio": aspect}});
        self.camera_of(camera, position, dir);
    }

    /// Adds the glTF camera `camera` at `position` looking along `dir`.
    pub fn camera_of(&mut self, camera: Value, position: [f32; 3], dir: [f32; 3]) {
        self.cameras.push(camera);
        self.nodes.push(json!({"name": "Camera", "camera": self.cameras.len() - 1, "translation": position, "rotation": look_rotation(dir)}));
    }

    /// Adds a `KHR_lights_punctual` light (a light object) at `position` pointing along `dir`.
    pub fn light(&mut self, light: Value, position: [f32; 3], dir: [f32; 3]) {
        self.lights.push(light);
        self.nodes.push(json!({
            "name": format!("Light{}", self.lights.len()),
            "translation": position,
            "rotation": look_rotation(dir),
            "extensions": {"KHR_lights_punctual": {"light": self.lights.len() - 1}}
        }));
    }

    /// Adds a node with `caustic` extras (for example an area light) at `position` pointing along `dir`.
    pub fn extras_node(&mut self, name: &str, caustic: Value, position: [f32; 3], dir: [f32; 3]) {
        self.nodes.push(json!({"name": name, "translation": position, "rotation": look_rotation(dir), "extras": {"caustic": caustic}}));
    }

    /// Sets node `node`'s `caustic` extras.
    pub fn set_node_extras(&mut self, node: usize, caustic: Value) {
        self.nodes[node]["extras"] = json!({"caustic": caustic});
    }

    /// Sets the scene's `caustic` extras.
    pub fn scene_extras(&mut self, caustic: Value) {
        self.scene_extras = Some(json!({"caustic": caustic}));
    }

    /// The glTF JSON, with the buffer embedded as a data URI.
    pub fn to_json(&self) -> Value {
        let uri = format!(
            "data:application/octet-stream;base64,{}",
            base64::engine::general_purpose::STANDARD.encode(&self.buffer)
        );
        let mut doc = json!({
            "asset": {"version": "2.0", "generator": "caustic tests"},
            "scene": 0,
            "scenes": [{"nodes": (0..self.nodes.len()).filter(|n| !self.children.contains(n)).collect::<Vec<_>>()}],
            "nodes": self.nodes,
            "meshes": self.meshes,
            "materials": self.materials,
            "accessors": self.accessors,
            "bufferViews": self.buffer_views,
            "buffers": [{"byteLength": self.buffer.len(), "uri": uri}],
            "cameras": self.cameras,
        });
        let mut used: std::collections::BTreeSet<String> = self
            .materials
            .iter()
            .filter_map(|m| m["extensions"].as_object())
            .flat_map(|e| e.keys().cloned())
            .collect();
        if !self.lights.is_empty() {
            used.insert("KHR_lights_punctual".into());
            doc["extensions"] = json!({"KHR_lights_punctual": {"lights": self.lights}});
        }
        let pointers = self.animations.iter().flat_map(|a| a["channels"].as_array().unwrap());
        if pointers.into_iter().any(|c| c["target"]["path"] == "pointer") {
            used.insert("KHR_animation_pointer".into());
        }
        if self.nodes.iter().any(|n| !n["extensions"]["EXT_mesh_gpu_instancing"].is_null()) {
            used.insert("EXT_mesh_gpu_instancing".into());
        }
        if !used.is_empty() {
            doc["extensionsUsed"] = json!(used);
        }
        if !self.animations.is_empty() {
            doc["animations"] = json!(self.animations);
        }
        if !self.skins.is_empty() {
            doc["skins"] = json!(self.skins);
        }
        if !self.images.is_empty() {
            doc["images"] = json!(self.images);
            doc["textures"] = json!((0..self.images.len()).map(|i| json!({"source": i})).collect::<Vec<_>>());
        }
        if let Some(extras) = &self.scene_extras {
            doc["scenes"][0]["extras"] = extras.clone();
        }
        doc
    }

    /// Writes the scene as a binary `dir/name.glb` (the buffer in the BIN chunk) and returns the path.
    pub fn write_glb(&self, dir: &Path, name: &str) -> PathBuf {
        let mut doc = self.to_json();
        doc["buffers"][0].as_object_mut().unwrap().remove("uri");
        let mut json = serde_json::to_vec(&doc).unwrap();
        json.resize(json.len().div_ceil(4) * 4, b' ');
        let mut bin = self.buffer.clone();
        bin.resize(bin.len().div_ceil(4) * 4, 0);
        let total = 12 + 8 + json.len() + 8 + bin.len();
        let mut out = Vec::with_capacity(total);
        for word in [0x4654_6C67u32, 2, total as u32, json.len() as u32, 0x4E4F_534A] {
            out.extend_from_slice(&word.to_le_bytes());
        }
        out.extend_from_slice(&json);
        for word in [bin.len() as u32, 0x004E_4942] {
            out.extend_from_slice(&word.to_le_bytes());
        }
        out.extend_from_slice(&bin);
        let path = dir.join(format!("{name}.glb"));
        std::fs::write(&path, out).unwrap();
        path
    }

    /// Writes the scene to `dir/name.gltf` and returns the path.
    pub fn write(&self, dir: &Path, name: &str) -> PathBuf {
        let path = dir.join(format!("{name}.gltf"));
        std::fs::write(&path, serde_json::to_string_pretty(&self.to_json()).unwrap()).unwrap();
        path
    }
}

/// A floor lit by a point light and an area light, three instances of a glowing square and two of
/// a grey box (`EXT_mesh_gpu_instancing`) and a camera, with their values animated: the light's intensity and colour, the square's emission strength and the
/// camera's field of view by `KHR_animation_pointer`, the area light's power by the
/// `caustic.tracks` extras. The hostile-input suite breaks it and the fuzzer mutates it.
pub fn animated_values() -> Value {
    let mut gltf = GltfBuilder::default();
    let grey = gltf.material(diffuse([0.5, 0.5, 0.5]));
    gltf.quad_y("Floor", 0.0, 2.0, true, grey);
    let glow = gltf.material(json!({"name": "Glow", "emissiveFactor": [1.0, 0.8, 0.6],
        "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 2.0}}}));
    gltf.quad_y("Glow", 0.01, 0.3, true, glow);
    let squares = gltf.last_node();
    let turn = glam::Quat::from_rotation_y(0.5).to_array();
    let identity = [0.0, 0.0, 0.0, 1.0];
    let scales = [[1.0; 3], [0.5; 3], [-1.0, 1.0, 1.0]];
    gltf.instance(squares, &[[0.0; 3], [0.7, 0.0, 0.0], [-0.7, 0.0, 0.3]], &[identity, turn, turn], &scales);
    gltf.light(json!({"type": "point", "intensity": 100.0}), [0.8, 1.5, 0.0], [0.0, -1.0, 0.0]);
    let area =
        json!({"area_light": {"shape": "SQUARE", "size": 0.5, "power": 20.0, "color": [1.0, 1.0, 1.0]}});
    gltf.extras_node("Area", area, [-0.8, 1.5, 0.0], [0.0, -1.0, 0.0]);
    let area = gltf.last_node();
    gltf.camera([0.0, 4.0, 0.01], [0.0, -1.0, 0.0], 0.9);
    // Still grey boxes, drawn through the two-level BVH (the glowing squares are expanded).
    gltf.mesh("Box", &box_triangles([-0.1, 0.0, -0.1], [0.1, 0.2, 0.1]), grey);
    let boxes = gltf.last_node();
    gltf.instance(
        boxes,
        &[[1.2, 0.0, 1.2], [-1.2, 0.0, -1.2]],
        &[identity, turn],
        &[[1.0; 3], [1.5, 1.0, 0.7]],
    );
    let times = [0.0, 1.0];
    let pair = |a: f32, b: f32| [vec![a], vec![b]];
    gltf.animate_pointer(
        "/extensions/KHR_lights_punctual/lights/0/intensity",
        &times,
        &pair(100.0, 400.0),
        "LINEAR",
    );
    gltf.animate_pointer(
        "/extensions/KHR_lights_punctual/lights/0/color",
        &times,
        &[vec![1.0, 1.0, 1.0], vec![1.0, 0.5, 0.2]],
        "STEP",
    );
    let strength = format!("/materials/{glow}/extensions/KHR_materials_emissive_strength/emissiveStrength");
    gltf.animate_pointer(&strength, &times, &pair(2.0, 6.0), "LINEAR");
    gltf.animate_pointer("/cameras/0/perspective/yfov", &times, &pair(0.9, 0.5), "LINEAR");
    gltf.scene_extras(
        json!({"fps": 24.0, "tracks": [{"pointer": format!("/nodes/{area}/extras/caustic/area_light/power"),
        "times": times, "values": [20.0, 60.0]}]}),
    );
    gltf.to_json()
}

/// A lit floor and a skinned square (two joints, one animated) with a morph target whose weight
/// is animated: the hostile-input suite breaks it one piece at a time and the fuzzer mutates it.
pub fn deformed_square() -> Value {
    let mut gltf = GltfBuilder::default();
    let white = gltf.material(diffuse([0.8, 0.8, 0.8]));
    gltf.quad_y("Floor", 0.0, 2.0, true, white);
    let square = [
        [[-0.2, 0.1, -0.2], [0.2, 0.1, -0.2], [0.2, 0.1, 0.2]],
        [[-0.2, 0.1, -0.2], [0.2, 0.1, 0.2], [-0.2, 0.1, 0.2]],
    ];
    gltf.mesh("Square", &square, white);
    let mesh_node = gltf.last_node();
    gltf.morph_target(&[0.0, 0.5, 0.0].repeat(6));
    gltf.animate_weights(mesh_node, &[0.0, 1.0], &[0.0, 1.0]);
    let bone = gltf.node(json!({"name": "Bone"}));
    gltf.animate(
        bone,
        "rotation",
        &[0.0, 1.0],
        &[vec![0.0, 0.0, 0.0, 1.0], vec![0.0, 0.383, 0.0, 0.924]],
        "LINEAR",
    );
    let root = gltf.node(json!({"name": "Root"}));
    let identity = glam::Mat4::IDENTITY.to_cols_array();
    gltf.skin(
        mesh_node,
        &[bone, root],
        Some(&[identity, identity]),
        &[0u16, 1, 0, 0].repeat(6),
        &[0.7f32, 0.3, 0.0, 0.0].repeat(6),
    );
    gltf.light(json!({"type": "point", "intensity": 50.0}), [0.0, 1.0, 0.0], [0.0, -1.0, 0.0]);
    gltf.camera([0.0, 2.0, 0.0], [0.0, -1.0, 0.0], 0.8);
    gltf.to_json()
}

/// A Lambertian glTF material of linear colour `rgb` (no specular layer: `KHR_materials_specular`
/// with a factor of 0, as Blender writes a Principled BSDF whose Specular IOR Level is 0).
pub fn diffuse(rgb: [f32; 3]) -> Value {
    json!({"pbrMetallicRoughness": {"baseColorFactor": [rgb[0], rgb[1], rgb[2], 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0},
        "extensions": {"KHR_materials_specular": {"specularFactor": 0.0}}})
}

/// Loads a `.gltf` file as JSON, for tests that edit a bundled scene.
pub fn load_json(path: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// Writes an edited copy of a bundled `.gltf` scene (and its `.bin`) into `dir`.
pub fn write_edited(original: &Path, dir: &Path, edit: impl FnOnce(&mut Value)) -> PathBuf {
    let mut doc = load_json(original);
    edit(&mut doc);
    for buffer in doc["buffers"].as_array().unwrap() {
        let uri = buffer["uri"].as_str().unwrap();
        std::fs::copy(original.parent().unwrap().join(uri), dir.join(uri)).unwrap();
    }
    let path = dir.join(original.file_name().unwrap());
    std::fs::write(&path, serde_json::to_string(&doc).unwrap()).unwrap();
    path
}

/// Writes `image` as an RGB EXR (for references and failure reports).
pub fn write_image(path: &Path, image: &Image) {
    let (w, h) = (image.width, image.height);
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    exr::prelude::write_rgb_file(path, w, h, |x, y| {
        let c = image.rgb[y * w + x];
        (c[0] as f32, c[1] as f32, c[2] as f32)
    })
    .unwrap();
}

/// The image averaged over `block` x `block` pixel blocks.
pub fn block_means(image: &Image, block: usize) -> Image {
    let (width, height) = (image.width / block, image.height / block);
    let rgb = (0..width * height)
        .map(|i| {
            let (x, y) = ((i % width) * block, (i / width) * block);
            image.mean(x, x + block, y, y + block)
        })
        .collect();
    Image { width, height, rgb }
}

/// Compares `image` (rendered with `passes` passes) with `tests/references/NAME.exr`, which
/// holds its 8x8 block means (a small file).
///
/// Each block's luminance must be within `2 / sqrt(passes)` of the reference's, relative, or
/// 0.002 absolute for dark blocks: SPPM noise falls at least as fast as 1 / sqrt(passes), so the
/// tolerance shrinks with the pass count. On failure the image, the reference and their absolute
/// difference (per block) are written to `tests/failures/NAME/` and named in the message. With
/// `CAUSTIC_BLESS=1` the image becomes the new reference instead.
pub fn assert_matches_reference(name: &str, image: &Image, passes: u64) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests");
    let reference_path = root.join("references").join(format!("{name}.exr"));
    let blocks = block_means(image, 8);
    if std::env::var("CAUSTIC_BLESS").as_deref() == Ok("1") {
        write_image(&reference_path, &blocks);
        return;
    }
    let reference = read_exr(&reference_path);
    assert_eq!(
        (reference.width, reference.height),
        (blocks.width, blocks.height),
        "{name}: size differs from its reference"
    );
    let relative = 2.0 / (passes as f64).sqrt();
    let mut failures = Vec::new();
    for i in 0..blocks.rgb.len() {
        let (x, y) = (i % blocks.width, i / blocks.width);
        let (a, b) = (blocks.luminance(x, x + 1, y, y + 1), reference.luminance(x, x + 1, y, y + 1));
        if (a - b).abs() > (relative * b).max(0.002) {
            failures.push(format!("block ({x}, {y}): {a:.4} vs reference {b:.4}"));
        }
    }
    if failures.is_empty() {
        return;
    }
    let folder = root.join("failures").join(name);
    write_image(&folder.join("image.exr"), image);
    write_image(&folder.join("reference.exr"), &reference);
    let difference = Image {
        width: blocks.width,
        height: blocks.height,
        rgb: blocks
            .rgb
            .iter()
            .zip(&reference.rgb)
            .map(|(a, b)| [0, 1, 2].map(|c| (a[c] - b[c]).abs()))
            .collect(),
    };
    write_image(&folder.join("difference.exr"), &difference);
    panic!(
        "{name}: {} blocks differ from {} beyond {:.1}% (the tolerance for {passes} passes); image, reference and difference written to {}: {}",
        failures.len(),
        reference_path.display(),
        relative * 100.0,
        folder.display(),
        failures.iter().take(5).cloned().collect::<Vec<_>>().join("; ")
    );
}

/// The 12 triangles of the axis-aligned box from `lo` to `hi`, counter-clockwise from outside.
pub fn box_triangles(lo: [f32; 3], hi: [f32; 3]) -> Vec<[[f32; 3]; 3]> {
    let p = |x: usize, y: usize, z: usize| [[lo[0], hi[0]][x], [lo[1], hi[1]][y], [lo[2], hi[2]][z]];
    let quads = [
        [p(0, 0, 0), p(0, 0, 1), p(0, 1, 1), p(0, 1, 0)],
        [p(1, 0, 0), p(1, 1, 0), p(1, 1, 1), p(1, 0, 1)],
        [p(0, 0, 0), p(1, 0, 0), p(1, 0, 1), p(0, 0, 1)],
        [p(0, 1, 0), p(0, 1, 1), p(1, 1, 1), p(1, 1, 0)],
        [p(0, 0, 0), p(0, 1, 0), p(1, 1, 0), p(1, 0, 0)],
        [p(0, 0, 1), p(1, 0, 1), p(1, 1, 1), p(0, 1, 1)],
    ];
    quads.iter().flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]).collect()
}

/// Every channel of a one-part EXR, by name.
pub fn exr_channels(path: &Path) -> Vec<(String, Vec<f32>)> {
    let image = exr::prelude::read_all_flat_layers_from_file(path).unwrap();
    let layer = &image.layer_data[0];
    layer
        .channel_data
        .list
        .iter()
        .map(|c| (c.name.to_string(), c.sample_data.values_as_f32().collect()))
        .collect()
}

/// Serialises the making of Python environments between the tests of one file.
static PYTHON_ENVS: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// A Python virtual environment `target/NAME` holding `packages`, made with `python` (such as
/// `python3.11`) and pip the first time; gives its interpreter.
pub fn python_env(name: &str, python: &str, packages: &[&str]) -> PathBuf {
    let _guard = PYTHON_ENVS.lock().unwrap_or_else(|e| e.into_inner());
    let target = Path::new(env!("CARGO_BIN_EXE_caustic")).ancestors().nth(2).expect("target folder");
    let venv = target.join(name);
    let interpreter = venv.join("bin").join("python");
    let ready = venv.join(format!("ready-{}", packages.join("-")));
    if !ready.exists() {
        eprintln!("installing {} into {} (once)", packages.join(", "), venv.display());
        let made = Command::new(python).args(["-m", "venv"]).arg(&venv).status();
        assert!(made.is_ok_and(|s| s.success()), "cannot create {}", venv.display());
        let installed =
            Command::new(&interpreter).args(["-m", "pip", "install", "--quiet"]).args(packages).status();
        assert!(installed.is_ok_and(|s| s.success()), "cannot install {}", packages.join(", "));
        std::fs::write(&ready, "").expect("mark the environment ready");
    }
    interpreter
}

/// Whether `program --version` runs.
pub fn available(program: &str) -> bool {
    Command::new(program).arg("--version").output().is_ok_and(|o| o.status.success())
}

/// Prints what a helper program said, and fails the test with it when the program failed.
pub fn assert_succeeded(output: Output, what: &str) {
    let text =
        format!("{}{}", String::from_utf8_lossy(&output.stdout), String::from_utf8_lossy(&output.stderr));
    eprintln!("{text}");
    assert!(output.status.success(), "{what} failed:\n{text}");
}
