//! RGB colours as smooth spectra: Jakob & Hanika 2019, "A Low-Dimensional Function Space for
//! Efficient Spectral Upsampling".
//!
//! A reflectance is `s(lambda) = sigmoid(c0 x^2 + c1 x + c2)` with `x` the wavelength mapped to
//! [0, 1] over 360..830 nm and `sigmoid(z) = 1/2 + z / (2 sqrt(1 + z^2))`, so it is smooth and
//! lies in [0, 1]. The coefficients are fitted by Newton's method so that the spectrum, lit by
//! D65, has the requested linear Rec.709 colour. Light colours (any non-negative RGB) are a
//! reflectance of `rgb / (2 max)` times `2 max`, times the D65 illuminant.

use glam::{DVec3, Vec2, Vec3, Vec4};

use super::tables::{cmf, d65, table_wavelengths, xyz_to_linear_rec709};

/// A smooth spectrum `scale * sigmoid(polynomial)`: a reflectance when `scale <= 1`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RgbSpectrum {
    coefficients: [f32; 3],
    scale: f32,
}

const LAMBDA_MIN_NM: f32 = 360.0;
const LAMBDA_RANGE_NM: f32 = 470.0;

fn sigmoid(z: f64) -> f64 {
    if z.is_infinite() {
        return if z > 0.0 { 1.0 } else { 0.0 };
    }
    0.5 + z / (2.0 * (1.0 + z * z).sqrt())
}

/// The sigmoid's inverse on (0, 1), for constant (grey) spectra.
fn inverse_sigmoid(s: f64) -> f64 {
    let w = 2.0 * s - 1.0;
    w / (1.0 - w * w).sqrt()
}

impl RgbSpectrum {
    /// A constant spectrum of value `value`.
    pub fn constant(value: f32) -> Self {
        RgbSpectrum { coefficients: [0.0, 0.0, f32::INFINITY], scale: value }
    }

    /// A reflectance whose colour under D65 is `rgb` (linear Rec.709, clamped to [0, 1]).
    pub fn reflectance(rgb: Vec3) -> Self {
        let rgb = rgb.clamp(Vec3::ZERO, Vec3::ONE);
        if rgb.max_element() - rgb.min_element() < 1e-6 {
            return Self::constant(rgb.x);
        }
        RgbSpectrum { coefficients: fit_coefficients(rgb.as_dvec3()), scale: 1.0 }
    }

    /// The spectral shape of a light of colour `rgb` (linear Rec.709, non-negative); multiply by
    /// [`super::d65`] to get the emitted spectrum.
    pub fn illuminant(rgb: Vec3) -> Self {
        let rgb = rgb.max(Vec3::ZERO);
        let max = rgb.max_element();
        if max - rgb.min_element() < 1e-6 * max.max(1e-30) {
            return Self::constant(max);
        }
        let shape = Self::reflectance(rgb / (2.0 * max));
        RgbSpectrum { scale: 2.0 * max, ..shape }
    }

    /// The spectrum's value at `lambda_nm`.
    pub fn eval(&self, lambda_nm: f32) -> f32 {
        self.eval_lanes(Vec4::splat(lambda_nm)).x
    }

    /// The spectrum's value at four wavelengths, nm.
    pub fn eval_lanes(&self, lambda_nm: Vec4) -> Vec4 {
        let [c0, c1, c2] = self.coefficients;
        if c2.is_infinite() {
            return Vec4::splat(self.scale);
        }
        let x = (lambda_nm - Vec4::splat(LAMBDA_MIN_NM)) / LAMBDA_RANGE_NM;
        let z = (x * c0 + Vec4::splat(c1)) * x + Vec4::splat(c2);
        let sigmoid = Vec4::splat(0.5) + z / (2.0 * (Vec4::ONE + z * z).map(f32::sqrt));
        self.scale * sigmoid
    }

    /// The luminance Y of the spectrum times D65 (1 for a constant spectrum of 1).
    pub fn luminance(&self) -> f64 {
        table_wavelengths().map(|l| f64::from(self.eval(l) * d65(l) * cmf(l).y)).sum()
    }

    /// The largest value the spectrum takes.
    pub fn max_value(&self) -> f32 {
        table_wavelengths().map(|l| self.eval(l)).fold(0.0, f32::max)
    }
}

/// Grid points per axis of [`IlluminantTable`].
const TABLE_SIZE: usize = 33;

/// Precomputed fits for light colours of any chromaticity (Jakob & Hanika's table, section 4):
/// for each channel that is the largest, a grid over the other two channels relative to it, each
/// entry the coefficients of the reflectance whose largest channel is 1/2. Looking up a colour
/// interpolates the coefficients bilinearly: thousands of times faster than a fit, for
/// environment images with millions of texels.
pub struct IlluminantTable {
    coefficients: Vec<[f32; 3]>,
}

impl IlluminantTable {
    /// The table, fitted once on first use (about 3,300 fits, in parallel).
    pub fn get() -> &'static IlluminantTable {
        static TABLE: std::sync::OnceLock<IlluminantTable> = std::sync::OnceLock::new();
        TABLE.get_or_init(|| {
            use rayon::prelude::*;
            let coefficients = (0..3 * TABLE_SIZE * TABLE_SIZE)
                .into_par_iter()
                .map(|k| {
                    let (largest, a, b) =
                        (k / (TABLE_SIZE * TABLE_SIZE), (k / TABLE_SIZE) % TABLE_SIZE, k % TABLE_SIZE);
                    let step = 1.0 / (TABLE_SIZE - 1) as f64;
                    fit_coefficients(Self::colour(largest, a as f64 * step, b as f64 * step) * 0.5)
                })
                .collect();
            IlluminantTable { coefficients }
        })
    }

    /// The colour whose channel `largest` is 1 and whose other two channels (in order) are `a`, `b`.
    fn colour(largest: usize, a: f64, b: f64) -> DVec3 {
        let mut rgb = [a, b];
        let mut full = [0.0; 3];
        full[largest] = 1.0;
        for (slot, value) in (0..3).filter(|&c| c != largest).zip(rgb.iter_mut()) {
            full[slot] = *value;
        }
        DVec3::from(full)
    }

    /// The spectral shape of a light of colour `rgb` (linear Rec.709, non-negative).
    pub fn illuminant(&self, rgb: Vec3) -> RgbSpectrum {
        let rgb = rgb.max(Vec3::ZERO);
        let max = rgb.max_element();
        if !(max > 0.0) || !max.is_finite() {
            return RgbSpectrum::constant(0.0);
        }
        let largest = if rgb.x == max {
            0
        } else if rgb.y == max {
            1
        } else {
            2
        };
        let others: Vec<f32> = (0..3).filter(|&c| c != largest).map(|c| rgb[c] / max).collect();
        let scale = (TABLE_SIZE - 1) as f32;
        let (x, y) = (others[0] * scale, others[1] * scale);
        let (i, j) = ((x as usize).min(TABLE_SIZE - 2), (y as usize).min(TABLE_SIZE - 2));
        let (tx, ty) = (x - i as f32, y - j as f32);
        let entry = |i: usize, j: usize| self.coefficients[(largest * TABLE_SIZE + i) * TABLE_SIZE + j];
        let mut coefficients = [0.0; 3];
        for (k, c) in coefficients.iter_mut().enumerate() {
            let top = entry(i, j)[k] * (1.0 - ty) + entry(i, j + 1)[k] * ty;
            let bottom = entry(i + 1, j)[k] * (1.0 - ty) + entry(i + 1, j + 1)[k] * ty;
            *c = top * (1.0 - tx) + bottom * tx;
        }
        RgbSpectrum { coefficients, scale: 2.0 * max }
    }
}

/// Linear Rec.709 colour of reflectance coefficients `c` under D65, with its Jacobian (columns
/// are d rgb / d c_k).
fn colour_and_jacobian(c: [f64; 3]) -> (DVec3, [DVec3; 3]) {
    let mut xyz = DVec3::ZERO;
    let mut d_xyz = [DVec3::ZERO; 3];
    for lambda in table_wavelengths() {
        let x = f64::from((lambda - LAMBDA_MIN_NM) / LAMBDA_RANGE_NM);
        let z = (c[0] * x + c[1]) * x + c[2];
        let weight = cmf(lambda).as_dvec3() * f64::from(d65(lambda));
        xyz += weight * sigmoid(z);
        let d_sigmoid = 0.5 / (1.0 + z * z).powf(1.5);
        for (k, power) in [x * x, x, 1.0].into_iter().enumerate() {
            d_xyz[k] += weight * d_sigmoid * power;
        }
    }
    (xyz_to_linear_rec709(xyz), d_xyz.map(xyz_to_linear_rec709))
}

/// Newton's method with step halving on the RGB residual, from a grey of the same mean.
fn fit_coefficients(target: DVec3) -> [f32; 3] {
    let mean = target.element_sum() / 3.0;
    let mut c = [0.0, 0.0, inverse_sigmoid(mean.clamp(1e-4, 1.0 - 1e-4))];
    let (mut rgb, mut jacobian) = colour_and_jacobian(c);
    for _ in 0..64 {
        let residual = rgb - target;
        if residual.abs().max_element() < 1e-7 {
            break;
        }
        let matrix = glam::DMat3::from_cols(jacobian[0], jacobian[1], jacobian[2]);
        if matrix.determinant().abs() < 1e-300 {
            break;
        }
        let step = matrix.inverse() * residual;
        let mut t = 1.0;
        loop {
            let trial = [c[0] - t * step.x, c[1] - t * step.y, c[2] - t * step.z];
            let (trial_rgb, trial_jacobian) = colour_and_jacobian(trial);
            if (trial_rgb - target).length() < residual.length() || t < 1e-3 {
                (c, rgb, jacobian) = (trial, trial_rgb, trial_jacobian);
                break;
            }
            t *= 0.5;
        }
    }
    c.map(|v| v as f32)
}

/// The linear Rec.709 colour of `spectrum` times D65 (what a white light reflects off it).
pub fn colour_under_d65(spectrum: &RgbSpectrum) -> Vec3 {
    colour_under_d65_of(|l| spectrum.eval(l))
}

/// The linear Rec.709 colour of the spectrum `value` (of the wavelength, nm) times D65.
pub fn colour_under_d65_of(value: impl Fn(f32) -> f32) -> Vec3 {
    let xyz: DVec3 = table_wavelengths().map(|l| cmf(l).as_dvec3() * f64::from(d65(l) * value(l))).sum();
    xyz_to_linear_rec709(xyz).as_vec3()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reflectances_round_trip_and_stay_bounded() {
        for rgb in [
            Vec3::splat(0.5),
            Vec3::new(0.8, 0.1, 0.1),
            Vec3::new(0.05, 0.6, 0.2),
            Vec3::new(0.1, 0.2, 0.9),
            Vec3::new(0.9, 0.9, 0.02),
            Vec3::new(0.01298, 0.04519, 0.71569),
        ] {
            let s = RgbSpectrum::reflectance(rgb);
            let back = colour_under_d65(&s);
            assert!((back - rgb).abs().max_element() < 2e-3, "{rgb} came back as {back}");
            assert!(s.max_value() <= 1.0);
            assert!(table_wavelengths().all(|l| s.eval(l) >= 0.0));
        }
    }

    #[test]
    fn the_illuminant_table_keeps_colours_within_two_percent() {
        let table = IlluminantTable::get();
        for rgb in
            [Vec3::new(4.0, 2.0, 1.0), Vec3::splat(3.0), Vec3::new(0.2, 0.5, 0.45), Vec3::new(0.1, 0.1, 0.3)]
        {
            let back = colour_under_d65(&table.illuminant(rgb));
            assert!((back - rgb).abs().max_element() < 0.02 * rgb.max_element(), "{rgb} came back as {back}");
        }
    }

    #[test]
    fn illuminants_keep_their_colour_and_scale() {
        let rgb = Vec3::new(4.0, 2.0, 1.0);
        let back = colour_under_d65(&RgbSpectrum::illuminant(rgb));
        assert!((back - rgb).abs().max_element() < 1e-2, "{back}");
    }
}

/// An image of spectra (a texture, an environment map), looked up with bilinear interpolation of
/// the spectra's values. Columns wrap around.
#[derive(Clone, Debug)]
pub struct SpectrumImage {
    width: usize,
    height: usize,
    texels: Vec<RgbSpectrum>,
}

/// What lies past an image's first and last rows.
#[derive(Clone, Copy, Debug)]
pub enum Rows {
    /// The image repeats (glTF's REPEAT).
    Wrap,
    /// The edge rows continue (the poles of an environment map).
    Clamp,
}

impl SpectrumImage {
    /// An image of `width` x `height` texels, row by row.
    pub fn new(width: usize, height: usize, texels: Vec<RgbSpectrum>) -> Self {
        SpectrumImage { width, height, texels }
    }

    /// Width and height in texels.
    pub fn size(&self) -> (usize, usize) {
        (self.width, self.height)
    }

    /// The value at image coordinates `point` (0 to 1 across and down; texel centres at half
    /// texels) and four wavelengths, nm.
    pub fn eval(&self, point: Vec2, rows: Rows, lambda_nm: Vec4) -> Vec4 {
        let last_row = (self.height - 1) as f32;
        let x = point.x * self.width as f32 - 0.5;
        let y = match rows {
            Rows::Wrap => point.y * self.height as f32 - 0.5,
            Rows::Clamp => (point.y * self.height as f32 - 0.5).clamp(0.0, last_row),
        };
        let (x0, y0) = (x.floor(), y.floor());
        let (tx, ty) = (x - x0, y - y0);
        let texel = |dx: i64, dy: i64| {
            let i = (x0 as i64 + dx).rem_euclid(self.width as i64) as usize;
            let j = match rows {
                Rows::Wrap => (y0 as i64 + dy).rem_euclid(self.height as i64),
                Rows::Clamp => (y0 as i64 + dy).min(self.height as i64 - 1),
            } as usize;
            self.texels[j * self.width + i].eval_lanes(lambda_nm)
        };
        let top = texel(0, 0) * (1.0 - tx) + texel(1, 0) * tx;
        let bottom = texel(0, 1) * (1.0 - tx) + texel(1, 1) * tx;
        top * (1.0 - ty) + bottom * ty
    }
}
