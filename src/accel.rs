//! Ray queries against the scene's triangles: compressed wide BVHs (obvhs' CWBVH, Ylitie et al.
//! 2017) over world-space triangles, one for the fixed part of a time range (built once, shared)
//! and one for the moving part (built per pose, small), and a two-level one for still instanced
//! meshes (a BVH per mesh in its own space under a BVH over the instances' boxes).
//!
//! Takes triangle corners; gives closest hits (triangle index, distance, barycentrics) and
//! occlusion tests, which pass through triangles that cast no shadow (area lights). Triangle
//! indices number the fixed part first, then the instanced triangles, then the moving part, as
//! `Scene` does.

use std::sync::{Arc, Mutex};
use std::time::Duration;

use crate::geometry::corners_scale;
use glam::{Mat3, Mat4, Vec2, Vec3, Vec3A};
use obvhs::{
    aabb::Aabb,
    cwbvh::{
        builder::{build_cwbvh, build_cwbvh_from_tris},
        CwBvh,
    },
    ray::{Ray, RayHit},
    triangle::Triangle,
    BvhBuildParams,
};

/// The closest intersection along a ray.
#[derive(Clone, Copy, Debug)]
pub struct Hit {
    /// Index of the triangle in the scene's list.
    pub triangle: u32,
    /// Distance along the (unit) ray direction.
    pub t: f32,
    /// Barycentric coordinates of the hit (weights of corners 1 and 2).
    pub barycentric: Vec2,
    /// The point hit, interpolated from the corners with the barycentric coordinates.
    pub p: Vec3,
    /// The triangle's unit geometric normal (zero for a degenerate triangle).
    pub ng: Vec3,
    /// The largest coordinate of the triangle's corners (for offsetting rays that leave it).
    pub scale: f32,
}

/// The nearest triangle along a ray of one BVH, as traversal finds it.
#[derive(Clone, Copy, Debug)]
struct Nearest {
    /// Where the triangle is among the BVH's leaves.
    slot: u32,
    /// Index of the triangle in the BVH's list.
    triangle: u32,
    /// Distance along the ray, in the BVH's working coordinates.
    t: f32,
}

/// One BVH over a list of triangles.
///
/// obvhs culls every node that a ray leaves within 1e-4 units of its origin (its CWBVH node test
/// clamps the entry distance to a fixed 1e-4): hits nearer than that are lost, which in a scene
/// 1e-4 units wide is nearly all of them, and at unit scale loses contact shadows and thin gaps.
/// So each BVH works in coordinates multiplied by a power of two (exact in floating point, so
/// nothing else changes) that brings its largest coordinate near 2^20, where 1e-4 units are
/// 1e-10 of the scene; huge coordinates (1e30) come down to it too, where obvhs's surface-area
/// costs would overflow.
pub struct Bvh {
    bvh: Option<CwBvh>,
    /// The triangles in working coordinates, in the order of the BVH's leaves (its primitive
    /// slots), so that the triangle test reads them without going through the slot's index.
    triangles: Vec<Triangle>,
    /// Working coordinates over world coordinates (a power of two).
    scale: f32,
    /// Per slot, whether its triangle blocks shadow rays.
    casts_shadow: Vec<bool>,
}

/// The power of two that brings the largest finite coordinate of `corners` near 2^20.
fn working_scale(corners: &[[Vec3; 3]]) -> f32 {
    let largest =
        corners.iter().flatten().filter(|v| v.is_finite()).map(|v| v.abs().max_element()).fold(0.0, f32::max);
    if largest <= 0.0 {
        return 1.0;
    }
    2f32.powi((20 - largest.log2().ceil() as i32).clamp(-100, 100))
}

/// Where an instance's mesh lies in the world.
#[derive(Clone, Copy, Debug)]
pub struct Placement {
    /// Its mesh's index.
    pub mesh: u32,
    /// The mesh's space to the world.
    pub to_world: Mat4,
    /// What turns the mesh's normals into the world's (the inverse transpose of `to_world`'s
    /// linear part).
    pub normal: Mat3,
    /// Its first triangle's number among the instanced ones.
    pub first: u32,
}

impl Placement {
    /// Instance `mesh` placed by `to_world`, its triangles numbered from `first`.
    pub fn new(mesh: u32, to_world: Mat4, first: u32) -> Self {
        Placement { mesh, to_world, normal: Mat3::from_mat4(to_world).inverse().transpose(), first }
    }
}

/// Meshes drawn many times (a two-level BVH): one BVH per mesh in its own space, and a BVH over
/// the instances' world boxes whose leaves carry a ray into their instance's mesh. Memory grows
/// with the meshes, not with the instances.
pub struct InstancedBvh {
    meshes: Vec<Bvh>,
    instances: Vec<Placement>,
    /// Each instance's world to its mesh's space.
    to_local: Vec<Mat4>,
    top: Option<CwBvh>,
    /// The top BVH's working coordinates over world coordinates (as [`Bvh`]'s).
    scale: f32,
    /// How many triangles the instances draw.
    triangles: u32,
}

impl InstancedBvh {
    /// The BVHs of `meshes` (each the corners of its triangles in its own space) placed by
    /// `instances`.
    pub fn build(meshes: &[Vec<[Vec3; 3]>], instances: &[Placement]) -> Self {
        let boxes: Vec<(Vec3, Vec3)> =
            instances.iter().map(|i| world_box(&meshes[i.mesh as usize], i.to_world)).collect();
        let corners: Vec<[Vec3; 3]> = boxes.iter().map(|&(lo, hi)| [lo, hi, hi]).collect();
        let scale = working_scale(&corners);
        let aabbs: Vec<Aabb> =
            boxes.iter().map(|&(lo, hi)| Aabb::new((lo * scale).into(), (hi * scale).into())).collect();
        let top = (!aabbs.is_empty())
            .then(|| build_cwbvh(&aabbs, BvhBuildParams::medium_build(), &mut Duration::default()));
        InstancedBvh {
            meshes: meshes.iter().map(|m| Bvh::build(m, &vec![true; m.len()], BuildFor::Range)).collect(),
            to_local: instances.iter().map(|i| i.to_world.inverse()).collect(),
            triangles: instances
                .iter()
                .map(|i| i.first + meshes[i.mesh as usize].len() as u32)
                .max()
                .unwrap_or(0),
            instances: instances.to_vec(),
            top,
            scale,
        }
    }

    /// The nearest instanced triangle along the ray before `t_max`: its instance, and where it
    /// is in the instance's mesh BVH (its distance in world units).
    fn nearest(&self, origin: Vec3, direction: Vec3, t_max: f32) -> Option<(usize, Nearest, f32)> {
        let top = self.top.as_ref()?;
        let ray =
            Ray::new((origin * self.scale).into(), (direction + Vec3::ZERO).into(), 0.0, t_max * self.scale);
        let mut hit = RayHit::none();
        let mut best: Option<(usize, Nearest, f32)> = None;
        top.ray_traverse(ray, &mut hit, |ray, slot| {
            let instance = top.primitive_indices[slot] as usize;
            let limit = ray.tmax / self.scale;
            let (o, d) = self.local_ray(instance, origin, direction);
            let mesh = &self.meshes[self.instances[instance].mesh as usize];
            match mesh.nearest(o, d, limit, false) {
                Some(n) => {
                    let t = n.t / mesh.scale;
                    best = Some((instance, n, t));
                    t * self.scale
                }
                None => f32::INFINITY,
            }
        });
        best.filter(|b| b.2 < t_max)
    }

    /// The ray in instance `instance`'s mesh space (the direction not normalised, so that
    /// distances along it are the world's).
    fn local_ray(&self, instance: usize, origin: Vec3, direction: Vec3) -> (Vec3, Vec3) {
        let m = &self.to_local[instance];
        (m.transform_point3(origin), m.transform_vector3(direction))
    }

    /// The hit at `nearest` in instance `instance`, in world coordinates; triangles are numbered
    /// from `first_triangle`.
    fn hit(
        &self,
        instance: usize,
        nearest: Nearest,
        origin: Vec3,
        direction: Vec3,
        first_triangle: u32,
    ) -> Hit {
        let placed = &self.instances[instance];
        let (o, d) = self.local_ray(instance, origin, direction);
        let local = self.meshes[placed.mesh as usize].hit(nearest, o, d);
        let p = placed.to_world.transform_point3(local.p);
        // How far rounding can have moved the point: the local figure grown by the transform, and
        // the point's own size.
        let stretch =
            Mat3::from_mat4(placed.to_world).to_cols_array().iter().fold(0.0f32, |m, v| m.max(v.abs()));
        Hit {
            triangle: first_triangle + placed.first + local.triangle,
            p,
            ng: (placed.normal * local.ng).normalize_or_zero(),
            scale: (3.0 * stretch * local.scale).max(p.abs().max_element()),
            ..local
        }
    }

    /// Whether an instanced triangle lies on the ray before `t_max`.
    fn occluded(&self, origin: Vec3, direction: Vec3, t_max: f32) -> bool {
        let Some(top) = self.top.as_ref() else { return false };
        let ray =
            Ray::new((origin * self.scale).into(), (direction + Vec3::ZERO).into(), 0.0, t_max * self.scale);
        !top.ray_traverse_miss(ray, |_, slot| {
            let instance = top.primitive_indices[slot] as usize;
            let (o, d) = self.local_ray(instance, origin, direction);
            match self.meshes[self.instances[instance].mesh as usize].occluded(o, d, t_max) {
                true => 0.0,
                false => f32::INFINITY,
            }
        })
    }
}

/// The world box of `corners` moved by `to_world`.
fn world_box(corners: &[[Vec3; 3]], to_world: Mat4) -> (Vec3, Vec3) {
    let points = corners.iter().flatten().map(|&c| to_world.transform_point3(c)).filter(|p| p.is_finite());
    points.fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| (lo.min(p), hi.max(p)))
}

/// The scene's BVHs: the fixed part (shared between poses) and the moving part.
pub struct Accel {
    fixed: Arc<Bvh>,
    moving: Bvh,
    fixed_count: u32,
    /// The instanced meshes (their triangles numbered after the fixed ones, before the moving
    /// ones), if any.
    instanced: Option<Arc<InstancedBvh>>,
    /// How many triangles the instances draw.
    instanced_count: u32,
    /// Every query asked, when recording (`caustic bench` replays them to time bare traversal).
    recorder: Option<Mutex<Vec<RecordedRay>>>,
}

/// What a query asked for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Query {
    /// The closest hit.
    Closest,
    /// The closest hit on a triangle that casts shadows.
    ClosestOpaque,
    /// Whether a triangle that casts shadows is in the way.
    Occluded,
}

/// One query, as asked.
#[derive(Clone, Copy, Debug)]
pub struct RecordedRay {
    origin: Vec3,
    direction: Vec3,
    t_max: f32,
    query: Query,
}

impl Accel {
    /// A BVH over `corners`, all fixed and all casting shadows.
    pub fn build(corners: &[[Vec3; 3]]) -> Self {
        Accel::new(Arc::new(Bvh::build(corners, &vec![true; corners.len()], BuildFor::Range)), Bvh::empty())
    }

    /// The fixed part's BVH with the moving part's (numbered after the fixed and instanced triangles).
    pub fn new(fixed: Arc<Bvh>, moving: Bvh) -> Self {
        let fixed_count = fixed.triangles.len() as u32;
        Accel { fixed, moving, fixed_count, instanced: None, instanced_count: 0, recorder: None }
    }

    /// This accelerator with `instanced` meshes too.
    pub fn with_instances(self, instanced: Option<Arc<InstancedBvh>>) -> Self {
        let instanced_count = instanced.as_ref().map_or(0, |i| i.triangles);
        Accel { instanced, instanced_count, ..self }
    }

    /// This accelerator, recording every query from now on.
    pub fn recording(self) -> Self {
        Accel { recorder: Some(Mutex::new(Vec::new())), ..self }
    }

    /// The queries recorded so far (in the order threads asked them).
    pub fn recorded(&self) -> Vec<RecordedRay> {
        self.recorder.as_ref().map_or_else(Vec::new, |r| r.lock().expect("recorder").clone())
    }

    /// Asks `rays` again (bare traversal, nothing else); gives how many hit.
    pub fn replay(&self, rays: &[RecordedRay]) -> usize {
        let answer = |r: &RecordedRay| match r.query {
            Query::Closest => self.nearest(r.origin, r.direction, r.t_max, false).is_some(),
            Query::ClosestOpaque => self.nearest(r.origin, r.direction, r.t_max, true).is_some(),
            Query::Occluded => self.blocked(r.origin, r.direction, r.t_max),
        };
        rays.iter().filter(|r| answer(r)).count()
    }

    #[inline]
    fn note(&self, origin: Vec3, direction: Vec3, t_max: f32, query: Query) {
        if let Some(recorder) = &self.recorder {
            recorder.lock().expect("recorder").push(RecordedRay { origin, direction, t_max, query });
        }
    }

    /// The closest hit along the ray from `origin` in the unit `direction` before `t_max`.
    pub fn intersect(&self, origin: Vec3, direction: Vec3, t_max: f32) -> Option<Hit> {
        self.note(origin, direction, t_max, Query::Closest);
        self.closest(origin, direction, t_max, false)
    }

    /// The closest hit on a triangle that casts shadows (what photons meet: they pass through
    /// area lights as if they were not there).
    pub fn intersect_opaque(&self, origin: Vec3, direction: Vec3, t_max: f32) -> Option<Hit> {
        self.note(origin, direction, t_max, Query::ClosestOpaque);
        self.closest(origin, direction, t_max, true)
    }

    fn closest(&self, origin: Vec3, direction: Vec3, t_max: f32, opaque_only: bool) -> Option<Hit> {
        let found = self.nearest(origin, direction, t_max, opaque_only);
        if let Some(instanced) = &self.instanced {
            let limit = found.as_ref().map_or(t_max, |(bvh, n, _)| n.t / bvh.scale);
            if let Some((instance, nearest, _)) = instanced.nearest(origin, direction, limit) {
                return Some(instanced.hit(instance, nearest, origin, direction, self.fixed_count));
            }
        }
        let (bvh, nearest, first_triangle) = found?;
        let hit = bvh.hit(nearest, origin, direction);
        Some(Hit { triangle: hit.triangle + first_triangle, ..hit })
    }

    /// The nearest triangle along the ray (traversal alone): the BVH it is in, where in it, and
    /// the scene's number of that BVH's first triangle.
    fn nearest(
        &self,
        origin: Vec3,
        direction: Vec3,
        t_max: f32,
        opaque_only: bool,
    ) -> Option<(&Bvh, Nearest, u32)> {
        let fixed = self.fixed.nearest(origin, direction, t_max, opaque_only);
        let t_fixed = fixed.map_or(t_max, |n| n.t / self.fixed.scale);
        match self.moving.nearest(origin, direction, t_fixed, opaque_only) {
            Some(moving) => Some((&self.moving, moving, self.fixed_count + self.instanced_count)),
            None => fixed.map(|f| (&*self.fixed, f, 0)),
        }
    }

    /// Whether anything that casts shadows lies on the ray from `origin` in the unit `direction`
    /// before `t_max`.
    pub fn occluded(&self, origin: Vec3, direction: Vec3, t_max: f32) -> bool {
        self.note(origin, direction, t_max, Query::Occluded);
        self.blocked(origin, direction, t_max)
    }

    fn blocked(&self, origin: Vec3, direction: Vec3, t_max: f32) -> bool {
        self.fixed.occluded(origin, direction, t_max)
            || self.moving.occluded(origin, direction, t_max)
            || self.instanced.as_ref().is_some_and(|i| i.occluded(origin, direction, t_max))
    }

    /// Whether a moving triangle that casts shadows lies on the ray before `t_max` (the fixed part
    /// is not tested).
    pub fn moving_occluded(&self, origin: Vec3, direction: Vec3, t_max: f32) -> bool {
        self.moving.occluded(origin, direction, t_max)
    }

    /// Whether any moving triangle (casting shadows or not) lies on the ray before `t_max`.
    pub fn moving_hit(&self, origin: Vec3, direction: Vec3, t_max: f32) -> bool {
        self.moving.nearest(origin, direction, t_max, false).is_some()
    }

    /// The box around the moving triangles, or `None` when nothing moves.
    pub fn moving_bounds(&self) -> Option<(Vec3, Vec3)> {
        let scale = self.moving.scale;
        let corners =
            self.moving.triangles.iter().flat_map(|t| [t.v0, t.v1, t.v2]).map(|v| Vec3::from(v) / scale);
        corners.map(|p| (p, p)).reduce(|(a, b), (c, d)| (a.min(c), b.max(d)))
    }
}

/// What a BVH is built for, which sets how much its build may cost.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BuildFor {
    /// The still part of a time range: built once, traced by every pass (obvhs' medium build).
    Range,
    /// The moving part at one time: built for every pose, which is every pass under motion blur
    /// (obvhs' very fast build: on a skinned column of 125,000 triangles under motion blur, a
    /// pass takes 17% less than with the medium build, and with one pose per frame tracing is
    /// no slower, 1.12 s against 1.11 s for 32 passes).
    Pose,
}

impl Bvh {
    /// A BVH over no triangles (the moving part of a still scene).
    pub fn empty() -> Self {
        Bvh::build(&[], &[], BuildFor::Pose)
    }

    /// Builds the BVH over `corners` (one entry per triangle), with whether each casts shadows,
    /// for the use `built_for` says.
    pub fn build(corners: &[[Vec3; 3]], casts_shadow: &[bool], built_for: BuildFor) -> Self {
        debug_assert_eq!(corners.len(), casts_shadow.len());
        let scale = working_scale(corners);
        // A triangle a transform has sent to infinity cannot be hit; it becomes a point (never hit)
        // so that the BVH's bounds stay finite and triangle numbers stay in step with the scene.
        let triangles: Vec<Triangle> = corners
            .iter()
            .map(|c| c.map(|v| v * scale))
            .map(|c| if c.iter().all(|v| v.is_finite()) { c } else { [Vec3::ZERO; 3] })
            .map(|c| Triangle { v0: c[0].into(), v1: c[1].into(), v2: c[2].into() })
            .collect();
        if triangles.is_empty() {
            return Bvh { bvh: None, triangles, scale, casts_shadow: Vec::new() };
        }
        let params = match built_for {
            BuildFor::Range => BvhBuildParams::medium_build(),
            BuildFor::Pose => BvhBuildParams::very_fast_build(),
        };
        let bvh = build_cwbvh_from_tris(&triangles, params, &mut Duration::default());
        let in_slots = |i: &u32| *i as usize;
        Bvh {
            triangles: bvh.primitive_indices.iter().map(in_slots).map(|i| triangles[i]).collect(),
            casts_shadow: bvh.primitive_indices.iter().map(in_slots).map(|i| casts_shadow[i]).collect(),
            bvh: Some(bvh),
            scale,
        }
    }

    /// The obvhs ray, in working coordinates, for a world-space ray.
    fn ray(&self, origin: Vec3, direction: Vec3, t_max: f32) -> Ray {
        // obvhs misses everything along a direction with a -0.0 component (its traversal order
        // takes the component's sign as positive while 1 / -0.0 is -inf); adding +0.0 turns -0.0
        // into +0.0 and changes nothing else. Lights pointing straight down (Blender's default
        // sun) give such directions.
        Ray::new((origin * self.scale).into(), (direction + Vec3::ZERO).into(), 0.0, t_max * self.scale)
    }

    /// The nearest triangle along the ray from `origin` in the unit `direction` before `t_max`,
    /// among the triangles that cast shadows if `opaque_only`.
    fn nearest(&self, origin: Vec3, direction: Vec3, t_max: f32, opaque_only: bool) -> Option<Nearest> {
        let bvh = self.bvh.as_ref()?;
        let ray = self.ray(origin, direction, t_max);
        let mut hit = RayHit::none();
        let found = bvh.ray_traverse(ray, &mut hit, |ray, slot| self.hit_distance(ray, slot, opaque_only));
        let slot = hit.primitive_id;
        found.then(|| Nearest { slot, triangle: bvh.primitive_indices[slot as usize], t: hit.t })
    }

    /// The hit at `nearest` along the ray from `origin` in the unit `direction`, in world
    /// coordinates. The surface there is computed from the BVH's own copy of the corners, which
    /// traversal has just read, rather than from the scene's vertex arrays. Working coordinates
    /// are world coordinates times a power of two, so every figure is the same bits as from the
    /// world corners.
    fn hit(&self, nearest: Nearest, origin: Vec3, direction: Vec3) -> Hit {
        // In SIMD vectors (the corners are stored so), converted once at the end.
        let Triangle { v0, v1, v2 } = self.triangles[nearest.slot as usize];
        let normal = (v1 - v0).cross(v2 - v0);
        let at = Vec3A::from(origin) * self.scale + Vec3A::from(direction) * nearest.t;
        let barycentric = barycentric(v0, v1 - v0, v2 - v0, normal, at);
        let w = [1.0 - barycentric.x - barycentric.y, barycentric.x, barycentric.y];
        let largest = corners_scale([v0, v1, v2]);
        // The inverse of a power of two: multiplying by it is dividing, exactly.
        let to_world = self.scale.recip();
        Hit {
            triangle: nearest.triangle,
            t: nearest.t * to_world,
            barycentric,
            p: ((v0 * w[0] + v1 * w[1] + v2 * w[2]) * to_world).into(),
            ng: normal.normalize_or_zero().into(),
            scale: largest * to_world,
        }
    }

    /// Whether anything that casts shadows lies on the ray from `origin` in the unit `direction`
    /// before `t_max`.
    pub fn occluded(&self, origin: Vec3, direction: Vec3, t_max: f32) -> bool {
        let Some(bvh) = self.bvh.as_ref() else {
            return false;
        };
        let ray = self.ray(origin, direction, t_max);
        !bvh.ray_traverse_miss(ray, |ray, slot| self.hit_distance(ray, slot, true))
    }

    /// The distance to the triangle in `slot` along `ray`; infinite for triangles that cast no
    /// shadow when `opaque_only`.
    fn hit_distance(&self, ray: &Ray, slot: usize, opaque_only: bool) -> f32 {
        if opaque_only && !self.casts_shadow[slot] {
            return f32::INFINITY;
        }
        self.triangles[slot].intersect(ray)
    }
}

/// The barycentric coordinates (weights of v1 and v2) of `p`, a point on the triangle with
/// corner `v0`, edges `e1` and `e2` from it, and normal `n = e1 x e2`.
fn barycentric(v0: Vec3A, e1: Vec3A, e2: Vec3A, n: Vec3A, p: Vec3A) -> Vec2 {
    let inv = 1.0 / n.length_squared();
    let d = p - v0;
    let b1 = d.cross(e2).dot(n) * inv;
    let b2 = e1.cross(d).dot(n) * inv;
    Vec2::new(b1, b2).clamp(Vec2::ZERO, Vec2::ONE)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::offset_origin;

    #[test]
    fn hits_the_closest_of_two_triangles_and_maps_its_index() {
        let quad = |z: f32| [Vec3::new(-1.0, -1.0, z), Vec3::new(1.0, -1.0, z), Vec3::new(0.0, 1.0, z)];
        let accel = Accel::build(&[quad(5.0), quad(2.0)]);
        let hit = accel.intersect(Vec3::ZERO, Vec3::Z, f32::INFINITY).unwrap();
        assert_eq!(hit.triangle, 1);
        assert!((hit.t - 2.0).abs() < 1e-6);
        assert!(accel.occluded(Vec3::ZERO, Vec3::Z, 3.0));
        assert!(!accel.occluded(Vec3::ZERO, Vec3::Z, 1.5));
        assert!(accel.intersect(Vec3::ZERO, -Vec3::Z, f32::INFINITY).is_none());
        // Barycentrics weight corners 1 and 2.
        let origin = Vec3::new(0.3, -0.2, 0.0);
        let hit = accel.intersect(origin, Vec3::Z, f32::INFINITY).unwrap();
        let c = quad(2.0);
        let b = hit.barycentric;
        let p = c[0] * (1.0 - b.x - b.y) + c[1] * b.x + c[2] * b.y;
        assert!((p - (origin + Vec3::Z * hit.t)).length() < 1e-5, "{p}");
    }

    #[test]
    fn hits_nearer_than_obvhs_cull_distance_are_found_at_any_scale() {
        for scale in [1e-4f32, 1.0, 1e3] {
            let quad = |z: f32| {
                [Vec3::new(-1.0, -1.0, z), Vec3::new(1.0, -1.0, z), Vec3::new(0.0, 1.0, z)].map(|v| v * scale)
            };
            let accel = Accel::build(&[quad(2e-5), quad(1.0)]);
            let hit = accel.intersect(Vec3::ZERO, Vec3::Z, f32::INFINITY).expect("a hit");
            assert_eq!(hit.triangle, 0, "scale {scale}");
            assert!((hit.t / (2e-5 * scale) - 1.0).abs() < 1e-4, "scale {scale}: t {}", hit.t);
            assert!(accel.occluded(Vec3::ZERO, Vec3::Z, 3e-5 * scale), "scale {scale}");
        }
    }

    #[test]
    fn directions_with_negative_zero_components_hit() {
        let quad = [Vec3::new(-1.0, 2.0, -1.0), Vec3::new(-1.0, 2.0, 1.0), Vec3::new(1.0, 2.0, 0.0)];
        let accel = Accel::build(&[quad]);
        let origin = Vec3::new(-0.001, 0.0, 0.0004);
        for direction in
            [Vec3::new(-0.0, 1.0, -1.2e-7), Vec3::new(-0.0, 1.0, -0.0), Vec3::new(0.0, 1.0, -0.0)]
        {
            assert!(accel.occluded(origin, direction, f32::INFINITY), "{direction:?}");
            assert!(accel.intersect(origin, direction, f32::INFINITY).is_some(), "{direction:?}");
        }
    }

    #[test]
    fn offset_origins_leave_the_surface_at_any_scale() {
        for scale in [1e-4f32, 1.0, 1e5, 1e6] {
            let c = [Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0)]
                .map(|v| v * scale + Vec3::splat(scale * 0.3));
            let accel = Accel::build(&[c]);
            let p = (c[0] + c[1] + c[2]) / 3.0;
            let o = offset_origin(p, Vec3::Z, Vec3::new(0.3, 0.2, 1.0).normalize(), scale * 1.3);
            assert!(!accel.occluded(o, Vec3::new(0.3, 0.2, 1.0).normalize(), f32::INFINITY), "{scale}");
        }
    }
}
