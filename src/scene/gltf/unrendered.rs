//! What a glTF file holds that Caustic does not render, each named in a warning line for its
//! material, mesh or node, so that no difference from Blender is silent. (A required extension
//! Caustic cannot read is refused before this, by the gltf crate's validation.)
//!
//! Occlusion textures are not light transport and are ignored without a warning.

use super::textures::{info_set, normal_set, raw_info_set};
use crate::materials::Material;
use crate::texture::UV_SETS;

/// Material extensions Caustic renders.
const RENDERED_MATERIAL_EXTENSIONS: &[&str] = &[
    "KHR_materials_clearcoat",
    "KHR_materials_dispersion",
    "KHR_materials_emissive_strength",
    "KHR_materials_ior",
    "KHR_materials_sheen",
    "KHR_materials_specular",
    "KHR_materials_transmission",
    "KHR_materials_volume",
];

/// One line for each thing in material `m` (resolved as `loaded`) that is not rendered.
pub fn material_warnings(m: &gltf::Material, loaded: &Material) -> Vec<String> {
    let name = m.name().unwrap_or("unnamed");
    let mut unrendered: Vec<String> = m
        .extensions()
        .into_iter()
        .flat_map(|e| e.keys())
        .filter(|k| !RENDERED_MATERIAL_EXTENSIONS.contains(&k.as_str()))
        .map(|k| format!("{k} is not rendered"))
        .collect();
    unrendered.extend(unrendered_textures(m));
    unrendered.extend(unrendered_volume(m));
    unrendered.extend(unrendered_medium(m));
    unrendered.extend(unrendered_layered_emission(loaded));
    unrendered.into_iter().map(|what| format!("material '{name}': {what}")).collect()
}

/// What of `m`'s `KHR_materials_volume` is not rendered: absorption where glTF says there is no
/// volume (a thickness factor of 0: a thin wall) or where light never enters (no transmission),
/// and the thickness texture (the geometry gives the path length).
fn unrendered_volume(m: &gltf::Material) -> Vec<String> {
    let Some(volume) = m.extension_value("KHR_materials_volume") else {
        return Vec::new();
    };
    let absorbs = volume["attenuationDistance"].is_number()
        && volume["attenuationColor"].as_array().is_some_and(|c| c.iter().any(|v| v.as_f64() != Some(1.0)));
    let thickness = volume["thicknessFactor"].as_f64().unwrap_or(0.0);
    let transmits = m.transmission().is_some_and(|t| t.transmission_factor() > 0.0);
    let mut unrendered = Vec::new();
    if absorbs && thickness <= 0.0 {
        unrendered.push(
            "KHR_materials_volume's attenuation is not rendered: its thicknessFactor of 0 makes it a thin wall without a volume (glTF's reading)".to_string(),
        );
    } else if absorbs && !transmits {
        unrendered.push("KHR_materials_volume's attenuation is not rendered: light does not enter a material without transmission".into());
    }
    if volume.get("thicknessTexture").is_some() {
        unrendered.push("KHR_materials_volume's thicknessTexture is not read (a closed mesh's geometry gives the path length, a thin wall's thicknessFactor)".into());
    }
    unrendered
}

/// What of `m`'s `caustic` medium is not rendered: all of it where light never enters (no
/// transmission); and `KHR_materials_volume`'s attenuation, which the medium replaces.
fn unrendered_medium(m: &gltf::Material) -> Vec<String> {
    let has_medium = m
        .extras()
        .as_ref()
        .and_then(|raw| serde_json::from_str::<serde_json::Value>(raw.get()).ok())
        .is_some_and(|extras| extras["caustic"]["medium"].is_object());
    if !has_medium {
        return Vec::new();
    }
    let mut unrendered = Vec::new();
    if !m.transmission().is_some_and(|t| t.transmission_factor() > 0.0) {
        unrendered.push(
            "its `caustic` medium is not rendered: light does not enter a material without transmission"
                .into(),
        );
    }
    if m.extension_value("KHR_materials_volume").is_some() {
        unrendered.push(
            "KHR_materials_volume's attenuation is not rendered: its `caustic` medium replaces it".into(),
        );
    }
    unrendered
}

/// Emission under a coat or a sheen: Cycles' Principled BSDF puts emission beneath both layers,
/// which dim it as they reflect, and Caustic adds it on top of them undimmed.
fn unrendered_layered_emission(m: &Material) -> Option<String> {
    if m.emission.is_none() {
        return None;
    }
    let layers = match (m.clearcoat.is_some(), m.sheen.is_some()) {
        (true, true) => "the coat and the sheen",
        (true, false) => "the coat",
        (false, true) => "the sheen",
        (false, false) => return None,
    };
    Some(format!("its emission is not dimmed by {layers} over it, as Cycles dims it"))
}

/// The textures of `m` that are not read: those on a texture coordinate set Caustic does not
/// carry.
fn unrendered_textures(m: &gltf::Material) -> Vec<String> {
    let pbr = m.pbr_metallic_roughness();
    let raw = |extension: &str, key: &str| Some(raw_info_set(m.extension_value(extension)?.get(key)?));
    let coat = |key: &str| raw("KHR_materials_clearcoat", key);
    let sets = [
        ("base colour", pbr.base_color_texture().map(|i| info_set(&i))),
        ("metallic-roughness", pbr.metallic_roughness_texture().map(|i| info_set(&i))),
        ("normal", m.normal_texture().map(|n| normal_set(&n))),
        ("emissive", m.emissive_texture().map(|i| info_set(&i))),
        ("clearcoat", coat("clearcoatTexture")),
        ("clearcoat roughness", coat("clearcoatRoughnessTexture")),
        ("clearcoat normal", coat("clearcoatNormalTexture")),
        ("sheen colour", raw("KHR_materials_sheen", "sheenColorTexture")),
        ("sheen roughness", raw("KHR_materials_sheen", "sheenRoughnessTexture")),
        ("specular", m.specular().and_then(|s| s.specular_texture()).map(|i| info_set(&i))),
        ("specular colour", m.specular().and_then(|s| s.specular_color_texture()).map(|i| info_set(&i))),
    ];
    sets.into_iter()
        .filter_map(|(what, set)| {
            let set = set.filter(|&s| s as usize >= UV_SETS)?;
            Some(format!(
                "its {what} texture reads texture coordinate set {set}, which is not rendered (sets 0 and 1 are)"
            ))
        })
        .collect()
}
