//! The first radius when none is given, from the view rather than the scene's size (which is
//! wrong for a wide exterior seen through a narrow window, or a ring seen close up in a large
//! hall): Hachisuka's SPPM notes ask for it from the visible points' pixel footprints.
//!
//! A pass's error at a pixel is its bias, which grows as `r^2` times how fast the light changes
//! across the view, plus its variance, which falls as `1 / (photons within r)`. Taking the light
//! to change over the view's size `S` (where the camera sees surfaces) and the photons a pass
//! lands per area there as `rho`, the sum is least at `r ~ S^(2/3) rho^(-1/6)`, that is
//! `r = c S (rho S^2)^(-1/6)`: a fraction of the view, smaller the more photons a pass lands in
//! it (a close-up and a wide shot of one scene each get theirs; a scene whose lights spend most
//! photons where the camera does not look gets a larger one). `c` is set so that the demo box
//! keeps the radius its benchmark against Cycles chose (2% of its diameter); the sweep in
//! `tests/bench/radius_sweep.py` measures the rule against the best radius.
//!
//! Both are measured on pass 0 of a probe of the whole image (so a render region, a farm task
//! and a whole render get the same radius): the view's size is the median over the visible
//! points of the film's size there ([`crate::camera::Camera::film_size_at`]); the density is the
//! count of photons of pass 0's first uniform paths within `PROBE_RADIUS` of those points.

use super::context::{Crop, PassSettings, PhotonSampling, Renderer};
use super::points::PointGrid;
use super::sppm::photon_sampling::{trace_pilot, AUTO_VISIBLE_BELOW};

/// Pixels of the probe film (the image's aspect ratio, at most the image's pixels).
const PROBE_PIXELS: f64 = 16_384.0;

/// Photon paths the density is measured with, at most (at most a pass's).
const PROBE_PATHS: usize = 65_536;

/// The radius, as a fraction of the view's size, within which photons are counted.
const PROBE_RADIUS: f64 = 0.05;

/// The first radius as a fraction of the view's size at [`DEMO_PHOTONS_PER_VIEW`]: the demo box's
/// 2% of its diameter.
const VIEW_FRACTION: f64 = 0.0155;

/// Photons a pass lands per view-sized area (`rho S^2`) in the demo box at its default photons.
const DEMO_PHOTONS_PER_VIEW: f64 = 74_000.0;

/// How far a dense view's radius may fall below `VIEW_FRACTION` of it.
const DENSE_LIMIT: f64 = 4.0;

/// Photons the first pass is expected to land within the radius of a visible point, at least.
const FIRST_PASS_PHOTONS: f64 = 1.0;

/// The largest first radius, as a fraction of the view's size.
const MAX_VIEW_FRACTION: f64 = 0.2;

/// How many uniform photons a visible one counts for, at most, in the density (1/seen is 5,500
/// and 600 on the sunlit room's close-up and wide shot): with 16, the default radius is the best
/// of the sweep on both shots at 10 and 60 CPU s (`tests/bench/radius_sweep.py --caustic-flags
/// "--photon-sampling visible"`); with 8 the close-up's was 1.4x too wide.
const VISIBLE_GAIN: f64 = 16.0;

/// What the first radius is chosen from.
#[derive(Clone, Copy, Debug)]
pub struct ViewMeasure {
    /// The view's size where the camera sees surfaces, scene units.
    pub size: f64,
    /// Photons a pass lands per view-sized area there, by the render's photon sampling.
    pub photons_per_view: f64,
}

impl ViewMeasure {
    /// The first radius this view gets: the least error's (see the module's notes), but wide
    /// enough that the first pass is expected to land `FIRST_PASS_PHOTONS` within it (where
    /// the lights spend nearly every photon out of view, the light there is smooth: the
    /// demo's bias, which the rule is set by, overstates it), and at most `MAX_VIEW_FRACTION`
    /// of the view.
    pub fn radius(&self) -> f64 {
        let scale = (self.photons_per_view / DEMO_PHOTONS_PER_VIEW).powf(-1.0 / 6.0).max(1.0 / DENSE_LIMIT);
        let least_error = self.size * VIEW_FRACTION * scale;
        let enough_photons =
            self.size * (FIRST_PASS_PHOTONS / (std::f64::consts::PI * self.photons_per_view)).sqrt();
        least_error.max(enough_photons).min(self.size * MAX_VIEW_FRACTION)
    }
}

impl Renderer<'_> {
    /// The view's size and photon density, measured on pass 0; `None` where the camera sees no
    /// surface photons are gathered at. Depends only on the scene, the image's size, the photons
    /// per pass, the photon sampling and the seed.
    pub fn measure_view(&self) -> Option<ViewMeasure> {
        let [width, height] = self.settings.crop.image;
        let scale = (PROBE_PIXELS / (f64::from(width) * f64::from(height))).sqrt().min(1.0);
        let probe = [width, height].map(|n| ((f64::from(n) * scale).round() as u32).max(1));
        let settings = PassSettings {
            crop: Crop::whole(probe),
            width: probe[0],
            height: probe[1],
            ..self.settings.clone()
        };
        let renderer = self.with_settings(settings);
        let pass = renderer.settings.pass_samples(0);
        let (eyes, _) = renderer.trace_visible_points(&pass);
        let aspect = width as f32 / height as f32;
        let camera = &self.scene.camera;
        let points: Vec<(usize, glam::Vec3, f32)> = eyes
            .iter()
            .enumerate()
            .filter_map(|(pixel, eye)| {
                let p = eye.point?.p;
                camera.film_size_at(p, aspect).filter(|s| s.is_finite()).map(|size| (pixel, p, size))
            })
            .collect();
        if points.is_empty() {
            return None;
        }
        let mut sizes: Vec<f32> = points.iter().map(|&(_, _, size)| size).collect();
        let middle = sizes.len() / 2;
        let size = f64::from(*sizes.select_nth_unstable_by(middle, f32::total_cmp).1);
        let radius = (size * PROBE_RADIUS) as f32;
        let near = PointGrid::new(points.iter().map(|&(pixel, p, _)| (pixel, p)), radius);
        let paths = self.settings.photons_per_pass.clamp(1, PROBE_PATHS);
        let pilot = trace_pilot(self, &pass, 0..paths, &near);
        let pairs: usize = pilot.photons.iter().map(|photon| near.count_near(photon.p)).sum();
        let disc = std::f64::consts::PI * f64::from(radius) * f64::from(radius);
        let per_area = pairs as f64 / (points.len() as f64 * disc)
            * (self.settings.photons_per_pass as f64 / paths as f64);
        let seen = pilot.seen_fraction();
        let concentrated = match self.settings.photon_sampling {
            PhotonSampling::Uniform => false,
            PhotonSampling::Visible => true,
            PhotonSampling::Auto => seen < AUTO_VISIBLE_BELOW,
        };
        // Visible photons draw only seen paths, 1 / seen times as many a pass as uniform ones;
        // but a chain's small steps move its path a little, so its photons are correlated and
        // count for less (see VISIBLE_GAIN).
        let gain = if concentrated && seen > 0.0 { (1.0 / seen).min(VISIBLE_GAIN) } else { 1.0 };
        Some(ViewMeasure { size, photons_per_view: per_area * gain * size * size })
    }
}
