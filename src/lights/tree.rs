//! A light tree for next-event estimation (Conty Estevez & Kulla 2018, "Importance Sampling of
//! Many Lights with Adaptive Tree Splitting", as pbrt-v4's BVH light sampler): a bounding volume
//! hierarchy over the lights with their power, bounds and emission cones. A point picks a light
//! by walking down from the root, at each node choosing a child in proportion to an upper bound
//! of what the child's lights can send it (power over squared distance, times the best cosines
//! its bounds allow at the light and at the point); the probability of a light is the product of
//! the choices on its path, found again from the bits of that path.
//!
//! The tree is built binary, by pbrt-v4's cost, and then two levels at a time are collapsed into
//! nodes of four children whose bounds are weighed together in the lanes of one vector: half the
//! levels to walk and a quarter of the arithmetic (on 2400 bulbs the tree's share of a pass fell
//! from 15% to 9%).
//!
//! Distant lights (a sun, the world) stand beside the tree: the tree as a whole and each distant
//! light are chosen in proportion to their power, as every light is without the tree.

use glam::{BVec4A, Quat, Vec3, Vec4};
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

/// Four children's bounds as sampling reads them, a child per lane (a lane without a child has
/// no power), so that one pass of vector arithmetic weighs all four.
#[derive(Clone, Copy, Debug)]
struct Bounds4 {
    /// The boxes' centres, by coordinate.
    centre: [Vec4; 3],
    /// The squares of the radii of the spheres around the boxes.
    radius2: Vec4,
    /// The least squared distance importance divides by (pbrt-v4's: half the box's diagonal).
    nearest2: Vec4,
    /// The cones' axes, by coordinate.
    axis: [Vec4; 3],
    cos_o: Vec4,
    sin_o: Vec4,
    cos_e: Vec4,
    phi: Vec4,
    two_sided: BVec4A,
}

impl Bounds4 {
    /// The bounds of up to four children, lane by lane.
    fn of(children: &[LightBounds]) -> Bounds4 {
        let lane = |f: &dyn Fn(&LightBounds) -> f32, empty: f32| {
            Vec4::from_array(std::array::from_fn(|k| children.get(k).map_or(empty, f)))
        };
        let coordinate = |f: &dyn Fn(&LightBounds) -> Vec3| -> [Vec4; 3] {
            std::array::from_fn(|axis| lane(&|b| f(b)[axis], 0.0))
        };
        let half_diagonal2 = |b: &LightBounds| (b.hi - b.lo).length_squared() / 4.0;
        Bounds4 {
            centre: coordinate(&LightBounds::centroid),
            radius2: lane(&half_diagonal2, 0.0),
            nearest2: lane(&|b| half_diagonal2(b).sqrt(), 1.0),
            axis: coordinate(&|b| b.axis),
            cos_o: lane(&|b| b.cos_o, 1.0),
            sin_o: lane(&|b| (1.0 - b.cos_o * b.cos_o).max(0.0).sqrt(), 0.0),
            cos_e: lane(&|b| b.cos_e, 1.0),
            phi: lane(&|b| b.phi, 0.0),
            two_sided: BVec4A::from_array(std::array::from_fn(|k| {
                children.get(k).is_some_and(|b| b.two_sided)
            })),
        }
    }

    /// For each child, an upper bound, up to a constant, of the light its lights send to a point
    /// `p` whose surface has the unit normal `n` (zero: no surface): pbrt-v4's
    /// `LightBounds::Importance`, four at a time.
    #[inline]
    fn importance(&self, p: Vec3, n: Vec3) -> Vec4 {
        let to_p = [
            Vec4::splat(p.x) - self.centre[0],
            Vec4::splat(p.y) - self.centre[1],
            Vec4::splat(p.z) - self.centre[2],
        ];
        let distance2 = to_p[0] * to_p[0] + to_p[1] * to_p[1] + to_p[2] * to_p[2];
        let inverse_distance = distance2.sqrt().max(Vec4::splat(f32::MIN_POSITIVE)).recip();
        // The cone of directions from p that each box's sphere covers (all of them from inside).
        let inside = distance2.cmple(self.radius2);
        let sin2_b = (self.radius2 * distance2.max(Vec4::splat(f32::MIN_POSITIVE)).recip()).min(Vec4::ONE);
        let cos_b = Vec4::select(inside, Vec4::NEG_ONE, (Vec4::ONE - sin2_b).sqrt());
        let sin_b = Vec4::select(inside, Vec4::ZERO, sin2_b.sqrt());
        // The least angle between an emitter's normal and p (pbrt-v4's theta'): the angle to the
        // cone's axis less the cone's and the box's widths.
        let toward =
            (self.axis[0] * to_p[0] + self.axis[1] * to_p[1] + self.axis[2] * to_p[2]) * inverse_distance;
        let cos_w = Vec4::select(self.two_sided, toward.abs(), toward);
        let cos_p = cos_angle_less(cos_angle_less(cos_w, self.cos_o, self.sin_o), cos_b, sin_b);
        let mut importance = self.phi * cos_p / distance2.max(self.nearest2);
        if n != Vec3::ZERO {
            let cos_i = ((to_p[0] * n.x + to_p[1] * n.y + to_p[2] * n.z) * inverse_distance).abs();
            importance *= cos_angle_less(cos_i, cos_b, sin_b);
        }
        // Zero where the emitters face away, and for lanes without a child (NaN compares false).
        Vec4::select(cos_p.cmpgt(self.cos_e) & importance.cmpgt(Vec4::ZERO), importance, Vec4::ZERO)
    }
}

/// The cosine of the angle a (of cosine `cos_a`, in [0, pi]) minus the angle b, clamped at 0,
/// lane by lane.
#[inline]
fn cos_angle_less(cos_a: Vec4, cos_b: Vec4, sin_b: Vec4) -> Vec4 {
    let sin_a = (Vec4::ONE - cos_a * cos_a).max(Vec4::ZERO).sqrt();
    Vec4::select(cos_a.cmpgt(cos_b), Vec4::ONE, cos_a * cos_b + sin_a * sin_b)
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

/// Where a slot of a node leads.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Child {
    /// No child (a node with fewer than four).
    Empty,
    /// The node of this index.
    Node(u32),
    /// The light of this index.
    Light(u32),
}

/// A node of four children (two levels of the binary tree the build makes, collapsed).
#[derive(Clone, Copy, Debug)]
struct Node {
    bounds: Bounds4,
    children: [Child; 4],
}

/// A binary node as the build makes it, before two levels are collapsed into one four-wide node.
struct BinaryNode {
    bounds: LightBounds,
    /// Its two children, or `None` for a leaf.
    children: Option<[usize; 2]>,
    /// Its light, for a leaf.
    light: u32,
}

/// Bits of a path kept per level: the slot of one of four children.
const SLOT_BITS: u32 = 2;

/// A light tree over a scene's lights.
#[derive(Clone, Debug)]
pub struct LightTree {
    nodes: Vec<Node>,
    /// Where sampling starts: the root node, the only light, or nothing.
    root: Child,
    /// For each light by index: the slots of its path from the root (`SLOT_BITS` a level) and
    /// its depth, for lights in the tree.
    paths: Vec<Option<(u64, u32)>>,
    /// Distant lights by index.
    distant: Vec<usize>,
    /// The distant lights and, as the last entry, the tree, by power.
    top: Distribution1D,
}

impl Default for LightTree {
    fn default() -> Self {
        LightTree::new(&[], &[])
    }
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
        let mut tree = LightTree {
            nodes: Vec::new(),
            root: Child::Empty,
            paths: vec![None; lights.len()],
            distant: Vec::new(),
            top: Distribution1D::new([]),
        };
        let mut tree_power = 0.0;
        if !leaves.is_empty() {
            let mut binary = Vec::new();
            build_binary(&mut binary, &mut leaves, 0);
            tree_power = f64::from(binary[0].bounds.phi);
            tree.root = tree.collapse(&binary, 0, 0, 0);
        }
        tree.top = Distribution1D::new(distant.iter().map(|&i| powers[i]).chain([tree_power]));
        tree.distant = distant;
        tree
    }

    /// The four-wide subtree of binary node `at`, whose path from the root is `bits` at `depth`:
    /// its children are the binary node's grandchildren (or its children where those are leaves).
    fn collapse(&mut self, binary: &[BinaryNode], at: usize, bits: u64, depth: u32) -> Child {
        let Some(children) = binary[at].children else {
            let light = binary[at].light;
            self.paths[light as usize] = Some((bits, depth));
            return Child::Light(light);
        };
        let slots: Vec<usize> =
            children.iter().flat_map(|&c| binary[c].children.map_or(vec![c], |g| g.to_vec())).collect();
        let bounds: Vec<LightBounds> = slots.iter().map(|&c| binary[c].bounds).collect();
        let index = self.nodes.len();
        self.nodes.push(Node { bounds: Bounds4::of(&bounds), children: [Child::Empty; 4] });
        for (slot, &c) in slots.iter().enumerate() {
            let child = self.collapse(binary, c, bits | (slot as u64) << (SLOT_BITS * depth), depth + 1);
            self.nodes[index].children[slot] = child;
        }
        Child::Node(index as u32)
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
        let (mut child, mut probability) = (self.root, p_top);
        loop {
            match child {
                Child::Empty => return None,
                Child::Light(light) => return Some((light as usize, probability)),
                Child::Node(index) => {
                    let node = &self.nodes[index as usize];
                    let shares = self.shares(node, p, n);
                    let (slot, share, rest) = choose(shares, u);
                    u = rest;
                    probability *= share;
                    child = node.children[slot];
                }
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
        let mut child = self.root;
        for level in 0..depth {
            let Child::Node(index) = child else { return 0.0 };
            let node = &self.nodes[index as usize];
            let slot = (bits >> (SLOT_BITS * level) & 0b11) as usize;
            probability *= self.shares(node, p, n)[slot];
            child = node.children[slot];
        }
        probability
    }

    /// The probabilities of going on to each child of `node` from `p` (normal `n`): their shares
    /// of the children's importance, or, where none can light `p` by its bounds though their
    /// parent could, their shares of the power (so that every light reachable by its ancestors
    /// keeps a probability, and they sum to one).
    fn shares(&self, node: &Node, p: Vec3, n: Vec3) -> [f32; 4] {
        let importance = node.bounds.importance(p, n);
        let sum = importance.element_sum();
        let weights = if sum > 0.0 && sum.is_finite() { importance } else { node.bounds.phi };
        (weights / weights.element_sum()).to_array()
    }
}

/// The slot `u` chooses among `shares` (summing to one), its share, and `u` rescaled within it.
fn choose(shares: [f32; 4], u: f32) -> (usize, f32, f32) {
    let mut below = 0.0;
    let last = shares.iter().rposition(|&s| s > 0.0).unwrap_or(0);
    for (slot, &share) in shares.iter().enumerate() {
        if share > 0.0 && (u < below + share || slot == last) {
            return (slot, share, ((u - below) / share).clamp(0.0, 1.0 - f32::EPSILON));
        }
        below += share;
    }
    (last, shares[last], u)
}

/// Builds the binary tree over `leaves` into `nodes` (its root first), at `depth`; gives the
/// index of its root.
fn build_binary(nodes: &mut Vec<BinaryNode>, leaves: &mut [(LightBounds, u32)], depth: u32) -> usize {
    let at = nodes.len();
    if let [(bounds, light)] = leaves {
        nodes.push(BinaryNode { bounds: *bounds, children: None, light: *light });
        return at;
    }
    nodes.push(BinaryNode { bounds: leaves[0].0, children: None, light: 0 });
    let mid = split(leaves, depth);
    let (first, second) = leaves.split_at_mut(mid);
    let a = build_binary(nodes, first, depth + 1);
    let b = build_binary(nodes, second, depth + 1);
    nodes[at].bounds = nodes[a].bounds.union(&nodes[b].bounds);
    nodes[at].children = Some([a, b]);
    at
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
