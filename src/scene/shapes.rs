//! Area lights as emitting triangles in the light's local frame (emitting toward local -z), and
//! point lights with a radius as emitting spheres (emitting outward).

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

/// Segments around a sphere light (and half as many from pole to pole).
const SPHERE_SEGMENTS: usize = 32;

/// The local-space triangles of a sphere of `radius` about the origin, wound so their normals
/// point outward (a UV sphere: its projected outline within 0.5% of the sphere's).
pub fn sphere_triangles(radius: f32) -> Vec<[Vec3; 3]> {
    let rings = SPHERE_SEGMENTS / 2;
    let point = |ring: usize, segment: usize| {
        let theta = std::f32::consts::PI * ring as f32 / rings as f32;
        let phi = std::f32::consts::TAU * segment as f32 / SPHERE_SEGMENTS as f32;
        radius * Vec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin())
    };
    let mut triangles = Vec::new();
    for ring in 0..rings {
        for segment in 0..SPHERE_SEGMENTS {
            let [a, b, c, d] =
                [(ring, segment), (ring, segment + 1), (ring + 1, segment + 1), (ring + 1, segment)]
                    .map(|(r, s)| point(r, s));
            if ring > 0 {
                triangles.push([a, b, c]);
            }
            if ring + 1 < rings {
                triangles.push([a, c, d]);
            }
        }
    }
    triangles
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spheres_face_outward_and_have_a_sphere_area() {
        let triangles = sphere_triangles(2.0);
        let mut area = 0.0;
        for [a, b, c] in triangles {
            let n = (b - a).cross(c - a);
            assert!(n.dot(a + b + c) > 0.0, "inward triangle");
            area += n.length() / 2.0;
        }
        let sphere = 4.0 * std::f32::consts::PI * 4.0;
        assert!((area / sphere - 1.0).abs() < 0.01, "{area} vs {sphere}");
    }

    #[test]
    fn area_lights_face_down_their_local_z() {
        for shape in [AreaShape::Square, AreaShape::Rectangle, AreaShape::Disk, AreaShape::Ellipse] {
            let light = AreaLightExtras { shape, size: 2.0, size_y: Some(1.0), power: 1.0, color: [1.0; 3] };
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
