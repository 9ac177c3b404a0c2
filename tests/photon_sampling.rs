//! Visibility-driven photons (`--photon-sampling visible`) against uniform ones: the same image
//! within noise on the demo scene (where 40% of uniform paths reach a visible point) and on the
//! sunlit room (0.1%); the same bits with any thread count; exact merging of pass ranges.

mod common;

use caustic::render::PhotonSampling;
use common::*;

/// `scene` at 64x48 with `passes` passes of `photons` photon paths, drawn by `sampling`.
fn render_with(scene: &str, sampling: PhotonSampling, passes: u64, photons: usize, threads: usize) -> Image {
    let dir = tempfile::tempdir().unwrap();
    let mut settings = settings(&bundled_scene(scene), dir.path(), passes);
    settings.resolution = Some([64, 48]);
    settings.photons = Some(photons);
    settings.photon_sampling = sampling;
    render(&settings, threads)
}

/// Visible photons' image equals uniform photons': the whole image's mean within `whole`, and
/// each 16x16 block's within `block` (relative), or 0.003 where dark.
fn assert_same_image(scene: &str, passes: u64, photons: usize, whole: f64, block: f64) {
    let visible = render_with(scene, PhotonSampling::Visible, passes, photons, 2);
    let uniform = render_with(scene, PhotonSampling::Uniform, passes, photons, 2);
    let (a, b) = (visible.luminance(0, 64, 0, 48), uniform.luminance(0, 64, 0, 48));
    eprintln!("{scene}: mean luminance {a} with visible photons, {b} with uniform ones");
    assert!(
        (a / b - 1.0).abs() < whole,
        "{scene}: mean luminance {a} with visible photons, {b} with uniform ones"
    );
    let (visible, uniform) = (block_means(&visible, 16), block_means(&uniform, 16));
    for y in 0..visible.height {
        for x in 0..visible.width {
            let (a, b) = (visible.luminance(x, x + 1, y, y + 1), uniform.luminance(x, x + 1, y, y + 1));
            eprintln!("{scene}: block ({x}, {y}): {a} visible, {b} uniform, {:.3}", a / b - 1.0);
            assert!(
                (a - b).abs() <= (block * b).max(0.003),
                "{scene}: block ({x}, {y}): {a} with visible photons, {b} with uniform ones"
            );
        }
    }
}

#[test]
fn visible_photons_render_the_demo_as_uniform_photons_do() {
    assert_same_image("cornell_glass.gltf", 256, 3072, 0.02, 0.05);
}

#[test]
fn visible_photons_render_the_sunlit_room_as_uniform_photons_do() {
    assert_same_image("sunlit_room.gltf", 64, 100_000, 0.08, 0.2);
}

#[test]
fn visible_photons_give_the_same_bits_with_any_thread_count() {
    let one = render_with("sunlit_room.gltf", PhotonSampling::Visible, 4, 20_000, 1);
    let two = render_with("sunlit_room.gltf", PhotonSampling::Visible, 4, 20_000, 2);
    assert_eq!(one.rgb, two.rgb);
}

/// Passes 0..2 and 2..5 of the sunlit room with visible photons, rendered apart and merged,
/// equal the 5-pass render within 1e-6 relative (chains are keyed by pass, never by thread or
/// by the passes rendered before).
#[test]
fn visible_photons_merge_pass_ranges_exactly() {
    use caustic::render::{self, RenderSettings};
    let dir = tempfile::tempdir().unwrap();
    let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
    let mut whole = settings(&bundled_scene("sunlit_room.gltf"), &dir.path().join("whole"), 5);
    whole.resolution = Some([64, 48]);
    whole.photons = Some(20_000);
    whole.photon_sampling = PhotonSampling::Visible;
    pool.install(|| render::render(&whole)).unwrap();
    let parts = dir.path().join("parts");
    let files: Vec<_> = [0..2, 2..5]
        .into_iter()
        .map(|passes| {
            let s = RenderSettings {
                passes: None,
                out_dir: parts.clone(),
                partial_passes: Some(passes.clone()),
                ..whole.clone()
            };
            pool.install(|| render::render(&s)).unwrap();
            caustic::render::partial::partial_path(&parts, 1, &passes)
        })
        .collect();
    let merged = render::merge(&files, &dir.path().join("merged"), 0.9).unwrap();
    let (path, _) = &merged[0];
    let (a, b) =
        (exr_channels(path), exr_channels(&dir.path().join("whole").join(path.file_name().unwrap())));
    for ((channel, x), (_, y)) in a.iter().zip(&b) {
        let worst =
            x.iter().zip(y).map(|(x, y)| (x - y).abs() / (1e-6 * y.abs()).max(1e-30)).fold(0.0, f32::max);
        assert!(worst <= 1.0, "{channel}: differs by {worst} times the tolerance");
    }
}

/// The error bound covers the true error at its confidence with visible photons too: on the
/// demo box at 64x48 (against the error test's reference, `tests/references/error_cornell_glass.exr`),
/// the fraction of pixels whose true error lies within their 90% bound is within 10 percentage
/// points of 90% after 256 and 1024 passes (as `tests/error.rs` asks of uniform photons).
#[test]
fn the_error_bound_covers_the_true_error_with_visible_photons() {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("log.jsonl");
    let mut s = settings(&bundled_scene("cornell_glass.gltf"), dir.path(), 1024);
    s.resolution = Some([64, 48]);
    s.seed = 7;
    s.photon_sampling = PhotonSampling::Visible;
    s.errors.log = Some(log.clone());
    s.errors.reference = Some(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/references/error_cornell_glass.exr"),
    );
    render(&s, 2);
    let lines: Vec<serde_json::Value> =
        std::fs::read_to_string(&log).unwrap().lines().map(|l| serde_json::from_str(l).unwrap()).collect();
    for passes in [256, 1024] {
        let line = lines.iter().find(|l| l["passes"] == passes && l.get("stopped_by").is_none()).unwrap();
        let coverage = line["true"]["coverage"].as_f64().unwrap();
        eprintln!("visible photons at {passes} passes: coverage {coverage:.3}");
        assert!((coverage - 0.9).abs() <= 0.10, "visible photons at {passes} passes: coverage {coverage:.3}");
    }
}

/// `caustic info` says what `--photon-sampling auto` uses on pass 0 and why: visible chains in the
/// sunlit room (under 1% of uniform paths reach a visible point), uniform paths on the demo box
/// (about 40%).
#[test]
fn info_says_what_auto_photon_sampling_uses() {
    let photons = |scene: &str| {
        let out = run_caustic(&["info", bundled_scene(scene).to_str().unwrap()]);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        report["photons"].clone()
    };
    let room = photons("sunlit_room.gltf");
    assert!(room["pilot_seen_fraction_pass_0"].as_f64().unwrap() < 0.01, "{room}");
    assert_eq!(room["auto_uses_on_pass_0"], "visible", "{room}");
    let demo = photons("cornell_glass.gltf");
    let seen = demo["pilot_seen_fraction_pass_0"].as_f64().unwrap();
    assert!((0.3..0.5).contains(&seen), "{demo}");
    assert_eq!(demo["auto_uses_on_pass_0"], "uniform", "{demo}");
}
