//! Vertex connection and merging (`--method vcm`): Georgiev, Křivánek, Davidovič & Slusallek
//! 2012, and Hachisuka, Pantaleoni & Jensen 2012's unified path sampling. A pass traces one light
//! subpath per photon and one camera subpath per pixel; every path is found by every technique
//! that can sample it (a camera path meeting an emitter, next-event estimation, connecting the
//! two subpaths' vertices, light tracing to the camera, and merging at the pass's radius where
//! SPPM would gather: up to the camera path's first vertex that gathers photons) and the
//! techniques are combined by multiple importance sampling (`mis.rs`), so caustics keep photon
//! merging's robustness and diffuse light path tracing's rate of convergence.
//!
//! A camera path splits in two at its first glossy vertex, up to the vertex where it gathers
//! (`eye_paths.rs`).
//!
//! The stages: light subpaths (`light_paths.rs`, which also traces light to the camera), the
//! light vertices bucketed for merging (`merge.rs`), and camera subpaths (`eye_paths.rs`) whose
//! vertices run the estimators (`connect.rs`, `merge.rs`). A pass depends only on (scene,
//! settings, seed, pass index), as an SPPM pass does, with the same radius sequence.
//!
//! Media that only absorb (coloured glass, water, gems) weigh every segment and connection by
//! their transmittance, which every technique computes alike and leaves out of the weights.
//!
//! A point or spot light with a radius is its sphere to every technique: light paths leave it,
//! camera paths meet it, next-event estimation samples the solid angle it covers. With Soft
//! Falloff (Blender's default), which makes the light a disc facing whatever it lights, the
//! sphere's light is scaled at the point it lights by the disc's falloff, `d^2 / (d^2 + r^2)`, as
//! SPPM's photons are: the same light wherever the light is wholly above that point's horizon
//! (`lights/sphere.rs`). The camera itself sees the disc, as under SPPM.
//!
//! Not yet rendered this way (a scene with them is refused with `--method vcm`): media that
//! scatter.
//!
//! The frames of a block share the paths that meet only static triangles (`reuse.rs`).

mod connect;
mod eye_paths;
mod light_paths;
mod merge;
mod mis;
mod reuse;
mod view;

use rayon::prelude::*;

use super::context::{collect_counting, PassSamples, PassStats, PixelEstimate, Renderer};
use super::shadow::ShadowRay;
use crate::spectrum::SampledSpectrum;
use crate::transport::emission::photon_chunks;
use eye_paths::{trace_camera_path, Lights};
use glam::Vec3;
use light_paths::{trace_light_path, LightVertex, Splat};
use merge::MergeSet;
use mis::PassWeights;
use view::View;

/// `value`, or zero where it is not a finite number (a weight or density that overflowed at a
/// grazing angle or between nearly touching vertices).
fn finite(value: SampledSpectrum) -> SampledSpectrum {
    if value.is_finite() {
        value
    } else {
        SampledSpectrum::ZERO
    }
}

/// How much of the light along the segment from `a` (on a triangle of geometric normal `ng`
/// whose largest coordinate is `scale`) along `direction` reaches `distance` (a shadow ray).
fn visibility(
    renderer: &Renderer,
    pass: &PassSamples,
    (a, ng, scale): (Vec3, Vec3, f32),
    direction: Vec3,
    distance: f32,
    stats: &mut PassStats,
) -> f32 {
    stats.shadow_rays += 1;
    let ray = ShadowRay::leaving(a, (ng, scale), direction, distance);
    let through = ray.visibility(renderer, &pass.wavelengths);
    // What static triangles block, they block in every frame.
    if through > 0.0 {
        renderer.watch(ray.origin, ray.direction, ray.t_max, stats);
    }
    through
}

/// One chunk of a pass's light subpaths: their vertices path after path, where each path's
/// vertices start (and one past the last), and their light tracing contributions.
#[derive(Default)]
pub struct LightSubpaths {
    vertices: Vec<LightVertex>,
    starts: Vec<usize>,
    splats: Vec<Splat>,
    /// Where each path's splats start (and one past the last).
    splat_starts: Vec<usize>,
    /// The paths' indices in the pass.
    ids: Vec<u32>,
    /// The paths (by their place in the chunk) with a ray that met the renderer's watched box.
    watched: Vec<usize>,
    stats: PassStats,
}

impl LightSubpaths {
    /// The vertices of the chunk's path `k`.
    pub fn path(&self, k: usize) -> &[LightVertex] {
        &self.vertices[self.starts[k]..self.starts[k + 1]]
    }

    /// Every vertex, with the index of its path in the pass.
    fn vertices_by_path(&self) -> impl Iterator<Item = (u32, &LightVertex)> {
        self.ids.iter().enumerate().flat_map(move |(k, &id)| self.path(k).iter().map(move |v| (id, v)))
    }

    /// What the chunk's path `k` adds to the film by light tracing.
    fn splats_of(&self, k: usize) -> &[Splat] {
        &self.splats[self.splat_starts[k]..self.splat_starts[k + 1]]
    }

    /// Traces paths `paths` of `pass` (given in increasing order) into one chunk.
    fn trace(
        renderer: &Renderer,
        pass: &PassSamples,
        (weights, view): (&PassWeights, &View),
        paths: impl Iterator<Item = u64>,
    ) -> Self {
        let capacity = 2 * paths.size_hint().0;
        let mut chunk = LightSubpaths { vertices: Vec::with_capacity(capacity), ..LightSubpaths::default() };
        for (place, k) in paths.enumerate() {
            chunk.starts.push(chunk.vertices.len());
            chunk.splat_starts.push(chunk.splats.len());
            chunk.ids.push(k as u32);
            let stats =
                trace_light_path(renderer, pass, weights, view, k, &mut chunk.vertices, &mut chunk.splats);
            if stats.watched_rays > 0 {
                chunk.watched.push(place);
            }
            chunk.stats = chunk.stats + stats;
        }
        chunk.starts.push(chunk.vertices.len());
        chunk.splat_starts.push(chunk.splats.len());
        chunk
    }
}

/// The light paths one frame of a block traced again (those whose rays met the box the moving
/// triangles fill), in place of the paths traced for every frame.
pub struct Retraced {
    /// The paths' indices in the pass, increasing.
    paths: Vec<u64>,
    /// The paths, [`RETRACED_CHUNK`] to a chunk.
    chunks: Vec<LightSubpaths>,
}

/// Paths to a chunk of [`Retraced`] paths.
const RETRACED_CHUNK: usize = 64;

impl Retraced {
    /// Traces `paths` of `pass` (increasing) in the frame of `renderer`.
    fn trace(renderer: &Renderer, pass: &PassSamples, setup: (&PassWeights, &View), paths: Vec<u64>) -> Self {
        let chunks = paths
            .par_chunks(RETRACED_CHUNK)
            .map(|chunk| LightSubpaths::trace(renderer, pass, setup, chunk.iter().copied()))
            .collect();
        Retraced { paths, chunks }
    }

    /// Path `k`'s vertices, where the frame traced it again.
    fn path(&self, k: u64) -> Option<&[LightVertex]> {
        let place = self.paths.binary_search(&k).ok()?;
        Some(self.chunks[place / RETRACED_CHUNK].path(place % RETRACED_CHUNK))
    }
}

impl Renderer<'_> {
    /// Renders `pass` by vertex connection and merging: one estimate per pixel, in row-major
    /// order.
    pub(super) fn run_vcm_pass(&self, pass: &PassSamples) -> (Vec<PixelEstimate>, PassStats) {
        let paths = self.settings.photons_per_pass;
        let weights = PassWeights::new(pass.radius, paths);
        let view = View::new(self.scene.camera, self.settings.crop);
        let chunks = self.trace_light_subpaths(pass, &weights, &view);
        let vertices = chunks.par_iter().flat_map_iter(LightSubpaths::vertices_by_path);
        let merge_set = MergeSet::new(vertices, pass.radius);
        let open_edges = &self.scene.open_edges;
        let merge_sets = &[(&merge_set, &[][..])];
        let lights =
            Lights { chunks: &chunks, paths, merge_sets, open_edges, keep_merges: false, retraced: None };
        let pixels = (self.settings.width * self.settings.height) as usize;
        let (mut estimates, stats) = collect_counting(pixels, |pixel| {
            let (found, stats) = trace_camera_path(self, pass, (&weights, &view), &lights, pixel);
            (found.estimate, stats)
        });
        for &(pixel, radiance) in chunks.iter().flat_map(|chunk| &chunk.splats) {
            estimates[pixel as usize].radiance += radiance;
        }
        (estimates, chunks.iter().fold(stats, |all, chunk| all + chunk.stats))
    }

    /// The pass's light subpaths, traced in parallel chunks, in path order (kept in their
    /// chunks: joining them would copy every vertex once more).
    fn trace_light_subpaths(
        &self,
        pass: &PassSamples,
        weights: &PassWeights,
        view: &View,
    ) -> Vec<LightSubpaths> {
        photon_chunks(0..self.settings.photons_per_pass)
            .map(|range| LightSubpaths::trace(self, pass, (weights, view), range))
            .collect()
    }
}
