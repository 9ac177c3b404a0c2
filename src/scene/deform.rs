//! Meshes that change shape, beyond what their node does: glTF skins (each vertex carried by a
//! weighted blend of its joints' matrices, the mesh node's own transform ignored, as the glTF 2.0
//! specification's skinning section says) and morph targets (offsets of positions, normals and
//! tangents, weighted by the node's animated `weights`, else the node's or the mesh's default
//! ones). A deforming mesh is posed at each pass's time like a moving one, so it is
//! motion-blurred as a moving mesh is; morph targets apply first, then the skin.

use std::sync::Arc;

use glam::{Mat3, Mat4, Vec3, Vec4};

use super::animation::Rig;

/// A skin: its joints (nodes) and their inverse bind matrices.
#[derive(Debug)]
pub struct Skin {
    /// The joints' nodes.
    pub joints: Vec<usize>,
    /// Each joint's inverse bind matrix (identity where the file has none).
    pub inverse_bind: Vec<Mat4>,
}

/// How a primitive's vertices hang from a skin's joints.
#[derive(Clone, Debug)]
pub struct Skinning {
    /// The skin.
    pub skin: Arc<Skin>,
    /// Influences per vertex (four per `JOINTS_n`/`WEIGHTS_n` set).
    pub per_vertex: usize,
    /// Each influence's joint (an index into the skin's joints).
    pub joints: Vec<u16>,
    /// Each influence's weight; a vertex's sum to one, or are all zero (it follows the mesh's
    /// node, as a vertex in no group follows its object in Blender).
    pub weights: Vec<f32>,
}

/// One morph target's offsets (each empty where the target has none).
#[derive(Clone, Debug, Default)]
pub struct MorphTarget {
    /// Position offsets.
    pub positions: Vec<Vec3>,
    /// Normal offsets.
    pub normals: Vec<Vec3>,
    /// Tangent offsets (xyz).
    pub tangents: Vec<Vec3>,
}

/// A primitive's morph targets and their weights when no animation sets them.
#[derive(Clone, Debug)]
pub struct Morph {
    /// The targets.
    pub targets: Vec<MorphTarget>,
    /// Default weights, one per target (the node's, else the mesh's, else zeros).
    pub weights: Vec<f32>,
}

/// What changes a mesh's shape.
#[derive(Clone, Debug, Default)]
pub struct Deformation {
    /// Its skin, if any.
    pub skin: Option<Skinning>,
    /// Its morph targets, if any.
    pub morph: Option<Morph>,
}

impl Deformation {
    /// Whether the shape of a mesh on `node` changes anywhere in [t0, t1] seconds: a joint moves
    /// or the weights vary.
    pub fn changes_within(&self, rig: &Rig, node: usize, t0: f32, t1: f32) -> bool {
        let joints_move =
            self.skin.as_ref().is_some_and(|s| s.skin.joints.iter().any(|&j| rig.moves_within(j, t0, t1)));
        joints_move || (self.morph.is_some() && rig.weights_vary_within(node, t0, t1))
    }

    /// The deformation of a mesh whose vertex `i` is vertex `order[i]` of this one's.
    pub fn picked(&self, order: &[usize]) -> Deformation {
        // Offsets a target does not have stay absent.
        let pick =
            |values: &[Vec3]| if values.is_empty() { Vec::new() } else { picked_runs(values, order, 1) };
        let skin = self.skin.as_ref().map(|s| {
            let k = s.per_vertex;
            Skinning {
                skin: Arc::clone(&s.skin),
                per_vertex: k,
                joints: picked_runs(&s.joints, order, k),
                weights: picked_runs(&s.weights, order, k),
            }
        });
        let morph = self.morph.as_ref().map(|m| Morph {
            targets: (m.targets.iter())
                .map(|t| MorphTarget {
                    positions: pick(&t.positions),
                    normals: pick(&t.normals),
                    tangents: pick(&t.tangents),
                })
                .collect(),
            weights: m.weights.clone(),
        });
        Deformation { skin, morph }
    }

    /// What the deformation says of a mesh's skin and morph targets, for `caustic info`.
    pub fn kinds(&self) -> Vec<&'static str> {
        let kinds = [(self.skin.is_some(), "skin"), (self.morph.is_some(), "morph targets")];
        kinds.into_iter().filter(|(has, _)| *has).map(|(_, kind)| kind).collect()
    }
}

/// The runs of `k` values of the vertices `order` names, in that order.
fn picked_runs<T: Copy>(values: &[T], order: &[usize], k: usize) -> Vec<T> {
    order.iter().flat_map(|&v| values[v * k..(v + 1) * k].iter().copied()).collect()
}

/// A mesh's vertex attributes that a deformation moves (tangents may be empty).
pub struct Vertices<'a> {
    /// Positions.
    pub positions: &'a mut [Vec3],
    /// Normals.
    pub normals: &'a mut [Vec3],
    /// Tangents (xyz and handedness).
    pub tangents: &'a mut [Vec4],
}

impl Deformation {
    /// Moves the `vertices` of a mesh on `node` into their shape at `time`; gives the matrix
    /// that then takes them to world space (the node's; the identity for a skinned mesh, whose
    /// joints have placed it).
    pub fn apply(&self, mut vertices: Vertices, rig: &Rig, node: usize, time: f32) -> Mat4 {
        let world = rig.world(node, time);
        if let Some(morph) = &self.morph {
            let weights = rig.weights(node, time).unwrap_or_else(|| morph.weights.clone());
            apply_morph(&mut vertices, morph, &weights);
        }
        match &self.skin {
            Some(skinning) => {
                apply_skin(&mut vertices, skinning, rig, time, world);
                Mat4::IDENTITY
            }
            None => world,
        }
    }
}

/// Adds the targets' offsets, times `weights`, to `vertices`.
fn apply_morph(vertices: &mut Vertices, morph: &Morph, weights: &[f32]) {
    for (target, &w) in morph.targets.iter().zip(weights).filter(|(_, &w)| w != 0.0) {
        let add = |values: &mut [Vec3], offsets: &[Vec3]| {
            values.iter_mut().zip(offsets).for_each(|(v, &d)| *v += w * d);
        };
        add(vertices.positions, &target.positions);
        add(vertices.normals, &target.normals);
        let tangents = vertices.tangents.iter_mut().zip(&target.tangents);
        tangents.for_each(|(t, &d)| *t += (w * d).extend(0.0));
    }
    if morph.targets.iter().any(|t| !t.normals.is_empty()) {
        vertices.normals.iter_mut().for_each(|n| *n = n.normalize_or_zero());
    }
}

/// Moves `vertices` to world space by their joints at `time` (vertices with no weight by the
/// mesh node's matrix `node_world`); normals and tangents turn with them.
fn apply_skin(vertices: &mut Vertices, skinning: &Skinning, rig: &Rig, time: f32, node_world: Mat4) {
    let skin = &skinning.skin;
    let joint_matrices: Vec<Mat4> = skin
        .joints
        .iter()
        .zip(&skin.inverse_bind)
        .map(|(&j, &inverse)| rig.world(j, time) * inverse)
        .collect();
    let k = skinning.per_vertex;
    for v in 0..vertices.positions.len() {
        let influences =
            skinning.joints[v * k..(v + 1) * k].iter().zip(&skinning.weights[v * k..(v + 1) * k]);
        let blended = influences
            .filter(|(_, &w)| w > 0.0)
            .map(|(&j, &w)| joint_matrices[j as usize] * w)
            .reduce(|a, b| a + b)
            .unwrap_or(node_world);
        vertices.positions[v] = blended.transform_point3(vertices.positions[v]);
        let linear = Mat3::from_mat4(blended);
        if let Some(n) = vertices.normals.get_mut(v) {
            *n = (cofactor(linear) * *n).normalize_or_zero();
        }
        if let Some(t) = vertices.tangents.get_mut(v) {
            *t = (linear * t.truncate()).normalize_or_zero().extend(t.w);
        }
    }
}

/// The cofactor matrix of `m`: the inverse transpose times the determinant, which turns normals
/// as the inverse transpose does (up to length) and stays finite where `m` is singular.
fn cofactor(m: Mat3) -> Mat3 {
    Mat3::from_cols(m.y_axis.cross(m.z_axis), m.z_axis.cross(m.x_axis), m.x_axis.cross(m.y_axis))
}

/// The weights of `count` morph targets as glTF stores them: groups of four in 4-vectors (for
/// animation tracks), from a flat list whose entries are `count` weights each.
pub fn weight_groups(flat: &[f32], count: usize) -> Vec<Vec<Vec4>> {
    let entries = flat.len() / count.max(1);
    (0..count.div_ceil(4))
        .map(|g| {
            (0..entries)
                .map(|e| {
                    Vec4::from_array(std::array::from_fn(|i| {
                        let target = 4 * g + i;
                        if target < count {
                            flat[e * count + target]
                        } else {
                            0.0
                        }
                    }))
                })
                .collect()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_cofactor_turns_normals_as_the_inverse_transpose_does() {
        let m =
            Mat3::from_cols(Vec3::new(2.0, 0.3, 0.0), Vec3::new(0.1, 0.5, 0.2), Vec3::new(0.0, -0.4, 3.0));
        let n = Vec3::new(0.3, -0.7, 0.2).normalize();
        let expected = (m.inverse().transpose() * n).normalize();
        assert!((cofactor(m) * n).normalize().abs_diff_eq(expected, 1e-5));
    }

    #[test]
    fn weights_are_grouped_by_four_per_entry() {
        // Two entries (keys) of five targets.
        let flat: Vec<f32> = (0..10).map(|i| i as f32).collect();
        let groups = weight_groups(&flat, 5);
        assert_eq!(groups.len(), 2);
        assert_eq!(groups[0], vec![Vec4::new(0.0, 1.0, 2.0, 3.0), Vec4::new(5.0, 6.0, 7.0, 8.0)]);
        assert_eq!(groups[1], vec![Vec4::new(4.0, 0.0, 0.0, 0.0), Vec4::new(9.0, 0.0, 0.0, 0.0)]);
    }
}
