//! One whole pass for one frame (DESIGN.md steps 1 to 4): its samples, the eye pass, the photon
//! pass and the gather.

use rayon::prelude::*;

use std::time::Instant;

use super::gather::{gather, PhotonSet};
use super::photons::{photon_chunks, trace_photon, Photon};
use super::renderer::{collect_counting, PassSamples, PassStats, PixelEstimate, Renderer};
use super::visible::{trace_eye_path, EyeResult};

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
        let (photons, photon_stats) = self.trace_photons(&pass);
        let photon_ns = lap();
        let set = PhotonSet::new(&photons, pass.radius, &self.scene.open_edges);
        let grid_ns = lap();
        let estimates = gather(&points, &set);
        let stages = PassStats { stage_ns: [eye_ns, photon_ns, grid_ns, lap()], ..PassStats::default() };
        (pass, estimates, eye_stats + photon_stats + stages)
    }

    fn trace_visible_points(&self, pass: &PassSamples) -> (Vec<EyeResult>, PassStats) {
        let pixels = (self.settings.width * self.settings.height) as usize;
        collect_counting(pixels, |pixel| trace_eye_path(self, pass, pixel))
    }

    fn trace_photons(&self, pass: &PassSamples) -> (Vec<Photon>, PassStats) {
        let chunks: Vec<(Vec<Photon>, PassStats)> = photon_chunks(self.settings.photons_per_pass)
            .map(|paths| {
                let mut photons = Vec::with_capacity(paths.end as usize - paths.start as usize);
                let stats = paths.map(|k| trace_photon(self, pass, k, &mut photons)).sum();
                (photons, stats)
            })
            .collect();
        let stats = chunks.iter().map(|(_, s)| *s).sum();
        let mut photons = Vec::with_capacity(chunks.iter().map(|(p, _)| p.len()).sum());
        chunks.into_iter().for_each(|(p, _)| photons.extend(p));
        (photons, stats)
    }
}
