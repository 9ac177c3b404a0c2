//! `EXT_mesh_gpu_instancing`: a node drawing its mesh once per instance, each placed by its own
//! translation, rotation and scale within the node.
//!
//! A still, closed mesh of materials that neither emit nor change is kept once, in its own space
//! ([`InstancedMesh`]), and drawn through a two-level BVH ([`InstancedBvh`]), so memory grows with
//! the meshes, not with the instances. Any other instanced mesh (one that moves, deforms, emits,
//! is animated, is open or is held out) is expanded into mesh instances of its own (the vertices
//! moved by the instance's transform), which render exactly as the same meshes written out one
//! node each; an expansion past [`MAX_EXPANDED_TRIANGLES`] is refused rather than run out of
//! memory.

use std::sync::Arc;

use glam::{Mat3, Mat4, Vec3, Vec4};

use super::{Geometry, Surface};
use crate::accel::{Hit, InstancedBvh, Placement};
use crate::spectrum::Wavelengths;

/// The extension's name.
pub const EXTENSION: &str = "EXT_mesh_gpu_instancing";

/// The most triangles the instances of one node may expand into.
pub const MAX_EXPANDED_TRIANGLES: usize = 20_000_000;

/// A mesh drawn by a node's instances, kept once (see [`Instances`]).
#[derive(Clone, Debug)]
pub struct InstancedMesh {
    /// The node (it does not move).
    pub node: usize,
    /// The mesh's primitives, in the node's space.
    pub geometry: Geometry,
    /// Each instance's transform within the node.
    pub matrices: Vec<Mat4>,
}

/// The instanced meshes of a scene, each stored once in its own space with where its instances
/// are: what a hit on an instanced triangle (numbered after the moving ones) reads.
#[derive(Debug, Default)]
pub struct Instances {
    meshes: Vec<Geometry>,
    placements: Vec<Placement>,
    triangles: usize,
}

impl Instances {
    /// The instances of `meshes` in the world (their nodes posed by `world`).
    pub fn new(meshes: &[InstancedMesh], world: impl Fn(usize) -> Mat4) -> Self {
        let mut placements = Vec::new();
        let mut first = 0;
        for (m, mesh) in meshes.iter().enumerate() {
            let node = world(mesh.node);
            for &matrix in &mesh.matrices {
                placements.push(Placement::new(m as u32, node * matrix, first as u32));
                first += mesh.geometry.triangles.len();
            }
        }
        Instances {
            meshes: meshes.iter().map(|m| m.geometry.clone()).collect(),
            placements,
            triangles: first,
        }
    }

    /// How many triangles the instances draw.
    pub fn triangle_count(&self) -> usize {
        self.triangles
    }

    /// How many triangles are stored.
    pub fn stored_triangles(&self) -> usize {
        self.meshes.iter().map(|m| m.triangles.len()).sum()
    }

    /// The two-level BVH over the instances.
    pub fn bvh(&self) -> Option<Arc<InstancedBvh>> {
        (!self.placements.is_empty())
            .then(|| Arc::new(InstancedBvh::build(&self.corners(), &self.placements)))
    }

    fn corners(&self) -> Vec<Vec<[Vec3; 3]>> {
        self.meshes.iter().map(Geometry::corners).collect()
    }

    /// The instance that draws instanced triangle `t`, and `t` within its mesh.
    fn find(&self, t: usize) -> (&Placement, usize) {
        let k = self.placements.partition_point(|p| p.first as usize <= t) - 1;
        (&self.placements[k], t - self.placements[k].first as usize)
    }

    /// The surface at `hit` (in world coordinates) on instanced triangle `t`.
    pub fn surface(&self, t: usize, hit: &Hit, lambda: &Wavelengths) -> Surface {
        let (placed, local) = self.find(t);
        let linear = Mat3::from_mat4(placed.to_world);
        let mesh = &self.meshes[placed.mesh as usize];
        let mut surface =
            mesh.surface_with_normal(local, hit, lambda, |n| (placed.normal * n).normalize_or_zero());
        let tangent = surface.inputs.tangent;
        if tangent != Vec4::ZERO {
            let turned = (linear * tangent.truncate()).normalize_or_zero();
            surface.inputs.tangent = turned.extend(tangent.w * linear.determinant().signum());
        }
        surface
    }

    /// The material of instanced triangle `t`.
    pub fn material(&self, t: usize) -> u32 {
        let (placed, local) = self.find(t);
        self.meshes[placed.mesh as usize].triangles[local].material
    }

    /// The box around every instance.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        let boxes = self.placements.iter().filter_map(|p| {
            let (lo, hi) = self.meshes[p.mesh as usize].bounds()?;
            let corners =
                (0..8).map(|k| Vec3::select(glam::BVec3::new(k & 1 != 0, k & 2 != 0, k & 4 != 0), hi, lo));
            corners
                .map(|c| p.to_world.transform_point3(c))
                .map(|c| (c, c))
                .reduce(|(a, b), (c, d)| (a.min(c), b.max(d)))
        });
        boxes.reduce(|(a, b), (c, d)| (a.min(c), b.max(d)))
    }
}
