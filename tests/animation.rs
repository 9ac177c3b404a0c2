//! Animation, motion blur, depth of field and frame ranges, against closed forms.

mod common;

use caustic::render::{self, RenderReport, RenderSettings};
use caustic::scene::Scene;
use common::*;
use glam::Vec3;
use serde_json::json;
use std::path::{Path, PathBuf};

/// A white emitter of radiance 10, a `size` square in the plane z = 0 facing +z.
fn emitter(gltf: &mut GltfBuilder, size: f32) -> usize {
    let material = gltf.material(json!({"emissiveFactor": [1.0, 1.0, 1.0],
        "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 10.0}},
        "pbrMetallicRoughness": {"baseColorFactor": [0.0, 0.0, 0.0, 1.0]}}));
    let h = size / 2.0;
    let (a, b, c, d) = ([-h, -h, 0.0], [h, -h, 0.0], [h, h, 0.0], [-h, h, 0.0]);
    gltf.mesh("Emitter", &[[a, b, c], [a, c, d]], material);
    gltf.last_node()
}

fn render_report(settings: &RenderSettings) -> RenderReport {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
    pool.install(|| render::render(settings)).unwrap_or_else(|e| panic!("render failed: {e}"))
}

/// Mean luminance of the rows `rows` at each column.
fn column_profile(image: &Image, rows: std::ops::Range<usize>) -> Vec<f64> {
    (0..image.width).map(|x| image.luminance(x, x + 1, rows.start, rows.end)).collect()
}

/// The width (pixels) between the half-maximum crossings of a profile, linearly interpolated.
fn full_width_at_half_maximum(profile: &[f64]) -> f64 {
    let peak = profile.iter().copied().fold(0.0, f64::max);
    let half = peak / 2.0;
    let first = profile.iter().position(|&v| v >= half).unwrap();
    let last = profile.iter().rposition(|&v| v >= half).unwrap();
    let left = first as f64 - (profile[first] - half) / (profile[first] - profile[first - 1]);
    let right = last as f64 + (profile[last] - half) / (profile[last] - profile[last + 1]);
    right - left
}

/// A 0.1 square emitter moving from x = -1 at t = 0 to x = 1 at t = 2/24 s, seen from z = 5.
fn moving_emitter_scene(dir: &Path) -> PathBuf {
    let mut gltf = GltfBuilder::default();
    let node = emitter(&mut gltf, 0.1);
    gltf.animate(
        node,
        "translation",
        &[0.0, 2.0 / 24.0],
        &[vec![-1.0, 0.0, 0.0], vec![1.0, 0.0, 0.0]],
        "LINEAR",
    );
    gltf.camera_with_aspect([0.0, 0.0, 5.0], [0.0, 0.0, -1.0], 0.3, 4.0);
    gltf.scene_extras(json!({"resolution": [128, 32], "fps": 24.0,
        "shutter": {"length_frames": 1.0, "position": "CENTER"}}));
    gltf.write(dir, "moving")
}

/// Frame 1's shutter (one frame, centred) sweeps the emitter from x = -0.5 to 0.5: the streak's
/// width at half maximum is that distance projected (within 1 pixel), and its total light equals
/// the still emitter's (within 2%).
#[test]
fn motion_blur_streaks_over_the_projected_distance_and_keeps_the_energy() {
    let dir = tempfile::tempdir().unwrap();
    let path = moving_emitter_scene(dir.path());
    let mut s = settings(&path, &dir.path().join("blur"), 256);
    s.photons = Some(1000);
    let blurred = render(&s, 2);
    s.out_dir = dir.path().join("still");
    s.shutter_frames = Some(0.0);
    let still = render(&s, 2);
    let scene = Scene::load(&path).unwrap();
    let aspect = 4.0;
    let end_x = |x: f32| scene.camera.project(Vec3::new(x, 0.0, 0.0), aspect).unwrap().x as f64 * 128.0;
    let expected = end_x(0.5) - end_x(-0.5);
    let measured = full_width_at_half_maximum(&column_profile(&blurred, 15..17));
    eprintln!("motion blur: streak {measured:.2} px, projected sweep {expected:.2} px");
    assert!((measured - expected).abs() <= 1.0, "streak {measured:.2} px, expected {expected:.2} px");
    let (energy_blurred, energy_still) = (blurred.luminance(0, 128, 0, 32), still.luminance(0, 128, 0, 32));
    eprintln!("motion blur: energy {energy_blurred:.6} vs still {energy_still:.6}");
    assert!(
        (energy_blurred / energy_still - 1.0).abs() < 0.02,
        "energy {energy_blurred} vs still {energy_still}"
    );
}

/// The diameter (pixels) of a uniform disc of light from its second moment: a disc of diameter
/// D has mean squared radius D^2 / 8 (robust to noise, unlike a half-maximum on sparse samples).
/// The disc is convolved with the object's own sharp image, a square of side `object_px` centred
/// on the image's centre; variances add, so that image's second moment, as the pixels sample it,
/// is taken away.
fn disc_diameter(image: &Image, object_px: f64) -> f64 {
    let mean_r2 = second_moment(
        &(0..image.rgb.len())
            .map(|i| {
                ((i % image.width) as f64 + 0.5, (i / image.width) as f64 + 0.5, image.rgb[i][1].max(0.0))
            })
            .collect::<Vec<_>>(),
    );
    let sharp = sharp_square(object_px, image.width as f64 / 2.0);
    (8.0 * (mean_r2 - 2.0 * sharp)).max(0.0).sqrt()
}

/// The mean squared distance from their centroid of weighted points `(x, y, weight)`.
fn second_moment(points: &[(f64, f64, f64)]) -> f64 {
    let total: f64 = points.iter().map(|w| w.2).sum();
    let (cx, cy) = points.iter().fold((0.0, 0.0), |(x, y), w| (x + w.0 * w.2 / total, y + w.1 * w.2 / total));
    points.iter().map(|w| ((w.0 - cx).powi(2) + (w.1 - cy).powi(2)) * w.2 / total).sum()
}

/// The variance along one axis of a sharp square of side `side` centred at `centre`, as pixels
/// (each the mean over its unit square) sample it at their centres. For 2.55 px centred on a
/// pixel corner it is 0.69, where the continuous `(side^2 + 1) / 12` gives 0.63: the difference
/// alone reads as a blur of 1.0 px.
fn sharp_square(side: f64, centre: f64) -> f64 {
    let (lo, hi) = (centre - side / 2.0, centre + side / 2.0);
    let pixels: Vec<(f64, f64, f64)> = (lo.floor() as i64..hi.ceil() as i64)
        .map(|i| (i as f64 + 0.5, 0.0, (hi.min(i as f64 + 1.0) - lo.max(i as f64)).max(0.0)))
        .collect();
    second_moment(&pixels)
}

/// A small emitter (0.02 wide) at distance 5 behind a thin lens of aperture radius
/// 50 mm / (2 x 0.25) = 0.1: focused at 2.5 it becomes a disc of diameter 2 A |z - f| / z on the
/// plane in focus, projected (within 1 pixel, measured by the disc's second moment less the
/// emitter's own size); focused at 5 its blur stays within a pixel (the same measure below 1).
#[test]
fn depth_of_field_blurs_to_the_circle_of_confusion() {
    let dir = tempfile::tempdir().unwrap();
    let scene_with_focus = |focus: f32| {
        let mut gltf = GltfBuilder::default();
        emitter(&mut gltf, 0.02);
        gltf.camera([0.0, 0.0, 5.0], [0.0, 0.0, -1.0], 0.2);
        let camera = gltf.last_node();
        let mut doc = gltf.to_json();
        doc["nodes"][camera]["extras"] =
            json!({"caustic": {"lens": {"fstop": 0.25, "focus_distance": focus, "focal_length_mm": 50.0}}});
        doc["scenes"][0]["extras"] = json!({"caustic": {"resolution": [128, 128]}});
        let path = dir.path().join(format!("lens_{focus}.gltf"));
        std::fs::write(&path, doc.to_string()).unwrap();
        let mut s = settings(&path, &dir.path().join(format!("out_{focus}")), 256);
        s.photons = Some(1000);
        render(&s, 2)
    };
    let blurred = scene_with_focus(2.5);
    let (aperture, object, focus) = (0.1f64, 5.0f64, 2.5f64);
    let diameter_on_focus_plane = 2.0 * aperture * (object - focus) / object;
    let pixels_per_unit = 128.0 / (2.0 * focus * (0.1f64).tan());
    let expected = diameter_on_focus_plane * pixels_per_unit;
    let measured = disc_diameter(&blurred, 0.02 * focus / object * pixels_per_unit);
    eprintln!("depth of field: disc {measured:.2} px, circle of confusion {expected:.2} px");
    assert!((measured - expected).abs() <= 1.0, "disc {measured:.2} px, expected {expected:.2} px");

    let sharp = scene_with_focus(5.0);
    let blur = disc_diameter(&sharp, 0.02 * pixels_per_unit * focus / object);
    eprintln!("depth of field: in focus, blur {blur:.2} px");
    assert!(blur < 1.0, "in focus: blurred over {blur:.2} px");
}

/// Frame 2 of a 1-3 range is the same bits as frame 2 rendered alone (a frame's passes depend
/// only on the seed, the pass and the frame's own time).
#[test]
fn a_frame_in_a_range_is_the_frame_rendered_alone() {
    let dir = tempfile::tempdir().unwrap();
    let path = moving_emitter_scene(dir.path());
    let mut s = settings(&path, &dir.path().join("range"), 8);
    s.photons = Some(500);
    s.frames = vec![1, 2, 3];
    let range = render_report(&s);
    s.out_dir = dir.path().join("alone");
    s.frames = vec![2];
    let alone = render_report(&s);
    assert_eq!(range.frames.len(), 3);
    assert_eq!(read_exr(&range.frames[1].path).rgb, read_exr(&alone.frames[0].path).rgb);
}

/// What a scene does not need is skipped: a static scene over 10 frames builds its BVH once and
/// is never posed again; without an aperture the lens is never sampled; a moving scene is posed
/// at every pass.
#[test]
fn work_a_scene_does_not_need_is_skipped() {
    let dir = tempfile::tempdir().unwrap();
    let mut s = settings(&bundled_scene("furnace.gltf"), &dir.path().join("static"), 2);
    s.resolution = Some([8, 8]);
    s.frames = (1..=10).collect();
    let still = render_report(&s);
    assert_eq!((still.frames.len(), still.fixed_bvh_builds, still.poses), (10, 1, 0));
    assert!(still.frames.iter().all(|f| f.stats.lens_samples == 0));
    s.fstop = Some(2.0);
    s.frames = vec![1];
    let with_lens = render_report(&s);
    assert!(with_lens.frames[0].stats.lens_samples > 0);
    let path = moving_emitter_scene(dir.path());
    let mut s = settings(&path, &dir.path().join("moving"), 3);
    s.frames = vec![1, 2];
    assert_eq!(render_report(&s).poses, 6);
}

/// `--resume` skips frames whose EXR exists and renders the rest.
#[test]
fn resume_skips_finished_frames() {
    let dir = tempfile::tempdir().unwrap();
    let mut s = settings(&bundled_scene("furnace.gltf"), dir.path(), 1);
    s.resolution = Some([4, 4]);
    s.frames = vec![1, 2];
    render_report(&s);
    s.frames = vec![1, 2, 3];
    s.resume = true;
    let report = render_report(&s);
    assert_eq!(report.skipped, vec![1, 2]);
    assert_eq!(report.frames.iter().map(|f| f.frame).collect::<Vec<_>>(), vec![3]);
    assert!(dir.path().join("frame_0003.exr").exists());
}

/// `caustic info` says what a scene needs: the Blender-exported animated box needs motion blur,
/// depth of field and a moving camera; the still demo needs none of them (nor absorption, nor
/// alpha) and skips their work; the glass of water needs absorption.
#[test]
fn info_reports_what_a_scene_needs() {
    let info = |scene: &str| {
        let output = run_caustic(&["info", bundled_scene(scene).to_str().unwrap(), "--frames", "1-24"]);
        assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
        serde_json::from_slice::<serde_json::Value>(&output.stdout).unwrap()
    };
    let animated = info("cornell_animated.gltf");
    let needs = &animated["needs"];
    assert_eq!(
        (needs["motion_blur"].as_bool(), needs["depth_of_field"].as_bool(), needs["moving_camera"].as_bool()),
        (Some(true), Some(true), Some(true))
    );
    assert!(
        animated["triangles"]["moving"].as_u64().unwrap() > 0
            && animated["triangles"]["static"].as_u64().unwrap() > 0
    );
    let still = info("cornell_glass.gltf");
    assert_eq!(still["needs"]["motion_blur"], false);
    assert_eq!(still["needs"]["depth_of_field"], false);
    assert_eq!(still["triangles"]["moving"], 0);
    assert!(still["skipped"]
        .as_array()
        .unwrap()
        .iter()
        .any(|s| s.as_str().unwrap().contains("lens sampling")));
    // Absorption: the glass of water's water absorbs, the demo's glass does not.
    assert_eq!(
        (still["needs"]["absorption"].as_bool(), still["needs"]["alpha"].as_bool()),
        (Some(false), Some(false))
    );
    assert_eq!(info("water_glass.gltf")["needs"]["absorption"], true);
}
