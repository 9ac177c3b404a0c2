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

    /// Where the point `p` appears on the film (the inverse of [`Camera::ray`]), or `None`
    /// behind the camera.
    pub fn project(&self, p: Vec3, aspect: f32) -> Option<Vec2> {
        let d = p - self.position;
        let z = d.dot(self.forward);
        if z <= 0.0 {
            return None;
        }
        let x = d.dot(self.right) / (z * self.tan_half_fov_y * aspect);
        let y = d.dot(self.up) / (z * self.tan_half_fov_y);
        Some(Vec2::new((x + 1.0) / 2.0, (1.0 - y) / 2.0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn project_inverts_ray() {
        let camera = Camera::from_node(
            Mat4::from_rotation_y(0.3) * Mat4::from_translation(Vec3::new(1.0, 2.0, 3.0)),
            0.8,
        );
        let film = Vec2::new(0.2, 0.7);
        let (origin, direction) = camera.ray(film, 1.5);
        let back = camera.project(origin + 5.0 * direction, 1.5).unwrap();
        assert!((back - film).length() < 1e-5, "{back}");
    }
}
