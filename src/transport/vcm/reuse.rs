//! VCM's pass shared by a block of frames (reuse across frames, `transport/reuse.rs`).
//!
//! When neither the camera nor a light moves, the pass's light subpaths and camera subpaths are
//! traced once against the static triangles, and every ray they trace (their segments, the shadow
//! rays of next-event estimation, of connections and of light tracing) that meets the box the
//! moving triangles fill in some frame is counted. A light path with no such ray is the same in
//! every frame: it is traced once, merged from one set of vertices, and its light tracing is in
//! the common estimate. Each frame traces the other light paths again in its own scene. A pixel
//! is the same in every frame when its camera path has no such ray, the light path paired with
//! it is shared, and merging at its vertices reaches none of the frame's own light vertices: its
//! estimate is the common one (plus the light the frame's own paths trace onto it). A frame
//! traces the other pixels' camera paths again in its own scene, merging with the shared light
//! vertices and its own. So every frame gets the paths a render of it alone traces, with the same
//! random numbers, summed in another order: the images are those of `--no-reuse` up to float
//! rounding.
//!
//! Where the surfaces' open edges differ between frames (a moving open mesh), a pixel that merges
//! within the radius of the moving triangles' box is traced again by each frame too: the edges
//! there cut its merging discs. Where the camera or a light moves, or lies inside a volume that
//! moves, each frame renders its own pass.

use std::sync::Arc;
use std::time::{Duration, Instant};

use glam::Vec3;
use rayon::prelude::*;

use super::eye_paths::{trace_camera_path, Lights};
use super::light_paths::Splat;
use super::merge::{MergePoints, MergeSet};
use super::mis::PassWeights;
use super::view::View;
use super::{LightSubpaths, Retraced};
use crate::transport::context::{collect_counting, PassSamples, PassStats, PixelEstimate, Renderer};
use crate::transport::emission::photon_chunks;
use crate::transport::reuse::{FrameEstimates, SharedPassOutput, Swept};

/// VCM's pass for a block of frames (see [`crate::transport::run_shared_pass`]).
pub fn run_shared_pass(
    statics: &Renderer,
    frames: &[Renderer],
    pass: &PassSamples,
    share_eyes: bool,
    consume: &mut dyn FnMut(SharedPassOutput),
) -> (PassStats, Duration) {
    let start = Instant::now();
    if !(share_eyes && frames.iter().all(|f| f.starts_in_same_media(statics))) {
        for (index, frame) in frames.iter().enumerate() {
            let (estimates, stats) = frame.run_vcm_pass(pass);
            consume(SharedPassOutput { frame: index, estimates: FrameEstimates::Every(estimates), stats });
        }
        return (PassStats::default(), Duration::ZERO);
    }
    let swept = Swept::of(frames).0;
    let watcher = Renderer::choosing_lights_as(statics, statics.scene, statics.accel).watching(swept);
    // Where the surfaces' open edges differ between frames, the moving ones lie in the box.
    let edges_move = !frames.iter().all(|f| Arc::ptr_eq(&f.scene.open_edges, &statics.scene.open_edges));
    let shared = SharedPaths::trace(&watcher, pass, swept.filter(|_| edges_move));
    let shared_time = start.elapsed();
    for (index, frame) in frames.iter().enumerate() {
        let (differing, stats) = shared.frame_estimates(frame, pass);
        let estimates = FrameEstimates::Beside { common: &shared.common, differing };
        consume(SharedPassOutput { frame: index, estimates, stats });
    }
    (shared.stats, shared_time)
}

/// A pass's paths traced once for every frame of a block.
struct SharedPaths {
    weights: PassWeights,
    view: View,
    /// Every light path, traced against the static triangles.
    chunks: Vec<LightSubpaths>,
    /// Light paths in all.
    paths: usize,
    /// The light paths with a ray that meets the moving triangles' box, increasing: each frame
    /// traces them again.
    watched_paths: Vec<u64>,
    /// The vertices of the other light paths, for merging.
    merge_set: MergeSet,
    /// What the other light paths trace onto the film, by pixel (in path order for each pixel).
    splats: Vec<Splat>,
    /// Every pixel's estimate from the shared paths.
    common: Vec<PixelEstimate>,
    /// Every pixel's camera path as it bears on the frames.
    pixels: Vec<SharedPixel>,
    stats: PassStats,
}

/// What a frame must know of a pixel's camera path traced for every frame.
struct SharedPixel {
    /// A ray of it meets the moving triangles' box, or its paired light path does: every frame
    /// traces it again.
    watched: bool,
    /// Where it merged.
    merged_at: MergePoints,
}

impl SharedPaths {
    /// Traces `pass`'s paths by `watcher` (the static triangles, watching the moving ones' box);
    /// pixels that merge within the radius of `moving_edges` (the box of open edges that differ
    /// between frames) are watched too.
    fn trace(watcher: &Renderer, pass: &PassSamples, moving_edges: Option<(Vec3, Vec3)>) -> Self {
        let paths = watcher.settings.photons_per_pass;
        let weights = PassWeights::new(pass.radius, paths);
        let view = View::new(watcher.scene.camera, watcher.settings.crop);
        let chunks = watcher.trace_light_subpaths(pass, &weights, &view);
        let firsts: Vec<u64> = photon_chunks(0..paths).map(|range| range.start).collect();
        let watched_paths: Vec<u64> = (chunks.iter().zip(&firsts))
            .flat_map(|(chunk, &first)| chunk.watched.iter().map(move |&place| first + place as u64))
            .collect();
        let kept = chunks.par_iter().flat_map_iter(|chunk| chunk.kept_paths().flat_map(|k| chunk.path(k)));
        let merge_set = MergeSet::new(kept, pass.radius);
        let mut splats: Vec<Splat> =
            chunks.iter().flat_map(|chunk| chunk.kept_paths().flat_map(|k| chunk.splats_of(k))).copied().collect();
        splats.sort_by_key(|&(pixel, _)| pixel);
        let open_edges = &watcher.scene.open_edges;
        let lights = Lights { chunks: &chunks, paths, merge_sets: &[&merge_set], open_edges, retraced: None };
        let pixel_count = (watcher.settings.width * watcher.settings.height) as usize;
        let (traced, camera_stats) = collect_counting(pixel_count, |pixel| {
            let (found, stats) = trace_camera_path(watcher, pass, (&weights, &view), &lights, pixel);
            let paired = paths > 0 && watched_paths.binary_search(&((pixel % paths) as u64)).is_ok();
            let near_edges = moving_edges.is_some_and(|b| found.merged_at.may_reach(b, pass.radius));
            let watched = paired || near_edges || stats.watched_rays > 0;
            ((found.estimate, SharedPixel { watched, merged_at: found.merged_at }), stats)
        });
        let (mut common, pixels): (Vec<PixelEstimate>, Vec<SharedPixel>) = traced.into_iter().unzip();
        for &(pixel, radiance) in &splats {
            common[pixel as usize].radiance += radiance;
        }
        let stats = chunks.iter().fold(camera_stats, |all, chunk| all + chunk.stats);
        SharedPaths { weights, view, chunks, paths, watched_paths, merge_set, splats, common, pixels, stats }
    }

    /// `frame`'s estimates where they differ from the common ones, in pixel order, and the work
    /// it did: it traces the watched light paths again, and the camera paths of the pixels that
    /// are watched or whose merging reaches its own light vertices.
    fn frame_estimates(&self, frame: &Renderer, pass: &PassSamples) -> (Vec<(u32, PixelEstimate)>, PassStats) {
        let setup = (&self.weights, &self.view);
        let retraced = Retraced::trace(frame, pass, setup, self.watched_paths.clone());
        let own = retraced.chunks.par_iter().flat_map_iter(|chunk| &chunk.vertices);
        let own_set = MergeSet::new(own, pass.radius);
        let mut own_splats: Vec<Splat> = retraced.chunks.iter().flat_map(|c| &c.splats).copied().collect();
        own_splats.sort_by_key(|&(pixel, _)| pixel);
        let lights = Lights {
            chunks: &self.chunks,
            paths: self.paths,
            merge_sets: &[&self.merge_set, &own_set],
            open_edges: &frame.scene.open_edges,
            retraced: Some(&retraced),
        };
        let (estimates, stats) = collect_counting(self.pixels.len(), |pixel| {
            let shared = &self.pixels[pixel];
            let own_light = splats_at(&own_splats, pixel);
            if shared.watched || shared.merged_at.may_read(&own_set) {
                let (found, stats) = trace_camera_path(frame, pass, setup, &lights, pixel);
                let mut estimate = found.estimate;
                for &(_, radiance) in splats_at(&self.splats, pixel).iter().chain(own_light) {
                    estimate.radiance += radiance;
                }
                (Some(estimate), stats)
            } else if !own_light.is_empty() {
                let mut estimate = self.common[pixel];
                for &(_, radiance) in own_light {
                    estimate.radiance += radiance;
                }
                (Some(estimate), PassStats::default())
            } else {
                (None, PassStats::default())
            }
        });
        let differing = (estimates.into_iter().enumerate())
            .filter_map(|(pixel, estimate)| estimate.map(|e| (pixel as u32, e)))
            .collect();
        (differing, retraced.chunks.iter().fold(stats, |all, chunk| all + chunk.stats))
    }
}

/// The splats of `splats` (sorted by pixel) that land on `pixel`.
fn splats_at(splats: &[Splat], pixel: usize) -> &[Splat] {
    let pixel = pixel as u32;
    let start = splats.partition_point(|&(p, _)| p < pixel);
    let end = start + splats[start..].partition_point(|&(p, _)| p == pixel);
    &splats[start..end]
}
