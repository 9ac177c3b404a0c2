//! The node rig and what deforms meshes: node animation channels, skins and morph targets.

use std::sync::Arc;

use crate::scene::deform::{self, Deformation, Morph, MorphTarget, Skin, Skinning};
use crate::scene::pointers::{self, Keys, NodeProperty};

use super::Builder;
use glam::{Mat4, Quat, Vec3};
use gltf::animation::util::ReadOutputs;

use crate::scene::animation::{Interpolation, NodeMotion, Rig, Track};

/// Every node's parent, rest transform and animation tracks.
pub(super) fn rig(
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
pub(super) fn channel_keys(
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
pub(super) fn morph_target_count(node: &gltf::Node) -> usize {
    let primitives = node.mesh().into_iter().flat_map(|m| m.primitives().collect::<Vec<_>>());
    primitives.map(|p| p.morph_targets().len()).max().unwrap_or(0)
}

/// The skin and morph targets of a primitive of `count` vertices, if it has either: `skin` is
/// its node's; `default_weights` the node's or the mesh's `weights`.
pub(super) fn deformation<'a, 's, F>(
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
pub(super) fn skinning<'a, 's, F>(
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
pub(super) fn morph_targets<'a, 's, F>(
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

impl Builder<'_> {
    /// The skin `skin` of node `node` (read once, shared by every mesh it deforms).
    pub(super) fn skin(&mut self, skin: &gltf::Skin, node: &str) -> Result<Arc<Skin>, String> {
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
}
