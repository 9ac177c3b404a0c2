//! The film (docs/design.md, step 5): per-pixel sums over passes, and the EXR they become.
//!
//! A pixel keeps only sums: of the pass estimates converted to XYZ (the mean over the pass's four
//! wavelengths of `L cmf(lambda) / p(lambda)`),
//! of the square of their luminance, of the Laplacian term's luminance, of the coverage (alpha:
//! 0 where the camera sees through a transparent film or sees a holdout), and the pass count.
//! Two films of disjoint pass ranges therefore merge exactly by adding. The image is the mean,
//! white-balanced (below), XYZ to linear Rec.709, written as one part with `Combined.R/G/B/A`
//! (what Blender's render result reads), to a temporary file that is renamed into place when
//! complete. Optional spectral bins add `Spectral.<centre>nm` channels: the mean spectral
//! radiance over each band, W / (m^2 sr nm). Optional denoising guides add Cycles' `Denoising
//! Albedo.R/G/B` (the albedo's colour under white light) and `Denoising Normal.X/Y/Z`.
//!
//! With one fixed wavelength (`--wavelength`), the image is the radiance relative to the white
//! illuminant at that wavelength (a white surface under a white light is 1) in the colour of that
//! wavelength, brought into the Rec.709 gamut by adding white at constant luminance.

use glam::DVec3;
use rayon::prelude::*;

mod output;
mod spectral;
#[cfg(test)]
mod tests;

pub use spectral::{display_xyz, SpectralBins, MAX_SPECTRAL_BINS};

use crate::spectrum::{cmf, d65, SampledSpectrum, Wavelengths, LANES};

/// How the film weighs each pass's wavelength.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FilmMode {
    /// Wavelengths sampled with a density: XYZ by `L cmf / p`, white-balanced.
    Spectral,
    /// Every pass at `lambda_nm`: radiance relative to white, in that wavelength's colour.
    Monochromatic {
        /// The wavelength.
        lambda_nm: f32,
    },
}

/// One pixel's estimate of one pass: its radiance, its Laplacian term and its coverage.
pub type Estimate = (SampledSpectrum, SampledSpectrum, f32);

/// What one pass's estimates are weighed by in the film.
struct PassWeights {
    /// Each lane's XYZ per unit radiance.
    lanes: [DVec3; LANES],
    /// The white illuminant's XYZ estimate, and the luminance weight of the pass.
    white_xyz: DVec3,
    white_y: f64,
    radius2: f64,
    /// Each lane's spectral band and weight there (when the film keeps bands).
    bands: Option<[usize; LANES]>,
    band_weights: [f64; LANES],
}

/// The XYZ of lane values weighed by `weights` ([`Film::lane_weights`]).
fn lanes_xyz(weights: &[DVec3; LANES], values: SampledSpectrum) -> DVec3 {
    weights.iter().zip(values.to_array()).map(|(w, v)| *w * f64::from(v)).sum()
}

/// The f64 numbers one pixel's sums are stored as (see [`Film::pixel_sums`]).
pub const PIXEL_SUMS: usize = 8;

/// One pixel's running sums over passes.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PixelSums {
    /// Sum of the XYZ estimates.
    pub xyz: DVec3,
    /// Sum of the squared luminance estimates.
    pub y_squared: f64,
    /// Sum of the luminance estimates times the pass's white estimate `w_i` (for the variance of
    /// the white-balanced ratio, see `crate::error`).
    pub y_white: f64,
    /// Sum over passes of r_i^2 times the luminance of the pass's Laplacian estimate (the bias
    /// term of the error bound, see `crate::error`).
    pub laplacian_y: f64,
    /// Sum of the coverage estimates (the alpha channel is their mean).
    pub coverage: f64,
    /// Number of passes summed.
    pub passes: u64,
}

/// The image being rendered: sums per pixel, row-major from the top-left.
///
/// White balance: every pixel of a pass shares its wavelengths, so with few passes the estimate
/// `sum L cmf / p` carries a colour cast common to the whole image (with one wavelength a pass,
/// about 10% per channel at 32 passes for a grey scene). The film also sums the same estimator
/// for the white illuminant itself, `white = sum d65 cmf / p`, whose true value is known, and
/// scales each XYZ channel by `true white / estimated white` (a ratio estimator: consistent,
/// exact for any spectrum proportional to D65, and additive like every other sum, so merging
/// stays exact).
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
    /// Sum over passes of the weight `w_i` each pass's luminance gets in the image (its white
    /// luminance estimate; 1 per pass without white balance).
    pub white_y: f64,
    /// Sum of the squares of the same.
    pub white_y_squared: f64,
    /// Pixel estimates that were NaN or infinite, counted as zero.
    pub non_finite_estimates: u64,
    /// How wavelengths are weighed.
    pub mode: FilmMode,
    /// Optional spectral bands (count 0 when off).
    pub bins: SpectralBins,
    /// Sums of the denoising guides per pixel, [`GUIDE_SUMS`] each (empty when off).
    pub guides: Vec<f64>,
}

/// The sums of one pixel's denoising guides: the albedo's XYZ under white, and the normal.
pub const GUIDE_SUMS: usize = 6;

impl Film {
    /// An empty film with `spectral_bins` bands (0 for none), and denoising guides if `guides`.
    pub fn new(width: u32, height: u32, mode: FilmMode, spectral_bins: usize, guides: bool) -> Self {
        let pixels = (width * height) as usize;
        Film {
            guides: vec![0.0; if guides { pixels * GUIDE_SUMS } else { 0 }],
            mode,
            bins: SpectralBins { count: spectral_bins, sums: vec![0.0; pixels * spectral_bins] },
            width,
            height,
            pixels: vec![PixelSums::default(); (width * height) as usize],
            white_xyz: DVec3::ZERO,
            passes: 0,
            white_y: 0.0,
            white_y_squared: 0.0,
            non_finite_estimates: 0,
        }
    }

    /// Adds another film's sums to this one (passes rendered elsewhere: sums merge exactly).
    /// The films must have the same size, mode and bands.
    pub fn add(&mut self, other: &Film) {
        for (a, b) in self.pixels.iter_mut().zip(&other.pixels) {
            a.xyz += b.xyz;
            a.y_squared += b.y_squared;
            a.y_white += b.y_white;
            a.laplacian_y += b.laplacian_y;
            a.coverage += b.coverage;
            a.passes += b.passes;
        }
        for (a, b) in self.bins.sums.iter_mut().zip(&other.bins.sums) {
            *a += b;
        }
        for (a, b) in self.guides.iter_mut().zip(&other.guides) {
            *a += b;
        }
        self.white_xyz += other.white_xyz;
        self.passes += other.passes;
        self.white_y += other.white_y;
        self.white_y_squared += other.white_y_squared;
        self.non_finite_estimates = self.non_finite_estimates.wrapping_add(other.non_finite_estimates);
    }

    /// Every per-pixel sum as an f64, pixel by pixel (`PIXEL_SUMS` each), then the spectral bands,
    /// then the guides.
    pub fn pixel_sums(&self) -> Vec<f64> {
        let per_pixel = self.pixels.iter().flat_map(|p| {
            [p.xyz.x, p.xyz.y, p.xyz.z, p.y_squared, p.y_white, p.laplacian_y, p.coverage, p.passes as f64]
        });
        per_pixel.chain(self.bins.sums.iter().copied()).chain(self.guides.iter().copied()).collect()
    }

    /// Puts back sums that [`Film::pixel_sums`] gave; `None` when their count does not fit.
    pub fn set_pixel_sums(&mut self, sums: &[f64]) -> Option<()> {
        let pixel_part = self.pixels.len() * PIXEL_SUMS;
        let bins_end = pixel_part + self.bins.sums.len();
        if sums.len() != bins_end + self.guides.len() {
            return None;
        }
        for (p, s) in self.pixels.iter_mut().zip(sums[..pixel_part].chunks_exact(PIXEL_SUMS)) {
            *p = PixelSums {
                xyz: DVec3::new(s[0], s[1], s[2]),
                y_squared: s[3],
                y_white: s[4],
                laplacian_y: s[5],
                coverage: s[6],
                passes: s[7] as u64,
            };
        }
        self.bins.sums.copy_from_slice(&sums[pixel_part..bins_end]);
        self.guides.copy_from_slice(&sums[bins_end..]);
        Some(())
    }

    /// Adds one pass of gather radius `radius`: each pixel's radiance, Laplacian term (at the
    /// wavelengths `lambda`, each lane sampled with its density) and coverage, pixel `i`'s from
    /// `estimate_of(i)`.
    pub fn add_pass(
        &mut self,
        lambda: &Wavelengths,
        radius: f32,
        estimate_of: impl Fn(usize) -> Estimate + Sync,
    ) {
        let weights = self.pass_weights(lambda, radius);
        self.white_y += weights.white_y;
        self.white_y_squared += weights.white_y * weights.white_y;
        self.white_xyz += weights.white_xyz;
        self.passes += 1;
        self.for_each_entry(
            self.pixels.len(),
            |i| i,
            |i, sums, bins| {
                sums.passes += 1;
                add_estimate(&weights, sums, bins, estimate_of(i), 1.0)
            },
        );
    }

    /// Adds, at some pixels, the difference between a frame's estimate and the common one that a
    /// film of common estimates (shared by the frames of a block) received for the same pass:
    /// this film then holds one frame's differences, and adding it to the common film gives the
    /// frame's own sums (exactly, up to rounding). Pass counts are the common film's. Difference
    /// `k` of `count` is `difference(k)`: the pixel (increasing with `k`), the frame's estimate
    /// and the common one.
    pub fn add_differences(
        &mut self,
        lambda: &Wavelengths,
        radius: f32,
        count: usize,
        difference: impl Fn(usize) -> (usize, Estimate, Estimate) + Sync,
    ) {
        let weights = self.pass_weights(lambda, radius);
        self.for_each_entry(
            count,
            |k| difference(k).0,
            |k, sums, bins| {
                let (_, own, common) = difference(k);
                add_estimate(&weights, sums, bins, own, 1.0)
                    + add_estimate(&weights, sums, bins, common, -1.0)
            },
        );
    }

    /// Calls `add(k, sums, bands)` with the sums and spectral bands of pixel `pixel_of(k)`, for
    /// each `k` below `count` (pixels increasing with `k`), on blocks of pixels in parallel (each
    /// pixel's sums see the same additions in the same order with any number of threads). `add`
    /// gives the non-finite estimates it met, counted here.
    fn for_each_entry(
        &mut self,
        count: usize,
        pixel_of: impl Fn(usize) -> usize + Sync,
        add: impl Fn(usize, &mut PixelSums, &mut [f64]) -> i64 + Sync,
    ) {
        const BLOCK: usize = 4096;
        let bands = self.bins.count;
        let first_at = |pixel: usize| {
            let (mut lo, mut hi) = (0, count);
            while lo < hi {
                let mid = (lo + hi) / 2;
                if pixel_of(mid) < pixel {
                    lo = mid + 1;
                } else {
                    hi = mid;
                }
            }
            lo
        };
        let mut band_blocks: Vec<&mut [f64]> = self.bins.sums.chunks_mut((BLOCK * bands).max(1)).collect();
        band_blocks.resize_with(self.pixels.len().div_ceil(BLOCK), Default::default);
        let non_finite: i64 = self
            .pixels
            .par_chunks_mut(BLOCK)
            .zip(band_blocks)
            .enumerate()
            .map(|(b, (pixels, block_bands))| {
                let start = b * BLOCK;
                let mut non_finite = 0;
                for k in first_at(start)..first_at(start + pixels.len()) {
                    let i = pixel_of(k) - start;
                    let pixel_bands = block_bands.get_mut(i * bands..(i + 1) * bands).unwrap_or_default();
                    non_finite += add(k, &mut pixels[i], pixel_bands);
                }
                non_finite
            })
            .sum();
        self.non_finite_estimates = self.non_finite_estimates.wrapping_add(non_finite as u64);
    }

    /// What every pixel's estimate of one pass is weighed by.
    fn pass_weights(&self, lambda: &Wavelengths, radius: f32) -> PassWeights {
        let lanes = self.lane_weights(lambda);
        let white_xyz = lanes_xyz(&lanes, lambda.d65);
        let white_y = match self.mode {
            FilmMode::Spectral => white_xyz.y,
            FilmMode::Monochromatic { .. } => 1.0,
        };
        PassWeights {
            lanes,
            white_xyz,
            white_y,
            radius2: f64::from(radius) * f64::from(radius),
            bands: (self.bins.count > 0).then(|| lambda.nm.to_array().map(|l| self.bins.band(l))),
            band_weights: lambda
                .pdf
                .to_array()
                .map(|p| 1.0 / (f64::from(p) * self.bins.width_nm() * LANES as f64)),
        }
    }

    /// Each lane's XYZ per unit radiance at `lambda` (an estimate is the mean over lanes).
    fn lane_weights(&self, lambda: &Wavelengths) -> [DVec3; LANES] {
        std::array::from_fn(|k| {
            let (lambda_nm, pdf) = (lambda.nm[k], lambda.pdf[k]);
            let weight = match self.mode {
                FilmMode::Spectral => (cmf(lambda_nm) / pdf).as_dvec3(),
                FilmMode::Monochromatic { .. } => display_xyz(lambda_nm) / f64::from(d65(lambda_nm)),
            };
            weight / LANES as f64
        })
    }

    /// Adds one pass's denoising guides (each pixel's albedo at the wavelengths `lambda` and its
    /// normal), after [`Film::add_pass`] added the pass (whose count they share); nothing when the
    /// film keeps no guides.
    pub fn add_guides(
        &mut self,
        lambda: &Wavelengths,
        guides: impl Iterator<Item = (SampledSpectrum, glam::Vec3)>,
    ) {
        let weights = self.lane_weights(lambda);
        for (sums, (albedo, normal)) in self.guides.chunks_exact_mut(GUIDE_SUMS).zip(guides) {
            let xyz = lanes_xyz(&weights, albedo * lambda.d65);
            let values = [xyz.x, xyz.y, xyz.z, f64::from(normal.x), f64::from(normal.y), f64::from(normal.z)];
            for (sum, value) in sums.iter_mut().zip(values) {
                *sum += if value.is_finite() { value } else { 0.0 };
            }
        }
    }
}

/// Adds `sign` (1 or -1) times a pixel's estimate to its sums (not its pass count) and spectral
/// bands; gives `sign` where the estimate was not finite (then counted as zero), else 0.
fn add_estimate(
    w: &PassWeights,
    sums: &mut PixelSums,
    bands: &mut [f64],
    (radiance, laplacian, coverage): Estimate,
    sign: f64,
) -> i64 {
    // A non-finite estimate would poison the pixel's sums for good: count it as zero and report
    // it, so the image stays usable and the problem is not silent. (A film of differences takes
    // back the common film's count: the sum wraps back.)
    let (radiance, laplacian, non_finite) = if radiance.is_finite() && laplacian.is_finite() {
        (radiance, laplacian, 0)
    } else {
        (SampledSpectrum::ZERO, SampledSpectrum::ZERO, sign as i64)
    };
    let xyz = lanes_xyz(&w.lanes, radiance) * sign;
    sums.xyz += xyz;
    sums.y_squared += sign * (xyz.y * xyz.y);
    sums.y_white += xyz.y * w.white_y;
    sums.laplacian_y += w.radius2 * lanes_xyz(&w.lanes, laplacian).y * sign;
    sums.coverage += f64::from(coverage) * sign;
    if let Some(lane_bands) = w.bands {
        for k in 0..LANES {
            bands[lane_bands[k]] += f64::from(radiance[k]) * w.band_weights[k] * sign;
        }
    }
    non_finite
}
