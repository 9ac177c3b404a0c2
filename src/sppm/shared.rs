//! One pass shared by a block of frames (Weiss & Grosch 2012, "Stochastic Progressive Photon
//! Mapping for Dynamic Scenes"; DESIGN.md, "Frames, and reuse across frames").
//!
//! Every frame of the block renders the same pass: the same wavelengths, shutter point, radius
//! and random streams. Paths are traced once against the static triangles, and every segment
//! that meets the box the moving triangles fill this pass (in any frame) is kept with the path's
//! state there. Each frame tests only those segments against its own moving triangles: a path
//! nothing blocks is the frame's as it is; a blocked one is resumed from its first blocked
//! segment in the frame's full scene, drawing the random numbers it would have drawn. So every
//! frame gets exactly the paths a render of that frame alone traces, and the same expected value
//! and variance. Photons valid in every frame are bucketed and gathered once per pass; each frame
//! gathers only its own difference.
//!
//! Eye paths are shared the same way when the camera and the lights stand still; otherwise each
//! frame traces its own (photons are still shared). Photon paths from moving lights are traced
//! per frame.

use std::ops::Range;

use glam::Vec3;
use rayon::prelude::*;

use super::direct::ShadowRay;
use super::gather::{sum_over, FirstRound, PhotonSet, PhotonSums};
use super::photons::{continue_photon, photon_chunks, start_photon, trace_photon, Photon, PhotonState};
use super::renderer::{collect_counting, PassSamples, PassStats, PixelEstimate, Renderer};
use super::visible::{
    continue_eye_path, start_eye_path, trace_eye_path, with_direct, EyeEnd, EyeEvent, EyeResult, EyeState,
};
use crate::geometry::ray_meets_box;
use crate::spectrum::SampledSpectrum;

/// The box every frame's moving triangles lie in this pass, grown a little for rounding.
#[derive(Clone, Copy)]
struct Swept(Option<(Vec3, Vec3)>);

impl Swept {
    fn of(frames: &[Renderer]) -> Self {
        let union = frames
            .iter()
            .filter_map(|r| r.accel.moving_bounds())
            .reduce(|(a, b), (c, d)| (a.min(c), b.max(d)));
        Swept(union.map(|(lo, hi)| {
            let margin = (hi - lo).length() * 1e-4 + lo.abs().max(hi.abs()).max_element() * 1e-6;
            (lo - Vec3::splat(margin), hi + Vec3::splat(margin))
        }))
    }

    /// Whether the ray could meet a moving triangle in some frame.
    fn meets(self, ray: ShadowRay) -> bool {
        self.0.is_some_and(|b| ray_meets_box(ray.origin, ray.direction, ray.t_max, b))
    }
}

/// A segment of a shared path that meets the swept box.
struct Watched<S> {
    /// The path's state where a frame whose moving triangles block `ray` resumes it: as the
    /// segment starts (or, for a shadow ray of direct light on the way, as the path starts).
    state: S,
    /// The segment, to the static triangle it hit (infinite when it left the scene), or the
    /// shadow ray.
    ray: ShadowRay,
    /// Photons the path had stored before it.
    stored_before: usize,
}

/// A photon path some frame may change.
struct PathRecord {
    /// Its index in the pass.
    path: u64,
    /// Its photons in the shared list.
    photons: Range<usize>,
    /// Its segments that meet the swept box, in order.
    watched: Vec<Watched<PhotonState>>,
    /// It leaves a moving light: every frame traces it itself.
    from_moving_light: bool,
}

/// Photon paths traced against the static triangles.
struct SharedPhotons {
    photons: Vec<Photon>,
    /// The paths some frame may change, in path order.
    records: Vec<PathRecord>,
}

/// One frame's photons beside the shared ones: per record, how many shared photons stay valid
/// and what the frame traced itself.
struct FramePhotons {
    valid: Vec<usize>,
    own: Vec<Vec<Photon>>,
}

/// A pixel's eye path traced against the static triangles.
struct EyeRecord {
    end: EyeEnd,
    watched: Vec<Watched<EyeState>>,
    /// Which direct-light rays meet the swept box.
    direct_watched: [bool; 2],
}

/// What [`run_shared_pass`] hands each frame: its pixel estimates and the work it did itself.
pub struct SharedPassOutput {
    /// The frame's index in the block.
    pub frame: usize,
    /// Its pixel estimates, row-major.
    pub estimates: Vec<PixelEstimate>,
    /// Tests against its moving triangles and the paths resumed in it.
    pub stats: PassStats,
}

/// Renders `pass` for every frame of `frames` (each posed at its own time for this pass, all
/// choosing lights as `statics` does), sharing what they can through `statics`: the same scene
/// with the static triangles alone. `share_eyes` when neither the camera nor a light moves.
/// Hands each frame's estimates to `consume` in frame order; returns the work done once and the
/// time it took (before any frame's own work).
pub fn run_shared_pass(
    statics: &Renderer,
    frames: &[Renderer],
    pass: &PassSamples,
    share_eyes: bool,
    mut consume: impl FnMut(SharedPassOutput),
) -> (PassStats, std::time::Duration) {
    let start = std::time::Instant::now();
    let swept = Swept::of(frames);
    let (shared, mut stats) = trace_shared_photons(statics, pass, swept);
    let checked: Vec<(FramePhotons, PassStats)> =
        frames.iter().map(|frame| check_photons(frame, pass, &shared)).collect();
    let always_valid: Vec<usize> = (0..shared.records.len())
        .map(|r| checked.iter().map(|(f, _)| f.valid[r]).min().unwrap_or(0))
        .collect();
    let common = common_photons(&shared, &always_valid);
    let common_set = PhotonSet::new(&common, pass.radius, &statics.scene.open_edges);
    let eyes = share_eyes.then(|| trace_shared_eyes(statics, pass, swept));
    let common_first_round =
        |eye: &EyeResult| eye.point.map_or(FirstRound::default(), |vp| common_set.first_round(&vp));
    let common_rounds: Vec<FirstRound> = match &eyes {
        Some((records, eye_stats)) => {
            stats = stats + *eye_stats;
            records.par_iter().with_min_len(64).map(|r| common_first_round(&r.end.result)).collect()
        }
        None => Vec::new(),
    };
    let shared_time = start.elapsed();
    for (index, (frame, (photons, photon_stats))) in frames.iter().zip(&checked).enumerate() {
        let own = own_photons(&shared, &always_valid, photons);
        let own_set = PhotonSet::new(&own, pass.radius, &frame.scene.open_edges);
        let pixels = (frame.settings.width * frame.settings.height) as usize;
        let (estimates, eye_stats) = collect_counting(pixels, |pixel| {
            let (eye, common_round, eye_stats) = match &eyes {
                Some((records, _)) => match frame_eye(frame, pass, &records[pixel]) {
                    (eye, false, s) => (eye, common_rounds[pixel], s),
                    (eye, true, s) => {
                        let round = common_first_round(&eye);
                        (eye, round, s)
                    }
                },
                None => {
                    let (eye, s) = trace_eye_path(frame, pass, pixel);
                    let round = common_first_round(&eye);
                    (eye, round, s)
                }
            };
            let sums = eye.point.map_or(PhotonSums::default(), |vp| {
                sum_over(&vp, &[(&common_set, common_round), (&own_set, own_set.first_round(&vp))])
            });
            (own_set.estimate(&eye, sums), eye_stats)
        });
        let frame_stats = *photon_stats + eye_stats;
        consume(SharedPassOutput { frame: index, estimates, stats: frame_stats });
    }
    (stats, shared_time)
}

/// Traces every photon path of `pass` against the static triangles, keeping the segments that
/// meet the swept box.
fn trace_shared_photons(statics: &Renderer, pass: &PassSamples, swept: Swept) -> (SharedPhotons, PassStats) {
    let chunks: Vec<(SharedPhotons, PassStats)> = photon_chunks(statics.settings.photons_per_pass)
        .map(|paths| {
            let mut traced = SharedPhotons { photons: Vec::new(), records: Vec::new() };
            let stats = paths.map(|path| trace_shared_photon(statics, pass, path, swept, &mut traced)).sum();
            (traced, stats)
        })
        .collect();
    let mut shared = SharedPhotons { photons: Vec::new(), records: Vec::new() };
    let mut stats = PassStats::default();
    for (traced, chunk_stats) in chunks {
        let offset = shared.photons.len();
        shared.records.extend(
            traced
                .records
                .into_iter()
                .map(|r| PathRecord { photons: r.photons.start + offset..r.photons.end + offset, ..r }),
        );
        shared.photons.extend(traced.photons);
        stats = stats + chunk_stats;
    }
    (shared, stats)
}

/// Traces photon path `path` against the static triangles into `traced`.
fn trace_shared_photon(
    statics: &Renderer,
    pass: &PassSamples,
    path: u64,
    swept: Swept,
    traced: &mut SharedPhotons,
) -> PassStats {
    let Some((state, light)) = start_photon(statics, pass, path) else {
        return PassStats::default();
    };
    let start = traced.photons.len();
    if statics.scene.moving_lights.contains(&light) {
        let photons = start..start;
        traced.records.push(PathRecord { path, photons, watched: Vec::new(), from_moving_light: true });
        return PassStats::default();
    }
    let mut watched = Vec::new();
    let stats = continue_photon(statics, pass, state, &mut traced.photons, |state, t_hit, stored_before| {
        let ray = ShadowRay { origin: state.origin.into(), direction: state.direction.into(), t_max: t_hit };
        if swept.meets(ray) {
            watched.push(Watched { state: state.clone(), ray, stored_before });
        }
    });
    if !watched.is_empty() {
        let photons = start..traced.photons.len();
        traced.records.push(PathRecord { path, photons, watched, from_moving_light: false });
    }
    stats
}

/// Tests the shared paths against `frame`'s moving triangles and resumes the blocked ones.
fn check_photons(frame: &Renderer, pass: &PassSamples, shared: &SharedPhotons) -> (FramePhotons, PassStats) {
    let checked: Vec<(usize, Vec<Photon>, PassStats)> = shared
        .records
        .par_iter()
        .with_min_len(16)
        .map(|record| {
            let mut own = Vec::new();
            if record.from_moving_light {
                let stats = trace_photon(frame, pass, record.path, &mut own);
                return (0, own, stats);
            }
            let mut stats = PassStats::default();
            for w in &record.watched {
                stats.moving_tests += 1;
                if frame.accel.moving_occluded(w.ray.origin, w.ray.direction, w.ray.t_max) {
                    stats = stats + continue_photon(frame, pass, w.state.clone(), &mut own, |_, _, _| {});
                    return (w.stored_before, own, stats);
                }
            }
            (record.photons.len(), own, stats)
        })
        .collect();
    let stats = checked.iter().map(|(_, _, s)| *s).sum();
    let (valid, own) = checked.into_iter().map(|(v, o, _)| (v, o)).unzip();
    (FramePhotons { valid, own }, stats)
}

/// The shared photons every frame of the block keeps.
fn common_photons(shared: &SharedPhotons, always_valid: &[usize]) -> Vec<Photon> {
    let mut common = Vec::with_capacity(shared.photons.len());
    let mut next = 0;
    for (record, &valid) in shared.records.iter().zip(always_valid) {
        common.extend_from_slice(&shared.photons[next..record.photons.start + valid]);
        next = record.photons.end;
    }
    common.extend_from_slice(&shared.photons[next..]);
    common
}

/// A frame's photons beyond the common ones: shared photons it keeps that some other frame
/// does not, and the photons of the paths it traced itself.
fn own_photons(shared: &SharedPhotons, always_valid: &[usize], frame: &FramePhotons) -> Vec<Photon> {
    let mut own = Vec::new();
    for (r, record) in shared.records.iter().enumerate() {
        let start = record.photons.start;
        own.extend_from_slice(&shared.photons[start + always_valid[r]..start + frame.valid[r]]);
        own.extend_from_slice(&frame.own[r]);
    }
    own
}

/// Traces every pixel's eye path against the static triangles, keeping what the frames check.
fn trace_shared_eyes(statics: &Renderer, pass: &PassSamples, swept: Swept) -> (Vec<EyeRecord>, PassStats) {
    let pixels = (statics.settings.width * statics.settings.height) as usize;
    let records: Vec<(EyeRecord, PassStats)> = (0..pixels)
        .into_par_iter()
        .with_min_len(64)
        .map(|pixel| {
            let (state, start_stats) = start_eye_path(statics, pass, pixel);
            let start = state.clone();
            let mut watched = Vec::new();
            let (end, stats) = continue_eye_path(statics, pass, state, |event| {
                let (state, ray) = match event {
                    EyeEvent::Segment(state, t_hit) => (
                        state,
                        ShadowRay {
                            origin: state.origin.into(),
                            direction: state.direction.into(),
                            t_max: t_hit,
                        },
                    ),
                    EyeEvent::Shadow(ray) => (&start, ray),
                };
                if swept.meets(ray) {
                    watched.push(Watched { state: state.clone(), ray, stored_before: 0 });
                }
            });
            let direct_watched = end.direct.map(|t| t.ray.is_some_and(|r| swept.meets(r)));
            (EyeRecord { end, watched, direct_watched }, start_stats + stats)
        })
        .collect();
    let stats = records.iter().map(|(_, s)| *s).sum();
    (records.into_iter().map(|(r, _)| r).collect(), stats)
}

/// A shared eye path as `frame` sees it, and whether the frame had to resume it (its visible
/// point is then its own).
fn frame_eye(frame: &Renderer, pass: &PassSamples, record: &EyeRecord) -> (EyeResult, bool, PassStats) {
    let mut stats = PassStats::default();
    for w in &record.watched {
        stats.moving_tests += 1;
        if frame.accel.moving_occluded(w.ray.origin, w.ray.direction, w.ray.t_max) {
            let (end, resumed) = continue_eye_path(frame, pass, w.state.clone(), |_| {});
            return (end.result, true, stats + resumed);
        }
    }
    let end = &record.end;
    let Some(vp) = end.result.point else {
        return (end.result, false, stats);
    };
    let values = [0, 1].map(|i| {
        let term = end.direct[i];
        let blocked = record.direct_watched[i]
            && term.ray.is_some_and(|r| {
                stats.moving_tests += 1;
                frame.accel.moving_occluded(r.origin, r.direction, r.t_max)
            });
        if blocked {
            SampledSpectrum::ZERO
        } else {
            term.value
        }
    });
    let radiance = with_direct(end.radiance_before, vp.beta, values);
    (EyeResult { radiance, ..end.result }, false, stats)
}
