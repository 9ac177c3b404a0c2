//! Camera subpaths: a camera ray per pixel followed through every bounce (Russian roulette after
//! the third), and at each vertex whose BSDF is not a delta the estimators that meet light
//! subpaths there: next-event estimation, connections to the pixel's light path, and, up to the
//! path's first vertex where photons are gathered (see `mis.rs`), merging with the pass's light
//! vertices. Emission the path meets is weighted against them.

use glam::Vec3;

use super::connect::{connect, direct_light};
use super::finite;
use super::light_paths::LightVertex;
use super::merge::{CameraVertex, MergeSet};
use super::mis::{emitter_met, MergeVertex, Partials, PassWeights, Scatter};
use super::view::View;
use super::LightSubpaths;
use crate::geometry::offset_origin;
use crate::lights::Light;
use crate::materials::Transport;
use crate::scene::NOT_A_LIGHT;
use crate::spectrum::{hero_only, SampledSpectrum, LANES};
use crate::sppm::photons::chunk_of;
#[cfg(doc)]
use crate::sppm::photons::photon_chunks;
use crate::sppm::renderer::{PassSamples, PassStats, PixelEstimate, Renderer, MAX_DEPTH};
use crate::sppm::visible::{start_eye_path, EyeState, Meeting};

/// Bounces before Russian roulette may end a camera path.
const ROULETTE_AFTER: u32 = 3;

/// What a pass's camera paths meet light subpaths with.
pub struct Lights<'a> {
    /// The light paths, in the chunks they were traced in (see [`photon_chunks`]).
    pub chunks: &'a [LightSubpaths],
    /// Light paths in all.
    pub paths: usize,
    /// The light vertices for merging.
    pub merge_set: &'a MergeSet,
}

impl Lights<'_> {
    /// The light path paired with film pixel `pixel`.
    fn path_of(&self, pixel: usize) -> &[LightVertex] {
        if self.paths == 0 {
            return &[];
        }
        let (chunk, k) = chunk_of(pixel % self.paths);
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

/// Traces pixel `pixel`'s camera path for `pass`.
pub fn trace_camera_path(
    renderer: &Renderer,
    pass: &PassSamples,
    (weights, view): (&PassWeights, &View),
    lights: &Lights,
    pixel: usize,
) -> (PixelEstimate, PassStats) {
    let scene = renderer.scene;
    let lambda = &pass.wavelengths;
    let (mut state, mut stats) = start_eye_path(renderer, pass, pixel);
    let mut partials =
        Partials::leaving_camera(weights, view.pdf(state.direction.into()), view.traces_lights());
    let (mut radiance, mut laplacian, mut coverage) = (SampledSpectrum::ZERO, SampledSpectrum::ZERO, 1.0);
    let mut previous: Option<Previous> = None;
    let (mut travelled, mut segments) = (0.0f32, 0u32);
    let mut merging = MergeVertex::Ahead;
    while state.depth < MAX_DEPTH {
        stats.eye_rays += 1;
        let direction = Vec3::from(state.direction);
        let hit = renderer.accel.intersect(state.origin.into(), direction, f32::INFINITY);
        if !scene.sphere_lights.is_empty() {
            let segment = (travelled, hit.map_or(f32::INFINITY, |h| h.t));
            radiance += finite(spheres_met(renderer, pass, (&state, &partials, previous), segment));
        }
        let Some(hit) = hit else {
            if state.camera_ray && scene.transparent_film {
                coverage = 0.0;
            } else if !(renderer.has_volumes && state.media.medium(scene).is_some()) {
                radiance += finite(state.beta * escaped(renderer, pass, &partials, previous, direction));
            }
            break;
        };
        travelled += hit.t;
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
                let weight = match previous {
                    Some(prev) if light != NOT_A_LIGHT => {
                        let arrived = partials.arrived(Some(travelled), surface.frame.n().dot(wo));
                        emitter_weight(renderer, &arrived, prev, (light as usize, surface.p), wo)
                    }
                    _ => 1.0,
                };
                radiance += finite(state.beta * emitted * weight);
            }
        }
        let lobe = material.lobe(&surface.inputs, surface.frame, wo, lambda, state.rng.next_1d());
        match state.meet(&lobe.bsdf, material.holdout, &surface, wo) {
            Meeting::Ends { coverage: seen } => {
                coverage = seen;
                break;
            }
            Meeting::PassesThrough => continue,
            Meeting::Scatters => {}
        }
        let (frame, bsdf) = (lobe.frame, lobe.bsdf);
        // The sums at the vertex take the cosine of the lobe's normals, as connections there do.
        partials = partials.arrived(Some(travelled), frame.n().dot(wo));
        travelled = 0.0;
        segments += 1;
        state.beta *= lobe.weight;
        merging = merging.next(bsdf.is_gathered_at());
        if !bsdf.is_delta() {
            let camera = CameraVertex {
                p: surface.p,
                wo,
                frame,
                bsdf: &bsdf,
                beta: state.beta,
                hero_only: state.hero_only,
                partials,
                segments,
                merging,
                media: (state.media, surface.material),
            };
            let at = (&camera, surface.scale);
            radiance += direct_light(renderer, pass, at, &mut state.rng, &mut stats);
            radiance += connect(renderer, pass, weights, at, lights.path_of(pixel), MAX_DEPTH, &mut stats);
            if merging.merges() {
                let (merged, merged_laplacian) = lights.merge_set.merge(weights, &camera, MAX_DEPTH);
                radiance += merged;
                laplacian += merged_laplacian;
            }
        }
        let rng = &mut state.rng;
        let u = rng.next_2d();
        let u_lobe = bsdf.lobe_number(|| rng.next_1d());
        let Some(sample) = bsdf.sample(frame, wo, u, u_lobe, Transport::Radiance) else {
            break;
        };
        let survive = match segments > ROULETTE_AFTER {
            true => (sample.weight.element_sum() / LANES as f32).min(1.0),
            false => 1.0,
        };
        if survive < 1.0 && state.rng.next_1d() >= survive {
            break;
        }
        let reverse = if sample.is_delta { sample.pdf } else { bsdf.pdf(frame, sample.wi, wo) };
        let scatter = Scatter {
            forward: sample.pdf,
            reverse,
            cos_out: frame.n().dot(sample.wi).abs(),
            delta: sample.is_delta,
        };
        partials = partials.scattered(weights, scatter, merging.merges());
        if segments == 1 {
            partials = partials.past_first_camera_vertex();
        }
        if !state.hero_only && material.separates_wavelengths(&bsdf) {
            state.beta = hero_only(state.beta);
            state.hero_only = true;
        }
        state.beta *= sample.weight / survive;
        if renderer.has_volumes {
            state.media = state.media.crossed(scene, surface.material, surface.frame.ng(), wo, sample.wi);
        }
        previous = Some(Previous { p: surface.p, n: frame.n() });
        state.origin = offset_origin(surface.p, surface.frame.ng(), sample.wi, surface.scale).into();
        state.direction = sample.wi.into();
        state.depth += 1;
    }
    (PixelEstimate { radiance, laplacian, coverage }, stats)
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
