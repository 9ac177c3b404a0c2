//! Camera subpaths: a camera ray per pixel followed through every bounce (Russian roulette after
//! the third, and a quarter of paths going on past the vertex where they gather), and at each
//! vertex whose BSDF is not a delta the estimators that meet light subpaths there: next-event
//! estimation, connections to the pixel's light path, and, up to the path's first vertex where
//! photons are gathered (see `mis.rs`), merging with the pass's light vertices. Emission the path
//! meets is weighted against them.
//!
//! A path splits in two at its first glossy vertex (not a delta, before the vertex where it
//! gathers: a metal, a rough coat), after that vertex's own estimators: a branch samples the lobe
//! again from a Sobol sequence of its own (stratified over passes, as the path's first sample
//! is) and follows it up to the vertex where it gathers, and there it ends. Whatever the path and
//! its branch find between the split and that vertex (emission met, next-event estimation,
//! connections, merging) counts half from each; what the path finds past it counts whole, as
//! before. Each estimator is unbiased on its own and so is the mean of two, and the weights of a
//! path still sum to one along each branch. What a glossy surface mirrors (the floor a gold ball
//! reflects, a glass ball beside it and what the ball sees, the edge of a light's highlight) is
//! an integral over its lobe of light with high contrast, which one direction a pass samples
//! poorly; the second direction costs a few rays and one gathering vertex's estimators.
//! Measured on the glossy studio (issue 22, 96x72, VCM, 1000 passes, 4 seeds): the gold sphere's
//! relative MSE 4.18e-4 -> 3.50e-4, the whole image's 9.84e-4 -> 9.56e-4, for 5% more
//! instructions. Branches that continued to the path's end found no more (3.49e-4) for 2% more
//! again; branches that only merged found almost nothing (4.12e-4): the merges' noise there is
//! their light vertices', not the lobe's. A scene with no glossy vertex renders the same bits.

use glam::Vec3;

use super::connect::{connect, direct_light};
use super::finite;
use super::light_paths::LightVertex;
use super::merge::{merge, CameraVertex, KeptMerge, MergeSet};
use super::mis::{emitter_met, MergeVertex, Partials, PassWeights, Scatter};
use super::view::View;
use super::{LightSubpaths, Retraced};
use crate::geometry::offset_origin;
use crate::lights::Light;
use crate::materials::{Bsdf, Material, ShadingFrame, Transport};
use crate::scene::{OpenEdges, Surface, NOT_A_LIGHT};
use crate::spectrum::{hero_only, SampledSpectrum, LANES};
use crate::transport::context::{PassSamples, PassStats, PixelEstimate, Renderer, MAX_DEPTH};
use crate::transport::emission::chunk_of;
#[cfg(doc)]
use crate::transport::emission::photon_chunks;
use crate::transport::eye::{start_eye_path, EyeState, Meeting};

/// Bounces before Russian roulette may end a camera path.
const ROULETTE_AFTER: u32 = 3;

/// The probability that a camera path goes on past the vertex where it gathers (times what
/// Russian roulette keeps). Merging there already finds light arriving by every path from the
/// lights, so what the path finds further on (connections and next-event estimation at later
/// vertices, emission it meets) shares that light with merging, so going on one time in four
/// adds little variance (5-12% more error at equal passes), while going on always costs a
/// quarter to a half of a pass: several rays at each vertex. It lowered relative MSE times
/// render time on every scene measured (docs/vcm.md); a half was as good or a little worse. The
/// weights leave it out, as they leave out Russian roulette.
const PAST_GATHER: f32 = 0.25;

/// The branches a camera path splits into at its first glossy vertex.
const GLOSSY_BRANCHES: u32 = 2;

/// What a pass's camera paths meet light subpaths with.
pub struct Lights<'a> {
    /// The light paths, in the chunks they were traced in (see [`photon_chunks`]).
    pub chunks: &'a [LightSubpaths],
    /// Light paths in all.
    pub paths: usize,
    /// The light vertices for merging, in one set or more, each without the vertices of the
    /// paths it lists (increasing).
    pub merge_sets: &'a [(&'a MergeSet, &'a [u32])],
    /// Where the surfaces merged on end.
    pub open_edges: &'a OpenEdges,
    /// Keep the camera vertices merged at (for the frames of a block).
    pub keep_merges: bool,
    /// Paths a frame traced again, in place of the chunks' (reuse across frames).
    pub retraced: Option<&'a Retraced>,
}

impl Lights<'_> {
    /// The light path paired with film pixel `pixel`.
    fn path_of(&self, pixel: usize) -> &[LightVertex] {
        if self.paths == 0 {
            return &[];
        }
        let k = pixel % self.paths;
        if let Some(path) = self.retraced.and_then(|r| r.path(k as u64)) {
            return path;
        }
        let (chunk, k) = chunk_of(k);
        self.chunks[chunk].path(k)
    }
}

/// The vertex a camera path scattered at last, for the density with which next-event estimation
/// there would have picked a light the path meets.
#[derive(Clone, Copy)]
struct Previous {
    p: Vec3,
    n: Vec3,
}

/// A camera path (or a branch of one) between vertices: its state, its MIS sums, the vertex it
/// left, the distance since it, its segments, where it stands against its merging vertex, and
/// its part in the split at its first glossy vertex.
#[derive(Clone)]
struct Walk {
    state: EyeState,
    partials: Partials,
    previous: Option<Previous>,
    travelled: f32,
    segments: u32,
    merging: MergeVertex,
    part: Part,
}

/// A walk's part in the split at its path's first glossy vertex.
#[derive(Clone, Copy, PartialEq)]
enum Part {
    /// The path has not split yet.
    Unsplit,
    /// The path, between the split and the vertex where it gathers: its estimates there count
    /// for a share, its branches' for the rest.
    Shared,
    /// The path, past the vertex where it gathers: its estimates count whole again.
    Past,
    /// A branch, which ends at the vertex where it gathers.
    Branch,
}

impl Part {
    /// What a walk's estimates count for.
    fn scale(self) -> f32 {
        match self {
            Part::Shared | Part::Branch => 1.0 / GLOSSY_BRANCHES as f32,
            Part::Unsplit | Part::Past => 1.0,
        }
    }
}

/// What a camera path finds: its pixel's estimate, and where it merged.
pub struct Found {
    /// The pixel's estimate.
    pub estimate: PixelEstimate,
    /// The camera vertices it merged at, where its lights ask to keep them.
    pub kept: Vec<KeptMerge>,
}

/// Traces pixel `pixel`'s camera path for `pass`.
pub fn trace_camera_path(
    renderer: &Renderer,
    pass: &PassSamples,
    (weights, view): (&PassWeights, &View),
    lights: &Lights,
    pixel: usize,
) -> (Found, PassStats) {
    let (state, mut stats) = start_eye_path(renderer, pass, pixel);
    let partials = Partials::leaving_camera(weights, view.pdf(state.direction.into()), view.traces_lights());
    let mut walk = Walk {
        state,
        partials,
        previous: None,
        travelled: 0.0,
        segments: 0,
        merging: MergeVertex::Ahead,
        part: Part::Unsplit,
    };
    let estimate =
        PixelEstimate { radiance: SampledSpectrum::ZERO, laplacian: SampledSpectrum::ZERO, coverage: 1.0 };
    let mut found = Found { estimate, kept: Vec::new() };
    let mut branches = Vec::new();
    loop {
        walk_camera_path(
            renderer,
            pass,
            (weights, lights, pixel),
            walk,
            &mut found,
            &mut stats,
            &mut branches,
        );
        match branches.pop() {
            Some(next) => walk = next,
            None => break,
        }
    }
    (found, stats)
}

/// Follows `walk` to its end, adding what it finds to `found`; the branches it splits off are
/// pushed to `branches`, to be followed after it.
fn walk_camera_path(
    renderer: &Renderer,
    pass: &PassSamples,
    (weights, lights, pixel): (&PassWeights, &Lights, usize),
    mut walk: Walk,
    found: &mut Found,
    stats: &mut PassStats,
    branches: &mut Vec<Walk>,
) {
    let Found { estimate, kept } = found;
    let scene = renderer.scene;
    let lambda = &pass.wavelengths;
    while walk.state.depth < MAX_DEPTH {
        let scale = walk.part.scale();
        let state = &mut walk.state;
        stats.eye_rays += 1;
        let direction = Vec3::from(state.direction);
        let hit = renderer.accel.intersect(state.origin.into(), direction, f32::INFINITY);
        renderer.watch(state.origin.into(), direction, hit.map_or(f32::INFINITY, |h| h.t), stats);
        if !scene.sphere_lights.is_empty() {
            let segment = (walk.travelled, hit.map_or(f32::INFINITY, |h| h.t));
            estimate.radiance +=
                finite(spheres_met(renderer, pass, (state, &walk.partials, walk.previous), segment)) * scale;
        }
        let Some(hit) = hit else {
            if state.camera_ray && scene.transparent_film {
                estimate.coverage = 0.0;
            } else if !(renderer.has_volumes && state.media.medium(scene).is_some()) {
                estimate.radiance +=
                    finite(state.beta * escaped(renderer, pass, &walk.partials, walk.previous, direction))
                        * scale;
            }
            return;
        };
        walk.travelled += hit.t;
        if renderer.has_volumes {
            if let Some(kept) = state.media.transmittance(scene, lambda, hit.t) {
                state.beta *= kept;
            }
        }
        let surface = scene.surface(&hit, lambda);
        let material = &scene.materials[surface.material as usize];
        let wo = -direction;
        if !(state.camera_ray && (material.holdout || !material.seen_by_camera)) {
            let emitted = material.emitted(&surface.inputs, lambda, surface.frame.ng(), wo);
            if emitted.max_element() > 0.0 {
                let light = scene.triangle_light(hit.triangle);
                let weight = match walk.previous {
                    Some(prev) if light != NOT_A_LIGHT => {
                        let arrived = walk.partials.arrived(Some(walk.travelled), surface.frame.n().dot(wo));
                        emitter_weight(renderer, &arrived, prev, (light as usize, surface.p), wo)
                    }
                    _ => 1.0,
                };
                estimate.radiance += finite(state.beta * emitted * weight) * scale;
            }
        }
        let lobe = material.lobe(&surface.inputs, surface.frame, wo, lambda, state.rng.next_1d());
        match state.meet(&lobe.bsdf, material.holdout, &surface, wo) {
            Meeting::Ends { coverage: seen } => {
                estimate.coverage = seen;
                return;
            }
            Meeting::PassesThrough => continue,
            Meeting::Scatters => {}
        }
        let (frame, bsdf) = (lobe.frame, lobe.bsdf);
        // The sums at the vertex take the cosine of the lobe's normals, as connections there do.
        walk.partials = walk.partials.arrived(Some(walk.travelled), frame.n().dot(wo));
        walk.travelled = 0.0;
        walk.segments += 1;
        state.beta *= lobe.weight;
        walk.merging = walk.merging.next(bsdf.is_gathered_at());
        if !bsdf.is_delta() {
            let camera = CameraVertex {
                p: surface.p,
                wo,
                frame,
                bsdf: &bsdf,
                beta: state.beta,
                hero_only: state.hero_only,
                partials: walk.partials,
                segments: walk.segments,
                merging: walk.merging,
                media: (state.media, surface.material),
            };
            let at = (&camera, surface.scale);
            estimate.radiance += direct_light(renderer, pass, at, &mut state.rng, stats) * scale;
            estimate.radiance +=
                connect(renderer, pass, weights, at, lights.path_of(pixel), MAX_DEPTH, stats) * scale;
            if walk.merging.merges() {
                let edges = (lights.open_edges, lights.keep_merges);
                let merged = merge(lights.merge_sets, edges, weights, &camera, MAX_DEPTH);
                estimate.radiance += merged.radiance * scale;
                estimate.laplacian += merged.laplacian * scale;
                if lights.keep_merges {
                    kept.push(KeptMerge::new(&camera, scale, merged.mass.unwrap_or(1.0)));
                }
            }
        }
        if walk.merging != MergeVertex::Ahead {
            match walk.part {
                Part::Branch => return,
                Part::Shared => walk.part = Part::Past,
                Part::Unsplit | Part::Past => {}
            }
        }
        let vertex = Vertex { surface: &surface, material, frame, bsdf: &bsdf, wo };
        if walk.part == Part::Unsplit && !bsdf.is_delta() && walk.merging == MergeVertex::Ahead {
            walk.part = Part::Shared;
            for b in 1..GLOSSY_BRANCHES {
                let mut branch = walk.clone();
                branch.part = Part::Branch;
                branch.state.rng = walk.state.rng.branch(b);
                if leave_vertex(renderer, weights, &mut branch, &vertex) {
                    branches.push(branch);
                }
            }
        }
        if !leave_vertex(renderer, weights, &mut walk, &vertex) {
            return;
        }
    }
}

/// A camera vertex a walk leaves: the surface, its material, the lobe's normals and BSDF, and
/// the direction back along the path.
struct Vertex<'a> {
    surface: &'a Surface,
    material: &'a Material,
    frame: ShadingFrame,
    bsdf: &'a Bsdf,
    wo: Vec3,
}

/// Samples `walk`'s next direction at `vertex` and moves it onto the segment; false where the
/// path ends there.
fn leave_vertex(renderer: &Renderer, weights: &PassWeights, walk: &mut Walk, vertex: &Vertex) -> bool {
    let Vertex { surface, material, frame, bsdf, wo } = *vertex;
    let state = &mut walk.state;
    let rng = &mut state.rng;
    let u = rng.next_2d();
    let u_lobe = bsdf.lobe_number(|| rng.next_1d());
    let Some(sample) = bsdf.sample(frame, wo, u, u_lobe, Transport::Radiance) else {
        return false;
    };
    let roulette = match walk.segments > ROULETTE_AFTER {
        true => (sample.weight.element_sum() / LANES as f32).min(1.0),
        false => 1.0,
    };
    let survive = match walk.merging {
        MergeVertex::Here => roulette * PAST_GATHER,
        MergeVertex::Ahead | MergeVertex::Behind => roulette,
    };
    if survive < 1.0 && state.rng.next_1d() >= survive {
        return false;
    }
    let reverse = if sample.is_delta { sample.pdf } else { bsdf.pdf(frame, sample.wi, wo) };
    let scatter = Scatter {
        forward: sample.pdf,
        reverse,
        cos_out: frame.n().dot(sample.wi).abs(),
        delta: sample.is_delta,
    };
    walk.partials = walk.partials.scattered(weights, scatter, walk.merging.merges());
    if walk.segments == 1 {
        walk.partials = walk.partials.past_first_camera_vertex();
    }
    if !state.hero_only && material.separates_wavelengths(bsdf) {
        state.beta = hero_only(state.beta);
        state.hero_only = true;
    }
    state.beta *= sample.weight / survive;
    if renderer.has_volumes {
        state.media =
            state.media.crossed(renderer.scene, surface.material, surface.frame.ng(), wo, sample.wi);
    }
    walk.previous = Some(Previous { p: surface.p, n: frame.n() });
    state.origin = offset_origin(surface.p, surface.frame.ng(), sample.wi, surface.scale).into();
    state.direction = sample.wi.into();
    state.depth += 1;
    true
}

/// The weight of emission from the point `q` of light `light` toward `wo` that a camera path of
/// sums `arrived` meets, having scattered last at `prev`.
fn emitter_weight(
    renderer: &Renderer,
    arrived: &Partials,
    prev: Previous,
    (light, q): (usize, Vec3),
    wo: Vec3,
) -> f32 {
    let source = &renderer.scene.lights[light];
    let Some(density) = source.emission_density(q, wo) else { return 1.0 };
    let direct = renderer.light_probability(prev.p, prev.n, light) * source.direct_density(prev.p, q, wo);
    let emission = renderer.light_choice.probability(light) * density.emission;
    emitter_met(arrived, direct, emission)
}

/// What the sphere lights send to a camera path of sums `partials` (having scattered last at
/// `previous`) along its segment from `state` of `length`, `travelled` past its last vertex
/// already: each sphere the segment meets before its end (they hide nothing), times what the
/// volume there keeps of its light. The camera's own ray sees the lights visible to the camera
/// as SPPM's does (Soft Falloff's disc facing the camera, weight 1: no other technique finds
/// them); past a vertex the path meets each sphere itself, with Soft Falloff's factor at the
/// vertex, weighted against the techniques that reach it from the other end (see
/// [`crate::lights::Light::sample_surface_incident`]).
fn spheres_met(
    renderer: &Renderer,
    pass: &PassSamples,
    (state, partials, previous): (&EyeState, &Partials, Option<Previous>),
    (travelled, length): (f32, f32),
) -> SampledSpectrum {
    let scene = renderer.scene;
    let lambda = &pass.wavelengths;
    let (origin, direction) = (Vec3::from(state.origin), Vec3::from(state.direction));
    let kept = |t: f32| match renderer.has_volumes {
        true => state.media.transmittance(scene, lambda, t).unwrap_or(SampledSpectrum::ONE),
        false => SampledSpectrum::ONE,
    };
    let Some(prev) = previous else {
        return scene
            .spheres_met(origin, direction, length)
            .filter(|(_, sphere, _)| sphere.seen_by_camera || !state.camera_ray)
            .map(|(_, sphere, t)| state.beta * sphere.radiance(-direction, lambda) * kept(t))
            .sum();
    };
    let mut sum = SampledSpectrum::ZERO;
    for &i in &scene.sphere_lights {
        let Light::Sphere(sphere) = &scene.lights[i] else { continue };
        let Some(t) = sphere.surface_hit(origin, direction, length) else { continue };
        let q = origin + direction * t;
        let cos = sphere.normal_at(q).dot(-direction);
        let arrived = partials.arrived(Some(travelled + t), cos);
        let weight = emitter_weight(renderer, &arrived, prev, (i, q), -direction);
        let radiance = sphere.radiance(-direction, lambda) * sphere.receiver_factor(prev.p);
        sum += state.beta * radiance * kept(t) * weight;
    }
    sum
}

/// What the distant lights send along `direction` to a camera path of sums `partials` that
/// leaves the scene, each weighted against the other techniques (the camera's own ray: weight
/// 1).
fn escaped(
    renderer: &Renderer,
    pass: &PassSamples,
    partials: &Partials,
    previous: Option<Previous>,
    direction: Vec3,
) -> SampledSpectrum {
    let scene = renderer.scene;
    scene
        .distant_lights
        .iter()
        .map(|&i| {
            let radiance = scene.lights[i].escaped_radiance(direction, &pass.wavelengths);
            let weight = match previous {
                Some(prev) if radiance.max_element() > 0.0 => {
                    // A distant light has no point: its densities read the direction alone.
                    emitter_weight(renderer, partials, prev, (i, prev.p), -direction)
                }
                _ => 1.0,
            };
            radiance * weight
        })
        .sum()
}
