//! The world: light arriving from every direction, uniform or from an equirectangular image.
//!
//! Images are mapped as Blender maps an Environment Texture: the image's centre column faces
//! Blender's +x (glTF +x), its top row is straight up, and `rotation_deg` turns it about the up
//! axis. Each texel's colour becomes a smooth spectrum through [`IlluminantTable`]; directions are
//! importance-sampled by luminance times sin(theta) (pbrt-v4's image infinite light), the luminance
//! averaged over each texel's cell as the image is interpolated ([`cell_means`]).

use std::f32::consts::PI;
use std::path::Path;
use std::sync::Arc;

use glam::{Vec2, Vec3, Vec4};

use super::BoundingSphere;
use crate::sampling::{square_to_sphere, Distribution2D};
use crate::spectrum::{rgb::IlluminantTable, RgbSpectrum, Rows, SampledSpectrum, SpectrumImage, Wavelengths};

/// The world's light.
#[derive(Clone, Debug)]
pub struct World {
    /// Uniform radiance (times D65), or the image's strength as a constant.
    scale: RgbSpectrum,
    /// The environment image, if any.
    map: Option<Arc<EnvironmentMap>>,
    /// Where its photons start.
    pub sphere: BoundingSphere,
}

/// An equirectangular image of spectra with its sampling distribution.
pub struct EnvironmentMap {
    image: SpectrumImage,
    distribution: Distribution2D,
    rotation: f32,
    /// Luminance integrated over the sphere of directions.
    luminance_over_sphere: f64,
}

impl std::fmt::Debug for EnvironmentMap {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let (width, height) = self.image.size();
        write!(f, "EnvironmentMap({width}x{height})")
    }
}

impl World {
    /// The same radiance (linear Rec.709 colour, W / (m^2 sr) for white) from every direction.
    pub fn uniform(colour: Vec3) -> Self {
        World { scale: RgbSpectrum::illuminant(colour), map: None, sphere: BoundingSphere::default() }
    }

    /// An equirectangular `.hdr` or `.exr` image times `strength`, turned by `rotation_deg`.
    pub fn from_image(path: &Path, strength: f32, rotation_deg: f32) -> Result<Self, String> {
        let image = image::open(path)
            .map_err(|e| format!("cannot read environment image {}: {e}", path.display()))?;
        let image = image.into_rgb32f();
        let (width, height) = (image.width() as usize, image.height() as usize);
        if width == 0 || height == 0 {
            return Err(format!("environment image {} has no pixels", path.display()));
        }
        // Checked before negatives are clamped, which would turn a NaN into a black texel.
        if image.pixels().any(|p| !Vec3::from(p.0).is_finite()) {
            return Err(format!("environment image {} has non-finite pixels", path.display()));
        }
        let pixels: Vec<Vec3> = image.pixels().map(|p| Vec3::from(p.0).max(Vec3::ZERO)).collect();
        let map = EnvironmentMap::new(width, height, &pixels, rotation_deg.to_radians());
        Ok(World {
            scale: RgbSpectrum::constant(strength.max(0.0)),
            map: Some(Arc::new(map)),
            sphere: Default::default(),
        })
    }

    /// Spectral radiance arriving along `-dir`, seen by a ray of direction `dir`.
    pub fn radiance(&self, dir: Vec3, lambda: &Wavelengths) -> SampledSpectrum {
        let base = self.scale.eval_lanes(lambda.nm) * lambda.d65;
        match &self.map {
            None => base,
            Some(map) => base * map.eval(dir, lambda.nm),
        }
    }

    /// A direction light arrives from, with its density per solid angle.
    pub fn sample_direction(&self, u: Vec2) -> Option<(Vec3, f32)> {
        match &self.map {
            None => Some((square_to_sphere(u), 1.0 / (4.0 * PI))),
            Some(map) => map.sample(u),
        }
    }

    /// The density per solid angle of [`World::sample_direction`] for `dir`.
    pub fn pdf(&self, dir: Vec3) -> f32 {
        match &self.map {
            None => 1.0 / (4.0 * PI),
            Some(map) => map.pdf(dir),
        }
    }

    /// Luminance integrated over all directions, for choosing lights by power.
    pub fn luminance_over_sphere(&self) -> f64 {
        let sphere = self.map.as_ref().map_or(4.0 * std::f64::consts::PI, |m| m.luminance_over_sphere);
        self.scale.luminance() * sphere
    }
}

/// The mean over each texel's cell of `values` (row by row, `width` across) as [`SpectrumImage`]
/// interpolates them for [`Rows::Clamp`]: bilinearly between texel centres, wrapping across and
/// holding the edge rows. Over its own cell a texel's tent integrates to 3/4 in each axis and each
/// neighbour's to 1/8 (a held edge row counts as its own neighbour).
///
/// Directions are sampled in proportion to these means, not to the texels themselves: the radiance
/// a sampled direction reads is interpolated, so a bright texel (a sun baked into a sky) lights the
/// half of each neighbour's cell next to it, and sampling by texels would draw those directions as
/// rarely as the dark neighbour, weighting them by thousands. The means keep radiance over density
/// within 16 times its average for any image.
fn cell_means(values: &[f64], width: usize) -> Vec<f64> {
    let height = values.len() / width;
    let tent = |a: f64, b: f64, c: f64| (a + 6.0 * b + c) / 8.0;
    let across: Vec<f64> = (0..values.len())
        .map(|i| {
            let (row, x) = (i - i % width, i % width);
            tent(values[row + (x + width - 1) % width], values[i], values[row + (x + 1) % width])
        })
        .collect();
    (0..values.len())
        .map(|i| {
            let y = i / width;
            let above = across[i - width * usize::from(y > 0)];
            let below = across[i + width * usize::from(y + 1 < height)];
            tent(above, across[i], below)
        })
        .collect()
}

/// Polar angle from up and the image's horizontal coordinate of direction `dir` (glTF, y up).
fn direction_to_image(dir: Vec3, rotation: f32) -> Vec2 {
    // Blender's axes: x = glTF x, y = -glTF z, z = glTF y.
    let (bx, by, bz) = (dir.x, -dir.z, dir.y);
    let phi = by.atan2(bx) - rotation;
    let u = (0.5 - phi / (2.0 * PI)).rem_euclid(1.0);
    let theta = bz.clamp(-1.0, 1.0).acos();
    Vec2::new(u, theta / PI)
}

/// The inverse of [`direction_to_image`]: `point.y` is theta / pi (0 straight up).
fn image_to_direction(point: Vec2, rotation: f32) -> Vec3 {
    let phi = (0.5 - point.x) * 2.0 * PI + rotation;
    let theta = point.y * PI;
    let (bx, by, bz) = (theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos());
    Vec3::new(bx, bz, -by)
}

impl EnvironmentMap {
    fn new(width: usize, height: usize, pixels: &[Vec3], rotation: f32) -> Self {
        let table = IlluminantTable::get();
        let texels: Vec<RgbSpectrum> = pixels.iter().map(|&rgb| table.illuminant(rgb)).collect();
        let luminance: Vec<f64> =
            pixels.iter().map(|p| f64::from(0.2126 * p.x + 0.7152 * p.y + 0.0722 * p.z)).collect();
        let weights: Vec<f64> = cell_means(&luminance, width)
            .into_iter()
            .enumerate()
            .map(|(i, l)| l * (PI * ((i / width) as f32 + 0.5) / height as f32).sin() as f64)
            .collect();
        let texel_solid_angle = 2.0 * std::f64::consts::PI * std::f64::consts::PI / (width * height) as f64;
        let luminance_over_sphere = weights.iter().sum::<f64>() * texel_solid_angle;
        let distribution = Distribution2D::new(&weights, width);
        let image = SpectrumImage::new(width, height, texels);
        EnvironmentMap { image, distribution, rotation, luminance_over_sphere }
    }

    /// The image's value at four wavelengths (nm) toward `dir`, bilinearly interpolated (wrapping
    /// around).
    fn eval(&self, dir: Vec3, lambda_nm: Vec4) -> Vec4 {
        self.image.eval(direction_to_image(dir, self.rotation), Rows::Clamp, lambda_nm)
    }

    /// A direction by luminance, with its density per solid angle.
    fn sample(&self, u: Vec2) -> Option<(Vec3, f32)> {
        let (point, pdf_image) = self.distribution.sample(u)?;
        let sin_theta = (point.y * PI).sin();
        if sin_theta <= 0.0 {
            return None;
        }
        Some((image_to_direction(point, self.rotation), pdf_image / (2.0 * PI * PI * sin_theta)))
    }

    fn pdf(&self, dir: Vec3) -> f32 {
        let point = direction_to_image(dir, self.rotation);
        let sin_theta = (point.y * PI).sin();
        if sin_theta <= 0.0 {
            return 0.0;
        }
        self.distribution.pdf(point) / (2.0 * PI * PI * sin_theta)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn image_coordinates_round_trip_and_face_blender_axes() {
        for dir in [Vec3::new(0.3, 0.5, -0.81), Vec3::new(-0.7, -0.1, 0.7), Vec3::new(0.0, 0.2, 0.98)] {
            let dir = dir.normalize();
            let back = image_to_direction(direction_to_image(dir, 0.4), 0.4);
            assert!((back - dir).length() < 1e-5, "{dir} came back as {back}");
        }
        // Up is the top row; glTF +x (Blender +x) is the centre column.
        assert!(direction_to_image(Vec3::Y, 0.0).y < 1e-6);
        assert!((direction_to_image(Vec3::X, 0.0) - Vec2::new(0.5, 0.5)).length() < 1e-6);
    }

    #[test]
    fn sampled_directions_have_the_density_they_report() {
        let (w, h) = (16, 8);
        let pixels: Vec<Vec3> = (0..w * h).map(|i| Vec3::splat(1.0 + (i % 7) as f32)).collect();
        let map = EnvironmentMap::new(w, h, &pixels, 0.3);
        // The density integrates to 1 over the sphere (uniform directions, Monte Carlo).
        let n = 20000;
        let integral: f32 = (0..n)
            .map(|i| {
                let u = Vec2::new((i as f32 + 0.5) / n as f32, ((i * 7919) % n) as f32 / n as f32);
                map.pdf(square_to_sphere(u)) * 4.0 * PI / n as f32
            })
            .sum();
        assert!((integral - 1.0).abs() < 0.02, "{integral}");
        let (dir, pdf) = map.sample(Vec2::new(0.37, 0.61)).unwrap();
        assert!((pdf / map.pdf(dir) - 1.0).abs() < 1e-3);
    }

    /// A sun baked into one texel of a dark sky: every sampled direction's radiance over its
    /// density (a photon's flux, a light sample's weight) stays within 16 times their mean (the
    /// corner of a diagonal neighbour's cell reads a quarter of the sun, whose mean over that cell
    /// is a 64th), where the interpolated sun spilling into its dark neighbours' cells made it
    /// thousands.
    #[test]
    fn a_one_texel_sun_weights_no_direction_by_thousands() {
        let (w, h) = (32, 16);
        let mut pixels = vec![Vec3::splat(0.5); w * h];
        pixels[5 * w + 10] = Vec3::splat(2.0e4);
        let map = EnvironmentMap::new(w, h, &pixels, 0.0);
        let n = 256;
        let weights: Vec<f32> = (0..n * n)
            .filter_map(|i| map.sample(Vec2::new((i % n) as f32 + 0.5, (i / n) as f32 + 0.5) / n as f32))
            .map(|(dir, pdf)| map.eval(dir, Vec4::splat(550.0)).x / pdf)
            .collect();
        let mean = weights.iter().sum::<f32>() / weights.len() as f32;
        let max = weights.iter().cloned().fold(0.0, f32::max);
        assert!(max < 16.5 * mean, "the largest weight is {}x the mean", max / mean);
    }

    #[test]
    fn cell_means_integrate_the_interpolated_image() {
        // One bright texel among zeros: 3/4 of it stays in its cell in each axis, 1/8 spills to
        // each neighbour (wrapping across), and a held edge row keeps its outer eighth.
        let mut values = vec![0.0; 4 * 3];
        values[4 + 3] = 64.0;
        let means = cell_means(&values, 4);
        assert_eq!(means[4 + 3], 36.0);
        assert_eq!([means[4 + 2], means[4], means[3], means[8 + 3]], [6.0; 4]);
        assert_eq!([means[0], means[2], means[8 + 1]], [1.0, 1.0, 0.0]);
        let mut top = vec![0.0; 4 * 3];
        top[1] = 64.0;
        assert_eq!(cell_means(&top, 4)[1], 42.0);
        assert_eq!(means.iter().sum::<f64>(), 64.0);
    }
}
