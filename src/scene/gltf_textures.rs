//! glTF textures into Caustic textures: decoded images (8- and 16-bit, float), the texture
//! coordinate set, `KHR_texture_transform` and the sampler's wrap modes and filter (NEAREST or
//! linear; minification filters are not needed: a pass's pixel samples average the footprint).

use glam::{Vec2, Vec4};
use gltf::image::Format;
use gltf::texture::WrappingMode;

use crate::texture::{Rgba, TextureMap, Wrap, UV_SETS};

/// A decoded image as RGBA in [0, 1] (grey images' value in R, G and B; alpha 1 where absent).
pub fn decode(image: &gltf::image::Data) -> Result<Rgba, String> {
    let (channels, bits) = match image.format {
        Format::R8 => (1, 8),
        Format::R8G8 => (2, 8),
        Format::R8G8B8 => (3, 8),
        Format::R8G8B8A8 => (4, 8),
        Format::R16 => (1, 16),
        Format::R16G16 => (2, 16),
        Format::R16G16B16 => (3, 16),
        Format::R16G16B16A16 => (4, 16),
        Format::R32G32B32FLOAT => (3, 32),
        Format::R32G32B32A32FLOAT => (4, 32),
    };
    let values: Vec<f32> = match bits {
        8 => image.pixels.iter().map(|&v| f32::from(v) / 255.0).collect(),
        16 => image
            .pixels
            .chunks_exact(2)
            .map(|b| f32::from(u16::from_ne_bytes([b[0], b[1]])) / 65535.0)
            .collect(),
        _ => image.pixels.chunks_exact(4).map(|b| f32::from_ne_bytes([b[0], b[1], b[2], b[3]])).collect(),
    };
    let (width, height) = (image.width as usize, image.height as usize);
    if width == 0 || height == 0 || values.len() != width * height * channels {
        return Err(format!("an image of {width} x {height} texels holds {} values", values.len()));
    }
    let texels = values
        .chunks_exact(channels)
        .map(|c| {
            let at = |i: usize| if c[i].is_finite() { c[i] } else { 0.0 };
            match channels {
                1 => Vec4::new(at(0), at(0), at(0), 1.0),
                2 => Vec4::new(at(0), at(0), at(0), at(1)),
                3 => Vec4::new(at(0), at(1), at(2), 1.0),
                _ => Vec4::new(at(0), at(1), at(2), at(3)),
            }
        })
        .collect();
    Ok(Rgba { width, height, texels, bits: bits.min(16) })
}

fn wrap(mode: WrappingMode) -> Wrap {
    match mode {
        WrappingMode::Repeat => Wrap::Repeat,
        WrappingMode::ClampToEdge => Wrap::Clamp,
        WrappingMode::MirroredRepeat => Wrap::Mirror,
    }
}

/// `KHR_texture_transform`'s fields: offset, rotation, scale, and the set it overrides.
struct Transform {
    offset: [f32; 2],
    rotation: f32,
    scale: [f32; 2],
    set: Option<u32>,
}

/// The raw extension (texture infos the gltf crate does not type, such as normal textures').
fn raw_transform(value: &serde_json::Value) -> Transform {
    let pair = |key: &str, default: f32| {
        let v = &value[key];
        [0, 1].map(|i| v[i].as_f64().map_or(default, |x| x as f32))
    };
    Transform {
        offset: pair("offset", 0.0),
        rotation: value["rotation"].as_f64().unwrap_or(0.0) as f32,
        scale: pair("scale", 1.0),
        set: value["texCoord"].as_u64().map(|s| s.min(u64::from(u32::MAX)) as u32),
    }
}

/// Where a texture reference reads: its set (overridden by the transform's), transform and wrap
/// modes. `None` when the set is one Caustic does not carry (the caller warns).
fn map(texture: &gltf::Texture, set: u32, transform: Option<Transform>) -> Option<TextureMap> {
    let sampler = texture.sampler();
    let set = transform.as_ref().and_then(|t| t.set).unwrap_or(set) as usize;
    let finite =
        |t: &Transform| t.offset.iter().chain(&t.scale).all(|v| v.is_finite()) && t.rotation.is_finite();
    let transform = transform
        .filter(finite)
        .map(|t| TextureMap::transform(Vec2::from(t.offset), t.rotation, Vec2::from(t.scale)));
    let nearest = sampler.mag_filter() == Some(gltf::texture::MagFilter::Nearest);
    let wrap = [wrap(sampler.wrap_s()), wrap(sampler.wrap_t())];
    (set < UV_SETS).then_some(TextureMap { set, transform, wrap, nearest })
}

/// The map of a texture info (base colour, metallic-roughness, emissive, extensions' textures).
pub fn info_map(info: &gltf::texture::Info) -> Option<TextureMap> {
    let transform = info.texture_transform().map(|t| Transform {
        offset: t.offset(),
        rotation: t.rotation(),
        scale: t.scale(),
        set: t.tex_coord(),
    });
    map(&info.texture(), info.tex_coord(), transform)
}

/// The map of a normal texture.
pub fn normal_map(normal: &gltf::material::NormalTexture) -> Option<TextureMap> {
    let transform = normal.extension_value("KHR_texture_transform").map(raw_transform);
    map(&normal.texture(), normal.tex_coord(), transform)
}

/// A texture reference the gltf crate does not type (an extension's `...Texture` object).
pub struct RawInfo<'a> {
    /// The texture it names.
    pub texture: gltf::Texture<'a>,
    /// Where it reads, or `None` on a set Caustic does not carry.
    pub map: Option<TextureMap>,
    /// Its `scale` (normal textures'), 1 when absent.
    pub scale: f32,
}

/// The reference `value` (absent or null: `None`), its texture looked up in `document`.
pub fn raw_info<'a>(
    document: &'a gltf::Document,
    value: &serde_json::Value,
) -> Result<Option<RawInfo<'a>>, String> {
    if value.is_null() {
        return Ok(None);
    }
    let index = value["index"].as_u64().ok_or("a texture reference without a texture index")?;
    let texture = usize::try_from(index)
        .ok()
        .and_then(|i| document.textures().nth(i))
        .ok_or_else(|| format!("a texture reference to texture {index}, which the file does not have"))?;
    let transform = value["extensions"].get("KHR_texture_transform").map(raw_transform);
    let map = map(&texture, raw_set(value), transform);
    let scale = value["scale"].as_f64().map_or(1.0, |s| s as f32);
    Ok(Some(RawInfo { texture, map, scale: if scale.is_finite() { scale } else { 1.0 } }))
}

/// The texture coordinate set the reference `value` reads (its own `texCoord`, without the
/// transform's override, which [`map`] applies).
fn raw_set(value: &serde_json::Value) -> u32 {
    value["texCoord"].as_u64().map_or(0, |s| s.min(u64::from(u32::MAX)) as u32)
}

/// The texture coordinate set an untyped reference reads, with its transform's override.
pub fn raw_info_set(value: &serde_json::Value) -> u32 {
    let transform = value["extensions"].get("KHR_texture_transform").map(raw_transform);
    transform.and_then(|t| t.set).unwrap_or(raw_set(value))
}

/// The texture coordinate set a texture reads, with its transform's override.
pub fn info_set(info: &gltf::texture::Info) -> u32 {
    info.texture_transform().and_then(|t| t.tex_coord()).unwrap_or(info.tex_coord())
}

/// The texture coordinate set a normal texture reads, with its transform's override.
pub fn normal_set(normal: &gltf::material::NormalTexture) -> u32 {
    let transform = normal.extension_value("KHR_texture_transform").map(raw_transform);
    transform.and_then(|t| t.set).unwrap_or(normal.tex_coord())
}
