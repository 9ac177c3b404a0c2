//! One whole pass for one frame (docs/design.md, steps 1 to 4): its samples, the eye pass, the photon
//! pass and the gather.

use rayon::prelude::*;
use std::time::Instant;

use super::beams::{add_beams, in_media, Beam};
use super::gather::{gather, PhotonSet};
use super::photon_sampling::visible_points;
use super::visible::{continue_eye_path, trace_eye_path, EyeEvent, EyeResult};
use crate::transport::context::{collect_counting, PassSamples, PassStats, PixelEstimate, Renderer};
use crate::transport::eye::start_eye_path;

/// Pixels an eye pass with beams traces as one task.
const BEAM_CHUNK: usize = 256;

impl<'a> Renderer<'a> {
    /// Renders `pass` by SPPM: one estimate per pixel, in row-major order.
    pub(crate) fn run_sppm_pass(&self, pass: &PassSamples) -> (Vec<PixelEstimate>, PassStats) {
        let mut clock = Instant::now();
        let mut lap = || {
            let ns = clock.elapsed().as_nanos() as u64;
            clock = Instant::now();
            ns
        };
        let (points, beams, eye_stats) = match self.has_scattering {
            true => self.trace_visible_points_and_beams(pass),
            false => {
                let (points, stats) = self.trace_visible_points(pass);
                (points, Vec::new(), stats)
            }
        };
        let eye_ns = lap();
        let (photons, photon_stats) = match self.whole_image_points(pass) {
            Some(whole) => self.trace_photons(pass, visible_points(&whole)),
            None => self.trace_photons(pass, visible_points(&points)),
        };
        let photon_ns = lap();
        let (photons, media) = match self.has_scattering {
            true => {
                let (surfaces, media) = in_media(photons, pass.radius);
                (surfaces, Some(media))
            }
            false => (photons, None),
        };
        let set = PhotonSet::new(&photons, pass.radius, &self.scene.open_edges);
        let grid_ns = lap();
        let mut estimates = gather(&points, &set);
        if let Some(media) = &media {
            add_beams(&mut estimates, &beams, media, &pass.wavelengths);
        }
        let stages = PassStats { stage_ns: [eye_ns, photon_ns, grid_ns, lap()], ..PassStats::default() };
        (estimates, eye_stats + photon_stats + stages)
    }

    /// Every pixel's eye path, and its segments through media that scatter as beams, in pixel
    /// order. Pixels are traced in chunks, each gathering its beams into one list (a list per
    /// pixel cost an allocation a pixel a pass).
    #[inline(never)]
    fn trace_visible_points_and_beams(
        &self,
        pass: &PassSamples,
    ) -> (Vec<EyeResult>, Vec<Beam<'a>>, PassStats) {
        let pixels = (self.settings.width * self.settings.height) as usize;
        let chunks: Vec<(Vec<EyeResult>, Vec<Beam>, PassStats)> = (0..pixels)
            .into_par_iter()
            .chunks(BEAM_CHUNK)
            .map(|chunk| {
                let (mut points, mut beams, mut stats) = (Vec::new(), Vec::new(), PassStats::default());
                for pixel in chunk {
                    let (state, start_stats) = start_eye_path(self, pass, pixel);
                    let (end, path_stats) = continue_eye_path(self, pass, state, |event| {
                        if let EyeEvent::Segment(state, length) = event {
                            beams.extend(Beam::along(self.scene, pixel, state, length));
                        }
                    });
                    points.push(end.result);
                    stats = stats + start_stats + path_stats;
                }
                (points, beams, stats)
            })
            .collect();
        let mut all = (Vec::with_capacity(pixels), Vec::new(), PassStats::default());
        for (points, beams, stats) in chunks {
            all.0.extend(points);
            all.1.extend(beams);
            all.2 = all.2 + stats;
        }
        all
    }

    pub(crate) fn trace_visible_points(&self, pass: &PassSamples) -> (Vec<EyeResult>, PassStats) {
        let pixels = (self.settings.width * self.settings.height) as usize;
        collect_counting(pixels, |pixel| trace_eye_path(self, pass, pixel))
    }
}
