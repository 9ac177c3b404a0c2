//! What the film becomes: the white-balanced image, its alpha and guides, and the EXR.

use std::path::Path;

use exr::prelude::*;
use glam::DVec3;

use super::{Film, FilmMode, GUIDE_SUMS};
use crate::spectrum::{d65_xyz, xyz_to_linear_rec709};

impl Film {
    /// The guides' channels (name, one value per pixel): the mean albedo, white-balanced and in
    /// linear Rec.709, and the mean normal.
    fn guide_channels(&self) -> Vec<(&'static str, Vec<f32>)> {
        if self.guides.is_empty() {
            return Vec::new();
        }
        let balance = self.white_balance();
        let passes = self.passes.max(1) as f64;
        let pixels: Vec<[f64; GUIDE_SUMS]> = self
            .guides
            .chunks_exact(GUIDE_SUMS)
            .map(|s| {
                let rgb = xyz_to_linear_rec709(DVec3::new(s[0], s[1], s[2]) / passes * balance);
                [rgb.x, rgb.y, rgb.z, s[3] / passes, s[4] / passes, s[5] / passes]
            })
            .collect();
        let names = [
            "Denoising Albedo.R",
            "Denoising Albedo.G",
            "Denoising Albedo.B",
            "Denoising Normal.X",
            "Denoising Normal.Y",
            "Denoising Normal.Z",
        ];
        names
            .iter()
            .enumerate()
            .map(|(k, name)| (*name, pixels.iter().map(|p| p[k] as f32).collect()))
            .collect()
    }

    /// The per-channel XYZ scale that makes the passes' white estimate exact.
    fn white_balance(&self) -> DVec3 {
        if self.mode != FilmMode::Spectral || self.passes == 0 || self.white_xyz.min_element() <= 0.0 {
            return DVec3::ONE;
        }
        d65_xyz() / (self.white_xyz / self.passes as f64)
    }

    /// The luminance the white illuminant should have (the white balance's target): 1 for
    /// spectral films, and 1 per pass weight without white balance.
    pub fn white_target_y(&self) -> f64 {
        match self.mode {
            FilmMode::Spectral => d65_xyz().y,
            FilmMode::Monochromatic { .. } => 1.0,
        }
    }

    /// The mean linear Rec.709 colour of every pixel.
    pub fn rgb(&self) -> Vec<DVec3> {
        let balance = self.white_balance();
        self.pixels
            .iter()
            .map(|s| {
                if s.passes == 0 {
                    return DVec3::ZERO;
                }
                xyz_to_linear_rec709(s.xyz / s.passes as f64 * balance)
            })
            .collect()
    }

    /// The mean coverage (alpha) of every pixel (1 before any pass).
    pub fn alpha(&self) -> Vec<f32> {
        self.pixels
            .iter()
            .map(|s| if s.passes == 0 { 1.0 } else { (s.coverage / s.passes as f64) as f32 })
            .collect()
    }

    /// Writes the image, with `extra` channels (name, one value per pixel), to `path` through a
    /// temporary file beside it.
    pub fn write_exr(&self, path: &Path, extra: &[(&str, Vec<f32>)]) -> std::result::Result<(), String> {
        let rgb = self.rgb();
        let (w, h) = (self.width as usize, self.height as usize);
        let channel = |name: &str, values: Vec<f32>| AnyChannel::new(name, FlatSamples::F32(values));
        let component = |k: usize| rgb.iter().map(|c| c[k] as f32).collect::<Vec<f32>>();
        let mut list = vec![
            channel("Combined.R", component(0)),
            channel("Combined.G", component(1)),
            channel("Combined.B", component(2)),
            channel("Combined.A", self.alpha()),
        ];
        for (name, values) in extra.iter().cloned().chain(self.guide_channels()) {
            list.push(channel(name, values));
        }
        for k in 0..self.bins.count {
            let passes = self.passes.max(1) as f64;
            let band =
                (0..w * h).map(|i| (self.bins.sums[i * self.bins.count + k] / passes) as f32).collect();
            list.push(channel(&self.bins.channel_name(k), band));
        }
        let channels = AnyChannels::sort(SmallVec::from_vec(list));
        let layer = Layer::new((w, h), LayerAttributes::default(), Encoding::SMALL_LOSSLESS, channels);
        let image = Image::from_layer(layer);
        crate::output::write_whole(path, |temporary| {
            image.write().to_file(temporary).map_err(|e| format!("cannot write {}: {e}", path.display()))
        })
    }
}
