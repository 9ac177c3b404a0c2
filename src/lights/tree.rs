//! A light tree for next-event estimation (Conty Estevez & Kulla 2018, "Importance Sampling of
//! Many Lights with Adaptive Tree Splitting", as pbrt-v4's BVH light sampler): a bounding volume
//! hierarchy over the lights with their power, bounds and emission cones. A point picks a light
//! by walking down from the root, at each node choosing a child in proportion to an upper bound
//! of what the child's lights can send it (power over squared distance, times the best cosines
//! its bounds allow at the light and at the point); the probability of a light is the product of
//! the choices on its path, found again from the bits of that path.
//!
//! Distant lights (a sun, the world) stand beside the tree: the tree as a whole and each distant
//! light are chosen in proportion to their power, as every light is without the tree.

use glam::{Quat, Vec3};
use std::f32::consts::PI;

use super::Light;
use crate::sampling::Distribution1D;

/// Buckets per axis where the build looks for the cheapest split.
const BUCKETS: usize = 12;

/// The deepest a leaf may lie (its path is kept in the bits of a u64).
const MAX_DEPTH: u32 = 60;

/// What a node's lights can send where: their box, total power and emission cones.
#[derive(Clone, Copy, Debug)]
struct LightBounds {
    lo: Vec3,
    hi: Vec3,
    /// Total luminous power.
    phi: f32,
    /// The axis of the cone holding every emitter's normal (or spot axis).
    axis: Vec3,
    /// Cosine of the half-angle of that cone (theta_o).
    cos_o: f32,
    /// Cosine of the widest angle from its normal at which an emitter still emits (theta_e).
    cos_e: f32,
    /// Some emitter emits from both faces.
    two_sided: bool,
}

impl LightBounds {
    /// The bounds of `light` of luminous power `power`, or `None` for a distant light or one
    /// that emits nothing.
    fn of(light: &Light, power: f64) -> Option<LightBounds> {
        let phi = power as f32;
        if !(phi > 0.0) {
            return None;
        }
        let right_angle = 0.0;
        match light {
            Light::Sphere(sphere) => {
                let r = Vec3::splat(sphere.radius);
                let (axis, cos_o) = match sphere.beam {
                    Some(beam) => (beam.axis, 1.0 - beam.outer.one_minus_cos),
                    None => (Vec3::Z, -1.0),
                };
                let (lo, hi) = (sphere.position - r, sphere.position + r);
                Some(LightBounds { lo, hi, phi, axis, cos_o, cos_e: right_angle, two_sided: false })
            }
            Light::Triangle(t) => {
                let [a, b, c] = t.corners;
                let cos_e = t.spread.map_or(right_angle, |s| s.cos_half());
                let (lo, hi) = (a.min(b).min(c), a.max(b).max(c));
                Some(LightBounds { lo, hi, phi, axis: t.normal, cos_o: 1.0, cos_e, two_sided: t.both_sides })
            }
            Light::Sun { .. } | Light::World(_) => None,
        }
    }

    fn centroid(&self) -> Vec3 {
        (self.lo + self.hi) * 0.5
    }

    /// Both bounds in one.
    fn union(&self, other: &LightBounds) -> LightBounds {
        let (axis, cos_o) = cone_union((self.axis, self.cos_o), (other.axis, other.cos_o));
        LightBounds {
            lo: self.lo.min(other.lo),
            hi: self.hi.max(other.hi),
            phi: self.phi + other.phi,
            axis,
            cos_o,
            cos_e: self.cos_e.min(other.cos_e),
            two_sided: self.two_sided || other.two_sided,
        }
    }

    /// What sampling reads of these bounds, computed once.
    fn prepared(&self) -> NodeBounds {
        let half_diagonal2 = (self.hi - self.lo).length_squared() / 4.0;
        NodeBounds {
            centre: self.centroid(),
            radius2: half_diagonal2,
            nearest2: half_diagonal2.sqrt(),
            axis: self.axis,
            cos_o: self.cos_o,
            sin_o: (1.0 - self.cos_o * self.cos_o).max(0.0).sqrt(),
            cos_e: self.cos_e,
            phi: self.phi,
            two_sided: self.two_sided,
        }
    }

    /// pbrt-v4's cost of a node with these bounds (the surface area orientation heuristic), in a
    /// parent whose box is `parent` split along `axis`.
    fn cost(&self, parent: (Vec3, Vec3), axis: usize) -> f32 {
        let theta_o = self.cos_o.clamp(-1.0, 1.0).acos();
        let theta_e = self.cos_e.clamp(-1.0, 1.0).acos();
        let theta_w = (theta_o + theta_e).min(PI);
        let sin_o = (1.0 - self.cos_o * self.cos_o).max(0.0).sqrt();
        let orientation = 2.0 * PI * (1.0 - self.cos_o)
            + PI / 2.0
                * (2.0 * theta_w * sin_o - (theta_o - 2.0 * theta_w).cos() - 2.0 * theta_o * sin_o
                    + self.cos_o);
        let diagonal = parent.1 - parent.0;
        let stretch = diagonal.max_element() / diagonal[axis].max(f32::MIN_POSITIVE);
        let d = self.hi - self.lo;
        let area = 2.0 * (d.x * d.y + d.y * d.z + d.z * d.x);
        self.phi * orientation * stretch * area
    }
}

/// A node's bounds as sampling reads them (`LightBounds::prepared`).
#[derive(Clone, Copy, Debug)]
struct NodeBounds {
    /// The box's centre.
    centre: Vec3,
    /// The square of the radius of the sphere around the box.
    radius2: f32,
    /// The least squared distance importance divides by (pbrt-v4's: half the box's diagonal).
    nearest2: f32,
    axis: Vec3,
    cos_o: f32,
    sin_o: f32,
    cos_e: f32,
    phi: f32,
    two_sided: bool,
}

impl NodeBounds {
    /// An upper bound, up to a constant, of the light these lights send to a point `p` whose
    /// surface has the unit normal `n` (zero: no surface). pbrt-v4's `LightBounds::Importance`.
    fn importance(&self, p: Vec3, n: Vec3) -> f32 {
        let to_p = p - self.centre;
        let distance2 = to_p.length_squared();
        let wi = to_p / distance2.sqrt().max(f32::MIN_POSITIVE);
        let mut cos_w = self.axis.dot(wi);
        if self.two_sided {
            cos_w = cos_w.abs();
        }
        let sin_w = (1.0 - cos_w * cos_w).max(0.0).sqrt();
        // The cone of directions from p that the box's sphere covers.
        let cos_b = if distance2 <= self.radius2 { -1.0 } else { (1.0 - self.radius2 / distance2).sqrt() };
        let sin_b = (1.0 - cos_b * cos_b).max(0.0).sqrt();
        let (cos_x, sin_x) = angle_less((cos_w, sin_w), (self.cos_o, self.sin_o));
        let (cos_p, _) = angle_less((cos_x, sin_x), (cos_b, sin_b));
        if cos_p <= self.cos_e {
            return 0.0;
        }
        let mut importance = self.phi * cos_p / distance2.max(self.nearest2);
        if n != Vec3::ZERO {
            let cos_i = wi.dot(n).abs();
            let sin_i = (1.0 - cos_i * cos_i).max(0.0).sqrt();
            importance *= angle_less((cos_i, sin_i), (cos_b, sin_b)).0;
        }
        importance.max(0.0)
    }
}

/// The angle a minus the angle b, clamped at 0, as (cos, sin) from theirs.
fn angle_less((cos_a, sin_a): (f32, f32), (cos_b, sin_b): (f32, f32)) -> (f32, f32) {
    if cos_a > cos_b {
        return (1.0, 0.0);
    }
    (cos_a * cos_b + sin_a * sin_b, sin_a * cos_b - cos_a * sin_b)
}

/// The narrowest cone holding cones `a` and `b` (axis, cosine of the half-angle); pbrt-v4's
/// `Union` of direction cones.
fn cone_union(a: (Vec3, f32), b: (Vec3, f32)) -> (Vec3, f32) {
    let (theta_a, theta_b) = (a.1.clamp(-1.0, 1.0).acos(), b.1.clamp(-1.0, 1.0).acos());
    let theta_d = a.0.angle_between(b.0);
    if (theta_d + theta_b).min(PI) <= theta_a {
        return a;
    }
    if (theta_d + theta_a).min(PI) <= theta_b {
        return b;
    }
    let theta_o = (theta_a + theta_d + theta_b) / 2.0;
    let spin = a.0.cross(b.0);
    if theta_o >= PI || spin.length_squared() == 0.0 {
        return (Vec3::Z, -1.0);
    }
    let axis = Quat::from_axis_angle(spin.normalize(), theta_o - theta_a) * a.0;
    (axis.normalize(), theta_o.cos())
}

/// A node: its bounds, and its light (a leaf) or its second child (the first follows it).
#[derive(Clone, Copy, Debug)]
struct Node {
    bounds: NodeBounds,
    leaf: bool,
    index: u32,
}

/// A light tree over a scene's lights.
#[derive(Clone, Debug, Default)]
pub struct LightTree {
    nodes: Vec<Node>,
    /// For each light by index: the bits of its path from the root (1: the second child) and
    /// its depth, for lights in the tree.
    paths: Vec<Option<(u64, u32)>>,
    /// Distant lights by index.
    distant: Vec<usize>,
    /// The distant lights and, as the last entry, the tree, by power.
    top: Distribution1D,
}

impl LightTree {
    /// The tree over `lights` of luminous powers `powers` (distant ones beside it).
    pub fn new(lights: &[Light], powers: &[f64]) -> LightTree {
        let mut leaves: Vec<(LightBounds, u32)> = (lights.iter().zip(powers).enumerate())
            .filter_map(|(i, (l, &power))| Some((LightBounds::of(l, power)?, i as u32)))
            .collect();
        let distant: Vec<usize> = lights
            .iter()
            .enumerate()
            .filter(|(_, l)| matches!(l, Light::Sun { .. } | Light::World(_)))
            .map(|(i, _)| i)
            .collect();
        let mut tree = LightTree { paths: vec![None; lights.len()], ..LightTree::default() };
        if !leaves.is_empty() {
            tree.build(&mut leaves, 0, 0);
        }
        let tree_power = tree.nodes.first().map_or(0.0, |n| f64::from(n.bounds.phi));
        tree.top = Distribution1D::new(distant.iter().map(|&i| powers[i]).chain([tree_power]));
        tree.distant = distant;
        tree
    }

    /// Builds the subtree over `leaves` whose path from the root is `bits` at `depth`; gives
    /// its bounds.
    fn build(&mut self, leaves: &mut [(LightBounds, u32)], bits: u64, depth: u32) -> LightBounds {
        let at = self.nodes.len();
        if let [(bounds, light)] = leaves {
            self.nodes.push(Node { bounds: bounds.prepared(), leaf: true, index: *light });
            self.paths[*light as usize] = Some((bits, depth));
            return *bounds;
        }
        self.nodes.push(Node { bounds: leaves[0].0.prepared(), leaf: false, index: 0 });
        let mid = split(leaves, depth);
        let (first, second) = leaves.split_at_mut(mid);
        let a = self.build(first, bits, depth + 1);
        self.nodes[at].index = self.nodes.len() as u32;
        let b = self.build(second, bits | (1 << depth), depth + 1);
        let bounds = a.union(&b);
        self.nodes[at].bounds = bounds.prepared();
        bounds
    }

    /// A light for next-event estimation at `p` (of surface normal `n`, or zero), with the
    /// probability it was chosen with; `None` when the scene has no light.
    pub fn sample(&self, p: Vec3, n: Vec3, u: f32) -> Option<(usize, f32)> {
        let (top, p_top) = self.top.sample(u)?;
        if let Some(&distant) = self.distant.get(top) {
            return Some((distant, p_top));
        }
        // u rescaled within the tree's share of the top choice.
        let below = 1.0 - p_top;
        let mut u = ((u - below) / p_top).clamp(0.0, 1.0 - f32::EPSILON);
        let (mut node, mut probability) = (0, p_top);
        loop {
            let Node { leaf, index, .. } = self.nodes[node];
            if leaf {
                return Some((index as usize, probability));
            }
            let (first, second) = (node + 1, index as usize);
            let p_first = self.first_child_share(node, p, n);
            if u < p_first {
                u = (u / p_first).min(1.0 - f32::EPSILON);
                probability *= p_first;
                node = first;
            } else {
                u = ((u - p_first) / (1.0 - p_first)).clamp(0.0, 1.0 - f32::EPSILON);
                probability *= 1.0 - p_first;
                node = second;
            }
        }
    }

    /// The probability that [`LightTree::sample`] at `p` (of normal `n`) chooses light `light`.
    pub fn probability(&self, p: Vec3, n: Vec3, light: usize) -> f32 {
        if let Some(k) = self.distant.iter().position(|&d| d == light) {
            return self.top.probability(k);
        }
        let Some((bits, depth)) = self.paths.get(light).copied().flatten() else {
            return 0.0;
        };
        let mut probability = self.top.probability(self.distant.len());
        let mut node = 0;
        for level in 0..depth {
            let p_first = self.first_child_share(node, p, n);
            if bits >> level & 1 == 1 {
                probability *= 1.0 - p_first;
                node = self.nodes[node].index as usize;
            } else {
                probability *= p_first;
                node += 1;
            }
        }
        probability
    }

    /// The probability of going on to the first child of inner node `node` from `p` (normal `n`):
    /// its share of the children's importance, or, where neither can light `p` by its bounds
    /// though their parent could, its share of their power (so that every light reachable by its
    /// ancestors keeps a probability, and they sum to one).
    fn first_child_share(&self, node: usize, p: Vec3, n: Vec3) -> f32 {
        let (first, second) =
            (&self.nodes[node + 1].bounds, &self.nodes[self.nodes[node].index as usize].bounds);
        let importance = [first.importance(p, n), second.importance(p, n)];
        let sum = importance[0] + importance[1];
        if sum > 0.0 {
            importance[0] / sum
        } else {
            first.phi / (first.phi + second.phi)
        }
    }
}

/// Reorders `leaves` and gives where to split them (neither side empty): at the cheapest of the
/// bucket boundaries along each axis by pbrt-v4's cost, else (or where only median splits would
/// keep the leaves within `MAX_DEPTH`) at the median of the centroids along the longest axis.
fn split(leaves: &mut [(LightBounds, u32)], depth: u32) -> usize {
    // Median splits from here on would still keep every leaf within MAX_DEPTH.
    let levels_needed = usize::BITS - leaves.len().leading_zeros();
    let (lo, hi) = leaves
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), (b, _)| (lo.min(b.lo), hi.max(b.hi)));
    let (clo, chi) = leaves.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), (b, _)| {
        (lo.min(b.centroid()), hi.max(b.centroid()))
    });
    let bucket = |b: &LightBounds, axis: usize| {
        let t = (b.centroid()[axis] - clo[axis]) / (chi[axis] - clo[axis]);
        ((t * BUCKETS as f32) as usize).min(BUCKETS - 1)
    };
    let mut best: Option<(f32, usize, usize)> = None;
    for axis in 0..3 {
        if !(chi[axis] > clo[axis]) || depth + levels_needed > MAX_DEPTH {
            continue;
        }
        let mut buckets: [Option<LightBounds>; BUCKETS] = [None; BUCKETS];
        for (b, _) in leaves.iter() {
            let k = bucket(b, axis);
            buckets[k] = Some(buckets[k].map_or(*b, |c| c.union(b)));
        }
        for cut in 1..BUCKETS {
            let side =
                |range: &[Option<LightBounds>]| range.iter().flatten().copied().reduce(|a, b| a.union(&b));
            let (Some(a), Some(b)) = (side(&buckets[..cut]), side(&buckets[cut..])) else {
                continue;
            };
            let cost = a.cost((lo, hi), axis) + b.cost((lo, hi), axis);
            if best.is_none_or(|(c, _, _)| cost < c) {
                best = Some((cost, axis, cut));
            }
        }
    }
    if let Some((_, axis, cut)) = best {
        leaves.sort_by_key(|(b, i)| (bucket(b, axis) >= cut, *i));
        let mid = leaves.partition_point(|(b, _)| bucket(b, axis) < cut);
        if mid > 0 && mid < leaves.len() {
            return mid;
        }
    }
    let axis = (chi - clo).max_position();
    leaves.sort_by(|(a, i), (b, j)| a.centroid()[axis].total_cmp(&b.centroid()[axis]).then(i.cmp(j)));
    leaves.len() / 2
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Cone;
    use crate::lights::{BoundingSphere, Emission, EmittingTriangle, SphereLight};
    use crate::spectrum::Illuminant;

    /// A few hundred small emitting triangles of varied power and facing, spread through a
    /// room, a point light, a sphere light and a sun.
    fn many_lights() -> Vec<Light> {
        let mut lights = Vec::new();
        let mut state = 12345u32;
        let mut next = || {
            state = state.wrapping_mul(1664525).wrapping_add(1013904223);
            (state >> 8) as f32 / (1 << 24) as f32
        };
        for _ in 0..300 {
            let c = Vec3::new(next() * 10.0 - 5.0, next() * 4.0, next() * 10.0 - 5.0);
            let e = Vec3::new(next() - 0.5, next() - 0.5, next() - 0.5) * 0.2;
            let f = Vec3::new(next() - 0.5, next() - 0.5, next() - 0.5) * 0.2;
            let radiance = Illuminant::d65(Vec3::splat(0.1 + 10.0 * next()));
            let both = next() < 0.3;
            lights.push(Light::Triangle(EmittingTriangle::new(
                [c, c + e, c + f],
                Emission::Uniform(radiance),
                both,
            )));
        }
        let sphere = |position, radius| SphereLight {
            position,
            intensity: Illuminant::d65(Vec3::ONE),
            radius,
            beam: None,
            seen_by_camera: true,
            soft_falloff: false,
        };
        lights.push(Light::Sphere(sphere(Vec3::new(1.0, 3.0, 1.0), 0.0)));
        lights.push(Light::Sphere(sphere(Vec3::new(-2.0, 1.0, 0.0), 0.3)));
        lights.push(Light::Sun {
            direction: -Vec3::Y,
            irradiance: Illuminant::d65(Vec3::splat(0.01)),
            disc: Cone::from_half_angle(0.01),
            sphere: BoundingSphere { centre: Vec3::ZERO, radius: 10.0 },
        });
        lights
    }

    #[test]
    fn the_probabilities_it_samples_with_are_those_it_reports_and_sum_to_one() {
        let lights = many_lights();
        let powers: Vec<f64> = lights.iter().map(Light::power).collect();
        let tree = LightTree::new(&lights, &powers);
        for (p, n) in [
            (Vec3::new(0.0, 0.0, 0.0), Vec3::Y),
            (Vec3::new(4.0, 2.0, -3.0), Vec3::X),
            (Vec3::ZERO, Vec3::ZERO),
        ] {
            let sum: f64 = (0..lights.len()).map(|i| f64::from(tree.probability(p, n, i))).sum();
            assert!((sum - 1.0).abs() < 1e-4, "probabilities at {p} sum to {sum}");
            // Chi-square of the counts of 200000 stratified samples against those probabilities.
            let n_samples = 200_000;
            let mut counts = vec![0u32; lights.len()];
            for k in 0..n_samples {
                let (i, probability) = tree.sample(p, n, (k as f32 + 0.5) / n_samples as f32).unwrap();
                assert!((probability - tree.probability(p, n, i)).abs() <= 1e-5 * probability.max(1e-6));
                counts[i] += 1;
            }
            let chi2: f64 = counts
                .iter()
                .enumerate()
                .filter(|(i, _)| tree.probability(p, n, *i) > 0.0)
                .map(|(i, &c)| {
                    let expected = f64::from(tree.probability(p, n, i)) * n_samples as f64;
                    (f64::from(c) - expected).powi(2) / expected.max(1e-9)
                })
                .sum();
            // Stratified samples follow the probabilities far more closely than random ones.
            assert!(chi2 < lights.len() as f64, "chi-square {chi2} at {p}");
        }
    }
}
