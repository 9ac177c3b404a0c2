//! Pass ranges rendered apart and merged: exactly the whole run, and refused when they do not
//! belong together.

mod common;

use caustic::render::{self, Method, RenderSettings};
use common::*;
use std::path::{Path, PathBuf};

fn render_frames(settings: &RenderSettings) {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
    pool.install(|| render::render(settings)).unwrap_or_else(|e| panic!("render failed: {e}"));
}

/// Frames 1 and 2 of the shot at 48x36, 2000 photons a pass, into `out`.
fn shot_settings(out: &Path) -> RenderSettings {
    let mut s = settings(&bundled_scene("shot.gltf"), out, 8);
    s.frames = vec![1, 2];
    s.resolution = Some([48, 36]);
    s.photons = Some(2000);
    s
}

/// Renders passes `passes` of `base`'s frames as partial results into `out`; gives frame 1's file.
fn partial(base: &RenderSettings, out: &Path, passes: std::ops::Range<u64>) -> PathBuf {
    let s = RenderSettings {
        passes: None,
        out_dir: out.to_path_buf(),
        partial_passes: Some(passes.clone()),
        ..base.clone()
    };
    render_frames(&s);
    caustic::render::partial::partial_path(out, 1, &passes)
}

/// Passes 0..3 and 3..8 merged give the 8-pass render's Combined, Error and Variance channels
/// within 1e-6 relative (sums in f64 added in another order; in practice the same bits).
#[test]
fn merged_pass_ranges_equal_the_whole_run() {
    assert_merged_pass_ranges_equal_the_whole_run(Method::Sppm);
}

/// The same for passes of vertex connection and merging (their light tracing on the film too).
#[test]
fn merged_vcm_pass_ranges_equal_the_whole_run() {
    assert_merged_pass_ranges_equal_the_whole_run(Method::Vcm);
}

fn assert_merged_pass_ranges_equal_the_whole_run(method: Method) {
    let dir = tempfile::tempdir().unwrap();
    let whole = RenderSettings { method, ..shot_settings(&dir.path().join("whole")) };
    render_frames(&whole);
    let parts = dir.path().join("parts");
    partial(&whole, &parts, 3..8);
    partial(&whole, &parts, 0..3);
    let files: Vec<PathBuf> = std::fs::read_dir(&parts).unwrap().map(|e| e.unwrap().path()).collect();
    assert_eq!(files.len(), 4, "two frames, two ranges: {files:?}");
    let merged = render::merge(&files, &dir.path().join("merged"), 0.9).unwrap();
    assert_eq!(merged.len(), 2);
    for (path, film) in merged {
        assert_eq!(film.passes, 8);
        let name = path.file_name().unwrap();
        let (a, b) = (exr_channels(&path), exr_channels(&dir.path().join("whole").join(name)));
        assert_eq!(a.iter().map(|c| &c.0).collect::<Vec<_>>(), b.iter().map(|c| &c.0).collect::<Vec<_>>());
        for ((channel, x), (_, y)) in a.iter().zip(&b) {
            let worst =
                x.iter().zip(y).map(|(x, y)| (x - y).abs() / (1e-6 * y.abs()).max(1e-30)).fold(0.0, f32::max);
            assert!(worst <= 1.0, "{name:?} {channel}: differs by {worst} times the tolerance");
        }
    }
}

fn merge_error(files: &[PathBuf]) -> String {
    let out = tempfile::tempdir().unwrap();
    match render::merge(files, out.path(), 0.9) {
        Ok(_) => panic!("merged {files:?}"),
        Err(message) => message,
    }
}

fn assert_mentions(message: &str, parts: &[&str]) {
    for part in parts {
        assert!(message.contains(part), "'{message}' does not mention '{part}'");
    }
}

/// Partial results that do not belong together are refused with a message naming why.
#[test]
fn merges_that_do_not_add_up_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let base = shot_settings(&dir.path().join("unused"));
    let a = partial(&base, &dir.path().join("a"), 0..4);
    let b = partial(&base, &dir.path().join("b"), 4..8);
    let overlapping = partial(&base, &dir.path().join("c"), 2..6);
    let late = partial(&base, &dir.path().join("d"), 5..8);
    let other_seed = partial(&RenderSettings { seed: 7, ..base.clone() }, &dir.path().join("e"), 4..8);
    let other_scene_settings =
        RenderSettings { scene: bundled_scene("shot_moving_camera.gltf"), ..base.clone() };
    let other_scene = partial(&other_scene_settings, &dir.path().join("f"), 4..8);
    let frame_two = caustic::render::partial::partial_path(&dir.path().join("b"), 2, &(4..8));
    let other_method =
        partial(&RenderSettings { method: Method::Vcm, ..base.clone() }, &dir.path().join("g"), 4..8);

    assert_mentions(&merge_error(&[a.clone(), other_seed]), &["do not belong together", "seed 1 vs 7"]);
    assert_mentions(&merge_error(&[a.clone(), other_method]), &["do not belong together", "method"]);
    assert_mentions(
        &merge_error(&[a.clone(), other_scene]),
        &["scenes differ", "shot.gltf", "shot_moving_camera.gltf"],
    );
    assert_mentions(
        &merge_error(&[a.clone(), overlapping]),
        &["frame 1", "passes 0..4", "passes 2..6", "overlap"],
    );
    assert_mentions(&merge_error(&[a.clone(), late]), &["frame 1", "passes 4..5 are missing"]);
    assert_mentions(&merge_error(&[b.clone()]), &["frame 1", "passes 0..4 are missing"]);
    // Frame 2's half alone is incomplete even beside frame 1's whole range.
    assert_mentions(
        &merge_error(&[a.clone(), b.clone(), frame_two]),
        &["frame 2", "passes 0..4 are missing"],
    );
    // Damaged and foreign files.
    let truncated = dir.path().join("truncated.partial");
    let bytes = std::fs::read(&a).unwrap();
    std::fs::write(&truncated, &bytes[..bytes.len() - 100]).unwrap();
    assert_mentions(&merge_error(&[truncated]), &["truncated.partial", "truncated or damaged"]);
    assert_mentions(
        &merge_error(&[bundled_scene("shot.gltf")]),
        &["shot.gltf", "not a Caustic partial result"],
    );
}

/// `--pass-range` and `--partial` go together, and a range must hold passes.
#[test]
fn pass_range_flags_are_checked() {
    let scene = bundled_scene("furnace.gltf");
    let scene = scene.to_str().unwrap();
    let fails = |args: &[&str], expected: &str| {
        let output = run_caustic(args);
        let text = String::from_utf8_lossy(&output.stderr).to_string();
        assert!(!output.status.success() && text.contains(expected), "{args:?}: {text}");
    };
    fails(&["render", scene, "--pass-range", "0..4"], "--partial");
    fails(&["render", scene, "--partial"], "--pass-range");
    fails(&["render", scene, "--pass-range", "4..4", "--partial"], "A < B");
    fails(&["render", scene, "--pass-range", "0..4", "--partial", "--passes", "8"], "--passes");
    fails(&["merge", "no/such.partial"], "no/such.partial");
}
