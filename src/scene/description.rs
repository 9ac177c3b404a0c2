//! What a scene file says, independent of time: mesh instances in their nodes' local space,
//! lights and the camera attached to nodes, the node rig with its animation, materials and the
//! scene-wide settings from the `caustic` extras. [`super::pose`] turns it into a render-ready
//! [`super::Scene`] at a time.

use glam::{Mat3, Mat4, Vec2, Vec3};

use super::animation::Rig;
use super::{TriangleRef, VertexExtras};
pub use crate::camera::Lens;
use crate::camera::Projection;
use crate::geometry::Cone;
use crate::lights::{SphereLight, SpotFalloff, World};
use crate::materials::{Material, Volume};
use crate::spectrum::Illuminant;

/// Triangles attached to a node, in the node's local space.
#[derive(Clone, Debug)]
pub struct MeshInstance {
    /// The glTF node it hangs from.
    pub node: usize,
    /// The mesh's name, for messages.
    pub name: String,
    /// Local vertex positions.
    pub positions: Vec<Vec3>,
    /// Local vertex normals (zero where the file has none: the face normal is used).
    pub normals: Vec<Vec3>,
    /// Texture coordinates of the first set (zero where the file has none).
    pub uvs: Vec<Vec2>,
    /// Attributes only some meshes have, in local space.
    pub extras: super::VertexExtras,
    /// Triangles, indexing this instance's vertices.
    pub triangles: Vec<TriangleRef>,
    /// Its skin and morph targets, if it has either.
    pub deformation: Option<Box<super::deform::Deformation>>,
}

impl MeshInstance {
    /// This mesh with its vertices moved by `m` (an instance's transform within its node): positions,
    /// normals and tangents turned, the winding kept facing out where `m` mirrors.
    pub fn transformed(&self, m: Mat4) -> MeshInstance {
        let linear = Mat3::from_mat4(m);
        let normal_matrix = linear.inverse().transpose();
        let mut extras = VertexExtras::default();
        extras.append(0, &self.extras, self.positions.len(), linear);
        let mirrored = linear.determinant() < 0.0;
        let triangles = self.triangles.iter().map(|t| {
            let [a, b, c] = t.vertices;
            super::TriangleRef {
                vertices: if mirrored { [a, c, b] } else { [a, b, c] },
                material: t.material,
            }
        });
        MeshInstance {
            node: self.node,
            name: self.name.clone(),
            positions: self.positions.iter().map(|&p| m.transform_point3(p)).collect(),
            normals: self.normals.iter().map(|&n| (normal_matrix * n).normalize_or_zero()).collect(),
            uvs: self.uvs.clone(),
            extras,
            triangles: triangles.collect(),
            deformation: None,
        }
    }
}

/// A punctual light's kind and emission (see `crate::lights` for units).
#[derive(Clone, Debug)]
pub enum PunctualKind {
    /// A point or spot light, at the origin shining down -z (its node's pose places it).
    Sphere(SphereLight),
    /// Irradiance, W/m^2, and the sun's disc.
    Sun(Illuminant, Cone),
}

impl PunctualKind {
    /// This light with the animated `values`.
    pub fn set(&mut self, values: &super::values::LightValues) {
        match self {
            PunctualKind::Sun(irradiance, _) => *irradiance = values.emitted,
            PunctualKind::Sphere(sphere) => {
                sphere.intensity = values.emitted;
                if let Some(beam) = &mut sphere.beam {
                    beam.outer = values.outer.unwrap_or(beam.outer);
                    if let (Some(inner), SpotFalloff::Gltf { inner: cone }) =
                        (values.inner, &mut beam.falloff)
                    {
                        *cone = inner;
                    }
                }
            }
        }
    }
}

/// A `KHR_lights_punctual` light on a node (it shines down the node's local -z).
#[derive(Clone, Debug)]
pub struct PunctualLight {
    /// The glTF node.
    pub node: usize,
    /// What it emits (at rest).
    pub kind: PunctualKind,
    /// Its animated colour, intensity and cone, if any.
    pub animation: Option<Box<super::values::LightAnimation>>,
}

/// The camera on its node.
#[derive(Clone, Debug)]
pub struct CameraInstance {
    /// The glTF node.
    pub node: usize,
    /// How its film maps to rays.
    pub projection: Projection,
    /// Its film's offset in its plane, in film heights (Blender's lens shift).
    pub shift: Vec2,
    /// The file's aspect ratio, if any.
    pub aspect_ratio: Option<f32>,
    /// Focal length in millimetres (from the extras, else from the field of view and a 36 mm
    /// sensor width), for the aperture.
    pub focal_length_mm: f32,
    /// The lens from the extras (`None`: a pinhole unless flags give an f-stop).
    pub lens: Option<LensSettings>,
    /// Its animated field of view, if any.
    pub animation: Option<Box<super::values::CameraAnimation>>,
}

/// Depth-of-field settings as the user gives them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LensSettings {
    /// f-number (0: a pinhole).
    pub fstop: f32,
    /// Focus distance, scene units.
    pub focus_distance: f32,
    /// Aperture blades.
    pub blades: u32,
    /// Blade rotation, degrees.
    pub blade_rotation_deg: f32,
}

/// The shutter: open for `length` frames, placed around the frame as Blender places it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shutter {
    /// Open time in frames, relative to the frame (START: 0, CENTER: -length/2, END: -length).
    pub open: f32,
    /// Length in frames (0: no motion blur).
    pub length: f32,
}

impl Shutter {
    /// No motion blur.
    pub const CLOSED: Shutter = Shutter { open: 0.0, length: 0.0 };
}

/// Everything the file says.
#[derive(Debug)]
pub struct Description {
    /// Every node's motion.
    pub rig: Rig,
    /// Meshes (and area lights, as emitting triangles) on their nodes.
    pub meshes: Vec<MeshInstance>,
    /// Meshes drawn by the instances of still nodes, each kept once (`EXT_mesh_gpu_instancing`).
    pub instanced: Vec<super::instancing::InstancedMesh>,
    /// Punctual lights on their nodes.
    pub lights: Vec<PunctualLight>,
    /// The camera.
    pub camera: CameraInstance,
    /// Materials (at rest).
    pub materials: Vec<Material>,
    /// The animated materials (by index) and their animations.
    pub material_animations: Vec<(usize, super::values::MaterialAnimation)>,
    /// The world, if any.
    pub world: Option<World>,
    /// The medium filling the world outside every closed transmissive mesh, if any.
    pub fog: Option<Volume>,
    /// Resolution from the extras.
    pub resolution: Option<[u32; 2]>,
    /// The film is transparent where the camera sees the world (Blender's Film > Transparent).
    pub transparent_film: bool,
    /// Frames per second (the extras' `fps`, 24 when absent).
    pub fps: f32,
    /// The shutter from the extras.
    pub shutter: Shutter,
    /// What was skipped or assumed while loading.
    pub warnings: Vec<String>,
}
