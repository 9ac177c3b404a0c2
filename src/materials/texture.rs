//! Base-colour textures: each texel's sRGB colour becomes a reflectance spectrum at load.
//!
//! Fitting a spectrum is slow, so texels share fits through a cache keyed by their 8-bit colour.
//! Lookups wrap (glTF's default REPEAT) and interpolate the spectra's values bilinearly, which
//! keeps the result inside [0, 1].

use std::collections::HashMap;

use glam::{Vec2, Vec3, Vec4};

use crate::spectrum::{RgbSpectrum, Rows, SpectrumImage};

/// A texture of reflectance spectra.
#[derive(Clone, Debug)]
pub struct Texture {
    image: SpectrumImage,
}

/// The sRGB transfer function, decoded to linear.
fn srgb_to_linear(c: u8) -> f32 {
    let c = f32::from(c) / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

impl Texture {
    /// A texture from 8-bit sRGB texels (`channels` per texel, 3 or 4) times the linear `factor`.
    pub fn from_srgb8(width: usize, height: usize, channels: usize, pixels: &[u8], factor: Vec3) -> Self {
        let mut cache: HashMap<[u8; 3], RgbSpectrum> = HashMap::new();
        let texels = pixels
            .chunks_exact(channels)
            .map(|p| {
                let key = [p[0], p[1], p[2]];
                *cache.entry(key).or_insert_with(|| {
                    let rgb = Vec3::from(key.map(srgb_to_linear)) * factor;
                    RgbSpectrum::reflectance(rgb)
                })
            })
            .collect();
        Texture { image: SpectrumImage::new(width, height, texels) }
    }

    /// The reflectance at texture coordinate `uv` and four wavelengths, nm.
    pub fn eval(&self, uv: Vec2, lambda_nm: Vec4) -> Vec4 {
        self.image.eval(uv, Rows::Wrap, lambda_nm)
    }
}
