//! VCM's pass shared by a block of frames (reuse across frames, `transport/reuse.rs`).
//!
//! When neither the camera nor a light moves, the pass's light subpaths and camera subpaths are
//! traced once against the static triangles, and every ray they trace (their segments, the shadow
//! rays of next-event estimation, of connections and of light tracing) that meets the box the
//! moving triangles fill in some frame is counted. The common estimate of every pixel is made
//! from these paths, as though no frame's moving triangles were there. Each frame traces again
//! the light paths with such a ray, in its own scene, with the same random numbers; those that
//! come out otherwise than traced for every frame are the frame's changed paths. A pixel differs
//! from the common estimate where its camera path has such a ray, where the light path paired
//! with it changed, or where merging at its vertices reaches a changed path's vertex as traced
//! for every frame or as the frame traced it: the frame traces it again in its own scene,
//! merging with every path's vertices as the frame has them. A pixel that only receives the
//! light tracing of changed paths trades their splats. So every frame gets the paths a render of
//! it alone traces, summed in another order: the images are those of `--no-reuse` up to float
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
use super::light_paths::{LightVertex, Splat};
use super::merge::{KeptMerge, MergeSet};
use super::mis::PassWeights;
use super::view::View;
use super::{LightSubpaths, Retraced};
use crate::spectrum::SampledSpectrum;
use crate::transport::context::{
    collect_counting, PassSamples, PassStats, PixelEstimate, Ray, Renderer, MAX_DEPTH,
};
use crate::transport::emission::chunk_of;
use crate::transport::points::{PixelMarks, PointGrid};
use crate::transport::reuse::{FrameEstimates, SharedPassOutput, Swept};

impl Renderer<'_> {
    /// VCM's pass for a block of frames, this renderer holding their static triangles (see
    /// [`crate::transport::run_shared_pass`]).
    pub(in crate::transport) fn run_shared_vcm_pass(
        &self,
        frames: &[Renderer],
        pass: &PassSamples,
        share_eyes: bool,
        consume: &mut dyn FnMut(SharedPassOutput),
    ) -> (PassStats, Duration) {
        let statics = self;
        let start = Instant::now();
        if !(share_eyes && frames.iter().all(|f| f.starts_in_same_media(statics))) {
            for (index, frame) in frames.iter().enumerate() {
                let (estimates, stats) = frame.run_vcm_pass(pass);
                consume(SharedPassOutput {
                    frame: index,
                    estimates: FrameEstimates::Every(estimates),
                    stats,
                });
            }
            return (PassStats::default(), Duration::ZERO);
        }
        let swept = Swept::of(frames).0;
        let watcher = Renderer::choosing_lights_as(statics, statics.scene, statics.accel)
            .watching(swept)
            .logging_watched();
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
    /// Every light path's vertices, for merging.
    merge_set: MergeSet,
    /// What every light path traces onto the film, with its path, by pixel (in path order for
    /// each pixel).
    splats: Vec<PathSplat>,
    /// Every pixel's estimate from the paths traced for every frame.
    common: Vec<PixelEstimate>,
    /// The pixels whose camera paths have rays that meet the moving triangles' box.
    watched: Watched,
    /// Pixels in all.
    pixels: usize,
    /// Where each pixel's camera path merged.
    merges: KeptMerges,
    /// The same points, bucketed to find those a changed light vertex reaches.
    merge_points: PointGrid,
    stats: PassStats,
}

/// The pixels whose camera paths have rays that meet the moving triangles' box, with those rays.
#[derive(Default)]
struct Watched {
    /// The pixels, increasing.
    pixels: Vec<u32>,
    /// Where each one's rays start (and one past the last).
    starts: Vec<usize>,
    rays: Vec<Ray>,
    /// Whether the pixel merges within reach of open edges that move (every frame traces it).
    near_edges: Vec<bool>,
}

impl Watched {
    /// The pixels whose camera paths `frame` changes, increasing: those with a ray that meets one
    /// of its moving triangles (the others meet the same static triangles in every frame).
    fn changed_in(&self, frame: &Renderer) -> Vec<u32> {
        (0..self.pixels.len())
            .into_par_iter()
            .with_min_len(64)
            .filter(|&i| {
                let rays = &self.rays[self.starts[i]..self.starts[i + 1]];
                self.near_edges[i] || rays.iter().any(|&(o, d, t)| frame.accel.moving_hit(o, d, t))
            })
            .map(|i| self.pixels[i])
            .collect()
    }
}

/// The camera vertices every pixel merged at, pixel after pixel.
struct KeptMerges {
    kept: Vec<KeptMerge>,
    /// Where each pixel's start (and one past the last).
    starts: Vec<usize>,
}

impl KeptMerges {
    /// Where `pixel` merged.
    fn of(&self, pixel: usize) -> &[KeptMerge] {
        &self.kept[self.starts[pixel]..self.starts[pixel + 1]]
    }

    /// Every pixel's merging points, with the pixel.
    fn points(&self) -> impl Iterator<Item = (usize, Vec3)> + '_ {
        (0..self.starts.len() - 1).flat_map(move |pixel| self.of(pixel).iter().map(move |m| (pixel, m.p())))
    }
}

/// A light tracing contribution: the pixel, the light path, the radiance.
type PathSplat = (u32, u32, SampledSpectrum);

/// The light paths one frame changed: its own tracing of them, the vertices of both tracings
/// bucketed, and their splats by pixel.
struct Changes {
    /// Their indices in the pass, increasing.
    paths: Vec<u32>,
    /// The frame's tracing of every watched path.
    retraced: Retraced,
    /// The vertices of the changed paths as the frame traced them.
    own: MergeSet,
    /// Those of them that differ from the tracing for every frame.
    added: MergeSet,
    /// The vertices of the changed paths as traced for every frame that differ from the frame's.
    removed: MergeSet,
    /// What the changed paths trace onto the film in the frame, by pixel.
    splats: Vec<PathSplat>,
    /// Where the vertices of `added` and `removed` lie.
    moved: Vec<Vec3>,
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
        let watched_paths: Vec<u64> = (chunks.iter())
            .flat_map(|chunk| chunk.watched.iter().map(|&place| u64::from(chunk.ids[place])))
            .collect();
        let merge_set =
            MergeSet::new(chunks.par_iter().flat_map_iter(LightSubpaths::vertices_by_path), pass.radius);
        let splats = splats_by_pixel(&chunks);
        let open_edges = &watcher.scene.open_edges;
        let merge_sets = &[(&merge_set, &[][..])];
        let lights =
            Lights { chunks: &chunks, paths, merge_sets, open_edges, keep_merges: true, retraced: None };
        let pixel_count = (watcher.settings.width * watcher.settings.height) as usize;
        let (traced, camera_stats) = collect_counting(pixel_count, |pixel| {
            Renderer::take_watched();
            let (found, stats) = trace_camera_path(watcher, pass, (&weights, &view), &lights, pixel);
            let rays = if stats.watched_rays > 0 { Renderer::take_watched() } else { Vec::new() };
            let reach = |b: (Vec3, Vec3)| found.kept.iter().any(|m| within(m.p(), b, pass.radius));
            ((found.estimate, rays, moving_edges.is_some_and(reach), found.kept), stats)
        });
        let (mut common, watched, merges) = gather_pixels(traced);
        for &(pixel, _, radiance) in &splats {
            common[pixel as usize].radiance += radiance;
        }
        let stats = chunks.iter().fold(camera_stats, |all, chunk| all + chunk.stats);
        let merge_points = PointGrid::new(merges.points(), pass.radius);
        SharedPaths {
            weights,
            view,
            chunks,
            paths,
            watched_paths,
            merge_set,
            splats,
            common,
            watched,
            pixels: pixel_count,
            merges,
            merge_points,
            stats,
        }
    }

    /// The pixels `changes` may change, in order: `traced_again` (watched ones the frame's moving
    /// triangles change), those paired with a changed path, those that merge within reach of a
    /// changed vertex, and those a changed path traces light onto (or traced it onto, as traced
    /// for every frame).
    fn candidates(&self, changes: &Changes, traced_again: &[u32]) -> Vec<u32> {
        let pixels = self.pixels;
        let marks = PixelMarks::new(pixels);
        traced_again.iter().for_each(|&pixel| marks.mark(pixel));
        for &k in &changes.paths {
            if self.paths > 0 {
                (k as usize..pixels).step_by(self.paths).for_each(|pixel| marks.mark(pixel as u32));
            }
            self.shared_path(u64::from(k)).1.iter().for_each(|&(pixel, _)| marks.mark(pixel));
        }
        changes.splats.iter().for_each(|&(pixel, _, _)| marks.mark(pixel));
        self.merge_points.mark_near(&changes.moved, |&p| p, &marks);
        marks.marked()
    }

    /// What `changes` make of merging at `pixel`'s camera vertices: `Some(None)` where merging
    /// there reaches no changed vertex, `Some(Some(radiance, laplacian))` the change where it
    /// does, and `None` where a changed vertex cuts a disc (the pixel must be traced again).
    #[allow(clippy::option_option)]
    fn merging_change(
        &self,
        changes: &Changes,
        pixel: usize,
    ) -> Option<Option<(SampledSpectrum, SampledSpectrum)>> {
        let sets = (&changes.added, &changes.removed);
        let mut sum: Option<(SampledSpectrum, SampledSpectrum)> = None;
        for merge in self.merges.of(pixel) {
            let Some((radiance, laplacian)) = merge.change(sets, &self.weights, MAX_DEPTH)? else { continue };
            let (r, l) = sum.unwrap_or((SampledSpectrum::ZERO, SampledSpectrum::ZERO));
            sum = Some((r + radiance, l + laplacian));
        }
        Some(sum)
    }

    /// Path `k` as traced for every frame: its vertices and splats.
    fn shared_path(&self, k: u64) -> (&[LightVertex], &[Splat]) {
        let (chunk, place) = chunk_of(k as usize);
        (self.chunks[chunk].path(place), self.chunks[chunk].splats_of(place))
    }

    /// Traces the watched light paths in `frame`, and finds those it changes.
    fn changes(&self, frame: &Renderer, pass: &PassSamples) -> Changes {
        let retraced = Retraced::trace(frame, pass, (&self.weights, &self.view), self.watched_paths.clone());
        // Each changed path, and the first of its vertices that differs between the tracings.
        let mut paths = Vec::new();
        let mut first_changed = Vec::new();
        for chunk in &retraced.chunks {
            for (place, &k) in chunk.ids.iter().enumerate() {
                let ours = (chunk.path(place), chunk.splats_of(place));
                if let Some(first) = first_difference(ours, self.shared_path(u64::from(k))) {
                    paths.push(k);
                    first_changed.push(first);
                }
            }
        }
        let changed_place = |k: u32| paths.binary_search(&k).ok();
        let by_path = |chunk: &LightSubpaths| {
            (chunk.ids.iter().enumerate())
                .filter_map(|(place, &k)| changed_place(k).map(|c| (place, k, first_changed[c])))
                .collect::<Vec<_>>()
        };
        let own = retraced.chunks.par_iter().flat_map_iter(|chunk| {
            by_path(chunk)
                .into_iter()
                .flat_map(move |(place, k, _)| chunk.path(place).iter().map(move |v| (k, v)))
        });
        let own = MergeSet::new(own, pass.radius);
        let added = retraced.chunks.par_iter().flat_map_iter(|chunk| {
            by_path(chunk)
                .into_iter()
                .flat_map(move |(place, k, first)| chunk.path(place)[first..].iter().map(move |v| (k, v)))
        });
        let added = MergeSet::new(added, pass.radius);
        let removed = (paths.par_iter().zip(&first_changed)).flat_map_iter(|(&k, &first)| {
            self.shared_path(u64::from(k)).0[first..].iter().map(move |v| (k, v))
        });
        let removed = MergeSet::new(removed, pass.radius);
        let moved = (paths.iter().zip(&first_changed))
            .flat_map(|(&k, &first)| self.shared_path(u64::from(k)).0[first..].iter().map(|v| v.p))
            .chain(retraced.chunks.iter().flat_map(|chunk| {
                by_path(chunk)
                    .into_iter()
                    .flat_map(move |(place, _, first)| chunk.path(place)[first..].iter().map(|v| v.p))
            }))
            .collect();
        let mut splats: Vec<PathSplat> = (retraced.chunks.iter())
            .flat_map(|chunk| {
                by_path(chunk).into_iter().flat_map(move |(place, k, _)| {
                    chunk.splats_of(place).iter().map(move |&(pixel, radiance)| (pixel, k, radiance))
                })
            })
            .collect();
        splats.sort_by_key(|&(pixel, _, _)| pixel);
        Changes { paths, retraced, own, added, removed, splats, moved }
    }

    /// `frame`'s estimates where they differ from the common ones, in pixel order, and the work
    /// it did.
    fn frame_estimates(
        &self,
        frame: &Renderer,
        pass: &PassSamples,
    ) -> (Vec<(u32, PixelEstimate)>, PassStats) {
        let setup = (&self.weights, &self.view);
        let changes = self.changes(frame, pass);
        let changed = |k: u32| changes.paths.binary_search(&k).is_ok();
        let lights = Lights {
            chunks: &self.chunks,
            paths: self.paths,
            merge_sets: &[(&self.merge_set, &changes.paths), (&changes.own, &[])],
            open_edges: &frame.scene.open_edges,
            keep_merges: false,
            retraced: Some(&changes.retraced),
        };
        let traced_again = self.watched.changed_in(frame);
        let candidates = self.candidates(&changes, &traced_again);
        let (estimates, stats) = collect_counting(candidates.len(), |candidate| {
            let pixel = candidates[candidate] as usize;
            let paired = self.paths > 0 && changed((pixel % self.paths) as u32);
            let (old, new) = (splats_at(&self.splats, pixel), splats_at(&changes.splats, pixel));
            let merged = match paired || traced_again.binary_search(&(pixel as u32)).is_ok() {
                true => None,
                false => self.merging_change(&changes, pixel),
            };
            let Some(merged) = merged else {
                let (found, stats) = trace_camera_path(frame, pass, setup, &lights, pixel);
                let mut estimate = found.estimate;
                let kept = old.iter().filter(|&&(_, k, _)| !changed(k));
                for &(_, _, radiance) in kept.chain(new) {
                    estimate.radiance += radiance;
                }
                return (Some(estimate), stats);
            };
            let lost = old.iter().filter(|&&(_, k, _)| changed(k));
            if merged.is_none() && new.is_empty() && lost.clone().next().is_none() {
                return (None, PassStats::default());
            }
            let mut estimate = self.common[pixel];
            if let Some((radiance, laplacian)) = merged {
                estimate.radiance += radiance;
                estimate.laplacian += laplacian;
            }
            for &(_, _, radiance) in lost {
                estimate.radiance -= radiance;
            }
            for &(_, _, radiance) in new {
                estimate.radiance += radiance;
            }
            (Some(estimate), PassStats::default())
        });
        let differing = (candidates.into_iter().zip(estimates))
            .filter_map(|(pixel, estimate)| estimate.map(|e| (pixel, e)))
            .collect();
        (differing, changes.retraced.chunks.iter().fold(stats, |all, chunk| all + chunk.stats))
    }
}

/// Every pixel's common estimate, its watched rays (where it has some, or merges near moving open
/// edges) and its merging camera vertices, from `(estimate, rays, near moving edges, merges)` per
/// pixel.
fn gather_pixels(
    traced: Vec<(PixelEstimate, Vec<Ray>, bool, Vec<KeptMerge>)>,
) -> (Vec<PixelEstimate>, Watched, KeptMerges) {
    let mut common = Vec::with_capacity(traced.len());
    let (mut watched, mut kept, mut starts) = (Watched::default(), Vec::new(), Vec::new());
    for (pixel, (estimate, rays, near_edges, merges)) in traced.into_iter().enumerate() {
        common.push(estimate);
        if near_edges || !rays.is_empty() {
            watched.pixels.push(pixel as u32);
            watched.starts.push(watched.rays.len());
            watched.rays.extend(rays);
            watched.near_edges.push(near_edges);
        }
        starts.push(kept.len());
        kept.extend(merges);
    }
    watched.starts.push(watched.rays.len());
    starts.push(kept.len());
    (common, watched, KeptMerges { kept, starts })
}

/// Where two tracings of a light path differ: `None` where they came out the same (the same
/// vertices, throughputs and splats: the same random numbers gave the same path), else the first
/// vertex at which they differ (or the number of vertices they share, where only what follows or
/// their splats differ).
fn first_difference(
    (a, a_splats): (&[LightVertex], &[Splat]),
    (b, b_splats): (&[LightVertex], &[Splat]),
) -> Option<usize> {
    let same = |(u, v): (&LightVertex, &LightVertex)| {
        u.p == v.p && u.throughput == v.throughput && u.segments == v.segments
    };
    let shared = a.iter().zip(b).take_while(|&pair| same(pair)).count();
    (shared < a.len().max(b.len()) || a_splats != b_splats).then_some(shared.min(a.len()).min(b.len()))
}

/// Every path's splats in `chunks`, with its path, sorted by pixel (in path order for each pixel).
fn splats_by_pixel(chunks: &[LightSubpaths]) -> Vec<PathSplat> {
    let mut splats: Vec<PathSplat> = (chunks.iter())
        .flat_map(|chunk| {
            chunk.ids.iter().enumerate().flat_map(move |(place, &k)| {
                chunk.splats_of(place).iter().map(move |&(pixel, radiance)| (pixel, k, radiance))
            })
        })
        .collect();
    splats.sort_by_key(|&(pixel, _, _)| pixel);
    splats
}

/// The splats of `splats` (sorted by pixel) that land on `pixel`.
fn splats_at(splats: &[PathSplat], pixel: usize) -> &[PathSplat] {
    let pixel = pixel as u32;
    let start = splats.partition_point(|&(p, _, _)| p < pixel);
    let end = start + splats[start..].partition_point(|&(p, _, _)| p == pixel);
    &splats[start..end]
}

/// Whether `p` lies within `radius` of the box `(lo, hi)`.
fn within(p: Vec3, (lo, hi): (Vec3, Vec3), radius: f32) -> bool {
    (lo - p).max(p - hi).max(Vec3::ZERO).length() <= radius
}
