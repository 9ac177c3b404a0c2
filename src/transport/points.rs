//! A pass's points seen from the camera (SPPM's visible points, VCM's merging camera vertices)
//! bucketed by position, to find those a photon or light vertex reaches: the pixels a frame's own
//! paths change (reuse across frames), and whether a photon path is seen at all
//! (visibility-driven photons).

use std::sync::atomic::{AtomicU64, Ordering};

use glam::Vec3;
use rayon::prelude::*;

use super::grid::PhotonGrid;

/// A mark per pixel, set from any thread.
pub struct PixelMarks(Vec<AtomicU64>);

impl PixelMarks {
    pub fn new(pixels: usize) -> Self {
        PixelMarks((0..pixels.div_ceil(64)).map(|_| AtomicU64::new(0)).collect())
    }

    pub fn mark(&self, pixel: u32) {
        self.0[pixel as usize / 64].fetch_or(1 << (pixel % 64), Ordering::Relaxed);
    }

    /// The marked pixels, in order.
    pub fn marked(&self) -> Vec<u32> {
        let mut pixels = Vec::new();
        for (w, word) in self.0.iter().enumerate() {
            let mut bits = word.load(Ordering::Relaxed);
            while bits != 0 {
                pixels.push(w as u32 * 64 + bits.trailing_zeros());
                bits &= bits - 1;
            }
        }
        pixels
    }
}

/// Visible points bucketed by position for lookups within the pass's radius.
pub struct PointGrid {
    grid: PhotonGrid,
    /// The sorted points' pixels and positions.
    pixels: Vec<u32>,
    positions: Vec<Vec3>,
    /// The squared distance within which a photon reaches a point, with a margin for rounding:
    /// a gather counts a photon by the same distance computed otherwise.
    reach2: f32,
}

impl PointGrid {
    /// A grid over the visible points `(pixel, position)` for the gather radius `radius`.
    pub fn new(points: impl Iterator<Item = (usize, Vec3)>, radius: f32) -> Self {
        let (pixels, points): (Vec<u32>, Vec<Vec3>) = points.map(|(pixel, p)| (pixel as u32, p)).unzip();
        let (grid, order) = PhotonGrid::build(&points, radius);
        PointGrid {
            grid,
            pixels: order.iter().map(|&i| pixels[i as usize]).collect(),
            positions: order.iter().map(|&i| points[i as usize]).collect(),
            reach2: radius * radius * 1.001,
        }
    }

    /// Marks the pixels with a point within the radius of some item of `items` (at `position`).
    pub fn mark_near<T: Sync>(&self, items: &[T], position: impl Fn(&T) -> Vec3 + Sync, marks: &PixelMarks) {
        items.par_iter().with_min_len(64).for_each(|item| {
            let p = position(item);
            self.grid.for_each_near(p, |range| {
                for i in range {
                    if self.positions[i].distance_squared(p) < self.reach2 {
                        marks.mark(self.pixels[i]);
                    }
                }
            });
        });
    }

    /// How many visible points lie within the radius of `p`.
    pub fn count_near(&self, p: Vec3) -> usize {
        let mut count = 0;
        self.grid.for_each_near(p, |range| {
            count += self.positions[range].iter().filter(|q| q.distance_squared(p) < self.reach2).count()
        });
        count
    }

    /// Whether some visible point lies within the radius of `p`.
    pub fn reaches(&self, p: Vec3) -> bool {
        let mut found = false;
        self.grid.for_each_near(p, |range| {
            found = found || self.positions[range].iter().any(|q| q.distance_squared(p) < self.reach2)
        });
        found
    }
}
