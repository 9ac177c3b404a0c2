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

/// The eight corners of a 2 x 2 x 2 block, numbered as octants are, and the shift that brings
/// each one's octants in 4 x 4 x 4 slots (bit `x + 4 y + 16 z`) to the lowest bits.
const CORNERS: [(IVec3, u32); 8] = {
    let mut corners = [(IVec3::ZERO, 0); 8];
    let mut k = 0;
    while k < 8 {
        let (x, y, z) = (k as i32 & 1, (k as i32 >> 1) & 1, (k as i32 >> 2) & 1);
        corners[k] = (IVec3::new(x, y, z), (2 * x + 8 * y + 32 * z) as u32);
        k += 1;
    }
    corners
};

/// Buckets of at most this many photons are read whole: testing a few more photons costs less
/// than starting a range per octant (as many as four in a cell). Modelled cycles (instructions
/// and mispredictions counted by cachegrind) were lowest with 16 both in early passes of the
/// demo and after pass 64 of the bench box (none in either had buckets of 17 to 32).
const WHOLE_BUCKET: usize = 16;

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
        // Per axis, the squared gap from `p` to the octants below, at and above its own, in
        // octants (the fourth lane out of reach).
        let below = scaled - floor;
        let above = Vec3::ONE - below;
        let gaps: [Vec4; 3] = std::array::from_fn(|axis| {
            Vec4::new(below[axis] * below[axis], 0.0, above[axis] * above[axis], f32::INFINITY)
        });
        // Bit `x + 4 y + 16 z` is set where the octant at `(x, y, z) - 1` from `p`'s own is
        // within reach.
        let mut near = 0u64;
        for z in 0..3 {
            for y in 0..3 {
                let mask = (gaps[0] + (gaps[1][y] + gaps[2][z])).cmplt(Vec4::ONE).bitmask();
                near |= u64::from(mask) << (4 * y + 16 * z);
            }
        }
        // The same in slots of the two cells per axis, `x + 4 y + 16 z` again: the octant below
        // `p`'s own is the first cell's first where `p`'s octant is odd, else its second.
        let to_slots = IVec3::ONE - parity;
        let within = near << (to_slots.x + 4 * to_slots.y + 16 * to_slots.z);
        let first_parity = octant_number(first_cell & IVec3::ONE);
        for (k, (corner, shift)) in CORNERS.iter().enumerate() {
            let slots = within >> shift;
            if slots & CELL_SLOTS == 0 {
                continue;
            }
            // The cells of the block differ in parity: each has its own bucket of its group.
            let b = hash_cell(first_cell + *corner, self.groups) * PARITIES + (first_parity ^ k);
            let bucket = self.start[b * OCTANTS] as usize..self.start[(b + 1) * OCTANTS] as usize;
            if bucket.len() <= WHOLE_BUCKET {
                visit(bucket);
                continue;
            }
            let mut reached = octants_of(slots);
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

/// The slots (bits `x + 4 y + 16 z`) of the cell at the lowest corner.
const CELL_SLOTS: u64 = 0x33_0033;

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
