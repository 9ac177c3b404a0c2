//! The one place that drives the pipeline: load, prepare the time range, then for each frame run
//! passes (posing the scene at each pass's time when something moves), accumulate, write.
//!
//! Takes the render settings; gives `OUT/frame_####.exr` per frame and a report of what was done.
//! Passes run until `--passes` or `--time-budget` is reached, whichever comes first. Each pass
//! samples one time in the frame's shutter (docs/design.md, step 1), shared by its eye rays and photons.

mod blocks;
mod merge;
pub mod partial;
mod report;
mod settings;
mod shot;

pub use crate::progress::ProgressStyle;
pub use crate::transport::{LightSampling, Method, PhotonSampling};
pub use blocks::add_estimates;
pub use blocks::render;
pub use merge::merge;
pub use report::{write_frame, FrameReport, RenderReport, TimeSplit};
pub use settings::*;
pub use shot::{motion_spans, Shot};

/// Set when the user asks the render to stop (Ctrl-C, SIGTERM): the pass in flight finishes,
/// frames not yet written are dropped, and the render ends with an error naming what was kept.
static STOP_REQUESTED: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Asks the render in progress to stop after its current pass (safe from a signal handler).
pub fn request_stop() {
    STOP_REQUESTED.store(true, std::sync::atomic::Ordering::SeqCst);
}

pub(super) fn stop_requested() -> bool {
    STOP_REQUESTED.load(std::sync::atomic::Ordering::SeqCst)
}

/// Passes when neither a pass count nor a time budget is given.
pub const DEFAULT_PASSES: u64 = 64;

/// Memory for the frames rendered together when `--memory-budget` is not given: 4 GiB.
pub const DEFAULT_MEMORY_BUDGET: u64 = 4 << 30;

/// Blender's default focus distance, used when an f-stop is given without one.
pub const DEFAULT_FOCUS_DISTANCE: f32 = 10.0;
