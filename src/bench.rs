//! `caustic bench`: passes, photon paths and rays per second with 1 and 2 threads, and peak
//! memory, for one scene at one resolution. Figures for notes and comparisons, never for tests.

use std::path::Path;
use std::time::Instant;

use crate::frames::{load_description, RenderSettings, Shot};
use crate::sppm::{PassStats, Renderer};

/// The process's peak resident memory in MiB (Linux `VmHWM`), if known.
fn peak_memory_mib() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib / 1024.0)
}

/// Runs the benchmark and prints its figures.
pub fn run(scene_path: &Path, resolution: [u32; 2], passes: u64) -> Result<(), String> {
    let mut settings = RenderSettings::new(scene_path, Path::new("renders"));
    settings.resolution = Some(resolution);
    let description = load_description(&settings)?;
    let start = Instant::now();
    let shot = Shot::new(&settings, description)?;
    let (scene, accel) = shot.pose(0.0);
    println!(
        "scene {} ({} triangles, {} lights), {}x{}, {} passes; BVH build {:.3} s",
        scene_path.display(),
        scene.triangle_count(),
        scene.lights.len(),
        resolution[0],
        resolution[1],
        passes,
        start.elapsed().as_secs_f64()
    );
    let renderer = Renderer::new(&scene, &accel, shot.sppm().clone());
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().map_err(|e| e.to_string())?;
        let start = Instant::now();
        let stats =
            pool.install(|| (0..passes).fold(PassStats::default(), |sum, i| sum + renderer.run_pass(i).2));
        let seconds = start.elapsed().as_secs_f64();
        let rays = stats.eye_rays + stats.shadow_rays + stats.photon_rays;
        let photon_paths = passes * renderer.settings().photons_per_pass as u64;
        println!(
            "threads {threads}: {:.3} passes/s, {:.0} photon paths/s, {:.2} Mrays/s (eye {:.2}, shadow {:.2}, photon {:.2})",
            passes as f64 / seconds,
            photon_paths as f64 / seconds,
            rays as f64 / seconds / 1e6,
            stats.eye_rays as f64 / seconds / 1e6,
            stats.shadow_rays as f64 / seconds / 1e6,
            stats.photon_rays as f64 / seconds / 1e6,
        );
    }
    match peak_memory_mib() {
        Some(mib) => println!("peak memory: {mib:.1} MiB"),
        None => println!("peak memory: unknown on this platform"),
    }
    Ok(())
}
