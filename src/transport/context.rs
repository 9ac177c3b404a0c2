//! What every stage of a pass reads: the settings, the pass's shared samples, the renderer (the
//! scene, its BVHs and how lights are chosen), and what a pass produces and counts.

use glam::Vec3;
use std::sync::{Arc, Mutex, PoisonError};

use crate::accel::Accel;
use crate::geometry::ray_meets_box;
use crate::lights::LightTree;
use crate::materials::{Bsdf, ShadingFrame};
use crate::sampling::{pass_sample, Distribution1D};
use crate::scene::{media_scatter, Scene};
use crate::spectrum::{SampledSpectrum, Wavelengths};

use super::media::{media_at, Media};
use super::method::Method;
use super::radius;

/// Longest path (bounces) an eye path follows through delta surfaces, and a photon overall.
pub const MAX_DEPTH: u32 = 32;

/// Where a pixel's camera path met its first non-delta surface.
#[derive(Clone, Copy, Debug)]
pub struct VisiblePoint {
    /// Position.
    pub p: Vec3,
    /// Normals there.
    pub frame: ShadingFrame,
    /// Unit direction back along the path.
    pub wo: Vec3,
    /// The BSDF at the pass's wavelengths.
    pub bsdf: Bsdf,
    /// Path throughput from the camera to here.
    pub beta: SampledSpectrum,
    /// The largest coordinate of its triangle (for offsetting rays that leave it), negative when
    /// the path carries its hero wavelength alone: one field for both keeps the point at 144 bytes.
    scale_and_hero_only: f32,
}

impl VisiblePoint {
    /// A visible point at `p` on a triangle whose largest coordinate is `scale`, reached with
    /// throughput `beta`, carrying its hero wavelength alone if `hero_only`.
    pub fn new(
        p: Vec3,
        frame: ShadingFrame,
        wo: Vec3,
        bsdf: Bsdf,
        beta: SampledSpectrum,
        hero_only: bool,
        scale: f32,
    ) -> Self {
        let scale_and_hero_only = if hero_only { -scale.abs() } else { scale.abs() };
        VisiblePoint { p, frame, wo, bsdf, beta, scale_and_hero_only }
    }

    /// The largest coordinate of its triangle (for offsetting rays that leave it).
    pub fn scale(&self) -> f32 {
        self.scale_and_hero_only.abs()
    }

    /// Whether the path carries its hero wavelength alone ([`crate::spectrum::hero_only`]).
    pub fn hero_only(&self) -> bool {
        self.scale_and_hero_only.is_sign_negative()
    }
}

// Visible points are made, moved and collected once per pixel and pass, so their size is watched:
// at 144 bytes (the shading frame 16-byte aligned) a pixel's result moves by `memcpy`, which
// costs the caustic box 2% of its time; the aligned frame saves more than that (see
// `ShadingFrame`).
const _: () = assert!(std::mem::size_of::<VisiblePoint>() <= 144);

/// The window of the image a film covers (all of it, or Blender's render region): pixel
/// `(x, y)` of the film is pixel `origin + (x, y)` of the image, with that pixel's samples.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Crop {
    /// The whole image's size.
    pub image: [u32; 2],
    /// The film's top-left pixel in the image.
    pub origin: [u32; 2],
    /// The film's size.
    pub size: [u32; 2],
}

impl Crop {
    /// All of an image of `size`.
    pub fn whole(size: [u32; 2]) -> Self {
        Crop { image: size, origin: [0, 0], size }
    }

    /// The image pixel (x, y) of film pixel `pixel` (row-major), and its index in the image.
    pub fn image_pixel(&self, pixel: usize) -> ([u32; 2], u64) {
        let width = self.size[0] as usize;
        let (x, y) = ((pixel % width) as u32 + self.origin[0], (pixel / width) as u32 + self.origin[1]);
        ([x, y], u64::from(y) * u64::from(self.image[0]) + u64::from(x))
    }
}

/// Settings of the SPPM passes.
#[derive(Clone, Debug)]
pub struct PassSettings {
    /// The window of the image the film covers.
    pub crop: Crop,
    /// Film width in pixels (the crop's).
    pub width: u32,
    /// Film height in pixels (the crop's).
    pub height: u32,
    /// Photon paths traced per pass.
    pub photons_per_pass: usize,
    /// Knaus & Zwicker's alpha in (0, 1).
    pub alpha: f64,
    /// The first pass's gather radius, in scene units.
    pub initial_radius: f64,
    /// The random seed.
    pub seed: u64,
    /// Render every pass at this wavelength instead of sampling them per pass.
    pub fixed_wavelength_nm: Option<f32>,
    /// How next-event estimation chooses a light.
    pub light_sampling: LightSampling,
    /// How photon paths draw their primary samples.
    pub photon_sampling: PhotonSampling,
    /// How a pass combines camera and light paths.
    pub method: Method,
}

/// How next-event estimation chooses a light (photons always leave lights in proportion to their
/// power).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum LightSampling {
    /// In proportion to its power alone.
    Power,
    /// By the light tree: power, distance and orientation as seen from the point.
    #[default]
    Tree,
}

/// How a pass's photon paths draw their primary samples (`photon_sampling.rs`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum PhotonSampling {
    /// Each path from a stream of its own.
    #[default]
    Uniform,
    /// Markov chains over the paths that some visible point sees.
    Visible,
    /// Per pass: visible where fewer than `AUTO_VISIBLE_BELOW` of the pilot's paths are seen,
    /// else uniform.
    Auto,
}

impl PassSettings {
    /// The wavelengths and radius of pass `index` (0-based).
    pub fn pass_samples(&self, index: u64) -> PassSamples {
        let wavelengths = match self.fixed_wavelength_nm {
            Some(lambda_nm) => Wavelengths::single(lambda_nm, 1.0),
            None => Wavelengths::sampled(pass_sample(self.seed, index)),
        };
        let r1_squared = self.initial_radius * self.initial_radius;
        let radius = radius::radius_squared(r1_squared, self.alpha, index + 1).sqrt() as f32;
        PassSamples { index, wavelengths, radius }
    }
}

/// What pass `i` shares between all its pixels and photons (docs/design.md, step 1).
#[derive(Clone, Copy, Debug)]
pub struct PassSamples {
    /// The pass index, from 0.
    pub index: u64,
    /// The wavelengths every path carries.
    pub wavelengths: Wavelengths,
    /// The gather radius, on surfaces and across beams in media.
    pub radius: f32,
}

/// One pixel's estimate for one pass, at the pass's wavelengths.
#[derive(Clone, Copy, Debug, Default)]
pub struct PixelEstimate {
    /// Spectral radiance.
    pub radiance: SampledSpectrum,
    /// The same estimate with the kernel's Laplacian in place of the kernel (for the bias term).
    pub laplacian: SampledSpectrum,
    /// The eye path's coverage of the film (alpha), 0 or 1.
    pub coverage: f32,
}

/// Counts of the work a pass did, for the benchmark.
#[derive(Clone, Copy, Debug, Default)]
pub struct PassStats {
    /// Rays from the camera, delta bounces included.
    pub eye_rays: u64,
    /// Shadow rays of next-event estimation.
    pub shadow_rays: u64,
    /// Rays along photon paths.
    pub photon_rays: u64,
    /// Photons stored for gathering.
    pub photons_stored: u64,
    /// Points drawn on the camera's aperture (zero for a pinhole).
    pub lens_samples: u64,
    /// Uniform photon paths traced as a pass's pilot.
    pub pilot_paths: u64,
    /// Pilot paths that a visible point sees.
    pub pilot_paths_seen: u64,
    /// Steps of photon Markov chains.
    pub chain_steps: u64,
    /// Chain steps whose proposed path a visible point sees.
    pub chain_steps_seen: u64,
    /// Segments of shared paths tested against a frame's moving triangles (reuse across frames).
    pub moving_tests: u64,
    /// Rays of a path traced once for a block of frames that meet the box the frames' moving
    /// triangles fill (VCM's reuse across frames: each frame traces that path again).
    pub watched_rays: u64,
    /// Wall-clock nanoseconds of a single-frame pass's stages: eye paths, photon paths, the
    /// photon grid's build, and the gather (zero for passes shared by frames).
    pub stage_ns: [u64; 4],
}

impl std::iter::Sum for PassStats {
    fn sum<I: Iterator<Item = PassStats>>(iter: I) -> PassStats {
        iter.fold(PassStats::default(), |a, b| a + b)
    }
}

impl std::ops::Add for PassStats {
    type Output = PassStats;
    fn add(self, o: PassStats) -> PassStats {
        PassStats {
            eye_rays: self.eye_rays + o.eye_rays,
            shadow_rays: self.shadow_rays + o.shadow_rays,
            photon_rays: self.photon_rays + o.photon_rays,
            photons_stored: self.photons_stored + o.photons_stored,
            lens_samples: self.lens_samples + o.lens_samples,
            pilot_paths: self.pilot_paths + o.pilot_paths,
            pilot_paths_seen: self.pilot_paths_seen + o.pilot_paths_seen,
            chain_steps: self.chain_steps + o.chain_steps,
            chain_steps_seen: self.chain_steps_seen + o.chain_steps_seen,
            moving_tests: self.moving_tests + o.moving_tests,
            watched_rays: self.watched_rays + o.watched_rays,
            stage_ns: std::array::from_fn(|i| self.stage_ns[i] + o.stage_ns[i]),
        }
    }
}

/// Pixels (or other items) one parallel task computes together.
const TASK_ITEMS: usize = 64;

/// `f(i)` for every `i` in `0..count`, computed in parallel tasks that each sum the counts `f`
/// returns: only the results are stored per item. The results are written in place, in
/// parallel, into a list allocated once (not filled first); counts are whole numbers, so their
/// sum is the same whichever task adds first.
pub fn collect_counting<T: Send>(
    count: usize,
    f: impl Fn(usize) -> (T, PassStats) + Sync,
) -> (Vec<T>, PassStats) {
    use rayon::prelude::*;
    let total = Mutex::new(PassStats::default());
    let results = (0..count)
        .into_par_iter()
        .with_min_len(TASK_ITEMS)
        .map_init(
            || Tally { total: &total, sum: PassStats::default() },
            |tally, i| {
                let (value, stats) = f(i);
                tally.sum = tally.sum + stats;
                value
            },
        )
        .collect();
    (results, total.into_inner().unwrap_or_else(PoisonError::into_inner))
}

/// One task's counts, added to the pass's total when the task ends.
struct Tally<'a> {
    total: &'a Mutex<PassStats>,
    sum: PassStats,
}

impl Drop for Tally<'_> {
    fn drop(&mut self) {
        if let Ok(mut total) = self.total.lock() {
            *total = *total + self.sum;
        }
    }
}

/// Everything a pass reads: the scene, its BVH, how lights are chosen, and the settings.
pub struct Renderer<'a> {
    pub(super) scene: &'a Scene,
    pub(super) accel: &'a Accel,
    pub(super) light_choice: Arc<Distribution1D>,
    /// The scene's light tree, where next-event estimation uses it.
    light_tree: Option<&'a LightTree>,
    pub(super) settings: PassSettings,
    /// Some material's alpha cuts its surface away somewhere: shadow rays look through.
    pub(super) has_cut_away_surfaces: bool,
    /// Some material absorbs inside, or the world has fog: paths keep the stack of the insides
    /// they are in.
    pub(super) has_volumes: bool,
    /// Some medium scatters: paths meet events in media, and photons are stored there.
    pub(super) has_scattering: bool,
    /// The insides the camera and each light are in (none where nothing absorbs).
    start_media: StartMedia,
    /// The box that moving triangles fill in some frame, where this renderer traces paths that a
    /// block of frames shares: rays that meet it are counted in [`PassStats::watched_rays`].
    watched: Option<(Vec3, Vec3)>,
    /// Whether the rays that meet the watched box are also logged ([`Renderer::take_watched`]).
    logs_watched: bool,
}

/// A ray: origin, unit direction, and how far it runs.
pub type Ray = (Vec3, Vec3, f32);

thread_local! {
    /// The watched rays a renderer that logs them traced on this thread, since they were last
    /// taken.
    static WATCHED: std::cell::RefCell<Vec<Ray>> = const { std::cell::RefCell::new(Vec::new()) };
}

/// The insides paths start in.
#[derive(Default, PartialEq)]
struct StartMedia {
    /// The camera's (at its lens centre).
    camera: Media,
    /// Each light's (at its centre), by index; empty when every light is outside them all.
    lights: Vec<Media>,
}

impl StartMedia {
    /// The insides `renderer`'s camera and lights are in.
    fn of(renderer: &Renderer) -> Self {
        if !renderer.has_volumes {
            return StartMedia::default();
        }
        let at = |p: Option<Vec3>| p.map_or(Media::NONE, |p| media_at(renderer.scene, renderer.accel, p));
        let lights: Vec<Media> = renderer.scene.lights.iter().map(|l| at(l.centre())).collect();
        let inside = lights.iter().any(|&m| m != Media::NONE);
        StartMedia {
            camera: at(Some(renderer.scene.camera.position)),
            lights: if inside { lights } else { Vec::new() },
        }
    }
}

impl<'a> Renderer<'a> {
    /// Renders `pass` by the settings' method: one estimate per pixel, in row-major order.
    pub fn run_pass(&self, pass: &PassSamples) -> (Vec<PixelEstimate>, PassStats) {
        match self.settings.method {
            Method::Sppm => self.run_sppm_pass(pass),
            Method::Vcm => self.run_vcm_pass(pass),
        }
    }

    /// A renderer for `scene`; lights are chosen in proportion to their power.
    pub fn new(scene: &'a Scene, accel: &'a Accel, settings: PassSettings) -> Self {
        Renderer::with_light_choice(scene, accel, Arc::clone(&scene.light_choice), settings)
    }

    fn with_light_choice(
        scene: &'a Scene,
        accel: &'a Accel,
        light_choice: Arc<Distribution1D>,
        settings: PassSettings,
    ) -> Self {
        let mut renderer = Renderer {
            scene,
            accel,
            light_choice,
            light_tree: (settings.light_sampling == LightSampling::Tree).then_some(&*scene.light_tree),
            settings,
            has_cut_away_surfaces: scene.materials.iter().any(|m| m.alpha.cuts()),
            has_volumes: scene.materials.iter().any(|m| m.volume.is_some()) || scene.fog.is_some(),
            has_scattering: media_scatter(&scene.materials, &scene.fog),
            start_media: StartMedia::default(),
            watched: None,
            logs_watched: false,
        };
        renderer.start_media = StartMedia::of(&renderer);
        renderer
    }

    /// A renderer for `scene` that chooses lights as `other` does (frames that share photon
    /// paths must choose their lights alike).
    pub fn choosing_lights_as(other: &Renderer, scene: &'a Scene, accel: &'a Accel) -> Self {
        Renderer::with_light_choice(scene, accel, Arc::clone(&other.light_choice), other.settings.clone())
    }

    /// This renderer with `settings` instead.
    pub(super) fn with_settings(&self, settings: PassSettings) -> Renderer<'a> {
        Renderer::with_light_choice(self.scene, self.accel, Arc::clone(&self.light_choice), settings)
    }

    /// This renderer, counting the rays that meet `swept` (the box moving triangles fill).
    pub(super) fn watching(self, swept: Option<(Vec3, Vec3)>) -> Self {
        Renderer { watched: swept, ..self }
    }

    /// This renderer, logging the rays that meet the watched box on the thread that traces them.
    pub(super) fn logging_watched(self) -> Self {
        Renderer { logs_watched: true, ..self }
    }

    /// Counts the ray from `origin` along `direction` up to `t_max` in `stats` where it meets
    /// the watched box, and logs it where this renderer logs them.
    pub(super) fn watch(&self, origin: Vec3, direction: Vec3, t_max: f32, stats: &mut PassStats) {
        if self.watched.is_some_and(|b| ray_meets_box(origin, direction, t_max, b)) {
            stats.watched_rays += 1;
            if self.logs_watched {
                WATCHED.with(|log| log.borrow_mut().push((origin, direction, t_max)));
            }
        }
    }

    /// The watched rays logged on this thread since they were last taken.
    pub(super) fn take_watched() -> Vec<Ray> {
        WATCHED.with(|log| std::mem::take(&mut *log.borrow_mut()))
    }

    /// Whether the camera and every light start in the same volumes as `other`'s.
    pub(super) fn starts_in_same_media(&self, other: &Renderer) -> bool {
        self.start_media == other.start_media
    }

    /// A light for next-event estimation at `p`, of shading normal `n`, with the probability of
    /// choosing it; `None` when no light reaches `p`.
    pub(super) fn choose_light(&self, p: Vec3, n: Vec3, u: f32) -> Option<(usize, f32)> {
        match self.light_tree {
            Some(tree) => tree.sample(p, n, u),
            None => self.light_choice.sample(u),
        }
    }

    /// The probability that [`Renderer::choose_light`] at `p` (normal `n`) chooses light `index`.
    pub(super) fn light_probability(&self, p: Vec3, n: Vec3, index: usize) -> f32 {
        match self.light_tree {
            Some(tree) => tree.probability(p, n, index),
            None => self.light_choice.probability(index),
        }
    }

    /// The volumes the camera is in.
    pub(super) fn camera_media(&self) -> Media {
        self.start_media.camera
    }

    /// The volumes light `index` is in.
    pub(super) fn light_media(&self, index: usize) -> Media {
        self.start_media.lights.get(index).copied().unwrap_or(Media::NONE)
    }

    /// The settings.
    pub fn settings(&self) -> &PassSettings {
        &self.settings
    }

    /// The wavelength and radius of pass `index` (0-based).
    pub fn pass_samples(&self, index: u64) -> PassSamples {
        self.settings.pass_samples(index)
    }
}
