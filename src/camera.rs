//! The camera: film position (and a lens point) to a primary ray.
//!
//! The camera looks down its local -z with +y up (glTF's convention). Its projection is
//! perspective (`yfov`, the vertical field of view), orthographic (glTF's `ymag`, half the film's
//! height) or Blender's equirectangular panorama (longitude and latitude ranges, as Cycles maps
//! them: longitude 0 straight ahead, growing to the right). Blender's lens shift moves the film
//! in its plane. Without a lens the camera is a pinhole and never draws a lens sample. With one it is a
//! thin lens (pbrt-v4 section 5.2.3): rays start on the aperture (a disc, or a regular polygon of
//! `blades` sides) and pass through the point the pinhole ray meets on the plane in focus.

use glam::{Mat4, Vec2, Vec3};

use crate::sampling::{square_to_disc, square_to_triangle};

/// The thin lens of a camera (aperture radius = focal length / (2 f-stop), as Cycles computes it).
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

/// How the film maps to rays.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Projection {
    /// Rays from one point.
    Perspective {
        /// tan(yfov / 2).
        tan_half_fov_y: f32,
    },
    /// Parallel rays from the film.
    Orthographic {
        /// Half the film's height, scene units.
        half_height: f32,
    },
    /// Rays in every direction of the ranges.
    Equirectangular {
        /// Longitudes of the film's left and right edges, radians (0 ahead, growing rightward).
        longitude: [f32; 2],
        /// Latitudes of the film's bottom and top edges, radians.
        latitude: [f32; 2],
    },
}

impl Projection {
    /// Its name, for reports.
    pub fn name(&self) -> &'static str {
        match self {
            Projection::Perspective { .. } => "perspective",
            Projection::Orthographic { .. } => "orthographic",
            Projection::Equirectangular { .. } => "equirectangular panorama",
        }
    }
}

/// A camera in world space.
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
    /// How the film maps to rays.
    pub projection: Projection,
    /// The film's offset in its plane, in film heights (Blender's lens shift).
    pub shift: Vec2,
    /// The thin lens, or `None` for a pinhole.
    pub lens: Option<Lens>,
}

impl Camera {
    /// The camera of a node with world matrix `world`, its projection and its film's shift.
    pub fn from_node(world: Mat4, projection: Projection, shift: Vec2) -> Self {
        Camera {
            position: world.transform_point3(Vec3::ZERO),
            right: world.transform_vector3(Vec3::X).normalize(),
            up: world.transform_vector3(Vec3::Y).normalize(),
            forward: world.transform_vector3(-Vec3::Z).normalize(),
            projection,
            shift,
            lens: None,
        }
    }

    /// A perspective camera of vertical field of view `yfov` (radians), unshifted.
    pub fn perspective(world: Mat4, yfov: f32) -> Self {
        Camera::from_node(world, Projection::Perspective { tan_half_fov_y: (yfov / 2.0).tan() }, Vec2::ZERO)
    }

    /// The same camera with `lens` (a pinhole when `None` or of zero aperture; a panorama has no
    /// lens).
    pub fn with_lens(self, lens: Option<Lens>) -> Self {
        let panorama = matches!(self.projection, Projection::Equirectangular { .. });
        Camera { lens: lens.filter(|l| l.aperture_radius > 0.0 && !panorama), ..self }
    }

    /// Where `film` lies on the film plane, in half film heights from the centre of the
    /// unshifted film, x to the right and y up.
    fn film_plane(&self, film: Vec2, aspect: f32) -> Vec2 {
        Vec2::new((2.0 * film.x - 1.0) * aspect, 1.0 - 2.0 * film.y) + 2.0 * self.shift
    }

    /// The film position of a point `(x, y)` of the film plane (the inverse of `film_plane`).
    fn film_of_plane(&self, plane: Vec2, aspect: f32) -> Vec2 {
        let p = plane - 2.0 * self.shift;
        Vec2::new((p.x / aspect + 1.0) / 2.0, (1.0 - p.y) / 2.0)
    }

    /// The ray through `film` from the lens point `u` (ignored by a pinhole).
    pub fn ray_through_lens(&self, film: Vec2, aspect: f32, u: Vec2) -> (Vec3, Vec3) {
        let (origin, direction) = self.ray(film, aspect);
        let Some(lens) = self.lens else { return (origin, direction) };
        let focus = origin + direction * (lens.focus_distance / direction.dot(self.forward));
        let origin = self.lens_point(u);
        (origin, (focus - origin).normalize())
    }

    /// The point of the aperture that the uniform sample `u` picks (the camera's position for a
    /// pinhole); every point of the aperture is as likely.
    pub fn lens_point(&self, u: Vec2) -> Vec3 {
        let Some(lens) = self.lens else { return self.position };
        let p = aperture_point(&lens, u) * lens.aperture_radius;
        self.position + self.right * p.x + self.up * p.y
    }

    /// Where the point `p` appears on the film through the aperture point `lens_point` (the
    /// inverse of [`Camera::ray_through_lens`]: the film position whose ray from there passes
    /// through `p`), or `None` behind the lens. A pinhole's is [`Camera::project`]'s.
    pub fn project_through_lens(&self, p: Vec3, lens_point: Vec3, aspect: f32) -> Option<Vec2> {
        let Some(lens) = self.lens else { return self.project(p, aspect) };
        let along = (p - lens_point).dot(self.forward);
        if !(along > 0.0) {
            return None;
        }
        // The ray from the lens point through `p` meets the plane in focus where the pinhole ray
        // of the same film position does.
        let focus = lens_point + (p - lens_point) * (lens.focus_distance / along);
        self.project(focus, aspect)
    }

    /// The ray through `film`, in [0, 1]^2 with (0, 0) the top-left corner, for an image of
    /// width / height `aspect`. Returns (origin, unit direction).
    pub fn ray(&self, film: Vec2, aspect: f32) -> (Vec3, Vec3) {
        match self.projection {
            Projection::Perspective { tan_half_fov_y } => {
                let p = self.film_plane(film, aspect) * tan_half_fov_y;
                (self.position, (self.forward + p.x * self.right + p.y * self.up).normalize())
            }
            Projection::Orthographic { half_height } => {
                let p = self.film_plane(film, aspect) * half_height;
                (self.position + p.x * self.right + p.y * self.up, self.forward)
            }
            Projection::Equirectangular { longitude, latitude } => {
                let lon = longitude[0] + (longitude[1] - longitude[0]) * film.x;
                let lat = latitude[1] + (latitude[0] - latitude[1]) * film.y;
                let (sin_lon, cos_lon) = lon.sin_cos();
                let (sin_lat, cos_lat) = lat.sin_cos();
                let local =
                    self.forward * (cos_lat * cos_lon) + self.right * (cos_lat * sin_lon) + self.up * sin_lat;
                (self.position, local.normalize())
            }
        }
    }

    /// How large the film is where it sees `p`: the square root of the area the whole image
    /// covers on the plane through `p` facing the camera (at `p`'s distance for a panorama), in
    /// scene units; `None` behind the camera. A pixel's footprint there is this over the square
    /// root of the image's pixels.
    pub fn film_size_at(&self, p: Vec3, aspect: f32) -> Option<f32> {
        let d = p - self.position;
        let z = d.dot(self.forward);
        match self.projection {
            Projection::Perspective { tan_half_fov_y } => {
                (z > 0.0).then(|| 2.0 * z * tan_half_fov_y * aspect.sqrt())
            }
            Projection::Orthographic { half_height } => (z > 0.0).then(|| 2.0 * half_height * aspect.sqrt()),
            Projection::Equirectangular { longitude, latitude } => {
                let solid = ((longitude[1] - longitude[0]) * (latitude[1] - latitude[0])).abs();
                Some(d.length() * solid.sqrt())
            }
        }
    }

    /// Where the point `p` appears on the film (the inverse of [`Camera::ray`]), or `None`
    /// behind the camera.
    pub fn project(&self, p: Vec3, aspect: f32) -> Option<Vec2> {
        let d = p - self.position;
        let (x, y, z) = (d.dot(self.right), d.dot(self.up), d.dot(self.forward));
        match self.projection {
            Projection::Perspective { tan_half_fov_y } => {
                (z > 0.0).then(|| self.film_of_plane(Vec2::new(x, y) / (z * tan_half_fov_y), aspect))
            }
            Projection::Orthographic { half_height } => {
                (z > 0.0).then(|| self.film_of_plane(Vec2::new(x, y) / half_height, aspect))
            }
            Projection::Equirectangular { longitude, latitude } => {
                let lon = x.atan2(z);
                let lat = (y / d.length()).clamp(-1.0, 1.0).asin();
                Some(Vec2::new(
                    (lon - longitude[0]) / (longitude[1] - longitude[0]),
                    (lat - latitude[1]) / (latitude[0] - latitude[1]),
                ))
            }
        }
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
    use std::f32::consts::PI;

    #[test]
    fn project_inverts_ray_for_every_projection() {
        let world = Mat4::from_rotation_y(0.3) * Mat4::from_translation(Vec3::new(1.0, 2.0, 3.0));
        let panorama = Projection::Equirectangular { longitude: [-3.0, 3.0], latitude: [-1.5, 1.2] };
        for projection in [
            Projection::Perspective { tan_half_fov_y: 0.4 },
            Projection::Orthographic { half_height: 2.0 },
            panorama,
        ] {
            let camera = Camera::from_node(world, projection, Vec2::new(0.1, -0.05));
            let film = Vec2::new(0.2, 0.7);
            let (origin, direction) = camera.ray(film, 1.5);
            let back = camera.project(origin + 5.0 * direction, 1.5).unwrap();
            assert!((back - film).length() < 1e-5, "{projection:?}: {back}");
        }
    }

    #[test]
    fn the_film_size_at_a_point_is_the_root_of_the_area_the_image_covers_there() {
        let world = Mat4::from_rotation_y(0.3) * Mat4::from_translation(Vec3::new(1.0, 2.0, 3.0));
        let aspect = 1.5;
        for projection in
            [Projection::Perspective { tan_half_fov_y: 0.4 }, Projection::Orthographic { half_height: 2.0 }]
        {
            let camera = Camera::from_node(world, projection, Vec2::new(0.1, -0.05));
            // The image's corners on the plane 5 units ahead.
            let on_plane = |film: Vec2| {
                let (origin, direction) = camera.ray(film, aspect);
                let depth = 5.0 - (origin - camera.position).dot(camera.forward);
                origin + direction * (depth / direction.dot(camera.forward))
            };
            let corner = on_plane(Vec2::ZERO);
            let width = (on_plane(Vec2::X) - corner).length();
            let height = (on_plane(Vec2::Y) - corner).length();
            let p = on_plane(Vec2::new(0.3, 0.8));
            let size = camera.film_size_at(p, aspect).unwrap();
            assert!((size - (width * height).sqrt()).abs() < 1e-4 * size, "{projection:?}: {size}");
            assert_eq!(camera.film_size_at(camera.position - 5.0 * camera.forward, aspect), None);
        }
    }

    #[test]
    fn a_shift_of_half_the_film_height_moves_the_centre_to_the_top_edge() {
        let tan = 0.4;
        let camera = Camera::from_node(
            Mat4::IDENTITY,
            Projection::Perspective { tan_half_fov_y: tan },
            Vec2::new(0.0, 0.5),
        );
        let (_, direction) = camera.ray(Vec2::new(0.5, 0.5), 2.0);
        assert!((direction - Vec3::new(0.0, tan, -1.0).normalize()).length() < 1e-6, "{direction}");
    }

    #[test]
    fn a_full_panorama_looks_ahead_at_its_centre_and_behind_at_its_edges() {
        let full = Projection::Equirectangular { longitude: [-PI, PI], latitude: [-PI / 2.0, PI / 2.0] };
        let camera = Camera::from_node(Mat4::IDENTITY, full, Vec2::ZERO);
        let dir = |x: f32, y: f32| camera.ray(Vec2::new(x, y), 2.0).1;
        assert!((dir(0.5, 0.5) - -Vec3::Z).length() < 1e-6);
        assert!((dir(0.75, 0.5) - Vec3::X).length() < 1e-6, "a quarter to the right looks right");
        assert!((dir(0.0, 0.5) - Vec3::Z).length() < 1e-6);
        assert!((dir(0.5, 0.0) - Vec3::Y).length() < 1e-6, "the top row looks up");
    }
}

#[cfg(test)]
mod lens_tests {
    use super::*;

    #[test]
    fn a_point_seen_through_the_lens_projects_back_to_the_film_position_of_its_ray() {
        let lens = Lens { aperture_radius: 0.2, focus_distance: 3.0, blades: 6, blade_rotation: 0.1 };
        let camera = Camera::perspective(Mat4::IDENTITY, 0.8).with_lens(Some(lens));
        for i in 0..50 {
            let film = Vec2::new((i as f32 * 0.618034).fract(), (i as f32 * 0.754878).fract());
            let u = Vec2::new((i as f32 * 0.3819).fract(), (i as f32 * 0.5698).fract());
            let (origin, direction) = camera.ray_through_lens(film, 1.5, u);
            assert!(origin.distance(camera.lens_point(u)) < 1e-6);
            for distance in [0.5, 3.0, 20.0] {
                let back = camera.project_through_lens(origin + direction * distance, origin, 1.5).unwrap();
                assert!(back.distance(film) < 1e-4, "{film} came back as {back} from {distance}");
            }
        }
    }

    #[test]
    fn lens_rays_meet_on_the_plane_in_focus() {
        let lens = Lens { aperture_radius: 0.1, focus_distance: 4.0, blades: 0, blade_rotation: 0.0 };
        let camera = Camera::perspective(Mat4::IDENTITY, 0.8).with_lens(Some(lens));
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
