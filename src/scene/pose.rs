//! Posing a [`Description`] at a time: the fixed part once per time range, the moving part per
//! time (docs/design.md, "Frames, and reuse across frames": static geometry is built once per range, moving objects per time).
//!
//! A mesh, light or camera is moving over a range when its node or an ancestor has a track whose
//! value changes within it (a mesh also when a joint of its skin moves or its morph target weights
//! vary: [`super::deform`]); everything else is flattened to world space once and shared (`Arc`)
//! by every pose. A scene with nothing moving is posed once and never again.

use std::borrow::Cow;
use std::sync::Arc;

use glam::{Mat3, Mat4, Vec3};

use super::animation::Rig;
use super::deform::{Deformation, Vertices};
use super::description::{Description, Lens, LensSettings, MeshInstance, PunctualKind, PunctualLight};
use super::instancing::Instances;
use super::{
    bounding_sphere, Geometry, OpenEdges, OpenSides, Scene, TriangleRef, DEFAULT_RADIUS_FRACTION, NOT_A_LIGHT,
};
use crate::accel::{BuildFor, Bvh, InstancedBvh};
use crate::camera::Camera;
use crate::lights::{
    Beam, BoundingSphere, CutEmission, Emission, EmittingTriangle, Light, LightTree, SphereLight,
    TexturedEmission,
};
use crate::materials::Material;
use crate::sampling::Distribution1D;

/// A span of glTF time, in seconds, that a render covers (frames and their shutters).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TimeRange {
    /// The earliest time.
    pub start: f32,
    /// The latest time.
    pub end: f32,
}

impl TimeRange {
    /// The single instant `time`.
    pub fn at(time: f32) -> Self {
        TimeRange { start: time, end: time }
    }
}

/// A description made ready for a time range: its fixed part built, its moving parts listed.
#[derive(Debug)]
pub struct Prepared {
    /// What the file says.
    pub description: Arc<Description>,
    /// The range it is ready for.
    pub range: TimeRange,
    fixed: Arc<Geometry>,
    /// The still nodes' instances, each mesh kept once.
    instances: Arc<Instances>,
    fixed_lights: Vec<Light>,
    /// The powers by which photons choose the fixed lights: an animated light's at its peak, so
    /// that the choice is the same whatever range a render covers (reuse across frames).
    fixed_choice_powers: Vec<f64>,
    /// The materials emitting at their peaks, where any emission is animated.
    peak_materials: Option<Vec<Material>>,
    fixed_triangle_lights: Arc<Vec<u32>>,
    open_edges: Arc<OpenEdges>,
    /// The moving triangles' open sides, found in their pose at the range's start.
    moving_open_sides: OpenSides,
    moving_meshes: Vec<usize>,
    moving_lights: Vec<usize>,
    camera_moves: bool,
    lens: Option<Lens>,
    /// The materials at the range's start.
    materials: Arc<Vec<Material>>,
    /// The materials whose animated values change within the range.
    varying_materials: Vec<usize>,
    sphere: BoundingSphere,
}

/// Flattens `mesh` with the world matrix `world` into `out`.
pub(super) fn flatten(mesh: &MeshInstance, world: Mat4, out: &mut Geometry) {
    let normal_matrix = Mat3::from_mat4(world).inverse().transpose();
    let mirrored = Mat3::from_mat4(world).determinant() < 0.0;
    let base = out.positions.len() as u32;
    out.positions.extend(mesh.positions.iter().map(|&p| world.transform_point3(p)));
    out.normals.extend(mesh.normals.iter().map(|&n| (normal_matrix * n).normalize_or_zero()));
    out.uvs.extend_from_slice(&mesh.uvs);
    out.extras.append(base as usize, &mesh.extras, mesh.positions.len(), Mat3::from_mat4(world));
    out.triangles.extend(mesh.triangles.iter().map(|t| {
        let [a, b, c] = t.vertices.map(|v| base + v);
        super::TriangleRef { vertices: if mirrored { [a, c, b] } else { [a, b, c] }, material: t.material }
    }));
}

/// `mesh` in its shape at `time`, and the matrix that takes it to world space.
fn posed<'a>(mesh: &'a MeshInstance, rig: &Rig, time: f32) -> (Cow<'a, MeshInstance>, Mat4) {
    let Some(deformation) = &mesh.deformation else {
        return (Cow::Borrowed(mesh), rig.world(mesh.node, time));
    };
    let mut shaped = mesh.clone();
    let vertices = Vertices {
        positions: &mut shaped.positions,
        normals: &mut shaped.normals,
        tangents: &mut shaped.extras.tangents,
    };
    let world = deformation.apply(vertices, rig, mesh.node, time);
    (Cow::Owned(shaped), world)
}

/// `meshes` of `description` flattened in their pose (and shape) at `time`.
fn flatten_at(description: &Description, meshes: &[usize], time: f32) -> Geometry {
    let mut out = Geometry::default();
    for &m in meshes {
        let (mesh, world) = posed(&description.meshes[m], &description.rig, time);
        flatten(&mesh, world, &mut out);
    }
    out
}

/// The triangle lights of `geometry` (numbered from `first_light`), and each triangle's light.
fn triangle_lights(
    geometry: &Geometry,
    materials: &[Material],
    first_light: usize,
) -> (Vec<Light>, Vec<u32>) {
    let mut lights = Vec::new();
    let mut of_triangle = vec![NOT_A_LIGHT; geometry.triangles.len()];
    for (i, (t, corners)) in geometry.triangles.iter().zip(geometry.corners()).enumerate() {
        let material = &materials[t.material as usize];
        if let Some(emission) = emission(geometry, t, material) {
            of_triangle[i] = (first_light + lights.len()) as u32;
            let triangle = EmittingTriangle::new(corners, emission, material.emits_both_sides);
            lights.push(Light::Triangle(triangle.with_spread(material.emission_spread)));
        }
    }
    (lights, of_triangle)
}

/// What triangle `t` of `geometry` emits, if its material emits (where its alpha leaves it).
fn emission(geometry: &Geometry, t: &TriangleRef, material: &Material) -> Option<Emission> {
    let radiance = material.emission?;
    let uvs = || t.vertices.map(|v| geometry.uvs_at(v as usize));
    let emission = match &material.emission_texture {
        None => Emission::Uniform(radiance),
        Some(texture) => {
            Emission::Textured(Box::new(TexturedEmission { texture: texture.clone(), uvs: uvs() }))
        }
    };
    if !material.alpha.cuts() {
        return Some(emission);
    }
    let alphas = &geometry.extras.alphas;
    let vertex_alpha = t.vertices.map(|v| alphas.get(v as usize).copied().unwrap_or(1.0));
    Some(Emission::Cut(Box::new(CutEmission {
        emission,
        alpha: material.alpha.clone(),
        uvs: uvs(),
        vertex_alpha,
    })))
}

/// A punctual light at `time`, posed with its node's world matrix (the sphere is set by the pose).
fn punctual(light: &PunctualLight, rig: &Rig, time: f32) -> Light {
    let world = rig.world(light.node, time);
    let position = world.transform_point3(Vec3::ZERO);
    let axis = world.transform_vector3(-Vec3::Z).normalize();
    let mut kind = Cow::Borrowed(&light.kind);
    if let Some(animation) = &light.animation {
        kind.to_mut().set(&animation.at(time));
    }
    match kind.as_ref() {
        PunctualKind::Sphere(sphere) => Light::Sphere(SphereLight {
            position,
            beam: sphere.beam.map(|beam| Beam { axis, ..beam }),
            ..sphere.clone()
        }),
        PunctualKind::Sun(irradiance, disc) => {
            Light::Sun { direction: axis, irradiance: *irradiance, disc: *disc, sphere: Default::default() }
        }
    }
}

/// The indices of the materials whose animated values change within `range`, and every
/// material at the range's start.
fn materials_at_start(description: &Description, range: TimeRange) -> Vec<Material> {
    let mut materials = description.materials.clone();
    for (m, animation) in &description.material_animations {
        animation.apply(&mut materials[*m], range.start);
    }
    materials
}

/// The indices below `count` that `listed` (in order) does not hold, in order.
fn others(listed: &[usize], count: usize) -> Vec<usize> {
    (0..count).filter(|i| listed.binary_search(i).is_err()).collect()
}

/// What changes within a time range: the meshes that move, deform or take a changing material,
/// the lights that move or change, the materials that change, and the camera.
#[derive(Clone, Debug, PartialEq)]
pub struct Motion {
    /// Meshes (by index) that move, deform or take a changing material.
    pub meshes: Vec<usize>,
    /// Punctual lights (by index) that move or change.
    pub lights: Vec<usize>,
    /// Materials (by index) whose animated values change.
    pub materials: Vec<usize>,
    /// The camera moves or zooms.
    pub camera: bool,
}

impl Motion {
    /// Whether nothing changes.
    pub fn is_still(&self) -> bool {
        self.meshes.is_empty() && self.lights.is_empty() && self.materials.is_empty() && !self.camera
    }

    /// What changes in `description` within `range`.
    pub fn within(description: &Description, range: TimeRange) -> Self {
        let rig = &description.rig;
        let moves = |node: usize| rig.moves_within(node, range.start, range.end);
        let materials: Vec<usize> = description
            .material_animations
            .iter()
            .filter(|(_, animation)| animation.tracks.vary_within(range.start, range.end))
            .map(|(m, _)| *m)
            .collect();
        let mut material_varies = vec![false; description.materials.len()];
        materials.iter().for_each(|&m| material_varies[m] = true);
        let mesh_changes = |mesh: &MeshInstance| {
            let changes = |d: &Deformation| d.changes_within(rig, mesh.node, range.start, range.end);
            let varying_material = mesh.triangles.iter().any(|t| material_varies[t.material as usize]);
            moves(mesh.node) || mesh.deformation.as_deref().is_some_and(changes) || varying_material
        };
        let light_changes = |light: &PunctualLight| {
            let animated =
                light.animation.as_ref().is_some_and(|a| a.tracks.vary_within(range.start, range.end));
            moves(light.node) || animated
        };
        let camera = &description.camera;
        let zooms = camera.animation.as_ref().is_some_and(|a| a.tracks.vary_within(range.start, range.end));
        Motion {
            meshes: (0..description.meshes.len()).filter(|&m| mesh_changes(&description.meshes[m])).collect(),
            lights: (0..description.lights.len())
                .filter(|&l| light_changes(&description.lights[l]))
                .collect(),
            camera: moves(camera.node) || zooms,
            materials,
        }
    }
}

/// Every material with its emission at its peak, if any emission is animated.
fn peak_materials(description: &Description) -> Option<Vec<Material>> {
    let emitting = description.material_animations.iter().filter(|(_, a)| a.may_emit());
    let mut materials = None;
    for (m, animation) in emitting {
        let all = materials.get_or_insert_with(|| description.materials.clone());
        animation.peak(&mut all[*m]);
    }
    materials
}

/// The power of `light` at its peak (at `time`, where only its pose matters; a sun's photons
/// start on `sphere`).
fn peak_power(light: &PunctualLight, rig: &Rig, time: f32, sphere: BoundingSphere) -> f64 {
    let mut kind = light.kind.clone();
    if let Some(animation) = &light.animation {
        kind.set(&animation.peak());
    }
    let mut posed = punctual(&PunctualLight { kind, animation: None, node: light.node }, rig, time);
    if let Light::Sun { sphere: s, .. } = &mut posed {
        *s = sphere;
    }
    posed.power()
}

/// Times at which moving meshes are posed to bound their sweep over a range.
const SWEEP_SAMPLES: usize = 64;

/// Times at which deforming meshes are posed, vertex by vertex, to bound their sweep.
const DEFORMED_SWEEP_SAMPLES: usize = 16;

/// A box around `mesh` posed anywhere in `range`: its local box's corners posed at
/// [`SWEEP_SAMPLES`] + 1 times (a deforming mesh's vertices at [`DEFORMED_SWEEP_SAMPLES`] + 1),
/// grown by a tenth of its diagonal for what turns between them.
fn swept_bounds(description: &Description, mesh: &MeshInstance, range: TimeRange) -> Option<(Vec3, Vec3)> {
    let first = *mesh.positions.first()?;
    let (lo, hi) = mesh.positions.iter().fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p)));
    let corners: Vec<Vec3> =
        (0..8).map(|k| Vec3::select(glam::BVec3::new(k & 1 != 0, k & 2 != 0, k & 4 != 0), hi, lo)).collect();
    let samples = if mesh.deformation.is_some() { DEFORMED_SWEEP_SAMPLES } else { SWEEP_SAMPLES };
    let times = (0..=samples).map(|i| range.start + (range.end - range.start) * i as f32 / samples as f32);
    let posed = times.flat_map(|t| -> Vec<Vec3> {
        let (shaped, world) = posed(mesh, &description.rig, t);
        let points = if mesh.deformation.is_some() { &shaped.positions } else { &corners };
        points.iter().map(|&c| world.transform_point3(c)).collect()
    });
    let (lo, hi) = posed.map(|p| (p, p)).reduce(|(a, b), (c, d)| (a.min(c), b.max(d)))?;
    let margin = Vec3::splat((hi - lo).length() * 0.1);
    Some((lo - margin, hi + margin))
}

/// The thin lens the settings ask for, or `None` for a pinhole.
pub fn lens(settings: Option<LensSettings>, focal_length_mm: f32) -> Option<Lens> {
    let s = settings?;
    (s.fstop > 0.0).then(|| Lens {
        aperture_radius: focal_length_mm / 1000.0 / (2.0 * s.fstop),
        focus_distance: s.focus_distance,
        blades: s.blades,
        blade_rotation: s.blade_rotation_deg.to_radians(),
    })
}

impl Prepared {
    /// Builds the fixed part of `description` for `range`, with the camera's own lens.
    pub fn new(description: Arc<Description>, range: TimeRange) -> Self {
        let camera = &description.camera;
        let lens = lens(camera.lens, camera.focal_length_mm);
        Self::with_lens(description, range, lens)
    }

    /// Builds the fixed part of `description` for `range`, with `lens` on the camera.
    pub fn with_lens(description: Arc<Description>, range: TimeRange, lens: Option<Lens>) -> Self {
        let rig = &description.rig;
        let motion = Motion::within(&description, range);
        let materials = materials_at_start(&description, range);
        let (varying_materials, moving_meshes, moving_lights) =
            (motion.materials, motion.meshes, motion.lights);
        let fixed_meshes = others(&moving_meshes, description.meshes.len());
        let fixed_punctual = others(&moving_lights, description.lights.len());
        let fixed = flatten_at(&description, &fixed_meshes, range.start);
        let mut fixed_lights: Vec<Light> =
            fixed_punctual.iter().map(|&l| punctual(&description.lights[l], rig, range.start)).collect();
        // Distant lights aim their photons at one sphere for the whole range, so that a photon
        // path from the sun is the same in every frame (reuse across frames).
        let swept =
            moving_meshes.iter().filter_map(|&m| swept_bounds(&description, &description.meshes[m], range));
        let instances = Instances::new(&description.instanced, |node| rig.world(node, range.start));
        let sphere = bounding_sphere(fixed.bounds().into_iter().chain(instances.bounds()).chain(swept));
        let peak_materials = peak_materials(&description);
        let fixed_punctual_peaks =
            fixed_punctual.iter().map(|&l| peak_power(&description.lights[l], rig, range.start, sphere));
        let fixed_emitter_peaks = peak_materials.as_ref().map(|peak| triangle_lights(&fixed, peak, 0).0);
        let (emitters, fixed_triangle_lights) = triangle_lights(&fixed, &materials, fixed_lights.len());
        let fixed_emitter_peaks = fixed_emitter_peaks.unwrap_or_else(|| emitters.clone());
        let fixed_choice_powers =
            fixed_punctual_peaks.chain(fixed_emitter_peaks.iter().map(Light::power)).collect();
        fixed_lights.extend(emitters);
        let open_edges = Arc::new(OpenEdges::of(&fixed, sphere.radius * DEFAULT_RADIUS_FRACTION as f32));
        let moving_open_sides = OpenSides::of(&flatten_at(&description, &moving_meshes, range.start));
        Prepared {
            camera_moves: motion.camera,
            materials: Arc::new(materials),
            varying_materials,
            description,
            range,
            fixed: Arc::new(fixed),
            instances: Arc::new(instances),
            fixed_lights,
            fixed_choice_powers,
            peak_materials,
            fixed_triangle_lights: Arc::new(fixed_triangle_lights),
            open_edges,
            moving_open_sides,
            moving_meshes,
            moving_lights,
            lens,
            sphere,
        }
    }

    /// Whether anything moves within the range (else one pose serves every time).
    pub fn has_motion(&self) -> bool {
        !self.moving_meshes.is_empty() || !self.moving_lights.is_empty() || self.camera_moves
    }

    /// Whether the camera moves within the range.
    pub fn camera_moves(&self) -> bool {
        self.camera_moves
    }

    /// Whether lights move (or change) within the range.
    pub fn lights_move(&self) -> bool {
        let may_emit = |m: usize| {
            self.materials[m].emission.is_some()
                || self
                    .description
                    .material_animations
                    .iter()
                    .any(|(a, animation)| *a == m && animation.may_emit())
        };
        !self.moving_lights.is_empty()
            || self.moving_meshes.iter().any(|&m| {
                let mesh = &self.description.meshes[m];
                mesh.triangles.iter().any(|t| may_emit(t.material as usize))
            })
    }

    /// Triangles in the fixed part, and in the moving part.
    pub fn triangle_counts(&self) -> (usize, usize) {
        let moving = self.moving_meshes.iter().map(|&m| self.description.meshes[m].triangles.len()).sum();
        (self.fixed.triangles.len(), moving)
    }

    /// Triangles the instances draw, and those they store.
    pub fn instanced_triangles(&self) -> (usize, usize) {
        (self.instances.triangle_count(), self.instances.stored_triangles())
    }

    /// The instances' two-level BVH (built once), if there are instances.
    pub fn instanced_bvh(&self) -> Option<Arc<InstancedBvh>> {
        self.instances.bvh()
    }

    /// The fixed part's BVH (built once).
    pub fn fixed_bvh(&self) -> Bvh {
        self.fixed.bvh(&self.materials, BuildFor::Range)
    }

    /// The lens on the camera.
    pub fn lens(&self) -> Option<Lens> {
        self.lens
    }

    /// The powers by which photons choose among `powers`' lights at `time` (`moving` the moving
    /// triangles then): animated lights' at their peaks (see `fixed_choice_powers`).
    fn choice_powers(&self, mut powers: Vec<f64>, moving: &Geometry, time: f32) -> Vec<f64> {
        let d = &self.description;
        if self.peak_materials.is_none() && d.lights.iter().all(|l| l.animation.is_none()) {
            return powers;
        }
        let fixed = self.fixed_lights.len();
        powers[..fixed].copy_from_slice(&self.fixed_choice_powers);
        let peak = |l: usize| peak_power(&d.lights[l], &d.rig, time, self.sphere);
        let moving_punctual = self.moving_lights.iter().map(|&l| peak(l));
        // The world, when there is one, is the last light; it keeps its own power.
        let end = powers.len() - usize::from(d.world.is_some());
        let emitters = match &self.peak_materials {
            Some(peak) => triangle_lights(moving, peak, 0).0.iter().map(Light::power).collect(),
            None => powers[fixed + self.moving_lights.len()..end].to_vec(),
        };
        let choice: Vec<f64> = moving_punctual.chain(emitters).collect();
        powers[fixed..end].copy_from_slice(&choice);
        powers
    }

    /// The materials at `time`: those of the range's start, with the varying ones changed.
    fn materials_at(&self, time: f32) -> Arc<Vec<Material>> {
        if self.varying_materials.is_empty() {
            return Arc::clone(&self.materials);
        }
        let mut materials = (*self.materials).clone();
        for (m, animation) in &self.description.material_animations {
            if self.varying_materials.contains(m) {
                animation.apply(&mut materials[*m], time);
            }
        }
        Arc::new(materials)
    }

    /// The camera at `time`: its node's pose, its field of view, and its lens's aperture grown
    /// with the focal length (a zoom keeps the f-number).
    fn camera_at(&self, time: f32) -> Camera {
        let c = &self.description.camera;
        let (projection, zoom) = match &c.animation {
            Some(animation) => animation.projection(c.projection, time),
            None => (c.projection, 1.0),
        };
        let lens = self.lens.map(|l| Lens { aperture_radius: l.aperture_radius * zoom, ..l });
        Camera::from_node(self.description.rig.world(c.node, time), projection, c.shift).with_lens(lens)
    }

    /// The scene at `time` seconds (within the range).
    pub fn pose(&self, time: f32) -> Scene {
        let d = &self.description;
        let moving = flatten_at(d, &self.moving_meshes, time);
        let open_edges = if self.moving_open_sides.is_empty() {
            Arc::clone(&self.open_edges)
        } else {
            Arc::new(self.open_edges.with_moving(&moving, &self.moving_open_sides))
        };
        let mut lights = self.fixed_lights.clone();
        let first_moving_light = lights.len();
        lights.extend(self.moving_lights.iter().map(|&l| punctual(&d.lights[l], &d.rig, time)));
        let materials = self.materials_at(time);
        let (emitters, moving_triangle_lights) = triangle_lights(&moving, &materials, lights.len());
        lights.extend(emitters);
        let moving_lights = first_moving_light..lights.len();
        let sphere = self.sphere;
        let mut distant_lights = Vec::new();
        for (i, light) in lights.iter_mut().enumerate() {
            if let Light::Sun { sphere: s, disc, .. } = light {
                *s = sphere;
                if !disc.is_delta() {
                    distant_lights.push(i);
                }
            }
        }
        let sphere_lights = lights
            .iter()
            .enumerate()
            .filter(|(_, l)| matches!(l, Light::Sphere(s) if s.radius > 0.0))
            .map(|(i, _)| i);
        let sphere_lights = sphere_lights.collect();
        if let Some(world) = &d.world {
            let mut world = world.clone();
            world.sphere = sphere;
            distant_lights.push(lights.len());
            lights.push(Light::World(world));
        }
        let powers: Vec<f64> = lights.iter().map(Light::power).collect();
        let light_tree = Arc::new(LightTree::new(&lights, &powers));
        let light_choice = Arc::new(Distribution1D::new(self.choice_powers(powers, &moving, time)));
        Scene {
            fixed: Arc::clone(&self.fixed),
            instances: Arc::clone(&self.instances),
            moving,
            materials,
            lights,
            fixed_triangle_lights: Arc::clone(&self.fixed_triangle_lights),
            moving_triangle_lights,
            open_edges,
            distant_lights,
            light_tree,
            light_choice,
            sphere_lights,
            moving_lights,
            camera: self.camera_at(time),
            resolution: d.resolution,
            aspect_ratio: d.camera.aspect_ratio,
            transparent_film: d.transparent_film,
            fog: d.fog.clone(),
        }
    }
}
