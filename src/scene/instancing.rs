//! `EXT_mesh_gpu_instancing`: a node drawing its mesh once per instance, each placed by its own
//! translation, rotation and scale within the node. Each instance is expanded into mesh instances
//! of its own (the vertices moved by the instance's transform), so instances render exactly as
//! the same meshes written out one node each; memory grows with the instances, so an expansion
//! past [`MAX_EXPANDED_TRIANGLES`] is refused rather than run out of memory (a two-level BVH that
//! shares one mesh among its instances is not built yet).

use glam::{Mat3, Mat4, Quat, Vec3};

use super::description::MeshInstance;
use super::pointers::floats;
use super::VertexExtras;

/// The extension's name.
pub const EXTENSION: &str = "EXT_mesh_gpu_instancing";

/// The most triangles the instances of one node may expand into.
pub const MAX_EXPANDED_TRIANGLES: usize = 20_000_000;

/// The transforms of `node`'s instances within the node, if it has the extension.
pub fn matrices(
    node: &gltf::Node,
    document: &gltf::Document,
    buffers: &[gltf::buffer::Data],
) -> Result<Option<Vec<Mat4>>, String> {
    let Some(extension) = node.extension_value(EXTENSION) else {
        return Ok(None);
    };
    let name = node.name().unwrap_or("unnamed");
    let in_node = |e: String| format!("node '{name}' {EXTENSION}: {e}");
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

/// `mesh` with its vertices moved by `m` (an instance's transform within its node): positions,
/// normals and tangents turned, the winding kept facing out where `m` mirrors.
pub fn transformed(mesh: &MeshInstance, m: Mat4) -> MeshInstance {
    let linear = Mat3::from_mat4(m);
    let normal_matrix = linear.inverse().transpose();
    let mut extras = VertexExtras::default();
    extras.append(0, &mesh.extras, mesh.positions.len(), linear);
    let mirrored = linear.determinant() < 0.0;
    let triangles = mesh.triangles.iter().map(|t| {
        let [a, b, c] = t.vertices;
        super::TriangleRef { vertices: if mirrored { [a, c, b] } else { [a, b, c] }, material: t.material }
    });
    MeshInstance {
        node: mesh.node,
        name: mesh.name.clone(),
        positions: mesh.positions.iter().map(|&p| m.transform_point3(p)).collect(),
        normals: mesh.normals.iter().map(|&n| (normal_matrix * n).normalize_or_zero()).collect(),
        uvs: mesh.uvs.clone(),
        extras,
        triangles: triangles.collect(),
        deformation: None,
    }
}
