//! `--memory-budget` bounds what rendering frames together costs beyond rendering one alone
//! (the frames' sums, and the eye paths, gathers and common film a block shares).
//!
//! The test program counts the heap as the `caustic` program does, so it holds this one test:
//! another running beside it would count too.

mod common;

use caustic::memory::{self, CountingAllocator};
use caustic::render::{self, RenderSettings};
use common::*;

#[global_allocator]
static ALLOCATOR: CountingAllocator = CountingAllocator;

/// The heap's peak while `settings` render, in MiB, and the longest block.
fn peak_while_rendering(settings: &RenderSettings) -> (f64, usize) {
    memory::reset_peak();
    let report = render::render(settings).unwrap_or_else(|e| panic!("render failed: {e}"));
    (memory::peak_mib().expect("the counting allocator is installed"), report.block_frames)
}

#[test]
fn frames_rendered_together_stay_within_the_memory_budget() {
    let dir = tempfile::tempdir().unwrap();
    let mut s = settings(&bundled_scene("shot.gltf"), &dir.path().join("alone"), 2);
    s.resolution = Some([160, 120]);
    let (alone, _) = peak_while_rendering(&s);
    let budget_mib = 40;
    s.frames = (1..=24).collect();
    s.memory_budget = budget_mib << 20;
    s.out_dir = dir.path().join("together");
    let (together, block) = peak_while_rendering(&s);
    assert!(block > 1 && block < 24, "the budget holds some of the frames at once, not all: {block}");
    let beyond = together - alone;
    assert!(
        beyond <= budget_mib as f64,
        "{block} frames at once took {beyond:.1} MiB beyond one frame alone, over the {budget_mib} MiB budget"
    );
    eprintln!("{block} frames at once: {beyond:.1} MiB beyond one frame alone ({alone:.1} MiB)");
}
