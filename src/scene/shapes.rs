//! Area lights as emitting triangles in the light's local frame (emitting toward local -z).

use glam::Vec3;

use super::extras::{AreaLightExtras, AreaShape};

/// Segments of the polygon that stands for a disc or an ellipse.
const DISC_SEGMENTS: usize = 64;

/// The local-space triangles of an area light, wound so their normal is local -z.
pub fn area_light_triangles(light: &AreaLightExtras) -> Vec<[Vec3; 3]> {
    let size_y = match light.shape {
        AreaShape::Square | AreaShape::Disk => light.size,
        AreaShape::Rectangle | AreaShape::Ellipse => light.size_y.unwrap_or(light.size),
    };
    let (hx, hy) = (light.size / 2.0, size_y / 2.0);
    match light.shape {
        AreaShape::Square | AreaShape::Rectangle => {
            let c = [(-hx, -hy), (-hx, hy), (hx, hy), (hx, -hy)].map(|(x, y)| Vec3::new(x, y, 0.0));
            vec![[c[0], c[1], c[2]], [c[0], c[2], c[3]]]
        }
        AreaShape::Disk | AreaShape::Ellipse => (0..DISC_SEGMENTS)
            .map(|k| {
                let point = |k: usize| {
                    let phi = std::f32::consts::TAU * k as f32 / DISC_SEGMENTS as f32;
                    Vec3::new(hx * phi.cos(), hy * phi.sin(), 0.0)
                };
                [Vec3::ZERO, point(k + 1), point(k)]
            })
            .collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn area_lights_face_down_their_local_z() {
        for shape in [AreaShape::Square, AreaShape::Rectangle, AreaShape::Disk, AreaShape::Ellipse] {
            let light = AreaLightExtras {
                shape,
                size: 2.0,
                size_y: Some(1.0),
                power: 1.0,
                color: [1.0; 3],
                spread_deg: None,
            };
            let triangles = area_light_triangles(&light);
            let mut area = 0.0;
            for [a, b, c] in triangles {
                let n = (b - a).cross(c - a);
                assert!(n.z < 0.0, "{shape:?}");
                area += n.length() / 2.0;
            }
            let expected = match shape {
                AreaShape::Square => 4.0,
                AreaShape::Rectangle => 2.0,
                AreaShape::Disk => std::f32::consts::PI,
                AreaShape::Ellipse => std::f32::consts::PI / 2.0,
            };
            assert!((area / expected - 1.0).abs() < 0.01, "{shape:?}: {area}");
        }
    }
}
