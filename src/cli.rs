//! The command line: arguments to settings, errors to one message and a non-zero exit.

use std::path::{Path, PathBuf};

use clap::{Args, Parser, Subcommand};

use crate::error::Statistic;
use crate::monitor::ErrorSettings;
use crate::render::{self, LightSampling, Method, PhotonSampling, ProgressStyle, RenderSettings};

/// The bundled demo scene, used when no scene is given.
pub const DEMO_SCENE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/cornell_glass.gltf");

/// Caustic: spectral progressive photon mapping for glTF scenes.
#[derive(Parser, Debug)]
#[command(name = "caustic", version, about, long_about = None)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Render a glTF scene to OUT/frame_0001.exr.
    Render(RenderArgs),
    /// Measure passes, photon paths and rays per second, with 1 and 2 threads, and peak memory.
    Bench(BenchArgs),
    /// Print, as JSON, what a scene needs (dispersion, motion, depth of field) and what will be skipped.
    Info(InfoArgs),
    /// Draw error against time from --log files as an SVG chart (estimated, and true when known).
    Plot(PlotArgs),
    /// Print, as JSON, an EXR's luminance error against a reference EXR (RMSE, relative MSE, mean
    /// relative error): for regression tests and comparisons with other renderers.
    Compare(CompareArgs),
    /// Add up partial results (`render --pass-range A..B --partial`) into OUT/frame_####.exr.
    Merge(MergeArgs),
}

/// Flags of `caustic merge`.
#[derive(Args, Debug)]
pub struct MergeArgs {
    /// Partial results (`frame_####.passes_A-B.partial`), of one or more frames; each frame's must
    /// cover passes 0..N without a gap or an overlap.
    #[arg(required = true)]
    partials: Vec<PathBuf>,
    /// Output folder for frame_NNNN.exr.
    #[arg(short, long = "out", value_name = "DIR", default_value = "renders")]
    out: PathBuf,
    /// Confidence of the per-pixel error bound (Error.Y), in (0, 1).
    #[arg(long, value_name = "C", default_value_t = 0.9, allow_negative_numbers = true, value_parser = unit_interval)]
    confidence: f64,
}

/// Flags of `caustic compare`.
#[derive(Args, Debug)]
pub struct CompareArgs {
    /// The image to measure (an EXR with `Combined.R/G/B` or `R/G/B`).
    image: PathBuf,
    /// The converged reference, the same size.
    #[arg(long, value_name = "EXR")]
    reference: PathBuf,
}

/// Flags of `caustic plot`.
#[derive(Args, Debug)]
pub struct PlotArgs {
    /// Log files written by `caustic render --log`.
    #[arg(required = true)]
    logs: Vec<PathBuf>,
    /// The chart to write (SVG).
    #[arg(short, long = "out", value_name = "SVG")]
    out: PathBuf,
}

/// Flags of `caustic info`.
#[derive(Args, Debug)]
pub struct InfoArgs {
    /// The scene (default: the demo scene).
    scene: Option<PathBuf>,
    /// Frames the render would cover: 7, 1-48, 1-48:2 or 1,5,9.
    #[arg(long, value_name = "SPEC", value_parser = parse_frames, default_value = "1")]
    frames: FrameList,
    /// Image size WxH the render would have (shapes the first radius).
    #[arg(long, value_name = "WxH", value_parser = parse_resolution)]
    resolution: Option<[u32; 2]>,
    /// Photon paths per pass the render would trace (shapes the first radius).
    #[arg(long, value_name = "N", value_parser = at_least_one)]
    photons: Option<u64>,
    /// How the render would draw photon paths (shapes the first radius).
    #[arg(long, value_enum, default_value_t = PhotonSampling::Uniform)]
    photon_sampling: PhotonSampling,
}

/// Flags of `caustic render`.
#[derive(Args, Debug)]
pub struct RenderArgs {
    /// The glTF 2.0 scene (.gltf or .glb); the bundled demo scene when omitted.
    scene: Option<PathBuf>,
    /// Output folder for frame_NNNN.exr.
    #[arg(short, long = "out", value_name = "DIR", default_value = "renders")]
    out: PathBuf,
    /// Number of passes (default 64 unless --time-budget is given).
    #[arg(long, value_name = "N", value_parser = at_least_one)]
    passes: Option<u64>,
    /// Stop after the pass that ends past this many seconds.
    #[arg(long, value_name = "SECS", allow_negative_numbers = true, value_parser = positive_f64)]
    time_budget: Option<f64>,
    /// Photon paths per pass (default: one per pixel).
    #[arg(long, value_name = "N", value_parser = at_least_one)]
    photons: Option<u64>,
    /// Radius reduction alpha of Knaus & Zwicker, in (0, 1) (default: 2/3 for sppm, 0.8 for
    /// vcm).
    #[arg(long, value_name = "A", allow_negative_numbers = true, value_parser = unit_interval)]
    alpha: Option<f64>,
    /// First-pass gather radius in scene units (default: from the view where the camera sees
    /// surfaces and the photons a pass lands there; `caustic info` prints it and what it comes from).
    #[arg(long, value_name = "R", allow_negative_numbers = true, value_parser = positive_f64)]
    radius: Option<f64>,
    /// Image size WxH (default: the scene's, else 640 wide at the camera's aspect).
    #[arg(long, value_name = "WxH", value_parser = parse_resolution)]
    resolution: Option<[u32; 2]>,
    /// Render only the window X,Y,W,H of the image (pixels from the top-left; Blender's render
    /// region): the EXR is W x H and its pixels are those of the whole image's render.
    #[arg(long, value_name = "X,Y,W,H", value_parser = parse_crop)]
    crop: Option<[u32; 4]>,
    /// Random seed: the same seed gives the same image with any thread count.
    #[arg(long, value_name = "S", default_value_t = 1)]
    seed: u64,
    /// Worker threads, 1 to 256 (default: all cores).
    #[arg(long, value_name = "N", value_parser = thread_count)]
    threads: Option<u64>,
    /// Progress display: a bar on the terminal, JSON lines on stdout, or none.
    #[arg(long, value_enum, default_value_t = ProgressStyle::Bar)]
    progress: ProgressStyle,
    /// Render every pass at this one wavelength, 360 to 830 nm (diagnosis; the image is the
    /// radiance relative to white at that wavelength, in its colour).
    #[arg(long, value_name = "NM", value_parser = wavelength, conflicts_with = "spectral_bins")]
    wavelength: Option<f32>,
    /// How next-event estimation chooses a light: by the light tree (power, distance and
    /// orientation as seen from each point), or in proportion to power alone.
    #[arg(long, value_enum, default_value_t = LightSampling::Tree)]
    light_sampling: LightSampling,
    /// How photon paths are drawn: uniformly from the lights, or by Markov chains that keep to
    /// the paths some visible point sees (Hachisuka & Jensen 2011: for a room lit through a
    /// window, a small object in a large scene); auto is uniform where anything in the scene is
    /// animated or where a uniform pilot of pass 0 finds a quarter of its paths seen or more (the
    /// demo box, at 40%, renders faster uniformly), else chooses per pass by its own pilot.
    #[arg(long, value_enum, default_value_t = PhotonSampling::Uniform)]
    photon_sampling: PhotonSampling,
    /// How a pass combines camera and light paths: stochastic progressive photon mapping, or
    /// vertex connection and merging (photon merging where SPPM gathers and at glossy vertices
    /// before, combined with path tracing, light tracing and connections by multiple importance
    /// sampling; not yet for media that scatter).
    #[arg(long, value_enum, default_value_t = Method::Sppm)]
    method: Method,
    /// Also write Cycles' Denoising Albedo and Denoising Normal passes (for Blender's Denoise
    /// node, Open Image Denoise).
    #[arg(long)]
    denoising_passes: bool,
    /// Also write K spectral bands (channels Spectral.<centre>nm, W/(m^2 sr nm)), 1 to 94.
    #[arg(long, value_name = "K", value_parser = spectral_bins, default_value_t = 0)]
    spectral_bins: usize,
    /// Frames to render: 7, 1-48, 1-48:2 (every second frame) or 1,5,9; files OUT/frame_####.exr.
    #[arg(long, value_name = "SPEC", value_parser = parse_frames, default_value = "1")]
    frames: FrameList,
    /// Skip frames whose EXR already exists (EXRs are written whole and renamed, never half).
    #[arg(long)]
    resume: bool,
    /// Motion-blur shutter length in frames, centred on each frame (0 turns motion blur off);
    /// default: the scene's.
    #[arg(long, value_name = "FRAMES", allow_negative_numbers = true, value_parser = non_negative_f32)]
    shutter: Option<f32>,
    /// Camera f-stop for depth of field (0 turns it off); default: the scene's camera.
    #[arg(long, value_name = "F", allow_negative_numbers = true, value_parser = non_negative_f32)]
    fstop: Option<f32>,
    /// Distance to the plane in focus, scene units; default: the scene's camera, else 10.
    #[arg(long, value_name = "D", allow_negative_numbers = true, value_parser = non_negative_f32)]
    focus_distance: Option<f32>,
    /// Confidence of the per-pixel error bound (Error.Y), in (0, 1).
    #[arg(long, value_name = "C", default_value_t = 0.9, allow_negative_numbers = true, value_parser = unit_interval)]
    confidence: f64,
    /// Append error-against-time lines (JSON) for each frame to FILE.
    #[arg(long, value_name = "FILE")]
    log: Option<PathBuf>,
    /// A converged render to measure the true error against (#### becomes the frame number).
    #[arg(long, value_name = "EXR")]
    reference: Option<PathBuf>,
    /// End a frame when the relative error bound's statistic falls below E (e.g. 0.05).
    #[arg(long, value_name = "E", allow_negative_numbers = true, value_parser = positive_f64)]
    target_error: Option<f64>,
    /// The statistic --target-error compares: mean, median or p90 of the relative bound.
    #[arg(long, value_enum, default_value_t = Statistic::Mean)]
    target_statistic: Statistic,
    /// Render each frame on its own instead of sharing paths on static geometry between frames
    /// rendered together (the same images in expectation; for comparison, and as a fallback).
    #[arg(long)]
    no_reuse: bool,
    /// Render exactly passes A..B (A included, B not) of each frame, as passes A..B of a whole
    /// run would be; needs --partial.
    #[arg(long, value_name = "A..B", value_parser = parse_pass_range, requires = "partial",
          conflicts_with_all = ["passes", "time_budget", "target_error"])]
    pass_range: Option<std::ops::Range<u64>>,
    /// Write each frame's sums as OUT/frame_####.passes_A-B.partial for `caustic merge`, instead of
    /// an EXR; needs --pass-range.
    #[arg(long, requires = "pass_range")]
    partial: bool,
    /// Memory for the frames rendered together, e.g. 4G, 512M or bytes (default 4G): it sets how
    /// many frames share each pass.
    #[arg(long, value_name = "SIZE", value_parser = memory_size, default_value = "4G")]
    memory_budget: u64,
}

/// Flags of `caustic bench`.
#[derive(Args, Debug)]
pub struct BenchArgs {
    /// The scene (default: the demo scene).
    scene: Option<PathBuf>,
    /// Image size WxH (default 640x360; with --frames, the scene's).
    #[arg(long, value_parser = parse_resolution)]
    resolution: Option<[u32; 2]>,
    /// Passes per measurement.
    #[arg(long, default_value_t = 8, value_parser = at_least_one)]
    passes: u64,
    /// Index of the first pass measured: later passes gather with smaller radii, as most of a
    /// long render does (the radius squared falls as pass^(-1/3)).
    #[arg(long, value_name = "I", default_value_t = 0)]
    first_pass: u64,
    /// Photon paths per pass (default: one per pixel).
    #[arg(long, value_name = "N", value_parser = at_least_one)]
    photons: Option<u64>,
    /// How photon paths are drawn (as `caustic render --photon-sampling`).
    #[arg(long, value_enum, default_value_t = PhotonSampling::Uniform)]
    photon_sampling: PhotonSampling,
    /// How a pass combines camera and light paths (as `caustic render --method`).
    #[arg(long, value_enum, default_value_t = Method::default())]
    method: Method,
    /// Instead, render these frames with and without reuse across frames at equal passes (at the
    /// scene's resolution) and compare time, rays per frame and peak memory.
    #[arg(long, value_name = "SPEC", value_parser = parse_frames)]
    frames: Option<FrameList>,
}

/// Parses `s` as a `T` that `valid` accepts, or says what was `expected`.
fn parse_checked<T: std::str::FromStr>(
    s: &str,
    valid: impl Fn(&T) -> bool,
    expected: &str,
) -> Result<T, String> {
    s.parse::<T>().ok().filter(|v| valid(v)).ok_or_else(|| format!("expected {expected}, got '{s}'"))
}

fn at_least_one(s: &str) -> Result<u64, String> {
    parse_checked(s, |&v| v >= 1, "a whole number of at least 1")
}

fn wavelength(s: &str) -> Result<f32, String> {
    parse_checked(s, |v| (360.0..=830.0).contains(v), "a wavelength from 360 to 830 nm")
}

fn spectral_bins(s: &str) -> Result<usize, String> {
    let max = crate::film::MAX_SPECTRAL_BINS;
    parse_checked(s, |&v| v <= max, &format!("a number of bands from 0 to {max}"))
}

fn thread_count(s: &str) -> Result<u64, String> {
    parse_checked(s, |v| (1..=256).contains(v), "a whole number from 1 to 256")
}

/// A size in bytes: a whole number with an optional K, M, G or T (powers of 1024).
fn memory_size(s: &str) -> Result<u64, String> {
    let bad = || format!("expected a size like 4G, 512M or a number of bytes, got '{s}'");
    let upper = s.trim().to_ascii_uppercase();
    let number = upper.strip_suffix("IB").or(upper.strip_suffix('B')).unwrap_or(&upper);
    let (digits, shift) = match number.char_indices().last() {
        Some((i, unit @ ('K' | 'M' | 'G' | 'T'))) => {
            (&number[..i], 10 * (1 + "KMGT".find(unit).unwrap_or(0)))
        }
        _ => (number, 0),
    };
    let value: u64 = digits.trim().parse().ok().filter(|&v| v >= 1).ok_or_else(bad)?;
    value.checked_mul(1 << shift).ok_or_else(|| format!("'{s}' is too large"))
}

/// A pass range `A..B` with A < B.
fn parse_pass_range(s: &str) -> Result<std::ops::Range<u64>, String> {
    let range = s
        .split_once("..")
        .and_then(|(a, b)| Some(a.trim().parse::<u64>().ok()?..b.trim().parse::<u64>().ok()?));
    match range {
        Some(r) if r.start < r.end => Ok(r),
        _ => Err(format!("expected passes A..B with A < B (A included, B not), e.g. 0..32; got '{s}'")),
    }
}

fn positive_f64(s: &str) -> Result<f64, String> {
    parse_checked(s, |&v: &f64| v > 0.0 && v.is_finite(), "a positive number")
}

fn non_negative_f32(s: &str) -> Result<f32, String> {
    parse_checked(s, |&v: &f32| v >= 0.0 && v.is_finite(), "a number >= 0")
}

/// The frames a `--frames` specification names, in order.
#[derive(Clone, Debug)]
pub struct FrameList(pub Vec<i32>);

/// The most frames one render takes.
const MAX_FRAMES: usize = 1_000_000;

/// A frame specification: `7`, `1-48`, `1-48:2` or `1,5,9` (items may mix: `1-10,20`).
pub fn parse_frames(spec: &str) -> Result<FrameList, String> {
    let bad = || format!("expected frames like 7, 1-48, 1-48:2 or 1,5,9 (whole numbers >= 0), got '{spec}'");
    let mut frames = Vec::new();
    for item in spec.split(',') {
        let (range, step) = item.split_once(':').map_or((item, "1"), |(r, s)| (r, s));
        let step: usize = step.trim().parse().ok().filter(|&s| s >= 1).ok_or_else(bad)?;
        let (first, last) = range.split_once('-').unwrap_or((range, range));
        let first: i32 = first.trim().parse().ok().filter(|&f| f >= 0).ok_or_else(bad)?;
        let last: i32 = last.trim().parse().ok().filter(|&l| l >= first).ok_or_else(bad)?;
        if (last - first) as usize / step + frames.len() >= MAX_FRAMES {
            return Err(format!("'{spec}' asks for more than {MAX_FRAMES} frames"));
        }
        frames.extend((first..=last).step_by(step));
    }
    Ok(FrameList(frames))
}

fn unit_interval(s: &str) -> Result<f64, String> {
    parse_checked(s, |&v: &f64| v > 0.0 && v < 1.0, "a number strictly between 0 and 1")
}

fn parse_crop(s: &str) -> Result<[u32; 4], String> {
    let numbers: Vec<u32> = s
        .split(',')
        .map(|n| n.trim().parse::<u32>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("expected X,Y,W,H in whole pixels (such as 10,20,64,48), got '{s}'"))?;
    match numbers[..] {
        [x, y, w, h] if w > 0 && h > 0 => Ok([x, y, w, h]),
        _ => Err(format!("expected X,Y,W,H with a width and height of 1 or more, got '{s}'")),
    }
}

fn parse_resolution(s: &str) -> Result<[u32; 2], String> {
    let parsed =
        s.split_once(['x', 'X']).and_then(|(w, h)| Some([w.parse::<u32>().ok()?, h.parse::<u32>().ok()?]));
    match parsed {
        Some([w, h]) if (1..=65536).contains(&w) && (1..=65536).contains(&h) => Ok([w, h]),
        _ => Err(format!("expected WIDTHxHEIGHT with each between 1 and 65536, e.g. 640x360; got '{s}'")),
    }
}

impl RenderArgs {
    fn settings(&self) -> RenderSettings {
        RenderSettings {
            scene: self.scene.clone().unwrap_or_else(|| PathBuf::from(DEMO_SCENE)),
            out_dir: self.out.clone(),
            passes: self.passes,
            time_budget_s: self.time_budget,
            photons: self.photons.map(|n| n as usize),
            alpha: self.alpha,
            radius: self.radius,
            resolution: self.resolution,
            crop: self.crop,
            seed: self.seed,
            progress: self.progress,
            wavelength_nm: self.wavelength,
            light_sampling: self.light_sampling,
            photon_sampling: self.photon_sampling,
            method: self.method,
            spectral_bins: self.spectral_bins,
            denoising_passes: self.denoising_passes,
            frames: self.frames.0.clone(),
            resume: self.resume,
            shutter_frames: self.shutter,
            fstop: self.fstop,
            focus_distance: self.focus_distance,
            errors: ErrorSettings {
                confidence: self.confidence,
                log: self.log.clone(),
                reference: self.reference.clone(),
                target: self.target_error.map(|e| (e, self.target_statistic)),
            },
            reuse: !self.no_reuse,
            memory_budget: self.memory_budget,
            partial_passes: self.pass_range.clone(),
        }
    }
}

/// A thread pool of `threads` workers (all cores when `None`).
fn thread_pool(threads: Option<u64>) -> Result<rayon::ThreadPool, String> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads.unwrap_or(0) as usize)
        .build()
        .map_err(|e| format!("cannot start worker threads: {e}"))
}

/// Parses the arguments and runs the command; `Err` is the message for stderr.
pub fn run(cli: Cli) -> Result<(), String> {
    match cli.command {
        Command::Render(args) => {
            let settings = args.settings();
            // Ctrl-C and SIGTERM end the render after its current pass, keeping every written frame.
            ctrlc::set_handler(render::request_stop).map_err(|e| format!("cannot watch for Ctrl-C: {e}"))?;
            let report = thread_pool(args.threads)?.install(|| render::render(&settings))?;
            if settings.progress != ProgressStyle::Json {
                if !report.skipped.is_empty() {
                    eprintln!("caustic: skipped {} frames already rendered (--resume)", report.skipped.len());
                }
                if let (Some(peak), true) = (crate::memory::peak_mib(), report.frames.len() > 1) {
                    eprintln!(
                        "caustic: {} frames rendered {} at a time (--memory-budget); peak memory {peak:.0} MiB",
                        report.frames.len(),
                        report.block_frames
                    );
                }
            }
            Ok(())
        }
        Command::Info(args) => {
            let scene = args.scene.unwrap_or_else(|| PathBuf::from(DEMO_SCENE));
            let settings = RenderSettings {
                frames: args.frames.0,
                resolution: args.resolution,
                photons: args.photons.map(|n| n as usize),
                photon_sampling: args.photon_sampling,
                ..RenderSettings::new(&scene, Path::new("."))
            };
            let report = crate::info::report(&settings)?;
            println!("{}", serde_json::to_string_pretty(&report).expect("JSON"));
            Ok(())
        }
        Command::Plot(args) => crate::plot::plot(&args.logs, &args.out),
        Command::Compare(args) => {
            let error = crate::monitor::compare(&args.image, &args.reference)?;
            println!("{}", serde_json::to_string(&error).expect("JSON"));
            Ok(())
        }
        Command::Merge(args) => {
            for (path, frame) in render::merge(&args.partials, &args.out, args.confidence)? {
                eprintln!("caustic: wrote {} ({} passes)", path.display(), frame.passes);
            }
            Ok(())
        }
        Command::Bench(args) => {
            let scene = args.scene.unwrap_or_else(|| PathBuf::from(DEMO_SCENE));
            match args.frames {
                Some(frames) => {
                    crate::bench::run_frames(&scene, frames.0, (args.passes, args.method), args.resolution)
                }
                None => {
                    let photons = args.photons.map(|n| n as usize);
                    crate::bench::run(
                        &scene,
                        args.resolution.unwrap_or(BENCH_RESOLUTION),
                        args.first_pass..args.first_pass + args.passes,
                        photons,
                        (args.photon_sampling, args.method),
                    )
                }
            }
        }
    }
}

/// `caustic bench`'s image size when none is given (one frame).
const BENCH_RESOLUTION: [u32; 2] = [640, 360];

/// The program: parse, run, and exit non-zero with one message on failure.
pub fn main() -> std::process::ExitCode {
    report_panics_as_errors();
    let cli = Cli::parse();
    match run(cli) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(message) => {
            eprintln!("caustic: error: {message}");
            std::process::ExitCode::FAILURE
        }
    }
}

/// A panic (a bug in Caustic) is reported on one `caustic: error:` line that says where it
/// happened and what went wrong, so that whoever ran the renderer (the add-on shows the last
/// error line) sees the cause rather than Rust's note about backtraces. With `RUST_BACKTRACE`
/// set, Rust's own report follows.
fn report_panics_as_errors() {
    let rust_report = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let message = info
            .payload()
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| info.payload().downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "no message".into());
        let place = info
            .location()
            .map_or_else(|| "an unknown place".into(), |l| format!("{}:{}", l.file(), l.line()));
        eprintln!(
            "caustic: error: internal error at {place}: {} (a bug in Caustic: please report it with the scene)",
            message.replace('\n', " ")
        );
        if std::env::var_os("RUST_BACKTRACE").is_some() {
            rust_report(info);
        }
    }));
}
