//! Geometry shared by every stage: moving ray origins off surfaces robustly.
//!
//! Ray origins are offset by a few ULPs of the position's coordinates, so self-intersection stays
//! fixed at any scene scale (1e-4 to 1e6 units), where a fixed epsilon would fail at one end.

use glam::Vec3;

/// A ray origin moved off the surface at `p` (geometric normal `ng`) to the side of `direction`,
/// by a few ULPs of `p`'s coordinates (Wächter & Binder 2019, "A Fast and Robust Method for
/// Avoiding Self-Intersection", Ray Tracing Gems chapter 6).
pub fn offset_origin(p: Vec3, ng: Vec3, direction: Vec3) -> Vec3 {
    const ORIGIN: f32 = 1.0 / 32.0;
    const FLOAT_SCALE: f32 = 1.0 / 65536.0;
    const INT_SCALE: f32 = 256.0;
    let n = if ng.dot(direction) < 0.0 { -ng } else { ng };
    let offset = |p: f32, n: f32| {
        let of_i = (INT_SCALE * n) as i32;
        let bits = p.to_bits() as i32;
        let moved = f32::from_bits((bits + if p < 0.0 { -of_i } else { of_i }) as u32);
        if p.abs() < ORIGIN {
            p + FLOAT_SCALE * n
        } else {
            moved
        }
    };
    Vec3::new(offset(p.x, n.x), offset(p.y, n.y), offset(p.z, n.z))
}
