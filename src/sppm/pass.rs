//! One whole pass for one frame (DESIGN.md steps 1 to 4): its samples, the eye pass, the photon
//! pass and the gather.

use std::time::Instant;

use super::gather::{gather, PhotonSet};
use super::photon_sampling::visible_points;
use super::renderer::{collect_counting, PassSamples, PassStats, PixelEstimate, Renderer};
use super::visible::{trace_eye_path, EyeResult};
use super::volume_gather::{gather_with_media, in_media};

impl Renderer<'_> {
    /// Renders pass `index`: one estimate per pixel, in row-major order.
    pub fn run_pass(&self, index: u64) -> (PassSamples, Vec<PixelEstimate>, PassStats) {
        let pass = self.pass_samples(index);
        let mut clock = Instant::now();
        let mut lap = || {
            let ns = clock.elapsed().as_nanos() as u64;
            clock = Instant::now();
            ns
        };
        let (points, eye_stats) = self.trace_visible_points(&pass);
        let eye_ns = lap();
        let (photons, photon_stats) = match self.whole_image_points(&pass) {
            Some(whole) => self.trace_photons(&pass, visible_points(&whole)),
            None => self.trace_photons(&pass, visible_points(&points)),
        };
        let photon_ns = lap();
        let (photons, media) = match self.has_scattering {
            true => in_media(photons, &pass),
            false => (photons, None),
        };
        let set = PhotonSet::new(&photons, pass.radius, &self.scene.open_edges);
        let grid_ns = lap();
        let estimates = match &media {
            None => gather(&points, &set),
            Some(media) => gather_with_media(&points, &set, media),
        };
        let stages = PassStats { stage_ns: [eye_ns, photon_ns, grid_ns, lap()], ..PassStats::default() };
        (pass, estimates, eye_stats + photon_stats + stages)
    }

    pub(super) fn trace_visible_points(&self, pass: &PassSamples) -> (Vec<EyeResult>, PassStats) {
        let pixels = (self.settings.width * self.settings.height) as usize;
        collect_counting(pixels, |pixel| trace_eye_path(self, pass, pixel))
    }
}
