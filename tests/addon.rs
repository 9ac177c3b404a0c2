//! The Blender add-on's tests (`tests/addon/*.py`), run in `bpy`: Blender 5.0.1 as a Python module
//! from PyPI, whose wheels exist for Linux x86_64 with CPython 3.11 only.
//!
//! The first run makes a virtual environment in `target/bpy-venv` with `bpy` and `OpenEXR` (a few
//! hundred MB from PyPI, a few minutes); later runs reuse it. Each script runs with
//! `CAUSTIC_BINARY` naming this build's `caustic`. Elsewhere the tests pass with a message that
//! says why they did not run.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Mutex;

/// What the tests install into the environment.
const PACKAGES: &[&str] = &["bpy==5.0.1", "OpenEXR==3.5.3"];

/// Serialises the environment's creation between the tests of this file.
static VENV: Mutex<()> = Mutex::new(());

fn repository() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// The folder cargo builds into (the binary's grandparent: target/debug/caustic).
fn target_dir() -> PathBuf {
    Path::new(env!("CARGO_BIN_EXE_caustic")).ancestors().nth(2).expect("target folder").to_path_buf()
}

/// Why bpy cannot run here, if it cannot.
fn unsupported() -> Option<String> {
    if !cfg!(all(target_os = "linux", target_arch = "x86_64")) {
        return Some("bpy 5.0.1 wheels exist for Linux x86_64 only".into());
    }
    match Command::new("python3.11").arg("--version").output() {
        Ok(output) if output.status.success() => None,
        _ => Some("bpy 5.0.1 needs CPython 3.11, and `python3.11` is not on PATH".into()),
    }
}

/// The environment's Python, creating the environment the first time.
fn bpy_python() -> PathBuf {
    let _guard = VENV.lock().unwrap_or_else(|e| e.into_inner());
    let venv = target_dir().join("bpy-venv");
    let python = venv.join("bin").join("python");
    let ready = venv.join(format!("ready-{}", PACKAGES.join("-")));
    if ready.exists() {
        return python;
    }
    eprintln!("installing {} into {} (once)", PACKAGES.join(", "), venv.display());
    run(Command::new("python3.11").args(["-m", "venv"]).arg(&venv), "create the bpy virtual environment");
    run(Command::new(&python).args(["-m", "pip", "install", "--quiet"]).args(PACKAGES), "install bpy");
    std::fs::write(&ready, "").expect("mark the environment ready");
    python
}

fn run(command: &mut Command, what: &str) {
    let status = command.status().unwrap_or_else(|e| panic!("cannot {what}: {e}"));
    assert!(status.success(), "cannot {what}: {status}");
}

/// Runs one test script in bpy and fails with its output when a test in it fails.
fn run_script(name: &str) {
    if let Some(reason) = unsupported() {
        eprintln!("skipped tests/addon/{name}: {reason}");
        return;
    }
    let output = Command::new(bpy_python())
        .arg(repository().join("tests").join("addon").join(name))
        .env("CAUSTIC_BINARY", env!("CARGO_BIN_EXE_caustic"))
        .env("PYTHONDONTWRITEBYTECODE", "1")
        .output()
        .expect("run the bpy test script");
    let text =
        format!("{}{}", String::from_utf8_lossy(&output.stdout), String::from_utf8_lossy(&output.stderr));
    eprintln!("{text}");
    assert!(output.status.success(), "tests/addon/{name} failed:\n{text}");
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
