//! Caustics and transport through glass in the bundled scenes.

mod common;

use caustic::scene::Scene;
use common::*;
use glam::Vec3;

/// The pixel where the world point `p` appears.
fn pixel_of(image: &Image, scene: &Scene, p: Vec3) -> (usize, usize) {
    let aspect = image.width as f32 / image.height as f32;
    let film = scene.camera.project(p, aspect).expect("point in front of the camera");
    ((film.x * image.width as f32) as usize, (film.y * image.height as f32) as usize)
}

/// Mean luminance of the 3x3 window at (x, y).
fn luminance_3x3(image: &Image, (x, y): (usize, usize)) -> f64 {
    image.luminance(x - 1, x + 2, y - 1, y + 2)
}

/// The brightest 3x3 window within `reach` pixels of `(x, y)`.
fn brightest_near(image: &Image, (x, y): (usize, usize), reach: usize) -> f64 {
    let mut best: f64 = 0.0;
    for j in y - reach..=y + reach {
        for i in x - reach..=x + reach {
            best = best.max(luminance_3x3(image, (i, j)));
        }
    }
    best
}

/// The demo scene's glass sphere focuses the area light onto the floor: the caustic (searched
/// within 16 pixels of where the line from the light through the sphere's centre meets the floor,
/// a paraxial estimate) must be at least 3 times as bright as the floor beside the sphere at a
/// similar distance from the light (measured: about 5 times).
#[test]
fn demo_scene_shows_a_caustic_under_the_sphere() {
    let dir = tempfile::tempdir().unwrap();
    let path = bundled_scene("cornell_glass.gltf");
    let mut s = settings(&path, dir.path(), 32);
    s.resolution = Some([480, 360]);
    let image = render(&s, 2);
    let scene = Scene::load(&path).unwrap();
    // Blender (x, y, z) is glTF (x, z, -y): the light at Blender (-0.3, 0.4, 1.98) through the
    // sphere's centre (0.3, -0.3, 0.55) meets the floor at (0.53, -0.57, 0).
    let caustic = brightest_near(&image, pixel_of(&image, &scene, Vec3::new(0.53, 0.0, 0.57)), 16);
    let beside = luminance_3x3(&image, pixel_of(&image, &scene, Vec3::new(-0.5, 0.0, 0.57)));
    assert!(caustic > 3.0 * beside, "caustic {caustic} vs floor beside it {beside}");
}

/// Renders the demo scene edited by `edit` at 120x90.
fn render_edited(edit: impl FnOnce(&mut serde_json::Value), passes: u64) -> Image {
    let dir = tempfile::tempdir().unwrap();
    let path = write_edited(&bundled_scene("cornell_glass.gltf"), dir.path(), edit);
    let mut s = settings(&path, dir.path(), passes);
    s.resolution = Some([120, 90]);
    s.photons = Some(40_000);
    render(&s, 2)
}

/// Index of the element of `doc[list]` named `name`.
fn index_named(doc: &serde_json::Value, list: &str, name: &str) -> usize {
    doc[list].as_array().unwrap().iter().position(|m| m["name"] == name).unwrap()
}

/// Sets the glass material's index of refraction.
fn set_glass_ior(doc: &mut serde_json::Value, ior: f64) {
    let glass = index_named(doc, "materials", "Glass");
    doc["materials"][glass]["extensions"]["KHR_materials_ior"] = serde_json::json!({"ior": ior});
    doc["extensionsUsed"].as_array_mut().unwrap().push("KHR_materials_ior".into());
}

/// Removes the glass sphere's node from the scene.
fn remove_sphere(doc: &mut serde_json::Value) {
    let sphere = index_named(doc, "nodes", "GlassSphere");
    doc["scenes"][0]["nodes"].as_array_mut().unwrap().retain(|n| n.as_u64() != Some(sphere as u64));
}

/// The largest relative difference between 10x10-pixel block luminances of two images, over
/// blocks bright enough to measure (luminance above 0.05).
fn largest_block_difference(a: &Image, b: &Image) -> f64 {
    let mut largest: f64 = 0.0;
    for by in 0..a.height / 10 {
        for bx in 0..a.width / 10 {
            let (x, y) = (bx * 10, by * 10);
            let (la, lb) = (a.luminance(x, x + 10, y, y + 10), b.luminance(x, x + 10, y, y + 10));
            if lb > 0.05 {
                largest = largest.max((la / lb - 1.0).abs());
            }
        }
    }
    largest
}

/// Glass of index 1.0 neither reflects nor bends light: the scene renders as if the sphere were
/// not there. Tolerance: the image means within 1.5% and every bright 10x10 block within 10% (the
/// noise of 64 passes of 40,000 photons); glass of index 1.5 must differ by more than 30%
/// somewhere (its shadow and caustic), so the comparison can fail.
#[test]
fn clear_glass_of_index_one_renders_as_no_glass() {
    let no_glass = render_edited(remove_sphere, 64);
    let index_one = render_edited(|doc| set_glass_ior(doc, 1.0), 64);
    let index_one_and_a_half = render_edited(|doc| set_glass_ior(doc, 1.5), 64);
    let (mean_a, mean_b) = (index_one.luminance(0, 120, 0, 90), no_glass.luminance(0, 120, 0, 90));
    assert!(
        (mean_a / mean_b - 1.0).abs() < 0.015,
        "image mean {mean_a} with IOR 1.0, {mean_b} without glass"
    );
    let difference = largest_block_difference(&index_one, &no_glass);
    assert!(difference < 0.10, "a block differs by {:.1}%", difference * 100.0);
    let glass_difference = largest_block_difference(&index_one_and_a_half, &no_glass);
    assert!(glass_difference > 0.3, "IOR 1.5 differs by only {:.1}%", glass_difference * 100.0);
}
