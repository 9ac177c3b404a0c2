//! Materials as Blender writes them, rendered end to end: the glTF BRDF's specular layer over
//! the base (white furnaces with known answers).

mod common;

use common::*;
use serde_json::{json, Value};
use std::path::Path;

/// A sphere of `material` seen with vertical field of view `yfov` from 4 radii away (0.45 fills
/// the view, 0.55 shows its rim about 1.3 pixels inside the edges), under a uniform white world
/// of radiance 1.
fn sphere_in_a_white_world(dir: &Path, material: Value, yfov: f32, passes: u64) -> Image {
    let mut gltf = GltfBuilder::default();
    let material = gltf.material(material);
    gltf.sphere("Ball", [0.0, 0.0, 0.0], 1.0, 48, material);
    gltf.camera([0.0, 0.0, 4.0], [0.0, 0.0, -1.0], yfov);
    gltf.scene_extras(json!({"resolution": [32, 32], "world": {"color": [1.0, 1.0, 1.0], "strength": 1.0}}));
    let path = gltf.write(dir, "furnace");
    render(&settings(&path, dir, passes), 2)
}

/// A non-metal of white base colour with a specular layer reflects all the light it receives,
/// however rough: its layer takes what it reflects from the base and no more. In a white world
/// of radiance 1 it vanishes (radiance 1 everywhere, within 2%: noise and the albedo tables).
#[test]
fn a_white_principled_sphere_vanishes_in_a_white_furnace() {
    let dir = tempfile::tempdir().unwrap();
    for roughness in [0.0, 0.2, 0.5, 1.0] {
        let material = json!({"pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, 1.0],
            "metallicFactor": 0.0, "roughnessFactor": roughness}});
        let image = sphere_in_a_white_world(dir.path(), material, 0.45, 32);
        // The sphere's disc: the centre 12 x 12 pixels lie well inside it.
        for (c, value) in image.mean(10, 22, 10, 22).iter().enumerate() {
            assert!((value - 1.0).abs() < 0.02, "roughness {roughness}, channel {c}: {value}");
        }
    }
}

/// A black base under Blender's default specular layer (IOR 1.5) reflects only the layer: 4% of
/// the world head on (Fresnel at normal incidence), rising toward the rim. Without a layer (a
/// factor of 0) it is black.
#[test]
fn a_black_principled_sphere_shows_its_specular_layer() {
    let dir = tempfile::tempdir().unwrap();
    let black = |extensions: Value| {
        json!({"pbrMetallicRoughness": {"baseColorFactor": [0.0, 0.0, 0.0, 1.0], "metallicFactor": 0.0,
            "roughnessFactor": 0.0}, "extensions": extensions})
    };
    let image = sphere_in_a_white_world(dir.path(), black(json!({})), 0.55, 8);
    let centre = image.luminance(14, 18, 14, 18);
    assert!((centre - 0.04).abs() < 0.004, "centre {centre}");
    // Columns 3 and 4 of the middle rows see the surface at 52 to 60 degrees, where Fresnel's
    // reflectance at 1.5 is 0.06 to 0.09.
    let rim = image.luminance(3, 5, 14, 18);
    assert!(rim > 0.06 && rim < 0.09, "rim {rim}, centre {centre}");
    let layerless = black(json!({"KHR_materials_specular": {"specularFactor": 0.0}}));
    let none = sphere_in_a_white_world(dir.path(), layerless, 0.55, 8);
    assert!(none.luminance(8, 24, 8, 24) < 1e-6);
}

/// What a file holds and Caustic does not render is named, one line for each material, mesh or
/// node, when the scene loads (`caustic info` prints the same warnings as `caustic render`).
#[test]
fn unrendered_features_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let mut gltf = GltfBuilder::default();
    let paint = gltf.material(json!({"name": "Car paint", "alphaMode": "BLEND",
        "extensions": {"KHR_materials_iridescence": {"iridescenceFactor": 1.0}}}));
    gltf.sphere("Body", [0.0, 0.0, 0.0], 1.0, 8, paint);
    gltf.camera([0.0, 0.0, 4.0], [0.0, 0.0, -1.0], 0.5);
    gltf.scene_extras(json!({"world": {"color": [1.0, 1.0, 1.0], "strength": 1.0}}));
    let path = gltf.write(dir.path(), "paint");
    let output = run_caustic(&["info", path.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    for expected in [
        "material 'Car paint': KHR_materials_iridescence is not rendered",
        "material 'Car paint': alpha mode Blend is not rendered (the surface is opaque)",
    ] {
        assert!(stderr.contains(expected), "no '{expected}' in:\n{stderr}");
    }
}
