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
    let paint = gltf.material(json!({"name": "Car paint",
        "extensions": {"KHR_materials_iridescence": {"iridescenceFactor": 1.0}}}));
    gltf.sphere("Body", [0.0, 0.0, 0.0], 1.0, 8, paint);
    let neon = gltf.material(json!({"name": "Varnished neon", "emissiveFactor": [1.0, 0.2, 0.1],
        "extensions": {"KHR_materials_clearcoat": {"clearcoatFactor": 1.0}}}));
    gltf.sphere("Sign", [3.0, 0.0, 0.0], 0.5, 8, neon);
    let lamp = gltf.material(json!({"name": "Lamp", "emissiveFactor": [1.0, 1.0, 1.0],
        "extensions": {"KHR_materials_clearcoat": {"clearcoatFactor": 0.0}}}));
    gltf.sphere("Bulb", [-3.0, 0.0, 0.0], 0.5, 8, lamp);
    let decal = gltf.material(json!({"name": "Decal", "alphaMode": "BLEND"}));
    gltf.mesh("Sticker", &[[[0.0, 0.0, 1.1], [0.2, 0.0, 1.1], [0.0, 0.2, 1.1]]], decal);
    gltf.attribute("COLOR_0", &[[1.0f32, 1.0, 1.0, 0.5]; 3].concat(), 4, "VEC4");
    gltf.camera([0.0, 0.0, 4.0], [0.0, 0.0, -1.0], 0.5);
    gltf.scene_extras(json!({"world": {"color": [1.0, 1.0, 1.0], "strength": 1.0}}));
    let path = gltf.write(dir.path(), "paint");
    let output = run_caustic(&["info", path.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    let expected = "material 'Car paint': KHR_materials_iridescence is not rendered";
    assert!(stderr.contains(expected), "no '{expected}' in:\n{stderr}");
    let expected =
        "material 'Varnished neon': its emission is not dimmed by the coat over it, as Cycles dims it";
    assert!(stderr.contains(expected), "no '{expected}' in:\n{stderr}");
    // A coat of factor 0 is no coat; the decal's vertex alpha is rendered: nothing is said of them.
    assert!(!stderr.contains("Lamp"), "{stderr}");
    assert!(!stderr.contains("Sticker") && !stderr.contains("Decal"), "{stderr}");
}

/// The corners of the ground square spanning x and z in [-1, 1] at y = 0 (two triangles), and
/// their texture coordinates: u = (x + 1) / 2 and v = (z + 1) / 2.
const GROUND: [[[f32; 3]; 3]; 2] = [
    [[-1.0, 0.0, -1.0], [-1.0, 0.0, 1.0], [1.0, 0.0, 1.0]],
    [[-1.0, 0.0, -1.0], [1.0, 0.0, 1.0], [1.0, 0.0, -1.0]],
];

fn ground_uvs() -> Vec<[f32; 2]> {
    GROUND.iter().flatten().map(|p| [(p[0] + 1.0) / 2.0, (p[2] + 1.0) / 2.0]).collect()
}

/// The ground of `material` seen from straight above (image x along world +x, 32 x 32 pixels
/// over x in [-1.02, 1.02]), lit as `light` says: a uniform white world, or a sun.
fn ground(dir: &Path, material: Value, images: &[&str], light: Light, passes: u64) -> Image {
    let images = images.iter().map(|uri| json!({"uri": uri})).collect();
    ground_of_images(dir, material, images, light, passes, |_| {})
}

/// `ground`, with each image's glTF object given, and `edit` applied to the file before it is
/// written.
fn ground_of_images(
    dir: &Path,
    material: Value,
    images: Vec<Value>,
    light: Light,
    passes: u64,
    edit: impl FnOnce(&mut Value),
) -> Image {
    let mut gltf = GltfBuilder::default();
    for image in images {
        gltf.image(image);
    }
    let material = gltf.material(material);
    gltf.mesh_with_uvs("Ground", &GROUND, &ground_uvs(), material);
    gltf.camera([0.0, 4.0, 0.0], [0.0, -1.0, 0.0], 0.5);
    match light {
        Light::WhiteWorld => gltf.scene_extras(
            json!({"resolution": [32, 32], "world": {"color": [1.0, 1.0, 1.0], "strength": 1.0}}),
        ),
        Light::Sun(from) => {
            let to = from.map(|c| -c);
            gltf.light(json!({"type": "directional", "intensity": 683.0}), from, to);
            gltf.scene_extras(json!({"resolution": [32, 32]}));
        }
        Light::Point => {
            gltf.light(json!({"type": "point", "intensity": 100.0}), [0.0, 2.0, 0.0], [0.0, -1.0, 0.0]);
            gltf.scene_extras(json!({"resolution": [32, 32]}));
        }
    }
    let mut doc = gltf.to_json();
    edit(&mut doc);
    let path = dir.join("ground.gltf");
    std::fs::write(&path, doc.to_string()).unwrap();
    render(&settings(&path, dir, passes), 2)
}

enum Light {
    WhiteWorld,
    Sun([f32; 3]),
    Point,
}

/// A Lambertian material (no specular layer) with glTF fields merged in.
fn lambert(extra: Value) -> Value {
    let mut material = diffuse([0.8, 0.8, 0.8]);
    for (key, value) in extra.as_object().unwrap() {
        material[key] = value.clone();
    }
    material
}

/// The ground's light under a sun at `sun` (a unit vector toward it), with a normal map that tilts
/// every normal `tilt_deg` toward u (red) or toward the image's up (green), relative to the flat
/// ground's.
fn normal_mapped_ratio(dir: &Path, tilt_deg: f32, toward_up: bool, sun: [f32; 3]) -> f64 {
    let tilt = tilt_deg.to_radians();
    let (side, up) = ((0.5 + 0.5 * tilt.sin()) * 255.0, (0.5 + 0.5 * tilt.cos()) * 255.0);
    let rgb = if toward_up { [127.5, side, up] } else { [side, 127.5, up] };
    let name = format!("tilt_{tilt_deg}_{toward_up}.png");
    image::RgbImage::from_pixel(4, 4, image::Rgb(rgb.map(|c| c.round() as u8)))
        .save(dir.join(&name))
        .unwrap();
    let luminance = |material: Value, images: &[&str]| {
        ground(dir, material, images, Light::Sun(sun), 16).luminance(8, 24, 8, 24)
    };
    luminance(lambert(json!({"normalTexture": {"index": 0}})), &[&name]) / luminance(lambert(json!({})), &[])
}

/// Cycles' shadowing of a normal map's bend (Blender's Bump Map Correction): GGX masking at
/// the light's angle `light_deg` from the smooth normal, with `alpha^2 = tan^2(bend) / 8`.
fn bend_shadowing(tilt_deg: f64, light_deg: f64) -> f64 {
    let alpha2 = tilt_deg.to_radians().tan().powi(2) / 8.0;
    2.0 / (1.0 + (1.0 + alpha2 * light_deg.to_radians().tan().powi(2)).sqrt())
}

fn cos_deg(deg: f64) -> f64 {
    deg.to_radians().cos()
}

/// A normal map bends the shading normal as its texels say, in the frame of the texture's u
/// (red) and of the image's up, decreasing v (green), with tangents MikkTSpace generates: a
/// normal tilted 30 degrees toward the sun, which stands 45 degrees from the zenith, receives
/// cos 15 / cos 45 = 1.366 times the light of the flat ground, and tilted away,
/// cos 75 / cos 45 = 0.366, each times the bend's shadowing (0.990 here), within 2%.
#[test]
fn a_normal_map_bends_the_light_as_its_texels_say() {
    let dir = tempfile::tempdir().unwrap();
    let s = std::f32::consts::FRAC_1_SQRT_2;
    let shadowing = bend_shadowing(30.0, 45.0);
    // The image's up is decreasing v: world -z.
    for (toward_up, toward, away) in [(false, [s, s, 0.0], [-s, s, 0.0]), (true, [0.0, s, -s], [0.0, s, s])] {
        let ratio = normal_mapped_ratio(dir.path(), 30.0, toward_up, toward);
        let expected = shadowing * cos_deg(15.0) / cos_deg(45.0);
        assert!(
            (ratio / expected - 1.0).abs() < 0.02,
            "toward the sun (up: {toward_up}): {ratio}, not {expected}"
        );
        let ratio = normal_mapped_ratio(dir.path(), 30.0, toward_up, away);
        let expected = shadowing * cos_deg(75.0) / cos_deg(45.0);
        assert!(
            (ratio / expected - 1.0).abs() < 0.02,
            "away from the sun (up: {toward_up}): {ratio}, not {expected}"
        );
    }
}

/// Near the terminator a bent normal does not light the surface fully: a normal tilted 45
/// degrees toward a sun 75 degrees from the zenith sees it at 30 degrees, cos 30 / cos 75 = 3.35
/// times the flat ground's light, but Cycles (and Caustic) shadow the bend to 0.753 of that:
/// 2.52, within 2%.
#[test]
fn a_normal_maps_bend_is_shadowed_near_the_terminator() {
    let dir = tempfile::tempdir().unwrap();
    let sun = 75f32.to_radians();
    let ratio = normal_mapped_ratio(dir.path(), 45.0, false, [sun.sin(), sun.cos(), 0.0]);
    let expected = bend_shadowing(45.0, 75.0) * cos_deg(30.0) / cos_deg(75.0);
    assert!((ratio / expected - 1.0).abs() < 0.02, "{ratio}, not {expected}");
}

/// A 16-bit PNG base colour is read at its depth and decoded from sRGB: under a white world the
/// ground's radiance is its albedo (2%).
#[test]
fn a_16_bit_base_colour_texture_is_read() {
    let dir = tempfile::tempdir().unwrap();
    let value = 30000u16;
    image::ImageBuffer::<image::Rgb<u16>, _>::from_pixel(4, 4, image::Rgb([value; 3]))
        .save(dir.path().join("grey16.png"))
        .unwrap();
    let material =
        lambert(json!({"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}, "metallicFactor": 0.0}}));
    let image = ground(dir.path(), material, &["grey16.png"], Light::WhiteWorld, 16);
    let c = f64::from(value) / 65535.0;
    let expected = ((c + 0.055) / 1.055).powf(2.4);
    for (ch, mean) in image.mean(8, 24, 8, 24).iter().enumerate() {
        assert!((mean / expected - 1.0).abs() < 0.02, "channel {ch}: {mean} vs {expected}");
    }
}

/// An image Blender reads as Non-Color (the add-on labels it `colour_space: linear`) is a base
/// colour of its stored values, undecoded, as Cycles reads it: under a white world the ground's
/// radiance is the texel's value (2%); labelled sRGB, or unlabelled, it is decoded.
#[test]
fn a_non_color_base_colour_texture_is_read_linear() {
    let dir = tempfile::tempdir().unwrap();
    let value = 100u8;
    image::RgbImage::from_pixel(4, 4, image::Rgb([value; 3])).save(dir.path().join("grey.png")).unwrap();
    let material =
        lambert(json!({"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}, "metallicFactor": 0.0}}));
    let stored = f64::from(value) / 255.0;
    let decoded = ((stored + 0.055) / 1.055).powf(2.4);
    for (space, expected) in [(Some("linear"), stored), (Some("srgb"), decoded), (None, decoded)] {
        let mut image = json!({"uri": "grey.png"});
        if let Some(space) = space {
            image["extras"] = json!({"caustic": {"colour_space": space}});
        }
        let render =
            ground_of_images(dir.path(), material.clone(), vec![image], Light::WhiteWorld, 16, |_| {});
        for (ch, mean) in render.mean(8, 24, 8, 24).iter().enumerate() {
            assert!((mean / expected - 1.0).abs() < 0.02, "{space:?}, channel {ch}: {mean} vs {expected}");
        }
    }
}

/// A texture whose image file is missing renders magenta (reflectance 1, 0, 1), as Cycles shows a
/// missing image, and the warning names the file; the render does not fail.
#[test]
fn a_missing_texture_is_magenta_and_named() {
    let dir = tempfile::tempdir().unwrap();
    let material =
        lambert(json!({"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}, "metallicFactor": 0.0}}));
    let images = vec![json!({"uri": "textures/wood%20planks.png", "name": "Wood"})];
    let render = ground_of_images(dir.path(), material, images, Light::WhiteWorld, 16, |_| {});
    let [r, g, b] = render.mean(8, 24, 8, 24);
    assert!((r - 1.0).abs() < 0.03 && (b - 1.0).abs() < 0.03 && g < 0.03, "not magenta: {r} {g} {b}");
    let output = run_caustic(&["info", dir.path().join("ground.gltf").to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    let named =
        stderr.contains("image 'Wood'") && stderr.contains("wood planks.png") && stderr.contains("magenta");
    assert!(named, "the warning does not name the missing file:\n{stderr}");
}

/// A WebP texture (`EXT_texture_webp`, required, with no PNG fallback) is read: under a white world
/// the ground shows the texel's decoded sRGB value (2%).
#[test]
fn a_webp_texture_is_read() {
    let dir = tempfile::tempdir().unwrap();
    let value = 180u8;
    let texels = image::RgbaImage::from_pixel(4, 4, image::Rgba([value, value, value, 255]));
    texels.save_with_format(dir.path().join("grey.webp"), image::ImageFormat::WebP).unwrap();
    let material =
        lambert(json!({"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}, "metallicFactor": 0.0}}));
    let images = vec![json!({"uri": "grey.webp"})];
    let render = ground_of_images(dir.path(), material, images, Light::WhiteWorld, 16, |doc| {
        doc["textures"][0] = json!({"extensions": {"EXT_texture_webp": {"source": 0}}});
        doc["extensionsUsed"] = json!(["EXT_texture_webp"]);
        doc["extensionsRequired"] = json!(["EXT_texture_webp"]);
    });
    let expected = ((f64::from(value) / 255.0 + 0.055) / 1.055).powf(2.4);
    for (ch, mean) in render.mean(8, 24, 8, 24).iter().enumerate() {
        assert!((mean / expected - 1.0).abs() < 0.02, "channel {ch}: {mean} vs {expected}");
    }
}

/// The metallic-roughness texture drives both: blue is metallic and green roughness, times
/// their factors. Its left half (u < 0.5, x < 0) is a smooth metal, which mirrors the black sky
/// under a point light, and its right half a rough dielectric, lit.
#[test]
fn the_metallic_roughness_texture_drives_metal_and_roughness() {
    let dir = tempfile::tempdir().unwrap();
    let texels =
        image::RgbImage::from_fn(
            4,
            1,
            |x, _| if x < 2 { image::Rgb([0, 0, 255]) } else { image::Rgb([0, 255, 0]) },
        );
    texels.save(dir.path().join("mr.png")).unwrap();
    let material = lambert(json!({"pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.8, 1.0],
        "metallicFactor": 1.0, "roughnessFactor": 1.0, "metallicRoughnessTexture": {"index": 0}}}));
    let image = ground(dir.path(), material, &["mr.png"], Light::Point, 16);
    let (metal, rough) = (image.luminance(6, 10, 14, 18), image.luminance(22, 26, 14, 18));
    // The rough half: albedo 0.8 / pi times 100 cd / 683 at 2 m, about 0.0093.
    assert!(rough > 0.008 && metal < 1e-3 * rough, "metal {metal}, rough {rough}");
}

/// `COLOR_0` multiplies the base colour: a white ground with red vertices is red.
#[test]
fn vertex_colours_multiply_the_base_colour() {
    let dir = tempfile::tempdir().unwrap();
    let mut gltf = GltfBuilder::default();
    let material = gltf.material(lambert(
        json!({"pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, 1.0], "metallicFactor": 0.0}}),
    ));
    gltf.mesh_with_uvs("Ground", &GROUND, &ground_uvs(), material);
    gltf.attribute("COLOR_0", &[[0.9f32, 0.1, 0.1, 1.0]; 6].concat(), 4, "VEC4");
    gltf.camera([0.0, 4.0, 0.0], [0.0, -1.0, 0.0], 0.5);
    gltf.scene_extras(json!({"resolution": [16, 16], "world": {"color": [1.0, 1.0, 1.0], "strength": 1.0}}));
    let path = gltf.write(dir.path(), "coloured");
    let image = render(&settings(&path, dir.path(), 16), 2);
    let [r, g, b] = image.mean(4, 12, 4, 12);
    assert!((r - 0.9).abs() < 0.03 && (g - 0.1).abs() < 0.02 && (b - 0.1).abs() < 0.02, "{r} {g} {b}");
}

/// `KHR_texture_transform` (here a required extension, as Blender writes it for a Mapping node)
/// moves the texture: an offset of half the image swaps a two-colour texture's halves.
#[test]
fn texture_transform_moves_the_texture() {
    let dir = tempfile::tempdir().unwrap();
    let texels = image::RgbImage::from_fn(4, 1, |x, _| {
        if x < 2 {
            image::Rgb([255, 255, 255])
        } else {
            image::Rgb([0, 0, 0])
        }
    });
    texels.save(dir.path().join("halves.png")).unwrap();
    let render_with = |transform: Value| {
        let info = json!({"index": 0, "extensions": {"KHR_texture_transform": transform}});
        let material =
            lambert(json!({"pbrMetallicRoughness": {"baseColorTexture": info, "metallicFactor": 0.0}}));
        let mut gltf = GltfBuilder::default();
        gltf.texture("halves.png");
        let m = gltf.material(material);
        gltf.mesh_with_uvs("Ground", &GROUND, &ground_uvs(), m);
        gltf.camera([0.0, 4.0, 0.0], [0.0, -1.0, 0.0], 0.5);
        gltf.scene_extras(
            json!({"resolution": [32, 32], "world": {"color": [1.0, 1.0, 1.0], "strength": 1.0}}),
        );
        let mut doc = gltf.to_json();
        doc["extensionsRequired"] = json!(["KHR_texture_transform"]);
        doc["extensionsUsed"].as_array_mut().unwrap().push(json!("KHR_texture_transform"));
        let path = dir.path().join("transformed.gltf");
        std::fs::write(&path, doc.to_string()).unwrap();
        render(&settings(&path, dir.path(), 4), 2)
    };
    let plain = render_with(json!({}));
    let moved = render_with(json!({"offset": [0.5, 0.0]}));
    let (left, right) = ((6, 10), (22, 26));
    assert!(
        plain.luminance(left.0, left.1, 14, 18) > 0.9 && plain.luminance(right.0, right.1, 14, 18) < 0.01
    );
    assert!(
        moved.luminance(left.0, left.1, 14, 18) < 0.01 && moved.luminance(right.0, right.1, 14, 18) > 0.9
    );
}

/// A black leaf at height 1 over the ground of `GROUND` (the same square), whose base colour
/// texture `texture` (and vertex colours of alpha `vertex_alpha`, if any) cut it as `alpha_mode`
/// says, under a sun straight above; the ground seen from `eye` (below the leaf or above it).
fn leaf_over_ground(dir: &Path, alpha: Value, texture: &str, vertex_alpha: Option<f32>, eye: f32) -> Image {
    let mut gltf = GltfBuilder::default();
    gltf.texture(texture);
    let ground = gltf.material(lambert(json!({})));
    gltf.mesh_with_uvs("Ground", &GROUND, &ground_uvs(), ground);
    let mut leaf = json!({"pbrMetallicRoughness": {"baseColorFactor": [0.0, 0.0, 0.0, 1.0], "metallicFactor": 0.0,
        "baseColorTexture": {"index": 0}}, "extensions": {"KHR_materials_specular": {"specularFactor": 0.0}}});
    for (key, value) in alpha.as_object().unwrap() {
        leaf[key] = value.clone();
    }
    let leaf = gltf.material(leaf);
    let raised = GROUND.map(|t| t.map(|p| [p[0], 1.0, p[2]]));
    gltf.mesh_with_uvs("Leaf", &raised, &ground_uvs(), leaf);
    if let Some(a) = vertex_alpha {
        gltf.attribute("COLOR_0", &[[1.0f32, 1.0, 1.0, a]; 6].concat(), 4, "VEC4");
    }
    gltf.light(json!({"type": "directional", "intensity": 683.0}), [0.0, 5.0, 0.0], [0.0, -1.0, 0.0]);
    gltf.camera([0.0, eye, 0.0], [0.0, -1.0, 0.0], if eye < 1.0 { 1.5 } else { 0.5 });
    gltf.scene_extras(json!({"resolution": [32, 32]}));
    let path = gltf.write(dir, "leaf");
    render(&settings(&path, dir, 16), 2)
}

/// A leaf clipped by its texture's alpha (MASK) casts a shadow of its shape, for light samples
/// and photons alike, and is seen through where it is cut away: its left half (u < 0.5) is
/// there, its right half is not.
#[test]
fn an_alpha_masked_leaf_casts_the_shadow_of_its_shape() {
    let dir = tempfile::tempdir().unwrap();
    image::RgbaImage::from_fn(4, 1, |x, _| image::Rgba([0, 0, 0, if x < 2 { 255 } else { 0 }]))
        .save(dir.path().join("half.png"))
        .unwrap();
    let mask = json!({"alphaMode": "MASK", "alphaCutoff": 0.5});
    // From 0.5 above the ground, under the leaf: the left half of the ground is in its shadow.
    let below = leaf_over_ground(dir.path(), mask.clone(), "half.png", None, 0.5);
    let (shadow, lit) = (below.luminance(2, 12, 10, 22), below.luminance(20, 30, 10, 22));
    // The lit ground: albedo 0.8 / pi under 1 W/m^2.
    assert!((lit / (0.8 / std::f64::consts::PI) - 1.0).abs() < 0.03, "lit {lit}");
    assert!(shadow < 1e-3 * lit, "shadow {shadow}, lit {lit}");
    // From above: the black leaf on the left, the lit ground through the cut on the right.
    let above = leaf_over_ground(dir.path(), mask, "half.png", None, 4.0);
    let (leaf, hole) = (above.luminance(6, 10, 14, 18), above.luminance(22, 26, 14, 18));
    assert!(leaf < 1e-3 && (hole / lit - 1.0).abs() < 0.03, "leaf {leaf}, hole {hole}, lit {lit}");
}

/// A leaf of alpha 0.25 (BLEND) lets three quarters of the sun through to the ground below it
/// (2%), and is seen a quarter black from above.
#[test]
fn a_blended_leaf_lets_its_transparency_through() {
    let dir = tempfile::tempdir().unwrap();
    image::RgbaImage::from_pixel(2, 2, image::Rgba([0, 0, 0, 64]))
        .save(dir.path().join("quarter.png"))
        .unwrap();
    let blend = json!({"alphaMode": "BLEND"});
    let below = leaf_over_ground(dir.path(), blend.clone(), "quarter.png", None, 0.5).luminance(4, 28, 4, 28);
    let open = 0.8 / std::f64::consts::PI;
    let alpha = 64.0 / 255.0;
    assert!((below / (open * (1.0 - alpha)) - 1.0).abs() < 0.02, "below {below} vs {}", open * (1.0 - alpha));
    let above = leaf_over_ground(dir.path(), blend, "quarter.png", None, 4.0).luminance(8, 24, 8, 24);
    let expected = open * (1.0 - alpha) * (1.0 - alpha);
    assert!((above / expected - 1.0).abs() < 0.05, "above {above} vs {expected}");
}

/// An emitting quad at height 1 over the ground, cut in half by its texture's alpha (MASK), in
/// the dark, seen from `eye`: against the same quad's left half modelled as geometry.
fn glowing_half(dir: &Path, cut: bool, eye: f32) -> Image {
    let mut gltf = GltfBuilder::default();
    gltf.texture("half.png");
    let ground = gltf.material(lambert(json!({})));
    gltf.mesh_with_uvs("Ground", &GROUND, &ground_uvs(), ground);
    let mut glow = json!({"pbrMetallicRoughness": {"baseColorFactor": [0.0, 0.0, 0.0, 1.0], "metallicFactor": 0.0},
        "emissiveFactor": [1.0, 1.0, 1.0], "extensions": {"KHR_materials_specular": {"specularFactor": 0.0}}});
    let raised = GROUND.map(|t| t.map(|p| [p[0], 1.0, p[2]]));
    if cut {
        glow["alphaMode"] = json!("MASK");
        glow["pbrMetallicRoughness"]["baseColorTexture"] = json!({"index": 0});
        let glow = gltf.material(glow);
        gltf.mesh_with_uvs("Glow", &raised, &ground_uvs(), glow);
    } else {
        let glow = gltf.material(glow);
        let left: Vec<_> = raised.iter().map(|t| t.map(|p| [p[0].min(0.0), p[1], p[2]])).collect();
        gltf.mesh("Glow", &left, glow);
    }
    gltf.camera([0.0, eye, 0.0], [0.0, -1.0, 0.0], if eye < 1.0 { 1.5 } else { 0.5 });
    gltf.scene_extras(json!({"resolution": [32, 32]}));
    let path = gltf.write(dir, "glow");
    render(&settings(&path, dir, 32), 2)
}

/// Alpha cuts emission as it cuts the surface: a glowing quad cut in half by its texture's alpha
/// (MASK) shows radiance 1 where it is there and the ground through the cut (seen from above), and
/// lights the ground as its left half modelled alone does (seen from below it), within 3%: for the
/// camera, light samples and photons alike.
#[test]
fn alpha_cuts_emission() {
    let dir = tempfile::tempdir().unwrap();
    image::RgbaImage::from_fn(4, 1, |x, _| image::Rgba([0, 0, 0, if x < 2 { 255 } else { 0 }]))
        .save(dir.path().join("half.png"))
        .unwrap();
    let (cut, half) = (glowing_half(dir.path(), true, 0.5), glowing_half(dir.path(), false, 0.5));
    for (x0, x1) in [(2, 12), (12, 20), (20, 30)] {
        let (a, b) = (cut.luminance(x0, x1, 10, 22), half.luminance(x0, x1, 10, 22));
        assert!((a / b - 1.0).abs() < 0.03, "ground at columns {x0}..{x1}: cut {a}, half {b}");
    }
    let (cut, half) = (glowing_half(dir.path(), true, 4.0), glowing_half(dir.path(), false, 4.0));
    let (glow, hole) = (cut.luminance(6, 10, 14, 18), cut.luminance(22, 26, 14, 18));
    assert!((glow - 1.0).abs() < 0.01, "glow {glow}");
    let ground = half.luminance(22, 26, 14, 18);
    assert!((hole / ground - 1.0).abs() < 0.03, "hole {hole}, ground {ground}");
}

/// The vertex colours' alpha multiplies the texture's (glTF: `COLOR_0` multiplies the base
/// colour, alpha included): a BLEND leaf of texture alpha 0.5 and vertex alpha 0.5 lets three
/// quarters of the sun through (2%); a MASK leaf of cutoff 0.4 and the same alphas is cut away.
#[test]
fn vertex_alpha_multiplies_the_leafs_alpha() {
    let dir = tempfile::tempdir().unwrap();
    image::RgbaImage::from_pixel(2, 2, image::Rgba([0, 0, 0, 128]))
        .save(dir.path().join("half_alpha.png"))
        .unwrap();
    let open = 0.8 / std::f64::consts::PI;
    let alpha = 0.5 * 128.0 / 255.0;
    let below = |mode: Value| {
        leaf_over_ground(dir.path(), mode, "half_alpha.png", Some(0.5), 0.5).luminance(4, 28, 4, 28)
    };
    let blended = below(json!({"alphaMode": "BLEND"}));
    assert!(
        (blended / (open * (1.0 - alpha)) - 1.0).abs() < 0.02,
        "blended {blended} vs {}",
        open * (1.0 - alpha)
    );
    let masked = below(json!({"alphaMode": "MASK", "alphaCutoff": 0.4}));
    assert!((masked / open - 1.0).abs() < 0.02, "masked {masked} vs {open}");
}

/// An emissive texture glows with its texels' colours, times the emissive factor and strength,
/// to the camera, to light sampling and to photons: an emitter whose texture is white on its
/// left half and black on its right lights the ground below as an emitter of its left half
/// alone does (3%), and shows its texels (2%).
#[test]
fn an_emissive_texture_glows_as_its_texels_say() {
    let dir = tempfile::tempdir().unwrap();
    image::RgbImage::from_fn(
        8,
        1,
        |x, _| if x < 4 { image::Rgb([255, 255, 255]) } else { image::Rgb([0, 0, 0]) },
    )
    .save(dir.path().join("half.png"))
    .unwrap();
    let scene = |emitter: &[[[f32; 3]; 3]], textured: bool, eye: [f32; 3], look: [f32; 3]| {
        let mut gltf = GltfBuilder::default();
        gltf.texture("half.png");
        let ground = gltf.material(lambert(json!({})));
        gltf.mesh_with_uvs("Ground", &GROUND, &ground_uvs(), ground);
        let mut glow = json!({"emissiveFactor": [1.0, 1.0, 1.0], "pbrMetallicRoughness": {"baseColorFactor": [0.0, 0.0, 0.0, 1.0]},
            "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 2.0}}});
        if textured {
            glow["emissiveTexture"] = json!({"index": 0});
        }
        let glow = gltf.material(glow);
        let uvs: Vec<[f32; 2]> =
            emitter.iter().flatten().map(|p| [(p[0] + 1.0) / 2.0, (p[2] + 1.0) / 2.0]).collect();
        gltf.mesh_with_uvs("Panel", emitter, &uvs, glow);
        gltf.camera(eye, look, 1.5);
        gltf.scene_extras(json!({"resolution": [32, 32]}));
        let path = gltf.write(dir.path(), "glow");
        render(&settings(&path, dir.path(), 32), 2)
    };
    // The panel faces down at height 1 (its corners turned so its normal points to the ground).
    let panel = |x1: f32| {
        let (a, b, c, d) = ([-1.0, 1.0, -1.0], [-1.0, 1.0, 1.0], [x1, 1.0, 1.0], [x1, 1.0, -1.0]);
        vec![[a, c, b], [a, d, c]]
    };
    let below = ([0.0, 0.5, 0.0], [0.0, -1.0, 0.0]);
    let textured = scene(&panel(1.0), true, below.0, below.1).luminance(4, 28, 4, 28);
    let half = scene(&panel(0.0), false, below.0, below.1).luminance(4, 28, 4, 28);
    assert!((textured / half - 1.0).abs() < 0.03, "textured {textured}, half {half}");
    // Looking up at the panel from 0.5 below it (the image mirrored): 2 on one side, 0 on the other.
    let above = scene(&panel(1.0), true, [0.0, 0.5, 0.0], [0.0, 1.0, 0.0]);
    let columns: Vec<f64> = [(4, 8), (24, 28)].iter().map(|&(a, b)| above.luminance(a, b, 12, 20)).collect();
    let (bright, dark) = (columns[0].max(columns[1]), columns[0].min(columns[1]));
    assert!((bright / 2.0 - 1.0).abs() < 0.02 && dark < 1e-3, "columns {columns:?}");
}

/// A white base under a clear coat (Cycles' layering: what the coat reflects is taken from the
/// layers under it) reflects all the light it receives, smooth or rough: in a white world of
/// radiance 1 it vanishes (2%).
#[test]
fn a_clear_coated_white_sphere_vanishes_in_a_white_furnace() {
    let dir = tempfile::tempdir().unwrap();
    for roughness in [0.0, 0.3] {
        let material = json!({"pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, 1.0],
            "metallicFactor": 0.0, "roughnessFactor": 0.5},
            "extensions": {"KHR_materials_clearcoat": {"clearcoatFactor": 1.0,
                "clearcoatRoughnessFactor": roughness}}});
        let image = sphere_in_a_white_world(dir.path(), material, 0.45, 32);
        for (c, value) in image.mean(10, 22, 10, 22).iter().enumerate() {
            assert!((value - 1.0).abs() < 0.02, "coat roughness {roughness}, channel {c}: {value}");
        }
    }
}

/// A smooth clear coat over a black base mirrors the white world with Fresnel's reflectance at
/// index 1.5, 4% head on, times its factor; the clearcoat texture's red channel scales the
/// factor (128 / 255: half the reflection). 4% relative tolerance.
#[test]
fn a_clear_coat_reflects_its_factor_times_fresnel() {
    let dir = tempfile::tempdir().unwrap();
    image::RgbImage::from_pixel(4, 4, image::Rgb([128, 255, 0])).save(dir.path().join("half.png")).unwrap();
    let black_coated = |coat: Value| {
        let mut material = diffuse([0.0, 0.0, 0.0]);
        material["extensions"]["KHR_materials_clearcoat"] = coat;
        material
    };
    let full = json!({"clearcoatFactor": 1.0});
    let textured = json!({"clearcoatFactor": 1.0, "clearcoatTexture": {"index": 0}});
    for (coat, images, expected) in [(full, vec![], 0.04), (textured, vec!["half.png"], 0.04 * 128.0 / 255.0)]
    {
        let image = ground(dir.path(), black_coated(coat.clone()), &images, Light::WhiteWorld, 8);
        let seen = image.luminance(8, 24, 8, 24);
        assert!((seen / expected - 1.0).abs() < 0.04, "{coat}: {seen} vs {expected}");
    }
}

/// Under a smooth clear coat, a Lambertian ground lit by a sun keeps what the coat does not
/// reflect toward the viewer: seen head on, 1 - 0.04 of the uncoated ground's radiance (1%).
#[test]
fn a_clear_coat_attenuates_the_base_by_what_it_reflects() {
    let dir = tempfile::tempdir().unwrap();
    let s = std::f32::consts::FRAC_1_SQRT_2;
    let seen = |material: Value| {
        ground(dir.path(), material, &[], Light::Sun([s, s, 0.0]), 64).luminance(8, 24, 8, 24)
    };
    let mut coated = lambert(json!({}));
    coated["extensions"]["KHR_materials_clearcoat"] = json!({"clearcoatFactor": 1.0});
    let ratio = seen(coated) / seen(lambert(json!({})));
    assert!((ratio - 0.96).abs() < 0.01, "{ratio}");
}

/// A sheen over a white base (Cycles' layering) reflects all the light it receives: in a white
/// world it vanishes (2%). Over a black base, the fibres reflect 2.5% head on (Zeltner et al.'s
/// albedo at roughness 0.5, as Cycles' table has it: the glTF specification's Charlie sheen
/// reflects several times more) and over three times as much toward the rim.
#[test]
fn a_sheen_vanishes_in_a_white_furnace_and_glows_at_the_rim() {
    let dir = tempfile::tempdir().unwrap();
    let sheen = |base: f32| {
        let mut material = diffuse([base, base, base]);
        material["extensions"]["KHR_materials_sheen"] =
            json!({"sheenColorFactor": [1.0, 1.0, 1.0], "sheenRoughnessFactor": 0.5});
        material
    };
    let image = sphere_in_a_white_world(dir.path(), sheen(1.0), 0.45, 32);
    for (c, value) in image.mean(10, 22, 10, 22).iter().enumerate() {
        assert!((value - 1.0).abs() < 0.02, "channel {c}: {value}");
    }
    let black = sphere_in_a_white_world(dir.path(), sheen(0.0), 0.55, 16);
    let (centre, rim) = (black.luminance(14, 18, 14, 18), black.luminance(3, 5, 14, 18));
    assert!((centre / 0.0249 - 1.0).abs() < 0.1 && rim > 3.0 * centre, "centre {centre}, rim {rim}");
}

/// The specular textures scale the layer: `specularTexture`'s alpha its factor (128 / 255: half
/// the reflection) and `specularColorTexture` its colour (a pure red one reflects red alone, as much
/// as the smooth spectrum nearest pure red does: 89%). A black smooth ground under a white world
/// shows its layer alone: 4% head on (4%).
#[test]
fn the_specular_textures_scale_the_layer() {
    let dir = tempfile::tempdir().unwrap();
    image::RgbaImage::from_pixel(4, 4, image::Rgba([255, 255, 255, 128]))
        .save(dir.path().join("half.png"))
        .unwrap();
    image::RgbImage::from_pixel(4, 4, image::Rgb([255, 0, 0])).save(dir.path().join("red.png")).unwrap();
    let black_glossy = |specular: Value| {
        json!({"pbrMetallicRoughness": {"baseColorFactor": [0.0, 0.0, 0.0, 1.0], "metallicFactor": 0.0,
            "roughnessFactor": 0.0}, "extensions": {"KHR_materials_specular": specular}})
    };
    let seen = |specular: Value, images: &[&str]| {
        ground(dir.path(), black_glossy(specular), images, Light::WhiteWorld, 8).mean(8, 24, 8, 24)
    };
    let plain = seen(json!({}), &[]);
    assert!((plain[1] / 0.04 - 1.0).abs() < 0.04, "{plain:?}");
    let half = seen(json!({"specularTexture": {"index": 0}}), &["half.png"]);
    assert!((half[1] / plain[1] - 128.0 / 255.0).abs() < 0.02, "{half:?} vs {plain:?}");
    let red = seen(json!({"specularColorTexture": {"index": 0}}), &["red.png"]);
    assert!(red[0] > 0.85 * plain[0] && red[1].abs() < 0.05 * plain[1], "{red:?} vs {plain:?}");
}

/// The ground of `GROUND` seen from just above it, under glass of base colour `colour` and
/// roughness `roughness` held over it at heights 0.5 to 0.6 (a closed slab over its middle, or an
/// open pane at 0.6 over all of it if `thin`), in a sun straight above: the share of the sun the glass lets through (photons
/// alone carry it). The ground is dark (albedo 0.05), so that the light it sends back up and the
/// glass reflects down again is under 0.5% of it.
fn light_under_glass(dir: &Path, colour: [f32; 3], thin: bool, roughness: f32) -> f64 {
    let mut gltf = GltfBuilder::default();
    let ground = gltf.material(diffuse([0.05, 0.05, 0.05]));
    gltf.mesh_with_uvs("Ground", &GROUND, &ground_uvs(), ground);
    let glass = gltf.material(
        json!({"pbrMetallicRoughness": {"baseColorFactor": [colour[0], colour[1], colour[2], 1.0],
        "metallicFactor": 0.0, "roughnessFactor": roughness},
        "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1.0}}}),
    );
    let slab = box_triangles([-0.5, 0.5, -0.5], [0.5, 0.6, 0.5]);
    // As wide as the ground, so that a frosted pane's spread loses nothing over its edges.
    let pane: Vec<_> = GROUND.iter().map(|t| t.map(|p| [p[0], 0.6, p[2]])).collect();
    gltf.mesh("Glass", if thin { &pane } else { &slab }, glass);
    gltf.light(json!({"type": "directional", "intensity": 683.0}), [0.0, 5.0, 0.0], [0.0, -1.0, 0.0]);
    // From 0.4 above the ground, seeing x in [-0.37, 0.37]: all of it under the glass.
    gltf.camera([0.0, 0.4, 0.0], [0.0, -1.0, 0.0], 1.5);
    gltf.scene_extras(json!({"resolution": [32, 32]}));
    let path = gltf.write(dir, "glass");
    let mut s = settings(&path, dir, 32);
    s.photons = Some(40_000);
    let under = render(&s, 2).luminance(8, 24, 8, 24);
    under / (0.05 / std::f64::consts::PI)
}

/// Glass tints what it transmits by its base colour (as Cycles does: the square root of it at
/// each of a closed mesh's boundaries, the whole of it through a thin wall), reflecting the rest
/// untinted: under a slab or a pane of grey base colour 0.49 in a sun straight above, the ground
/// receives 0.49 (1 - R) / (1 + R) of the sun, R = 0.04 Fresnel's reflectance head on (the
/// slab's inner reflections summed), within 3%; white glass lets (1 - R) / (1 + R) through.
#[test]
fn glass_tints_what_it_transmits_by_its_base_colour() {
    let dir = tempfile::tempdir().unwrap();
    let through = (1.0 - 0.04) / (1.0 + 0.04);
    for thin in [false, true] {
        for grey in [1.0f32, 0.49] {
            let measured = light_under_glass(dir.path(), [grey; 3], thin, 0.0);
            let expected = f64::from(grey) * through;
            assert!(
                (measured / expected - 1.0).abs() < 0.03,
                "thin {thin}, grey {grey}: {measured} vs {expected}"
            );
        }
    }
}

/// A frosted pane (roughness 0.3, an open mesh: a rough thin wall) spreads the sun it lets
/// through but lets as much through as a clear one, (1 - R) / (1 + R) of it (3%; measured 1.4%
/// under), and tinted by its base colour; so does a frosted slab (a closed mesh: two rough
/// boundaries; 0.9% under). (Over a pane half the ground's width the middle of the ground lost
/// 4.8%: the spread's tails that would come from beyond its edges.)
#[test]
fn frosted_glass_lets_as_much_light_through_as_clear_glass() {
    let dir = tempfile::tempdir().unwrap();
    let through = (1.0 - 0.04) / (1.0 + 0.04);
    for thin in [true, false] {
        for grey in [1.0f32, 0.49] {
            let measured = light_under_glass(dir.path(), [grey; 3], thin, 0.3);
            let expected = f64::from(grey) * through;
            assert!(
                (measured / expected - 1.0).abs() < 0.03,
                "thin {thin}, grey {grey}: {measured} vs {expected}"
            );
        }
    }
}

/// A white glass sphere in a white world of radiance 1 vanishes (radiance 1 within 2%), smooth
/// or slightly frosted: what a rough boundary refracts toward the world, or reflects, is found by
/// light samples through the boundary and by the paths on through it alike (without light
/// samples through it, roughness 0.2 reads 0.04). At roughness 0.5 and 1 single scattering
/// loses light between microfacets at both boundaries and at every inner reflection (the centre
/// read 0.91 at 0.5); the boundary's albedo scaling gives it back, as Cycles' Multiscatter GGX
/// does, within 3% (camera paths are scaled for the direction they leave toward, which is exact
/// for flux but not for radiance through each boundary).
#[test]
fn a_frosted_glass_sphere_vanishes_in_a_white_furnace() {
    let dir = tempfile::tempdir().unwrap();
    for (roughness, tolerance) in [(0.0, 0.02), (0.2, 0.02), (0.5, 0.03), (1.0, 0.03)] {
        let material = json!({"pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, 1.0],
            "metallicFactor": 0.0, "roughnessFactor": roughness},
            "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1.0}}});
        let image = sphere_in_a_white_world(dir.path(), material, 0.45, 32);
        for (c, value) in image.mean(10, 22, 10, 22).iter().enumerate() {
            assert!((value - 1.0).abs() < tolerance, "roughness {roughness}, channel {c}: {value}");
        }
    }
}
