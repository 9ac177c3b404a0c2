//! What a render reports, and the end of a frame: why it stopped, its EXR written (to a
//! temporary file, renamed), the line announcing it.

use std::path::{Path, PathBuf};

use super::partial;
use super::settings::{output_path, RenderSettings};
use super::shot::Shot;
use crate::error::{summarize, ErrorSummary, PixelError};
use crate::film::{Film, FilmMode};
use crate::monitor::{Monitor, StopReason};
use crate::progress::Progress;
use rayon::prelude::*;

use crate::transport::PassStats;

/// What a finished frame reports.
#[derive(Clone, Debug)]
pub struct FrameReport {
    /// The frame number.
    pub frame: i32,
    /// The EXR written.
    pub path: PathBuf,
    /// Passes rendered.
    pub passes: u64,
    /// Wall-clock seconds for the passes.
    pub elapsed_s: f64,
    /// Work counts summed over passes.
    pub stats: PassStats,
    /// What ended the frame.
    pub stopped_by: StopReason,
    /// The frame's relative error bound statistics.
    pub error: ErrorSummary,
}

/// What a whole render reports.
#[derive(Clone, Debug, Default)]
pub struct RenderReport {
    /// Rendered frames, in order (skipped ones are absent).
    pub frames: Vec<FrameReport>,
    /// Frames skipped by `--resume`.
    pub skipped: Vec<i32>,
    /// BVHs built over the fixed part (one per span of frames over which the same things move).
    pub fixed_bvh_builds: u64,
    /// Scenes posed at a pass time (zero when nothing moves: one pose serves all).
    pub poses: u64,
    /// Frames rendered together in a block (pass-major); the longest block's.
    pub block_frames: usize,
    /// Work done once per pass for a whole block (paths shared between its frames).
    pub shared_stats: PassStats,
    /// Where the time went, summed over every frame and pass.
    pub time_split: TimeSplit,
}

/// Where a render's time went, in seconds summed over its frames and passes.
#[derive(Clone, Copy, Debug, Default)]
pub struct TimeSplit {
    /// Posing the scene at pass times (and building the moving BVH).
    pub posing: f64,
    /// Work shared by the frames of a block: photon paths against the static triangles, their
    /// checks, the common photons' grid, shared eye paths.
    pub shared: f64,
    /// Each frame's own work: its eye paths and gathers (all of a pass without reuse).
    pub frames: f64,
    /// Adding each pass's estimates to its frame's film.
    pub accumulation: f64,
    /// Each frame's error estimate after a pass, and the progress line.
    pub monitoring: f64,
    /// Writing each frame's EXR.
    pub output: f64,
}

/// Writes a frame's EXR with its error passes (the bound and the variance of the mean).
pub fn write_frame(film: &Film, errors: &[PixelError], path: &Path) -> Result<(), String> {
    let bound = errors.iter().map(|e| e.bound as f32).collect();
    let variance = errors.iter().map(|e| e.variance as f32).collect();
    film.write_exr(path, &[("Error.Y", bound), ("Variance.Y", variance)])
}

/// What stops `frame`, after `passes` passes, if anything: its target error (`target_met`, as
/// its monitor found), its time budget or the pass count.
pub(super) fn stop_reason(
    settings: &RenderSettings,
    frame: &FrameInProgress,
    passes: u64,
    target_met: bool,
    limit: Option<u64>,
) -> Option<StopReason> {
    if target_met {
        Some(StopReason::TargetError)
    } else if settings.time_budget_s.is_some_and(|budget| frame.elapsed_s >= budget) {
        Some(StopReason::TimeBudget)
    } else if limit.is_some_and(|n| passes >= n) {
        Some(StopReason::Passes)
    } else {
        None
    }
}

/// Writes the EXRs of frames stopped after the same pass (with their error passes, after
/// `photons` photon paths; as many at once as there are threads), announces them and reports
/// them in order.
pub(super) fn finish_frames(
    shot: &Shot,
    settings: &RenderSettings,
    mut stopped: Vec<(FrameInProgress, StopReason)>,
    common: &Option<Film>,
    photons: u64,
    report: &mut RenderReport,
) -> Result<(), String> {
    while !stopped.is_empty() {
        let rest = stopped.split_off(stopped.len().min(rayon::current_num_threads()));
        let group = std::mem::replace(&mut stopped, rest);
        let finished: Vec<_> = group
            .into_par_iter()
            .map(|(mut frame, stopped_by)| {
                let mut film =
                    std::mem::replace(&mut frame.film, Film::new(0, 0, FilmMode::Spectral, 0, false));
                if let Some(common) = common {
                    film.add(common);
                }
                let errors = frame.monitor.final_errors(&film);
                let written = write_output(shot, settings, frame.frame, &film, &errors);
                (frame, stopped_by, film, errors, written)
            })
            .collect();
        for (mut frame, stopped_by, film, errors, written) in finished {
            frame.monitor.finish(&film, &errors, frame.elapsed_s, photons, stopped_by)?;
            if film.non_finite_estimates > 0 {
                eprintln!(
                    "caustic: warning: frame {}: {} pixel estimates were NaN or infinite and counted as zero (please report this scene)",
                    frame.frame, film.non_finite_estimates
                );
            }
            announce(settings, frame, stopped_by, &film, &errors, written?, report);
        }
    }
    Ok(())
}

/// Announces a written frame and adds it to the report.
pub(super) fn announce(
    settings: &RenderSettings,
    frame: FrameInProgress,
    stopped_by: StopReason,
    film: &Film,
    errors: &[PixelError],
    path: PathBuf,
    report: &mut RenderReport,
) {
    Progress::written(
        settings.progress,
        frame.frame,
        &path,
        film.passes,
        frame.elapsed_s,
        stopped_by.as_str(),
    );
    report.frames.push(FrameReport {
        frame: frame.frame,
        path,
        passes: film.passes,
        elapsed_s: frame.elapsed_s,
        stats: frame.stats,
        stopped_by,
        error: summarize(errors),
    });
}

/// Writes a frame's EXR, or its partial result; gives its path.
pub(super) fn write_output(
    shot: &Shot,
    settings: &RenderSettings,
    frame: i32,
    film: &Film,
    errors: &[PixelError],
) -> Result<PathBuf, String> {
    let path = output_path(settings, frame);
    match (&settings.partial_passes, &shot.identity) {
        (Some(passes), Some((sha256, fingerprint))) => {
            let header = partial::header(
                &settings.scene,
                sha256.clone(),
                fingerprint.clone(),
                frame,
                passes.clone(),
                film,
            );
            partial::write(&path, &header, film)?;
        }
        _ => write_frame(film, errors, &path)?,
    }
    Ok(path)
}

/// A frame while its block renders.
pub(super) struct FrameInProgress {
    pub(super) frame: i32,
    pub(super) film: Film,
    pub(super) monitor: Monitor,
    pub(super) stats: PassStats,
    /// Its share of the block's wall-clock time.
    pub(super) elapsed_s: f64,
}
