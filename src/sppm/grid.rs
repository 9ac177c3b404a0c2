//! A hash grid over the pass's photons (Hachisuka & Jensen 2009's SPPM uses one over hit points;
//! gathering per pixel from photons keeps the result independent of thread timing).
//!
//! Cells are `2 r` wide and hashed into buckets; each cell is split into its eight octants, `r`
//! wide, and a bucket's photons are sorted by octant. The photons within `r` of a point lie in
//! the 3 x 3 x 3 octants around the point's own, which lie in the 2 x 2 x 2 cells around it: a
//! lookup hashes those eight cells and reads only the octants the sphere reaches, about half the
//! surface that whole cells of `2 r` would cover, from the same few places in memory. Photons are
//! sorted with a counting sort in photon order (deterministic); the caller keeps its photons in
//! that order, so a bucket's photons lie side by side in memory, octant after octant.

use glam::{IVec3, Vec3, Vec4};
use std::ops::Range;

use crate::geometry::{hash_cell, sort_into_buckets};
use rayon::prelude::*;

/// Octants of a cell: `x + 2 y + 4 z`, each 0 or 1.
const OCTANTS: usize = 8;

/// Parities of a cell's coordinates (numbered as octants are).
const PARITIES: usize = 8;

/// Buckets of hashed grid cells over photons sorted by bucket and octant: octant `o` of bucket
/// `b` holds the sorted photons `start[8 b + o]..start[8 b + o + 1]`.
pub struct PhotonGrid {
    /// The width of an octant: the lookup radius.
    octant_size: f32,
    /// Groups of buckets, one bucket per parity.
    groups: usize,
    start: Vec<u32>,
}

impl PhotonGrid {
    /// Buckets `positions` for lookups of radius `radius`; gives the grid and the order to keep
    /// the photons in (the index in `positions` of each sorted photon). Each photon's bucket is
    /// found in parallel; the counting sort that follows is serial, in photon order.
    pub fn build(positions: &[Vec3], radius: f32) -> (Self, Vec<u32>) {
        let groups = (positions.len() / 16).max(1);
        let key_of: Vec<u32> = positions
            .par_iter()
            .with_min_len(4096)
            .map(|&p| {
                let octant = (p / radius).floor().as_ivec3();
                let b = bucket_of(cell_of(octant), groups);
                (b * OCTANTS + octant_number(octant & IVec3::ONE)) as u32
            })
            .collect();
        let (start, order) = sort_into_buckets(&key_of, groups * PARITIES * OCTANTS);
        (PhotonGrid { octant_size: radius, groups, start }, order)
    }

    /// Calls `visit` with ranges of sorted photons that together hold every photon within the
    /// radius of `p`, each once (a superset: the caller checks distances). These are the octants
    /// that the sphere around `p` reaches, neighbours in memory joined into one range.
    pub fn for_each_near(&self, p: Vec3, mut visit: impl FnMut(Range<usize>)) {
        let scaled = p / self.octant_size;
        let floor = scaled.floor();
        let own = floor.as_ivec3();
        // The 3 x 3 x 3 octants around `p`'s own lie in two cells per axis, from `first_cell`:
        // the cell below `p`'s own where `p`'s octant is the lower of its cell, else its own.
        // The octant below `p`'s is the first cell's first or second (offset -2 or -1 from it).
        // (Written so that no step overflows at the ends of the integers.)
        let parity = own & IVec3::ONE;
        let first_cell = cell_of(own) - IVec3::ONE + parity;
        // Per axis, the squared gap from `p` to each octant of the two cells (infinite where the
        // octant is not one of the three around `p`'s own), in octants.
        let below = scaled - floor;
        let above = Vec3::ONE - below;
        let offsets = (parity - IVec3::splat(2)).as_vec3();
        let gaps: [Vec4; 3] = std::array::from_fn(|axis| {
            let offset = Vec4::splat(offsets[axis]) + Vec4::new(0.0, 1.0, 2.0, 3.0);
            let (below, above) =
                (Vec4::splat(below[axis] * below[axis]), Vec4::splat(above[axis] * above[axis]));
            let beside = Vec4::select(offset.cmpeq(Vec4::ZERO), Vec4::ZERO, Vec4::INFINITY);
            let beside = Vec4::select(offset.cmpeq(Vec4::ONE), above, beside);
            Vec4::select(offset.cmpeq(Vec4::NEG_ONE), below, beside)
        });
        // Bit `x + 4 y + 16 z` is set where the octant in slot (x, y, z) is within reach.
        let mut within = 0u64;
        for z in 0..4 {
            for y in 0..4 {
                let mask = (gaps[0] + (gaps[1][y] + gaps[2][z])).cmplt(Vec4::ONE).bitmask();
                within |= u64::from(mask) << (4 * y + 16 * z);
            }
        }
        for k in 0..8 {
            let corner = IVec3::new(k & 1, (k >> 1) & 1, (k >> 2) & 1);
            let mut reached = octants_of(within >> (2 * corner.x + 8 * corner.y + 32 * corner.z));
            if reached == 0 {
                continue;
            }
            let b = bucket_of(first_cell + corner, self.groups);
            while reached != 0 {
                let first = reached.trailing_zeros();
                let run = (reached >> first).trailing_ones();
                let key = b * OCTANTS + first as usize;
                visit(self.start[key] as usize..self.start[key + run as usize] as usize);
                reached &= !(((1u32 << run) - 1) << first);
            }
        }
    }
}

/// The octants of one cell from bits `x + 4 y + 16 z` of the 4 x 4 x 4 slots, shifted to the
/// cell's corner: bits 0, 1, 4, 5, 16, 17, 20, 21 become octants 0 to 7.
fn octants_of(slots: u64) -> u32 {
    let s = slots as u32;
    (s & 0x3) | ((s >> 2) & 0xC) | ((s >> 12) & 0x30) | ((s >> 14) & 0xC0)
}

/// The bucket of cell `cell`: a hashed group, and in it the bucket of the cell's parity (the
/// evenness of its coordinates). The eight cells of any 2 x 2 x 2 block differ in parity, so a
/// lookup never finds two of its cells in one bucket, and reads each photon once.
fn bucket_of(cell: IVec3, groups: usize) -> usize {
    hash_cell(cell, groups) * PARITIES + octant_number(cell & IVec3::ONE)
}

/// The cell of `2 r` that holds the octant `octant` (floor division by two).
fn cell_of(octant: IVec3) -> IVec3 {
    octant >> IVec3::ONE
}

/// The number of the octant at `bits` (each 0 or 1) within its cell.
fn octant_number(bits: IVec3) -> usize {
    (bits.x + 2 * bits.y + 4 * bits.z) as usize
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
