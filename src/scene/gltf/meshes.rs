//! Meshes: triangles with their attributes (normals, texture coordinates, colours, tangents).

use std::sync::Arc;

use crate::scene::deform::Skin;
use crate::scene::instancing::InstancedMesh;
use crate::scene::pose::flatten;
use crate::scene::Geometry;

use super::instances::instance_matrices;
use super::rigs::deformation;
use super::Builder;
use glam::{Mat4, Vec2, Vec3, Vec4};

use crate::scene::animation::Rig;
use crate::scene::description::MeshInstance;
use crate::scene::{tangents, TriangleRef, VertexExtras};
use crate::spectrum::RgbSpectrum;

/// `TEXCOORD_1`, `COLOR_0` (fitted to reflectance spectra; only where the material `reads_colours`)
/// and `TANGENT` of a primitive of `count` vertices; each empty where the primitive has none or a
/// mismatched one (warned). The colours' alpha is kept where it is below 1 somewhere on a
/// material whose alpha `cuts`.
pub(super) fn vertex_extras<'a, 's, F>(
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
pub(super) fn optional_attribute<T: Default + Clone>(
    values: Vec<T>,
    count: usize,
    attribute: &str,
    mesh: &str,
    warnings: &mut Vec<String>,
) -> Vec<T> {
    if values.is_empty() {
        return values;
    }
    one_per_position(values, count, attribute, mesh, warnings).unwrap_or_default()
}

/// `values` when it has `count` entries (one per position); otherwise `None`, with a warning.
fn one_per_position<T>(
    values: Vec<T>,
    count: usize,
    attribute: &str,
    mesh: &str,
    warnings: &mut Vec<String>,
) -> Option<Vec<T>> {
    if values.len() == count {
        return Some(values);
    }
    warnings.push(mismatch(values.len(), count, attribute, mesh));
    None
}

/// The warning for an attribute of `len` entries on a mesh of `count` positions.
fn mismatch(len: usize, count: usize, attribute: &str, mesh: &str) -> String {
    format!("mesh '{mesh}': {attribute} has {len} entries for {count} positions; ignored")
}

/// Linear RGB colours as reflectance spectra, fitted once per colour at 10 bits a channel.
pub(super) fn reflectances(colours: &[Vec4]) -> Vec<RgbSpectrum> {
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
pub(super) fn matching_attribute<T: Default + Clone>(
    values: Vec<T>,
    count: usize,
    attribute: &str,
    mesh: &str,
    warnings: &mut Vec<String>,
) -> Vec<T> {
    one_per_position(values, count, attribute, mesh, warnings).unwrap_or_else(|| vec![T::default(); count])
}

pub(super) fn is_valid_triangle(c: &[Vec3; 3]) -> bool {
    let area2 = (c[1] - c[0]).cross(c[2] - c[0]).length_squared();
    c.iter().all(|v| v.is_finite()) && area2 > 0.0 && area2.is_finite()
}

impl Builder<'_> {
    pub(super) fn add_mesh(
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

    /// Adds each triangle primitive of `mesh` as a mesh instance of `node` (deformed by `skin`
    /// and its morph targets, if any).
    pub(super) fn add_primitives(
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
    pub(super) fn with_tangents(&mut self, mesh: MeshInstance, material: u32) -> MeshInstance {
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
