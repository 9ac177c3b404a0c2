//! The Blender add-on's tests (`tests/addon/*.py`), run in `bpy`: Blender 5.0.1 as a Python module
//! from PyPI, whose wheels exist for Linux x86_64 with CPython 3.11 only.
//!
//! The first run makes a virtual environment in `target/bpy-venv` with `bpy` and `OpenEXR` (a few
//! hundred MB from PyPI, a few minutes); later runs reuse it. Each script runs with
//! `CAUSTIC_BINARY` naming this build's `caustic`. Elsewhere the tests pass with a message that
//! says why they did not run.

mod common;

use common::{assert_succeeded, available, python_env};
use std::path::Path;
use std::process::Command;

/// What the tests install into the environment.
const PACKAGES: &[&str] = &["bpy==5.0.1", "OpenEXR==3.5.3"];

/// Why bpy cannot run here, if it cannot.
fn unsupported() -> Option<String> {
    if !cfg!(all(target_os = "linux", target_arch = "x86_64")) {
        return Some("bpy 5.0.1 wheels exist for Linux x86_64 only".into());
    }
    (!available("python3.11")).then(|| "bpy 5.0.1 needs CPython 3.11, and `python3.11` is not on PATH".into())
}

/// Runs one test script in bpy and fails with its output when a test in it fails.
fn run_script(name: &str) {
    if let Some(reason) = unsupported() {
        eprintln!("skipped tests/addon/{name}: {reason}");
        return;
    }
    let output = Command::new(python_env("bpy-venv", "python3.11", PACKAGES))
        .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests").join("addon").join(name))
        .env("CAUSTIC_BINARY", env!("CARGO_BIN_EXE_caustic"))
        .env("PYTHONDONTWRITEBYTECODE", "1")
        .output()
        .expect("run the bpy test script");
    assert_succeeded(output, &format!("tests/addon/{name}"));
}

/// Renders through the add-on: still images, an animation, cancelling, errors, the extras.
#[test]
fn addon_renders_inside_blender() {
    run_script("test_addon.py");
}

/// The installable zips: the extension installs and registers the engine.
#[test]
fn addon_packages_install() {
    run_script("test_package.py");
}

/// Scenes combining at random what Blender shots contain (two dozen seeds; a soak run takes more):
/// exported through the add-on and rendered with no panic, no non-finite pixel, no unnamed failure.
#[test]
fn addon_combinations_export_and_render() {
    run_script("test_combinations.py");
}

/// Blender parity: scenes built in bpy, rendered through the add-on, against Cycles' references.
#[test]
fn addon_renders_match_cycles() {
    run_script("test_parity.py");
}
