//! The command line as a user meets it: determinism across thread counts, and one clear message
//! with a non-zero exit for every kind of bad input.

mod common;

use common::*;
use std::path::Path;

fn stderr(output: &std::process::Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

/// Runs `caustic render` with `args` and asserts it fails with a message containing every one of
/// `expected` and no panic.
fn assert_fails(args: &[&str], expected: &[&str]) {
    let output = run_caustic(args);
    let message = stderr(&output);
    assert!(!output.status.success(), "{args:?} succeeded: {message}");
    assert!(!message.contains("panicked"), "{args:?} panicked: {message}");
    for part in expected {
        assert!(message.contains(part), "{args:?}: message {message:?} does not mention {part:?}");
    }
}

#[test]
fn same_seed_gives_identical_bits_with_one_and_two_threads() {
    let dir = tempfile::tempdir().unwrap();
    let scene = bundled_scene("cornell_glass.gltf");
    let mut files = Vec::new();
    for threads in ["1", "2"] {
        let out = dir.path().join(threads);
        let out = out.to_str().unwrap();
        let args = ["render", scene.to_str().unwrap(), "-o", out, "--passes", "3", "--resolution", "96x72"];
        let output =
            run_caustic(&[&args[..], &["--threads", threads, "--progress", "none", "--seed", "7"]].concat());
        assert!(output.status.success(), "{}", stderr(&output));
        files.push(std::fs::read(Path::new(out).join("frame_0001.exr")).unwrap());
    }
    assert!(files[0] == files[1], "the EXRs differ between 1 and 2 threads");
}

#[test]
fn writes_a_complete_exr_and_no_temporary_file() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().to_str().unwrap();
    let scene = bundled_scene("spot_glass.gltf");
    let output = run_caustic(&[
        "render",
        scene.to_str().unwrap(),
        "-o",
        out,
        "--passes",
        "2",
        "--resolution",
        "32x24",
        "--progress",
        "none",
    ]);
    assert!(output.status.success(), "{}", stderr(&output));
    let names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    assert_eq!(names, ["frame_0001.exr"]);
    let image = read_exr(&dir.path().join("frame_0001.exr"));
    assert_eq!((image.width, image.height), (32, 24));
    assert!(image.mean_all().iter().all(|c| c.is_finite() && *c > 0.0), "{:?}", image.mean_all());
}

#[test]
fn json_progress_reports_every_pass() {
    let dir = tempfile::tempdir().unwrap();
    let scene = bundled_scene("furnace.gltf");
    let out = dir.path().to_str().unwrap();
    let output = run_caustic(&[
        "render",
        scene.to_str().unwrap(),
        "-o",
        out,
        "--passes",
        "3",
        "--resolution",
        "8x8",
        "--progress",
        "json",
    ]);
    assert!(output.status.success(), "{}", stderr(&output));
    let all: Vec<serde_json::Value> =
        String::from_utf8(output.stdout).unwrap().lines().map(|l| serde_json::from_str(l).unwrap()).collect();
    let (lines, written): (Vec<_>, Vec<_>) = all.into_iter().partition(|l| l.get("written").is_none());
    assert_eq!(lines.len(), 3);
    assert_eq!(written.len(), 1);
    assert!(written[0]["written"].as_str().unwrap().ends_with("frame_0001.exr"));
    assert_eq!(written[0]["stopped_by"], "passes");
    for (k, line) in lines.iter().enumerate() {
        assert_eq!(line["frame"], 1);
        assert_eq!(line["pass"], k as u64 + 1);
        assert_eq!(line["passes"], 3);
        assert!(line["elapsed_s"].as_f64().unwrap() >= 0.0);
    }
}

#[test]
fn help_explains_every_flag() {
    let output = run_caustic(&["render", "--help"]);
    let text = String::from_utf8_lossy(&output.stdout);
    for flag in [
        "--out",
        "--passes",
        "--time-budget",
        "--photons",
        "--alpha",
        "--radius",
        "--resolution",
        "--seed",
        "--threads",
        "--progress",
        "--no-reuse",
        "--memory-budget",
    ] {
        assert!(text.contains(flag), "help does not mention {flag}");
    }
}

#[test]
fn a_missing_scene_is_named() {
    assert_fails(&["render", "no/such/scene.gltf"], &["no/such/scene.gltf", "no such file"]);
}

#[test]
fn a_malformed_gltf_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("broken.gltf");
    std::fs::write(&path, "{ \"asset\": { \"version\": ").unwrap();
    assert_fails(&["render", path.to_str().unwrap()], &["broken.gltf", "malformed JSON"]);
}

#[test]
fn an_unknown_required_extension_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let path = write_edited(&bundled_scene("furnace.gltf"), dir.path(), |doc| {
        doc["extensionsUsed"] = serde_json::json!(["EXT_from_the_future"]);
        doc["extensionsRequired"] = serde_json::json!(["EXT_from_the_future"]);
    });
    assert_fails(&["render", path.to_str().unwrap()], &["furnace.gltf", "EXT_from_the_future"]);
}

#[test]
fn a_missing_buffer_file_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let path = write_edited(&bundled_scene("furnace.gltf"), dir.path(), |_| {});
    std::fs::remove_file(dir.path().join("furnace.bin")).unwrap();
    assert_fails(&["render", path.to_str().unwrap()], &["furnace.gltf", "cannot read"]);
}

#[test]
fn a_scene_without_camera_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let path = write_edited(&bundled_scene("furnace.gltf"), dir.path(), |doc| {
        doc.as_object_mut().unwrap().remove("cameras");
        let nodes = doc["nodes"].as_array_mut().unwrap();
        nodes.iter_mut().for_each(|n| {
            n.as_object_mut().unwrap().remove("camera");
        });
    });
    assert_fails(&["render", path.to_str().unwrap()], &["furnace.gltf", "no camera"]);
}

#[test]
fn a_bad_extras_field_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let path = write_edited(&bundled_scene("furnace.gltf"), dir.path(), |doc| {
        doc["scenes"][0]["extras"] = serde_json::json!({"caustic": {"resolutoin": [4, 4]}});
    });
    assert_fails(&["render", path.to_str().unwrap()], &["furnace.gltf", "resolutoin"]);
}

/// A scene that names a camera node renders through it; naming a node without a camera is an error.
#[test]
fn the_scene_chooses_its_camera_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let mut gltf = GltfBuilder::default();
    let red = gltf.material(diffuse([0.8, 0.1, 0.1]));
    gltf.quad_y("Floor", 0.0, 5.0, true, red);
    gltf.light(serde_json::json!({"type": "point", "intensity": 5000.0}), [0.0, 3.0, 0.0], [0.0, -1.0, 0.0]);
    gltf.camera([0.0, 2.0, 0.0], [0.0, -1.0, 0.0], 0.5);
    gltf.camera([0.0, 2.0, 0.0], [0.0, 1.0, 0.0], 0.5);
    let mut doc = gltf.to_json();
    let up = doc["nodes"].as_array().unwrap().len() - 1;
    doc["nodes"][up]["name"] = "LookingUp".into();
    doc["scenes"][0]["extras"] =
        serde_json::json!({"caustic": {"camera": "LookingUp", "resolution": [4, 4]}});
    let path = dir.path().join("two_cameras.gltf");
    std::fs::write(&path, doc.to_string()).unwrap();
    let mut s = settings(&path, &dir.path().join("up"), 4);
    s.resolution = Some([4, 4]);
    assert!(render(&s, 1).mean_all()[0] < 1e-6, "the camera looking up sees the floor");
    doc["scenes"][0]["extras"]["caustic"]["camera"] = "Floor".into();
    std::fs::write(&path, doc.to_string()).unwrap();
    assert_fails(&["render", path.to_str().unwrap()], &["caustic.camera", "'Floor'", "not a camera"]);
}

#[test]
fn bad_flag_values_are_named() {
    let scene = bundled_scene("furnace.gltf");
    let scene = scene.to_str().unwrap();
    assert_fails(&["render", scene, "--passes", "0"], &["--passes"]);
    assert_fails(&["render", scene, "--passes", "many"], &["--passes"]);
    assert_fails(&["render", scene, "--alpha", "1.5"], &["--alpha", "between 0 and 1"]);
    assert_fails(&["render", scene, "--radius", "-1"], &["--radius", "positive"]);
    assert_fails(&["render", scene, "--time-budget", "0"], &["--time-budget", "positive"]);
    assert_fails(&["render", scene, "--resolution", "640by480"], &["--resolution", "WIDTHxHEIGHT"]);
    assert_fails(&["render", scene, "--resolution", "0x10"], &["--resolution"]);
    assert_fails(&["render", scene, "--resolution", "65536x65536"], &["resolution 65536x65536", "GiB"]);
    assert_fails(&["render", scene, "--threads", "0"], &["--threads"]);
    assert_fails(&["render", scene, "--threads", "100000"], &["--threads", "1 to 256"]);
    assert_fails(&["render", scene, "--photons", "0"], &["--photons"]);
    assert_fails(&["render", scene, "--progress", "loud"], &["--progress"]);
    assert_fails(&["render", scene, "--memory-budget", "lots"], &["--memory-budget", "4G"]);
    assert_fails(&["render", scene, "--memory-budget", "0"], &["--memory-budget"]);
    assert_fails(&["render", scene, "--memory-budget", "99999999999T"], &["--memory-budget", "too large"]);
}

/// `--memory-budget` takes K, M, G and T (powers of 1024), with or without B or iB.
#[test]
fn memory_budgets_take_units() {
    let dir = tempfile::tempdir().unwrap();
    let scene = bundled_scene("furnace.gltf");
    for size in ["512M", "2g", "1GiB", "100000000", "64KB"] {
        let output = run_caustic(&[
            "render",
            scene.to_str().unwrap(),
            "-o",
            dir.path().to_str().unwrap(),
            "--passes",
            "1",
            "--resolution",
            "4x4",
            "--progress",
            "none",
            "--memory-budget",
            size,
        ]);
        assert!(output.status.success(), "{size}: {}", stderr(&output));
    }
}

#[test]
fn an_unwritable_output_folder_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let blocker = dir.path().join("file");
    std::fs::write(&blocker, "not a folder").unwrap();
    let out = blocker.join("renders");
    let scene = bundled_scene("furnace.gltf");
    assert_fails(
        &[
            "render",
            scene.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--passes",
            "1",
            "--resolution",
            "4x4",
            "--progress",
            "none",
        ],
        &["output folder", "renders"],
    );
}

/// `caustic compare` measures any renderer's EXR (here R/G/B, as Blender writes) against a
/// reference: one pixel of 64 off by 100% gives relative MSE 1 / (1 + f^2) / 64 with f 1% of the
/// reference's mean, and mean relative error 1/64; different sizes are refused, naming both.
#[test]
fn compare_prints_the_error_against_a_reference() {
    let dir = tempfile::tempdir().unwrap();
    let flat = Image { width: 8, height: 8, rgb: vec![[1.0; 3]; 64] };
    let mut off = Image { width: 8, height: 8, rgb: vec![[1.0; 3]; 64] };
    off.rgb[9] = [2.0; 3];
    let small = Image { width: 4, height: 8, rgb: vec![[1.0; 3]; 32] };
    for (name, image) in [("flat", &flat), ("off", &off), ("small", &small)] {
        write_image(&dir.path().join(format!("{name}.exr")), image);
    }
    let path = |name: &str| dir.path().join(format!("{name}.exr")).to_str().unwrap().to_owned();
    let output = run_caustic(&["compare", &path("off"), "--reference", &path("flat")]);
    assert!(output.status.success(), "{}", stderr(&output));
    let error: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    let expected = 1.0 / (1.0 + 1e-4) / 64.0;
    assert!((error["relative_mse"].as_f64().unwrap() - expected).abs() < 1e-9, "{error}");
    assert!((error["mean_relative"].as_f64().unwrap() - 1.0 / 64.0).abs() < 1e-9, "{error}");
    let same = run_caustic(&["compare", &path("flat"), "--reference", &path("flat")]);
    let error: serde_json::Value = serde_json::from_slice(&same.stdout).unwrap();
    assert_eq!(error["relative_mse"].as_f64(), Some(0.0), "{error}");
    let output = run_caustic(&["compare", &path("small"), "--reference", &path("flat")]);
    assert!(!output.status.success());
    let message = stderr(&output);
    assert!(message.contains("small.exr is 4x8") && message.contains("flat.exr is 8x8"), "{message}");
    let output = run_caustic(&["compare", &path("missing"), "--reference", &path("flat")]);
    assert!(stderr(&output).contains("cannot read image") && stderr(&output).contains("missing.exr"));
}

/// Every scene in `scenes/` loads and renders (one pass at 8 x 6, its first frame) with nothing
/// to warn about: what the project ships, it renders whole.
#[test]
fn every_bundled_scene_renders_without_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut names: Vec<_> = std::fs::read_dir(&scenes)
        .unwrap()
        .map(|entry| entry.unwrap().path())
        .filter(|path| path.extension().is_some_and(|e| e == "gltf"))
        .collect();
    names.sort();
    assert!(names.len() >= 10, "scenes: {names:?}");
    for scene in names {
        let out = dir.path().join(scene.file_stem().unwrap());
        let mut args = vec!["render", scene.to_str().unwrap(), "-o", out.to_str().unwrap()];
        args.extend(["--passes", "1", "--resolution", "8x6", "--photons", "64", "--progress", "none"]);
        let output = run_caustic(&args);
        assert!(output.status.success(), "{}: {}", scene.display(), stderr(&output));
        assert_eq!(stderr(&output), "", "{}", scene.display());
        assert!(out.join("frame_0001.exr").exists(), "{}", scene.display());
    }
}
