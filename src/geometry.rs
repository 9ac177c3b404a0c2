//! Geometry shared by every stage: moving ray origins off surfaces robustly, and cones of
//! directions that stay precise when narrow.
//!
//! Ray origins are offset by a few ULPs of the position's coordinates, so self-intersection stays
//! fixed at any scene scale (1e-4 to 1e6 units), where a fixed epsilon would fail at one end.
//! Near the origin, where ULPs vanish, the offset follows the size of the coordinates the point
//! was computed from instead.

use glam::{IVec3, Vec3, Vec3A};

/// A ray origin moved off the surface at `p` (geometric normal `ng`) to the side of `direction`,
/// by a few ULPs of `p`'s coordinates (Wächter & Binder 2019, "A Fast and Robust Method for
/// Avoiding Self-Intersection", Ray Tracing Gems chapter 6). `scale` is the largest coordinate
/// `p` was computed from (its triangle's corners): Wächter & Binder's fixed offset near the
/// origin is meant for coordinates of order 1 and is scaled down with smaller ones (a 1e-4 scene
/// would otherwise be offset by a tenth of its size).
pub fn offset_origin(p: Vec3, ng: Vec3, direction: Vec3, scale: f32) -> Vec3 {
    const ORIGIN: f32 = 1.0 / 32.0;
    const FLOAT_SCALE: f32 = 1.0 / 65536.0;
    const INT_SCALE: f32 = 32.0;
    let s = scale.clamp(f32::MIN_POSITIVE, 1.0);
    let n = if ng.dot(direction) < 0.0 { -ng } else { ng };
    let offset = |p: f32, n: f32| {
        let of_i = (INT_SCALE * n) as i32;
        let bits = p.to_bits() as i32;
        let moved = f32::from_bits((bits + if p < 0.0 { -of_i } else { of_i }) as u32);
        if p.abs() < ORIGIN * s {
            p + FLOAT_SCALE * s * n
        } else {
            moved
        }
    };
    Vec3::new(offset(p.x, n.x), offset(p.y, n.y), offset(p.z, n.z))
}

/// The largest coordinate of a triangle's corners: the size of the coordinates its points are
/// computed from, as [`offset_origin`] takes it.
pub fn corners_scale([a, b, c]: [Vec3A; 3]) -> f32 {
    a.abs().max(b.abs()).max(c.abs()).max_element()
}

/// The bucket of grid cell `cell` among `buckets` (Teschner et al. 2003's spatial hash).
pub fn hash_cell(cell: IVec3, buckets: usize) -> usize {
    let h = (cell.x as u32).wrapping_mul(73_856_093)
        ^ (cell.y as u32).wrapping_mul(19_349_663)
        ^ (cell.z as u32).wrapping_mul(83_492_791);
    // In place of a division: Fibonacci hashing mixes every bit of `h` into the high bits, which
    // Lemire's multiply-shift scales to `buckets`.
    let mixed = h.wrapping_mul(0x9e37_79b9);
    ((u64::from(mixed) * buckets as u64) >> 32) as usize
}

/// Items sorted by bucket with a counting sort, in item order within a bucket (deterministic):
/// `bucket_of[i]` is item `i`'s bucket among `buckets`. Gives where each bucket starts in the
/// sorted order (`buckets + 1` entries) and the item at each sorted place.
pub fn sort_into_buckets(bucket_of: &[u32], buckets: usize) -> (Vec<u32>, Vec<u32>) {
    // Bucket b's count goes to entry b + 2, so that the running sum leaves bucket b's start at
    // entry b + 1: that entry is the bucket's next free place while items are placed, and ends
    // at the bucket's end, which is bucket b + 1's start (one array, and no copy of it).
    let mut bucket_start = vec![0u32; buckets + 2];
    for &b in bucket_of {
        bucket_start[b as usize + 2] += 1;
    }
    for i in 2..=buckets + 1 {
        bucket_start[i] += bucket_start[i - 1];
    }
    let mut order = vec![0u32; bucket_of.len()];
    for (i, &b) in bucket_of.iter().enumerate() {
        let next = &mut bucket_start[b as usize + 1];
        order[*next as usize] = i as u32;
        *next += 1;
    }
    bucket_start.pop();
    (bucket_start, order)
}

/// Whether the ray from `origin` along `direction` meets the box `[lo, hi]` before `t_max`
/// (the slab test; a ray starting inside meets it).
pub fn ray_meets_box(origin: Vec3, direction: Vec3, t_max: f32, (lo, hi): (Vec3, Vec3)) -> bool {
    let inverse = direction.recip();
    let (a, b) = ((lo - origin) * inverse, (hi - origin) * inverse);
    // NaN (a zero direction component on a slab's plane) must not exclude: max/min skip NaN.
    let near = a.min(b).max_element().max(0.0);
    let far = a.max(b).min_element().min(t_max);
    near <= far
}

/// A cone of directions about an axis, kept as `1 - cos(half-angle)`: near 1, cosines of narrow
/// cones (a 0.1 degree spot, the sun's 0.27 degree radius) differ in their last f32 bits, but
/// `1 - cos` keeps full precision.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Cone {
    /// `1 - cos(half-angle)`, in [0, 2].
    pub one_minus_cos: f32,
}

impl Cone {
    /// The cone of half-angle `radians` (computed as `2 sin^2(half-angle / 2)` in f64).
    pub fn from_half_angle(radians: f32) -> Self {
        let s = (f64::from(radians.clamp(0.0, std::f32::consts::PI)) / 2.0).sin();
        Cone { one_minus_cos: (2.0 * s * s) as f32 }
    }

    /// Its solid angle, `2 pi (1 - cos)`.
    pub fn solid_angle(&self) -> f32 {
        2.0 * std::f32::consts::PI * self.one_minus_cos
    }

    /// Whether it is a single direction (a delta light).
    pub fn is_delta(&self) -> bool {
        self.one_minus_cos <= 0.0
    }

    /// Whether the unit vector `w` lies inside the cone about the unit `axis`.
    pub fn contains(&self, axis: Vec3, w: Vec3) -> bool {
        one_minus_cos_between(axis, w) <= self.one_minus_cos
    }
}

/// `1 - cos` of the angle between unit vectors, exact for small angles: `|a - b|^2 / 2`.
pub fn one_minus_cos_between(a: Vec3, b: Vec3) -> f32 {
    (a - b).length_squared() / 2.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sorts_into_buckets_keeping_item_order_within_each() {
        let bucket_of = [2, 0, 2, 3, 0, 2];
        let (bucket_start, order) = sort_into_buckets(&bucket_of, 5);
        assert_eq!(bucket_start, [0, 2, 2, 5, 6, 6]);
        assert_eq!(order, [1, 4, 0, 2, 5, 3]);
        assert_eq!(sort_into_buckets(&[], 1), (vec![0, 0], vec![]));
    }
}
