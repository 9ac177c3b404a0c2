//! A hash grid over the pass's photons (Hachisuka & Jensen 2009's SPPM uses one over hit points;
//! gathering per pixel from photons keeps the result independent of thread timing).
//!
//! Cells are `2 r` wide, so the photons within `r` of a point lie in the 2 x 2 x 2 cells around
//! it. Photons are sorted by bucket with a counting sort in photon order (deterministic); the
//! caller keeps its photons in that order, so a bucket's photons lie side by side in memory.

use glam::{IVec3, Vec3, Vec4};
use std::ops::Range;

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

/// `items` (at `position`) bucketed for lookups within `radius`, in parallel: the grid, what
/// `arrival` reads of each item, in bucket order, and their positions in that order, kept apart.
pub(crate) fn bucketed<I: Sync, A: Send>(
    items: &[I],
    radius: f32,
    position: impl Fn(&I) -> Vec3 + Sync,
    arrival: impl Fn(&I) -> A + Sync,
) -> (PhotonGrid, Vec<A>, Positions) {
    let positions: Vec<Vec3> = items.par_iter().with_min_len(4096).map(&position).collect();
    let (grid, order) = PhotonGrid::build(&positions, radius);
    let sorted = order.par_iter().with_min_len(4096).map(|&i| arrival(&items[i as usize])).collect();
    (grid, sorted, Positions::new(order.iter().map(|&i| positions[i as usize])))
}

/// Photon positions, one array per coordinate, so that four distances are tested at once.
/// Each array has three more entries than photons, far away, for the last group of four.
pub(crate) struct Positions {
    x: Vec<f32>,
    y: Vec<f32>,
    z: Vec<f32>,
}

impl Positions {
    pub(crate) fn new(points: impl ExactSizeIterator<Item = Vec3>) -> Self {
        let padded = points.len() + 3;
        let mut positions = Positions {
            x: Vec::with_capacity(padded),
            y: Vec::with_capacity(padded),
            z: Vec::with_capacity(padded),
        };
        for p in points.chain([Vec3::INFINITY; 3]) {
            positions.x.push(p.x);
            positions.y.push(p.y);
            positions.z.push(p.z);
        }
        positions
    }

    pub(crate) fn at(&self, i: usize) -> Vec3 {
        Vec3::new(self.x[i], self.y[i], self.z[i])
    }

    /// Calls `visit(i, d2)` for each photon `i` in `range` at squared distance `d2 < r2` from
    /// `p`. About one candidate in six is within reach, unpredictably: four distances are tested
    /// at a time, without branches, and only the hits are visited.
    #[inline]
    pub(crate) fn for_each_within(
        &self,
        range: Range<usize>,
        p: Vec3,
        r2: f32,
        mut visit: impl FnMut(usize, f32),
    ) {
        let lane = Vec4::new(0.0, 1.0, 2.0, 3.0);
        for i in range.clone().step_by(4) {
            let dx = Vec4::from_slice(&self.x[i..i + 4]) - p.x;
            let dy = Vec4::from_slice(&self.y[i..i + 4]) - p.y;
            let dz = Vec4::from_slice(&self.z[i..i + 4]) - p.z;
            let d2 = dx * dx + dy * dy + dz * dz;
            let in_range = lane.cmplt(Vec4::splat((range.end - i) as f32));
            let mut hits = (d2.cmplt(Vec4::splat(r2)) & in_range).bitmask();
            let d2 = d2.to_array();
            while hits != 0 {
                let k = hits.trailing_zeros() as usize;
                visit(i + k, d2[k]);
                hits &= hits - 1;
            }
        }
    }
}
