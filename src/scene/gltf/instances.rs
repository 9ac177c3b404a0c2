//! Meshes drawn many times (`EXT_mesh_gpu_instancing`, and nodes sharing a mesh): kept once.

use crate::scene::instancing::{self};
use crate::scene::pointers::floats;

use super::Builder;
use glam::{Mat4, Quat, Vec3};

use crate::scene::description::MeshInstance;

/// The transforms of `node`'s instances within the node, if it has the extension.
pub(super) fn instance_matrices(
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

impl Builder<'_> {
    /// Whether the mesh instances from `first` on can be drawn by a two-level BVH: they do not
    /// deform, their materials neither emit nor change nor are light surfaces, and they close up
    /// (open meshes keep their open edges, which only flattened triangles have).
    pub(super) fn may_share(&self, first: usize) -> bool {
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
    pub(super) fn add_instances(
        &mut self,
        first: usize,
        matrices: &[Mat4],
        name: &str,
    ) -> Result<(), String> {
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
}

/// Whether the triangles of `instances` close up: every edge (matched by its end positions,
/// rounded to a millionth of the mesh's size, so that seams whose vertices differ in their last
/// bits still match) is shared by an even number of triangles.
pub(super) fn is_closed(instances: &[MeshInstance]) -> bool {
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
