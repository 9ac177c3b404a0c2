//! glTF animation: keyframe tracks on node translation, rotation and scale, sampled exactly as the
//! glTF 2.0 specification defines them (Appendix C): STEP holds the previous key, LINEAR
//! interpolates (rotations by spherical linear interpolation along the short arc), CUBICSPLINE is
//! the cubic Hermite spline with the file's in- and out-tangents scaled by the key interval.
//! Before the first key and after the last the value is clamped. The gltf crate only reads the
//! keys; this module interpolates.

use glam::{Mat4, Quat, Vec3, Vec4};

/// How a track interpolates between keys.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interpolation {
    /// The previous key's value.
    Step,
    /// Linear (slerp for rotations).
    Linear,
    /// Cubic Hermite with tangents from the file (three values per key: in-tangent, value, out-tangent).
    CubicSpline,
}

/// One animated property: key times (seconds) and values as 4-vectors (xyz for translation and
/// scale, xyzw quaternions for rotation); for CUBICSPLINE, three entries per key.
#[derive(Clone, Debug)]
pub struct Track {
    /// Key times in seconds, increasing.
    pub times: Vec<f32>,
    /// Values (see the type's documentation).
    pub values: Vec<Vec4>,
    /// Interpolation between keys.
    pub interpolation: Interpolation,
    /// Whether the values are rotations (unit quaternions).
    pub is_rotation: bool,
}

impl Track {
    /// The key value of key `k` (the middle entry of a CUBICSPLINE triple).
    fn key(&self, k: usize) -> Vec4 {
        match self.interpolation {
            Interpolation::CubicSpline => self.values[3 * k + 1],
            _ => self.values[k],
        }
    }

    /// The track's value at `time` seconds.
    pub fn sample(&self, time: f32) -> Vec4 {
        let last = self.times.len() - 1;
        if time <= self.times[0] || last == 0 {
            return self.key(0);
        }
        if time >= self.times[last] {
            return self.key(last);
        }
        let k = self.times.partition_point(|&t| t <= time) - 1;
        let delta = self.times[k + 1] - self.times[k];
        let s = (time - self.times[k]) / delta;
        match self.interpolation {
            Interpolation::Step => self.key(k),
            Interpolation::Linear if self.is_rotation => {
                let (a, b) = (Quat::from_vec4(self.key(k)), Quat::from_vec4(self.key(k + 1)));
                Vec4::from(a.slerp(b, s))
            }
            Interpolation::Linear => self.key(k).lerp(self.key(k + 1), s),
            Interpolation::CubicSpline => {
                let (p0, m0) = (self.values[3 * k + 1], self.values[3 * k + 2] * delta);
                let (p1, m1) = (self.values[3 * (k + 1) + 1], self.values[3 * (k + 1)] * delta);
                let (s2, s3) = (s * s, s * s * s);
                let v = (2.0 * s3 - 3.0 * s2 + 1.0) * p0
                    + (s3 - 2.0 * s2 + s) * m0
                    + (-2.0 * s3 + 3.0 * s2) * p1
                    + (s3 - s2) * m1;
                if self.is_rotation {
                    v.normalize()
                } else {
                    v
                }
            }
        }
    }

    /// The largest key value, component by component.
    pub fn peak(&self) -> Vec4 {
        (0..self.times.len()).map(|k| self.key(k)).fold(Vec4::splat(f32::NEG_INFINITY), Vec4::max)
    }

    /// Whether the value changes anywhere in [t0, t1].
    pub fn varies_within(&self, t0: f32, t1: f32) -> bool {
        let first = self.sample(t0);
        let inside = self.times.iter().copied().filter(|&t| t > t0 && t < t1);
        inside.chain([t1]).any(|t| (self.sample(t) - first).abs().max_element() > 1e-7)
    }
}

/// A node's local transform: rest pose, with the animated parts replaced by their tracks.
#[derive(Clone, Debug, Default)]
pub struct NodeMotion {
    /// The parent node, if any.
    pub parent: Option<usize>,
    /// Rest translation, rotation, scale.
    pub rest: (Vec3, Quat, Vec3),
    /// Animated translation.
    pub translation: Option<Track>,
    /// Animated rotation.
    pub rotation: Option<Track>,
    /// Animated scale.
    pub scale: Option<Track>,
    /// Animated morph target weights: a track per group of four targets.
    pub weights: Vec<Track>,
    /// How many morph target weights the tracks animate.
    pub weight_count: usize,
}

/// Every node's transform over time.
#[derive(Clone, Debug, Default)]
pub struct Rig {
    /// Nodes by glTF index.
    pub nodes: Vec<NodeMotion>,
}

impl Rig {
    /// The local matrix of `node` at `time` seconds.
    pub fn local(&self, node: usize, time: f32) -> Mat4 {
        let n = &self.nodes[node];
        let (mut t, mut r, mut s) = n.rest;
        if let Some(track) = &n.translation {
            t = track.sample(time).truncate();
        }
        if let Some(track) = &n.rotation {
            r = Quat::from_vec4(track.sample(time)).normalize();
        }
        if let Some(track) = &n.scale {
            s = track.sample(time).truncate();
        }
        Mat4::from_scale_rotation_translation(s, r, t)
    }

    /// The world matrix of `node` at `time` seconds (parents first).
    pub fn world(&self, node: usize, time: f32) -> Mat4 {
        let local = self.local(node, time);
        match self.nodes[node].parent {
            Some(parent) => self.world(parent, time) * local,
            None => local,
        }
    }

    /// The morph target weights of `node` at `time` seconds, if an animation sets them.
    pub fn weights(&self, node: usize, time: f32) -> Option<Vec<f32>> {
        let n = &self.nodes[node];
        if n.weights.is_empty() {
            return None;
        }
        let all = n.weights.iter().flat_map(|track| track.sample(time).to_array());
        Some(all.take(n.weight_count).collect())
    }

    /// Whether the morph target weights of `node` vary anywhere in [t0, t1] seconds.
    pub fn weights_vary_within(&self, node: usize, t0: f32, t1: f32) -> bool {
        self.nodes[node].weights.iter().any(|t| t.varies_within(t0, t1))
    }

    /// Whether `node` or any ancestor moves anywhere in [t0, t1] seconds.
    pub fn moves_within(&self, node: usize, t0: f32, t1: f32) -> bool {
        let n = &self.nodes[node];
        let tracks = [&n.translation, &n.rotation, &n.scale];
        tracks.iter().filter_map(|t| t.as_ref()).any(|t| t.varies_within(t0, t1))
            || n.parent.is_some_and(|p| self.moves_within(p, t0, t1))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn track(times: &[f32], values: &[[f32; 4]], interpolation: Interpolation, is_rotation: bool) -> Track {
        Track {
            times: times.to_vec(),
            values: values.iter().map(|v| Vec4::from(*v)).collect(),
            interpolation,
            is_rotation,
        }
    }

    #[test]
    fn linear_and_step_follow_the_spec_and_clamp() {
        let keys = [[0.0, 0.0, 0.0, 0.0], [2.0, 4.0, -2.0, 0.0]];
        let linear = track(&[1.0, 2.0], &keys, Interpolation::Linear, false);
        assert_eq!(linear.sample(1.25), Vec4::new(0.5, 1.0, -0.5, 0.0));
        assert_eq!(linear.sample(0.0), Vec4::ZERO);
        assert_eq!(linear.sample(9.0), Vec4::from(keys[1]));
        let step = track(&[1.0, 2.0], &keys, Interpolation::Step, false);
        assert_eq!(step.sample(1.99), Vec4::ZERO);
        assert_eq!(step.sample(2.0), Vec4::from(keys[1]));
    }

    #[test]
    fn rotations_slerp_along_the_short_arc() {
        // 0 and 270 degrees about z: the short arc goes through -45 degrees at the middle.
        let a = Quat::IDENTITY;
        let b = -Quat::from_rotation_z(1.5 * std::f32::consts::PI); // the same rotation as -90 degrees, far hemisphere
        let t = track(&[0.0, 1.0], &[a.to_array(), b.to_array()], Interpolation::Linear, true);
        let middle = Quat::from_vec4(t.sample(0.5));
        let expected = Quat::from_rotation_z(-std::f32::consts::FRAC_PI_4);
        assert!(middle.angle_between(expected) < 1e-4, "{middle}");
    }

    #[test]
    fn cubic_spline_is_the_hermite_curve_of_the_spec() {
        // Keys at t = 0 (value 1, out-tangent 2) and t = 2 (in-tangent -1, value 3).
        // At s = 0.5: h00 = 0.5, h10 = 0.125, h01 = 0.5, h11 = -0.125, tangents scaled by 2:
        // 0.5 * 1 + 0.125 * 4 + 0.5 * 3 - 0.125 * (-2) = 2.75.
        let values = [
            [0.0; 4],
            [1.0, 0.0, 0.0, 0.0],
            [2.0, 0.0, 0.0, 0.0],
            [-1.0, 0.0, 0.0, 0.0],
            [3.0, 0.0, 0.0, 0.0],
            [0.0; 4],
        ];
        let t = track(&[0.0, 2.0], &values, Interpolation::CubicSpline, false);
        assert!((t.sample(1.0).x - 2.75).abs() < 1e-6, "{}", t.sample(1.0));
        assert_eq!(t.sample(-1.0).x, 1.0);
        assert_eq!(t.sample(5.0).x, 3.0);
    }

    #[test]
    fn nested_nodes_compose_and_report_motion() {
        let moving = track(&[0.0, 1.0], &[[0.0; 4], [1.0, 0.0, 0.0, 0.0]], Interpolation::Linear, false);
        let rest = (Vec3::ZERO, Quat::IDENTITY, Vec3::ONE);
        let parent = NodeMotion { rest, translation: Some(moving), ..Default::default() };
        let child =
            NodeMotion { parent: Some(0), rest: (Vec3::Y, Quat::IDENTITY, Vec3::ONE), ..Default::default() };
        let rig = Rig { nodes: vec![parent, child] };
        assert_eq!(rig.world(1, 0.5).transform_point3(Vec3::ZERO), Vec3::new(0.5, 1.0, 0.0));
        assert!(rig.moves_within(1, 0.2, 0.3));
        assert!(!rig.moves_within(1, 2.0, 3.0));
    }
}
