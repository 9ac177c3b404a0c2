//! Rendering on a farm: the Flamenco job type, compiled with node against Flamenco's documented
//! job-compiler API and its tasks run locally (tests/farm/flamenco_test.js), and an end-to-end
//! run on Dask with a local cluster of two worker processes (tests/farm/dask_test.py, in a
//! virtual environment `target/farm-venv` with `distributed` that the first run makes). Each
//! passes with a message saying why when node or python3 is missing.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// What the Dask test installs.
const PACKAGES: &[&str] = &["distributed==2026.8.0"];

fn repository() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn available(program: &str) -> bool {
    Command::new(program).arg("--version").output().is_ok_and(|o| o.status.success())
}

fn assert_ran(output: Output, what: &str) {
    let text =
        format!("{}{}", String::from_utf8_lossy(&output.stdout), String::from_utf8_lossy(&output.stderr));
    eprintln!("{text}");
    assert!(output.status.success(), "{what} failed:\n{text}");
}

#[test]
fn flamenco_job_type_compiles_and_its_tasks_merge_exactly() {
    if !available("node") {
        eprintln!("skipped tests/farm/flamenco_test.js: node is not on PATH");
        return;
    }
    let output = Command::new("node")
        .arg(repository().join("tests/farm/flamenco_test.js"))
        .env("CAUSTIC_BINARY", env!("CARGO_BIN_EXE_caustic"))
        .output()
        .expect("run node");
    assert_ran(output, "tests/farm/flamenco_test.js");
}

/// The environment's Python, making the environment the first time.
fn farm_python() -> PathBuf {
    let target = Path::new(env!("CARGO_BIN_EXE_caustic")).ancestors().nth(2).expect("target folder");
    let venv = target.join("farm-venv");
    let python = venv.join("bin").join("python");
    let ready = venv.join(format!("ready-{}", PACKAGES.join("-")));
    if !ready.exists() {
        let status =
            Command::new("python3").args(["-m", "venv"]).arg(&venv).status().expect("python3 -m venv");
        assert!(status.success(), "cannot create {}", venv.display());
        let status = Command::new(&python).args(["-m", "pip", "install", "--quiet"]).args(PACKAGES).status();
        assert!(status.is_ok_and(|s| s.success()), "cannot install {}", PACKAGES.join(", "));
        std::fs::write(&ready, "").expect("mark the environment ready");
    }
    python
}

#[test]
fn dask_cluster_renders_pass_chunks_that_merge_into_the_single_process_image() {
    if !available("python3") {
        eprintln!("skipped tests/farm/dask_test.py: python3 is not on PATH");
        return;
    }
    let output = Command::new(farm_python())
        .arg(repository().join("tests/farm/dask_test.py"))
        .env("CAUSTIC_BINARY", env!("CARGO_BIN_EXE_caustic"))
        .env("PYTHONDONTWRITEBYTECODE", "1")
        .output()
        .expect("run the Dask test");
    assert_ran(output, "tests/farm/dask_test.py");
}
