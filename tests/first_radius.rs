//! The first radius when none is given (`src/transport/footprint.rs`): from the view where the camera
//! sees surfaces and the photons a pass lands there, not from the scene's size. A close-up and a
//! wide shot of one room get radii apart as their views' sizes to the 2/3; a render region gets
//! the whole render's; a camera that sees no surface falls back to the scene's size.

mod common;

use std::sync::Arc;

use caustic::render::{load_description, RenderSettings, Shot};
use common::*;
use serde_json::{json, Value};

/// A 10 m square room 4 m high, white, lit by a point light 3 m up, seen straight down from
/// `camera_height` (a 32x32 image of vertical field of view 0.8 rad).
fn room(dir: &std::path::Path, camera_height: f32) -> std::path::PathBuf {
    let mut gltf = GltfBuilder::default();
    let white = gltf.material(
        json!({"pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.8, 1.0], "metallicFactor": 0.0}}),
    );
    gltf.quad_y("Floor", 0.0, 5.0, true, white);
    gltf.quad_y("Ceiling", 4.0, 5.0, false, white);
    gltf.light(
        json!({"type": "point", "intensity": 100.0, "color": [1.0, 1.0, 1.0]}),
        [0.0, 3.0, 0.0],
        [0.0, -1.0, 0.0],
    );
    gltf.camera([0.0, camera_height, 0.0], [0.0, -1.0, 0.0], 0.8);
    gltf.scene_extras(json!({"resolution": [32, 32]}));
    gltf.write(dir, &format!("room_{camera_height}"))
}

/// What `caustic info` says of the photons of `scene` at `photons` a pass.
fn photons_info(scene: &std::path::Path, photons: u64) -> Value {
    let output = run_caustic(&["info", scene.to_str().unwrap(), "--photons", &photons.to_string()]);
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    serde_json::from_slice::<Value>(&output.stdout).unwrap()["photons"].clone()
}

#[test]
fn a_close_up_and_a_wide_shot_get_radii_apart_as_their_views_to_the_two_thirds() {
    let dir = tempfile::tempdir().unwrap();
    let (close, wide) =
        (photons_info(&room(dir.path(), 0.5), 400_000), photons_info(&room(dir.path(), 2.0), 400_000));
    let size = |info: &Value| info["radius_from"]["view_size"].as_f64().unwrap();
    let radius = |info: &Value| info["initial_radius"].as_f64().unwrap();
    eprintln!("close-up {close}\nwide {wide}");
    // The film's size at the floor grows with the camera's height: exactly 4x, and 2 tan(0.4) h.
    assert!(
        (size(&wide) / size(&close) - 4.0).abs() < 1e-3,
        "view sizes {} and {}",
        size(&close),
        size(&wide)
    );
    assert!((size(&wide) - 2.0 * 0.4f64.tan() * 2.0).abs() < 1e-3 * size(&wide), "wide view {}", size(&wide));
    // The floor's photon density is the same in both views (the light bounces off the ceiling
    // over the whole floor): the least error's radius goes as S^(2/3) (the density is measured,
    // so within 10%).
    let ratio = radius(&wide) / radius(&close);
    assert!(
        (ratio / 4f64.powf(2.0 / 3.0) - 1.0).abs() < 0.1,
        "radii {} and {}: ratio {ratio}",
        radius(&close),
        radius(&wide)
    );
}

#[test]
fn a_view_that_few_photons_reach_gets_a_wider_radius() {
    let dir = tempfile::tempdir().unwrap();
    let scene = room(dir.path(), 2.0);
    let (many, few) = (photons_info(&scene, 400_000), photons_info(&scene, 400_000 / 64));
    let radius = |info: &Value| info["initial_radius"].as_f64().unwrap();
    let density = |info: &Value| info["radius_from"]["photons_per_view"].as_f64().unwrap();
    eprintln!("many {many}\nfew {few}");
    // The measured density follows the photons a pass (within the probe's noise) ...
    assert!(
        (density(&many) / density(&few) / 64.0 - 1.0).abs() < 0.15,
        "{} and {}",
        density(&many),
        density(&few)
    );
    // ... and the radius grows as it falls: as its -1/6 power, or faster where the first pass
    // must land a photon within it.
    assert!(radius(&few) / radius(&many) >= 2.0 * 0.95, "radii {} and {}", radius(&many), radius(&few));
}

#[test]
fn a_camera_that_sees_no_surface_takes_the_scenes_size() {
    let dir = tempfile::tempdir().unwrap();
    let mut gltf = GltfBuilder::default();
    let white = gltf.material(
        json!({"pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.8, 1.0], "metallicFactor": 0.0}}),
    );
    gltf.quad_y("Floor", 0.0, 5.0, true, white);
    gltf.light(
        json!({"type": "point", "intensity": 100.0, "color": [1.0, 1.0, 1.0]}),
        [0.0, 3.0, 0.0],
        [0.0, -1.0, 0.0],
    );
    gltf.camera([0.0, 1.0, 0.0], [0.0, 1.0, 0.0], 0.8);
    gltf.scene_extras(json!({"resolution": [32, 32]}));
    let info = photons_info(&gltf.write(dir.path(), "up"), 1024);
    assert_eq!(info["radius_from"], json!("the scene's size (the camera sees no surface)"), "{info}");
    // 2% of the bounding sphere's diameter (the floor's half diagonal is 7.1).
    let radius = info["initial_radius"].as_f64().unwrap();
    assert!(radius > 0.04 * 5.0 && radius < 0.04 * 7.5, "{radius}");
}

#[test]
fn a_render_region_gets_the_whole_renders_radius() {
    let dir = tempfile::tempdir().unwrap();
    let scene = room(dir.path(), 2.0);
    let radius = |crop: Option<[u32; 4]>| {
        let settings = RenderSettings { crop, ..settings(&scene, dir.path(), 1) };
        let description = Arc::new(load_description(&settings).unwrap());
        Shot::new(&settings, description).unwrap().pass_settings().initial_radius
    };
    assert_eq!(radius(None), radius(Some([3, 5, 10, 7])));
}

/// An animated scene's view is measured at frame 1 whatever frames a render covers: a farm task
/// rendering frame 5 alone and a render of frames 1-10 give frame 5 the same radius, so their
/// passes merge.
#[test]
fn every_frame_range_of_an_animated_shot_gets_the_same_radius() {
    let dir = tempfile::tempdir().unwrap();
    let radius = |frames: Vec<i32>| {
        let settings =
            RenderSettings { frames, ..settings(&bundled_scene("cornell_animated.gltf"), dir.path(), 1) };
        let description = Arc::new(load_description(&settings).unwrap());
        let shot = Shot::new(&settings, description).unwrap();
        assert!(shot.view().is_some(), "the camera sees the box");
        shot.pass_settings().initial_radius
    };
    assert_eq!(radius(vec![5]), radius((1..=10).collect()));
    assert_eq!(radius(vec![5]), radius(vec![20, 21]));
}
