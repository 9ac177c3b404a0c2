//! The world light: uniform, and equirectangular images mapped as Blender maps them.

mod common;

use common::*;
use serde_json::json;
use std::path::Path;

/// Writes an equirectangular EXR of `width` x `height` whose texel (x, y from the top) is `f`.
fn write_environment(path: &Path, width: u32, height: u32, f: impl Fn(u32, u32) -> f32) {
    let image = image::Rgb32FImage::from_fn(width, height, |x, y| image::Rgb([f(x, y); 3]));
    image::DynamicImage::ImageRgb32F(image).save(path).unwrap();
}

/// A large diffuse ground of albedo 0.5 facing up, seen from above, under `world`.
fn ground_under(dir: &Path, world: serde_json::Value) -> Image {
    let mut gltf = GltfBuilder::default();
    let material = gltf.material(diffuse([0.5, 0.5, 0.5]));
    gltf.quad_y("Ground", 0.0, 50.0, true, material);
    gltf.camera([0.0, 1.0, 0.0], [0.0, -1.0, 0.0], 0.5);
    gltf.scene_extras(json!({"resolution": [16, 16], "world": world}));
    let path = gltf.write(dir, "ground");
    render(&settings(&path, dir, 64), 2)
}

/// A ground under a uniform white world of radiance 1 receives irradiance pi and reflects
/// radiance albedo * 1 = 0.5. Tolerance 2% (light and BSDF sampling noise, wavelengths).
#[test]
fn ground_under_a_uniform_world_reflects_its_albedo() {
    let dir = tempfile::tempdir().unwrap();
    let image = ground_under(dir.path(), json!({"color": [1.0, 1.0, 1.0], "strength": 1.0}));
    for (c, value) in image.mean_all().iter().enumerate() {
        assert!((value / 0.5 - 1.0).abs() < 0.02, "channel {c}: {value}");
    }
}

/// An image bright (2) in its top half and black below lights an upward ground like a uniform
/// sky of 2: radiance 0.5 * 2 = 1 (2%). If the image were upside down the ground would be black.
#[test]
fn the_top_of_an_environment_image_is_up() {
    let dir = tempfile::tempdir().unwrap();
    write_environment(&dir.path().join("sky.exr"), 16, 64, |_, y| if y < 32 { 2.0 } else { 0.0 });
    let image = ground_under(dir.path(), json!({"image": "sky.exr", "strength": 1.0}));
    for (c, value) in image.mean_all().iter().enumerate() {
        assert!((value / 1.0 - 1.0).abs() < 0.02, "channel {c}: {value}");
    }
}

/// The image's centre column faces glTF (and Blender) +x, as Blender's Environment Texture does:
/// a wall facing +x is lit by a bright band there, and dark when the image turns 180 degrees.
#[test]
fn the_centre_of_an_environment_image_faces_plus_x() {
    let dir = tempfile::tempdir().unwrap();
    write_environment(
        &dir.path().join("band.exr"),
        64,
        32,
        |x, _| if (28..36).contains(&x) { 5.0 } else { 0.0 },
    );
    let render_wall = |rotation_deg: f32| {
        let mut gltf = GltfBuilder::default();
        let material = gltf.material(diffuse([0.5, 0.5, 0.5]));
        let (a, b, c, d) = ([0.0, -5.0, -5.0], [0.0, -5.0, 5.0], [0.0, 5.0, 5.0], [0.0, 5.0, -5.0]);
        gltf.mesh("Wall", &[[a, c, b], [a, d, c]], material);
        gltf.camera([1.0, 0.0, 0.0], [-1.0, 0.0, 0.0], 0.5);
        let world = json!({"image": "band.exr", "strength": 1.0, "rotation_deg": rotation_deg});
        gltf.scene_extras(json!({"resolution": [8, 8], "world": world}));
        let path = gltf.write(dir.path(), "wall");
        render(&settings(&path, dir.path(), 16), 2).luminance(0, 8, 0, 8)
    };
    let (facing, turned_away) = (render_wall(0.0), render_wall(180.0));
    assert!(facing > 0.1 && facing > 20.0 * turned_away, "lit {facing}, turned away {turned_away}");
}

/// A world image that cannot be read is a magenta world (radiance 1, 0, 1 times the strength), as
/// Cycles renders a missing environment image, and the warning names the file: the ground
/// reflects 0.5, 0, 0.5 (3%).
#[test]
fn a_missing_environment_image_is_magenta_and_named() {
    let dir = tempfile::tempdir().unwrap();
    let image = ground_under(dir.path(), json!({"image": "nowhere.hdr", "strength": 1.0}));
    let [r, g, b] = image.mean_all();
    assert!(
        (r / 0.5 - 1.0).abs() < 0.03 && (b / 0.5 - 1.0).abs() < 0.03 && g < 0.01,
        "not magenta: {r} {g} {b}"
    );
    let output = run_caustic(&["info", dir.path().join("ground.gltf").to_str().unwrap()]);
    let message = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{message}");
    assert!(message.contains("nowhere.hdr") && message.contains("magenta"), "{message}");
}
