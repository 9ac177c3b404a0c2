//! The multiple importance sampling weights of vertex connection and merging, all in one place.
//!
//! Georgiev, Křivánek, Davidovič & Slusallek (2012) and their technical report's recursive form:
//! each subpath carries three partial sums (`vcm`, `vc`, `vm`) of the ratios of the densities with
//! which the other techniques would have sampled its vertices, so that every estimator's weight
//! is found from the two subpaths' sums and the densities at its own vertices. With the power
//! heuristic (`mis(x) = x^2`), and merging counted as a technique of density a share
//! ([`MERGE_SHARE`]) of `pi r^2` times the light paths of the pass (its acceptance probability).
//!
//! Direct light is never merged (as SPPM stores no photon at a path's first vertex): merging a
//! light path's first vertex would blur what next-event estimation finds sharp (a shadow's edge),
//! and where a light emits into a narrow beam the weights would hand direct light to merging.
//! Merging there is left out of every weight: of light vertices one segment from their light
//! (their own merge, and the `vm_factor` terms for merging them), and of a camera vertex's next-
//! event estimation and of a camera path meeting a light (`vc_to_light`).
//!
//! Direct light is not light traced either: a light path's first vertex is not traced to the
//! camera. Next-event estimation finds direct light with low variance (its samples stratified
//! across passes), and the power heuristic, which weighs by density alone, handed light tracing a
//! fifth of it on the benchmarks' walls: a splat a pixel or so a pass, whose noise dominated
//! direct light (relative MSE at 20 CPU s 1.5e-3 with, 1.0e-3 without, on the diffuse box; as
//! much on the caustic box). Light tracing is left out of the weights of paths of two segments
//! (light, one vertex, camera): of next-event estimation at a camera path's first vertex
//! ([`Partials::without_light_tracing`]) and of a camera path meeting a light right after it
//! ([`Partials::past_first_camera_vertex`]).
//!
//! Merging stops where SPPM gathers: a camera path merges at its vertices up to its first where
//! photons are gathered ([`crate::materials::Bsdf::is_gathered_at`]: not a delta, a metal or a
//! narrow specular layer), glossy ones before it too, and at none past it ([`MergeVertex`]); so a
//! path is merged only at vertices with no gathering vertex between them and the camera, and each
//! light subpath carries its sums two ways to say which of its vertices those are
//! ([`LightPartials`]). Merging at every vertex, as Georgiev et al. do, let rare camera paths
//! find a caustic's dense photons a bounce away (the caustic box's ceiling, lit by the caustic
//! under its ball): a whole disc of photons at once, which weights made of densities per path do
//! not see as the jackpot it is: the caustic box's worst 1% of pixels held 62% of its error at
//! 10 CPU s. Stopping where SPPM gathers lowers the error at equal time on every scene measured
//! but the diffuse box, where it is about even (docs/vcm.md has the figures). Stopping at the
//! first vertex that is not a delta instead (a metal included) made the gold sphere 5x worse: its
//! reflection of the floor lost merging.
//!
//! Densities are of the hero wavelength's BSDF (every technique uses the same ones, so the
//! weights of a path still sum to one), and leave Russian roulette out (every technique leaves it
//! out alike).

/// The share of its acceptance probability `pi r^2 n` that merging is credited with in the
/// weights. Georgiev et al. credit all of it, as though a merge were as good an estimate as a
/// connection of that density; but a merge is biased (its disc blurs what it finds), its kernel
/// (the biweight, as SPPM's gather) has 1.8x the variance of a uniform disc's, and the light
/// vertices of a pass are shared by every pixel's merges. Any share keeps the weights of a path
/// summing to one; a quarter moved weight toward connections and path tracing where they do well
/// and measured best on the diffuse box, the caustic box and the glossy studio, a half and an
/// eighth between (docs/vcm.md has the figures).
const MERGE_SHARE: f32 = 0.25;

/// The heuristic: the power heuristic's square.
#[inline]
pub fn mis(x: f32) -> f32 {
    x * x
}

/// The weight of a technique whose density, relative to the others' summed in `others` (each
/// over its own), is 1. Where the sums overflow (a vertex seen at a grazing angle, two vertices
/// nearly touching) and make no number, the sample is left out: weight 0.
#[inline]
fn share(others: f32) -> f32 {
    let weight = 1.0 / (1.0 + others);
    if weight.is_nan() {
        0.0
    } else {
        weight
    }
}

/// What every weight of a pass shares: its merging radius and light path count.
#[derive(Clone, Copy, Debug)]
pub struct PassWeights {
    /// `mis(eta)`, `eta = MERGE_SHARE * pi r^2 n`: merging's density over a connection's.
    pub vm_factor: f32,
    /// `mis(1 / eta)`.
    pub vc_factor: f32,
    /// Light paths in the pass (`n`).
    pub light_paths: f32,
}

impl PassWeights {
    /// The weights of a pass of `light_paths` light paths, merging within `radius`.
    pub fn new(radius: f32, light_paths: usize) -> Self {
        let eta = MERGE_SHARE * std::f32::consts::PI * radius * radius * light_paths as f32;
        PassWeights { vm_factor: mis(eta), vc_factor: mis(1.0 / eta), light_paths: light_paths as f32 }
    }
}

/// A subpath's partial sums, as they stand at its last vertex.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Partials {
    /// Connection-or-merging at the vertex before.
    pub vcm: f32,
    /// Connections.
    pub vc: f32,
    /// Merging.
    pub vm: f32,
    /// `vc` for a camera path whose next vertex is on a light: without merging at the vertex it
    /// left, which is a light path's first (direct light is not merged).
    pub vc_to_light: f32,
}

/// The densities of a scattering at a vertex: of the direction sampled (`forward`) and of the way
/// back (`reverse`), per solid angle; the cosine of the sampled direction; a delta lobe's.
#[derive(Clone, Copy, Debug)]
pub struct Scatter {
    /// Density of the sampled direction.
    pub forward: f32,
    /// Density of the reverse direction, sampled from the sampled one.
    pub reverse: f32,
    /// Cosine between the sampled direction and the shading normal.
    pub cos_out: f32,
    /// The lobe is a delta.
    pub delta: bool,
}

impl Partials {
    /// A light path leaving a light whose emission density is `emission` (choice included), at
    /// `cos` from its normal; next-event estimation's density of its point is still to come, at
    /// the receiver (see [`Partials::chosen_at`]).
    pub fn leaving_light(pass: &PassWeights, emission: f32, cos: f32, delta: bool, finite: bool) -> Self {
        let vcm = mis(1.0 / emission);
        let vc = match (delta, finite) {
            (true, _) => 0.0,
            (false, true) => mis(cos / emission),
            (false, false) => mis(1.0 / emission),
        };
        Partials { vcm, vc, vm: vc * pass.vc_factor, vc_to_light: vc }
    }

    /// The camera path through one pixel, whose direction's density per solid angle in units of
    /// pixels is `camera_pdf`; light tracing (light paths meeting the camera) takes part when
    /// `light_tracing`.
    pub fn leaving_camera(pass: &PassWeights, camera_pdf: f32, light_tracing: bool) -> Self {
        let vcm = if light_tracing { mis(pass.light_paths / camera_pdf) } else { 0.0 };
        Partials { vcm, vc: 0.0, vm: 0.0, vc_to_light: 0.0 }
    }

    /// A camera path's sums at its first vertex, for next-event estimation there: direct light
    /// is not light traced, and light tracing's term is all they hold there.
    pub fn without_light_tracing(self) -> Self {
        Partials::default()
    }

    /// A camera path's sums as it leaves its first vertex: a light it meets next is that vertex's
    /// direct light, which is not light traced, and light tracing's term is all `vc_to_light`
    /// holds there.
    pub fn past_first_camera_vertex(self) -> Self {
        Partials { vc_to_light: 0.0, ..self }
    }

    /// A light path's first vertex: next-event estimation there picks the path's point on its
    /// light with density `direct` (per area, or per solid angle for a distant light; the light's
    /// choice included).
    pub fn chosen_at(self, direct: f32) -> Self {
        Partials { vcm: self.vcm * mis(direct), ..self }
    }

    /// Arriving at a vertex at `distance` (`None` for the first segment from a distant light),
    /// at `cos` from its shading normal.
    pub fn arrived(self, distance: Option<f32>, cos: f32) -> Self {
        let vcm = distance.map_or(self.vcm, |d| self.vcm * mis(d * d));
        let inv = 1.0 / mis(cos.abs().max(1e-7));
        Partials { vcm: vcm * inv, vc: self.vc * inv, vm: self.vm * inv, vc_to_light: self.vc_to_light * inv }
    }

    /// Leaving a vertex by `scatter`; `merged` whether merging at the vertex is a technique (not
    /// at a light path's first vertex).
    pub fn scattered(self, pass: &PassWeights, s: Scatter, merged: bool) -> Self {
        if s.delta {
            let cos = mis(s.cos_out);
            return Partials { vcm: 0.0, vc: self.vc * cos, vm: self.vm * cos, vc_to_light: self.vc * cos };
        }
        let out = mis(s.cos_out / s.forward);
        let connected = self.vc * mis(s.reverse) + self.vcm;
        let merging = if merged { 1.0 } else { 0.0 };
        Partials {
            vc: out * (connected + pass.vm_factor * merging),
            vm: out * (self.vm * mis(s.reverse) + self.vcm * pass.vc_factor + merging),
            vcm: mis(1.0 / s.forward),
            vc_to_light: out * connected,
        }
    }
}

/// Where a camera vertex lies on its path against the path's first vertex where photons are
/// gathered ([`crate::materials::Bsdf::is_gathered_at`]), as SPPM's visible point: the path
/// merges at every vertex up to that one (glossy ones before it too) and at none past it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MergeVertex {
    /// Before it (or the path has none): the vertex merges, and so do light vertices met here.
    Ahead,
    /// It is this one: the vertex merges, and light vertices met here do not.
    Here,
    /// Past it: nothing merges here.
    Behind,
}

impl MergeVertex {
    /// The state at the next vertex of a camera path, which gathers photons or not.
    pub fn next(self, gathered: bool) -> Self {
        match self {
            MergeVertex::Ahead if gathered => MergeVertex::Here,
            MergeVertex::Ahead => MergeVertex::Ahead,
            _ => MergeVertex::Behind,
        }
    }

    /// Whether a camera vertex here merges (if its lobe is not a delta).
    pub fn merges(self) -> bool {
        self != MergeVertex::Behind
    }
}

/// A light subpath's sums two ways, since a path merges only at vertices with no vertex where
/// photons are gathered between them and the camera: `none` with merging at none of its
/// vertices so far, `last` with merging at those past its last vertex where photons are
/// gathered, that one included (past the path's first vertex: direct light is not merged).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LightPartials {
    /// Merging at none of the subpath's vertices.
    pub none: Partials,
    /// Merging at its vertices from its last where photons are gathered on.
    pub last: Partials,
}

impl LightPartials {
    /// Both sums the same: `partials`, at a light.
    pub fn new(partials: Partials) -> Self {
        LightPartials { none: partials, last: partials }
    }

    /// Both sums changed alike by `change`.
    pub fn map(self, change: impl Fn(Partials) -> Partials) -> Self {
        LightPartials { none: change(self.none), last: change(self.last) }
    }

    /// Leaving a vertex by `scatter`, the vertex gathering photons or not (`gathered`), being
    /// past the path's first or not (`past_first`).
    pub fn scattered(self, pass: &PassWeights, scatter: Scatter, gathered: bool, past_first: bool) -> Self {
        let from = if gathered { self.none } else { self.last };
        LightPartials {
            none: self.none.scattered(pass, scatter, false),
            last: from.scattered(pass, scatter, past_first),
        }
    }

    /// The sums at a light vertex (gathering photons or not: `gathered`; past its path's first or
    /// not: `past_first`) for a technique whose camera side is at `camera`, and whether merging
    /// at the light vertex takes part.
    pub fn seen_from(self, camera: MergeVertex, gathered: bool, past_first: bool) -> (Partials, bool) {
        match camera {
            MergeVertex::Ahead if gathered => (self.none, past_first),
            MergeVertex::Ahead => (self.last, past_first),
            _ => (self.none, false),
        }
    }
}

/// The weight of a camera path meeting an emitter: `direct` the density with which next-event
/// estimation at the vertex before would have picked the point (per area, choice included; per
/// solid angle for distant lights), `emission` the light's density of emitting the path's last
/// segment (choice included). A camera ray meeting it first has weight 1.
pub fn emitter_met(camera: &Partials, direct: f32, emission: f32) -> f32 {
    share(mis(direct) * camera.vcm + mis(emission) * camera.vc_to_light)
}

/// The weight of next-event estimation: a light picked with probability `p_choice` and a
/// direction of density `direct` (per solid angle; a delta light's: the squared distance, or 1
/// when distant), which the BSDF samples with density `bsdf_forward` (0 for a delta light) and
/// the reverse with `bsdf_reverse`; the light emits the ray with `emission` (choice included), at
/// `cos_light` from its normal, arriving at `cos_here`.
pub struct DirectWeight {
    /// Choice probability of the light.
    pub p_choice: f32,
    /// Density of the direction, per solid angle.
    pub direct: f32,
    /// The BSDF's density of the direction toward the light.
    pub bsdf_forward: f32,
    /// The BSDF's density of the way back.
    pub bsdf_reverse: f32,
    /// The light's emission density of the ray, choice included.
    pub emission: f32,
    /// Cosine at the light.
    pub cos_light: f32,
    /// Cosine at the receiving vertex.
    pub cos_here: f32,
}

impl DirectWeight {
    /// The weight, for a camera path whose sums are `camera`.
    pub fn weight(&self, camera: &Partials) -> f32 {
        let w_light = mis(self.bsdf_forward / (self.p_choice * self.direct));
        let w_camera = mis(self.emission * self.cos_here / (self.p_choice * self.direct * self.cos_light))
            * (camera.vcm + camera.vc * mis(self.bsdf_reverse));
        share(w_light + w_camera)
    }
}

/// One end of a connection: the subpath's sums, and at its vertex the BSDF's density of the
/// connecting direction (`forward`) and of the way back (`reverse`), the cosine there, and
/// whether merging at the vertex is a technique (not at a light path's first vertex).
#[derive(Clone, Copy, Debug)]
pub struct End {
    /// The subpath's sums.
    pub partials: Partials,
    /// Density of the connecting direction from this end's incoming one.
    pub forward: f32,
    /// Density of the incoming direction from the connecting one.
    pub reverse: f32,
    /// Cosine of the connecting direction at this end.
    pub cos: f32,
    /// Merging at this end's vertex is a technique.
    pub merged: bool,
}

impl End {
    /// What merging at this end's vertex adds to the weights: `vm_factor`, or 0.
    fn merging(&self, pass: &PassWeights) -> f32 {
        if self.merged {
            pass.vm_factor
        } else {
            0.0
        }
    }
}

/// The weight of connecting a light vertex to a camera vertex `distance2` apart (squared).
pub fn connection(pass: &PassWeights, light: &End, camera: &End, distance2: f32) -> f32 {
    // Each end's density of the other's vertex, per area there.
    let camera_to_light = camera.forward * light.cos / distance2;
    let light_to_camera = light.forward * camera.cos / distance2;
    let w_light = mis(camera_to_light)
        * (light.merging(pass) + light.partials.vcm + light.partials.vc * mis(light.reverse));
    let w_camera = mis(light_to_camera)
        * (camera.merging(pass) + camera.partials.vcm + camera.partials.vc * mis(camera.reverse));
    share(w_light + w_camera)
}

/// The weight of merging a light vertex of sums `light` at a camera vertex of sums `camera`,
/// whose BSDF samples the light vertex's incoming direction with density `forward` and its own
/// incoming one from it with `reverse`.
pub fn merging(pass: &PassWeights, light: &Partials, camera: &Partials, forward: f32, reverse: f32) -> f32 {
    let w_light = light.vcm * pass.vc_factor + light.vm * mis(forward);
    let w_camera = camera.vcm * pass.vc_factor + camera.vm * mis(reverse);
    share(w_light + w_camera)
}

/// The weight of a light vertex seen by the camera (light tracing): `light` the vertex's end
/// toward the camera (its `forward` density and cosine are not read), `camera_area` the camera's
/// density of the vertex per area, in pixels.
pub fn light_traced(pass: &PassWeights, light: &End, camera_area: f32) -> f32 {
    let w_light = mis(camera_area / pass.light_paths)
        * (light.merging(pass) + light.partials.vcm + light.partials.vc * mis(light.reverse));
    share(w_light)
}

#[cfg(test)]
mod tests {
    //! The weights of every technique that can sample a path sum to one: checked on random paths
    //! of Lambertian and delta (mirror or glass) vertices between an area light and a pinhole
    //! camera, each technique's weight found as its estimator finds it (the sums carried along
    //! each subpath, then the technique's own densities). No technique connects or merges at a
    //! delta vertex.
    use super::*;
    use glam::Vec3;
    use std::f32::consts::FRAC_1_PI;

    /// A path `v[0]` (on the light) .. `v[k]` (the camera), each vertex with a unit normal.
    struct Path {
        p: Vec<Vec3>,
        n: Vec<Vec3>,
        /// Which vertices scatter by a delta lobe (never the light's or the camera's).
        delta: Vec<bool>,
        /// Which vertices gather photons (a camera path merges at its first), of those that are
        /// not deltas; the others are as glossy lobes.
        gathered: Vec<bool>,
    }

    /// The pass: its weights, the light's area, its choice probabilities (emission by power,
    /// next-event estimation by the tree: different) and the camera's density of the path's first
    /// direction.
    struct Setup {
        pass: PassWeights,
        area: f32,
        p_emit: f32,
        p_nee: f32,
        camera_pdf: f32,
    }

    impl Path {
        fn dir(&self, from: usize, to: usize) -> Vec3 {
            (self.p[to] - self.p[from]).normalize()
        }
        fn d2(&self, a: usize, b: usize) -> f32 {
            self.p[a].distance_squared(self.p[b])
        }
        fn cos(&self, at: usize, to: usize) -> f32 {
            self.n[at].dot(self.dir(at, to)).abs()
        }
        /// A Lambertian vertex's density of the direction toward `to` (any incoming direction).
        fn pdf(&self, at: usize, to: usize) -> f32 {
            self.cos(at, to) * FRAC_1_PI
        }
        /// The light subpath's sums at `v[last]`, as `light_paths.rs` carries them.
        fn light_sums(&self, s: &Setup, last: usize) -> LightPartials {
            let emission = self.cos(0, 1) * FRAC_1_PI / s.area * s.p_emit;
            let leaving = Partials::leaving_light(&s.pass, emission, self.cos(0, 1), false, true);
            let mut sums = LightPartials::new(leaving);
            for i in 1..=last {
                sums = sums.map(|p| p.arrived(Some(self.d2(i - 1, i).sqrt()), self.cos(i, i - 1)));
                if i == 1 {
                    sums = sums.map(|p| p.chosen_at(s.p_nee / s.area));
                }
                if i < last {
                    let scatter = Scatter {
                        forward: self.pdf(i, i + 1),
                        reverse: self.pdf(i, i - 1),
                        cos_out: self.cos(i, i + 1),
                        delta: self.delta[i],
                    };
                    sums = sums.scattered(&s.pass, scatter, self.gathered[i], i > 1);
                }
            }
            sums
        }
        /// The camera subpath's sums at `v[last]`, as `eye_paths.rs` carries them.
        fn camera_sums(&self, s: &Setup, last: usize) -> Partials {
            let k = self.p.len() - 1;
            let mut sums = Partials::leaving_camera(&s.pass, s.camera_pdf, true);
            for i in (last..k).rev() {
                sums = sums.arrived(Some(self.d2(i + 1, i).sqrt()), self.cos(i, i + 1));
                if i > last {
                    let scatter = Scatter {
                        forward: self.pdf(i, i - 1),
                        reverse: self.pdf(i, i + 1),
                        cos_out: self.cos(i, i - 1),
                        delta: self.delta[i],
                    };
                    sums = sums.scattered(&s.pass, scatter, i >= self.merged_at());
                    if i == k - 1 {
                        sums = sums.past_first_camera_vertex();
                    }
                }
            }
            sums
        }
        /// The camera path's first vertex that gathers photons (0 where none does): it merges
        /// there and at every vertex before.
        fn merged_at(&self) -> usize {
            let k = self.p.len() - 1;
            (1..k).rev().find(|&i| self.gathered[i]).unwrap_or(0)
        }
        /// Every technique's weight for the path.
        fn weights(&self, s: &Setup) -> Vec<(String, f32)> {
            let k = self.p.len() - 1;
            let mut all = Vec::new();
            // The camera path meets the light.
            let direct_area = s.p_nee / s.area;
            let emission = self.cos(0, 1) * FRAC_1_PI / s.area * s.p_emit;
            all.push(("emitter met".into(), emitter_met(&self.camera_sums(s, 0), direct_area, emission)));
            // Next-event estimation at v[1].
            let nee = DirectWeight {
                p_choice: s.p_nee,
                direct: self.d2(0, 1) / (s.area * self.cos(0, 1)),
                bsdf_forward: self.pdf(1, 0),
                bsdf_reverse: self.pdf(1, 2),
                emission,
                cos_light: self.cos(0, 1),
                cos_here: self.cos(1, 0),
            };
            if !self.delta[1] {
                let camera = match k {
                    2 => self.camera_sums(s, 1).without_light_tracing(),
                    _ => self.camera_sums(s, 1),
                };
                all.push(("next-event".into(), nee.weight(&camera)));
            }
            // Connections v[i - 1] (light) to v[i] (camera).
            for i in (2..k).filter(|&i| !self.delta[i - 1] && !self.delta[i]) {
                let seen_from = match i.cmp(&self.merged_at()) {
                    std::cmp::Ordering::Greater => MergeVertex::Ahead,
                    std::cmp::Ordering::Equal => MergeVertex::Here,
                    std::cmp::Ordering::Less => MergeVertex::Behind,
                };
                let light_sums = self.light_sums(s, i - 1);
                let (partials, merged) = light_sums.seen_from(seen_from, self.gathered[i - 1], i - 1 > 1);
                let light = End {
                    partials,
                    forward: self.pdf(i - 1, i),
                    reverse: self.pdf(i - 1, i - 2),
                    cos: self.cos(i - 1, i),
                    merged,
                };
                let camera = End {
                    partials: self.camera_sums(s, i),
                    forward: self.pdf(i, i - 1),
                    reverse: self.pdf(i, i + 1),
                    cos: self.cos(i, i - 1),
                    merged: i >= self.merged_at(),
                };
                all.push((
                    format!("connection {i}"),
                    connection(&s.pass, &light, &camera, self.d2(i - 1, i)),
                ));
            }
            // Light tracing from v[k - 1], unless it is the light path's first vertex.
            let camera_area = s.camera_pdf * self.cos(k - 1, k) / self.d2(k - 1, k);
            let light_sums = self.light_sums(s, k - 1);
            let (partials, merged) =
                light_sums.seen_from(MergeVertex::Ahead, self.gathered[k - 1], k - 1 > 1);
            let light = End {
                partials,
                forward: 0.0,
                reverse: self.pdf(k - 1, k - 2),
                cos: self.cos(k - 1, k),
                merged,
            };
            if !self.delta[k - 1] && k - 1 > 1 {
                all.push(("light traced".into(), light_traced(&s.pass, &light, camera_area)));
            }
            // Merging where the camera path merges, but at the light path's first vertex (direct
            // light is not merged).
            for i in (2..k).filter(|&i| !self.delta[i] && i >= self.merged_at()) {
                let light_sums = self.light_sums(s, i);
                let w = merging(
                    &s.pass,
                    if self.gathered[i] { &light_sums.none } else { &light_sums.last },
                    &self.camera_sums(s, i),
                    self.pdf(i, i - 1),
                    self.pdf(i, i + 1),
                );
                all.push((format!("merge {i}"), w));
            }
            all
        }
    }

    /// A small deterministic stream of uniform numbers.
    struct Lcg(u64);

    impl Lcg {
        fn next(&mut self) -> f32 {
            self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (self.0 >> 40) as f32 / (1u64 << 24) as f32
        }
        fn vec(&mut self) -> Vec3 {
            Vec3::new(self.next(), self.next(), self.next()) * 2.0 - 1.0
        }
    }

    #[test]
    fn every_techniques_weight_sums_to_one_along_random_paths() {
        let mut rng = Lcg(7);
        let (mut with_delta, mut with_glossy) = (0, 0);
        for trial in 0..400 {
            let k = 2 + trial % 6;
            let p: Vec<Vec3> = (0..=k).map(|_| rng.vec()).collect();
            let n: Vec<Vec3> = (0..=k).map(|_| rng.vec().normalize()).collect();
            let delta: Vec<bool> = (0..=k).map(|i| i > 0 && i < k && rng.next() < 0.3).collect();
            let gathered: Vec<bool> = delta.iter().map(|&d| !d && rng.next() < 0.7).collect();
            with_delta += usize::from(delta.contains(&true));
            with_glossy += usize::from((1..k).any(|i| !delta[i] && !gathered[i]));
            let path = Path { p, n, delta, gathered };
            let setup = Setup {
                pass: PassWeights::new(0.01 + 0.2 * rng.next(), 1000 + (rng.next() * 50000.0) as usize),
                area: 0.1 + rng.next(),
                p_emit: 0.05 + 0.95 * rng.next(),
                p_nee: 0.05 + 0.95 * rng.next(),
                camera_pdf: 1e4 + 1e6 * rng.next(),
            };
            let weights = path.weights(&setup);
            let sum: f32 = weights.iter().map(|(_, w)| w).sum();
            assert!((sum - 1.0).abs() < 1e-3, "path of {k} segments: weights sum to {sum}: {weights:?}");
            assert!(weights.iter().all(|(_, w)| (0.0..=1.0).contains(w)), "{weights:?}");
        }
        assert!(with_delta > 100, "only {with_delta} paths had a delta vertex");
        assert!(with_glossy > 100, "only {with_glossy} paths had a glossy vertex");
    }
}
