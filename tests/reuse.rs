//! Reuse across frames (Weiss & Grosch's DSPPM): frames rendered together share the paths on
//! static geometry, and must render what each frame rendered alone renders.
//!
//! A frame in a block gets exactly the paths it would trace alone (the shared ones where nothing
//! moving blocks them, the rest traced again, or resumed from the blocked segment, with the same
//! random numbers), so a block and `--no-reuse` agree pixel for pixel up to float rounding, by
//! either method: the sums are added in another order. Tolerance: 1e-4 relative (+ 1e-6
//! absolute), far below the noise.

mod common;

use caustic::render::{self, RenderReport, RenderSettings};
use caustic::scene::Scene;
use caustic::transport::Method;
use common::*;
use glam::{Vec2, Vec3};
use serde_json::json;
use std::path::{Path, PathBuf};

fn render_frames(settings: &RenderSettings, threads: usize) -> RenderReport {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
    pool.install(|| render::render(settings)).unwrap_or_else(|e| panic!("render failed: {e}"))
}

fn frame_image(settings: &RenderSettings, frame: i32) -> Image {
    read_exr(&render::frame_path(&settings.out_dir, frame))
}

/// Asserts that every channel of every pixel of `a` is within `1e-4 |b| + 1e-6` of `b`.
fn assert_same_up_to_rounding(a: &Image, b: &Image, what: &str) {
    let worst = a
        .rgb
        .iter()
        .zip(&b.rgb)
        .flat_map(|(p, q)| (0..3).map(move |c| (p[c] - q[c]).abs() / (1e-4 * q[c].abs() + 1e-6)))
        .fold(0.0, f64::max);
    assert!(worst <= 1.0, "{what}: differs by {worst:.1} times the rounding tolerance");
}

/// How the reuse runs of [`assert_reuse_renders_each_frame_alone`] rendered.
struct Reuse {
    /// Frames rendered together (the same for both methods).
    block: usize,
    /// Every run, by both methods, traced camera paths once for all the frames of a block.
    shares_camera_paths: bool,
}

/// Renders `scene`'s `frames` with reuse and with `--no-reuse` for several seeds, by both
/// methods, and compares every frame.
fn assert_reuse_renders_each_frame_alone(scene: &Path, frames: &[i32], resolution: [u32; 2]) -> Reuse {
    let dir = tempfile::tempdir().unwrap();
    let (mut blocks, mut shares_camera_paths) = (Vec::new(), true);
    for (method, seed) in [Method::Sppm, Method::Vcm].into_iter().flat_map(|m| [(m, 1), (m, 2), (m, 3)]) {
        let name = format!("{}{seed}", method.flag());
        let mut shared = settings(scene, &dir.path().join(format!("shared_{name}")), 6);
        shared.frames = frames.to_vec();
        shared.resolution = Some(resolution);
        shared.photons = Some(4000);
        shared.seed = seed;
        shared.method = method;
        let alone = RenderSettings {
            reuse: false,
            out_dir: dir.path().join(format!("alone_{name}")),
            ..shared.clone()
        };
        let report = render_frames(&shared, 2);
        blocks.push(report.block_frames);
        shares_camera_paths &= report.shared_stats.eye_rays > 0;
        assert_eq!(render_frames(&alone, 2).block_frames, 1);
        for &frame in frames {
            let what = format!("{} frame {frame} {name}", scene.display());
            assert_same_up_to_rounding(&frame_image(&shared, frame), &frame_image(&alone, frame), &what);
        }
    }
    assert!(blocks.iter().all(|&b| b == blocks[0]), "both methods render the same blocks: {blocks:?}");
    Reuse { block: blocks[0], shares_camera_paths }
}

#[test]
fn a_still_camera_shares_eye_and_photon_paths_and_renders_each_frame_as_alone() {
    let reuse = assert_reuse_renders_each_frame_alone(&bundled_scene("shot.gltf"), &[1, 9, 17, 24], [64, 48]);
    assert_eq!(reuse.block, 4, "all four frames render together");
    assert!(reuse.shares_camera_paths, "the camera paths are traced once for the four frames");
}

#[test]
fn a_moving_camera_shares_photon_paths_and_renders_each_frame_as_alone() {
    assert_reuse_renders_each_frame_alone(&bundled_scene("shot_moving_camera.gltf"), &[1, 12, 24], [64, 48]);
}

/// A point light that moves over a floor with a static box: its photons are traced per frame,
/// and nothing else may change.
#[test]
fn a_moving_light_renders_each_frame_as_alone() {
    let dir = tempfile::tempdir().unwrap();
    let mut gltf = GltfBuilder::default();
    let white = gltf.material(diffuse([0.8, 0.8, 0.8]));
    gltf.quad_y("Floor", 0.0, 3.0, true, white);
    gltf.sphere("Ball", [0.0, 0.5, 0.0], 0.5, 8, white);
    gltf.light(json!({"type": "point", "intensity": 4000.0}), [-1.0, 2.0, 0.0], [0.0, -1.0, 0.0]);
    let light = gltf.last_node();
    gltf.animate(light, "translation", &[0.0, 1.0], &[vec![-1.0, 2.0, 0.0], vec![1.0, 2.0, 0.0]], "LINEAR");
    gltf.camera([0.0, 3.0, 4.0], [0.0, -3.0, -4.0], 0.9);
    gltf.scene_extras(json!({"fps": 24.0}));
    let scene = gltf.write(dir.path(), "moving_light");
    assert_reuse_renders_each_frame_alone(&scene, &[1, 12, 24], [48, 48]);
}

/// A point light whose intensity and colour change, a glowing square whose emission changes and
/// a ball whose base colour and roughness change (`KHR_animation_pointer`), over a still floor:
/// what they light is traced per frame, the floor stays shared, and nothing else may change.
#[test]
fn animated_values_render_each_frame_as_alone() {
    let dir = tempfile::tempdir().unwrap();
    let mut gltf = GltfBuilder::default();
    let white = gltf.material(diffuse([0.8, 0.8, 0.8]));
    gltf.quad_y("Floor", 0.0, 3.0, true, white);
    let ball = gltf.material(diffuse([0.2, 0.8, 0.2]));
    gltf.sphere("Ball", [0.0, 0.5, 0.0], 0.5, 8, ball);
    let glow = gltf.material(json!({"emissiveFactor": [1.0, 0.5, 0.2]}));
    gltf.quad_y("Glow", 0.01, 0.3, true, glow);
    gltf.light(json!({"type": "point", "intensity": 4000.0}), [-1.0, 2.0, 0.0], [0.0, -1.0, 0.0]);
    gltf.camera([0.0, 3.0, 4.0], [0.0, -3.0, -4.0], 0.9);
    gltf.scene_extras(json!({"fps": 24.0}));
    let times = [0.0, 1.0];
    let keys = |a: &[f32], b: &[f32]| [a.to_vec(), b.to_vec()];
    gltf.animate_pointer(
        "/extensions/KHR_lights_punctual/lights/0/intensity",
        &times,
        &keys(&[1000.0], &[6000.0]),
        "LINEAR",
    );
    gltf.animate_pointer(
        "/extensions/KHR_lights_punctual/lights/0/color",
        &times,
        &keys(&[1.0, 1.0, 1.0], &[1.0, 0.3, 0.1]),
        "LINEAR",
    );
    gltf.animate_pointer(
        &format!("/materials/{glow}/emissiveFactor"),
        &times,
        &keys(&[1.0, 0.5, 0.2], &[0.1, 0.2, 1.0]),
        "STEP",
    );
    let factor = format!("/materials/{ball}/pbrMetallicRoughness/baseColorFactor");
    gltf.animate_pointer(&factor, &times, &keys(&[0.2, 0.8, 0.2, 1.0], &[0.8, 0.2, 0.2, 1.0]), "LINEAR");
    let roughness = format!("/materials/{ball}/pbrMetallicRoughness/roughnessFactor");
    gltf.animate_pointer(&roughness, &times, &keys(&[1.0], &[0.2]), "LINEAR");
    let scene = gltf.write(dir.path(), "animated_values");
    let reuse = assert_reuse_renders_each_frame_alone(&scene, &[1, 12, 24], [48, 48]);
    assert!(reuse.block > 1, "the still floor is shared: frames render together");
}

/// A ball moving over a still grid of instanced boxes (`EXT_mesh_gpu_instancing`, two levels):
/// the boxes are shared like the floor, and nothing else may change.
#[test]
fn instanced_meshes_render_each_frame_as_alone() {
    let dir = tempfile::tempdir().unwrap();
    let mut gltf = GltfBuilder::default();
    let white = gltf.material(diffuse([0.8, 0.8, 0.8]));
    gltf.quad_y("Floor", 0.0, 3.0, true, white);
    gltf.mesh("Box", &box_triangles([-0.1, 0.0, -0.1], [0.1, 0.3, 0.1]), white);
    let boxes = gltf.last_node();
    let places: Vec<[f32; 3]> =
        (0..25).map(|k| [(k % 5) as f32 * 0.5 - 1.0, 0.0, (k / 5) as f32 * 0.5 - 1.0]).collect();
    gltf.instance(boxes, &places, &vec![[0.0, 0.0, 0.0, 1.0]; 25], &vec![[1.0; 3]; 25]);
    gltf.sphere("Ball", [0.0, 0.6, 0.0], 0.25, 8, white);
    let ball = gltf.last_node();
    gltf.animate(ball, "translation", &[0.0, 1.0], &[vec![-1.0, 0.0, 0.0], vec![1.0, 0.0, 0.0]], "LINEAR");
    gltf.light(json!({"type": "point", "intensity": 4000.0}), [0.0, 2.0, 0.5], [0.0, -1.0, 0.0]);
    gltf.camera([0.0, 3.0, 4.0], [0.0, -3.0, -4.0], 0.9);
    gltf.scene_extras(json!({"fps": 24.0}));
    let scene = gltf.write(dir.path(), "instanced");
    let reuse = assert_reuse_renders_each_frame_alone(&scene, &[1, 12, 24], [48, 48]);
    assert!(reuse.block > 1, "the floor and the boxes are shared: frames render together");
    assert!(reuse.shares_camera_paths, "the camera paths are traced once for the frames");
}

/// A skinned square whose morph target weight is animated, over a still lit floor: the square
/// deforms and joins the moving part, the floor stays shared, and nothing else may change.
#[test]
fn a_deforming_mesh_renders_each_frame_as_alone() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("deformed.gltf");
    std::fs::write(&scene, deformed_square().to_string()).unwrap();
    let reuse = assert_reuse_renders_each_frame_alone(&scene, &[1, 12, 24], [48, 48]);
    assert!(reuse.block > 1, "the still floor is shared: frames render together");
}

/// A floor under a point light, with a red ball that rests at x = -1 until frame 4, rolls to
/// x = +1 by frame 7 and rests there.
fn rolling_ball_scene(dir: &Path) -> PathBuf {
    let mut gltf = GltfBuilder::default();
    let white = gltf.material(diffuse([0.8, 0.8, 0.8]));
    let red = gltf.material(diffuse([0.8, 0.1, 0.1]));
    gltf.quad_y("Floor", 0.0, 6.0, true, white);
    gltf.sphere("Ball", [0.0, 0.0, 0.0], 0.5, 24, red);
    let ball = gltf.last_node();
    let keys = [vec![-1.0, 0.5, 0.0], vec![1.0, 0.5, 0.0]];
    gltf.animate(ball, "translation", &[4.0 / 24.0, 7.0 / 24.0], &keys, "LINEAR");
    gltf.light(
        json!({"type": "point", "intensity": 4.0 * std::f32::consts::PI * 683.0}),
        [0.0, 4.0, 0.0],
        [0.0, -1.0, 0.0],
    );
    gltf.camera_with_aspect([0.0, 5.0, 6.0], [0.0, -5.0, -6.0], 0.6, 1.0);
    gltf.scene_extras(json!({"fps": 24.0}));
    gltf.write(dir, "rolling_ball")
}

/// Reuse is decided per span of frames over which the same things move: the ball rolling only
/// between frames 4 and 7 is static geometry in frames 1-4 and 8-10 (those spans are never
/// posed), and every frame still renders as it does alone.
#[test]
fn an_object_moving_mid_range_is_static_before_and_after() {
    let dir = tempfile::tempdir().unwrap();
    let scene = rolling_ball_scene(dir.path());
    let frames: Vec<i32> = (1..=10).collect();
    let reuse = assert_reuse_renders_each_frame_alone(&scene, &frames, [48, 48]);
    assert_eq!(reuse.block, 4, "the longest span, frames 1-4, renders together");
    let mut s = settings(&scene, &dir.path().join("spans"), 2);
    (s.frames, s.resolution) = (frames, Some([16, 16]));
    let report = render_frames(&s, 2);
    assert_eq!(report.fixed_bvh_builds, 3, "spans 1-4, 5-7 and 8-10");
    let info = caustic::info::report(&s).unwrap();
    assert_eq!(info["spans"], json!([[1, 2, 3, 4], [5, 6, 7], [8, 9, 10]]), "caustic info names the spans");
    assert_eq!(report.poses, 3, "only the frames where the ball rolls are posed");
    let still = |f: i32| read_exr(&render::frame_path(&s.out_dir, f)).rgb;
    assert!(still(1) == still(4) && still(8) == still(10), "frames where nothing moves are alike");
    assert!(still(1) != still(8), "the ball has moved");
}

/// A white floor lit by a point light of 4 pi W/sr 4 above the origin (floor radiance
/// 16 / d^3 at distance d), with a glass ball (radius 0.5, centre 1 above the floor) that jumps
/// from x = -1.2 in frame 1 to x = +1.2 in frame 2, seen from above at an angle.
fn jumping_ball_scene(dir: &Path) -> PathBuf {
    let mut gltf = GltfBuilder::default();
    let white = gltf.material(diffuse([1.0, 1.0, 1.0]));
    let glass = gltf.material(
        json!({"pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, 1.0], "roughnessFactor": 0.0},
        "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1.0}}}),
    );
    gltf.quad_y("Floor", 0.0, 6.0, true, white);
    gltf.sphere("Ball", [0.0, 0.0, 0.0], 0.5, 48, glass);
    let ball = gltf.last_node();
    gltf.animate(
        ball,
        "translation",
        &[0.0, 1.5 / 24.0],
        &[vec![-1.2, 1.0, 0.0], vec![1.2, 1.0, 0.0]],
        "STEP",
    );
    gltf.light(
        json!({"type": "point", "intensity": 4.0 * std::f32::consts::PI * 683.0}),
        [0.0, 4.0, 0.0],
        [0.0, -1.0, 0.0],
    );
    gltf.camera_with_aspect([0.0, 5.0, 6.0], [0.0, -5.0, -6.0], 0.6, 1.5);
    gltf.scene_extras(json!({"fps": 24.0, "resolution": [96, 64]}));
    gltf.write(dir, "jumping_ball")
}

/// The floor's radiance without the ball, 16 / d^3, at the floor point pixel (x, y) sees.
fn bare_floor_radiance(scene: &Scene, image: &Image, x: usize, y: usize) -> f64 {
    let film = Vec2::new((x as f32 + 0.5) / image.width as f32, (y as f32 + 0.5) / image.height as f32);
    let (origin, direction) = scene.camera.ray(film, image.width as f32 / image.height as f32);
    let p = origin - direction * (origin.y / direction.y);
    16.0 / f64::from(p.distance(Vec3::new(0.0, 4.0, 0.0))).powi(3)
}

/// Pixels whose floor point lies within `radius` of `centre` (on the floor), with the floor
/// point's distance from `centre`.
fn pixels_near(scene: &Scene, image: &Image, centre: Vec3, radius: f32) -> Vec<(usize, usize, f32)> {
    let aspect = image.width as f32 / image.height as f32;
    let mut found = Vec::new();
    for y in 0..image.height {
        for x in 0..image.width {
            let film =
                Vec2::new((x as f32 + 0.5) / image.width as f32, (y as f32 + 0.5) / image.height as f32);
            let (origin, direction) = scene.camera.ray(film, aspect);
            let p = origin - direction * (origin.y / direction.y);
            let d = p.distance(centre);
            if d < radius {
                found.push((x, y, d));
            }
        }
    }
    found
}

/// Mean measured luminance over `pixels`, and the bare floor's mean over the same pixels.
fn measured_and_bare(scene: &Scene, image: &Image, pixels: &[(usize, usize, f32)]) -> (f64, f64) {
    let n = pixels.len() as f64;
    let measured = pixels.iter().map(|&(x, y, _)| image.luminance(x, x + 1, y, y + 1)).sum::<f64>() / n;
    let bare = pixels.iter().map(|&(x, y, _)| bare_floor_radiance(scene, image, x, y)).sum::<f64>() / n;
    (measured, bare)
}

/// Where the ball's shadow and caustic fall in frame 1 lies bare in frame 2 (the bare floor's
/// value within 4%: no photon of frame 1 is left over), and the other way round; the shadow
/// and the caustic are there in the frame the ball is above them.
#[test]
fn shadow_and_caustic_move_with_the_object_and_leave_no_stale_photons() {
    let dir = tempfile::tempdir().unwrap();
    let path = jumping_ball_scene(dir.path());
    let mut s = settings(&path, &dir.path().join("out"), 64);
    s.frames = vec![1, 2];
    s.photons = Some(40_000);
    s.radius = Some(0.02);
    assert_eq!(render_frames(&s, 2).block_frames, 2);
    let scene = Scene::load(&path).unwrap();
    // The light's ray through the ball's centre meets the floor 4/3 as far out: x = +-1.6.
    for (lit, bare, x) in [(1, 2, -1.6f32), (2, 1, 1.6)] {
        let (with_ball, without) = (frame_image(&s, lit), frame_image(&s, bare));
        let centre = Vec3::new(x, 0.0, 0.0);
        let region = pixels_near(&scene, &with_ball, centre, 0.6);
        let (value, expected) = measured_and_bare(&scene, &without, &region);
        eprintln!("frame {bare} where the ball was in frame {lit}: {value:.4}, bare floor {expected:.4}");
        assert!((value / expected - 1.0).abs() < 0.04, "frame {bare}: {value}, bare floor {expected}");
        let rim: Vec<_> = region.iter().copied().filter(|p| p.2 > 0.35).collect();
        let (shadow, bare_rim) = measured_and_bare(&scene, &with_ball, &rim);
        let core: Vec<_> = region.iter().copied().filter(|p| p.2 < 0.12).collect();
        let (caustic, bare_core) = measured_and_bare(&scene, &with_ball, &core);
        eprintln!("frame {lit}: shadow rim {shadow:.4} (bare {bare_rim:.4}), caustic core {caustic:.4} (bare {bare_core:.4})");
        assert!(shadow < 0.5 * bare_rim, "frame {lit}: no shadow under the ball ({shadow} vs {bare_rim})");
        assert!(
            caustic > 2.0 * bare_core,
            "frame {lit}: no caustic under the ball ({caustic} vs {bare_core})"
        );
    }
}

/// Mean absolute difference of luminance between two images over the rows `rows`.
fn mean_difference(a: &Image, b: &Image, rows: std::ops::Range<usize>) -> f64 {
    let mut sum = 0.0;
    for y in rows.clone() {
        for x in 0..a.width {
            sum += (a.luminance(x, x + 1, y, y + 1) - b.luminance(x, x + 1, y, y + 1)).abs();
        }
    }
    sum / (rows.len() * a.width) as f64
}

/// In the shot's static top half (ceiling, light, upper walls), frames rendered together differ
/// from one frame to the next by at most half of what frames rendered with independent random
/// numbers (a seed per frame) differ by.
#[test]
fn shared_random_numbers_halve_flicker_in_static_regions() {
    let dir = tempfile::tempdir().unwrap();
    let scene = bundled_scene("shot.gltf");
    let mut s = settings(&scene, &dir.path().join("together"), 8);
    s.frames = vec![1, 2, 3];
    s.resolution = Some([64, 48]);
    render_frames(&s, 2);
    let together: Vec<Image> = s.frames.iter().map(|&f| frame_image(&s, f)).collect();
    let independent: Vec<Image> = s
        .frames
        .iter()
        .map(|&f| {
            let alone = RenderSettings {
                frames: vec![f],
                seed: f as u64 + 100,
                out_dir: dir.path().join(format!("seed{f}")),
                ..s.clone()
            };
            render_frames(&alone, 2);
            frame_image(&alone, f)
        })
        .collect();
    let flicker = |images: &[Image]| {
        (mean_difference(&images[0], &images[1], 0..24) + mean_difference(&images[1], &images[2], 0..24))
            / 2.0
    };
    let (shared, seeded) = (flicker(&together), flicker(&independent));
    eprintln!(
        "frame-to-frame difference in the static half: {shared:.5} shared, {seeded:.5} a seed per frame"
    );
    assert!(shared <= 0.5 * seeded, "flicker {shared} with shared numbers vs {seeded} with a seed per frame");
}

/// The same frames with 1 and 2 threads give the same bits; a memory budget too small for two
/// frames renders them one at a time, with the same images (up to rounding).
#[test]
fn blocks_are_deterministic_and_follow_the_memory_budget() {
    for method in [Method::Sppm, Method::Vcm] {
        let dir = tempfile::tempdir().unwrap();
        let scene = bundled_scene("shot.gltf");
        let mut s = settings(&scene, &dir.path().join("two"), 4);
        s.frames = vec![5, 6, 7];
        s.resolution = Some([48, 36]);
        s.method = method;
        assert_eq!(render_frames(&s, 2).block_frames, 3);
        let one = RenderSettings { out_dir: dir.path().join("one"), ..s.clone() };
        render_frames(&one, 1);
        let small = RenderSettings { out_dir: dir.path().join("small"), memory_budget: 1 << 10, ..s.clone() };
        assert_eq!(render_frames(&small, 2).block_frames, 1);
        for f in [5, 6, 7] {
            let (a, b) = (frame_image(&s, f), frame_image(&one, f));
            assert!(a.rgb == b.rgb, "{method:?} frame {f}: 1 and 2 threads differ");
            assert_same_up_to_rounding(
                &frame_image(&small, f),
                &a,
                &format!("{method:?} frame {f} one at a time"),
            );
        }
    }
}

/// Frames rendered together stop one by one: each at its own target error (the block goes on
/// without it), each written with the passes it took, and the same frame rendered alone stops
/// after the same passes.
#[test]
fn frames_in_a_block_stop_at_their_own_target_error() {
    let dir = tempfile::tempdir().unwrap();
    let scene = bundled_scene("shot.gltf");
    let mut s = settings(&scene, &dir.path().join("together"), 0);
    s.passes = None;
    s.frames = vec![1, 24];
    s.resolution = Some([32, 24]);
    s.errors.target = Some((0.3, caustic::error::Statistic::Mean));
    let together = render_frames(&s, 2);
    assert_eq!(together.block_frames, 2);
    for report in &together.frames {
        assert_eq!(report.stopped_by, caustic::monitor::StopReason::TargetError, "frame {}", report.frame);
        assert!(report.error.mean <= 0.3, "frame {}: {}", report.frame, report.error.mean);
        let alone = RenderSettings {
            frames: vec![report.frame],
            out_dir: dir.path().join(format!("alone{}", report.frame)),
            ..s.clone()
        };
        assert_eq!(render_frames(&alone, 2).frames[0].passes, report.passes, "frame {}", report.frame);
    }
}
