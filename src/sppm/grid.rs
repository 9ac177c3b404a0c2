//! A hash grid over the pass's photons (Hachisuka & Jensen 2009's SPPM uses one over hit points;
//! gathering per pixel from photons keeps the result independent of thread timing).
//!
//! Cells are `2 r` wide, so the photons within `r` of a point lie in the 2 x 2 x 2 cells around
//! it. Photons are sorted by bucket with a counting sort in photon order (deterministic); the
//! caller keeps its photons in that order, so a bucket's photons lie side by side in memory.

use glam::{IVec3, Vec3};

use crate::geometry::{hash_cell, sort_into_buckets};
use rayon::prelude::*;

/// Buckets of hashed grid cells over photons sorted by bucket: bucket `b` holds the sorted
/// photons `bucket_start[b]..bucket_start[b + 1]`.
pub struct PhotonGrid {
    cell_size: f32,
    bucket_start: Vec<u32>,
}

impl PhotonGrid {
    /// Buckets `positions` for lookups of radius `radius`; gives the grid and the order to keep
    /// the photons in (the index in `positions` of each sorted photon). Each photon's bucket is
    /// found in parallel; the counting sort that follows is serial, in photon order.
    pub fn build(positions: &[Vec3], radius: f32) -> (Self, Vec<u32>) {
        let cell_size = 2.0 * radius;
        let buckets = (2 * positions.len()).max(1);
        let bucket_of: Vec<u32> = positions
            .par_iter()
            .with_min_len(4096)
            .map(|&p| hash_cell((p / cell_size).floor().as_ivec3(), buckets) as u32)
            .collect();
        let (bucket_start, order) = sort_into_buckets(&bucket_of, buckets);
        (PhotonGrid { cell_size, bucket_start }, order)
    }

    /// Calls `visit` with the range of sorted photons of every bucket within the 2 x 2 x 2 block
    /// of cells around `p` that the sphere of radius `cell_size / 2` around `p` reaches (a
    /// superset of the photons within that radius; the caller checks distances). About a third
    /// of the block's cells lie out of reach of a point on a surface, with their photons.
    pub fn for_each_near(&self, p: Vec3, mut visit: impl FnMut(std::ops::Range<usize>)) {
        let buckets = self.bucket_start.len() - 1;
        let scaled = p / self.cell_size;
        let base = (scaled - 0.5).floor();
        // Per axis, how far `p` lies beyond the lower cell (into the upper one) and short of
        // the upper cell, in cells: the sphere reaches a cell when these add up, squared, to
        // less than a quarter.
        let into_upper = (scaled - base - Vec3::ONE).max(Vec3::ZERO);
        let short_of_upper = (base + Vec3::ONE - scaled).max(Vec3::ZERO);
        let base = base.as_ivec3();
        let mut seen = [usize::MAX; 8];
        for k in 0..8 {
            let upper = [k & 1 != 0, (k >> 1) & 1 != 0, (k >> 2) & 1 != 0];
            let gap = Vec3::select(glam::BVec3::from(upper), short_of_upper, into_upper);
            if gap.length_squared() >= 0.25 {
                continue;
            }
            let b = hash_cell(base + IVec3::from(upper.map(i32::from)), buckets);
            if seen[..k].contains(&b) {
                continue;
            }
            seen[k] = b;
            visit(self.bucket_start[b] as usize..self.bucket_start[b + 1] as usize);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_every_photon_within_the_radius() {
        let points: Vec<Vec3> = (0..2000)
            .map(|i| Vec3::new((i * 37 % 101) as f32, (i * 53 % 89) as f32, (i * 11 % 97) as f32) * 0.01)
            .collect();
        let radius = 0.07;
        let (grid, order) = PhotonGrid::build(&points, radius);
        for q in [Vec3::splat(0.3), Vec3::new(0.05, 0.8, 0.41), Vec3::new(-0.02, 0.0, 0.9)] {
            let mut found = Vec::new();
            grid.for_each_near(q, |range| {
                let near =
                    order[range].iter().map(|&i| i as usize).filter(|&i| points[i].distance(q) < radius);
                found.extend(near)
            });
            found.sort();
            let expected: Vec<usize> =
                (0..points.len()).filter(|&i| points[i].distance(q) < radius).collect();
            assert_eq!(found, expected);
        }
    }
}
