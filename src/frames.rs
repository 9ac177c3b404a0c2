//! The one place that drives the pipeline: load, prepare the time range, then for each frame run
//! passes (posing the scene at each pass's time when something moves), accumulate, write.
//!
//! Takes the render settings; gives `OUT/frame_####.exr` per frame and a report of what was done.
//! Passes run until `--passes` or `--time-budget` is reached, whichever comes first. Each pass
//! samples one time in the frame's shutter (DESIGN.md step 1), shared by its eye rays and photons.

use std::borrow::Cow;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

use crate::accel::{Accel, BuildFor, Bvh, InstancedBvh};
use crate::error::{summarize, ErrorSummary, PixelError};
use crate::film::{Estimate, Film, FilmMode, GUIDE_SUMS};
use crate::monitor::{ErrorSettings, Monitor, StopReason};
use crate::partial;
use crate::progress::Progress;
pub use crate::progress::ProgressStyle;
use crate::sampling::pass_time_sample;
use crate::scene::description::{Lens, LensSettings, Shutter};
use crate::scene::pose::{lens, Motion};
use crate::scene::{Description, Prepared, Scene, TimeRange, DEFAULT_RADIUS_FRACTION};
pub use crate::sppm::{LightSampling, Method, PhotonSampling};
use rayon::prelude::*;

use crate::sppm::{
    run_shared_pass, vcm_unsupported, Crop, FrameEstimates, PassSamples, PassStats, PixelEstimate, Renderer,
    SppmSettings, ViewMeasure,
};

/// Set when the user asks the render to stop (Ctrl-C, SIGTERM): the pass in flight finishes,
/// frames not yet written are dropped, and the render ends with an error naming what was kept.
static STOP_REQUESTED: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Asks the render in progress to stop after its current pass (safe from a signal handler).
pub fn request_stop() {
    STOP_REQUESTED.store(true, std::sync::atomic::Ordering::SeqCst);
}

fn stop_requested() -> bool {
    STOP_REQUESTED.load(std::sync::atomic::Ordering::SeqCst)
}

/// Passes when neither a pass count nor a time budget is given.
pub const DEFAULT_PASSES: u64 = 64;

/// Memory for the frames rendered together when `--memory-budget` is not given: 4 GiB.
pub const DEFAULT_MEMORY_BUDGET: u64 = 4 << 30;

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
    /// Knaus & Zwicker's alpha (default: the method's, [`Method::default_alpha`]).
    pub alpha: Option<f64>,
    /// First-pass gather radius (default: from the scene's size).
    pub radius: Option<f64>,
    /// Resolution override.
    pub resolution: Option<[u32; 2]>,
    /// The window `[x, y, width, height]` of the image to render (all of it when `None`).
    pub crop: Option<[u32; 4]>,
    /// Random seed.
    pub seed: u64,
    /// Progress display.
    pub progress: ProgressStyle,
    /// Render every pass at this wavelength (nm).
    pub wavelength_nm: Option<f32>,
    /// How next-event estimation chooses a light.
    pub light_sampling: LightSampling,
    /// How photon paths draw their primary samples.
    pub photon_sampling: PhotonSampling,
    /// How a pass combines camera and light paths.
    pub method: Method,
    /// Spectral bands written beside Combined (0 for none).
    pub spectral_bins: usize,
    /// Write Cycles' Denoising Albedo and Denoising Normal passes.
    pub denoising_passes: bool,
    /// Shutter length override in frames (0: no motion blur), centred on the frame.
    pub shutter_frames: Option<f32>,
    /// f-stop override (0: a pinhole).
    pub fstop: Option<f32>,
    /// Focus distance override, scene units.
    pub focus_distance: Option<f32>,
    /// Error bound, log, reference and target.
    pub errors: ErrorSettings,
    /// Share paths between frames rendered together (`--no-reuse` turns it off).
    pub reuse: bool,
    /// Memory for the frames rendered together, in bytes.
    pub memory_budget: u64,
    /// Render exactly these passes and write partial results (`--pass-range A..B --partial`)
    /// for `caustic merge` instead of EXRs.
    pub partial_passes: Option<Range<u64>>,
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
            alpha: None,
            radius: None,
            resolution: None,
            crop: None,
            seed: 1,
            progress: ProgressStyle::None,
            wavelength_nm: None,
            light_sampling: LightSampling::Tree,
            photon_sampling: PhotonSampling::Uniform,
            method: Method::Sppm,
            spectral_bins: 0,
            denoising_passes: false,
            shutter_frames: None,
            fstop: None,
            focus_distance: None,
            errors: ErrorSettings::default(),
            reuse: true,
            memory_budget: DEFAULT_MEMORY_BUDGET,
            partial_passes: None,
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

/// Image size: the flag, else the scene's extras, else 640 wide at the camera's aspect ratio.
pub fn resolution(settings: &RenderSettings, description: &Description) -> [u32; 2] {
    settings.resolution.or(description.resolution).unwrap_or_else(|| {
        let aspect =
            description.camera.aspect_ratio.filter(|a| a.is_finite() && *a > 0.0).unwrap_or(16.0 / 9.0);
        [640, ((640.0 / aspect).round() as u32).max(1)]
    })
}

/// Photons per pass at which the scene-based first radius is 2% of the scene's diameter.
const DEFAULT_RADIUS_PHOTONS: f64 = 49_152.0;

/// The first pass's radius when none is given: from the view where the camera sees surfaces
/// ([`ViewMeasure::radius`]); where it sees none, 2% of the scene's bounding diameter, shrunk as
/// `photons^(-1/6)` above `DEFAULT_RADIUS_PHOTONS` photons a pass (the radius of least error
/// goes as the photons' density to the -1/6).
pub fn default_radius(scene: &Scene, view: Option<ViewMeasure>, photons_per_pass: usize) -> f64 {
    view.map(|v| v.radius()).unwrap_or_else(|| {
        let shrink = (DEFAULT_RADIUS_PHOTONS / photons_per_pass.max(1) as f64).powf(1.0 / 6.0).min(1.0);
        f64::from(scene.bounding_sphere().radius) * DEFAULT_RADIUS_FRACTION * shrink
    })
}

/// How a render of `settings` draws its photon paths: `auto` is uniform where anything in the
/// scene is animated, so that frames sharing photon paths (reuse across frames, which draws them
/// uniformly) give the images `--no-reuse` and a farm's single frames give.
fn photon_sampling(settings: &RenderSettings, description: &Description) -> PhotonSampling {
    if settings.method == Method::Vcm {
        return PhotonSampling::Uniform;
    }
    match settings.photon_sampling {
        PhotonSampling::Auto if is_animated(description) => PhotonSampling::Uniform,
        chosen => chosen,
    }
}

/// Whether anything in `description` changes over time.
pub fn is_animated(description: &Description) -> bool {
    !Motion::within(description, TimeRange { start: f32::MIN, end: f32::MAX }).is_still()
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

/// The window of the image a render covers: `--crop`, which must lie inside the image, or the whole.
fn crop(window: Option<[u32; 4]>, image: [u32; 2]) -> Result<Crop, String> {
    let Some([x, y, w, h]) = window else { return Ok(Crop::whole(image)) };
    if u64::from(x) + u64::from(w) > u64::from(image[0]) || u64::from(y) + u64::from(h) > u64::from(image[1])
    {
        return Err(format!(
            "--crop {x},{y},{w},{h} reaches beyond the {}x{} image (x + width and y + height must fit)",
            image[0], image[1]
        ));
    }
    Ok(Crop { image, origin: [x, y], size: [w, h] })
}

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

/// What a render writes for `frame`: its EXR, or its partial result.
fn output_path(settings: &RenderSettings, frame: i32) -> PathBuf {
    match &settings.partial_passes {
        Some(passes) => partial::partial_path(&settings.out_dir, frame, passes),
        None => frame_path(&settings.out_dir, frame),
    }
}

/// The output file of `frame`.
pub fn frame_path(out_dir: &Path, frame: i32) -> PathBuf {
    out_dir.join(format!("frame_{frame:04}.exr"))
}

/// Everything that shapes a pass beyond the scene: what partial results must share to merge.
fn fingerprint(
    sppm: &SppmSettings,
    shutter: Shutter,
    prepared: &Prepared,
    settings: &RenderSettings,
) -> serde_json::Value {
    let lens =
        prepared.lens().map(|l| [l.aperture_radius, l.focus_distance, l.blades as f32, l.blade_rotation]);
    serde_json::json!({
        "resolution": [sppm.width, sppm.height],
        "crop": [sppm.crop.image, sppm.crop.origin],
        "photons_per_pass": sppm.photons_per_pass,
        "alpha": sppm.alpha,
        "initial_radius": sppm.initial_radius,
        "seed": sppm.seed,
        "wavelength_nm": sppm.fixed_wavelength_nm,
        "light_sampling": format!("{:?}", sppm.light_sampling),
        "photon_sampling": format!("{:?}", sppm.photon_sampling),
        "method": format!("{:?}", sppm.method),
        "spectral_bins": settings.spectral_bins,
        "denoising_passes": settings.denoising_passes,
        "shutter": [shutter.open, shutter.length],
        "lens": lens,
    })
}

/// A render of one scene over its frames: the prepared time range and what every frame shares.
pub struct Shot {
    prepared: Prepared,
    fixed_bvh: Arc<Bvh>,
    /// The still instances' two-level BVH (built once), if any.
    instanced_bvh: Option<Arc<InstancedBvh>>,
    still: Option<(Scene, Accel)>,
    shutter: Shutter,
    sppm: SppmSettings,
    /// For partial results: the scene's SHA-256 and the settings that shape every pass.
    identity: Option<(String, serde_json::Value)>,
    /// The view the first radius was measured from.
    view: Option<ViewMeasure>,
}

impl Shot {
    /// Prepares `description` for the frames and settings of `settings`.
    pub fn new(settings: &RenderSettings, description: Arc<Description>) -> Result<Self, String> {
        let [full_width, full_height] = resolution(settings, &description);
        check_resolution([full_width, full_height])?;
        let crop = crop(settings.crop, [full_width, full_height])?;
        let [width, height] = crop.size;
        let shutter = shutter(settings, &description);
        let range = time_range(&settings.frames, shutter, description.fps);
        let photon_sampling = photon_sampling(settings, &description);
        let lens_settings = lens_settings(settings, &description);
        if let Some(l) = lens_settings.filter(|l| l.fstop > 0.0 && !(l.focus_distance > 0.0)) {
            return Err(format!(
                "depth of field (f-stop {}) needs a positive focus distance, got {} (set --focus-distance or the camera's)",
                l.fstop, l.focus_distance
            ));
        }
        let lens = lens(lens_settings, description.camera.focal_length_mm);
        let prepared = Prepared::with_lens(description, range, lens);
        let fixed_bvh = Arc::new(prepared.fixed_bvh());
        let instanced_bvh = prepared.instanced_bvh();
        let first = prepared.pose(range.start);
        let photons_per_pass = settings.photons.unwrap_or((full_width * full_height) as usize);
        let sppm = SppmSettings {
            width,
            height,
            crop,
            photons_per_pass,
            alpha: settings.alpha.unwrap_or(settings.method.default_alpha()),
            // Measured from the view below when not given.
            initial_radius: settings.radius.unwrap_or(0.0),
            seed: settings.seed,
            fixed_wavelength_nm: settings.wavelength_nm,
            light_sampling: settings.light_sampling,
            photon_sampling,
            method: settings.method,
        };
        if settings.method == Method::Vcm {
            if let Some(what) = vcm_unsupported(&first) {
                return Err(format!(
                    "--method vcm does not render {what} yet; render this scene with --method sppm"
                ));
            }
        }
        let still_accel =
            || Accel::new(Arc::clone(&fixed_bvh), Bvh::empty()).with_instances(instanced_bvh.clone());
        let still = (!prepared.has_motion()).then(|| (first, still_accel()));
        let mut shot =
            Shot { prepared, fixed_bvh, instanced_bvh, still, shutter, sppm, identity: None, view: None };
        shot.settle_from_view(lens, settings.radius.is_none());
        if settings.partial_passes.is_some() {
            let fingerprint = fingerprint(&shot.sppm, shutter, &shot.prepared, settings);
            shot.identity = Some((partial::scene_sha256(&settings.scene)?, fingerprint));
        }
        Ok(shot)
    }

    /// Settles what is measured on the scene's view: the first radius when `default_radius`
    /// (none was given), then whether `auto` photon sampling needs chains at all (where pass 0's
    /// pilot finds a quarter of its paths seen or more, every pass is uniform, and pays nothing
    /// for a pilot). An animated scene's view is measured at frame 1 (Blender's first), prepared
    /// for that instant alone: every frame range, a farm task's or a whole shot's, gets the same
    /// radius.
    fn settle_from_view(&mut self, lens: Option<Lens>, default_radius: bool) {
        let description = Arc::clone(&self.prepared.description);
        if default_radius {
            let measure = |scene: &Scene, accel: &Accel| {
                let view = Renderer::new(scene, accel, self.sppm.clone()).measure_view();
                (view, self::default_radius(scene, view, self.sppm.photons_per_pass))
            };
            let (view, radius) = match &self.still {
                Some((scene, accel)) if !is_animated(&description) => measure(scene, accel),
                _ => {
                    let time = seconds(1.0 + self.shutter.open, description.fps);
                    let instant =
                        Prepared::with_lens(description, TimeRange { start: time, end: time }, lens);
                    let accel = Accel::new(Arc::new(instant.fixed_bvh()), Bvh::empty())
                        .with_instances(instant.instanced_bvh());
                    measure(&instant.pose(time), &accel)
                }
            };
            (self.view, self.sppm.initial_radius) = (view, radius);
        }
        let mostly_seen = match (&self.still, self.sppm.photon_sampling) {
            (Some((scene, accel)), PhotonSampling::Auto) => {
                Renderer::new(scene, accel, self.sppm.clone()).auto_at_load().1
            }
            _ => false,
        };
        if mostly_seen {
            self.sppm.photon_sampling = PhotonSampling::Uniform;
        }
    }

    /// The view the first radius was measured from (`None` where the radius was given or the
    /// camera sees no surface).
    pub fn view(&self) -> Option<ViewMeasure> {
        self.view
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
        let moving = scene.moving.bvh(&scene.materials, BuildFor::Pose);
        let accel =
            Accel::new(Arc::clone(&self.fixed_bvh), moving).with_instances(self.instanced_bvh.clone());
        (scene, accel)
    }

    /// The fixed part's BVH alone (what paths shared between frames are traced against).
    fn fixed_accel(&self) -> Accel {
        Accel::new(Arc::clone(&self.fixed_bvh), Bvh::empty()).with_instances(self.instanced_bvh.clone())
    }

    /// The pose `frame` renders pass `pass` in (its `own` when it has one for all its passes);
    /// counts the poses made.
    fn posed<'a>(
        &'a self,
        frame: i32,
        own: &'a Option<(Scene, Accel)>,
        pass: u64,
        poses: &mut u64,
    ) -> Posed<'a> {
        match (&self.still, own) {
            (Some((scene, accel)), _) | (None, Some((scene, accel))) => Posed::Borrowed(scene, accel),
            (None, None) => {
                *poses += 1;
                let (scene, accel) = self.pose(self.pass_time(frame, pass));
                Posed::Owned(scene, accel)
            }
        }
    }

    /// The time of pass `index` of `frame`: one point of the shutter, the same for every frame.
    fn pass_time(&self, frame: i32, index: u64) -> f32 {
        let offset = self.shutter.open + pass_time_sample(self.sppm.seed, index) * self.shutter.length;
        seconds(frame as f32 + offset, self.prepared.description.fps)
    }
}

/// Renders every frame of `settings.frames` and writes `OUT/frame_####.exr` for each.
///
/// Frames are rendered pass-major in blocks (DESIGN.md, "Frames, and reuse across frames"): every
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
    if settings.method == Method::Vcm && settings.photon_sampling != PhotonSampling::Uniform {
        let chosen = clap::ValueEnum::to_possible_value(&settings.photon_sampling);
        eprintln!(
            "caustic: warning: --photon-sampling {} is not used by --method vcm, whose light paths are drawn uniformly",
            chosen.map_or_else(String::new, |v| v.get_name().to_string())
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
        span_settings.radius = Some(shot.sppm.initial_radius);
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

/// `frames` split, in order, into spans over which the same things move. A span's time is cut
/// into pieces: its first frame's shutter, then for each next frame the time from the frame
/// before's shutter closing to its own closing. A frame joins the span before it when its piece
/// changes what the span's pieces change (a shutter of no length changes nothing and agrees with
/// anything). So an object that moves only between frames 10 and 12 of 1 to 24 makes spans 1-10,
/// 11-12 and 13-24, and is static geometry in the first and the last.
pub fn motion_spans(description: &Description, frames: &[i32], shutter: Shutter) -> Vec<Vec<i32>> {
    let fps = description.fps;
    let close = |frame: i32| seconds(frame as f32 + shutter.open + shutter.length, fps);
    let mut spans: Vec<(Vec<i32>, Option<Motion>)> = Vec::new();
    for &frame in frames {
        if let Some((span, moving)) = spans.last_mut() {
            let (a, b) = (close(span[span.len() - 1]), close(frame));
            let piece = Motion::within(description, TimeRange { start: a.min(b), end: a.max(b) });
            if moving.as_ref().is_none_or(|m| *m == piece) {
                span.push(frame);
                *moving = Some(piece);
                continue;
            }
        }
        let own = (shutter.length > 0.0)
            .then(|| Motion::within(description, time_range(&[frame], shutter, description.fps)));
        spans.push((vec![frame], own));
    }
    spans.into_iter().map(|(span, _)| span).collect()
}

impl Shot {
    /// Whether a block of `frames` frames shares paths: reuse is on, there is more than one
    /// frame, there are static triangles to share, no medium scatters (paths that end in
    /// media, and the direct light along their segments, are not shared), and the passes are
    /// SPPM's (VCM's paths are not shared yet).
    fn shares(&self, settings: &RenderSettings, frames: usize) -> bool {
        settings.reuse
            && settings.method == Method::Sppm
            && frames > 1
            && self.prepared.triangle_counts().0 > 0
            && !self.prepared.description.scatters()
    }

    /// How many frames render together: as many as the memory budget holds beside what one
    /// pass needs, at least one; one when reuse is off.
    fn block_frames(&self, settings: &RenderSettings, frames: usize) -> usize {
        if !self.shares(settings, frames) {
            return 1;
        }
        let pixels = u64::from(self.sppm.width) * u64::from(self.sppm.height);
        let guides = if settings.denoising_passes { GUIDE_SUMS } else { 0 };
        let per_frame = pixels * (FRAME_BYTES_PER_PIXEL + 8 * (settings.spectral_bins + guides) as u64);
        let photons = self.sppm.photons_per_pass as u64 * PHOTON_BYTES_PER_PATH;
        let shared = pixels * (BYTES_PER_PIXEL + SHARED_BYTES_PER_PIXEL) + photons;
        let fit = settings.memory_budget.saturating_sub(shared) / per_frame.max(1);
        (fit as usize).clamp(1, frames)
    }
}

/// What a frame keeps while its block renders: its sums, its error monitor, its work counts.
const FRAME_BYTES_PER_PIXEL: u64 = 96;

/// What a block holds per pixel for its frames together: a shared eye path with its common
/// gather and every shared photon's sums (560 bytes), its common estimate (48), its visible
/// point bucketed (16) and the common film (64); generously.
const SHARED_BYTES_PER_PIXEL: u64 = 704;

/// What one pass holds per photon path (its photons and the segments frames check), generously.
const PHOTON_BYTES_PER_PATH: u64 = 256;

/// A frame while its block renders.
struct FrameInProgress {
    frame: i32,
    film: Film,
    monitor: Monitor,
    stats: PassStats,
    /// Its share of the block's wall-clock time.
    elapsed_s: f64,
}

/// A pose to render a pass in: the shot's still one, a frame's own, or one made for the pass.
enum Posed<'a> {
    Borrowed(&'a Scene, &'a Accel),
    Owned(Scene, Accel),
}

impl Posed<'_> {
    fn parts(&self) -> (&Scene, &Accel) {
        match self {
            Posed::Borrowed(scene, accel) => (scene, accel),
            Posed::Owned(scene, accel) => (scene, accel),
        }
    }
}

/// The passes a frame renders at most: a partial result's range, else `--passes`, else none
/// when a time budget or a target error ends it, else the default.
fn pass_limit(settings: &RenderSettings) -> Option<u64> {
    if let Some(passes) = &settings.partial_passes {
        return Some(passes.end - passes.start);
    }
    let open_ended = settings.time_budget_s.is_some() || settings.errors.target.is_some();
    settings.passes.or((!open_ended).then_some(DEFAULT_PASSES))
}

/// Renders `frames` pass-major until each is stopped, writing each as it stops.
fn render_block(
    shot: &Shot,
    settings: &RenderSettings,
    frames: &[i32],
    report: &mut RenderReport,
) -> Result<(), String> {
    let s = &shot.sppm;
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
                let (_, estimates, stats) = Renderer::new(scene, accel, s.clone()).run_pass(pass);
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
fn shared_pass(
    shot: &Shot,
    poses: &[Posed],
    samples: &PassSamples,
    active: &mut [FrameInProgress],
    common: &mut Option<Film>,
    accumulation: &mut Duration,
) -> (PassStats, Duration) {
    let s = &shot.sppm;
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
fn whole_film<'a>(film: &'a Film, common: &Option<Film>) -> Cow<'a, Film> {
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
fn add_pass(
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
fn sums(e: &PixelEstimate) -> Estimate {
    (e.radiance, e.laplacian, e.coverage)
}

/// Writes a frame's EXR with its error passes (the bound and the variance of the mean).
pub fn write_frame(film: &Film, errors: &[PixelError], path: &Path) -> Result<(), String> {
    let bound = errors.iter().map(|e| e.bound as f32).collect();
    let variance = errors.iter().map(|e| e.variance as f32).collect();
    film.write_exr(path, &[("Error.Y", bound), ("Variance.Y", variance)])
}

/// What stops `frame`, after `passes` passes, if anything: its target error (`target_met`, as
/// its monitor found), its time budget or the pass count.
fn stop_reason(
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
fn finish_frames(
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
fn announce(
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
fn write_output(
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

/// Adds up partial results into `OUT/frame_####.exr`, one per frame they hold, with the error
/// passes a whole run writes; gives each EXR with its merged film.
pub fn merge(paths: &[PathBuf], out_dir: &Path, confidence: f64) -> Result<Vec<(PathBuf, Film)>, String> {
    let mut by_frame: std::collections::BTreeMap<i32, Vec<partial::Partial>> = Default::default();
    for path in paths {
        let p = partial::read(path)?;
        by_frame.entry(p.header.frame).or_default().push(p);
    }
    std::fs::create_dir_all(out_dir)
        .map_err(|e| format!("cannot create output folder {}: {e}", out_dir.display()))?;
    let mut written = Vec::new();
    for (frame, partials) in by_frame {
        let film = partial::merge(partials)?;
        let path = frame_path(out_dir, frame);
        write_frame(&film, &crate::error::pixel_errors(&film, confidence), &path)?;
        written.push((path, film));
    }
    Ok(written)
}
