//! Rendering on a farm: the Flamenco job type, compiled with node against Flamenco's documented
//! job-compiler API and its tasks run locally (tests/farm/flamenco_test.js), and an end-to-end
//! run on Dask with a local cluster of two worker processes (tests/farm/dask_test.py, in a
//! virtual environment `target/farm-venv` with `distributed` that the first run makes). Each
//! passes with a message saying why when node or python3 is missing.

mod common;

use common::{assert_succeeded, available, python_env};
use std::path::Path;
use std::process::Command;

/// What the Dask test installs.
const PACKAGES: &[&str] = &["distributed==2026.8.0"];

fn script(name: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests").join("farm").join(name)
}

#[test]
fn flamenco_job_type_compiles_and_its_tasks_merge_exactly() {
    if !available("node") {
        eprintln!("skipped tests/farm/flamenco_test.js: node is not on PATH");
        return;
    }
    let output = Command::new("node")
        .arg(script("flamenco_test.js"))
        .env("CAUSTIC_BINARY", env!("CARGO_BIN_EXE_caustic"))
        .output()
        .expect("run node");
    assert_succeeded(output, "tests/farm/flamenco_test.js");
}

#[test]
fn dask_cluster_renders_pass_chunks_that_merge_into_the_single_process_image() {
    if !available("python3") {
        eprintln!("skipped tests/farm/dask_test.py: python3 is not on PATH");
        return;
    }
    let output = Command::new(python_env("farm-venv", "python3", PACKAGES))
        .arg(script("dask_test.py"))
        .env("CAUSTIC_BINARY", env!("CARGO_BIN_EXE_caustic"))
        .env("PYTHONDONTWRITEBYTECODE", "1")
        .output()
        .expect("run the Dask test");
    assert_succeeded(output, "tests/farm/dask_test.py");
}
