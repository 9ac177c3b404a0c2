//! What a render is asked for, and what follows from it before a pass runs: the settings and
//! their defaults, the image size and crop, the shutter and lens, the first radius, photon
//! sampling, the output paths, and the fingerprint partial results carry.

use std::ops::Range;
use std::path::{Path, PathBuf};

use super::partial;
use super::{DEFAULT_FOCUS_DISTANCE, DEFAULT_MEMORY_BUDGET};
use crate::monitor::ErrorSettings;
use crate::scene::description::{LensSettings, Shutter};
use crate::scene::pose::Motion;
use crate::scene::{Description, Prepared, Scene, TimeRange, DEFAULT_RADIUS_FRACTION};

use crate::progress::ProgressStyle;
use crate::transport::{Crop, LightSampling, Method, PassSettings, PhotonSampling, ViewMeasure};

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

/// Image size: the flag, else the scene's extras, else 640 wide at the camera's aspect ratio.
pub fn resolution(settings: &RenderSettings, description: &Description) -> [u32; 2] {
    settings.resolution.or(description.resolution).unwrap_or_else(|| {
        let aspect =
            description.camera.aspect_ratio.filter(|a| a.is_finite() && *a > 0.0).unwrap_or(16.0 / 9.0);
        [640, ((640.0 / aspect).round() as u32).max(1)]
    })
}

/// Photons per pass at which the scene-based first radius is 2% of the scene's diameter.
pub(super) const DEFAULT_RADIUS_PHOTONS: f64 = 49_152.0;

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
pub(super) fn photon_sampling(settings: &RenderSettings, description: &Description) -> PhotonSampling {
    if !settings.method.capabilities().samples_photons_by_visibility {
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
pub(super) fn seconds(frame: f32, fps: f32) -> f32 {
    frame / fps
}

/// The time span every frame's shutter covers.
pub(super) fn time_range(frames: &[i32], shutter: Shutter, fps: f32) -> TimeRange {
    let first = *frames.iter().min().unwrap_or(&0) as f32;
    let last = *frames.iter().max().unwrap_or(&0) as f32;
    TimeRange {
        start: seconds(first + shutter.open, fps),
        end: seconds(last + shutter.open + shutter.length, fps),
    }
}

/// Memory a pixel needs while rendering (sums, eye result, estimate), in bytes, generously.
pub(super) const BYTES_PER_PIXEL: u64 = 256;

/// The largest image memory Caustic will try to allocate, in bytes.
pub(super) const MAX_IMAGE_BYTES: u64 = 16 << 30;

/// The window of the image a render covers: `--crop`, which must lie inside the image, or the whole.
pub(super) fn crop(window: Option<[u32; 4]>, image: [u32; 2]) -> Result<Crop, String> {
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
pub(super) fn check_resolution([width, height]: [u32; 2]) -> Result<(), String> {
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
pub(super) fn output_path(settings: &RenderSettings, frame: i32) -> PathBuf {
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
pub(super) fn fingerprint(
    pass_settings: &PassSettings,
    shutter: Shutter,
    prepared: &Prepared,
    settings: &RenderSettings,
) -> serde_json::Value {
    let lens =
        prepared.lens().map(|l| [l.aperture_radius, l.focus_distance, l.blades as f32, l.blade_rotation]);
    serde_json::json!({
        "resolution": [pass_settings.width, pass_settings.height],
        "crop": [pass_settings.crop.image, pass_settings.crop.origin],
        "photons_per_pass": pass_settings.photons_per_pass,
        "alpha": pass_settings.alpha,
        "initial_radius": pass_settings.initial_radius,
        "seed": pass_settings.seed,
        "wavelength_nm": pass_settings.fixed_wavelength_nm,
        "light_sampling": format!("{:?}", pass_settings.light_sampling),
        "photon_sampling": format!("{:?}", pass_settings.photon_sampling),
        "method": format!("{:?}", pass_settings.method),
        "spectral_bins": settings.spectral_bins,
        "denoising_passes": settings.denoising_passes,
        "shutter": [shutter.open, shutter.length],
        "lens": lens,
    })
}
