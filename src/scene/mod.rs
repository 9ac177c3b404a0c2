//! The render-ready scene: world-space triangles, materials, lights and the camera.
//!
//! Takes a glTF 2.0 file (`.gltf` with its `.bin`, or `.glb`) plus the `caustic` extras
//! ([`extras`]); gives a [`Scene`] that the accelerator and the SPPM passes read and never change.
//! Every triangle is flattened to world space at load; emitting triangles are also lights.

pub mod extras;
mod gltf_loader;
mod shapes;

use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3};

use crate::camera::Camera;
use crate::lights::{BoundingSphere, Light};
use crate::materials::{Material, ShadingFrame};

/// A scene that cannot be loaded: the file and what is wrong with it.
#[derive(Debug, thiserror::Error)]
#[error("{}: {message}", path.display())]
pub struct SceneError {
    /// The scene file.
    pub path: PathBuf,
    /// What is wrong, naming the mesh, node or field.
    pub message: String,
}

/// One triangle: indices into the vertex arrays and its material.
#[derive(Clone, Copy, Debug)]
pub struct TriangleRef {
    /// Vertex indices, counter-clockwise seen from the outside.
    pub vertices: [u32; 3],
    /// Index into `Scene::materials`.
    pub material: u32,
}

/// The render-ready scene.
#[derive(Debug)]
pub struct Scene {
    /// World-space vertex positions.
    pub positions: Vec<Vec3>,
    /// World-space unit shading normals, one per vertex.
    pub normals: Vec<Vec3>,
    /// Texture coordinates, one per vertex (zero where the mesh has none).
    pub uvs: Vec<Vec2>,
    /// The triangles.
    pub triangles: Vec<TriangleRef>,
    /// Materials, indexed by `TriangleRef::material`.
    pub materials: Vec<Material>,
    /// Every light, emitting triangles included.
    pub lights: Vec<Light>,
    /// For each triangle, the index in `lights` of its emitter, or [`NOT_A_LIGHT`].
    pub triangle_lights: Vec<u32>,
    /// Indices in `lights` of the distant lights a ray leaving the scene can see.
    pub distant_lights: Vec<usize>,
    /// The camera.
    pub camera: Camera,
    /// The resolution the scene asks for, if it does.
    pub resolution: Option<[u32; 2]>,
    /// The camera's aspect ratio (width / height), if the file gives one.
    pub aspect_ratio: Option<f32>,
    /// What was skipped or assumed while loading, for the user.
    pub warnings: Vec<String>,
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
    /// Texture coordinates.
    pub uv: Vec2,
    /// Index into `Scene::materials`.
    pub material: u32,
}

impl Scene {
    /// Loads a glTF 2.0 scene.
    pub fn load(path: &Path) -> Result<Scene, SceneError> {
        gltf_loader::load(path)
    }

    /// The corners of every triangle, in triangle order.
    pub fn triangle_corners(&self) -> Vec<[Vec3; 3]> {
        self.triangles.iter().map(|t| t.vertices.map(|v| self.positions[v as usize])).collect()
    }

    /// The surface at barycentric coordinates `b` (weights of corners 1 and 2) of `triangle`.
    pub fn surface(&self, triangle: u32, b: Vec2) -> Surface {
        let t = self.triangles[triangle as usize];
        let [i0, i1, i2] = t.vertices.map(|v| v as usize);
        let w = [1.0 - b.x - b.y, b.x, b.y];
        let interpolate = |a: &[Vec3]| a[i0] * w[0] + a[i1] * w[1] + a[i2] * w[2];
        let p = interpolate(&self.positions);
        let ng = (self.positions[i1] - self.positions[i0])
            .cross(self.positions[i2] - self.positions[i0])
            .normalize_or_zero();
        let n = interpolate(&self.normals).normalize_or_zero();
        let n = if n == Vec3::ZERO { ng } else { n };
        let uv = self.uvs[i0] * w[0] + self.uvs[i1] * w[1] + self.uvs[i2] * w[2];
        Surface { p, frame: ShadingFrame { n, ng }, uv, material: t.material }
    }

    /// Radiance that a ray of direction `dir` receives when it leaves the scene.
    pub fn escaped_radiance(&self, dir: Vec3, lambda_nm: f32) -> f32 {
        self.distant_lights.iter().map(|&i| self.lights[i].escaped_radiance(dir, lambda_nm)).sum()
    }

    /// The sphere around every triangle (radius 1 at the origin for an empty scene).
    pub fn bounding_sphere(&self) -> BoundingSphere {
        if self.positions.is_empty() {
            return BoundingSphere { centre: Vec3::ZERO, radius: 1.0 };
        }
        let min = self.positions.iter().fold(Vec3::INFINITY, |a, &p| a.min(p));
        let max = self.positions.iter().fold(Vec3::NEG_INFINITY, |a, &p| a.max(p));
        BoundingSphere { centre: (min + max) / 2.0, radius: ((max - min).length() / 2.0).max(1e-6) }
    }
}
