//! Open edges: where a surface ends in the open (a wall's front edge, a table top's rim, the
//! border of a plane). The gather's disc reaches past such an edge, where no photons of the
//! surface land, and renormalises its kernel by the distance to it (`transport/kernel.rs`).
//!
//! An edge is open when one triangle alone has it, after welding corners at equal positions
//! across every mesh (exporters split vertices at seams and sharp edges; two meshes that share a
//! border share its corners). The still triangles' open edges are found and bucketed once; the
//! moving triangles' open sides are found once, and their edges bucketed again in each pose.

use std::collections::HashMap;
use std::sync::Arc;

use glam::{IVec3, Vec3};

use super::Geometry;
use crate::geometry::{hash_cell, sort_into_buckets};

/// A triangle's side that no other triangle shares.
#[derive(Clone, Copy, Debug)]
struct OpenEdge {
    a: Vec3,
    b: Vec3,
    /// The triangle's unit normal.
    normal: Vec3,
    /// The unit direction in the triangle's plane, across the edge, away from the triangle.
    outward: Vec3,
}

/// The open edges of a scene at one time: those of the triangles that stay still, found and
/// bucketed once, and those of the moving triangles as posed.
#[derive(Debug, Default)]
pub struct OpenEdges {
    still: Arc<EdgeGrid>,
    moving: EdgeGrid,
}

/// Which sides of a geometry's triangles are open, as (triangle, side) pairs: found once, and
/// the same sides in any pose of those triangles.
#[derive(Debug, Default)]
pub struct OpenSides(Vec<(usize, usize)>);

/// Open edges bucketed by grid cells for lookups near a point.
#[derive(Debug, Default)]
struct EdgeGrid {
    edges: Vec<OpenEdge>,
    cell_size: f32,
    /// Bucket `k` lists the edges `entries[bucket_start[k]..bucket_start[k + 1]]`.
    bucket_start: Vec<u32>,
    entries: Vec<u32>,
}

/// Beyond this many open edges (a soup of loose triangles: foliage, particles) none are looked
/// up, as the grid would take gigabytes; the gather still finds walls from their photons.
const MOST_OPEN_EDGES: usize = 250_000;

/// Surfaces whose normals are within this cosine of each other are taken as one surface.
const SAME_SURFACE_COSINE: f32 = 0.9;

/// How far off a surface's plane (in radii) an edge may lie and still bound it (tessellated
/// curved surfaces).
const PLANE_TOLERANCE: f32 = 0.25;

impl OpenEdges {
    /// The open edges of `geometry` (the still triangles), bucketed for lookups of radius about
    /// `cell_size`.
    pub fn of(geometry: &Geometry, cell_size: f32) -> Self {
        let cell_size = cell_size.max(f32::MIN_POSITIVE);
        let edges = OpenSides::of(geometry).edges(geometry);
        OpenEdges { still: Arc::new(EdgeGrid::new(edges, cell_size)), moving: EdgeGrid::default() }
    }

    /// These edges and those of `moving` (posed triangles whose open sides are `sides`).
    pub fn with_moving(&self, moving: &Geometry, sides: &OpenSides) -> Self {
        OpenEdges {
            still: Arc::clone(&self.still),
            moving: EdgeGrid::new(sides.edges(moving), self.still.cell_size),
        }
    }

    /// How many edges are open.
    pub fn len(&self) -> usize {
        self.still.edges.len() + self.moving.edges.len()
    }

    /// Whether no edge is open.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// For a point `p` on a surface of normal `n`: the distance within the surface to its nearest
    /// open edge closer than `reach`, per axis of the direction across the edge (infinite where
    /// there is none), so that two edges meeting at a corner both count.
    pub fn distances(&self, p: Vec3, n: Vec3, reach: f32) -> Vec3 {
        self.still.distances(p, n, reach).min(self.moving.distances(p, n, reach))
    }
}

impl OpenSides {
    /// Every triangle side of `geometry` that no other triangle shares (corners welded by
    /// position); none when there are more than [`MOST_OPEN_EDGES`].
    pub fn of(geometry: &Geometry) -> Self {
        let mut welded: HashMap<[u32; 3], u32> = HashMap::new();
        let ids: Vec<u32> = geometry
            .positions
            .iter()
            .map(|p| {
                let next = welded.len() as u32;
                // + 0.0 makes -0.0 the same key as 0.0.
                *welded.entry(p.to_array().map(|c| (c + 0.0).to_bits())).or_insert(next)
            })
            .collect();
        let mut sides: HashMap<(u32, u32), (u32, usize, usize)> = HashMap::new();
        for (t, triangle) in geometry.triangles.iter().enumerate() {
            for k in 0..3 {
                let (i, j) = (triangle.vertices[k], triangle.vertices[(k + 1) % 3]);
                let key = (ids[i as usize].min(ids[j as usize]), ids[i as usize].max(ids[j as usize]));
                sides.entry(key).and_modify(|(count, _, _)| *count += 1).or_insert((1, t, k));
            }
        }
        let mut open: Vec<(usize, usize)> =
            sides.into_values().filter(|&(count, _, _)| count == 1).map(|(_, t, k)| (t, k)).collect();
        if open.len() > MOST_OPEN_EDGES {
            return OpenSides::default();
        }
        open.sort_unstable();
        OpenSides(open)
    }

    /// Whether no side is open.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// The open edges these sides are in `geometry` (a pose of the triangles they were found in).
    fn edges(&self, geometry: &Geometry) -> Vec<OpenEdge> {
        self.0.iter().filter_map(|&(t, k)| open_edge(geometry, t, k)).collect()
    }
}

impl EdgeGrid {
    /// `edges` bucketed by cells of `cell_size`.
    fn new(edges: Vec<OpenEdge>, cell_size: f32) -> Self {
        let mut pairs: Vec<(IVec3, u32)> = Vec::new();
        for (i, edge) in edges.iter().enumerate() {
            pairs.extend(cells_near_segment(edge.a, edge.b, cell_size).into_iter().map(|c| (c, i as u32)));
        }
        let buckets = (2 * pairs.len()).max(1);
        let bucket_of: Vec<u32> = pairs.iter().map(|&(c, _)| hash_cell(c, buckets) as u32).collect();
        let (bucket_start, order) = sort_into_buckets(&bucket_of, buckets);
        let entries = order.iter().map(|&i| pairs[i as usize].1).collect();
        EdgeGrid { edges, cell_size, bucket_start, entries }
    }

    /// [`OpenEdges::distances`] over these edges.
    fn distances(&self, p: Vec3, n: Vec3, reach: f32) -> Vec3 {
        let mut nearest = Vec3::INFINITY;
        if self.edges.is_empty() {
            return nearest;
        }
        let buckets = self.bucket_start.len() - 1;
        let extent = Vec3::splat((reach - self.cell_size).max(0.0));
        let lo = ((p - extent) / self.cell_size).floor().as_ivec3();
        let hi = ((p + extent) / self.cell_size).floor().as_ivec3();
        for z in lo.z..=hi.z {
            for y in lo.y..=hi.y {
                for x in lo.x..=hi.x {
                    let b = hash_cell(IVec3::new(x, y, z), buckets);
                    let listed =
                        &self.entries[self.bucket_start[b] as usize..self.bucket_start[b + 1] as usize];
                    for &e in listed {
                        let edge = &self.edges[e as usize];
                        if let Some(d) = edge.distance_within_surface(p, n, reach) {
                            let axis = edge.outward.abs().max_position();
                            nearest[axis] = nearest[axis].min(d);
                        }
                    }
                }
            }
        }
        nearest
    }
}

impl OpenEdge {
    /// The distance from `p` (on a surface of normal `n`) to this edge within the surface, when
    /// the edge bounds that surface on `p`'s side and lies within `reach`.
    fn distance_within_surface(&self, p: Vec3, n: Vec3, reach: f32) -> Option<f32> {
        if self.normal.dot(n).abs() < SAME_SURFACE_COSINE {
            return None;
        }
        let height = (p - self.a).dot(self.normal);
        if height.abs() > PLANE_TOLERANCE * reach {
            return None;
        }
        let q = p - height * self.normal;
        if (q - self.a).dot(self.outward) > 0.0 {
            return None;
        }
        let along = self.b - self.a;
        let t = ((q - self.a).dot(along) / along.length_squared()).clamp(0.0, 1.0);
        let d = q.distance(self.a + t * along);
        (d < reach).then_some(d)
    }
}

/// Side `k` (corners `k` and `k + 1`) of triangle `t`, or `None` for a degenerate triangle.
fn open_edge(geometry: &Geometry, t: usize, k: usize) -> Option<OpenEdge> {
    let corners = geometry.triangles[t].vertices.map(|v| geometry.positions[v as usize]);
    let (a, b, c) = (corners[k], corners[(k + 1) % 3], corners[(k + 2) % 3]);
    let normal = (corners[1] - corners[0]).cross(corners[2] - corners[0]).normalize_or_zero();
    let mut outward = (b - a).cross(normal).normalize_or_zero();
    if normal == Vec3::ZERO || outward == Vec3::ZERO || !outward.is_finite() {
        return None;
    }
    if (c - a).dot(outward) > 0.0 {
        outward = -outward;
    }
    Some(OpenEdge { a, b, normal, outward })
}

/// The grid cells within a cell of any point of the segment `a`-`b` (and a few more): the cells
/// around each piece of it one cell long.
fn cells_near_segment(a: Vec3, b: Vec3, cell_size: f32) -> Vec<IVec3> {
    let pieces = ((b - a).length() / cell_size).ceil().clamp(1.0, 1e6) as usize;
    let mut cells = Vec::new();
    for k in 0..pieces {
        let (start, end) = (a.lerp(b, k as f32 / pieces as f32), a.lerp(b, (k + 1) as f32 / pieces as f32));
        let lo = ((start.min(end) - Vec3::splat(cell_size)) / cell_size).floor().as_ivec3();
        let hi = ((start.max(end) + Vec3::splat(cell_size)) / cell_size).floor().as_ivec3();
        for z in lo.z..=hi.z {
            for y in lo.y..=hi.y {
                for x in lo.x..=hi.x {
                    cells.push(IVec3::new(x, y, z));
                }
            }
        }
    }
    cells.sort_unstable_by_key(|c| c.to_array());
    cells.dedup();
    cells
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::TriangleRef;

    /// A unit square on the floor (y = 0, normal up) of two triangles, with its corners given
    /// twice (as an exporter splits them) so that welding matters.
    fn floor_square() -> Geometry {
        let corners = [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 0.0, -1.0), Vec3::new(0.0, 0.0, -1.0)];
        let positions = [corners, corners].concat();
        Geometry {
            normals: vec![Vec3::ZERO; positions.len()],
            uvs: vec![glam::Vec2::ZERO; positions.len()],
            extras: Default::default(),
            positions,
            triangles: vec![
                TriangleRef { vertices: [0, 1, 2], material: 0 },
                TriangleRef { vertices: [4, 6, 7], material: 0 },
            ],
        }
    }

    #[test]
    fn a_squares_border_is_open_and_its_diagonal_is_not() {
        let edges = OpenEdges::of(&floor_square(), 0.1);
        assert_eq!(edges.len(), 4);
        let d = edges.distances(Vec3::new(0.03, 0.0, -0.5), Vec3::Y, 0.1);
        assert!((d.x - 0.03).abs() < 1e-6, "{d}");
        assert_eq!((d.y, d.z), (f32::INFINITY, f32::INFINITY));
        let corner = edges.distances(Vec3::new(0.95, 0.0, -0.02), Vec3::Y, 0.1);
        assert!((corner.x - 0.05).abs() < 1e-6 && (corner.z - 0.02).abs() < 1e-6, "{corner}");
        let middle = edges.distances(Vec3::new(0.5, 0.0, -0.5), Vec3::Y, 0.1);
        assert_eq!(middle, Vec3::INFINITY);
    }

    #[test]
    fn edges_of_other_surfaces_and_from_outside_do_not_count() {
        let edges = OpenEdges::of(&floor_square(), 0.1);
        let on_a_wall = edges.distances(Vec3::new(0.03, 0.05, -0.5), Vec3::X, 0.1);
        assert_eq!(on_a_wall, Vec3::INFINITY);
        let beyond = edges.distances(Vec3::new(-0.03, 0.0, -0.5), Vec3::Y, 0.1);
        assert_eq!(beyond, Vec3::INFINITY);
        let far_above = edges.distances(Vec3::new(0.03, 0.05, -0.5), Vec3::Y, 0.1);
        assert_eq!(far_above, Vec3::INFINITY);
    }

    #[test]
    fn a_soup_of_loose_triangles_is_not_searched() {
        let count = MOST_OPEN_EDGES / 3 + 1;
        let positions: Vec<Vec3> = (0..count)
            .flat_map(|i| {
                let o = Vec3::new(i as f32, 0.0, 0.0);
                [o, o + Vec3::new(0.5, 0.0, 0.0), o + Vec3::new(0.0, 0.0, -0.5)]
            })
            .collect();
        let soup = Geometry {
            normals: vec![Vec3::ZERO; positions.len()],
            uvs: vec![glam::Vec2::ZERO; positions.len()],
            extras: Default::default(),
            triangles: (0..count as u32)
                .map(|i| TriangleRef { vertices: [3 * i, 3 * i + 1, 3 * i + 2], material: 0 })
                .collect(),
            positions,
        };
        let edges = OpenEdges::of(&soup, 0.1);
        assert!(edges.is_empty(), "{} open edges kept", edges.len());
        assert_eq!(edges.distances(Vec3::new(0.1, 0.0, -0.1), Vec3::Y, 0.1), Vec3::INFINITY);
    }

    #[test]
    fn a_radius_larger_than_the_cells_finds_far_edges() {
        let edges = OpenEdges::of(&floor_square(), 0.01);
        let d = edges.distances(Vec3::new(0.3, 0.0, -0.5), Vec3::Y, 0.35);
        assert!((d.x - 0.3).abs() < 1e-6, "{d}");
    }
}
