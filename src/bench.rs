//! `caustic bench`: passes, photon paths and rays per second with 1 and 2 threads, and peak
//! memory, for one scene at one resolution; with `--frames`, a frame range rendered with and
//! without reuse across frames at equal passes. Figures for notes and comparisons, never for tests.

use std::path::Path;
use std::time::Instant;

use crate::film::{Film, FilmMode};
use crate::memory;
use crate::render::{
    self, add_estimates, load_description, Method, PhotonSampling, RenderReport, RenderSettings, Shot,
};
use crate::transport::{PassStats, Renderer};
use rayon::prelude::*;

/// Rays of every kind in `stats`.
fn rays(stats: PassStats) -> u64 {
    stats.eye_rays + stats.shadow_rays + stats.photon_rays
}

/// Renders `frames` of `scene` (at `resolution`, else the scene's) with and without reuse across
/// frames, `passes` passes each by `method`, and prints wall time, rays per frame and peak memory for both,
/// and the speed-up.
pub fn run_frames(
    scene: &Path,
    frames: Vec<i32>,
    (passes, method): (u64, Method),
    resolution: Option<[u32; 2]>,
) -> Result<(), String> {
    let out = std::env::temp_dir().join(format!("caustic-bench-{}", std::process::id()));
    let mut settings = RenderSettings::new(scene, &out);
    settings.resolution = resolution;
    settings.frames = frames;
    settings.passes = Some(passes);
    settings.method = method;
    let count = settings.frames.len() as f64;
    let mut seconds = Vec::new();
    for reuse in [true, false] {
        settings.reuse = reuse;
        memory::reset_peak();
        let start = Instant::now();
        let report: RenderReport = render::render(&settings)?;
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
        let t = report.time_split;
        println!(
            "  time per frame: posing {:.3} s, shared work {:.3} s, the frame's own paths and gathers {:.3} s, accumulation {:.3} s, error estimates {:.3} s, output {:.3} s",
            t.posing / count,
            t.shared / count,
            t.frames / count,
            t.accumulation / count,
            t.monitoring / count,
            t.output / count
        );
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

/// Times each measurement is repeated: the machine's other load only ever slows a run down, so
/// the fastest of several interleaved runs is the figure least disturbed by it.
const ROUNDS: usize = 3;

/// Times one pass's recorded rays are replayed for one measurement of bare traversal (one replay
/// takes a twentieth of a second, too short to time alone).
const REPLAYS: usize = 8;

/// Runs the benchmark and prints its figures: throughput and time split with 1 and 2 threads,
/// the bare BVH traversal rate on the same rays, and the peak memory of a pass. Each rate is
/// measured [`ROUNDS`] times, 1 and 2 threads interleaved; the fastest run is reported.
pub fn run(
    scene_path: &Path,
    resolution: [u32; 2],
    passes: std::ops::Range<u64>,
    photons: Option<usize>,
    (photon_sampling, method): (PhotonSampling, Method),
) -> Result<(), String> {
    let mut settings = RenderSettings::new(scene_path, Path::new("renders"));
    settings.resolution = Some(resolution);
    settings.photons = photons;
    settings.photon_sampling = photon_sampling;
    settings.method = method;
    let description = load_description(&settings)?;
    let start = Instant::now();
    let shot = Shot::new(&settings, std::sync::Arc::new(description))?;
    let (scene, accel) = shot.pose(0.0);
    println!(
        "scene {} ({} triangles, {} lights), {}x{}, {} photon paths per pass, passes {}..{}; BVH build {:.3} s",
        scene_path.display(),
        scene.triangle_count(),
        scene.lights.len(),
        resolution[0],
        resolution[1],
        shot.pass_settings().photons_per_pass,
        passes.start,
        passes.end,
        start.elapsed().as_secs_f64()
    );
    let renderer = Renderer::new(&scene, &accel, shot.pass_settings().clone());
    memory::reset_peak();
    in_pool(2, || time_passes(&renderer, passes.start..passes.start + 1))?;
    let pass_memory = peak_memory();
    let recorded = {
        let (scene, accel) = shot.pose(0.0);
        let accel = accel.recording();
        let renderer = Renderer::new(&scene, &accel, shot.pass_settings().clone());
        renderer.run_pass(&renderer.pass_samples(passes.start));
        accel.recorded()
    };
    let mut fastest: [Option<Timed>; 2] = [None, None];
    let mut fastest_bare = [f64::INFINITY; 2];
    for round in 1..=ROUNDS {
        let mut seconds = [0.0; 2];
        for (slot, threads) in [1, 2].into_iter().enumerate() {
            let (s, (stats, accumulation_s)) = in_pool(threads, || time_passes(&renderer, passes.clone()))?;
            seconds[slot] = s;
            if fastest[slot].as_ref().is_none_or(|f| s < f.seconds) {
                fastest[slot] = Some(Timed { seconds: s, stats, accumulation_s });
            }
            let (bare, _) = in_pool(threads, || {
                (0..REPLAYS)
                    .map(|_| recorded.par_chunks(4096).map(|chunk| accel.replay(chunk)).sum::<usize>())
                    .sum::<usize>()
            })?;
            fastest_bare[slot] = fastest_bare[slot].min(bare / REPLAYS as f64);
        }
        println!("round {round}: 2 threads {:.2}x as fast as 1", seconds[0] / seconds[1]);
    }
    let pass_count = passes.end - passes.start;
    let photons_per_pass = renderer.settings().photons_per_pass;
    for (slot, timed) in fastest.iter().flatten().enumerate() {
        print_throughput(slot + 1, pass_count, timed, photons_per_pass);
        let raw = recorded.len() as f64 / fastest_bare[slot];
        let [eye_ns, photon_ns, ..] = timed.stats.stage_ns;
        let tracing_s = (eye_ns + photon_ns) as f64 * 1e-9;
        println!(
            "threads {}: bare obvhs traversal of one pass's {} rays: {:.2} Mrays/s; the full pass runs at {:.0}% of it, its eye and photon paths alone (all its rays, no grid or gather) at {:.0}%",
            slot + 1,
            recorded.len(),
            raw / 1e6,
            rays(timed.stats) as f64 / timed.seconds / raw * 100.0,
            rays(timed.stats) as f64 / tracing_s / raw * 100.0
        );
    }
    if let [Some(one), Some(two)] = &fastest {
        println!("fastest runs: 2 threads {:.2}x as fast as 1", one.seconds / two.seconds);
    }
    println!("peak heap memory of a render's pass (measured before the rays were recorded): {pass_memory}");
    Ok(())
}

/// One timed run of the passes.
struct Timed {
    seconds: f64,
    stats: PassStats,
    /// Of `seconds`, the time spent adding passes to the film.
    accumulation_s: f64,
}

/// Runs `work` on a pool of `threads` workers; gives its wall time and result.
fn in_pool<T: Send>(threads: usize, work: impl FnOnce() -> T + Send) -> Result<(f64, T), String> {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().map_err(|e| e.to_string())?;
    let start = Instant::now();
    let result = pool.install(work);
    Ok((start.elapsed().as_secs_f64(), result))
}

/// Renders `passes` into a film as a render does; gives the stats and the seconds spent adding
/// passes to the film.
fn time_passes(renderer: &Renderer, passes: std::ops::Range<u64>) -> (PassStats, f64) {
    let s = renderer.settings();
    let mut film = Film::new(s.width, s.height, FilmMode::Spectral, 0, false);
    let (mut stats, mut accumulation_s) = (PassStats::default(), 0.0);
    for i in passes {
        let samples = renderer.pass_samples(i);
        let (estimates, pass_stats) = renderer.run_pass(&samples);
        let added = Instant::now();
        add_estimates(&mut film, &samples, &estimates);
        accumulation_s += added.elapsed().as_secs_f64();
        stats = stats + pass_stats;
    }
    (stats, accumulation_s)
}

fn print_throughput(threads: usize, passes: u64, timed: &Timed, photons_per_pass: usize) {
    let Timed { seconds, stats, accumulation_s } = timed;
    let per_second = |n: u64| n as f64 / seconds / 1e6;
    println!(
        "threads {threads}: {:.3} passes/s ({:.1} ms a pass), {:.0} photon paths/s, {:.2} Mrays/s (eye {:.2}, shadow {:.2}, photon {:.2})",
        passes as f64 / seconds,
        seconds / passes as f64 * 1e3,
        (passes * photons_per_pass as u64) as f64 / seconds,
        per_second(rays(*stats)),
        per_second(stats.eye_rays),
        per_second(stats.shadow_rays),
        per_second(stats.photon_rays),
    );
    let [eye, photon, grid, gather] = stats.stage_ns.map(|ns| ns as f64 * 1e-9 / seconds * 100.0);
    println!(
        "  time split: eye paths {eye:.0}%, photon paths {photon:.0}%, grid build {grid:.0}%, gather {gather:.0}%, accumulation {:.0}%",
        accumulation_s / seconds * 100.0
    );
    print_photon_sampling(stats);
}

/// The fractions of photon paths a visible point sees, among the pilot's uniform paths and the
/// Markov chains' steps (`--photon-sampling`).
fn print_photon_sampling(stats: &PassStats) {
    let share = |seen: u64, all: u64| match all {
        0 => "none traced".to_string(),
        _ => format!("{:.1}% of {all}", seen as f64 / all as f64 * 100.0),
    };
    println!(
        "  photon paths a visible point sees: uniform pilot {}, chain proposals {}",
        share(stats.pilot_paths_seen, stats.pilot_paths),
        share(stats.chain_steps_seen, stats.chain_steps)
    );
}
