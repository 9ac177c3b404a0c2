//! The one place that drives the pipeline: load, prepare the time range, then for each frame run
//! passes (posing the scene at each pass's time when something moves), accumulate, write.
//!
//! Takes the render settings; gives `OUT/frame_####.exr` per frame and a report of what was done.
//! Passes run until `--passes` or `--time-budget` is reached, whichever comes first. Each pass
//! samples one time in the frame's shutter (DESIGN.md step 1), shared by its eye rays and photons.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use crate::accel::{Accel, Bvh};
use crate::error::{summarize, ErrorSummary, PixelError};
use crate::film::{Film, FilmMode};
use crate::monitor::{ErrorSettings, Monitor, StopReason};
use crate::progress::Progress;
pub use crate::progress::ProgressStyle;
use crate::sampling::pass_time_sample;
use crate::scene::description::{LensSettings, Shutter};
use crate::scene::pose::lens;
use crate::scene::{Description, Prepared, Scene, TimeRange};
use crate::sppm::{PassStats, Renderer, SppmSettings};

/// Passes when neither a pass count nor a time budget is given.
pub const DEFAULT_PASSES: u64 = 64;

/// Blender's default focus distance, used when an f-stop is given without one.
pub const DEFAULT_FOCUS_DISTANCE: f32 = 10.0;

/// Everything `caustic render` was asked for.
#[derive(Clone, Debug)]
pub struct RenderSettings {
    /// The glTF scene.
    pub scene: PathBuf,
    /// Output folder.
    pub out_dir: PathBuf,
    /// Frames to render, in order.
    pub frames: Vec<i32>,
    /// Skip frames whose EXR already exists (EXRs are only ever complete: written and renamed).
    pub resume: bool,
    /// Pass count, if given.
    pub passes: Option<u64>,
    /// Wall-clock budget per frame in seconds, if given.
    pub time_budget_s: Option<f64>,
    /// Photon paths per pass (default: one per pixel).
    pub photons: Option<usize>,
    /// Knaus & Zwicker's alpha.
    pub alpha: f64,
    /// First-pass gather radius (default: from the scene's size).
    pub radius: Option<f64>,
    /// Resolution override.
    pub resolution: Option<[u32; 2]>,
    /// Random seed.
    pub seed: u64,
    /// Progress display.
    pub progress: ProgressStyle,
    /// Render every pass at this wavelength (nm).
    pub wavelength_nm: Option<f32>,
    /// Spectral bands written beside Combined (0 for none).
    pub spectral_bins: usize,
    /// Shutter length override in frames (0: no motion blur), centred on the frame.
    pub shutter_frames: Option<f32>,
    /// f-stop override (0: a pinhole).
    pub fstop: Option<f32>,
    /// Focus distance override, scene units.
    pub focus_distance: Option<f32>,
    /// Error bound, log, reference and target.
    pub errors: ErrorSettings,
}

impl RenderSettings {
    /// The defaults of `caustic render SCENE -o OUT_DIR`: frame 1, 64 passes, seed 1.
    pub fn new(scene: &Path, out_dir: &Path) -> Self {
        RenderSettings {
            scene: scene.to_path_buf(),
            out_dir: out_dir.to_path_buf(),
            frames: vec![1],
            resume: false,
            passes: None,
            time_budget_s: None,
            photons: None,
            alpha: 2.0 / 3.0,
            radius: None,
            resolution: None,
            seed: 1,
            progress: ProgressStyle::None,
            wavelength_nm: None,
            spectral_bins: 0,
            shutter_frames: None,
            fstop: None,
            focus_distance: None,
            errors: ErrorSettings::default(),
        }
    }
}

/// What a finished frame reports.
#[derive(Clone, Debug)]
pub struct FrameReport {
    /// The frame number.
    pub frame: i32,
    /// The EXR written.
    pub path: PathBuf,
    /// The accumulated image.
    pub film: Film,
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
    /// BVHs built over the fixed part (one per range).
    pub fixed_bvh_builds: u64,
    /// Scenes posed at a pass time (zero when nothing moves: one pose serves all).
    pub poses: u64,
}

/// Image size: the flag, else the scene's extras, else 640 wide at the camera's aspect ratio.
pub fn resolution(settings: &RenderSettings, description: &Description) -> [u32; 2] {
    settings.resolution.or(description.resolution).unwrap_or_else(|| {
        let aspect =
            description.camera.aspect_ratio.filter(|a| a.is_finite() && *a > 0.0).unwrap_or(16.0 / 9.0);
        [640, ((640.0 / aspect).round() as u32).max(1)]
    })
}

/// The first pass's radius when none is given: 1/100 of the scene's bounding diameter.
pub fn default_radius(scene: &Scene) -> f64 {
    f64::from(scene.bounding_sphere().radius) * 0.02
}

/// Loads the scene description and prints its warnings to stderr.
pub fn load_description(settings: &RenderSettings) -> Result<Description, String> {
    let description = Description::load(&settings.scene).map_err(|e| e.to_string())?;
    for warning in &description.warnings {
        eprintln!("caustic: warning: {}: {warning}", settings.scene.display());
    }
    Ok(description)
}

/// The shutter: the flag's length centred on the frame, else the scene's.
pub fn shutter(settings: &RenderSettings, description: &Description) -> Shutter {
    match settings.shutter_frames {
        Some(length) => Shutter { open: -length / 2.0, length },
        None => description.shutter,
    }
}

/// The lens settings: the flags over the camera's extras.
pub fn lens_settings(settings: &RenderSettings, description: &Description) -> Option<LensSettings> {
    let from_scene = description.camera.lens;
    let fstop = settings.fstop.or(from_scene.map(|l| l.fstop))?;
    let focus_distance =
        settings.focus_distance.or(from_scene.map(|l| l.focus_distance)).unwrap_or(DEFAULT_FOCUS_DISTANCE);
    let (blades, blade_rotation_deg) = from_scene.map_or((0, 0.0), |l| (l.blades, l.blade_rotation_deg));
    Some(LensSettings { fstop, focus_distance, blades, blade_rotation_deg })
}

/// glTF time (seconds) of frame time `frame` (frames may be fractional).
fn seconds(frame: f32, fps: f32) -> f32 {
    frame / fps
}

/// The time span every frame's shutter covers.
fn time_range(frames: &[i32], shutter: Shutter, fps: f32) -> TimeRange {
    let first = *frames.iter().min().unwrap_or(&0) as f32;
    let last = *frames.iter().max().unwrap_or(&0) as f32;
    TimeRange {
        start: seconds(first + shutter.open, fps),
        end: seconds(last + shutter.open + shutter.length, fps),
    }
}

/// Memory a pixel needs while rendering (sums, eye result, estimate), in bytes, generously.
const BYTES_PER_PIXEL: u64 = 256;

/// The largest image memory Caustic will try to allocate, in bytes.
const MAX_IMAGE_BYTES: u64 = 16 << 30;

/// Refuses resolutions whose buffers would not fit in memory, before anything is allocated.
fn check_resolution([width, height]: [u32; 2]) -> Result<(), String> {
    let bytes = u64::from(width) * u64::from(height) * BYTES_PER_PIXEL;
    if bytes > MAX_IMAGE_BYTES {
        return Err(format!(
            "resolution {width}x{height} would need about {} GiB of image buffers (at most {} GiB)",
            bytes >> 30,
            MAX_IMAGE_BYTES >> 30
        ));
    }
    Ok(())
}

/// The output file of `frame`.
pub fn frame_path(out_dir: &Path, frame: i32) -> PathBuf {
    out_dir.join(format!("frame_{frame:04}.exr"))
}

/// A render of one scene over its frames: the prepared time range and what every frame shares.
pub struct Shot {
    prepared: Prepared,
    fixed_bvh: Arc<Bvh>,
    still: Option<(Scene, Accel)>,
    shutter: Shutter,
    sppm: SppmSettings,
}

impl Shot {
    /// Prepares `description` for the frames and settings of `settings`.
    pub fn new(settings: &RenderSettings, description: Description) -> Result<Self, String> {
        let [width, height] = resolution(settings, &description);
        check_resolution([width, height])?;
        let shutter = shutter(settings, &description);
        let range = time_range(&settings.frames, shutter, description.fps);
        let lens = lens(lens_settings(settings, &description), description.camera.focal_length_mm);
        let prepared = Prepared::with_lens(Arc::new(description), range, lens);
        let fixed_bvh = Arc::new(Bvh::build(&prepared.fixed_corners()));
        let first = prepared.pose(range.start);
        let sppm = SppmSettings {
            width,
            height,
            photons_per_pass: settings.photons.unwrap_or((width * height) as usize),
            alpha: settings.alpha,
            initial_radius: settings.radius.unwrap_or_else(|| default_radius(&first)),
            seed: settings.seed,
            fixed_wavelength_nm: settings.wavelength_nm,
        };
        let still = (!prepared.has_motion()).then(|| (first, Accel::new(Arc::clone(&fixed_bvh), &[])));
        Ok(Shot { prepared, fixed_bvh, still, shutter, sppm })
    }

    /// The SPPM settings every pass uses.
    pub fn sppm(&self) -> &SppmSettings {
        &self.sppm
    }

    /// The shutter.
    pub fn shutter(&self) -> Shutter {
        self.shutter
    }

    /// The prepared scene (what moves, the lens).
    pub fn prepared(&self) -> &Prepared {
        &self.prepared
    }

    /// The scene and its BVHs at `time`.
    pub fn pose(&self, time: f32) -> (Scene, Accel) {
        let scene = self.prepared.pose(time);
        let accel = Accel::new(Arc::clone(&self.fixed_bvh), &scene.moving.corners());
        (scene, accel)
    }

    /// The time of pass `index` of `frame`: one point of the shutter, the same for every frame.
    fn pass_time(&self, frame: i32, index: u64) -> f32 {
        let offset = self.shutter.open + pass_time_sample(self.sppm.seed, index) * self.shutter.length;
        seconds(frame as f32 + offset, self.prepared.description.fps)
    }
}

/// Renders every frame of `settings.frames` and writes `OUT/frame_####.exr` for each.
pub fn render(settings: &RenderSettings) -> Result<RenderReport, String> {
    let shot = Shot::new(settings, load_description(settings)?)?;
    std::fs::create_dir_all(&settings.out_dir)
        .map_err(|e| format!("cannot create output folder {}: {e}", settings.out_dir.display()))?;
    let mut report = RenderReport { fixed_bvh_builds: 1, ..Default::default() };
    for &frame in &settings.frames {
        let path = frame_path(&settings.out_dir, frame);
        if settings.resume && path.exists() {
            report.skipped.push(frame);
            continue;
        }
        let run = run_passes(&shot, settings, frame)?;
        report.poses += run.poses;
        let film = run.film;
        if film.non_finite_estimates > 0 {
            eprintln!(
                "caustic: warning: frame {frame}: {} pixel estimates were NaN or infinite and counted as zero (please report this scene)",
                film.non_finite_estimates
            );
        }
        let bound = run.errors.iter().map(|e| e.bound as f32).collect();
        let variance = run.errors.iter().map(|e| e.variance as f32).collect();
        film.write_exr(&path, &[("Error.Y", bound), ("Variance.Y", variance)])?;
        Progress::written(
            settings.progress,
            frame,
            &path,
            film.passes,
            run.elapsed_s,
            run.stopped_by.as_str(),
        );
        let error = summarize(&run.errors);
        let (passes, elapsed_s, stats, stopped_by) = (film.passes, run.elapsed_s, run.stats, run.stopped_by);
        report.frames.push(FrameReport { frame, path, film, passes, elapsed_s, stats, stopped_by, error });
    }
    Ok(report)
}

/// What a frame's passes produced.
struct FrameRun {
    film: Film,
    errors: Vec<PixelError>,
    elapsed_s: f64,
    stats: PassStats,
    poses: u64,
    stopped_by: StopReason,
}

/// Runs passes 0, 1, ... of `frame` until the pass count, the time budget or the target error.
fn run_passes(shot: &Shot, settings: &RenderSettings, frame: i32) -> Result<FrameRun, String> {
    let s = &shot.sppm;
    let mode = match s.fixed_wavelength_nm {
        Some(lambda_nm) => FilmMode::Monochromatic { lambda_nm },
        None => FilmMode::Spectral,
    };
    let mut film = Film::new(s.width, s.height, mode, settings.spectral_bins);
    let mut monitor = Monitor::new(&settings.errors, frame, s.width, s.height)?;
    let limit = settings.passes.or(if settings.time_budget_s.is_some() || settings.errors.target.is_some() {
        None
    } else {
        Some(DEFAULT_PASSES)
    });
    let progress = Progress::new(settings.progress, frame, limit);
    let start = Instant::now();
    let (mut stats, mut poses, mut pass) = (PassStats::default(), 0, 0);
    // Without a shutter every pass of a frame sees the same instant: pose it once.
    let frame_pose = (shot.still.is_none() && shot.shutter.length == 0.0).then(|| {
        poses += 1;
        shot.pose(shot.pass_time(frame, 0))
    });
    // A scene that stays put for the whole frame gets one renderer (its light choice is built
    // once, not per pass).
    let fixed_renderer = match (&shot.still, &frame_pose) {
        (Some((scene, accel)), _) | (None, Some((scene, accel))) => {
            Some(Renderer::new(scene, accel, s.clone()))
        }
        (None, None) => None,
    };
    loop {
        let (samples, estimates, pass_stats) = match &fixed_renderer {
            Some(renderer) => renderer.run_pass(pass),
            None => {
                let (scene, accel) = shot.pose(shot.pass_time(frame, pass));
                poses += 1;
                Renderer::new(&scene, &accel, s.clone()).run_pass(pass)
            }
        };
        film.add_pass(
            samples.lambda_nm,
            samples.lambda_pdf,
            samples.radius,
            estimates.iter().map(|e| (e.radiance, e.laplacian)),
        );
        stats = stats + pass_stats;
        pass += 1;
        let elapsed = start.elapsed().as_secs_f64();
        progress.update(pass, elapsed);
        let photons = pass * s.photons_per_pass as u64;
        let stopped_by = if monitor.after_pass(&film, elapsed, photons)? {
            Some(StopReason::TargetError)
        } else if settings.time_budget_s.is_some_and(|budget| elapsed >= budget) {
            Some(StopReason::TimeBudget)
        } else if limit.is_some_and(|n| pass >= n) {
            Some(StopReason::Passes)
        } else {
            None
        };
        if let Some(stopped_by) = stopped_by {
            progress.finish();
            let errors = monitor.finish(&film, elapsed, photons, stopped_by)?;
            return Ok(FrameRun { film, errors, elapsed_s: elapsed, stats, poses, stopped_by });
        }
    }
}
