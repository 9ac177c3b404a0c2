//! The gather's kernel, shared by SPPM's gather and VCM's merging: the normalised 2-D biweight
//! `K(t) = 3 / (pi r^2) (1 - t^2)^2`, `t = d / r` (Silverman 1986; integrates to 1 over the disc
//! of radius r), its Laplacian `-8 * 3 / (pi r^4) (1 - 2 t^2)` (the same photon sum with it in
//! place of `K` estimates the radiance's Laplacian, which the error bound's bias term needs:
//! Hachisuka, Jarosz & Jensen 2010), and the kernel mass that the ends of a surface (open edges,
//! walls meeting it) cut off the disc.

use glam::Vec3;
use std::f32::consts::PI;

use crate::scene::OpenEdges;

/// Photons on surfaces whose normal is within this cosine of perpendicular to the visible
/// point's, on either side, mark an edge (a wall seen from the floor). Those facing more toward
/// it are gathered; those facing more away lie behind it (the back of a thin wall). Walls meeting
/// at right angles after a rotation can face each other by +-1e-7, so perpendicular must not be
/// the boundary between gathered and not.
pub(crate) const EDGE_COSINE: f32 = 0.5;

/// The biweight kernel of one radius and its Laplacian.
#[derive(Clone, Copy)]
pub(crate) struct Kernel {
    /// The radius, squared.
    pub(crate) r2: f32,
    /// The kernel's factor: `K(t) = scale (1 - t^2)^2`.
    pub(crate) scale: f32,
    /// Its Laplacian's factor: `laplacian_scale (1 - 2 t^2)`.
    pub(crate) laplacian_scale: f32,
}

impl Kernel {
    pub(crate) fn new(radius: f32) -> Self {
        let r2 = radius * radius;
        let scale = 3.0 / (PI * r2);
        Kernel { r2, scale, laplacian_scale: -8.0 * scale / r2 }
    }

    /// The kernel mass the open edges `edges` near `p` (on a surface of normal `n`) cut off the
    /// disc, per axis.
    pub(crate) fn open_edge_cut(&self, edges: &OpenEdges, p: Vec3, n: Vec3) -> Vec3 {
        let radius = self.r2.sqrt();
        edges.distances(p, n, radius).map(|d| kernel_mass_beyond(d / radius))
    }

    /// The wall through `at` of normal `ng` (a photon's surface, meeting the surface of normal
    /// `n` at an edge) and the kernel mass its plane cuts off the disc around `p` (in that
    /// surface's plane).
    pub(crate) fn wall(&self, ng: Vec3, at: Vec3, p: Vec3, n: Vec3) -> Wall {
        let sine = (ng - ng.dot(n) * n).length();
        let height = (p - at).dot(ng);
        let mass = if sine < 0.5 { 0.0 } else { kernel_mass_beyond(height.abs() / sine / self.r2.sqrt()) };
        Wall { at, normal: ng, point_side: height, mass }
    }
}

/// The plane of a surface meeting a visible point's at an edge (a wall standing on the floor
/// the point is on), found from a photon on it.
#[derive(Clone, Copy, Default)]
pub(crate) struct Wall {
    /// The photon's position.
    at: Vec3,
    /// Its surface's normal.
    normal: Vec3,
    /// The visible point's height above the plane, along `normal`.
    pub(crate) point_side: f32,
    /// The kernel mass the plane cuts off the point's disc (zero: it does not reach the disc).
    pub(crate) mass: f32,
}

impl Wall {
    /// This wall, or `other` where it cuts more off the disc.
    pub(crate) fn or_if_cutting_more(self, other: Wall) -> Wall {
        if other.mass > self.mass {
            other
        } else {
            self
        }
    }

    /// Keeps `wall` (of a surface of normal `ng`) among `walls` where it cuts more off the disc
    /// than the one kept before along the same axis.
    pub(crate) fn keep_widest(walls: &mut [Wall; 3], wall: Wall, ng: Vec3) {
        let axis = ng.abs().max_position();
        walls[axis] = walls[axis].or_if_cutting_more(wall);
    }

    /// The kernel mass `walls` cut off, per axis.
    pub(crate) fn cut(walls: &[Wall; 3]) -> Vec3 {
        Vec3::from(walls.map(|w| w.mass))
    }

    /// Whether `p` lies across the plane from the visible point.
    pub(crate) fn separates(&self, p: Vec3) -> bool {
        (p - self.at).dot(self.normal) * self.point_side < 0.0
    }
}

/// The least kernel mass an estimate is divided by (where edges cut off more, as at the tip of
/// a sharp wedge, they are not trusted to be straight).
const LEAST_MASS_WITHIN: f32 = 0.25;

/// The kernel mass left within a surface whose edges cut `cut` off the disc, per axis.
pub(crate) fn kernel_mass_within(cut: Vec3) -> f32 {
    (1.0 - cut.element_sum()).max(LEAST_MASS_WITHIN)
}

/// The biweight kernel's mass beyond a line at distance `s` radii from its centre:
/// `M(s) = 16 / (5 pi) * integral from s to 1 of (1 - t^2)^(5/2) dt` (the kernel's marginal along
/// the line's normal), in closed form with `t = sin(phi)`.
fn kernel_mass_beyond(s: f32) -> f32 {
    if s >= 1.0 {
        return 0.0;
    }
    let phi = s.max(0.0).asin();
    let cos6_integral = 5.0 * phi / 16.0
        + 15.0 / 64.0 * (2.0 * phi).sin()
        + 3.0 / 64.0 * (4.0 * phi).sin()
        + (6.0 * phi).sin() / 192.0;
    (0.5 - 16.0 / (5.0 * PI) * cos6_integral).max(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The closed form against the biweight summed over a fine grid of the disc beyond the line
    /// `x = s` (radius 1): within 1e-4 at every distance, half the mass at the centre, none at 1.
    #[test]
    fn kernel_mass_beyond_a_line_matches_the_kernel_summed_there() {
        let n = 2000;
        let cell = 2.0 / n as f64;
        for s in [0.0, 0.1, 0.3, 0.5, 0.7, 0.9, 1.0] {
            let mut mass = 0.0;
            for i in 0..n {
                for j in 0..n {
                    let (x, y) = (-1.0 + (i as f64 + 0.5) * cell, -1.0 + (j as f64 + 0.5) * cell);
                    let t2 = x * x + y * y;
                    if x > s && t2 < 1.0 {
                        mass += 3.0 / std::f64::consts::PI * (1.0 - t2) * (1.0 - t2) * cell * cell;
                    }
                }
            }
            let closed = f64::from(kernel_mass_beyond(s as f32));
            assert!((closed - mass).abs() < 1e-4, "s = {s}: closed form {closed}, summed {mass}");
        }
        assert!((kernel_mass_beyond(0.0) - 0.5).abs() < 1e-6);
        assert_eq!(kernel_mass_beyond(1.0), 0.0);
    }
}
