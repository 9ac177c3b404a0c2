//! The gather (docs/design.md, step 4): at each visible point, the photons within the pass radius,
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

use glam::Vec3;
use rayon::prelude::*;
use std::f32::consts::FRAC_1_PI;
use std::sync::Arc;

use super::photons::Photon;
use super::visible::EyeResult;
use crate::materials::Bsdf;
use crate::scene::OpenEdges;
use crate::spectrum::{SampledSpectrum, LANES};
use crate::transport::context::{PixelEstimate, VisiblePoint};
use crate::transport::grid::{bucketed, PhotonGrid, Positions};
use crate::transport::kernel::{kernel_mass_within, Kernel, Wall, EDGE_COSINE};

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
