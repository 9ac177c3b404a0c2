//! Light vertices bucketed for merging at camera vertices within the pass radius, weighed by the
//! gather's biweight kernel (its Laplacian too, for the error bound's bias term).

use glam::Vec3;

use super::light_paths::{joined, LightVertex};
use super::mis::{merging, Partials, PassWeights};
use crate::materials::{Bsdf, ShadingFrame};
use crate::spectrum::SampledSpectrum;
use crate::sppm::gather::Kernel;
use crate::sppm::grid::PhotonGrid;

/// Light vertices on surfaces facing more away than this (in cosine of their geometric normals)
/// from a camera vertex's are not merged there: they lie on another surface (a wall meeting the
/// floor) or the other face of a thin one.
const FACING_COSINE: f32 = 0.5;

/// What merging reads of a light vertex.
#[derive(Clone, Copy, Debug)]
struct Arrival {
    p: Vec3,
    wi: Vec3,
    ng: Vec3,
    throughput: SampledSpectrum,
    hero_only: bool,
    partials: Partials,
    segments: u32,
}

/// The pass's light vertices, sorted by grid bucket.
pub struct MergeSet {
    sorted: Vec<Arrival>,
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
}

impl MergeSet {
    /// The light vertices of `vertices` for merging within `radius`.
    pub fn new(vertices: &[LightVertex], radius: f32) -> Self {
        let positions: Vec<Vec3> = vertices.iter().map(|v| v.p).collect();
        let (grid, order) = PhotonGrid::build(&positions, radius);
        let sorted = order
            .iter()
            .map(|&i| {
                let v = &vertices[i as usize];
                let ng = v.lobe.frame.ng();
                Arrival {
                    p: v.p,
                    wi: v.wo,
                    ng: if ng.dot(v.wo) < 0.0 { -ng } else { ng },
                    throughput: v.throughput,
                    hero_only: v.hero_only,
                    partials: v.partials,
                    segments: v.segments,
                }
            })
            .collect();
        MergeSet { sorted, grid, kernel: Kernel::new(radius) }
    }

    /// The weighted radiance merging finds at `camera` (times its throughput), and the same with
    /// the kernel's Laplacian, for paths of at most `max_segments`.
    pub fn merge(
        &self,
        weights: &PassWeights,
        camera: &CameraVertex,
        max_segments: u32,
    ) -> (SampledSpectrum, SampledSpectrum) {
        let (mut sum, mut laplacian) = (SampledSpectrum::ZERO, SampledSpectrum::ZERO);
        let ng = camera.frame.ng();
        let front = if ng.dot(camera.wo) < 0.0 { -ng } else { ng };
        let r2 = self.kernel.r2;
        self.grid.for_each_near(camera.p, |range| {
            for light in &self.sorted[range] {
                let d2 = light.p.distance_squared(camera.p);
                if d2 >= r2
                    || light.segments + camera.segments > max_segments
                    || light.ng.dot(front) < FACING_COSINE
                {
                    continue;
                }
                let f = camera.bsdf.eval(camera.frame, camera.wo, light.wi)
                    * camera.frame.photon_cosine_ratio(light.wi);
                if f.max_element() <= 0.0 {
                    continue;
                }
                let forward = camera.bsdf.pdf(camera.frame, camera.wo, light.wi);
                let reverse = camera.bsdf.pdf(camera.frame, light.wi, camera.wo);
                let weight = merging(weights, &light.partials, &camera.partials, forward, reverse);
                let value =
                    joined(camera.beta, camera.hero_only, light.throughput, light.hero_only) * f * weight;
                let t2 = d2 / r2;
                sum += value * ((1.0 - t2) * (1.0 - t2));
                laplacian += value * (1.0 - 2.0 * t2);
            }
        });
        let per_path = 1.0 / weights.light_paths;
        (sum * (self.kernel.scale * per_path), laplacian * (self.kernel.laplacian_scale * per_path))
    }
}
