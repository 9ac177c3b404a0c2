//! glTF textures into Caustic textures: decoded images (8- and 16-bit, float; PNG, JPEG and
//! WebP, a missing one magenta as in Cycles) with their colour spaces, the texture
//! coordinate set, `KHR_texture_transform` and the sampler's wrap modes and filter (NEAREST or
//! linear; minification filters are not needed: a pass's pixel samples average the footprint).

use std::path::Path;

use glam::{Vec2, Vec4};
use gltf::texture::WrappingMode;

use crate::texture::{Encoding, Rgba, TextureMap, Wrap, UV_SETS};

/// The file's images, decoded, with the colour space each is labelled with. An image that cannot
/// be read or decoded is shown as Cycles shows a missing image: magenta, with a warning that names
/// it.
pub struct Images {
    decoded: Vec<Option<Rgba>>,
    missing: Rgba,
}

/// Cycles' colour for a missing image.
const MISSING: Vec4 = Vec4::new(1.0, 0.0, 1.0, 1.0);

/// `EXT_texture_webp`: a texture's WebP image, in place of (or beside) its `source`.
pub const WEBP: &str = "EXT_texture_webp";

/// The `caustic` entry of an image's extras: the colour space Blender reads it in.
#[derive(Debug, Default, serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct ImageExtras {
    /// "srgb" or "linear"; without it, glTF's rule for the slot (colour sRGB, data linear).
    colour_space: Option<String>,
}

impl Images {
    /// Decodes `document`'s images (files relative to `base`, data URIs, buffer views), and says
    /// in `warnings` which cannot be read.
    pub fn load(
        document: &gltf::Document,
        base: &Path,
        buffers: &[gltf::buffer::Data],
        warnings: &mut Vec<String>,
    ) -> Result<Self, String> {
        let mut decoded = Vec::new();
        for image in document.images() {
            let name = image.name().map_or(format!("image {}", image.index()), |n| format!("image '{n}'"));
            let extras: ImageExtras =
                super::extras::parse(image.extras()).map_err(|e| format!("{name}: extras `caustic`: {e}"))?;
            let encoding = match extras.colour_space.as_deref() {
                None => Encoding::AsGltfSays,
                Some("srgb") => Encoding::Srgb,
                Some("linear") => Encoding::Linear,
                Some(other) => {
                    return Err(format!(
                        "{name}: extras `caustic.colour_space` is '{other}' (srgb or linear)"
                    ))
                }
            };
            let read = encoded(&image, base, buffers).and_then(|(bytes, source)| {
                decode(&bytes).map_err(|e| format!("{source} cannot be decoded ({e})"))
            });
            match read {
                Ok(rgba) => decoded.push(Some(Rgba { encoding, ..rgba })),
                Err(why) => {
                    warnings.push(format!(
                        "{name}: {why}; it is rendered magenta, as Cycles renders a missing image"
                    ));
                    decoded.push(None);
                }
            }
        }
        let missing =
            Rgba { width: 1, height: 1, texels: vec![MISSING], bits: 8, encoding: Encoding::Linear };
        Ok(Images { decoded, missing })
    }

    /// The image `texture` shows: its WebP image where it has one (`EXT_texture_webp`), else its
    /// source; magenta where that image could not be read or there is none.
    pub fn of(&self, texture: &gltf::Texture) -> &Rgba {
        let webp = texture.extension_value(WEBP).and_then(|w| w["source"].as_u64()).map(|i| i as usize);
        let index = webp.or_else(|| texture.source().map(|s| s.index()));
        index.and_then(|i| self.decoded.get(i)?.as_ref()).unwrap_or(&self.missing)
    }
}

/// An image's encoded bytes and where they came from (for messages).
fn encoded(
    image: &gltf::Image,
    base: &Path,
    buffers: &[gltf::buffer::Data],
) -> Result<(Vec<u8>, String), String> {
    match image.source() {
        gltf::image::Source::View { view, .. } => {
            let buffer = &buffers[view.buffer().index()].0;
            let bytes = buffer.get(view.offset()..view.offset() + view.length());
            let bytes =
                bytes.ok_or_else(|| format!("buffer view {} lies outside its buffer", view.index()))?;
            Ok((bytes.to_vec(), format!("buffer view {}", view.index())))
        }
        gltf::image::Source::Uri { uri, .. } => match uri.strip_prefix("data:") {
            Some(data) => {
                use base64::Engine;
                let payload =
                    data.split_once(";base64,").map(|(_, b)| b).ok_or("a data URI that is not base64")?;
                let bytes = base64::engine::general_purpose::STANDARD
                    .decode(payload)
                    .map_err(|e| format!("a data URI that is not valid base64 ({e})"))?;
                Ok((bytes, "a data URI".into()))
            }
            None => {
                let file = urlencoding::decode(uri).map_or_else(|_| uri.to_string(), |f| f.into_owned());
                let path = base.join(&file);
                let bytes =
                    std::fs::read(&path).map_err(|e| format!("'{}' cannot be read ({e})", path.display()))?;
                Ok((bytes, format!("'{}'", path.display())))
            }
        },
    }
}

/// Encoded image bytes (PNG, JPEG, WebP; OpenEXR and Radiance HDR) as RGBA: grey images' value in
/// R, G and B, alpha 1 where absent, non-finite values as 0; 8-bit images in [0, 1] as 8-bit,
/// deeper ones as 16-bit.
pub fn decode(bytes: &[u8]) -> Result<Rgba, String> {
    let image = image::load_from_memory(bytes).map_err(|e| e.to_string())?;
    let (width, height) = (image.width() as usize, image.height() as usize);
    if width == 0 || height == 0 {
        return Err("the image has no texels".into());
    }
    let bits =
        if image.color().bytes_per_pixel() / image.color().channel_count().max(1) == 1 { 8 } else { 16 };
    let finite = |c: f32| if c.is_finite() { c } else { 0.0 };
    let texels = image.into_rgba32f().pixels().map(|p| Vec4::from(p.0.map(finite))).collect();
    Ok(Rgba { width, height, texels, bits, encoding: Encoding::AsGltfSays })
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
