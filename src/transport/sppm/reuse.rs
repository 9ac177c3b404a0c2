//! SPPM's pass shared by a block of frames (Weiss & Grosch 2012, "Stochastic Progressive Photon
//! Mapping for Dynamic Scenes"; docs/design.md, "Frames, and reuse across frames").
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
//! per frame. With shared eye paths, every pixel's estimate from all the shared photons (as if no
//! frame blocked any path) is made once per pass ([`FrameEstimates::Beside`]), and a frame
//! estimates only the pixels where it differs: those whose eye path its moving triangles change,
//! and those whose visible point lies within the radius of a photon it changes (a shared one its
//! moving triangles block, or one of the paths it resumed; found from the photons, through a grid
//! of the visible points). Elsewhere the frame has the same photons within the radius as all the
//! shared ones, so the common estimate is its own, up to the order of the sum. Where it differs,
//! the sum of every shared photon at the visible point is kept from the common estimate, and the
//! frame gathers only its changed photons there: the shared ones it does not keep, their flux
//! negated, and those it traced. A pixel gathers all its photons again only where its eye path
//! was resumed or a changed photon shows a wall that cuts its disc (walls can hide photons).

use std::ops::Range;
use std::sync::Arc;

use glam::Vec3;
use rayon::prelude::*;

use super::gather::{sum_over, FirstRound, PhotonSet, PhotonSums};
use super::photons::{continue_photon, trace_photon, Photon};
use super::visible::{continue_eye_path, trace_eye_path, with_direct, EyeEnd, EyeEvent, EyeResult};
use crate::spectrum::SampledSpectrum;
use crate::transport::context::{collect_counting, PassSamples, PassStats, PixelEstimate, Renderer};
use crate::transport::emission::{photon_chunks, start_photon, PhotonState};
use crate::transport::eye::{start_eye_path, EyeState};
use crate::transport::points::{PixelMarks, PointGrid};
use crate::transport::reuse::{FrameEstimates, SharedPassOutput, Swept};
use crate::transport::shadow::ShadowRay;

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
    /// Its first round over the common photons.
    common_round: FirstRound,
    /// The open edges' cut of its visible point's disc, where the common photons asked for it.
    edge_cut: Option<Vec3>,
    /// What every shared photon adds up to at its visible point, where frames share estimates
    /// and those photons show no wall the point lies behind.
    beside: Option<PhotonSums>,
}

/// Eye paths traced once for every frame, and what their gathers share.
struct SharedEyes {
    records: Vec<EyeRecord>,
    /// The pixels whose path or direct light meets the swept box (frames test those), in order.
    watched: Vec<u32>,
    /// Each pixel's estimate from every shared photon, and its visible points bucketed by
    /// position; when frames share estimates (their surfaces' open edges are the same).
    common: Option<(Vec<PixelEstimate>, PointGrid)>,
}

impl Renderer<'_> {
    /// SPPM's pass for a block of frames, this renderer holding their static triangles (see
    /// [`crate::transport::run_shared_pass`]).
    pub(in crate::transport) fn run_shared_sppm_pass(
        &self,
        frames: &[Renderer],
        pass: &PassSamples,
        share_eyes: bool,
        consume: &mut dyn FnMut(SharedPassOutput),
    ) -> (PassStats, std::time::Duration) {
        let statics = self;
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
        let unstable_set =
            PhotonSet::new(&unstable_photons(&shared, &always_valid), pass.radius, &statics.scene.open_edges);
        let same_edges = frames.iter().all(|f| Arc::ptr_eq(&f.scene.open_edges, &statics.scene.open_edges));
        let eyes = share_eyes.then(|| {
            let (eyes, eye_stats) =
                trace_shared_eyes(statics, pass, swept, [&common_set, &unstable_set], same_edges);
            stats = stats + eye_stats;
            eyes
        });
        let shared_time = start.elapsed();
        for (index, (frame, (photons, photon_stats))) in frames.iter().zip(&checked).enumerate() {
            let own = own_photons(&shared, &always_valid, photons);
            let own_set = PhotonSet::new(&own, pass.radius, &frame.scene.open_edges);
            let sets = GatherSets { common: &common_set, own: &own_set };
            let (estimates, eye_stats) = match &eyes {
                Some(eyes) => match &eyes.common {
                    Some((common, points)) => {
                        let changed = changed_photons(&shared, photons);
                        let (differing, s) = differing_estimates(frame, pass, eyes, points, sets, &changed);
                        (FrameEstimates::Beside { common, differing }, s)
                    }
                    None => {
                        let pixels = eyes.records.len();
                        let (estimates, s) = collect_counting(pixels, |pixel| {
                            let (change, s) = frame_eye(frame, pass, &eyes.records[pixel]);
                            (sets.estimate(eyes, pixel, &change), s)
                        });
                        (FrameEstimates::Every(estimates), s)
                    }
                },
                None => {
                    let pixels = (frame.settings.width * frame.settings.height) as usize;
                    let (estimates, s) = collect_counting(pixels, |pixel| {
                        let (eye, s) = trace_eye_path(frame, pass, pixel);
                        (sets.estimate_with(&eye, None), s)
                    });
                    (FrameEstimates::Every(estimates), s)
                }
            };
            let frame_stats = *photon_stats + eye_stats;
            consume(SharedPassOutput { frame: index, estimates, stats: frame_stats });
        }
        (stats, shared_time)
    }
}

/// The photon sets a frame gathers from: the common photons and its own.
#[derive(Clone, Copy)]
struct GatherSets<'a> {
    common: &'a PhotonSet,
    own: &'a PhotonSet,
}

impl GatherSets<'_> {
    /// The estimate of pixel `pixel` of a shared eye pass, as its path changed in the frame.
    fn estimate(self, eyes: &SharedEyes, pixel: usize, change: &EyeChange) -> PixelEstimate {
        let record = &eyes.records[pixel];
        match change {
            EyeChange::Same => self.estimate_with(&record.end.result, Some(record)),
            EyeChange::Direct(eye) => self.estimate_with(eye, Some(record)),
            EyeChange::Resumed(eye) => self.estimate_with(eye, None),
        }
    }

    /// The estimate of an eye path, whose visible point is that of `shared` when given (its
    /// first round over the common photons and its edges' cut are then known).
    fn estimate_with(self, eye: &EyeResult, shared: Option<&EyeRecord>) -> PixelEstimate {
        let sums = eye.point.map_or(PhotonSums::default(), |vp| {
            let common_round = shared.map_or_else(|| self.common.first_round(&vp), |r| r.common_round);
            sum_over(&vp, &[(self.common, common_round), (self.own, self.own.first_round(&vp))])
        });
        let edge_cut = shared.and_then(|r| r.edge_cut);
        self.own.estimate_cut(eye, sums, |vp| edge_cut.unwrap_or_else(|| self.own.edge_cut(vp)))
    }
}

/// A frame's estimates at the pixels where they differ from the common ones: those whose
/// watched path its moving triangles change, and those whose visible point its `changed`
/// photons reach, in pixel order. Where every shared photon's sums at a visible point are
/// known, the frame's are those changed by its photons there; elsewhere (a changed photon on a
/// wall, a path resumed) the pixel gathers its own.
fn differing_estimates(
    frame: &Renderer,
    pass: &PassSamples,
    eyes: &SharedEyes,
    points: &PointGrid,
    sets: GatherSets,
    changed: &[Photon],
) -> (Vec<(u32, PixelEstimate)>, PassStats) {
    let (changes, stats) = collect_counting(eyes.watched.len(), |i| {
        frame_eye(frame, pass, &eyes.records[eyes.watched[i] as usize])
    });
    let marks = PixelMarks::new(eyes.records.len());
    for (&pixel, change) in eyes.watched.iter().zip(&changes) {
        if !matches!(change, EyeChange::Same) {
            marks.mark(pixel);
        }
    }
    points.mark_near(changed, |photon| photon.p, &marks);
    let change = |pixel: u32| match eyes.watched.binary_search(&pixel) {
        Ok(i) => &changes[i],
        Err(_) => &EyeChange::Same,
    };
    let changed = PhotonSet::new(changed, pass.radius, &frame.scene.open_edges);
    let estimates = marks
        .marked()
        .into_par_iter()
        .with_min_len(64)
        .map(|pixel| {
            let (record, change) = (&eyes.records[pixel as usize], change(pixel));
            let estimate = changed_estimate(&changed, record, change)
                .unwrap_or_else(|| sets.estimate(eyes, pixel as usize, change));
            (pixel, estimate)
        })
        .collect();
    (estimates, stats)
}

/// A pixel's estimate from what every shared photon adds up to at its visible point changed by
/// a frame's `changed` photons, as its eye path changed; `None` where that sum is not known,
/// the eye path was resumed, or a changed photon shows a wall.
fn changed_estimate(changed: &PhotonSet, record: &EyeRecord, change: &EyeChange) -> Option<PixelEstimate> {
    let eye = match change {
        EyeChange::Same => &record.end.result,
        EyeChange::Direct(eye) => eye,
        EyeChange::Resumed(_) => return None,
    };
    let sums = changed.sums_changed(eye.point.as_ref()?, record.beside?)?;
    let edge_cut = |vp: &_| record.edge_cut.unwrap_or_else(|| changed.edge_cut(vp));
    Some(changed.estimate_cut(eye, sums, edge_cut))
}

/// Where a frame's photons differ from all the shared ones: the shared photons it does not
/// keep, with their flux negated, then the photons of the paths it traced itself.
fn changed_photons(shared: &SharedPhotons, frame: &FramePhotons) -> Vec<Photon> {
    let mut photons = record_photons(shared, |r, record| frame.valid[r]..record.photons.len(), |_| &[]);
    for photon in &mut photons {
        photon.flux = -photon.flux;
    }
    photons.extend(frame.own.iter().flatten());
    photons
}

/// Traces every photon path of `pass` against the static triangles, keeping the segments that
/// meet the swept box.
fn trace_shared_photons(statics: &Renderer, pass: &PassSamples, swept: Swept) -> (SharedPhotons, PassStats) {
    let chunks: Vec<(SharedPhotons, PassStats)> = photon_chunks(0..statics.settings.photons_per_pass)
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
    record_photons(shared, |r, _| always_valid[r]..frame.valid[r], |r| &frame.own[r])
}

/// The shared photons some frame of the block does not keep.
fn unstable_photons(shared: &SharedPhotons, always_valid: &[usize]) -> Vec<Photon> {
    record_photons(shared, |r, record| always_valid[r]..record.photons.len(), |_| &[])
}

/// For each record `r` of a path some frame may change, its shared photons `kept(r)` (counted
/// along the path), then `traced(r)`.
fn record_photons<'a>(
    shared: &SharedPhotons,
    kept: impl Fn(usize, &PathRecord) -> Range<usize>,
    traced: impl Fn(usize) -> &'a [Photon],
) -> Vec<Photon> {
    let mut photons = Vec::new();
    for (r, record) in shared.records.iter().enumerate() {
        let Range { start, end } = kept(r, record);
        photons.extend_from_slice(&shared.photons[record.photons.start + start..record.photons.start + end]);
        photons.extend_from_slice(traced(r));
    }
    photons
}

/// Traces every pixel's eye path against the static triangles, keeping what the frames check,
/// and gathers the common photons at each; with `common estimates`, finishes every pixel's
/// estimate from all the shared photons (the common and the `unstable` ones, which some frame
/// does not keep) and buckets the visible points.
fn trace_shared_eyes(
    statics: &Renderer,
    pass: &PassSamples,
    swept: Swept,
    [common_set, unstable_set]: [&PhotonSet; 2],
    common_estimates: bool,
) -> (SharedEyes, PassStats) {
    let pixels = (statics.settings.width * statics.settings.height) as usize;
    let (mut records, stats) = collect_counting(pixels, |pixel| {
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
        let common_round = end.result.point.map_or(FirstRound::default(), |vp| common_set.first_round(&vp));
        let record = EyeRecord { end, watched, direct_watched, common_round, edge_cut: None, beside: None };
        (record, start_stats + stats)
    });
    let watched = (0..records.len() as u32)
        .filter(|&p| {
            let r = &records[p as usize];
            !r.watched.is_empty() || r.direct_watched.contains(&true)
        })
        .collect();
    let common = common_estimates.then(|| {
        let estimates = records
            .par_iter_mut()
            .with_min_len(64)
            .map(|r| {
                let eye = &r.end.result;
                let sums = eye.point.map_or(PhotonSums::default(), |vp| {
                    let rounds =
                        [(common_set, r.common_round), (unstable_set, unstable_set.first_round(&vp))];
                    let sums = sum_over(&vp, &rounds);
                    r.beside = rounds.iter().all(|(_, round)| !round.behind_a_wall()).then_some(sums);
                    sums
                });
                common_set.estimate_cut(eye, sums, |vp| *r.edge_cut.insert(common_set.edge_cut(vp)))
            })
            .collect();
        let points =
            records.iter().enumerate().filter_map(|(pixel, r)| r.end.result.point.map(|vp| (pixel, vp.p)));
        (estimates, PointGrid::new(points, pass.radius))
    });
    (SharedEyes { records, watched, common }, stats)
}

/// How a frame's moving triangles change a shared eye path.
enum EyeChange {
    /// Not at all.
    Same,
    /// They block some of the direct light at its visible point.
    Direct(EyeResult),
    /// They block it: the frame resumed it, and its visible point is its own.
    Resumed(EyeResult),
}

/// How `frame`'s moving triangles change a shared eye path, and the tests that took.
fn frame_eye(frame: &Renderer, pass: &PassSamples, record: &EyeRecord) -> (EyeChange, PassStats) {
    let mut stats = PassStats::default();
    for w in &record.watched {
        stats.moving_tests += 1;
        if frame.accel.moving_occluded(w.ray.origin, w.ray.direction, w.ray.t_max) {
            let (end, resumed) = continue_eye_path(frame, pass, w.state.clone(), |_| {});
            return (EyeChange::Resumed(end.result), stats + resumed);
        }
    }
    let end = &record.end;
    let Some(vp) = end.result.point else {
        return (EyeChange::Same, stats);
    };
    let blocked = [0, 1].map(|i| {
        record.direct_watched[i]
            && end.direct[i].ray.is_some_and(|r| {
                stats.moving_tests += 1;
                frame.accel.moving_occluded(r.origin, r.direction, r.t_max)
            })
    });
    if blocked == [false; 2] {
        return (EyeChange::Same, stats);
    }
    let values = [0, 1].map(|i| if blocked[i] { SampledSpectrum::ZERO } else { end.direct[i].value });
    let radiance = with_direct(end.radiance_before, vp.beta, values);
    (EyeChange::Direct(EyeResult { radiance, ..end.result }), stats)
}
