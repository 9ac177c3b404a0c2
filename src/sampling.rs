//! Random streams, the per-pass low-discrepancy sequence, and warps from the unit square.
//!
//! Every stream is keyed by `(seed, pass, index)` alone, never by thread or time, so a render is
//! the same bits with any thread count and any pass range (docs/design.md, "Determinism").

use glam::{Vec2, Vec3};
use rand::RngExt;
use rand_pcg::Pcg32;

/// Which kind of stream a key belongs to, so that eye and photon streams never coincide.
#[derive(Clone, Copy)]
pub enum Stream {
    /// One per pixel and pass.
    Eye = 1,
    /// One per photon path and pass.
    Photon = 2,
    /// One per Markov chain of photon paths and pass.
    PhotonChain = 3,
}

/// SplitMix64's finaliser: a good 64-bit mix.
fn mix(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// The random stream for `(seed, stream, pass, index)`.
pub fn stream(seed: u64, kind: Stream, pass: u64, index: u64) -> Sampler {
    let key = mix(mix(mix(seed ^ 0x9e37_79b9_7f4a_7c15) ^ kind as u64) ^ pass);
    Sampler { pcg: Pcg32::new(mix(key ^ index), key | 1) }
}

/// Dimensions of a pixel's stream drawn from its pass-indexed Sobol sequence: the film and lens
/// samples, and the choices at the first vertices and at the visible point.
const PIXEL_SOBOL_DIMENSIONS: u32 = 16;

/// Sobol points per scrambled sequence (`sobol_burley`'s limit); later passes start a new one.
const SOBOL_SEQUENCE: u64 = 1 << 16;

/// Pixel `pixel`'s stream for pass `pass`: its first draws are point `pass` of the pixel's own
/// Owen-scrambled Sobol sequence (Burley 2020), so that over passes a pixel's film positions,
/// lens points and light samples are stratified (as a sampler's samples per pixel are in Cycles):
/// a light's edge or a highlight converges faster than with independent draws. Every point alone
/// is uniform, so each pass's estimate stays unbiased; the rest of the stream is the pass's own.
pub fn pixel_stream(seed: u64, pass: u64, pixel: u64) -> PixelSampler {
    let key = mix(mix(seed ^ 0x736f_626f_6c00) ^ pixel) ^ (pass / SOBOL_SEQUENCE);
    let sobol = SobolPrefix {
        seed: mix(key) as u32,
        index: (pass % SOBOL_SEQUENCE) as u32,
        next_dimension: 0,
        four: [0.0; 4],
    };
    PixelSampler { sobol, rest: stream(seed, Stream::Eye, pass, pixel) }
}

/// Where a stream stands in its Sobol point (drawn four dimensions at a time, which
/// `sobol_burley` computes together).
#[derive(Clone, Copy)]
struct SobolPrefix {
    seed: u32,
    index: u32,
    next_dimension: u32,
    four: [f32; 4],
}

impl SobolPrefix {
    fn next(&mut self) -> f32 {
        let d = self.next_dimension;
        if d.is_multiple_of(4) {
            self.four = sobol_burley::sample_4d(self.index, d / 4, self.seed);
        }
        self.next_dimension += 1;
        self.four[d as usize % 4]
    }
}

/// A stream of uniform numbers in [0, 1). Cloning it saves its state, so a path can be resumed
/// later with exactly the numbers it would have drawn.
#[derive(Clone)]
pub struct Sampler {
    pcg: Pcg32,
}

impl Sampler {
    /// One uniform number in [0, 1).
    #[inline]
    pub fn next_1d(&mut self) -> f32 {
        self.pcg.random::<f32>()
    }

    /// Two uniform numbers in [0, 1).
    pub fn next_2d(&mut self) -> Vec2 {
        Vec2::new(self.next_1d(), self.next_1d())
    }
}

/// Where a path draws its uniform numbers from: a stream of its own, or a point of primary
/// sample space that a Markov chain moves ([`PrimarySample`]).
pub trait Uniforms {
    /// One uniform number in [0, 1).
    fn next_1d(&mut self) -> f32;

    /// Two uniform numbers in [0, 1).
    fn next_2d(&mut self) -> Vec2 {
        let u = self.next_1d();
        Vec2::new(u, self.next_1d())
    }
}

impl Uniforms for Sampler {
    #[inline]
    fn next_1d(&mut self) -> f32 {
        Sampler::next_1d(self)
    }
}

impl<T: Uniforms> Uniforms for &mut T {
    #[inline]
    fn next_1d(&mut self) -> f32 {
        (**self).next_1d()
    }
}

/// `u` moved by `step` (of either sign) and wrapped into [0, 1): a symmetric move on the circle.
pub fn wrap_unit(u: f32, step: f32) -> f32 {
    let moved = u + step;
    let wrapped = moved - moved.floor();
    if wrapped < 1.0 {
        wrapped
    } else {
        0.0
    }
}

/// A pixel's stream: a Sobol prefix, then a [`Sampler`]'s numbers (photon paths, which draw
/// from a `Sampler` alone, do not test at every draw whether a prefix is left).
#[derive(Clone)]
pub struct PixelSampler {
    sobol: SobolPrefix,
    rest: Sampler,
}

impl PixelSampler {
    /// One uniform number in [0, 1).
    #[inline]
    pub fn next_1d(&mut self) -> f32 {
        if self.sobol.next_dimension < PIXEL_SOBOL_DIMENSIONS {
            self.sobol.next()
        } else {
            self.rest.next_1d()
        }
    }

    /// Two uniform numbers in [0, 1).
    pub fn next_2d(&mut self) -> Vec2 {
        Vec2::new(self.next_1d(), self.next_1d())
    }

    /// The stream of branch `branch` (from 1) of a path split where this stream stands: point
    /// `pass` of a Sobol sequence of its own from its first dimension (stratified over passes,
    /// independent of this stream's), then numbers of its own.
    pub fn branch(&self, branch: u32) -> PixelSampler {
        let key = mix(u64::from(self.sobol.seed) << 32 ^ u64::from(branch) ^ 0x6272_616e_6368);
        let sobol =
            SobolPrefix { seed: mix(key) as u32, index: self.sobol.index, next_dimension: 0, four: [0.0; 4] };
        let rest = Sampler { pcg: Pcg32::new(mix(key ^ u64::from(self.sobol.index)), key | 1) };
        PixelSampler { sobol, rest }
    }
}

/// The pass's point of the golden-ratio (Kronecker) sequence, rotated by the seed: stratified over
/// passes, so wavelengths cover the spectrum evenly however the passes are split.
pub fn pass_sample(seed: u64, pass: u64) -> f32 {
    const INVERSE_GOLDEN_RATIO: f64 = 0.618_033_988_749_894_9;
    let offset = (mix(seed) >> 11) as f64 / (1u64 << 53) as f64;
    (offset + pass as f64 * INVERSE_GOLDEN_RATIO).fract() as f32
}

/// The pass's point in the shutter, in [0, 1): a second low-discrepancy sequence (Roberts' R2
/// constant), so that times are stratified over passes too and depend on (seed, pass) only.
pub fn pass_time_sample(seed: u64, pass: u64) -> f32 {
    const ALPHA: f64 = 0.569_840_290_998_053_3;
    let offset = (mix(seed ^ 0x7469_6d65) >> 11) as f64 / (1u64 << 53) as f64;
    (offset + pass as f64 * ALPHA).fract() as f32
}

/// Concentric map of the square to the unit disc (Shirley & Chiu 1997).
pub fn square_to_disc(u: Vec2) -> Vec2 {
    let p = 2.0 * u - Vec2::ONE;
    // The larger coordinate gives the radius, the ratio of the smaller to it the angle within
    // the octant (the same bits as a branch per octant, in fewer instructions).
    let by_y = p.x.abs() <= p.y.abs();
    let (radius, other) = if by_y { (p.y, p.x) } else { (p.x, p.y) };
    if radius == 0.0 {
        return Vec2::ZERO;
    }
    let (sin, cos) = sin_cos_within_quarter(std::f32::consts::FRAC_PI_4 * (other / radius));
    // Beyond the diagonal the angle is pi/2 minus this one: its cosine is this one's sine.
    radius * if by_y { Vec2::new(sin, cos) } else { Vec2::new(cos, sin) }
}

/// `(sin a, cos a)` for `|a| <= pi / 4`, by Cephes' single-precision polynomials (`sinf.c`,
/// `cosf.c`; within 2 ulps there), inline: the concentric map needs no more range, and libm's
/// `sincosf` was a call per sample.
fn sin_cos_within_quarter(a: f32) -> (f32, f32) {
    let z = a * a;
    let sin = ((-1.951_529_6e-4 * z + 8.332_161e-3) * z - 1.666_665_5e-1) * z * a + a;
    let cos = ((2.443_315_7e-5 * z - 1.388_731_6e-3) * z + 4.166_664_6e-2) * z * z - 0.5 * z + 1.0;
    (sin, cos)
}

/// Cosine-weighted direction about +z; density `cos(theta) / pi`.
pub fn square_to_cosine_hemisphere(u: Vec2) -> Vec3 {
    let d = square_to_disc(u);
    Vec3::new(d.x, d.y, (1.0 - d.length_squared()).max(0.0).sqrt())
}

/// Uniform direction in the cone about +z whose half-angle has `1 - cos = one_minus_cos_max`;
/// density `1 / (2 pi one_minus_cos_max)`. The direction's own `1 - cos theta` is
/// `u.x * one_minus_cos_max`, which callers may use for precise falloffs.
pub fn square_to_cone(u: Vec2, one_minus_cos_max: f32) -> Vec3 {
    let one_minus_cos = u.x * one_minus_cos_max;
    let cos_theta = 1.0 - one_minus_cos;
    let sin_theta = (one_minus_cos * (2.0 - one_minus_cos)).max(0.0).sqrt();
    let phi = std::f32::consts::TAU * u.y;
    Vec3::new(sin_theta * phi.cos(), sin_theta * phi.sin(), cos_theta)
}

/// Uniform direction on the sphere; density `1 / (4 pi)`.
pub fn square_to_sphere(u: Vec2) -> Vec3 {
    square_to_cone(u, 2.0)
}

/// Uniform barycentric coordinates (b1, b2) on a triangle (Heitz 2019, "A Low-Distortion Map
/// Between Triangle and Square").
pub fn square_to_triangle(u: Vec2) -> Vec2 {
    if u.y > u.x {
        let b0 = u.x / 2.0;
        Vec2::new(b0, u.y - b0)
    } else {
        let b1 = u.y / 2.0;
        Vec2::new(u.x - b1, b1)
    }
}

/// An orthonormal basis around the unit vector `n` (Duff et al. 2017), as (tangent, bitangent).
pub fn basis(n: Vec3) -> (Vec3, Vec3) {
    n.any_orthonormal_pair()
}

/// A discrete distribution over weights, sampled by inverting its CDF.
#[derive(Clone, Debug, Default)]
pub struct Distribution1D {
    cdf: Vec<f64>,
    total: f64,
}

impl Distribution1D {
    /// The distribution proportional to `weights` (non-negative; all zero gives an empty one).
    pub fn new(weights: impl IntoIterator<Item = f64>) -> Self {
        let mut total = 0.0;
        let cdf = weights
            .into_iter()
            .map(|w| {
                total += w.max(0.0);
                total
            })
            .collect();
        Distribution1D { cdf, total }
    }

    /// The sum of the weights.
    pub fn total(&self) -> f64 {
        self.total
    }

    /// An index for the uniform `u`, with its probability; `None` when every weight is zero.
    pub fn sample(&self, u: f32) -> Option<(usize, f32)> {
        if self.total <= 0.0 {
            return None;
        }
        let target = f64::from(u) * self.total;
        let i = self.cdf.partition_point(|&c| c <= target).min(self.cdf.len() - 1);
        Some((i, self.probability(i)))
    }

    /// A continuous position in [0, 1) for the uniform `u`, with its density: the chosen
    /// index's cell, and `u` rescaled to a position inside it.
    pub fn sample_continuous(&self, u: f32) -> Option<(f32, f32)> {
        let (i, p) = self.sample(u)?;
        let below = if i == 0 { 0.0 } else { self.cdf[i - 1] };
        let inside = ((f64::from(u) * self.total - below) / (self.cdf[i] - below)).clamp(0.0, 1.0);
        let n = self.cdf.len() as f32;
        Some((((i as f64 + inside) as f32 / n).min(1.0 - f32::EPSILON), p * n))
    }

    /// The probability of index `i`.
    pub fn probability(&self, i: usize) -> f32 {
        let below = if i == 0 { 0.0 } else { self.cdf[i - 1] };
        ((self.cdf[i] - below) / self.total) as f32
    }
}

/// A piecewise-constant density on the unit square from a grid of weights (rows of `width`),
/// sampled by a marginal over rows and a conditional within the row (pbrt-v4, section A.5).
#[derive(Clone, Debug, Default)]
pub struct Distribution2D {
    rows: Vec<Distribution1D>,
    marginal: Distribution1D,
}

impl Distribution2D {
    /// The distribution proportional to `weights`, `height` rows of `width`.
    pub fn new(weights: &[f64], width: usize) -> Self {
        let rows: Vec<Distribution1D> =
            weights.chunks_exact(width).map(|row| Distribution1D::new(row.iter().copied())).collect();
        let marginal = Distribution1D::new(rows.iter().map(Distribution1D::total));
        Distribution2D { rows, marginal }
    }

    /// A point (x along a row, y across rows) in [0, 1)^2 with its density; `None` if all
    /// weights are zero.
    pub fn sample(&self, u: Vec2) -> Option<(Vec2, f32)> {
        let (y, p_y) = self.marginal.sample_continuous(u.y)?;
        let row = &self.rows[((y * self.rows.len() as f32) as usize).min(self.rows.len() - 1)];
        let (x, p_x) = row.sample_continuous(u.x)?;
        Some((Vec2::new(x, y), p_x * p_y))
    }

    /// The density at `point` in [0, 1]^2.
    pub fn pdf(&self, point: Vec2) -> f32 {
        let height = self.rows.len();
        if height == 0 || self.marginal.total() <= 0.0 {
            return 0.0;
        }
        let j = ((point.y * height as f32) as usize).min(height - 1);
        let row = &self.rows[j];
        let width = row.cdf.len();
        let i = ((point.x * width as f32) as usize).min(width - 1);
        (row.cdf[i] - if i == 0 { 0.0 } else { row.cdf[i - 1] }) as f32 / self.marginal.total() as f32
            * (width * height) as f32
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn streams_depend_only_on_their_key() {
        let a = stream(7, Stream::Eye, 3, 11).next_1d();
        assert_eq!(a, stream(7, Stream::Eye, 3, 11).next_1d());
        assert_ne!(a, stream(7, Stream::Photon, 3, 11).next_1d());
        assert_ne!(a, stream(7, Stream::Eye, 4, 11).next_1d());
    }

    /// Over 256 passes, a pixel's film positions fill all 16 x 16 strata of the pixel, one each
    /// (independent draws leave about 95 of the 256 strata empty); other pixels' positions differ.
    #[test]
    fn a_pixels_film_samples_are_stratified_over_passes() {
        for pixel in [0, 1, 4097] {
            let mut strata = [0u32; 256];
            for pass in 0..256 {
                let u = pixel_stream(5, pass, pixel).next_2d();
                strata[(u.y * 16.0) as usize * 16 + (u.x * 16.0) as usize] += 1;
            }
            assert!(strata.iter().all(|&n| n == 1), "pixel {pixel}: {strata:?}");
        }
        assert_ne!(pixel_stream(5, 3, 0).next_2d(), pixel_stream(5, 3, 1).next_2d());
    }

    /// A branch's stream starts a Sobol sequence of its own: its first two dimensions fill all
    /// 16 x 16 strata over 256 passes, and differ from its parent's and from another branch's.
    #[test]
    fn a_branchs_samples_are_stratified_over_passes_on_their_own() {
        let mut strata = [0u32; 256];
        for pass in 0..256 {
            let mut parent = pixel_stream(5, pass, 7);
            parent.next_2d();
            parent.next_1d();
            let u = parent.branch(1).next_2d();
            strata[(u.y * 16.0) as usize * 16 + (u.x * 16.0) as usize] += 1;
            assert_ne!(u, parent.next_2d());
            assert_ne!(u, parent.branch(2).next_2d());
        }
        assert!(strata.iter().all(|&n| n == 1), "{strata:?}");
    }

    /// The inline sine and cosine agree with libm's to 2e-7 over their quarter turn.
    #[test]
    fn sine_and_cosine_within_a_quarter_match_libm() {
        for i in -1000..=1000 {
            let a = std::f32::consts::FRAC_PI_4 * i as f32 / 1000.0;
            let (sin, cos) = sin_cos_within_quarter(a);
            assert!((sin - a.sin()).abs() <= 2e-7 && (cos - a.cos()).abs() <= 2e-7, "{a}: {sin} {cos}");
        }
    }

    #[test]
    fn pass_samples_are_stratified() {
        let mut samples: Vec<f32> = (0..64).map(|i| pass_sample(1, i)).collect();
        samples.sort_by(f32::total_cmp);
        let largest_gap = samples.windows(2).map(|w| w[1] - w[0]).fold(0.0, f32::max);
        assert!(largest_gap < 3.0 / 64.0, "{largest_gap}");
    }

    #[test]
    fn two_dimensional_samples_have_the_density_they_report() {
        let weights = [1.0, 2.0, 0.0, 4.0, 1.0, 3.0];
        let d = Distribution2D::new(&weights, 3);
        for u in [Vec2::new(0.1, 0.2), Vec2::new(0.7, 0.9), Vec2::new(0.5, 0.5)] {
            let (point, pdf) = d.sample(u).unwrap();
            assert!((pdf - d.pdf(point)).abs() < 1e-4, "{point}: {pdf} vs {}", d.pdf(point));
        }
        // Cell (2, 0) has weight 0 of 11 and cell (0, 1) has 4 of 11; 6 cells.
        assert_eq!(d.pdf(Vec2::new(0.9, 0.1)), 0.0);
        assert!((d.pdf(Vec2::new(0.1, 0.9)) - 4.0 / 11.0 * 6.0).abs() < 1e-5);
    }

    #[test]
    fn distribution_picks_by_weight() {
        let d = Distribution1D::new([1.0, 0.0, 3.0]);
        assert_eq!(d.sample(0.1), Some((0, 0.25)));
        assert_eq!(d.sample(0.5), Some((2, 0.75)));
        assert!(Distribution1D::new([0.0]).sample(0.5).is_none());
    }
}
