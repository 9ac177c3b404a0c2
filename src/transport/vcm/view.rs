//! The camera as a path vertex: the density of its rays' directions per unit of film area in
//! pixels, and where a point it sees lands on the film (light tracing).
//!
//! Light paths reach a perspective camera, a pinhole or a thin lens. Through a lens, light tracing
//! picks a point of the aperture as the camera's own rays do (uniformly), and the point lands
//! where the ray from there through it meets the plane in focus; the density of the camera's ray
//! from a lens point is the pinhole's formula in that ray's direction (the plane in focus is the
//! film scaled), so the weights are the pinhole's. Another projection cannot be met, and light
//! tracing is left out of the weights as well as the image.

use glam::{Vec2, Vec3};

use crate::camera::{Camera, Projection};
use crate::transport::context::Crop;

/// The camera of a pass.
#[derive(Clone, Copy, Debug)]
pub struct View {
    camera: Camera,
    crop: Crop,
    /// Width over height of the whole image.
    aspect: f32,
    /// The distance, in pixels, of the image plane from the pinhole: a pixel covers unit area
    /// there. `None` where light paths cannot reach the camera.
    plane_distance: Option<f32>,
}

/// Where a point lands on the film.
#[derive(Clone, Copy, Debug)]
pub struct Landing {
    /// The film pixel (row-major within the crop).
    pub pixel: usize,
    /// Unit direction from the point toward the camera.
    pub toward: Vec3,
    /// Distance to the camera.
    pub distance: f32,
    /// The camera's density of the ray per solid angle, in pixels.
    pub pdf: f32,
}

impl View {
    /// The view of `camera` for a film of `crop`.
    pub fn new(camera: Camera, crop: Crop) -> Self {
        let [width, height] = crop.image.map(|n| n as f32);
        let plane_distance = match camera.projection {
            Projection::Perspective { tan_half_fov_y } => Some(height / (2.0 * tan_half_fov_y)),
            _ => None,
        };
        View { camera, crop, aspect: width / height, plane_distance }
    }

    /// Whether light paths can reach the camera.
    pub fn traces_lights(&self) -> bool {
        self.plane_distance.is_some()
    }

    /// Whether light tracing draws a point of a lens.
    pub fn has_lens(&self) -> bool {
        self.camera.lens.is_some()
    }

    /// The density per solid angle, in pixels, of a camera ray along the unit `direction` (1 where
    /// light paths cannot reach the camera: the weights then leave light tracing out).
    pub fn pdf(&self, direction: Vec3) -> f32 {
        match self.plane_distance {
            Some(d) => {
                let cos = direction.dot(self.camera.forward);
                if cos > 0.0 {
                    d * d / (cos * cos * cos)
                } else {
                    0.0
                }
            }
            None => 1.0,
        }
    }

    /// Where `p` lands on the film seen from the aperture point the uniform sample `u_lens` picks
    /// (a pinhole has one), if the camera sees that way and the pixel is the film's.
    pub fn landing(&self, p: Vec3, u_lens: Vec2) -> Option<Landing> {
        self.plane_distance?;
        let lens_point = self.camera.lens_point(u_lens);
        let film = self.camera.project_through_lens(p, lens_point, self.aspect)?;
        let [width, height] = self.crop.image.map(|n| n as f32);
        let (x, y) = (film.x * width, film.y * height);
        let [x0, y0] = self.crop.origin.map(|n| n as f32);
        let [w, h] = self.crop.size;
        let (fx, fy) = ((x - x0).floor(), (y - y0).floor());
        if !(fx >= 0.0 && fy >= 0.0 && fx < w as f32 && fy < h as f32) {
            return None;
        }
        let offset = lens_point - p;
        let distance = offset.length();
        let toward = offset / distance;
        let pdf = self.pdf(-toward);
        (distance > 0.0 && pdf > 0.0).then_some(Landing {
            pixel: fy as usize * w as usize + fx as usize,
            toward,
            distance,
            pdf,
        })
    }
}
