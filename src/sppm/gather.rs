//! The gather (DESIGN.md step 4): at each visible point, the photons within the pass radius,
//! weighted by a smooth kernel and the BSDF.
//!
//! The kernel is the normalised 2-D biweight `K(t) = 3 / (pi r^2) (1 - t^2)^2`, `t = d / r`
//! (Silverman 1986; integrates to 1 over the disc of radius r). Its 2-D Laplacian with respect to
//! the gather position is `-8 * 3 / (pi r^4) (1 - 2 t^2)`; the same photon sum with it in place
//! of `K` estimates the Laplacian of the radiance, which the error bound's bias term needs
//! (Hachisuka, Jarosz & Jensen 2010).
//!
//! Where the disc reaches past the end of the visible point's surface, the sum is divided by the
//! kernel mass left on the surface ([`PhotonSums`]): the ends are found from photons on surfaces
//! meeting the point's, and from the scene's open edges ([`crate::scene::OpenEdges`]). Photons
//! across such a surface's plane from a point behind it (a thin partition's far side) are left
//! out ([`Weigher`]).

use glam::{Vec3, Vec4};
use rayon::prelude::*;
use std::f32::consts::{FRAC_1_PI, PI};
use std::ops::Range;
use std::sync::Arc;

use super::grid::PhotonGrid;
use super::photons::Photon;
use super::renderer::{PixelEstimate, VisiblePoint};
use super::visible::EyeResult;
use crate::materials::Bsdf;
use crate::scene::OpenEdges;
use crate::spectrum::{SampledSpectrum, LANES};

/// Photons on surfaces whose normal is within this cosine of perpendicular to the visible
/// point's, on either side, mark an edge (a wall seen from the floor). Those facing more toward
/// it are gathered; those facing more away lie behind it (the back of a thin wall). Walls meeting
/// at right angles after a rotation can face each other by +-1e-7, so perpendicular must not be
/// the boundary between gathered and not.
pub(super) const EDGE_COSINE: f32 = 0.5;

/// The biweight kernel of one radius and its Laplacian.
#[derive(Clone, Copy)]
pub(super) struct Kernel {
    /// The radius, squared.
    pub(super) r2: f32,
    /// The kernel's factor: `K(t) = scale (1 - t^2)^2`.
    pub(super) scale: f32,
    /// Its Laplacian's factor: `laplacian_scale (1 - 2 t^2)`.
    pub(super) laplacian_scale: f32,
}

impl Kernel {
    pub(super) fn new(radius: f32) -> Self {
        let r2 = radius * radius;
        let scale = 3.0 / (PI * r2);
        Kernel { r2, scale, laplacian_scale: -8.0 * scale / r2 }
    }

    /// The kernel mass the open edges `edges` near `p` (on a surface of normal `n`) cut off the
    /// disc, per axis.
    pub(super) fn open_edge_cut(&self, edges: &OpenEdges, p: Vec3, n: Vec3) -> Vec3 {
        let radius = self.r2.sqrt();
        edges.distances(p, n, radius).map(|d| kernel_mass_beyond(d / radius))
    }

    /// The wall through `at` of normal `ng` (a photon's surface, meeting the surface of normal
    /// `n` at an edge) and the kernel mass its plane cuts off the disc around `p` (in that
    /// surface's plane).
    pub(super) fn wall(&self, ng: Vec3, at: Vec3, p: Vec3, n: Vec3) -> Wall {
        let sine = (ng - ng.dot(n) * n).length();
        let height = (p - at).dot(ng);
        let mass = if sine < 0.5 { 0.0 } else { kernel_mass_beyond(height.abs() / sine / self.r2.sqrt()) };
        Wall { at, normal: ng, point_side: height, mass }
    }
}

/// The plane of a surface meeting a visible point's at an edge (a wall standing on the floor
/// the point is on), found from a photon on it.
#[derive(Clone, Copy, Default)]
pub(super) struct Wall {
    /// The photon's position.
    at: Vec3,
    /// Its surface's normal.
    normal: Vec3,
    /// The visible point's height above the plane, along `normal`.
    point_side: f32,
    /// The kernel mass the plane cuts off the point's disc (zero: it does not reach the disc).
    mass: f32,
}

impl Wall {
    /// This wall, or `other` where it cuts more off the disc.
    fn or_if_cutting_more(self, other: Wall) -> Wall {
        if other.mass > self.mass {
            other
        } else {
            self
        }
    }

    /// Keeps `wall` (of a surface of normal `ng`) among `walls` where it cuts more off the disc
    /// than the one kept before along the same axis.
    pub(super) fn keep_widest(walls: &mut [Wall; 3], wall: Wall, ng: Vec3) {
        let axis = ng.abs().max_position();
        walls[axis] = walls[axis].or_if_cutting_more(wall);
    }

    /// The kernel mass `walls` cut off, per axis.
    pub(super) fn cut(walls: &[Wall; 3]) -> Vec3 {
        Vec3::from(walls.map(|w| w.mass))
    }

    /// Whether `p` lies across the plane from the visible point.
    fn separates(&self, p: Vec3) -> bool {
        (p - self.at).dot(self.normal) * self.point_side < 0.0
    }
}

/// What the gather reads of a photon besides its position: 48 bytes, where the whole photon
/// takes 64.
#[derive(Clone, Copy)]
struct Arrival {
    flux: SampledSpectrum,
    ng: Vec3,
    wi: Vec3,
    hero_only: bool,
}

impl Arrival {
    fn of(photon: &Photon) -> Self {
        Arrival { flux: photon.flux, ng: photon.ng, wi: photon.wi, hero_only: photon.hero_only }
    }
}

/// The box around `points` grown by `radius` (`None` when there are none).
fn reach(points: impl Iterator<Item = Vec3>, radius: f32) -> Option<(Vec3, Vec3)> {
    let (lo, hi) = points.map(|p| (p, p)).reduce(|(a, b), (c, d)| (a.min(c), b.max(d)))?;
    Some((lo - Vec3::splat(radius), hi + Vec3::splat(radius)))
}

fn within((lo, hi): (Vec3, Vec3), p: Vec3) -> bool {
    !(p.cmplt(lo).any() || p.cmpgt(hi).any())
}

/// Photons bucketed for gathering at one radius (a copy, sorted by bucket, so that a gather
/// reads each bucket's photons from consecutive memory). Their positions are kept apart, one
/// array per coordinate: most photons of the cells around a point are out of reach, and the
/// distance test reads 12 bytes a photon, four photons at a time, before any photon's other 48.
pub struct PhotonSet {
    sorted: Vec<Arrival>,
    positions: Positions,
    grid: PhotonGrid,
    reach: Option<(Vec3, Vec3)>,
    kernel: Kernel,
    open_edges: Arc<OpenEdges>,
}

impl PhotonSet {
    /// Buckets `photons` for gathers of radius `radius` in a scene whose surfaces end at
    /// `open_edges`.
    pub fn new(photons: &[Photon], radius: f32, open_edges: &Arc<OpenEdges>) -> Self {
        let (grid, sorted, positions) = bucketed(photons, radius, |p| p.p, Arrival::of);
        let reach = reach(photons.iter().map(|p| p.p), radius);
        PhotonSet {
            sorted,
            positions,
            grid,
            reach,
            kernel: Kernel::new(radius),
            open_edges: Arc::clone(open_edges),
        }
    }

    /// What the photons near `vp` add up to there, before the path throughput.
    pub fn sum_at(&self, vp: &VisiblePoint) -> PhotonSums {
        sum_over(vp, &[(self, self.first_round(vp))])
    }

    /// Whether `p` lies in the box the photons reach (their box grown by the radius).
    fn reaches(&self, p: Vec3) -> bool {
        self.reach.is_some_and(|r| within(r, p))
    }

    /// The photons near `vp` weighed before any wall is known, and the walls they show.
    pub fn first_round(&self, vp: &VisiblePoint) -> FirstRound {
        if !self.reaches(vp.p) {
            return FirstRound::default();
        }
        let weighed = self.weigh_near(Weigher::new(&self.kernel, vp, None));
        FirstRound { walls: weighed.walls, behind_a_wall: weighed.behind_a_wall, sums: weighed.finish() }
    }

    /// The photons near `vp` weighed with `walls` known: those across them are left out.
    fn sum_beside(&self, vp: &VisiblePoint, walls: [Wall; 3]) -> PhotonSums {
        if !self.reaches(vp.p) {
            return PhotonSums::default();
        }
        self.weigh_near(Weigher::new(&self.kernel, vp, Some(walls))).finish()
    }

    /// A pixel's estimate from its eye result and the photon sums at its visible point (of this
    /// set, or of several sets of the same radius added up), cut by the scene's open edges near
    /// the point (looked up once for the sum).
    pub fn estimate(&self, eye: &EyeResult, sums: PhotonSums) -> PixelEstimate {
        self.estimate_cut(eye, sums, |vp| self.edge_cut(vp))
    }

    /// The kernel mass the scene's open edges near `vp` cut off its disc, per axis.
    pub fn edge_cut(&self, vp: &VisiblePoint) -> Vec3 {
        self.kernel.open_edge_cut(&self.open_edges, vp.p, vp.frame.ng())
    }

    /// [`PhotonSet::estimate`] with the open edges' cut given by `edge_cut` (asked only where
    /// photons were found).
    pub fn estimate_cut(
        &self,
        eye: &EyeResult,
        mut sums: PhotonSums,
        edge_cut: impl FnOnce(&VisiblePoint) -> Vec3,
    ) -> PixelEstimate {
        let Some(vp) = eye.point else {
            return PixelEstimate {
                radiance: eye.radiance,
                laplacian: SampledSpectrum::ZERO,
                coverage: eye.coverage,
            };
        };
        if sums.kernel != SampledSpectrum::ZERO {
            sums.cut = sums.cut.max(edge_cut(&vp));
        }
        PixelEstimate {
            radiance: eye.radiance + vp.beta * sums.kernel / sums.kernel_mass_within(),
            laplacian: vp.beta * sums.laplacian,
            coverage: eye.coverage,
        }
    }

    /// `sums` (at `vp`, from photons that showed no wall the point lies behind) changed by this
    /// set's photons near `vp`: a frame's differences from a common set, those it takes out
    /// carrying their flux negated. `None` where one of them shows a wall that cuts the disc: it
    /// may change the walls, and the point needs a gather of its own.
    pub fn sums_changed(&self, vp: &VisiblePoint, sums: PhotonSums) -> Option<PhotonSums> {
        let change = self.first_round(vp);
        if change.walls.iter().any(|wall| wall.mass > 0.0) {
            return None;
        }
        Some(PhotonSums {
            kernel: (sums.kernel + change.sums.kernel).max(SampledSpectrum::ZERO),
            laplacian: sums.laplacian + change.sums.laplacian,
            cut: sums.cut,
        })
    }

    /// `sums` with every photon within the radius of its visible point added.
    fn weigh_near<'a>(&self, mut sums: Weigher<'a>) -> Weigher<'a> {
        let p = sums.vp.p;
        self.grid.for_each_near(p, |range| {
            self.positions.for_each_within(range, p, self.kernel.r2, |i, d2| {
                sums.add(&self.sorted[i], d2, || self.positions.at(i))
            });
        });
        sums
    }
}

/// A photon set's first round at a visible point: its sums, and the walls its photons showed.
#[derive(Clone, Copy, Default)]
pub struct FirstRound {
    sums: PhotonSums,
    walls: [Wall; 3],
    behind_a_wall: bool,
}

impl FirstRound {
    /// Whether its photons showed a wall the point lies behind (a sum over its set then leaves
    /// out the photons across it).
    pub fn behind_a_wall(&self) -> bool {
        self.behind_a_wall
    }
}

/// What the photons of several sets of one radius (frames sharing photons add their own to the
/// shared ones) add up to at `vp`, from each set's first round there. Where the point lies behind
/// a wall that any set's photons showed, every set is weighed again with all the walls known, so
/// that the sum is the one set of all the photons gives.
pub fn sum_over(vp: &VisiblePoint, rounds: &[(&PhotonSet, FirstRound)]) -> PhotonSums {
    let sums = if rounds.iter().any(|(_, first)| first.behind_a_wall) {
        let walls = rounds.iter().fold([Wall::default(); 3], |walls, (_, first)| {
            std::array::from_fn(|axis| walls[axis].or_if_cutting_more(first.walls[axis]))
        });
        rounds.iter().map(|(set, _)| set.sum_beside(vp, walls)).reduce(|a, b| a + b)
    } else {
        rounds.iter().map(|(_, first)| first.sums).reduce(|a, b| a + b)
    };
    sums.unwrap_or_default()
}

/// `items` (at `position`) bucketed for lookups within `radius`, in parallel: the grid, what
/// `arrival` reads of each item, in bucket order, and their positions in that order, kept apart.
pub(super) fn bucketed<I: Sync, A: Send>(
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
pub(super) struct Positions {
    x: Vec<f32>,
    y: Vec<f32>,
    z: Vec<f32>,
}

impl Positions {
    pub(super) fn new(points: impl ExactSizeIterator<Item = Vec3>) -> Self {
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

    pub(super) fn at(&self, i: usize) -> Vec3 {
        Vec3::new(self.x[i], self.y[i], self.z[i])
    }

    /// Calls `visit(i, d2)` for each photon `i` in `range` at squared distance `d2 < r2` from
    /// `p`. About one candidate in six is within reach, unpredictably: four distances are tested
    /// at a time, without branches, and only the hits are visited.
    #[inline]
    pub(super) fn for_each_within(
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

/// Sums photons' contributions at one visible point. The kernel and its Laplacian are sums of
/// each photon's flux times a number; for a diffuse surface the BSDF is the same for every photon
/// from the side it is seen from, and multiplies the sums once at the end.
///
/// A photon on a surface meeting the point's at an edge (a wall standing on the floor the point
/// is on) gives the wall's plane, which cuts the disc. Photons of the point's surface across that
/// plane are not the point's: they lie on the far side of the wall (a thin partition's other
/// side, lit while this one is dark), and the kernel mass there is cut off. Walls turn up as
/// photons do, so where the point is seen to lie behind one (a photon on the wall's other face),
/// the photons are weighed again with the walls known, those across them left out. Where every
/// wall faces the point (a room's walls, from its floor) nothing of the floor lies across them.
struct Weigher<'a> {
    kernel: &'a Kernel,
    vp: &'a VisiblePoint,
    /// The geometric normal on the side the point is seen from.
    front: Vec3,
    /// For a diffuse surface without a normal map, the cosine of the direction it is seen from
    /// (photons count from the same side of the shading normal) and its BSDF value.
    diffuse: Option<(f32, SampledSpectrum)>,
    /// The factor on the flux of a photon that carries its hero wavelength alone.
    hero_only_scale: f32,
    flux_kernel: SampledSpectrum,
    flux_laplacian: SampledSpectrum,
    /// Per axis of their normals, the walls found that cut the most off the disc.
    walls: [Wall; 3],
    /// A wall that cuts the disc and rises above the point's surface faces away from the point:
    /// the point lies behind it. (Below the surface, a wall facing away is the side of the block
    /// whose top the point is on, and nothing of the top lies across it.)
    behind_a_wall: bool,
    /// Walls found by an earlier round: photons across them are left out.
    known_walls: Option<[Wall; 3]>,
}

impl<'a> Weigher<'a> {
    fn new(kernel: &'a Kernel, vp: &'a VisiblePoint, known_walls: Option<[Wall; 3]>) -> Self {
        let diffuse = match vp.bsdf {
            Bsdf::Diffuse { albedo } if !vp.frame.is_bent() => {
                Some((vp.frame.n().dot(vp.wo), albedo * FRAC_1_PI))
            }
            _ => None,
        };
        Weigher {
            kernel,
            vp,
            front: vp.frame.ng() * vp.frame.ng().dot(vp.wo).signum(),
            diffuse,
            hero_only_scale: if vp.hero_only() { 1.0 / LANES as f32 } else { 1.0 },
            flux_kernel: SampledSpectrum::ZERO,
            flux_laplacian: SampledSpectrum::ZERO,
            walls: [Wall::default(); 3],
            behind_a_wall: false,
            known_walls,
        }
    }

    /// Adds `photon`, at squared distance `d2 < r^2`. Photons on surfaces meeting the point's at
    /// an edge add a wall; those facing away lie behind (the back of a thin wall), and those
    /// across a known wall lie beyond it.
    #[inline]
    fn add(&mut self, photon: &Arrival, d2: f32, at: impl FnOnce() -> Vec3) {
        let facing = photon.ng.dot(self.front);
        if facing < EDGE_COSINE {
            if facing > -EDGE_COSINE {
                self.add_wall(photon, at());
            }
            return;
        }
        if let Some(walls) = &self.known_walls {
            let p = at();
            if walls.iter().any(|w| w.mass > 0.0 && w.separates(p)) {
                return;
            }
        }
        let flux = if photon.hero_only { photon.flux * self.hero_only_scale } else { photon.flux };
        let weighted = match self.diffuse {
            Some((cos_wo, _)) if photon.wi.dot(self.vp.frame.n()) * cos_wo > 0.0 => flux,
            Some(_) => return,
            None => {
                let frame = self.vp.frame;
                flux * self.vp.bsdf.eval(frame, self.vp.wo, photon.wi) * frame.photon_cosine_ratio(photon.wi)
            }
        };
        let t2 = d2 / self.kernel.r2;
        self.flux_kernel += weighted * ((1.0 - t2) * (1.0 - t2));
        self.flux_laplacian += weighted * (1.0 - 2.0 * t2);
    }

    /// Adds a photon at `at` on a wall: its wall, where that cuts more off the disc than the walls
    /// found before with normals along the same axis.
    fn add_wall(&mut self, photon: &Arrival, at: Vec3) {
        let wall = self.kernel.wall(photon.ng, at, self.vp.p, self.vp.frame.ng());
        let rises_above_point = (at - self.vp.p).dot(self.front) > 0.0;
        self.behind_a_wall |= wall.mass > 0.0 && wall.point_side < 0.0 && rises_above_point;
        Wall::keep_widest(&mut self.walls, wall, photon.ng);
    }

    fn finish(self) -> PhotonSums {
        let bsdf = self.diffuse.map_or(SampledSpectrum::ONE, |(_, f)| f);
        PhotonSums {
            kernel: self.flux_kernel * bsdf * self.kernel.scale,
            laplacian: self.flux_laplacian * bsdf * self.kernel.laplacian_scale,
            cut: Wall::cut(&self.walls),
        }
    }
}

/// Every pixel's estimate from its eye result and the pass's photons.
pub fn gather(eye: &[EyeResult], set: &PhotonSet) -> Vec<PixelEstimate> {
    eye.par_iter()
        .with_min_len(64)
        .map(|e| set.estimate(e, e.point.map_or(PhotonSums::default(), |vp| set.sum_at(&vp))))
        .collect()
}

/// What the photons near a visible point add up to, before the path throughput.
///
/// Near an edge of its surface (where a wall meets the floor, or a table top ends) the gather
/// disc reaches past the surface, where no photons of it land: the kernel sum alone would
/// darken every room's corners by up to half. A photon on a surface meeting the point's at an
/// edge (a wall's, seen from the floor) gives that surface's plane, and so the line where it cuts
/// the disc; the scene's open edges give the rest ([`OpenEdges`]). The sum is divided by the
/// kernel mass left within the disc (renormalised kernel density estimation). The cut mass is
/// kept per axis of the direction across the edge, the largest of each, so that a corner's two
/// walls both count, an edge found both ways counts once, and sums over photon sets merge in any
/// order (frames sharing photons sum two sets).
#[derive(Clone, Copy, Debug, Default)]
pub struct PhotonSums {
    /// Kernel-weighted reflected flux.
    kernel: SampledSpectrum,
    /// The same with the kernel's Laplacian.
    laplacian: SampledSpectrum,
    /// Kernel mass cut off by edges, per axis of the direction across the edge.
    cut: Vec3,
}

/// The least kernel mass an estimate is divided by (where edges cut off more, as at the tip of
/// a sharp wedge, they are not trusted to be straight).
const LEAST_MASS_WITHIN: f32 = 0.25;

impl PhotonSums {
    /// The kernel mass within the surface.
    fn kernel_mass_within(&self) -> f32 {
        kernel_mass_within(self.cut)
    }
}

impl std::ops::Add for PhotonSums {
    type Output = PhotonSums;
    fn add(self, o: PhotonSums) -> PhotonSums {
        PhotonSums {
            kernel: self.kernel + o.kernel,
            laplacian: self.laplacian + o.laplacian,
            cut: self.cut.max(o.cut),
        }
    }
}

/// The kernel mass left within a surface whose edges cut `cut` off the disc, per axis.
pub(super) fn kernel_mass_within(cut: Vec3) -> f32 {
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
