//! Tangents for normal maps where the file has none: MikkTSpace (Mikkelsen 2008, the
//! bevy_mikktspace crate), as Blender and the glTF sample viewer generate them, on texture coordinates with v
//! flipped back to Blender's (v up), so that a normal map's green channel points up the image as
//! it does in Blender.
//!
//! MikkTSpace gives each triangle corner its own tangent, so the mesh is unwelded first: every
//! corner becomes a vertex of its own (only normal-mapped meshes without tangents pay for it).

use glam::{Vec2, Vec3, Vec4};

use super::description::MeshInstance;
use super::TriangleRef;

/// The mesh's corners as seen by MikkTSpace, with the tangents it writes.
struct Corners<'a> {
    mesh: &'a MeshInstance,
    uvs: &'a [Vec2],
    tangents: Vec<Vec4>,
}

impl Corners<'_> {
    fn vertex(&self, face: usize, vert: usize) -> usize {
        self.mesh.triangles[face].vertices[vert] as usize
    }
}

impl bevy_mikktspace::Geometry for Corners<'_> {
    fn num_faces(&self) -> usize {
        self.mesh.triangles.len()
    }

    fn num_vertices_of_face(&self, _face: usize) -> usize {
        3
    }

    fn position(&self, face: usize, vert: usize) -> [f32; 3] {
        self.mesh.positions[self.vertex(face, vert)].to_array()
    }

    fn normal(&self, face: usize, vert: usize) -> [f32; 3] {
        self.mesh.normals[self.vertex(face, vert)].to_array()
    }

    fn tex_coord(&self, face: usize, vert: usize) -> [f32; 2] {
        let uv = self.uvs[self.vertex(face, vert)];
        [uv.x, 1.0 - uv.y]
    }

    fn set_tangent(&mut self, tangent: Option<bevy_mikktspace::TangentSpace>, face: usize, vert: usize) {
        // A corner MikkTSpace finds no tangent for (a degenerate face alone) keeps none.
        self.tangents[3 * face + vert] = tangent.map_or(Vec4::ZERO, |t| Vec4::from(t.tangent_encoded()));
    }
}

/// `mesh` unwelded, with MikkTSpace tangents for texture coordinate set `set`; `None` when
/// MikkTSpace finds none (no usable normals or texture coordinates).
pub fn with_generated_tangents(mesh: &MeshInstance, set: usize) -> Option<MeshInstance> {
    let uvs = if set == 0 { &mesh.uvs } else { &mesh.extras.uvs1 };
    // Texture coordinates that are all one point (none in the file) span no tangent plane.
    let spans = uvs.first().is_some_and(|first| uvs.iter().any(|uv| uv != first));
    if uvs.len() != mesh.positions.len() || !spans || mesh.normals.contains(&Vec3::ZERO) {
        return None;
    }
    let mut corners = Corners { mesh, uvs, tangents: vec![Vec4::ZERO; 3 * mesh.triangles.len()] };
    bevy_mikktspace::generate_tangents(&mut corners).ok()?;
    let tangents = corners.tangents;
    let order: Vec<usize> = mesh.triangles.iter().flat_map(|t| t.vertices.map(|v| v as usize)).collect();
    let pick = |values: &[Vec2]| order.iter().map(|&v| values[v]).collect::<Vec<_>>();
    let mut extras = mesh.extras.clone();
    extras.uvs1 = if extras.uvs1.is_empty() { Vec::new() } else { pick(&mesh.extras.uvs1) };
    extras.colours =
        order.iter().filter(|_| !mesh.extras.colours.is_empty()).map(|&v| mesh.extras.colours[v]).collect();
    extras.alphas =
        order.iter().filter(|_| !mesh.extras.alphas.is_empty()).map(|&v| mesh.extras.alphas[v]).collect();
    extras.tangents = tangents;
    let triangles = (0..mesh.triangles.len() as u32)
        .map(|k| TriangleRef {
            vertices: [3 * k, 3 * k + 1, 3 * k + 2],
            material: mesh.triangles[k as usize].material,
        })
        .collect();
    Some(MeshInstance {
        node: mesh.node,
        name: mesh.name.clone(),
        positions: order.iter().map(|&v| mesh.positions[v]).collect(),
        normals: order.iter().map(|&v| mesh.normals[v]).collect(),
        uvs: pick(&mesh.uvs),
        extras,
        triangles,
        deformation: mesh.deformation.as_ref().map(|d| Box::new(d.picked(&order))),
    })
}
