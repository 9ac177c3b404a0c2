//! glTF textures: where a surface point's texture coordinates land in an image (the texture
//! coordinate set, `KHR_texture_transform`, the sampler's wrap modes and filter) and what the
//! image holds there: spectra (colour textures, whose sRGB texels are fitted once at load, as
//! reflectances or as emission) or linear data (metallic-roughness, normals, alpha), interpolated
//! bilinearly. Materials read them at surface points, emitting triangles at the points they
//! sample.
//!
//! Texel (0, 0) is the image's top-left corner, at texture coordinates (0, 0): glTF's origin.

use std::collections::HashMap;

use glam::{Affine2, Vec2, Vec3, Vec4};

use crate::spectrum::RgbSpectrum;

/// Texture coordinate sets a surface carries.
pub const UV_SETS: usize = 2;

/// A sampler's wrap mode along one axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Wrap {
    /// The image repeats (glTF's default).
    Repeat,
    /// The edge texels continue.
    Clamp,
    /// The image repeats mirrored every other time.
    Mirror,
}

impl Wrap {
    /// Texel `i` of `n` along this axis.
    fn texel(self, i: i64, n: usize) -> usize {
        let n = n as i64;
        (match self {
            Wrap::Repeat => i.rem_euclid(n),
            Wrap::Clamp => i.clamp(0, n - 1),
            Wrap::Mirror => {
                let k = i.rem_euclid(2 * n);
                if k < n {
                    k
                } else {
                    2 * n - 1 - k
                }
            }
        }) as usize
    }
}

/// Where texture coordinates land in an image.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TextureMap {
    /// The texture coordinate set read (0 or 1).
    pub set: usize,
    /// `KHR_texture_transform` (translation * rotation * scale), if the file gives one.
    pub transform: Option<Affine2>,
    /// Wrap modes along u and v.
    pub wrap: [Wrap; 2],
    /// The nearest texel is read (the sampler's NEAREST filter; Blender's Closest) instead of
    /// the four around the point, interpolated.
    pub nearest: bool,
}

impl Default for TextureMap {
    fn default() -> Self {
        TextureMap { set: 0, transform: None, wrap: [Wrap::Repeat; 2], nearest: false }
    }
}

impl TextureMap {
    /// `KHR_texture_transform`'s matrix: translation by `offset`, rotation by `rotation` (radians,
    /// counter-clockwise in the image as displayed, so clockwise in uv), then scale.
    pub fn transform(offset: Vec2, rotation: f32, scale: Vec2) -> Affine2 {
        let (s, c) = rotation.sin_cos();
        let rotation = Affine2::from_cols_array(&[c, -s, s, c, 0.0, 0.0]);
        Affine2::from_translation(offset) * rotation * Affine2::from_scale(scale)
    }

    /// The four texels around `uvs[set]` (transformed) in a `width` x `height` image, and their
    /// bilinear weights.
    fn taps(&self, uvs: &[Vec2; UV_SETS], width: usize, height: usize) -> [(usize, f32); 4] {
        let uv = uvs[self.set];
        let uv = self.transform.map_or(uv, |t| t.transform_point2(uv));
        // Coordinates that are not finite (NaN from a degenerate file) read texel 0.
        let uv = if uv.is_finite() { uv } else { Vec2::ZERO };
        let (x, y) = (uv.x * width as f32 - 0.5, uv.y * height as f32 - 0.5);
        // The nearest texel is the first of four with all the weight, from half a texel on.
        let (x, y) = if self.nearest { ((x + 0.5).floor(), (y + 0.5).floor()) } else { (x, y) };
        let (x0, y0) = (x.floor(), y.floor());
        let (tx, ty) = (x - x0, y - y0);
        let (x0, y0) = (clamp_to_i64(x0), clamp_to_i64(y0));
        let column = |dx: i64| self.wrap[0].texel(x0.saturating_add(dx), width);
        let row = |dy: i64| self.wrap[1].texel(y0.saturating_add(dy), height) * width;
        [
            (row(0) + column(0), (1.0 - tx) * (1.0 - ty)),
            (row(0) + column(1), tx * (1.0 - ty)),
            (row(1) + column(0), (1.0 - tx) * ty),
            (row(1) + column(1), tx * ty),
        ]
    }
}

/// A float coordinate as an integer, NaN as 0 (a NaN coordinate reads texel 0, never past it).
fn clamp_to_i64(x: f32) -> i64 {
    if x.is_nan() {
        0
    } else {
        x.clamp(-1e15, 1e15) as i64
    }
}

/// How an image's texels encode their values.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Encoding {
    /// As glTF says for the slot that reads it: sRGB for colour, linear for data.
    AsGltfSays,
    /// sRGB wherever it is read (Blender's sRGB colour space; Cycles decodes it even as data).
    Srgb,
    /// Linear wherever it is read (Blender's Non-Color and Linear colour spaces).
    Linear,
}

/// An image decoded to RGBA, as stored (sRGB-encoded where `encoding` says so).
#[derive(Clone, Debug)]
pub struct Rgba {
    /// Width in texels.
    pub width: usize,
    /// Height in texels.
    pub height: usize,
    /// Texels row by row from the top.
    pub texels: Vec<Vec4>,
    /// Bits per channel (8 or 16).
    pub bits: u32,
    /// How the texels' colour channels encode their values (alpha is always linear).
    pub encoding: Encoding,
}

/// The sRGB transfer function, decoded to linear.
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// A texture of spectra: reflectances (base colour) or emission.
#[derive(Clone, Debug)]
pub struct Texture {
    map: TextureMap,
    width: usize,
    height: usize,
    texels: Vec<RgbSpectrum>,
}

impl Texture {
    /// Emission from sRGB texels times the linear `factor` (any non-negative colour: the
    /// spectra of lights, times D65 where they are read).
    pub fn emission(image: &Rgba, map: TextureMap, factor: Vec3) -> Self {
        Self::fitted(image, map, |rgb| RgbSpectrum::illuminant(rgb * factor))
    }

    /// Reflectances from sRGB texels times the linear `factor`. Fitting a spectrum is slow, so
    /// texels share fits through a cache keyed by their colour at the image's bit depth (at most
    /// 10 bits a channel, finer than 8-bit sRGB's steps).
    pub fn reflectance(image: &Rgba, map: TextureMap, factor: Vec3) -> Self {
        Self::fitted(image, map, |rgb| RgbSpectrum::reflectance((rgb * factor).clamp(Vec3::ZERO, Vec3::ONE)))
    }

    /// Spectra `fit` gives for the texels' linear colours, fitted once per colour at the
    /// image's bit depth (at most 10 bits a channel).
    fn fitted(image: &Rgba, map: TextureMap, fit: impl Fn(Vec3) -> RgbSpectrum) -> Self {
        let decode = if image.encoding == Encoding::Linear { |c: f32| c } else { srgb_to_linear };
        let levels = ((1u32 << image.bits.min(10)) - 1) as f32;
        let mut cache: HashMap<[u16; 3], RgbSpectrum> = HashMap::new();
        let texels = image
            .texels
            .iter()
            .map(|p| {
                let key = [p.x, p.y, p.z].map(|c| (c.clamp(0.0, 1.0) * levels).round() as u16);
                *cache
                    .entry(key)
                    .or_insert_with(|| fit(Vec3::from(key.map(|c| decode(f32::from(c) / levels)))))
            })
            .collect();
        Texture { map, width: image.width, height: image.height, texels }
    }

    /// The luminance of the texels' spectra under D65 at the surface's texture coordinates.
    pub fn luminance(&self, uvs: &[Vec2; UV_SETS]) -> f64 {
        let taps = self.map.taps(uvs, self.width, self.height);
        taps.iter().map(|&(i, w)| self.texels[i].luminance() * f64::from(w)).sum()
    }

    /// The value at the surface's texture coordinates and four wavelengths, nm.
    pub fn eval(&self, uvs: &[Vec2; UV_SETS], lambda_nm: Vec4) -> Vec4 {
        self.map
            .taps(uvs, self.width, self.height)
            .iter()
            .map(|&(i, w)| self.texels[i].eval_lanes(lambda_nm) * w)
            .sum()
    }
}

/// A texture of linear data: four channels in [0, 1] (metallic-roughness, normals, factors).
#[derive(Clone, Debug)]
pub struct DataTexture {
    map: TextureMap,
    width: usize,
    height: usize,
    texels: Vec<Vec4>,
}

impl DataTexture {
    /// The image's texels as they are stored (their colour channels decoded where the image is
    /// labelled sRGB, as Cycles reads it).
    pub fn new(image: &Rgba, map: TextureMap) -> Self {
        let texels = match image.encoding {
            Encoding::Srgb => image
                .texels
                .iter()
                .map(|t| Vec4::new(srgb_to_linear(t.x), srgb_to_linear(t.y), srgb_to_linear(t.z), t.w))
                .collect(),
            _ => image.texels.clone(),
        };
        DataTexture { map, width: image.width, height: image.height, texels }
    }

    /// The texture coordinate set it reads.
    pub fn set(&self) -> usize {
        self.map.set
    }

    /// The four channels at the surface's texture coordinates.
    pub fn eval(&self, uvs: &[Vec2; UV_SETS]) -> Vec4 {
        self.map.taps(uvs, self.width, self.height).iter().map(|&(i, w)| self.texels[i] * w).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(width: usize, height: usize, f: impl Fn(usize, usize) -> f32) -> Rgba {
        let texels = (0..width * height).map(|i| Vec4::splat(f(i % width, i / width))).collect();
        Rgba { width, height, texels, bits: 8, encoding: Encoding::AsGltfSays }
    }

    fn at(texture: &DataTexture, u: f32, v: f32) -> f32 {
        texture.eval(&[Vec2::new(u, v), Vec2::ZERO]).x
    }

    /// Texel centres read their own value; (0, 0) is the top-left texel.
    #[test]
    fn texel_centres_and_the_origin() {
        let t = DataTexture::new(&image(4, 2, |x, y| (10 * y + x) as f32), TextureMap::default());
        assert_eq!(at(&t, 0.125, 0.25), 0.0);
        assert_eq!(at(&t, 0.875, 0.25), 3.0);
        assert_eq!(at(&t, 0.375, 0.75), 11.0);
    }

    #[test]
    fn wrap_modes() {
        let ramp = image(4, 1, |x, _| x as f32);
        let with = |wrap| DataTexture::new(&ramp, TextureMap { wrap: [wrap; 2], ..Default::default() });
        assert_eq!(at(&with(Wrap::Repeat), 1.125, 0.5), 0.0);
        assert_eq!(at(&with(Wrap::Clamp), 1.125, 0.5), 3.0);
        assert_eq!(at(&with(Wrap::Clamp), -0.875, 0.5), 0.0);
        assert_eq!(at(&with(Wrap::Mirror), 1.125, 0.5), 3.0);
        assert_eq!(at(&with(Wrap::Mirror), 1.875, 0.5), 0.0);
    }

    /// `KHR_texture_transform`'s specification example: offset (0, 1), rotation pi/2 and scale
    /// (0.5, 0.5) take uv (1, 0) to (0, 0.5) and (0, 1) to (0.5, 1), and the second texture
    /// coordinate set is read where the map says.
    #[test]
    fn texture_transform_and_sets() {
        let t = TextureMap::transform(Vec2::new(0.0, 1.0), std::f32::consts::FRAC_PI_2, Vec2::splat(0.5));
        assert!(t.transform_point2(Vec2::new(1.0, 0.0)).abs_diff_eq(Vec2::new(0.0, 0.5), 1e-6));
        assert!(t.transform_point2(Vec2::new(0.0, 1.0)).abs_diff_eq(Vec2::new(0.5, 1.0), 1e-6));
        let ramp = image(4, 1, |x, _| x as f32);
        let second = DataTexture::new(&ramp, TextureMap { set: 1, ..Default::default() });
        assert_eq!(second.eval(&[Vec2::ZERO, Vec2::new(0.625, 0.5)]).x, 2.0);
    }

    #[test]
    fn the_nearest_filter_reads_one_texel() {
        let ramp = image(4, 1, |x, _| x as f32);
        let t = DataTexture::new(&ramp, TextureMap { nearest: true, ..Default::default() });
        assert_eq!(at(&t, 0.49, 0.5), 1.0);
        assert_eq!(at(&t, 0.51, 0.5), 2.0);
        assert_eq!(at(&t, 0.99, 0.5), 3.0);
    }

    #[test]
    fn nan_coordinates_read_inside_the_image() {
        let t = DataTexture::new(&image(2, 2, |_, _| 1.0), TextureMap::default());
        assert!(at(&t, f32::NAN, 1e30).is_finite());
    }
}
