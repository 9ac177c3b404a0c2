//! The film (DESIGN.md step 5): per-pixel sums over passes, and the EXR they become.
//!
//! A pixel keeps only sums: of the pass estimates converted to XYZ (`L cmf(lambda) / p(lambda)`),
//! of the square of their luminance, of the Laplacian term's luminance, and the pass count.
//! Two films of disjoint pass ranges therefore merge exactly by adding. The image is the mean,
//! white-balanced (below), XYZ to linear Rec.709, written as one part with `Combined.R/G/B/A` (what Blender's render result
//! reads), to a temporary file that is renamed into place when complete.

use std::path::Path;

use exr::prelude::*;
use glam::DVec3;

use crate::spectrum::{cmf, d65, d65_xyz, xyz_to_linear_rec709};

/// One pixel's running sums over passes.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PixelSums {
    /// Sum of the XYZ estimates.
    pub xyz: DVec3,
    /// Sum of the squared luminance estimates.
    pub y_squared: f64,
    /// Sum of the luminance of the Laplacian term.
    pub laplacian_y: f64,
    /// Number of passes summed.
    pub passes: u64,
}

/// The image being rendered: sums per pixel, row-major from the top-left.
///
/// White balance: every pixel of a pass shares its wavelength, so with few passes the estimate
/// `sum L cmf / p` carries a colour cast common to the whole image (about 10% per channel at 32
/// passes for a grey scene). The film also sums the same estimator for the white illuminant
/// itself, `white = sum d65 cmf / p`, whose true value is known, and scales each XYZ channel by
/// `true white / estimated white` (a ratio estimator: consistent, exact for any spectrum
/// proportional to D65, and additive like every other sum, so merging stays exact).
#[derive(Clone, Debug)]
pub struct Film {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Per-pixel sums.
    pub pixels: Vec<PixelSums>,
    /// Sum over passes of the white illuminant's XYZ estimate, `d65 cmf / p`.
    pub white_xyz: DVec3,
    /// Passes summed into `white_xyz`.
    pub passes: u64,
    /// Pixel estimates that were NaN or infinite, counted as zero.
    pub non_finite_estimates: u64,
}

impl Film {
    /// An empty film.
    pub fn new(width: u32, height: u32) -> Self {
        Film {
            width,
            height,
            pixels: vec![PixelSums::default(); (width * height) as usize],
            white_xyz: DVec3::ZERO,
            passes: 0,
            non_finite_estimates: 0,
        }
    }

    /// Adds one pass: `radiance[i]` and `laplacian[i]` at `lambda_nm`, sampled with density `pdf`.
    pub fn add_pass(&mut self, lambda_nm: f32, pdf: f32, estimates: impl Iterator<Item = (f32, f32)>) {
        let weight = (cmf(lambda_nm) / pdf).as_dvec3();
        self.white_xyz += weight * f64::from(d65(lambda_nm));
        self.passes += 1;
        for (sums, (radiance, laplacian)) in self.pixels.iter_mut().zip(estimates) {
            // A non-finite estimate would poison the pixel's sums for good: count it as zero and
            // report it, so the image stays usable and the problem is not silent.
            let (radiance, laplacian) = if radiance.is_finite() && laplacian.is_finite() {
                (radiance, laplacian)
            } else {
                self.non_finite_estimates += 1;
                (0.0, 0.0)
            };
            let xyz = weight * f64::from(radiance);
            sums.xyz += xyz;
            sums.y_squared += xyz.y * xyz.y;
            sums.laplacian_y += weight.y * f64::from(laplacian);
            sums.passes += 1;
        }
    }

    /// The per-channel XYZ scale that makes the passes' white estimate exact.
    fn white_balance(&self) -> DVec3 {
        if self.passes == 0 || self.white_xyz.min_element() <= 0.0 {
            return DVec3::ONE;
        }
        d65_xyz() / (self.white_xyz / self.passes as f64)
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

    /// Writes the image to `path` through a temporary file beside it.
    pub fn write_exr(&self, path: &Path) -> std::result::Result<(), String> {
        let rgb = self.rgb();
        let (w, h) = (self.width as usize, self.height as usize);
        let channel = |name: &str, values: Vec<f32>| AnyChannel::new(name, FlatSamples::F32(values));
        let component = |k: usize| rgb.iter().map(|c| c[k] as f32).collect::<Vec<f32>>();
        let channels = AnyChannels::sort(SmallVec::from_vec(vec![
            channel("Combined.R", component(0)),
            channel("Combined.G", component(1)),
            channel("Combined.B", component(2)),
            channel("Combined.A", vec![1.0; w * h]),
        ]));
        let layer = Layer::new((w, h), LayerAttributes::default(), Encoding::SMALL_LOSSLESS, channels);
        let image = Image::from_layer(layer);
        let temporary = path.with_extension("exr.partial");
        image
            .write()
            .to_file(&temporary)
            .map_err(|e| format!("cannot write {}: {e}", temporary.display()))?;
        std::fs::rename(&temporary, path)
            .map_err(|e| format!("cannot rename {} to {}: {e}", temporary.display(), path.display()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::pass_sample;
    use crate::spectrum::sample_visible_wavelength;

    /// Adds `passes` passes in which every pixel sees `radiance(lambda)`.
    fn film_of(passes: u64, radiance: impl Fn(f32) -> f32) -> Film {
        let mut film = Film::new(2, 1);
        for i in 0..passes {
            let (lambda, pdf) = sample_visible_wavelength(pass_sample(5, i));
            film.add_pass(lambda, pdf, [(radiance(lambda), 0.0), (radiance(lambda), 0.0)].into_iter());
        }
        film
    }

    #[test]
    fn a_spectrum_proportional_to_d65_is_exactly_grey_after_any_number_of_passes() {
        for passes in [1, 3, 17] {
            let rgb = film_of(passes, |l| 0.25 * d65(l)).rgb()[0];
            assert!((rgb - DVec3::splat(0.25)).abs().max_element() < 1e-6, "{passes} passes: {rgb}");
        }
    }

    #[test]
    fn non_finite_estimates_are_counted_and_do_not_poison_the_pixel() {
        let film = film_of(16, |l| if l < 550.0 { f32::NAN } else { d65(l) });
        assert!(film.non_finite_estimates > 0);
        assert!(film.rgb().iter().all(|c| c.is_finite()));
    }
}
