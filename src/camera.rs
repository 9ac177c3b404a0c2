//! The perspective camera: film position (and a lens point) to a primary ray.
//!
//! The camera looks down its local -z with +y up (glTF's convention); `yfov` is the vertical
//! field of view. Without a lens it is a pinhole and never draws a lens sample. With one it is a
//! thin lens (pbrt-v4 section 5.2.3): rays start on the aperture (a disc, or a regular polygon of
//! `blades` sides) and pass through the point the pinhole ray meets on the plane in focus.

use glam::{Mat4, Vec2, Vec3};

use crate::sampling::{square_to_disc, square_to_triangle};

/// The thin lens of a camera (DESIGN.md: aperture radius = focal length / (2 f-stop), as Cycles).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lens {
    /// Aperture radius in scene units (zero: a pinhole).
    pub aperture_radius: f32,
    /// Distance to the plane in focus, scene units.
    pub focus_distance: f32,
    /// Polygonal aperture blades (0 or fewer than 3: a round aperture).
    pub blades: u32,
    /// Rotation of the blades, radians.
    pub blade_rotation: f32,
}

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
    /// The thin lens, or `None` for a pinhole.
    pub lens: Option<Lens>,
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
            lens: None,
        }
    }

    /// The same camera with `lens` (a pinhole when `None` or of zero aperture).
    pub fn with_lens(self, lens: Option<Lens>) -> Self {
        Camera { lens: lens.filter(|l| l.aperture_radius > 0.0), ..self }
    }

    /// The ray through `film` from the lens point `u` (ignored by a pinhole).
    pub fn ray_through_lens(&self, film: Vec2, aspect: f32, u: Vec2) -> (Vec3, Vec3) {
        let (origin, direction) = self.ray(film, aspect);
        let Some(lens) = self.lens else { return (origin, direction) };
        let focus = origin + direction * (lens.focus_distance / direction.dot(self.forward));
        let p = aperture_point(&lens, u) * lens.aperture_radius;
        let origin = origin + self.right * p.x + self.up * p.y;
        (origin, (focus - origin).normalize())
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

/// A uniform point on the unit aperture: the disc, or a regular polygon of `blades` sides
/// inscribed in it (one of its equal triangular sectors, then a uniform point in that sector).
fn aperture_point(lens: &Lens, u: Vec2) -> Vec2 {
    if lens.blades < 3 {
        return square_to_disc(u);
    }
    let n = lens.blades as f32;
    let sector = (u.x * n).floor().min(n - 1.0);
    let b = square_to_triangle(Vec2::new(u.x * n - sector, u.y));
    let corner = |k: f32| {
        let angle = lens.blade_rotation + std::f32::consts::TAU * k / n;
        Vec2::new(angle.cos(), angle.sin())
    };
    corner(sector) * b.x + corner(sector + 1.0) * b.y
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

#[cfg(test)]
mod lens_tests {
    use super::*;

    #[test]
    fn lens_rays_meet_on_the_plane_in_focus() {
        let lens = Lens { aperture_radius: 0.1, focus_distance: 4.0, blades: 0, blade_rotation: 0.0 };
        let camera = Camera::from_node(Mat4::IDENTITY, 0.8).with_lens(Some(lens));
        let film = Vec2::new(0.3, 0.6);
        let (pinhole_origin, pinhole_dir) = camera.ray(film, 1.5);
        let focus = pinhole_origin + pinhole_dir * (4.0 / pinhole_dir.dot(camera.forward));
        for u in [Vec2::new(0.1, 0.9), Vec2::new(0.7, 0.2)] {
            let (o, d) = camera.ray_through_lens(film, 1.5, u);
            assert!(o.distance(pinhole_origin) > 0.0 && o.distance(pinhole_origin) <= 0.1 + 1e-6);
            let t = (focus - o).dot(d);
            assert!((o + d * t).distance(focus) < 1e-4);
        }
    }

    #[test]
    fn polygonal_apertures_stay_inside_their_polygon() {
        let lens = Lens { aperture_radius: 1.0, focus_distance: 1.0, blades: 5, blade_rotation: 0.3 };
        for i in 0..200 {
            let p =
                aperture_point(&lens, Vec2::new((i as f32 + 0.5) / 200.0, ((i * 37) % 200) as f32 / 200.0));
            // Inside the inscribed pentagon: within its apothem of every edge's normal.
            for k in 0..5 {
                let mid = lens.blade_rotation + std::f32::consts::TAU * (k as f32 + 0.5) / 5.0;
                assert!(p.dot(Vec2::new(mid.cos(), mid.sin())) <= (std::f32::consts::PI / 5.0).cos() + 1e-5);
            }
        }
    }
}
