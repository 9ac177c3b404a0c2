//! The perspective camera: film position to a primary ray.
//!
//! A pinhole for now; the thin lens and the shutter come with the animation issue. The camera
//! looks down its local -z with +y up (glTF's convention); `yfov` is the vertical field of view.

use glam::{Mat4, Vec2, Vec3};

/// A perspective camera in world space.
#[derive(Clone, Copy, Debug)]
pub struct Camera {
    /// Centre of projection.
    pub position: Vec3,
    /// Unit vectors of the image's right, up, and the viewing direction.
    pub right: Vec3,
    /// Image up.
    pub up: Vec3,
    /// Viewing direction.
    pub forward: Vec3,
    /// tan(yfov / 2).
    pub tan_half_fov_y: f32,
}

impl Camera {
    /// The camera of a node with world matrix `world` and vertical field of view `yfov` (radians).
    pub fn from_node(world: Mat4, yfov: f32) -> Self {
        Camera {
            position: world.transform_point3(Vec3::ZERO),
            right: world.transform_vector3(Vec3::X).normalize(),
            up: world.transform_vector3(Vec3::Y).normalize(),
            forward: world.transform_vector3(-Vec3::Z).normalize(),
            tan_half_fov_y: (yfov / 2.0).tan(),
        }
    }

    /// The ray through `film`, in [0, 1]^2 with (0, 0) the top-left corner, for an image of
    /// width / height `aspect`. Returns (origin, unit direction).
    pub fn ray(&self, film: Vec2, aspect: f32) -> (Vec3, Vec3) {
        let x = (2.0 * film.x - 1.0) * self.tan_half_fov_y * aspect;
        let y = (1.0 - 2.0 * film.y) * self.tan_half_fov_y;
        let direction = (self.forward + x * self.right + y * self.up).normalize();
        (self.position, direction)
    }
}
