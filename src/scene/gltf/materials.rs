//! glTF materials into Caustic materials: metallic-roughness, the specular layer, transmission,
//! the index of refraction and its dispersion law, emission, and the base-colour,
//! metallic-roughness and normal textures, and the clear coat.

use std::sync::Arc;

use glam::Vec3;

use super::textures::{info_map, normal_map, raw_info, Images};
use crate::scene::extras::{self, MaterialExtras, MediumExtras};
use gltf::material::AlphaMode;

use crate::materials::{
    Alpha, BaseColour, Clearcoat, Coverage, Material, NormalMap, Sheen, Specular, Volume,
};
use crate::spectrum::{Dispersion, Illuminant, RgbSpectrum};
use crate::texture::{DataTexture, Rgba, Texture, TextureMap};

/// A glTF material as a Caustic material.
pub fn material(m: &gltf::Material, document: &gltf::Document, images: &Images) -> Result<Material, String> {
    let name = m.name().unwrap_or("unnamed").to_string();
    let pbr = m.pbr_metallic_roughness();
    let factor = Vec3::from_slice(&pbr.base_color_factor()[..3]);
    let in_material = |e: String| format!("material '{name}': {e}");
    let image = |texture: gltf::Texture| images.of(&texture);
    let base_colour = match pbr.base_color_texture().and_then(|i| Some((info_map(&i)?, i))) {
        Some((map, info)) => {
            BaseColour::Texture(Arc::new(Texture::reflectance(image(info.texture()), map, factor)))
        }
        None => BaseColour::Constant(RgbSpectrum::reflectance(factor)),
    };
    let metallic_roughness = match pbr.metallic_roughness_texture().and_then(|i| Some((info_map(&i)?, i))) {
        Some((map, info)) => Some(Arc::new(DataTexture::new(image(info.texture()), map))),
        None => None,
    };
    let coverage = || -> Result<Coverage, String> {
        let texture = match pbr.base_color_texture().and_then(|i| Some((info_map(&i)?, i))) {
            Some((map, info)) => Some(Arc::new(DataTexture::new(image(info.texture()), map))),
            None => None,
        };
        Ok(Coverage { factor: pbr.base_color_factor()[3].clamp(0.0, 1.0), texture })
    };
    let alpha = match m.alpha_mode() {
        AlphaMode::Opaque => Alpha::Opaque,
        AlphaMode::Mask => Alpha::Mask { cutoff: m.alpha_cutoff().unwrap_or(0.5), coverage: coverage()? },
        AlphaMode::Blend => Alpha::Blend { coverage: coverage()? },
    };
    let extras: MaterialExtras =
        extras::parse(m.extras()).map_err(|e| in_material(format!("extras `caustic`: {e}")))?;
    let normal_strength = extras.normal_map_strength.filter(|s| s.is_finite()).map_or(1.0, |s| s.max(0.0));
    let normal_map = match m.normal_texture().and_then(|n| Some((normal_map(&n)?, n))) {
        Some((map, normal)) => Some(NormalMap {
            strength: normal_strength,
            texture: Arc::new(DataTexture::new(image(normal.texture()), map)),
            scale: if normal.scale().is_finite() { normal.scale() } else { 1.0 },
        }),
        None => None,
    };
    let emission = Vec3::from(m.emissive_factor()) * m.emissive_strength().unwrap_or(1.0);
    let emission_texture = match m.emissive_texture().and_then(|i| Some((info_map(&i)?, i))) {
        Some((map, info)) if emission.max_element() > 0.0 => {
            Some(Arc::new(Texture::emission(image(info.texture()), map, emission)))
        }
        _ => None,
    };
    let specular = specular(m, &image);
    let clearcoat = clearcoat(m, document, images).map_err(in_material)?;
    let sheen = sheen(m, document, images).map_err(in_material)?;
    let volume = match &extras.medium {
        Some(extras) => Some(medium(extras).map_err(|e| in_material(format!("extras `caustic.medium.{e}")))?),
        None => volume(m).map_err(in_material)?,
    };
    let ior = dispersion_law(m, &extras).map_err(in_material)?;
    if extras.holdout {
        // Blender's Holdout shader: black wherever it is not a hole in the film.
        let black = BaseColour::Constant(RgbSpectrum::constant(0.0));
        return Ok(Material { name, holdout: true, base_colour: black, ..Material::default_grey() });
    }
    Ok(Material {
        ior,
        volume,
        priority: extras.priority.unwrap_or(0),
        clearcoat,
        sheen,
        specular,
        name,
        base_colour,
        metallic_roughness,
        normal_map,
        alpha,
        metallic: pbr.metallic_factor().clamp(0.0, 1.0),
        roughness: pbr.roughness_factor().clamp(0.0, 1.0),
        transmission: m.transmission().map_or(0.0, |t| t.transmission_factor()).clamp(0.0, 1.0),
        emission_texture,
        emission: (emission.max_element() > 0.0).then(|| Illuminant::d65(emission)),
        emits_both_sides: true,
        emission_spread: None,
        thin: false,
        holdout: false,
        seen_by_camera: true,
        light_surface: false,
        reads_vertex_colours: extras.vertex_colours.unwrap_or(true),
    })
}

/// The specular layer: the index with `KHR_materials_specular`'s factor and colour and their
/// textures (`image` decodes a texture's image), or `None` for a factor of 0.
fn specular<'a>(m: &gltf::Material<'a>, image: &dyn Fn(gltf::Texture<'a>) -> &'a Rgba) -> Option<Specular> {
    let ext = m.specular();
    let factor = ext.as_ref().map_or(1.0, |s| s.specular_factor()).clamp(0.0, 1.0);
    let colour = ext.as_ref().map_or(Vec3::ONE, |s| Vec3::from(s.specular_color_factor())).max(Vec3::ZERO);
    let mut layer = Specular::new(m.ior().unwrap_or(1.5), factor, colour)?;
    let Some(ext) = ext else {
        return Some(layer);
    };
    if let Some((map, info)) = ext.specular_texture().and_then(|i| Some((info_map(&i)?, i))) {
        layer.factor_texture = Some(Arc::new(DataTexture::new(image(info.texture()), map)));
    }
    if let Some((map, info)) = ext.specular_color_texture().and_then(|i| Some((info_map(&i)?, i))) {
        layer.colour_texture = Some(Arc::new(Texture::reflectance(image(info.texture()), map, Vec3::ONE)));
    }
    Some(layer)
}

/// `KHR_materials_clearcoat` (read raw: the gltf crate does not type it), or `None` without a
/// coat.
fn clearcoat(
    m: &gltf::Material,
    document: &gltf::Document,
    images: &Images,
) -> Result<Option<Clearcoat>, String> {
    const EXTENSION: &str = "KHR_materials_clearcoat";
    let Some(value) = m.extension_value(EXTENSION) else {
        return Ok(None);
    };
    let factor = unit_factor(value, "clearcoatFactor", 0.0);
    if factor <= 0.0 {
        return Ok(None);
    }
    let texture = |key: &str| {
        let texture = raw_texture(EXTENSION, value, key, document, images)?;
        Ok::<_, String>(texture.map(|(image, map, scale)| (Arc::new(DataTexture::new(image, map)), scale)))
    };
    let texture_only = |key: &str| texture(key).map(|t| t.map(|(texture, _)| texture));
    Ok(Some(Clearcoat {
        factor,
        factor_texture: texture_only("clearcoatTexture")?,
        roughness: unit_factor(value, "clearcoatRoughnessFactor", 0.0),
        roughness_texture: texture_only("clearcoatRoughnessTexture")?,
        normal_map: texture("clearcoatNormalTexture")?.map(|(texture, scale)| NormalMap {
            texture,
            scale,
            strength: 1.0,
        }),
    }))
}

/// An extension's texture reference `key` in `value`: its decoded image and where it reads, or
/// `None` when absent or on a texture coordinate set Caustic does not carry (warned).
fn raw_texture<'a>(
    extension: &str,
    value: &serde_json::Value,
    key: &str,
    document: &gltf::Document,
    images: &'a Images,
) -> Result<Option<(&'a Rgba, TextureMap, f32)>, String> {
    let in_key = |e: String| format!("{extension}.{key}: {e}");
    let Some(info) = raw_info(document, &value[key]).map_err(in_key)? else { return Ok(None) };
    let Some(map) = info.map else { return Ok(None) };
    Ok(Some((images.of(&info.texture), map, info.scale)))
}

/// A factor in [0, 1] at `key` in `value`, `default` when absent or not a finite number.
fn unit_factor(value: &serde_json::Value, key: &str, default: f32) -> f32 {
    match value[key].as_f64().map(|v| v as f32) {
        Some(v) if v.is_finite() => v.clamp(0.0, 1.0),
        _ => default,
    }
}

/// `KHR_materials_sheen` (read raw), or `None` without a sheen or with a black one.
fn sheen(m: &gltf::Material, document: &gltf::Document, images: &Images) -> Result<Option<Sheen>, String> {
    const EXTENSION: &str = "KHR_materials_sheen";
    let Some(value) = m.extension_value(EXTENSION) else {
        return Ok(None);
    };
    let factor = Vec3::from_array([0, 1, 2].map(|i| {
        let v = value["sheenColorFactor"][i].as_f64().unwrap_or(0.0) as f32;
        if v.is_finite() {
            v.clamp(0.0, 1.0)
        } else {
            0.0
        }
    }));
    if factor.max_element() <= 0.0 {
        return Ok(None);
    }
    let texture = |key: &str| raw_texture(EXTENSION, value, key, document, images);
    Ok(Some(Sheen {
        colour: RgbSpectrum::reflectance(factor),
        colour_texture: texture("sheenColorTexture")?
            .map(|(image, map, _)| Arc::new(Texture::reflectance(image, map, factor))),
        roughness: unit_factor(value, "sheenRoughnessFactor", 0.0),
        roughness_texture: texture("sheenRoughnessTexture")?
            .map(|(image, map, _)| Arc::new(DataTexture::new(image, map))),
    }))
}

/// `KHR_materials_volume` (read raw, so that values the gltf crate lets through are refused here
/// by name), or `None` where nothing is absorbed: without the
/// extension, without an attenuation distance (glTF's default: infinite), with a white colour,
/// or with a thickness factor of 0, which glTF reads as a thin wall without a volume (warned of
/// by `unrendered`).
fn volume(m: &gltf::Material) -> Result<Option<Volume>, String> {
    const EXTENSION: &str = "KHR_materials_volume";
    let Some(value) = m.extension_value(EXTENSION) else {
        return Ok(None);
    };
    let number = |key: &str| match &value[key] {
        serde_json::Value::Null => Ok(None),
        v => v.as_f64().map(Some).ok_or_else(|| format!("{EXTENSION}.{key}: expected a number, got {v}")),
    };
    let thickness = number("thicknessFactor")?.unwrap_or(0.0);
    if !(thickness >= 0.0) {
        return Err(format!("{EXTENSION}.thicknessFactor: expected 0 or more, got {thickness}"));
    }
    let distance = number("attenuationDistance")?;
    if let Some(d) = distance.filter(|&d| !(d > 0.0)) {
        return Err(format!("{EXTENSION}.attenuationDistance: expected a positive distance, got {d}"));
    }
    let colour = match &value["attenuationColor"] {
        serde_json::Value::Null => Vec3::ONE,
        v => unit_colour(v).ok_or_else(|| {
            format!("{EXTENSION}.attenuationColor: expected three numbers in [0, 1], got {v}")
        })?,
    };
    let distance = distance.map_or(f32::INFINITY, |d| d as f32);
    let absorbs = distance.is_finite() && colour != Vec3::ONE && thickness > 0.0;
    Ok(absorbs.then(|| Volume::new(colour, distance, thickness as f32)))
}

/// The homogeneous medium `extras` describe; an error names the field (`scattering`: ...).
pub fn medium(extras: &MediumExtras) -> Result<Volume, String> {
    let coefficient = |name: &str, rgb: [f32; 3]| {
        if rgb.iter().all(|c| c.is_finite() && *c >= 0.0) {
            Ok(Vec3::from(rgb))
        } else {
            Err(format!("{name}`: expected three finite numbers of 0 or more, got {rgb:?}"))
        }
    };
    let absorption = coefficient("absorption", extras.absorption)?;
    let scattering = coefficient("scattering", extras.scattering)?;
    let g = extras.anisotropy;
    if !(g.abs() < 1.0) {
        return Err(format!("anisotropy`: expected a number between -1 and 1 (not either), got {g}"));
    }
    Ok(Volume::medium(absorption, scattering, g, 0.0))
}

/// A JSON array of three numbers in [0, 1], as a colour.
fn unit_colour(value: &serde_json::Value) -> Option<Vec3> {
    let array = value.as_array().filter(|a| a.len() == 3)?;
    let channel = |i: usize| array[i].as_f64().filter(|c| (0.0..=1.0).contains(c)).map(|c| c as f32);
    Some(Vec3::new(channel(0)?, channel(1)?, channel(2)?))
}

/// The material's index against wavelength: the `caustic` extras first, then
/// `KHR_materials_dispersion` (read raw: the gltf crate does not type it), then a constant.
fn dispersion_law(m: &gltf::Material, extras: &MaterialExtras) -> Result<Dispersion, String> {
    let n_d = m.ior().unwrap_or(1.5);
    if let Some(name) = &extras.glass {
        return Dispersion::glass(name).ok_or_else(|| {
            format!(
                "extras `caustic.glass`: unknown glass '{name}' (the catalogue has {})",
                Dispersion::glass_names().join(", ")
            )
        });
    }
    if let Some(s) = &extras.sellmeier {
        if s.b.len() != s.c.len() || s.b.is_empty() || s.b.len() > 4 {
            return Err(
                "extras `caustic.sellmeier`: `b` and `c` need the same number of terms, 1 to 4".into()
            );
        }
        let (mut b, mut c) = ([0.0; 4], [0.0; 4]);
        b[..s.b.len()].copy_from_slice(&s.b);
        c[..s.c.len()].copy_from_slice(&s.c);
        return Ok(Dispersion::Sellmeier { b, c });
    }
    if let Some(table) = &extras.ior_table {
        return Dispersion::table(table.iter().map(|&[l, n]| (l, n)).collect())
            .map_err(|e| format!("extras `caustic.ior_table`: {e}"));
    }
    let khr = m.extension_value("KHR_materials_dispersion").and_then(|v| v["dispersion"].as_f64());
    let v_d = match (extras.abbe, khr) {
        (Some(v_d), _) if v_d > 0.0 => Some(v_d),
        (Some(v_d), _) => {
            return Err(format!("extras `caustic.abbe`: expected a positive Abbe number, got {v_d}"))
        }
        (None, Some(dispersion)) if dispersion > 0.0 => Some((20.0 / dispersion) as f32),
        _ => None,
    };
    Ok(match v_d {
        Some(v_d) => Dispersion::Abbe { n_d, v_d },
        None => Dispersion::Constant(n_d),
    })
}
