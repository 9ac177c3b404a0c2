//! How a pass's photon paths draw their primary samples: each from a stream of its own
//! (uniform), or from Markov chains that keep to the paths some visible point sees (Hachisuka &
//! Jensen 2011, "Robust Adaptive Photon Tracing using Photon Path Visibility").
//!
//! A path is *seen* when one of its stored photons lies within the pass's radius of a visible
//! point. A path that is not seen adds nothing to any pixel (the gather and its edge tests read
//! photons within the radius alone), so the pass's photon estimate is `V * E[f | seen]`, where
//! `V` is the fraction of primary sample space whose paths are seen. Uniform paths estimate `V`
//! (the normalisation, measured); Markov chains whose stationary distribution is uniform over
//! the seen paths estimate the mean. A chain's move is accepted when its proposal is seen: a
//! small step moves every coordinate but the light's choice by a symmetric amount (Kelemen et al.
//! 2002); a large step draws a new uniform path (it also counts toward `V`). Each chain starts
//! from a seen uniform path, a sample of the stationary distribution itself, so no start-up is
//! discarded.
//!
//! Every pass first traces a pilot: its first uniform paths, exactly as a uniform pass would.
//! Under [`PhotonSampling::Auto`] a pass whose pilot is mostly seen traces the rest uniformly
//! (the same bits as `uniform`); otherwise the rest of its paths' budget goes to chains. Chains
//! and their streams are keyed by (seed, pass, chain), never by thread, so a pass is the same
//! bits with any thread count and passes stay independent and mergeable.

use rayon::prelude::*;

use super::photons::{continue_photon, trace_photon, Photon};
use super::visible::EyeResult;
use crate::sampling::{stream, wrap_unit, Sampler, Stream, Uniforms};
use crate::transport::context::{Crop, PassSamples, PassSettings, PassStats, PhotonSampling, Renderer};
use crate::transport::emission::{emit_photon, photon_stream};
use crate::transport::points::PointGrid;

/// The share of a pass's photon paths traced uniformly first, as the pilot.
const PILOT_SHARE: usize = 16;

/// Under `auto`, a pass uses chains when fewer than this fraction of its pilot's paths are seen.
pub const AUTO_VISIBLE_BELOW: f64 = 0.25;

/// Steps of one Markov chain.
const CHAIN_STEPS: usize = 1024;

/// The probability that a chain's step is a large one (a new uniform path).
const LARGE_STEP: f32 = 0.25;

/// The largest and smallest moves of a coordinate in a small step, spread evenly in log scale
/// between them (Kelemen et al. 2002's mutation, their sizes). The size does not adapt to the
/// acceptance as Hachisuka & Jensen's does: adapting within chains as short as a pass's lets the
/// size, and so how long a chain stays, depend on where it is, which biased a glass ball's
/// caustic by 12% against Cycles.
const LARGEST_MOVE: f32 = 1.0 / 16.0;
const SMALLEST_MOVE: f32 = 1.0 / 1024.0;

impl Renderer<'_> {
    /// The photons of `pass`, whose visible points are `points` (those the eye pass found).
    pub(crate) fn trace_photons(
        &self,
        pass: &PassSamples,
        points: impl Iterator<Item = (usize, glam::Vec3)>,
    ) -> (Vec<Photon>, PassStats) {
        let paths = self.settings.photons_per_pass;
        if self.settings.photon_sampling == PhotonSampling::Uniform {
            return trace_uniform(self, pass, 0..paths);
        }
        let seen = PointGrid::new(points, pass.radius);
        let round = paths.div_ceil(PILOT_SHARE);
        let mut pilot = trace_pilot(self, pass, 0..round, &seen);
        if self.settings.photon_sampling == PhotonSampling::Auto
            && pilot.seen_fraction() >= AUTO_VISIBLE_BELOW
        {
            let (rest, stats) = trace_uniform(self, pass, round..paths);
            pilot.photons.extend(rest);
            return (pilot.photons, pilot.stats + stats);
        }
        // Chains need a seen path to start from: where the first round found none, the pilot
        // goes on, a round at a time, up to half the pass's paths. Those rounds run because the
        // rounds before found nothing, so they would bias the normalisation upward (as the
        // trials up to a first success overestimate its probability): only the first round
        // counts toward it.
        while pilot.seen_paths.is_empty() && (pilot.paths as usize) + round <= paths / 2 {
            let start = pilot.paths as usize;
            pilot.extend(trace_pilot(self, pass, start..start + round, &seen));
        }
        let (photons, stats) = trace_chains(self, pass, &pilot, paths - pilot.paths as usize, &seen);
        (photons, pilot.stats + stats)
    }

    /// The fraction of pass 0's pilot paths that a visible point sees, and whether `auto` is
    /// settled at load by it: where it is `AUTO_VISIBLE_BELOW` or more, every pass draws its
    /// photons uniformly and traces no pilot.
    pub fn auto_at_load(&self) -> (f64, bool) {
        let pass = self.pass_samples(0);
        let (points, _) = self.trace_visible_points(&pass);
        let seen = PointGrid::new(visible_points(&points), pass.radius);
        let fraction =
            trace_pilot(self, &pass, 0..self.settings.photons_per_pass.div_ceil(PILOT_SHARE), &seen)
                .seen_fraction();
        (fraction, fraction >= AUTO_VISIBLE_BELOW)
    }

    /// Where photon paths are drawn by visibility and the film is a window of the image: the
    /// whole image's eye pass, whose visible points decide which paths are seen (so that a
    /// render region holds exactly the whole render's pixels). `None` otherwise.
    pub(crate) fn whole_image_points(&self, pass: &PassSamples) -> Option<Vec<EyeResult>> {
        let crop = self.settings.crop;
        if self.settings.photon_sampling == PhotonSampling::Uniform || crop == Crop::whole(crop.image) {
            return None;
        }
        let [width, height] = crop.image;
        let whole = PassSettings { crop: Crop::whole(crop.image), width, height, ..self.settings.clone() };
        Some(self.with_settings(whole).trace_visible_points(pass).0)
    }
}

/// The visible points of an eye pass's results, with their pixels.
pub fn visible_points(eyes: &[EyeResult]) -> impl Iterator<Item = (usize, glam::Vec3)> + '_ {
    eyes.iter().enumerate().filter_map(|(pixel, eye)| eye.point.map(|vp| (pixel, vp.p)))
}

/// The uniform photon paths `range` of `pass`, in order.
fn trace_uniform(
    renderer: &Renderer,
    pass: &PassSamples,
    range: std::ops::Range<usize>,
) -> (Vec<Photon>, PassStats) {
    let chunks: Vec<(Vec<Photon>, PassStats)> = crate::transport::emission::photon_chunks(range)
        .map(|paths| {
            let mut photons = Vec::with_capacity(paths.end as usize - paths.start as usize);
            let stats = paths.map(|k| trace_photon(renderer, pass, k, &mut photons)).sum();
            (photons, stats)
        })
        .collect();
    concatenate(chunks)
}

/// The chunks' photons in order, and their counts summed.
fn concatenate(chunks: Vec<(Vec<Photon>, PassStats)>) -> (Vec<Photon>, PassStats) {
    let stats = chunks.iter().map(|(_, s)| *s).sum();
    let mut photons = Vec::with_capacity(chunks.iter().map(|(p, _)| p.len()).sum());
    chunks.into_iter().for_each(|(p, _)| photons.extend(p));
    (photons, stats)
}

/// The pilot: a pass's first uniform paths, their photons, and which of them are seen.
pub(crate) struct Pilot {
    pub(crate) photons: Vec<Photon>,
    /// The indices of the paths seen, in order.
    seen_paths: Vec<u64>,
    /// How many paths the pilot traced.
    paths: u64,
    /// The paths of its first round, which count toward the normalisation, and how many of
    /// them are seen.
    counted_paths: u64,
    counted_seen: u64,
    stats: PassStats,
}

impl Pilot {
    fn empty() -> Self {
        Pilot {
            photons: Vec::new(),
            seen_paths: Vec::new(),
            paths: 0,
            counted_paths: 0,
            counted_seen: 0,
            stats: PassStats::default(),
        }
    }

    /// The fraction of the paths that count toward the normalisation (its first round's) that
    /// a visible point sees.
    pub(crate) fn seen_fraction(&self) -> f64 {
        self.counted_seen as f64 / self.counted_paths as f64
    }

    /// This pilot followed by `more` (the next paths, which do not count toward the
    /// normalisation).
    fn extend(&mut self, more: Pilot) {
        self.photons.extend(more.photons);
        self.seen_paths.extend(more.seen_paths);
        self.paths += more.paths;
        self.stats = self.stats + PassStats { pilot_paths: 0, pilot_paths_seen: 0, ..more.stats };
    }
}

/// The uniform paths `paths` of `pass` as a pilot.
pub(crate) fn trace_pilot(
    renderer: &Renderer,
    pass: &PassSamples,
    paths: std::ops::Range<usize>,
    seen: &PointGrid,
) -> Pilot {
    let count = (paths.end - paths.start) as u64;
    let chunks: Vec<Pilot> = crate::transport::emission::photon_chunks(paths)
        .map(|range| {
            let mut pilot = Pilot::empty();
            for k in range {
                let first = pilot.photons.len();
                pilot.stats = pilot.stats + trace_photon(renderer, pass, k, &mut pilot.photons);
                if pilot.photons[first..].iter().any(|p| seen.reaches(p.p)) {
                    pilot.seen_paths.push(k);
                }
            }
            pilot
        })
        .collect();
    let mut pilot = Pilot::empty();
    chunks.into_iter().for_each(|chunk| pilot.extend(chunk));
    pilot.paths = count;
    pilot.counted_paths = pilot.paths;
    pilot.counted_seen = pilot.seen_paths.len() as u64;
    pilot.stats.pilot_paths = pilot.paths;
    pilot.stats.pilot_paths_seen = pilot.counted_seen;
    pilot
}

/// A chain's current path: its primary sample, its photons, and for how many steps it has stood.
#[derive(Default)]
struct ChainState {
    values: Vec<f32>,
    photons: Vec<Photon>,
    steps: u32,
}

/// What a chain gives: the photons of its states, each weighted by the steps it stood; the
/// steps it spent on seen paths; its large steps and how many of them were seen.
#[derive(Default)]
struct ChainResult {
    photons: Vec<Photon>,
    seen_steps: u64,
    large_steps: u64,
    large_seen: u64,
    stats: PassStats,
}

impl ChainResult {
    /// Adds `state`'s photons, weighted by the steps it stood.
    fn keep(&mut self, state: &ChainState) {
        if state.steps == 0 {
            return;
        }
        let weight = state.steps as f32;
        self.photons.extend(state.photons.iter().map(|p| Photon { flux: p.flux * weight, ..*p }));
        self.seen_steps += u64::from(state.steps);
    }
}

/// `steps` steps of Markov chains over the seen paths of `pass`, started from the pilot's seen
/// paths, weighted to estimate the pass's photon flux with the normalisation from every uniform
/// path (the pilot's and the large steps).
fn trace_chains(
    renderer: &Renderer,
    pass: &PassSamples,
    pilot: &Pilot,
    steps: usize,
    seen: &PointGrid,
) -> (Vec<Photon>, PassStats) {
    let chains = steps.div_ceil(CHAIN_STEPS);
    let results: Vec<ChainResult> = (0..chains)
        .into_par_iter()
        .map(|c| {
            let chain_steps = CHAIN_STEPS.min(steps - c * CHAIN_STEPS);
            let start = (!pilot.seen_paths.is_empty())
                .then(|| pilot.seen_paths[c % pilot.seen_paths.len()])
                .map(|k| replay(renderer, pass, k));
            run_chain(renderer, pass, c as u64, chain_steps, start, seen)
        })
        .collect();
    let large: u64 = pilot.counted_paths + results.iter().map(|r| r.large_steps).sum::<u64>();
    let large_seen: u64 = pilot.counted_seen + results.iter().map(|r| r.large_seen).sum::<u64>();
    let seen_steps: u64 = results.iter().map(|r| r.seen_steps).sum();
    let mut stats: PassStats = results.iter().map(|r| r.stats).sum();
    stats.chain_steps = steps as u64;
    // Photon fluxes carry 1 / (photons per pass) from their emission; the chains' estimate is
    // V / (seen steps) per step.
    let scale = match seen_steps {
        0 => 0.0,
        _ => {
            (renderer.settings.photons_per_pass as f64 * large_seen as f64
                / (large as f64 * seen_steps as f64)) as f32
        }
    };
    let mut photons = Vec::with_capacity(results.iter().map(|r| r.photons.len()).sum());
    for result in results {
        photons.extend(result.photons.into_iter().map(|p| Photon { flux: p.flux * scale, ..p }));
    }
    (photons, stats)
}

/// Uniform path `k` of `pass` traced again, with the primary sample it draws.
fn replay(renderer: &Renderer, pass: &PassSamples, k: u64) -> ChainState {
    let mut fresh = photon_stream(renderer, pass, k);
    let mut state = ChainState::default();
    let proposal = Proposal { values: &mut state.values, base: None, rng: &mut fresh };
    trace_sample(renderer, pass, proposal, &mut state.photons);
    state
}

/// The coordinate of a photon path's primary sample that chooses its light (the first that
/// [`emit_photon`] reads; it chooses the light alone).
const LIGHT_CHOICE: usize = 0;

/// A proposed path's primary sample, drawn as the path reads it: new uniform numbers (a large
/// step), or the coordinates of `base` (the chain's current sample) each moved by a small step,
/// but for the light's choice, which a small step keeps (a move of it would mostly cross to
/// another light, among many lamps of a hall one whose path misses what the camera sees, and be
/// refused; leaving it is a symmetric proposal too, and large steps still reach every light).
/// Where the proposal reads past the end of `base`, `base` grows by a new uniform number first
/// and the proposal reads it moved: `base` keeps it whether or not the proposal is accepted, as
/// Kelemen et al.'s sampler keeps every coordinate it has made (drawing it anew at each proposal
/// instead would let what rejected proposals found of it be forgotten, and the chain would no
/// longer keep to its target).
struct Proposal<'a> {
    /// The numbers the path read (a buffer the chain reuses).
    values: &'a mut Vec<f32>,
    base: Option<&'a mut Vec<f32>>,
    rng: &'a mut Sampler,
}

impl Uniforms for Proposal<'_> {
    fn next_1d(&mut self) -> f32 {
        let u = match &mut self.base {
            None => self.rng.next_1d(),
            Some(base) => {
                let i = self.values.len();
                if i == base.len() {
                    base.push(self.rng.next_1d());
                }
                match i {
                    LIGHT_CHOICE => base[i],
                    _ => wrap_unit(base[i], small_move(self.rng)),
                }
            }
        };
        self.values.push(u);
        u
    }
}

/// Traces the path of `proposal` (whose numbers go into its buffer), appending its photons to
/// `photons`; gives the work done.
fn trace_sample(
    renderer: &Renderer,
    pass: &PassSamples,
    mut proposal: Proposal,
    photons: &mut Vec<Photon>,
) -> PassStats {
    match emit_photon(renderer, pass, &mut proposal) {
        Some((state, _)) => continue_photon(renderer, pass, state, photons, |_, _, _| {}),
        None => PassStats::default(),
    }
}

/// One chain of `steps` steps from `start` (or, without one, from its first seen large step).
fn run_chain(
    renderer: &Renderer,
    pass: &PassSamples,
    chain: u64,
    steps: usize,
    start: Option<ChainState>,
    seen: &PointGrid,
) -> ChainResult {
    let mut rng = stream(renderer.settings.seed, Stream::PhotonChain, pass.index, chain);
    let mut result = ChainResult::default();
    let mut current = start;
    // Each proposal is traced into `proposed`'s buffers; an accepted one becomes the current
    // state, and the state it ends lends its buffers to the next proposal.
    let mut proposed = ChainState::default();
    for _ in 0..steps {
        // A step is large by a coin that nothing else decides, and only those count toward the
        // normalisation: a chain without a path yet also searches by large steps, but their
        // number depends on what they find (stopping at a first success would bias it).
        let counted = rng.next_1d() < LARGE_STEP;
        let base = current.as_mut().filter(|_| !counted).map(|state| &mut state.values);
        proposed.values.clear();
        proposed.photons.clear();
        let proposal = Proposal { values: &mut proposed.values, base, rng: &mut rng };
        result.stats = result.stats + trace_sample(renderer, pass, proposal, &mut proposed.photons);
        let accepted = proposed.photons.iter().any(|p| seen.reaches(p.p));
        result.stats.chain_steps_seen += u64::from(accepted);
        if counted {
            result.large_steps += 1;
            result.large_seen += u64::from(accepted);
        }

        if accepted {
            proposed.steps = 1;
            let ended = current.replace(std::mem::take(&mut proposed));
            if let Some(state) = ended {
                result.keep(&state);
                proposed = state;
            }
        } else if let Some(state) = &mut current {
            state.steps += 1;
        }
    }
    if let Some(state) = current {
        result.keep(&state);
    }
    result
}

/// A small step's move of one coordinate: of either sign, its size spread evenly in log scale
/// between [`SMALLEST_MOVE`] and [`LARGEST_MOVE`] (Kelemen et al. 2002).
fn small_move(rng: &mut Sampler) -> f32 {
    let magnitude = LARGEST_MOVE * (-(LARGEST_MOVE / SMALLEST_MOVE).ln() * rng.next_1d()).exp();
    if rng.next_1d() < 0.5 {
        -magnitude
    } else {
        magnitude
    }
}
