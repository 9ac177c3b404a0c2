//! The one place that drives the pipeline: load, build, run passes, accumulate, write.
//!
//! Takes the render settings; gives `OUT/frame_0001.exr` and a report of what was done. Passes
//! run until `--passes` or `--time-budget` is reached, whichever comes first.

use std::path::PathBuf;
use std::time::Instant;

use crate::accel::Accel;
use crate::film::{Film, FilmMode};
use crate::scene::Scene;
use crate::sppm::{PassStats, Renderer, SppmSettings};

/// Passes when neither a pass count nor a time budget is given.
pub const DEFAULT_PASSES: u64 = 64;

/// How progress is shown.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum ProgressStyle {
    /// A progress bar on the terminal (stderr).
    Bar,
    /// One JSON object per pass on stdout.
    Json,
    /// Nothing.
    None,
}

/// Everything `caustic render` was asked for.
#[derive(Clone, Debug)]
pub struct RenderSettings {
    /// The glTF scene.
    pub scene: PathBuf,
    /// Output folder.
    pub out_dir: PathBuf,
    /// Pass count, if given.
    pub passes: Option<u64>,
    /// Wall-clock budget in seconds, if given.
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
}

/// What a finished frame reports.
#[derive(Clone, Debug)]
pub struct FrameReport {
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
}

/// Image size: the flag, else the scene's extras, else 640 wide at the camera's aspect ratio.
pub fn resolution(settings: &RenderSettings, scene: &Scene) -> [u32; 2] {
    settings.resolution.or(scene.resolution).unwrap_or_else(|| {
        let aspect = scene.aspect_ratio.filter(|a| a.is_finite() && *a > 0.0).unwrap_or(16.0 / 9.0);
        [640, ((640.0 / aspect).round() as u32).max(1)]
    })
}

/// The first pass's radius when none is given: 1/100 of the scene's bounding diameter.
pub fn default_radius(scene: &Scene) -> f64 {
    f64::from(scene.bounding_sphere().radius) * 0.02
}

/// Loads the scene and prints its warnings to stderr.
pub fn load_scene(settings: &RenderSettings) -> Result<Scene, String> {
    let scene = Scene::load(&settings.scene).map_err(|e| e.to_string())?;
    for warning in &scene.warnings {
        eprintln!("caustic: warning: {}: {warning}", settings.scene.display());
    }
    Ok(scene)
}

/// The SPPM settings that `settings` asks for on `scene`.
pub fn sppm_settings(settings: &RenderSettings, scene: &Scene) -> SppmSettings {
    let [width, height] = resolution(settings, scene);
    SppmSettings {
        width,
        height,
        photons_per_pass: settings.photons.unwrap_or((width * height) as usize),
        alpha: settings.alpha,
        initial_radius: settings.radius.unwrap_or_else(|| default_radius(scene)),
        seed: settings.seed,
        fixed_wavelength_nm: settings.wavelength_nm,
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

/// Renders frame 1 of the scene and writes `OUT/frame_0001.exr`.
pub fn render(settings: &RenderSettings) -> Result<FrameReport, String> {
    let scene = load_scene(settings)?;
    check_resolution(resolution(settings, &scene))?;
    let accel = Accel::build(&scene.triangle_corners());
    let renderer = Renderer::new(&scene, &accel, sppm_settings(settings, &scene));
    std::fs::create_dir_all(&settings.out_dir)
        .map_err(|e| format!("cannot create output folder {}: {e}", settings.out_dir.display()))?;
    let (film, passes, elapsed_s, stats) = run_passes(&renderer, settings);
    if film.non_finite_estimates > 0 {
        eprintln!(
            "caustic: warning: {} pixel estimates were NaN or infinite and counted as zero (please report this scene)",
            film.non_finite_estimates
        );
    }
    let path = settings.out_dir.join(format!("frame_{:04}.exr", 1));
    film.write_exr(&path)?;
    Ok(FrameReport { path, film, passes, elapsed_s, stats })
}

/// Runs passes 0, 1, ... until the pass count or the time budget is reached.
pub fn run_passes(renderer: &Renderer, settings: &RenderSettings) -> (Film, u64, f64, PassStats) {
    let s = renderer.settings();
    let mode = match s.fixed_wavelength_nm {
        Some(lambda_nm) => FilmMode::Monochromatic { lambda_nm },
        None => FilmMode::Spectral,
    };
    let mut film = Film::new(s.width, s.height, mode, settings.spectral_bins);
    let limit =
        settings.passes.or(if settings.time_budget_s.is_some() { None } else { Some(DEFAULT_PASSES) });
    let progress = Progress::new(settings.progress, limit);
    let start = Instant::now();
    let mut stats = PassStats::default();
    let mut pass = 0;
    loop {
        let (samples, estimates, pass_stats) = renderer.run_pass(pass);
        film.add_pass(
            samples.lambda_nm,
            samples.lambda_pdf,
            estimates.iter().map(|e| (e.radiance, e.laplacian)),
        );
        stats = stats + pass_stats;
        pass += 1;
        let elapsed = start.elapsed().as_secs_f64();
        progress.update(pass, elapsed);
        let out_of_time = settings.time_budget_s.is_some_and(|budget| elapsed >= budget);
        if limit.is_some_and(|n| pass >= n) || out_of_time {
            progress.finish();
            return (film, pass, elapsed, stats);
        }
    }
}

/// Shows passes as they finish.
struct Progress {
    style: ProgressStyle,
    bar: Option<indicatif::ProgressBar>,
    limit: Option<u64>,
}

impl Progress {
    fn new(style: ProgressStyle, limit: Option<u64>) -> Self {
        let bar = (style == ProgressStyle::Bar).then(|| {
            let bar =
                indicatif::ProgressBar::with_draw_target(limit, indicatif::ProgressDrawTarget::stderr());
            // Without a pass count the time budget ends the frame: show passes and time only.
            let template = match limit {
                Some(_) => "frame 1 [{bar:40}] pass {pos}/{len} {elapsed_precise} eta {eta}",
                None => "frame 1 pass {pos} {elapsed_precise} (until the time budget)",
            };
            let style = indicatif::ProgressStyle::with_template(template).expect("valid template");
            bar.set_style(style.progress_chars("=> "));
            bar
        });
        Progress { style, bar, limit }
    }

    fn update(&self, pass: u64, elapsed_s: f64) {
        match self.style {
            ProgressStyle::Bar => self.bar.as_ref().expect("bar style has a bar").set_position(pass),
            ProgressStyle::Json => println!(
                "{}",
                serde_json::json!({"frame": 1, "pass": pass, "passes": self.limit, "elapsed_s": elapsed_s})
            ),
            ProgressStyle::None => {}
        }
    }

    fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
}
