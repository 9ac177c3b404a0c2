//! Light vertices bucketed for merging at camera vertices within the pass radius, weighed by the
//! gather's biweight kernel (its Laplacian too, for the error bound's bias term). Where the disc
//! reaches past the end of the camera vertex's surface (a room's corners, a table's edge), the sum
//! is divided by the kernel mass left on the surface, as the gather divides it: the ends are found
//! from light vertices on surfaces meeting the camera vertex's, and from the scene's open edges.

use glam::Vec3;
use rayon::prelude::*;
use std::f32::consts::FRAC_1_PI;

use super::light_paths::{joined, LightVertex};
use super::mis::{merging, LightPartials, MergeVertex, Partials, PassWeights};
use crate::materials::{Bsdf, ShadingFrame};
use crate::scene::OpenEdges;
use crate::spectrum::SampledSpectrum;
use crate::transport::grid::PhotonGrid;
use crate::transport::grid::{bucketed, Positions};
use crate::transport::kernel::{kernel_mass_within, Kernel, Wall, EDGE_COSINE};
use crate::transport::media::Media;

/// What merging reads of a light vertex within reach, besides its position.
#[derive(Clone, Copy, Debug)]
struct Arrival {
    wi: Vec3,
    ng: Vec3,
    throughput: SampledSpectrum,
    hero_only: bool,
    partials: LightPartials,
    segments: u32,
    /// The index of its path in the pass.
    path: u32,
}

impl Arrival {
    /// What merging reads of light vertex `v` of path `path`.
    fn of(path: u32, v: &LightVertex) -> Self {
        let ng = v.lobe.frame.ng();
        Arrival {
            wi: v.wo,
            ng: if ng.dot(v.wo) < 0.0 { -ng } else { ng },
            throughput: v.throughput,
            hero_only: v.hero_only,
            partials: v.partials,
            segments: v.segments,
            path,
        }
    }
}

/// The pass's light vertices, sorted by grid bucket, their positions kept apart (most of those in
/// the cells around a point are out of reach: the distance test reads only their positions).
pub struct MergeSet {
    sorted: Vec<Arrival>,
    positions: Positions,
    grid: PhotonGrid,
    kernel: Kernel,
}

/// A camera vertex merging: where it is, its lobe, its way back, its sums and path so far.
pub struct CameraVertex<'a> {
    /// Position.
    pub p: Vec3,
    /// Unit direction back along the camera path.
    pub wo: Vec3,
    /// Normals.
    pub frame: ShadingFrame,
    /// The BSDF.
    pub bsdf: &'a Bsdf,
    /// Throughput from the camera.
    pub beta: SampledSpectrum,
    /// The camera path carries its hero wavelength alone.
    pub hero_only: bool,
    /// MIS sums at the vertex.
    pub partials: Partials,
    /// Segments from the camera.
    pub segments: u32,
    /// Where it lies against the vertex its path merges at.
    pub merging: MergeVertex,
    /// The volumes the camera path arrived in, and the material of the surface (for what a
    /// segment leaving the vertex runs through).
    pub media: (Media, u32),
}

impl MergeSet {
    /// The light vertices of `vertices` (each with the index of its path) for merging within
    /// `radius`: those a segment or more past
    /// their light's first vertex (direct light is not merged). Built in parallel, the vertices kept in their order (the same bits with any
    /// thread count).
    pub fn new<'a>(vertices: impl ParallelIterator<Item = (u32, &'a LightVertex)>, radius: f32) -> Self {
        let vertices: Vec<(u32, &LightVertex)> = vertices.filter(|(_, v)| v.segments > 1).collect();
        let (grid, sorted, positions) =
            bucketed(&vertices, radius, |(_, v)| v.p, |&(path, v)| Arrival::of(path, v));
        MergeSet { sorted, positions, grid, kernel: Kernel::new(radius) }
    }

    /// Adds what merging finds at `camera` among this set's light vertices to `found`, leaving
    /// out those of the paths `excluded` (increasing).
    fn gather(
        &self,
        (weights, excluded): (&PassWeights, &[u32]),
        camera: &CameraVertex,
        max_segments: u32,
        found: &mut Merged,
    ) {
        let ng = camera.frame.ng();
        let front = if ng.dot(camera.wo) < 0.0 { -ng } else { ng };
        let shading = Shading::of(camera);
        let r2 = self.kernel.r2;
        self.grid.for_each_near(camera.p, |range| {
            self.positions.for_each_within(range, camera.p, r2, |i, d2| {
                let light = &self.sorted[i];
                if !excluded.is_empty() && excluded.binary_search(&light.path).is_ok() {
                    return;
                }
                found.reached = true;
                let facing = light.ng.dot(front);
                if facing < EDGE_COSINE {
                    if facing > -EDGE_COSINE {
                        let wall = self.kernel.wall(light.ng, self.positions.at(i), camera.p, ng);
                        Wall::keep_widest(&mut found.walls, wall, light.ng);
                        found.cut = true;
                    }
                    return;
                }
                if light.segments + camera.segments > max_segments {
                    return;
                }
                let Some((f, forward, reverse)) = shading.toward(camera, light.wi) else { return };
                let light_partials = match camera.merging {
                    // Light vertices before a gathering vertex do not merge.
                    MergeVertex::Here => &light.partials.none,
                    _ => &light.partials.last,
                };
                let weight = merging(weights, light_partials, &camera.partials, forward, reverse);
                let value =
                    joined(camera.beta, camera.hero_only, light.throughput, light.hero_only) * f * weight;
                if !value.is_finite() {
                    return;
                }
                let t2 = d2 / r2;
                found.sum += value * ((1.0 - t2) * (1.0 - t2));
                found.laplacian += value * (1.0 - 2.0 * t2);
            });
        });
    }
}

/// What merging at a camera vertex has found so far: the kernel-weighted sum, the same with the
/// kernel's Laplacian, and the walls that cut the disc.
#[derive(Default)]
struct Merged {
    sum: SampledSpectrum,
    laplacian: SampledSpectrum,
    walls: [Wall; 3],
    /// Whether a vertex within the disc lay on a surface that cuts it.
    cut: bool,
    /// Whether any vertex lay within the disc.
    reached: bool,
}

/// What merging at a camera vertex finds: the weighted radiance (times the vertex's throughput),
/// the same with the kernel's Laplacian, and the kernel mass its disc keeps on the surface (what
/// the radiance was divided by), where it was found.
pub struct Merge {
    pub radiance: SampledSpectrum,
    pub laplacian: SampledSpectrum,
    pub mass: Option<f32>,
}

/// What merging finds at `camera` among the light vertices of `sets` (one pass's, all of the same
/// radius, each without the vertices of the paths it lists) in a scene whose surfaces end at
/// `open_edges`, for paths of at most `max_segments`; the kernel mass is found where the radiance
/// is not zero, or where `with_mass`. Light vertices on surfaces facing more away than the
/// gather's `EDGE_COSINE` are not merged: they lie on a surface meeting the camera vertex's at an
/// edge (a wall, seen from the floor), whose plane cuts the disc, or on the other face of a thin
/// one.
pub fn merge(
    sets: &[(&MergeSet, &[u32])],
    (open_edges, with_mass): (&OpenEdges, bool),
    weights: &PassWeights,
    camera: &CameraVertex,
    max_segments: u32,
) -> Merge {
    let Some((first, _)) = sets.first() else {
        return Merge { radiance: SampledSpectrum::ZERO, laplacian: SampledSpectrum::ZERO, mass: None };
    };
    let mut found = Merged::default();
    for (set, excluded) in sets {
        set.gather((weights, excluded), camera, max_segments, &mut found);
    }
    let Merged { mut sum, laplacian, walls, .. } = found;
    let kernel = &first.kernel;
    let per_path = 1.0 / weights.light_paths;
    let mut mass = None;
    if sum != SampledSpectrum::ZERO || with_mass {
        let cut = Wall::cut(&walls).max(kernel.open_edge_cut(open_edges, camera.p, camera.frame.ng()));
        let kept = kernel_mass_within(cut);
        if sum != SampledSpectrum::ZERO {
            sum /= kept;
        }
        mass = Some(kept);
    }
    Merge {
        radiance: sum * (kernel.scale * per_path),
        laplacian: laplacian * (kernel.laplacian_scale * per_path),
        mass,
    }
}

/// A camera vertex where a path merged, kept for the frames of a block (reuse across frames):
/// the vertex, its BSDF, what its estimates count for, and the kernel mass its disc kept.
#[derive(Clone, Copy)]
pub struct KeptMerge {
    p: Vec3,
    wo: Vec3,
    frame: ShadingFrame,
    bsdf: Bsdf,
    beta: SampledSpectrum,
    hero_only: bool,
    partials: Partials,
    segments: u32,
    merging: MergeVertex,
    media: (Media, u32),
    scale: f32,
    mass: f32,
}

impl KeptMerge {
    /// `camera`, whose estimates count for `scale`, where merging kept `mass` of the kernel.
    pub fn new(camera: &CameraVertex, scale: f32, mass: f32) -> Self {
        KeptMerge {
            p: camera.p,
            wo: camera.wo,
            frame: camera.frame,
            bsdf: *camera.bsdf,
            beta: camera.beta,
            hero_only: camera.hero_only,
            partials: camera.partials,
            segments: camera.segments,
            merging: camera.merging,
            media: camera.media,
            scale,
            mass,
        }
    }

    /// Where it merged.
    pub fn p(&self) -> Vec3 {
        self.p
    }

    fn camera(&self) -> CameraVertex<'_> {
        CameraVertex {
            p: self.p,
            wo: self.wo,
            frame: self.frame,
            bsdf: &self.bsdf,
            beta: self.beta,
            hero_only: self.hero_only,
            partials: self.partials,
            segments: self.segments,
            merging: self.merging,
            media: self.media,
        }
    }

    /// What merging here gains from the light vertices of `added` and loses from those of
    /// `removed` (radiance and Laplacian, times what its estimates count for), for paths of at
    /// most `max_segments`: `Some(None)` where none lies within the disc, `None` where one of
    /// them lies on a surface that cuts the disc (the kernel mass would change).
    #[allow(clippy::option_option)]
    pub fn change(
        &self,
        (added, removed): (&MergeSet, &MergeSet),
        weights: &PassWeights,
        max_segments: u32,
    ) -> Option<Option<(SampledSpectrum, SampledSpectrum)>> {
        let camera = self.camera();
        let (mut gained, mut lost) = (Merged::default(), Merged::default());
        added.gather((weights, &[]), &camera, max_segments, &mut gained);
        removed.gather((weights, &[]), &camera, max_segments, &mut lost);
        if gained.cut || lost.cut {
            return None;
        }
        if !(gained.reached || lost.reached) {
            return Some(None);
        }
        let kernel = &added.kernel;
        let per_path = 1.0 / weights.light_paths;
        let radiance = (gained.sum - lost.sum) / self.mass * (kernel.scale * per_path) * self.scale;
        let laplacian =
            (gained.laplacian - lost.laplacian) * (kernel.laplacian_scale * per_path) * self.scale;
        Some(Some((radiance, laplacian)))
    }
}

/// How a camera vertex's BSDF is read for each light vertex merged there: a Lambertian one
/// without a normal map from numbers found once (most merges are on such surfaces), any other by
/// evaluating it.
enum Shading {
    /// `f = albedo / pi` in front of the shading normal `n` on the camera's side; the density of
    /// the camera's direction from any light direction is `reverse`.
    Lambertian { f: SampledSpectrum, n: Vec3, reverse: f32 },
    /// Evaluated per light vertex.
    General,
}

impl Shading {
    fn of(camera: &CameraVertex) -> Self {
        match *camera.bsdf {
            Bsdf::Diffuse { albedo } if !camera.frame.is_bent() => {
                let n = camera.frame.toward(camera.wo);
                Shading::Lambertian {
                    f: albedo * FRAC_1_PI,
                    n,
                    reverse: n.dot(camera.wo).max(0.0) * FRAC_1_PI,
                }
            }
            _ => Shading::General,
        }
    }

    /// The BSDF for light arriving from `wi`, and its densities of `wi` (forward) and of the way
    /// back (reverse); `None` where it is zero.
    #[inline]
    fn toward(&self, camera: &CameraVertex, wi: Vec3) -> Option<(SampledSpectrum, f32, f32)> {
        match *self {
            Shading::Lambertian { f, n, reverse } => {
                let cos = n.dot(wi);
                (cos > 0.0).then_some((f, cos * FRAC_1_PI, reverse))
            }
            Shading::General => {
                let f = camera.bsdf.eval(camera.frame, camera.wo, wi) * camera.frame.photon_cosine_ratio(wi);
                if f.max_element() <= 0.0 {
                    return None;
                }
                let forward = camera.bsdf.pdf(camera.frame, camera.wo, wi);
                Some((f, forward, camera.bsdf.pdf(camera.frame, wi, camera.wo)))
            }
        }
    }
}
