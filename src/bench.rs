//! `caustic bench`: passes, photon paths and rays per second with 1 and 2 threads, and peak
//! memory, for one scene at one resolution; with `--frames`, a frame range rendered with and
//! without reuse across frames at equal passes. Figures for notes and comparisons, never for tests.

use std::path::Path;
use std::time::Instant;

use crate::film::{Film, FilmMode};
use crate::frames::{self, load_description, RenderReport, RenderSettings, Shot};
use crate::memory;
use crate::sppm::{PassStats, Renderer};

/// Rays of every kind in `stats`.
fn rays(stats: PassStats) -> u64 {
    stats.eye_rays + stats.shadow_rays + stats.photon_rays
}

/// Renders `frames` of `scene` with and without reuse across frames, `passes` passes each, and
/// prints wall time, rays per frame and peak memory for both, and the speed-up.
pub fn run_frames(scene: &Path, frames: Vec<i32>, passes: u64) -> Result<(), String> {
    let out = std::env::temp_dir().join(format!("caustic-bench-{}", std::process::id()));
    let mut settings = RenderSettings::new(scene, &out);
    settings.frames = frames;
    settings.passes = Some(passes);
    let count = settings.frames.len() as f64;
    let mut seconds = Vec::new();
    for reuse in [true, false] {
        settings.reuse = reuse;
        memory::reset_peak();
        let start = Instant::now();
        let report: RenderReport = frames::render(&settings)?;
        let elapsed = start.elapsed().as_secs_f64();
        let own = report.frames.iter().map(|f| f.stats).sum::<PassStats>();
        let all = own + report.shared_stats;
        let peak = peak_memory();
        let mode = if reuse { "reuse" } else { "no reuse" };
        println!(
            "{mode}: {elapsed:.2} s ({:.3} s per frame), blocks of {} frames, peak heap memory {peak}",
            elapsed / count,
            report.block_frames
        );
        let per_frame = |n: u64| n as f64 / count;
        println!(
            "  per frame: {:.0} rays (eye {:.0}, shadow {:.0}, photon {:.0}), {:.0} tests against moving triangles",
            per_frame(rays(all)),
            per_frame(all.eye_rays),
            per_frame(all.shadow_rays),
            per_frame(all.photon_rays),
            per_frame(all.moving_tests),
        );
        seconds.push(elapsed);
    }
    let _ = std::fs::remove_dir_all(&out);
    println!("speed-up with reuse: {:.2}x", seconds[1] / seconds[0]);
    Ok(())
}

/// The peak heap memory since the last reset, for printing.
fn peak_memory() -> String {
    memory::peak_mib()
        .map_or("unknown (the counting allocator is not installed)".into(), |m| format!("{m:.1} MiB"))
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
        let s = renderer.settings();
        let mut film = Film::new(s.width, s.height, FilmMode::Spectral, 0);
        let mut accumulation_s = 0.0;
        let start = Instant::now();
        let stats = pool.install(|| {
            let mut stats = PassStats::default();
            for i in 0..passes {
                let (samples, estimates, pass_stats) = renderer.run_pass(i);
                let added = Instant::now();
                let sums = estimates.iter().map(|e| (e.radiance, e.laplacian));
                film.add_pass(samples.lambda_nm, samples.lambda_pdf, samples.radius, sums);
                accumulation_s += added.elapsed().as_secs_f64();
                stats = stats + pass_stats;
            }
            stats
        });
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
        let [eye, photon, grid, gather] = stats.stage_ns.map(|ns| ns as f64 * 1e-9 / seconds * 100.0);
        println!(
            "  time split: eye paths {eye:.0}%, photon paths {photon:.0}%, grid build {grid:.0}%, gather {gather:.0}%, accumulation {:.0}%",
            accumulation_s / seconds * 100.0
        );
    }
    println!("peak heap memory: {}", peak_memory());
    Ok(())
}
