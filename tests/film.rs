//! The film's alpha: a transparent film (Blender's Film > Transparent) and holdouts (Blender's
//! Holdout shader, and objects in holdout collections) are holes in the film where the camera
//! sees them, while the world and the holdouts go on lighting and shadowing the scene.

mod common;

use caustic::render::{self, RenderSettings};
use common::*;
use serde_json::{json, Value};
use std::path::Path;

/// A white ground (albedo 0.5) under a uniform world of radiance 1 and a small sphere of
/// `sphere` material over it (its node's `caustic` extras `node_extras`), seen from the side so
/// that the top rows see the sky; rendered at 32 x 32 with `scene_extras` added.
fn ground_and_sphere(
    dir: &Path,
    sphere: Value,
    node_extras: Value,
    scene_extras: Value,
) -> (Image, Vec<f32>) {
    let mut gltf = GltfBuilder::default();
    let ground = gltf.material(diffuse([0.5, 0.5, 0.5]));
    gltf.quad_y("Ground", 0.0, 20.0, true, ground);
    let ball = gltf.material(sphere);
    gltf.sphere("Ball", [0.0, 0.6, 0.0], 0.5, 32, ball);
    if !node_extras.is_null() {
        gltf.set_node_extras(gltf.last_node(), node_extras);
    }
    gltf.camera([0.0, 1.0, 3.0], [0.0, -0.25, -1.0], 0.9);
    let mut extras = json!({"resolution": [32, 32], "world": {"color": [1.0, 1.0, 1.0]}});
    extras.as_object_mut().unwrap().extend(scene_extras.as_object().cloned().unwrap_or_default());
    gltf.scene_extras(extras);
    let path = gltf.write(dir, "ground");
    let report = render::render(&settings(&path, dir, 16)).unwrap();
    let channels = exr_channels(&report.frames[0].path);
    let alpha = channels.into_iter().find(|(name, _)| name == "Combined.A").expect("an alpha channel").1;
    (read_exr(&report.frames[0].path), alpha)
}

/// The rows of pixels that see the sky (over the horizon) and a block of ground in front.
const SKY: (usize, usize) = (0, 4);
const GROUND: (usize, usize) = (26, 32);
/// The sphere's centre pixel block.
const BALL: (usize, usize, usize, usize) = (14, 18, 13, 17);

fn mean_alpha(alpha: &[f32], x0: usize, x1: usize, y0: usize, y1: usize) -> f32 {
    let values: Vec<f32> = (y0..y1).flat_map(|y| (x0..x1).map(move |x| alpha[y * 32 + x])).collect();
    values.iter().sum::<f32>() / values.len() as f32
}

#[test]
fn a_transparent_film_hides_the_world_it_is_lit_by() {
    let dir = tempfile::tempdir().unwrap();
    let white = diffuse([0.8, 0.8, 0.8]);
    let (opaque, opaque_alpha) = ground_and_sphere(dir.path(), white.clone(), Value::Null, json!({}));
    let (image, alpha) = ground_and_sphere(dir.path(), white, Value::Null, json!({"transparent_film": true}));
    assert!(opaque_alpha.iter().all(|&a| a == 1.0), "an opaque film has alpha 1 everywhere");
    assert!(opaque.luminance(0, 32, SKY.0, SKY.1) > 0.9, "the sky is seen on an opaque film");
    assert_eq!(mean_alpha(&alpha, 0, 32, SKY.0, SKY.1), 0.0);
    assert_eq!(image.luminance(0, 32, SKY.0, SKY.1), 0.0, "the sky is not seen");
    assert_eq!(mean_alpha(&alpha, 0, 32, GROUND.0, GROUND.1), 1.0);
    let (lit, reference) =
        (image.luminance(0, 32, GROUND.0, GROUND.1), opaque.luminance(0, 32, GROUND.0, GROUND.1));
    assert!(
        (lit / reference - 1.0).abs() < 0.03,
        "the world still lights the ground: {lit} against {reference}"
    );
}

#[test]
fn a_holdout_is_a_black_hole_in_the_film_that_still_casts_its_shadow() {
    let dir = tempfile::tempdir().unwrap();
    let (plain, _) = ground_and_sphere(dir.path(), diffuse([0.8, 0.8, 0.8]), Value::Null, json!({}));
    let shader = json!({"pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.8, 1.0]}, "extras": {"caustic": {"holdout": true}}});
    let object = (diffuse([0.8, 0.8, 0.8]), json!({"holdout": true}));
    for (what, sphere, node) in
        [("Holdout shader", shader, Value::Null), ("holdout object", object.0, object.1)]
    {
        let (image, alpha) = ground_and_sphere(dir.path(), sphere, node, json!({}));
        let (x0, x1, y0, y1) = BALL;
        assert_eq!(mean_alpha(&alpha, x0, x1, y0, y1), 0.0, "{what}: the sphere is a hole");
        assert_eq!(image.luminance(x0, x1, y0, y1), 0.0, "{what}: the hole is black");
        assert_eq!(mean_alpha(&alpha, 0, 32, SKY.0, SKY.1), 1.0, "{what}: the sky stays");
        // Under the sphere (the contact shadow, rows just below it) the ground is as dark as
        // under a plain sphere: the holdout still blocks the world's light.
        let (shadowed, reference) = (image.luminance(14, 18, 24, 26), plain.luminance(14, 18, 24, 26));
        assert!((shadowed / reference - 1.0).abs() < 0.15, "{what}: shadow {shadowed} against {reference}");
    }
}

/// A crop (Blender's render region) renders the window's pixels exactly as the whole image's
/// render has them (each pixel keeps its samples, and the photons do not depend on the window).
#[test]
fn a_crop_is_the_same_pixels_as_the_whole_image() {
    let dir = tempfile::tempdir().unwrap();
    let scene = bundled_scene("cornell_glass.gltf");
    let whole_settings = RenderSettings {
        resolution: Some([48, 36]),
        photons: Some(4096),
        ..settings(&scene, &dir.path().join("whole"), 4)
    };
    let whole = render(&whole_settings, 2);
    let crop = render(
        &RenderSettings {
            crop: Some([10, 5, 20, 12]),
            out_dir: dir.path().join("crop"),
            ..whole_settings.clone()
        },
        1,
    );
    assert_eq!((crop.width, crop.height), (20, 12));
    for y in 0..12 {
        for x in 0..20 {
            assert_eq!(
                crop.rgb[y * 20 + x],
                whole.rgb[(y + 5) * 48 + x + 10],
                "pixel ({x}, {y}) of the crop"
            );
        }
    }
    let beyond = RenderSettings { crop: Some([40, 0, 10, 10]), ..whole_settings };
    let message = render::render(&beyond).err().expect("a crop beyond the image is refused");
    assert!(message.contains("--crop 40,0,10,10 reaches beyond the 48x36 image"), "{message}");
}

/// Denoising guides (`--denoising-passes`): the ground's albedo and the world's 1 in Cycles'
/// Denoising Albedo, the ground's normal in view space in Denoising Normal, and the image itself
/// the same bits as without them.
#[test]
fn denoising_passes_hold_the_albedo_and_normal_the_camera_sees() {
    let dir = tempfile::tempdir().unwrap();
    let mut gltf = GltfBuilder::default();
    let ground = gltf.material(diffuse([0.5, 0.25, 0.125]));
    gltf.quad_y("Ground", 0.0, 20.0, true, ground);
    // Looking down at 45 degrees: the ground's up normal is (0, cos 45, sin 45) in view space.
    gltf.camera([0.0, 1.0, 3.0], [0.0, -1.0, -1.0], 0.6);
    gltf.scene_extras(json!({"resolution": [16, 16], "world": {"color": [1.0, 1.0, 1.0]}}));
    let path = gltf.write(dir.path(), "ground");
    let plain = render::render(&settings(&path, &dir.path().join("plain"), 64)).unwrap();
    let guided_settings =
        RenderSettings { denoising_passes: true, ..settings(&path, &dir.path().join("guided"), 64) };
    let guided = render::render(&guided_settings).unwrap();
    let (plain, guided_image) = (read_exr(&plain.frames[0].path), read_exr(&guided.frames[0].path));
    assert_eq!(plain.rgb, guided_image.rgb, "the guides change nothing in the image");
    let channels = exr_channels(&guided.frames[0].path);
    let channel = |name: &str| {
        channels.iter().find(|(n, _)| n == name).unwrap_or_else(|| panic!("no {name}")).1.clone()
    };
    let mean = |values: &[f32]| values.iter().map(|&v| f64::from(v)).sum::<f64>() / values.len() as f64;
    for (c, expected) in [("R", 0.5), ("G", 0.25), ("B", 0.125)] {
        let albedo = mean(&channel(&format!("Denoising Albedo.{c}")));
        assert!((albedo / expected - 1.0).abs() < 0.05, "albedo {c}: {albedo} against {expected}");
    }
    let half = std::f64::consts::FRAC_1_SQRT_2;
    for (c, expected) in [("X", 0.0), ("Y", half), ("Z", half)] {
        let normal = mean(&channel(&format!("Denoising Normal.{c}")));
        assert!((normal - expected).abs() < 0.01, "normal {c}: {normal} against {expected}");
    }
}
