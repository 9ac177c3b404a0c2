//! The render-ready scene at one time: world-space triangles, materials, lights and the camera.
//!
//! Takes a glTF 2.0 file (`.gltf` with its `.bin`, or `.glb`) plus the `caustic` extras
//! ([`extras`]); [`gltf`] reads it into a time-independent [`Description`]; [`pose`]
//! splits it, for a range of times, into a fixed part (flattened and indexed once) and the moving
//! instances, and poses a [`Scene`] at any time in the range. The accelerator and the SPPM passes
//! read a `Scene` and never change it. Emitting triangles are also lights.

pub mod animation;
mod attributes;
pub mod deform;
pub mod description;
mod edges;
pub mod extras;
mod gltf;
mod instancing;
pub mod pointers;
pub mod pose;
mod shapes;
mod tangents;
pub mod values;

use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{Vec2, Vec3, Vec3A};

use crate::accel::{BuildFor, Bvh, Hit};
use crate::camera::Camera;
use crate::lights::{BoundingSphere, Light, LightTree, SphereLight};
use crate::materials::{Material, ShadingFrame, SurfaceInputs, Volume};
use crate::sampling::Distribution1D;
use crate::spectrum::{SampledSpectrum, Wavelengths};
use crate::texture::UV_SETS;

pub use attributes::VertexExtras;
pub use description::Description;
pub use edges::{OpenEdges, OpenSides};
pub use pose::{Prepared, TimeRange};

/// A scene that cannot be loaded: the file and what is wrong with it.
#[derive(Debug, thiserror::Error)]
#[error("{}: {message}", path.display())]
pub struct SceneError {
    /// The scene file.
    pub path: PathBuf,
    /// What is wrong, naming the mesh, node or field.
    pub message: String,
}

/// The default first gather radius, as a fraction of the radius of the sphere around the scene
/// (smaller with more photons than pixels: `render::default_radius`).
pub const DEFAULT_RADIUS_FRACTION: f64 = 0.04;

/// One triangle: indices into the vertex arrays and its material.
#[derive(Clone, Copy, Debug)]
pub struct TriangleRef {
    /// Vertex indices, counter-clockwise seen from the outside.
    pub vertices: [u32; 3],
    /// Index into the scene's materials.
    pub material: u32,
}

/// World-space triangles with their vertex attributes.
#[derive(Clone, Debug, Default)]
pub struct Geometry {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Unit shading normals (zero where the file has none).
    pub normals: Vec<Vec3>,
    /// Texture coordinates (the first set).
    pub uvs: Vec<Vec2>,
    /// Attributes only some meshes have.
    pub extras: VertexExtras,
    /// The triangles.
    pub triangles: Vec<TriangleRef>,
}

impl Geometry {
    /// The BVH over these triangles, for the use `built_for` says; those of materials light
    /// passes through unchanged (area lights) cast no shadow.
    pub fn bvh(&self, materials: &[Material], built_for: BuildFor) -> Bvh {
        let casts_shadow: Vec<bool> =
            self.triangles.iter().map(|t| !materials[t.material as usize].light_surface).collect();
        Bvh::build(&self.corners(), &casts_shadow, built_for)
    }

    /// The corners of every triangle, in order.
    pub fn corners(&self) -> Vec<[Vec3; 3]> {
        self.triangles.iter().map(|t| t.vertices.map(|v| self.positions[v as usize])).collect()
    }

    /// The surface at `hit` on triangle `i`: the point, geometric normal and scale come with
    /// the hit; the shading normal, texture coordinates and material are looked up here.
    fn surface(&self, i: usize, hit: &Hit, lambda: &Wavelengths) -> Surface {
        self.surface_with_normal(i, hit, lambda, |n| n)
    }

    /// The surface at `hit` on triangle `i`, its interpolated unit normal taken to the hit's space
    /// by `to_hit` (an instance's normal matrix, normalised; the identity otherwise).
    #[inline]
    fn surface_with_normal(
        &self,
        i: usize,
        hit: &Hit,
        lambda: &Wavelengths,
        to_hit: impl Fn(Vec3) -> Vec3,
    ) -> Surface {
        let t = self.triangles[i];
        let [i0, i1, i2] = t.vertices.map(|v| v as usize);
        let b = hit.barycentric;
        let w = [1.0 - b.x - b.y, b.x, b.y];
        let normal = |i: usize| Vec3A::from(self.normals[i]);
        let n = Vec3::from((normal(i0) * w[0] + normal(i1) * w[1] + normal(i2) * w[2]).normalize_or_zero());
        let n = to_hit(n);
        let ng = hit.ng;
        let n = if n == Vec3::ZERO { ng } else { n };
        let uv = self.uvs[i0] * w[0] + self.uvs[i1] * w[1] + self.uvs[i2] * w[2];
        let inputs = self.extras.inputs([i0, i1, i2], Vec3::from(w), uv, lambda);
        Surface { p: hit.p, frame: ShadingFrame::new(n, ng), inputs, material: t.material, scale: hit.scale }
    }

    /// Vertex `v`'s texture coordinates, one pair per set.
    pub fn uvs_at(&self, v: usize) -> [Vec2; UV_SETS] {
        [self.uvs[v], self.extras.uvs1.get(v).copied().unwrap_or(Vec2::ZERO)]
    }

    /// The smallest and largest corner of the finite vertices, or `None` when there are none
    /// (vertices of skipped triangles may be NaN or infinite).
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        let mut finite = self.positions.iter().copied().filter(|p| p.is_finite());
        let first = finite.next()?;
        Some(finite.fold((first, first), |(lo, hi), p| (lo.min(p), hi.max(p))))
    }
}

/// The scene at one time. Triangles are numbered fixed first, then instanced, then moving.
#[derive(Clone, Debug)]
pub struct Scene {
    /// Triangles that do not move over the prepared time range (shared between poses).
    pub fixed: Arc<Geometry>,
    /// Triangles that move, posed at this time.
    pub moving: Geometry,
    /// Meshes drawn by still instances (their triangles numbered after the fixed ones).
    pub instances: Arc<instancing::Instances>,
    /// Materials, indexed by `TriangleRef::material`.
    pub materials: Arc<Vec<Material>>,
    /// Every light, emitting triangles included.
    pub lights: Vec<Light>,
    /// For each fixed triangle, the index in `lights` of its emitter, or [`NOT_A_LIGHT`].
    pub fixed_triangle_lights: Arc<Vec<u32>>,
    /// The same for each moving triangle.
    pub moving_triangle_lights: Vec<u32>,
    /// The open edges of the triangles in this pose (where surfaces end in the open).
    pub open_edges: Arc<OpenEdges>,
    /// Indices in `lights` of the distant lights a ray leaving the scene can see.
    pub distant_lights: Vec<usize>,
    /// The light tree over `lights`, for next-event estimation.
    pub light_tree: Arc<LightTree>,
    /// `lights` in proportion to their luminous power (photons, and next-event estimation without
    /// the tree).
    pub light_choice: Arc<Distribution1D>,
    /// Indices in `lights` of the lights with a sphere that rays can meet.
    pub sphere_lights: Vec<usize>,
    /// Indices in `lights` of the lights that move within the prepared range.
    pub moving_lights: std::ops::Range<usize>,
    /// The camera at this time.
    pub camera: Camera,
    /// The resolution the scene asks for, if it does.
    pub resolution: Option<[u32; 2]>,
    /// The camera's aspect ratio (width / height), if the file gives one.
    pub aspect_ratio: Option<f32>,
    /// The film is transparent where the camera sees the world.
    pub transparent_film: bool,
    /// The medium filling the world outside every closed transmissive mesh, if any.
    pub fog: Option<Volume>,
}

/// The entry of `Scene::triangle_lights` for triangles that emit nothing.
pub const NOT_A_LIGHT: u32 = u32::MAX;

/// A point on a surface, ready for shading.
#[derive(Clone, Copy, Debug)]
pub struct Surface {
    /// Position.
    pub p: Vec3,
    /// Shading and geometric normals.
    pub frame: ShadingFrame,
    /// What the material reads there: texture coordinates, vertex colour, tangent.
    pub inputs: SurfaceInputs,
    /// Index into `Scene::materials`.
    pub material: u32,
    /// The largest coordinate of its triangle's corners (how far rounding can have moved `p`).
    pub scale: f32,
}

impl Scene {
    /// Loads a glTF 2.0 scene and poses it at time 0 (frame 0), for inspection and tests.
    pub fn load(path: &Path) -> Result<Scene, SceneError> {
        let description = Description::load(path)?;
        Ok(Prepared::new(Arc::new(description), TimeRange::at(0.0)).pose(0.0))
    }

    /// The number of triangles, fixed and moving.
    pub fn triangle_count(&self) -> usize {
        self.fixed.triangles.len() + self.moving.triangles.len()
    }

    /// The surface where a ray hit, with what its material reads there at the wavelengths
    /// `lambda`.
    pub fn surface(&self, hit: &Hit, lambda: &Wavelengths) -> Surface {
        match self.part(hit.triangle) {
            Part::Fixed(t) => self.fixed.surface(t, hit, lambda),
            Part::Moving(t) => self.moving.surface(t, hit, lambda),
            Part::Instanced(t) => self.instances.surface(t, hit, lambda),
        }
    }

    /// Which part of the scene `triangle` is in, and its number there: triangles are numbered
    /// fixed first, then instanced (both the same in every pose), then moving.
    #[inline]
    fn part(&self, triangle: u32) -> Part {
        let (fixed, instanced) = (self.fixed.triangles.len(), self.instances.triangle_count());
        match triangle as usize {
            t if t < fixed => Part::Fixed(t),
            t if t < fixed + instanced => Part::Instanced(t - fixed),
            t => Part::Moving(t - fixed - instanced),
        }
    }

    /// The index in `materials` of `triangle`'s material.
    pub fn triangle_material(&self, triangle: u32) -> u32 {
        match self.part(triangle) {
            Part::Fixed(t) => self.fixed.triangles[t].material,
            Part::Moving(t) => self.moving.triangles[t].material,
            Part::Instanced(t) => self.instances.material(t),
        }
    }

    /// The index in `lights` of `triangle`'s emitter, or [`NOT_A_LIGHT`] (instanced meshes
    /// never emit).
    pub fn triangle_light(&self, triangle: u32) -> u32 {
        match self.part(triangle) {
            Part::Fixed(t) => self.fixed_triangle_lights[t],
            Part::Moving(t) => self.moving_triangle_lights[t],
            Part::Instanced(_) => NOT_A_LIGHT,
        }
    }

    /// Radiance that a ray of direction `dir` receives when it leaves the scene.
    pub fn escaped_radiance(&self, dir: Vec3, lambda: &Wavelengths) -> SampledSpectrum {
        self.distant_lights.iter().map(|&i| self.lights[i].escaped_radiance(dir, lambda)).sum()
    }

    /// The sphere lights a ray from `origin` along the unit `direction` meets before `t_max`
    /// (they hide nothing behind them): each one's index in `lights`, the light and the distance.
    pub fn spheres_met(
        &self,
        origin: Vec3,
        direction: Vec3,
        t_max: f32,
    ) -> impl Iterator<Item = (usize, &SphereLight, f32)> + '_ {
        self.sphere_lights.iter().filter_map(move |&i| match &self.lights[i] {
            Light::Sphere(sphere) => sphere.hit(origin, direction, t_max).map(|t| (i, sphere, t)),
            _ => None,
        })
    }

    /// The sphere around every triangle (radius 1 at the origin for an empty scene).
    pub fn bounding_sphere(&self) -> BoundingSphere {
        bounding_sphere(
            [self.fixed.bounds(), self.moving.bounds(), self.instances.bounds()].into_iter().flatten(),
        )
    }
}

/// The part of the scene a triangle is in, with its number there.
enum Part {
    Fixed(usize),
    Moving(usize),
    Instanced(usize),
}

/// The sphere around a set of boxes (radius 1 at the origin when there are none).
pub fn bounding_sphere(boxes: impl Iterator<Item = (Vec3, Vec3)>) -> BoundingSphere {
    let union = boxes.reduce(|(a_lo, a_hi), (b_lo, b_hi)| (a_lo.min(b_lo), a_hi.max(b_hi)));
    match union {
        Some((lo, hi)) => {
            BoundingSphere { centre: (lo + hi) / 2.0, radius: ((hi - lo).length() / 2.0).max(1e-6) }
        }
        None => BoundingSphere { centre: Vec3::ZERO, radius: 1.0 },
    }
}

impl Description {
    /// Reads a glTF 2.0 file.
    pub fn load(path: &Path) -> Result<Description, SceneError> {
        gltf::load(path)
    }

    /// Whether some medium scatters light: a material's inside, or the world's fog.
    pub fn scatters(&self) -> bool {
        media_scatter(&self.materials, &self.fog)
    }
}

/// Whether some medium of `materials` or the fog `fog` scatters light.
pub fn media_scatter(materials: &[Material], fog: &Option<Volume>) -> bool {
    materials.iter().filter_map(|m| m.volume.as_ref()).chain(fog).any(Volume::scatters)
}
