//! Frames rendered together, pass-major, in blocks the memory budget holds: the pass loop,
//! posing each pass, the passes a block shares across its frames (reuse), and adding each
//! pass to its frame's film.

use std::borrow::Cow;
use std::sync::Arc;
use std::time::{Duration, Instant};

use super::report::{finish_frames, stop_reason, FrameInProgress, RenderReport};
use super::settings::{load_description, output_path, shutter, RenderSettings, BYTES_PER_PIXEL};
use super::shot::{motion_spans, Posed, Shot};
use super::{stop_requested, DEFAULT_PASSES};
use crate::film::{Estimate, Film, FilmMode, GUIDE_SUMS};
use crate::monitor::Monitor;
use crate::progress::Progress;
use crate::progress::ProgressStyle;

use crate::transport::{
    run_shared_pass, FrameEstimates, Method, PassSamples, PassStats, PhotonSampling, PixelEstimate, Renderer,
};

impl Shot {
    /// Whether a block of `frames` frames shares paths: reuse is on, there is more than one
    /// frame, there are static triangles to share, no medium scatters (paths that end in
    /// media, and the direct light along their segments, are not shared), and the passes are
    /// SPPM's (VCM's paths are not shared yet).
    pub(super) fn shares(&self, settings: &RenderSettings, frames: usize) -> bool {
        settings.reuse
            && settings.method.capabilities().reuses_across_frames
            && frames > 1
            && self.prepared.triangle_counts().0 > 0
            && !self.prepared.description.scatters()
    }

    /// How many frames render together: as many as the memory budget holds beside what one
    /// pass needs, at least one; one when reuse is off.
    pub(super) fn block_frames(&self, settings: &RenderSettings, frames: usize) -> usize {
        if !self.shares(settings, frames) {
            return 1;
        }
        let pixels = u64::from(self.pass_settings.width) * u64::from(self.pass_settings.height);
        let guides = if settings.denoising_passes { GUIDE_SUMS } else { 0 };
        let per_frame = pixels * (FRAME_BYTES_PER_PIXEL + 8 * (settings.spectral_bins + guides) as u64);
        let per_path = match settings.method {
            Method::Sppm => PHOTON_BYTES_PER_PATH,
            Method::Vcm => LIGHT_SUBPATH_BYTES_PER_PATH,
        };
        let photons = self.pass_settings.photons_per_pass as u64 * per_path;
        let shared = pixels * (BYTES_PER_PIXEL + SHARED_BYTES_PER_PIXEL) + photons;
        let fit = settings.memory_budget.saturating_sub(shared) / per_frame.max(1);
        (fit as usize).clamp(1, frames)
    }
}

/// What a frame keeps while its block renders: its sums, its error monitor, its work counts.
pub(super) const FRAME_BYTES_PER_PIXEL: u64 = 96;

/// What a block holds per pixel for its frames together: a shared eye path with its common
/// gather and every shared photon's sums (560 bytes), its common estimate (48), its visible
/// point bucketed (16) and the common film (64); generously.
pub(super) const SHARED_BYTES_PER_PIXEL: u64 = 704;

/// What one pass holds per photon path (its photons and the segments frames check), generously.
pub(super) const PHOTON_BYTES_PER_PATH: u64 = 256;

/// What one VCM pass holds per light path and pixel beyond SPPM's per pixel (the path's vertices,
/// bucketed for merging, its splats; the pixel's merging camera vertices and rays kept for the
/// frames), generously: measured, a block of the 24-frame shot at 320x240 peaked 28 MiB above
/// SPPM's, 380 bytes a pixel with a light path each.
pub(super) const LIGHT_SUBPATH_BYTES_PER_PATH: u64 = PHOTON_BYTES_PER_PATH + 512;

/// The passes a frame renders at most: a partial result's range, else `--passes`, else none
/// when a time budget or a target error ends it, else the default.
pub(super) fn pass_limit(settings: &RenderSettings) -> Option<u64> {
    if let Some(passes) = &settings.partial_passes {
        return Some(passes.end - passes.start);
    }
    let open_ended = settings.time_budget_s.is_some() || settings.errors.target.is_some();
    settings.passes.or((!open_ended).then_some(DEFAULT_PASSES))
}

/// Renders `frames` pass-major until each is stopped, writing each as it stops.
pub(super) fn render_block(
    shot: &Shot,
    settings: &RenderSettings,
    frames: &[i32],
    report: &mut RenderReport,
) -> Result<(), String> {
    let s = &shot.pass_settings;
    let mode = match s.fixed_wavelength_nm {
        Some(lambda_nm) => FilmMode::Monochromatic { lambda_nm },
        None => FilmMode::Spectral,
    };
    let (mut active, mut own_poses) = (Vec::new(), Vec::new());
    for &frame in frames {
        let film = Film::new(s.width, s.height, mode, settings.spectral_bins, settings.denoising_passes);
        let shown = settings.progress != ProgressStyle::None;
        let monitor = Monitor::new(&settings.errors, frame, [s.width, s.height], s.alpha, shown)?;
        active.push(FrameInProgress { frame, film, monitor, stats: PassStats::default(), elapsed_s: 0.0 });
        // Without a shutter every pass of a frame sees the same instant: pose it once.
        own_poses.push((shot.still.is_none() && shot.shutter.length == 0.0).then(|| {
            report.poses += 1;
            shot.pose(shot.pass_time(frame, 0))
        }));
    }
    let limit = pass_limit(settings);
    let progress = Progress::new(settings.progress, frames, limit);
    let share = shot.shares(settings, frames.len());
    let first_pass = settings.partial_passes.as_ref().map_or(0, |r| r.start);
    // With frames that share pixel estimates: the film of the common ones (each frame's own
    // film then holds its differences from it).
    let mut common: Option<Film> = None;
    let mut done = 0;
    while !active.is_empty() {
        let start = Instant::now();
        let pass = first_pass + done;
        let samples = s.pass_samples(pass);
        let poses: Vec<Posed> = active
            .iter()
            .zip(&own_poses)
            .map(|(f, own)| shot.posed(f.frame, own, pass, &mut report.poses))
            .collect();
        let posed = Instant::now();
        report.time_split.posing += (posed - start).as_secs_f64();
        let (mut accumulation, mut shared) = (Duration::ZERO, Duration::ZERO);
        if share {
            let stats;
            (stats, shared) =
                shared_pass(shot, &poses, &samples, &mut active, &mut common, &mut accumulation);
            report.shared_stats = report.shared_stats + stats;
        } else {
            for (frame, posed) in active.iter_mut().zip(&poses) {
                let (scene, accel) = posed.parts();
                let (estimates, stats) = Renderer::new(scene, accel, s.clone()).run_pass(&samples);
                let adding = Instant::now();
                add_pass(frame, &samples, &estimates, stats);
                accumulation += adding.elapsed();
            }
        }

        if settings.denoising_passes {
            for (frame, posed) in active.iter_mut().zip(&poses) {
                let (scene, accel) = posed.parts();
                let guides = Renderer::new(scene, accel, s.clone()).trace_guides(&samples);
                frame.film.add_guides(&samples.wavelengths, guides.iter().map(|g| (g.albedo, g.normal)));
            }
        }
        drop(poses);
        let passes_done = Instant::now();
        let split = &mut report.time_split;
        split.shared += shared.as_secs_f64();
        split.accumulation += accumulation.as_secs_f64();
        split.frames += (passes_done - posed).saturating_sub(shared + accumulation).as_secs_f64();
        let elapsed_share = start.elapsed().as_secs_f64() / active.len() as f64;
        done += 1;
        for frame in &mut active {
            frame.elapsed_s += elapsed_share;
        }
        let photons = done * s.photons_per_pass as u64;
        let mut target_met = Vec::with_capacity(active.len());
        for frame in &mut active {
            let met = match frame.monitor.measures_after(done) {
                true => {
                    frame.monitor.after_pass(&whole_film(&frame.film, &common), frame.elapsed_s, photons)?
                }
                false => false,
            };
            target_met.push(met);
        }
        let rendered: Vec<i32> = active.iter().map(|f| f.frame).collect();
        progress.update(&rendered, done, active[0].elapsed_s, active[0].monitor.status());
        report.time_split.monitoring += passes_done.elapsed().as_secs_f64();
        if stop_requested() {
            let written = report.frames.len();
            let unfinished: Vec<String> = active.iter().map(|f| f.frame.to_string()).collect();
            return Err(format!(
                "interrupted: {written} frame(s) written; frame(s) {} not finished and not written; run the same command with --resume to continue",
                unfinished.join(", ")
            ));
        }
        let (mut still_running, mut their_poses, mut stopped) = (Vec::new(), Vec::new(), Vec::new());
        for ((frame, own), met) in active.into_iter().zip(own_poses).zip(target_met) {
            match stop_reason(settings, &frame, done, met, limit) {
                Some(stopped_by) => stopped.push((frame, stopped_by)),
                None => {
                    still_running.push(frame);
                    their_poses.push(own);
                }
            }
        }
        let writing = Instant::now();
        finish_frames(shot, settings, stopped, &common, photons, report)?;
        report.time_split.output += writing.elapsed().as_secs_f64();
        (active, own_poses) = (still_running, their_poses);
    }
    progress.finish();
    Ok(())
}

/// Runs pass `samples.index` for every active frame at once, sharing paths between them; gives
/// the work done once and its time, and adds the time spent adding estimates to films to
/// `accumulation`. Where the frames share pixel estimates, those go to the `common` film once
/// and each frame's film gets its differences.
pub(super) fn shared_pass(
    shot: &Shot,
    poses: &[Posed],
    samples: &PassSamples,
    active: &mut [FrameInProgress],
    common: &mut Option<Film>,
    accumulation: &mut Duration,
) -> (PassStats, Duration) {
    let s = &shot.pass_settings;
    let (first_scene, _) = poses[0].parts();
    let fixed_accel = shot.fixed_accel();
    let statics = Renderer::new(first_scene, &fixed_accel, s.clone());
    let renderers: Vec<Renderer> = poses
        .iter()
        .map(|p| {
            let (scene, accel) = p.parts();
            Renderer::choosing_lights_as(&statics, scene, accel)
        })
        .collect();
    let share_eyes = !shot.prepared.camera_moves() && !shot.prepared.lights_move();
    run_shared_pass(&statics, &renderers, samples, share_eyes, |out| {
        let adding = Instant::now();
        let frame = &mut active[out.frame];
        match out.estimates {
            FrameEstimates::Every(estimates) => add_estimates(&mut frame.film, samples, &estimates),
            FrameEstimates::Beside { common: estimates, differing } => {
                if out.frame == 0 {
                    let film = &frame.film;
                    let new = || Film::new(film.width, film.height, film.mode, film.bins.count, false);
                    add_estimates(common.get_or_insert_with(new), samples, estimates);
                }
                let difference = |k: usize| {
                    let (pixel, own) = &differing[k];
                    (*pixel as usize, sums(own), sums(&estimates[*pixel as usize]))
                };
                frame.film.add_differences(&samples.wavelengths, samples.radius, differing.len(), difference);
            }
        }
        frame.stats = frame.stats + out.stats;
        *accumulation += adding.elapsed();
    })
}

/// A frame's whole film: its own, or the block's common film plus its differences from it.
pub(super) fn whole_film<'a>(film: &'a Film, common: &Option<Film>) -> Cow<'a, Film> {
    match common {
        Some(common) => {
            let mut whole = common.clone();
            whole.add(film);
            Cow::Owned(whole)
        }
        None => Cow::Borrowed(film),
    }
}

/// Adds one pass's estimates to a frame.
pub(super) fn add_pass(
    frame: &mut FrameInProgress,
    samples: &PassSamples,
    estimates: &[PixelEstimate],
    stats: PassStats,
) {
    add_estimates(&mut frame.film, samples, estimates);
    frame.stats = frame.stats + stats;
}

/// Adds one pass's pixel estimates to a film.
pub fn add_estimates(film: &mut Film, samples: &PassSamples, estimates: &[PixelEstimate]) {
    film.add_pass(&samples.wavelengths, samples.radius, |i| sums(&estimates[i]));
}

/// What the film adds of a pixel estimate.
pub(super) fn sums(e: &PixelEstimate) -> Estimate {
    (e.radiance, e.laplacian, e.coverage)
}

/// Renders every frame of `settings.frames` and writes `OUT/frame_####.exr` for each.
///
/// Frames are rendered pass-major in blocks (docs/design.md, "Frames, and reuse across frames"): every
/// frame of a block renders pass 0, then pass 1, and so on, sharing the paths that the static part
/// of the scene makes alike. The block is as long as the memory budget allows.
///
/// Reuse is decided per span of frames over which the same things move (see [`motion_spans`]):
/// each span is prepared on its own, so an object that moves only in frames 10 to 12 is static
/// geometry for the frames before and after. Every span renders with the first span's radius.
/// Spans are found over every frame asked for, so a `--resume`d render prepares the frames it
/// has left as the first run did.
pub fn render(settings: &RenderSettings) -> Result<RenderReport, String> {
    let description = Arc::new(load_description(settings)?);
    let by_visibility = settings.method.capabilities().samples_photons_by_visibility;
    if !by_visibility && settings.photon_sampling != PhotonSampling::Uniform {
        let chosen = clap::ValueEnum::to_possible_value(&settings.photon_sampling);
        eprintln!(
            "caustic: warning: --photon-sampling {} is not used by --method {}, whose light paths are drawn uniformly",
            chosen.map_or_else(String::new, |v| v.get_name().to_string()),
            settings.method.flag()
        );
    }
    std::fs::create_dir_all(&settings.out_dir)
        .map_err(|e| format!("cannot create output folder {}: {e}", settings.out_dir.display()))?;
    let mut report = RenderReport::default();
    let done = |f: &i32| settings.resume && output_path(settings, *f).exists();
    report.skipped = settings.frames.iter().copied().filter(done).collect();
    let mut span_settings = settings.clone();
    for span in motion_spans(&description, &settings.frames, shutter(settings, &description)) {
        let todo: Vec<i32> = span.iter().copied().filter(|f| !done(f)).collect();
        if todo.is_empty() && span_settings.radius.is_some() {
            continue;
        }
        span_settings.frames = span;
        let shot = Shot::new(&span_settings, Arc::clone(&description))?;
        span_settings.radius = Some(shot.pass_settings.initial_radius);
        report.fixed_bvh_builds += 1;
        let block_frames = shot.block_frames(settings, todo.len());
        if block_frames > 1 && settings.photon_sampling == PhotonSampling::Visible {
            eprintln!(
                "caustic: warning: frames {:?} share their photon paths (reuse across frames), which are drawn uniformly; --no-reuse draws each frame's by visibility",
                span_settings.frames
            );
        }
        report.block_frames = report.block_frames.max(block_frames);
        for block in todo.chunks(block_frames) {
            render_block(&shot, settings, block, &mut report)?;
        }
    }
    Ok(report)
}
