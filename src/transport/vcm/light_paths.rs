//! Light subpaths: paths leave lights chosen by power, as photons do, and every vertex where
//! their BSDF is not a delta is kept, with the path's throughput and MIS sums, for connections,
//! for merging and for light tracing (each vertex is connected to the camera at once).

use glam::{Vec2, Vec3, Vec3A};

use super::mis::{light_traced, End, LightPartials, MergeVertex, Partials, PassWeights, Scatter};
use super::view::View;
use super::visibility;
use crate::geometry::offset_origin;
use crate::lights::SoftFalloff;
use crate::materials::{Bsdf, Lobe, Transport};
use crate::sampling::Sampler;
use crate::spectrum::{hero_only, SampledSpectrum, LANES};
use crate::transport::context::{PassSamples, PassStats, Renderer, MAX_DEPTH};
use crate::transport::emission::photon_stream;
use crate::transport::media::Media;
use crate::transport::shadow::kept;

/// A vertex of a light subpath where its BSDF is not a delta.
#[derive(Clone, Copy, Debug)]
pub struct LightVertex {
    /// Position.
    pub p: Vec3,
    /// Unit direction toward where its light came from.
    pub wo: Vec3,
    /// The lobe it met there (frame, BSDF, the layers over it).
    pub lobe: Lobe,
    /// The light's flux over the path's density up to here (lobe choice included), for one path.
    pub throughput: SampledSpectrum,
    /// The path carries its hero wavelength alone.
    pub hero_only: bool,
    /// The MIS sums at the vertex.
    pub partials: LightPartials,
    /// Segments from the light.
    pub segments: u32,
    /// The largest coordinate of its triangle (for offsetting rays that leave it).
    pub scale: f32,
    /// The volumes the path arrived in, and the surface's material.
    pub media: (Media, u32),
}

impl LightVertex {
    /// The BSDF for light that arrived here scattering toward `w`, with the layers' correction
    /// for light going that way.
    pub fn eval_toward(&self, w: Vec3) -> SampledSpectrum {
        let lobe = &self.lobe;
        lobe.bsdf.eval(lobe.frame, w, self.wo) * lobe.importance_correction(self.wo, w)
    }

    /// Whether light leaving toward `w` stays on a side of the surface the BSDF sends it to (a
    /// shading normal tilted from the geometric one would otherwise leak light through).
    pub fn reaches(&self, w: Vec3) -> bool {
        self.lobe.bsdf.leaves_toward(self.lobe.frame.ng(), self.wo, w)
    }

    /// The sums at the vertex for a technique whose camera side is at `camera` against the vertex
    /// it merges at, and whether merging here takes part.
    pub fn partials_seen_from(&self, camera: MergeVertex) -> (Partials, bool) {
        self.partials.seen_from(camera, self.lobe.bsdf.is_gathered_at(), self.segments > 1)
    }
}

/// A light tracing contribution: radiance added to a film pixel.
pub type Splat = (u32, SampledSpectrum);

/// The throughput of a path made of two subpaths with throughputs `a` and `b`, each carrying its
/// hero wavelength alone or not (two collapsed subpaths carry its weight twice).
pub fn joined(a: SampledSpectrum, a_hero: bool, b: SampledSpectrum, b_hero: bool) -> SampledSpectrum {
    if a_hero && b_hero {
        a * b / LANES as f32
    } else {
        a * b
    }
}

/// One light subpath's tracing state.
struct Walk {
    origin: Vec3A,
    direction: Vec3A,
    throughput: SampledSpectrum,
    hero_only: bool,
    partials: LightPartials,
    /// The light it left and the point it left from (next-event estimation's density of that
    /// point from the first vertex completes the sums).
    light: (usize, Vec3),
    /// Soft Falloff's factor on the flux, still to be taken where the path first meets a surface.
    soft_falloff: Option<SoftFalloff>,
    /// Distance since the last vertex, across surfaces that alpha cut away.
    travelled: f32,
    /// Whether the path left a distant light and has met nothing yet.
    from_distance: bool,
    segments: u32,
    /// Rays traced, past surfaces alpha cuts away too (at most [`MAX_DEPTH`]).
    rays: u32,
    /// The volumes it is in.
    media: Media,
    rng: Sampler,
}

/// Traces light path `k` of `pass`, appending its vertices to `vertices` and what it adds to the
/// film by light tracing to `splats`.
pub fn trace_light_path(
    renderer: &Renderer,
    pass: &PassSamples,
    weights: &PassWeights,
    view: &View,
    k: u64,
    vertices: &mut Vec<LightVertex>,
    splats: &mut Vec<Splat>,
) -> PassStats {
    let mut stats = PassStats::default();
    let Some(mut walk) = start(renderer, pass, weights, k) else { return stats };
    let scene = renderer.scene;
    let lambda = &pass.wavelengths;
    while walk.rays < MAX_DEPTH {
        walk.rays += 1;
        stats.photon_rays += 1;
        let (origin, direction) = (walk.origin.into(), walk.direction.into());
        let hit = renderer.accel.intersect_opaque(origin, direction, f32::INFINITY);
        renderer.watch(origin, direction, hit.map_or(f32::INFINITY, |h| h.t), &mut stats);
        let Some(hit) = hit else { break };
        let surface = scene.surface(&hit, lambda);
        let material = &scene.materials[surface.material as usize];
        let wo = -Vec3::from(walk.direction);
        let rng = &mut walk.rng;
        let lobe = material.lobe(&surface.inputs, surface.frame, wo, lambda, rng.next_1d());
        walk.travelled += hit.t;
        if renderer.has_volumes {
            if let Some(kept) = walk.media.transmittance(scene, lambda, hit.t) {
                walk.throughput *= kept;
            }
        }
        if lobe.bsdf == Bsdf::Black {
            break;
        }
        if lobe.bsdf == Bsdf::PassThrough {
            walk.origin = offset_origin(surface.p, surface.frame.ng(), -wo, surface.scale).into();
            continue;
        }
        let n = lobe.frame.n();
        let distance = (!walk.from_distance || walk.segments > 0).then_some(walk.travelled);
        walk.partials = walk.partials.map(|p| p.arrived(distance, n.dot(wo)));
        if walk.segments == 0 {
            let (light, q) = walk.light;
            let direct = scene.lights[light].direct_density(surface.p, q, walk.direction.into());
            let direct = renderer.light_probability(surface.p, n, light) * direct;
            walk.partials = walk.partials.map(|p| p.chosen_at(direct));
            if let Some(soft) = walk.soft_falloff {
                walk.throughput *= soft.at(surface.p);
            }
        }
        walk.segments += 1;
        walk.travelled = 0.0;
        walk.throughput *= lobe.weight;
        let bsdf = lobe.bsdf;
        if !bsdf.is_delta() {
            let vertex = LightVertex {
                p: surface.p,
                wo,
                lobe,
                throughput: walk.throughput,
                hero_only: walk.hero_only,
                partials: walk.partials,
                segments: walk.segments,
                scale: surface.scale,
                media: (walk.media, surface.material),
            };
            if let Some(splat) =
                to_camera(renderer, pass, (weights, view), &vertex, &mut walk.rng, &mut stats)
            {
                splats.push(splat);
            }
            vertices.push(vertex);
        }
        let rng = &mut walk.rng;
        let u = rng.next_2d();
        let u_lobe = bsdf.lobe_number(|| rng.next_1d());
        let Some(sample) = bsdf.sample(lobe.frame, wo, u, u_lobe, Transport::Importance) else {
            break;
        };
        let weight = sample.weight * lobe.importance_correction(wo, sample.wi);
        let survive = (weight.element_sum() / LANES as f32).min(1.0);
        if walk.rng.next_1d() >= survive {
            break;
        }
        let reverse = if sample.is_delta { sample.pdf } else { bsdf.pdf(lobe.frame, sample.wi, wo) };
        let scatter =
            Scatter { forward: sample.pdf, reverse, cos_out: n.dot(sample.wi).abs(), delta: sample.is_delta };
        walk.partials = walk.partials.scattered(weights, scatter, bsdf.is_gathered_at(), walk.segments > 1);
        if !walk.hero_only && material.separates_wavelengths(&bsdf) {
            walk.throughput = hero_only(walk.throughput);
            walk.hero_only = true;
        }
        walk.throughput *= weight / survive;
        if renderer.has_volumes {
            walk.media = walk.media.crossed(scene, surface.material, surface.frame.ng(), wo, sample.wi);
        }
        walk.origin = offset_origin(surface.p, surface.frame.ng(), sample.wi, surface.scale).into();
        walk.direction = sample.wi.into();
    }
    stats
}

/// Light path `k` as it leaves its light.
fn start(renderer: &Renderer, pass: &PassSamples, weights: &PassWeights, k: u64) -> Option<Walk> {
    let mut rng = photon_stream(renderer, pass, k);
    let (light, p_light) = renderer.light_choice.sample(rng.next_1d())?;
    let source = &renderer.scene.lights[light];
    let emitted = source.emit_photon(rng.next_2d(), rng.next_2d(), &pass.wavelengths)?;
    let density = source.emission_density(emitted.origin, emitted.direction)?;
    let partials = LightPartials::new(Partials::leaving_light(
        weights,
        density.emission * p_light,
        density.cos,
        density.delta,
        density.finite,
    ));
    Some(Walk {
        origin: emitted.origin.into(),
        direction: emitted.direction.into(),
        throughput: emitted.flux / p_light,
        hero_only: false,
        partials,
        light: (light, emitted.origin),
        soft_falloff: source.photon_falloff(),
        travelled: 0.0,
        from_distance: !density.finite,
        segments: 0,
        rays: 0,
        media: renderer.light_media(light),
        rng,
    })
}

/// Light tracing: `vertex` seen by the camera (through a point of its lens drawn from `rng`), if
/// it is and is not its light path's first, and its weighted radiance on the pixel.
fn to_camera(
    renderer: &Renderer,
    pass: &PassSamples,
    (weights, view): (&PassWeights, &View),
    vertex: &LightVertex,
    rng: &mut Sampler,
    stats: &mut PassStats,
) -> Option<Splat> {
    // Direct light is not light traced (see `mis.rs`): only vertices past the first, where
    // merging is a technique.
    if vertex.segments == 1 {
        return None;
    }
    let u_lens = if view.has_lens() { rng.next_2d() } else { Vec2::ZERO };
    let landing = view.landing(vertex.p, u_lens)?;
    let toward = landing.toward;
    if !vertex.reaches(toward) {
        return None;
    }
    let f = vertex.eval_toward(toward);
    if f.max_element() <= 0.0 {
        return None;
    }
    let cos_here = vertex.lobe.frame.n().dot(toward).abs();
    // The camera's density of the vertex per area, in pixels.
    let camera_area = landing.pdf * cos_here / (landing.distance * landing.distance);
    let reverse = vertex.lobe.bsdf.pdf(vertex.lobe.frame, toward, vertex.wo);
    let (partials, merged) = vertex.partials_seen_from(MergeVertex::Ahead);
    let end = End { partials, forward: 0.0, reverse, cos: cos_here, merged };
    let weight = light_traced(weights, &end, camera_area);
    let at = (vertex.p, vertex.lobe.frame.ng(), vertex.scale);
    let through = visibility(renderer, pass, at, toward, landing.distance, stats);
    if through <= 0.0 {
        return None;
    }
    let kept = kept(
        renderer,
        &pass.wavelengths,
        vertex.media,
        (vertex.lobe.frame.ng(), vertex.wo),
        toward,
        landing.distance,
    );
    let radiance = vertex.throughput * f * kept * (weight * camera_area * through / weights.light_paths);
    radiance.is_finite().then_some((landing.pixel as u32, radiance))
}
