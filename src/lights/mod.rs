//! Lights: emission, next-event estimation toward a point, and photon emission.
//!
//! Radiometric units (one place for all of them, docs/design.md, "Input"): every light's colour is an
//! [`Illuminant`]: an [`RgbSpectrum`] shape times D65 normalised to luminance 1 (or a black body's
//! spectrum, for a colour temperature), times a scalar in the unit below.
//! - point and spot: radiant intensity in W/sr (glTF candela / 683; Blender writes W / (4 pi) * 683);
//! - sun: irradiance in W/m^2 on a plane facing it (glTF lux / 683);
//! - emitting triangles (emissive meshes and area lights): radiance in W / (m^2 sr)
//!   (glTF emissive factor times `emissive_strength`, no 683; area lights P / (pi A));
//! - world: radiance in W / (m^2 sr).
//!
//! Distant lights (sun, world) emit photons from a disc covering the scene's bounding sphere.

mod sphere;
mod tree;
mod world;

pub use sphere::{Beam, SoftFalloff, SphereLight, SpotFalloff};
pub use tree::LightTree;
pub use world::World;

use glam::{Vec2, Vec3, Vec3A};
use std::f32::consts::PI;
use std::sync::Arc;

use crate::geometry::{corners_scale, offset_origin, Cone};
use crate::materials::{Alpha, Spread, SurfaceInputs};
use crate::sampling::{
    basis, square_to_cone, square_to_cosine_hemisphere, square_to_disc, square_to_triangle,
};
use crate::spectrum::{Illuminant, SampledSpectrum, Wavelengths};
use crate::texture::{Texture, UV_SETS};

/// The scene's bounding sphere, where distant lights start their photons.
#[derive(Clone, Copy, Debug, Default)]
pub struct BoundingSphere {
    /// Centre.
    pub centre: Vec3,
    /// Radius (positive).
    pub radius: f32,
}

/// A light source.
#[derive(Clone, Debug)]
pub enum Light {
    /// A point or spot light, with Blender's radius or without.
    Sphere(SphereLight),
    /// A distant light with an angular diameter (soft shadows) or none.
    Sun {
        /// Unit direction the light travels.
        direction: Vec3,
        /// Irradiance on a plane facing the sun, W/m^2.
        irradiance: Illuminant,
        /// The sun's disc as a cone of directions (zero for a delta sun).
        disc: Cone,
        /// Where its photons start.
        sphere: BoundingSphere,
    },
    /// One emitting triangle of an emissive mesh or an area light.
    Triangle(EmittingTriangle),
    /// Light from infinitely far away in every direction.
    World(World),
}

/// What an emitting triangle emits: one radiance, or an emissive texture's across it.
#[derive(Clone, Debug)]
pub enum Emission {
    /// The same radiance everywhere, W / (m^2 sr).
    Uniform(Illuminant),
    /// A texture of radiance spectra, read at the texture coordinates of the triangle's corners
    /// (boxed: every light's size is the largest variant's, and few triangles carry a texture).
    Textured(Box<TexturedEmission>),
    /// Emission where the material's alpha cuts the surface away: the emission times the
    /// surface's opacity.
    Cut(Box<CutEmission>),
}

/// Emission on a triangle that alpha cuts: it glows where the surface is there.
#[derive(Clone, Debug)]
pub struct CutEmission {
    /// What the surface emits where it is there.
    pub emission: Emission,
    /// The material's alpha.
    pub alpha: Alpha,
    /// Each corner's texture coordinates, one pair per set.
    pub uvs: [[Vec2; UV_SETS]; 3],
    /// Each corner's `COLOR_0` alpha.
    pub vertex_alpha: [f32; 3],
}

impl CutEmission {
    /// The probability that the surface is there at barycentric coordinates `b`.
    fn opacity(&self, b: Vec2) -> f32 {
        let a = &self.vertex_alpha;
        let inputs = SurfaceInputs {
            uv: corner_mix(&self.uvs, b),
            alpha: a[0] * (1.0 - b.x - b.y) + a[1] * b.x + a[2] * b.y,
            ..SurfaceInputs::default()
        };
        self.alpha.opacity(&inputs)
    }
}

/// An emissive texture on one triangle.
#[derive(Clone, Debug)]
pub struct TexturedEmission {
    /// The texture, factor and strength baked in.
    pub texture: Arc<Texture>,
    /// Each corner's texture coordinates, one pair per set.
    pub uvs: [[Vec2; UV_SETS]; 3],
}

impl Emission {
    /// The radiance at barycentric coordinates `b` and the wavelengths `lambda`.
    fn at(&self, b: Vec2, lambda: &Wavelengths) -> SampledSpectrum {
        match self {
            Emission::Uniform(radiance) => radiance.eval(lambda),
            Emission::Textured(t) => t.texture.eval(&corner_mix(&t.uvs, b), lambda.nm) * lambda.d65,
            Emission::Cut(c) => c.emission.at(b, lambda) * c.opacity(b),
        }
    }

    /// The luminance at barycentric coordinates `b`.
    fn luminance_at(&self, b: Vec2) -> f64 {
        match self {
            Emission::Uniform(radiance) => radiance.luminance(),
            Emission::Textured(t) => t.texture.luminance(&corner_mix(&t.uvs, b)),
            Emission::Cut(c) => c.emission.luminance_at(b) * f64::from(c.opacity(b)),
        }
    }

    /// The mean luminance over the triangle (where it varies, from 64 stratified points), for
    /// choosing lights by power.
    fn mean_luminance(&self) -> f64 {
        match self {
            Emission::Uniform(radiance) => radiance.luminance(),
            _ => {
                let points = (0..64).map(|i| Vec2::new((i % 8) as f32 + 0.5, (i / 8) as f32 + 0.5) / 8.0);
                points.map(|u| self.luminance_at(square_to_triangle(u))).sum::<f64>() / 64.0
            }
        }
    }
}

/// The texture coordinates at barycentric coordinates `b` of a triangle with corners' `uvs`.
fn corner_mix(uvs: &[[Vec2; UV_SETS]; 3], b: Vec2) -> [Vec2; UV_SETS] {
    std::array::from_fn(|set| uvs[0][set] * (1.0 - b.x - b.y) + uvs[1][set] * b.x + uvs[2][set] * b.y)
}

/// An emitting triangle, with what sampling it needs computed once.
#[derive(Clone, Debug)]
pub struct EmittingTriangle {
    /// Its corners.
    corners: [Vec3; 3],
    /// Emitted radiance, W / (m^2 sr).
    emission: Emission,
    /// Whether both faces emit (meshes) or only the front (area lights).
    both_sides: bool,
    /// How an area light's Spread narrows what its front emits.
    spread: Option<Spread>,
    /// Its unit normal (corners counter-clockwise), zero when degenerate.
    normal: Vec3,
    /// Its area.
    area: f32,
    /// The largest coordinate of its corners (for offsetting photons that leave it).
    scale: f32,
}

impl EmittingTriangle {
    /// The triangle `corners` emitting `emission` (W / (m^2 sr)) from its front, or from both
    /// faces if `both_sides`.
    pub fn new(corners: [Vec3; 3], emission: Emission, both_sides: bool) -> Self {
        let cross = (corners[1] - corners[0]).cross(corners[2] - corners[0]);
        EmittingTriangle {
            corners,
            emission,
            both_sides,
            spread: None,
            normal: cross.normalize_or_zero(),
            area: 0.5 * cross.length(),
            scale: corners_scale(corners.map(Vec3A::from)),
        }
    }

    /// The same triangle with an area light's `spread`.
    pub fn with_spread(self, spread: Option<Spread>) -> Self {
        EmittingTriangle { spread, ..self }
    }

    /// Faces that emit: 1 or 2.
    fn sides(&self) -> f32 {
        if self.both_sides {
            2.0
        } else {
            1.0
        }
    }

    /// A uniform point on it, and its barycentric coordinates.
    fn point(&self, u: Vec2) -> (Vec3, Vec2) {
        let b = square_to_triangle(u);
        let c = &self.corners;
        (c[0] * (1.0 - b.x - b.y) + c[1] * b.x + c[2] * b.y, b)
    }
}

/// Light arriving at a point, sampled for next-event estimation.
#[derive(Clone, Copy, Debug)]
pub struct LightSample {
    /// Unit direction from the point toward the light.
    pub wi: Vec3,
    /// Distance to the light (infinite for distant lights).
    pub distance: f32,
    /// Incident radiance over the density of `wi` (cosine at the receiver not included).
    pub radiance_over_pdf: SampledSpectrum,
    /// The density of `wi` per solid angle; zero for delta lights (a point, a spot, a delta sun).
    pub pdf: f32,
}

/// A photon leaving a light.
#[derive(Clone, Copy, Debug)]
pub struct EmittedPhoton {
    /// Where it starts.
    pub origin: Vec3,
    /// Unit direction of travel.
    pub direction: Vec3,
    /// Its flux over the density of its origin and direction, W.
    pub flux: SampledSpectrum,
}

/// How densely a light emits along one ray, for weighing photon paths against the other ways
/// of sampling the same path (vertex connection and merging, `transport/vcm/`). Light choice is not
/// included.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EmissionDensity {
    /// The density of a photon's origin and direction: per area and per solid angle (a distant
    /// light's: per area of the disc its photons start on and per solid angle; a point's: per
    /// solid angle).
    pub emission: f32,
    /// The cosine between the ray and the light's normal (1 for points and distant lights).
    pub cos: f32,
    /// No path can meet the light: a point, or a sun without a disc.
    pub delta: bool,
    /// The light lies at a finite distance (not a sun or the world).
    pub finite: bool,
}

/// A point on the disc of `sphere` facing `direction`, upstream of the scene.
fn disc_origin(sphere: &BoundingSphere, direction: Vec3, u: Vec2) -> Vec3 {
    let (t, b) = basis(direction);
    let d = square_to_disc(u) * sphere.radius;
    sphere.centre - direction * sphere.radius + t * d.x + b * d.y
}

impl Light {
    /// For photons from a light with Soft Falloff: its factor on their flux where they first
    /// meet a surface.
    pub fn photon_falloff(&self) -> Option<SoftFalloff> {
        match self {
            Light::Sphere(sphere) => sphere.photon_falloff(),
            _ => None,
        }
    }

    /// Where it is, for finding the volumes its photons start in: a point light's position, a
    /// triangle's centroid; `None` for lights at infinity.
    pub fn centre(&self) -> Option<Vec3> {
        match self {
            Light::Sphere(sphere) => Some(sphere.position),
            Light::Triangle(t) => Some((t.corners[0] + t.corners[1] + t.corners[2]) / 3.0),
            Light::Sun { .. } | Light::World(_) => None,
        }
    }

    /// Total emitted luminous power, for choosing lights in proportion to it.
    pub fn power(&self) -> f64 {
        let power = match self {
            Light::Sphere(sphere) => sphere.power(),
            Light::Sun { irradiance, sphere, .. } => {
                irradiance.luminance() * f64::from(PI * sphere.radius * sphere.radius)
            }
            Light::Triangle(triangle) => {
                f64::from(triangle.sides())
                    * triangle.emission.mean_luminance()
                    * f64::from(PI * triangle.area)
            }
            Light::World(world) => {
                let r = f64::from(world.sphere.radius);
                world.luminance_over_sphere() * std::f64::consts::PI * r * r
            }
        };
        if power.is_finite() {
            power.max(0.0)
        } else {
            0.0
        }
    }

    /// Samples light arriving at `p` (for next-event estimation); `None` when none arrives.
    pub fn sample_incident(&self, p: Vec3, u: Vec2, lambda: &Wavelengths) -> Option<LightSample> {
        match self {
            Light::Sphere(sphere) => sphere.sample_incident(p, u, lambda),
            Light::Sun { direction, irradiance, disc, .. } => {
                let (t, b) = basis(-*direction);
                let local = square_to_cone(u, disc.one_minus_cos);
                let wi = (t * local.x + b * local.y - *direction * local.z).normalize();
                let radiance_over_pdf = irradiance.eval(lambda);
                let pdf = if disc.is_delta() { 0.0 } else { 1.0 / disc.solid_angle() };
                Some(LightSample { wi, distance: f32::INFINITY, radiance_over_pdf, pdf })
            }
            Light::Triangle(triangle) => {
                let (q, b) = triangle.point(u);
                let (wi, distance) = direction_and_distance(p, q)?;
                let pdf = self.pdf_incident(p, wi, q);
                if pdf <= 0.0 {
                    return None;
                }
                let mut radiance_over_pdf = triangle.emission.at(b, lambda) / pdf;
                if let Some(spread) = triangle.spread {
                    radiance_over_pdf *= spread.attenuation(-triangle.normal.dot(wi));
                }
                Some(LightSample { wi, distance, radiance_over_pdf, pdf })
            }
            Light::World(world) => {
                let (wi, pdf) = world.sample_direction(u)?;
                let radiance_over_pdf = world.radiance(wi, lambda) / pdf;
                Some(LightSample { wi, distance: f32::INFINITY, radiance_over_pdf, pdf })
            }
        }
    }

    /// The density per solid angle with which [`Light::sample_incident`] picks the direction `wi`
    /// from `p`, given that the ray along it reaches this light at `q` (a point on a triangle
    /// light) or escapes (distant lights). Zero for delta lights.
    pub fn pdf_incident(&self, p: Vec3, wi: Vec3, q: Vec3) -> f32 {
        match self {
            Light::Triangle(triangle) => {
                let cos_light = -triangle.normal.dot(wi);
                let cos_light = if triangle.both_sides { cos_light.abs() } else { cos_light };
                if cos_light <= 0.0 {
                    return 0.0;
                }
                p.distance_squared(q) / (triangle.area * cos_light)
            }
            Light::Sun { direction, disc, .. } if !disc.is_delta() && disc.contains(-*direction, wi) => {
                1.0 / disc.solid_angle()
            }
            Light::World(world) => world.pdf(wi),
            Light::Sphere(sphere) => sphere.pdf_incident(p, wi, q),
            _ => 0.0,
        }
    }

    /// Radiance that a ray of direction `dir` leaving the scene receives from this light
    /// (distant lights with a solid angle: the world, a sun with an angular diameter).
    pub fn escaped_radiance(&self, dir: Vec3, lambda: &Wavelengths) -> SampledSpectrum {
        match self {
            Light::Sun { direction, irradiance, disc, .. }
                if !disc.is_delta() && disc.contains(-*direction, dir) =>
            {
                irradiance.eval(lambda) / disc.solid_angle()
            }
            Light::World(world) => world.radiance(dir, lambda),
            _ => SampledSpectrum::ZERO,
        }
    }

    /// Samples a photon leaving the light, carrying the wavelengths `lambda`.
    pub fn emit_photon(
        &self,
        u_position: Vec2,
        u_direction: Vec2,
        lambda: &Wavelengths,
    ) -> Option<EmittedPhoton> {
        let photon = match self {
            Light::Sphere(sphere) => sphere.emit_photon(u_position, u_direction, lambda),
            Light::Sun { direction, irradiance, disc, sphere } => {
                let (t, b) = basis(*direction);
                let local = square_to_cone(u_direction, disc.one_minus_cos);
                let direction = (t * local.x + b * local.y + *direction * local.z).normalize();
                EmittedPhoton {
                    origin: disc_origin(sphere, direction, u_position),
                    direction,
                    flux: irradiance.eval(lambda) * PI * sphere.radius * sphere.radius,
                }
            }
            Light::Triangle(triangle) => {
                let mut n = triangle.normal;
                let mut u = u_direction;
                if triangle.both_sides {
                    if u.x < 0.5 {
                        n = -n;
                        u.x *= 2.0;
                    } else {
                        u.x = 2.0 * u.x - 1.0;
                    }
                }
                let (q, b) = triangle.point(u_position);
                let (t, bitangent) = basis(n);
                let (local, weight) = match triangle.spread {
                    Some(spread) => spread.sample(u),
                    None => (square_to_cosine_hemisphere(u), 1.0),
                };
                // Unit to rounding (an orthonormal basis, a unit local direction).
                let direction = t * local.x + bitangent * local.y + n * local.z;
                EmittedPhoton {
                    origin: offset_origin(q, n, direction, triangle.scale),
                    direction,
                    flux: triangle.emission.at(b, lambda) * (PI * triangle.area * triangle.sides() * weight),
                }
            }
            Light::World(world) => {
                // A direction light arrives from, then the photon travels the other way.
                let (wi, pdf) = world.sample_direction(u_direction)?;
                let r = world.sphere.radius;
                EmittedPhoton {
                    origin: disc_origin(&world.sphere, -wi, u_position),
                    direction: -wi,
                    flux: world.radiance(wi, lambda) * PI * r * r / pdf,
                }
            }
        };
        (photon.flux.max_element() > 0.0 && photon.flux.is_finite()).then_some(photon)
    }
}

impl Light {
    /// How densely [`Light::emit_photon`] emits a photon from the point `q` of the light (read
    /// only for a sphere's normal) along the unit `direction` of travel; `None` where it emits
    /// nothing that way. A light with a radius is its sphere here, Soft Falloff or not (see
    /// [`Light::sample_surface_incident`]).
    pub fn emission_density(&self, q: Vec3, direction: Vec3) -> Option<EmissionDensity> {
        let density = match self {
            Light::Sphere(sphere) if sphere.radius > 0.0 => {
                let (emission, cos) = sphere.surface_emission(q, direction)?;
                EmissionDensity { emission, cos, delta: false, finite: true }
            }
            Light::Sphere(sphere) => EmissionDensity {
                emission: 1.0 / sphere.beam.map_or(4.0 * PI, |b| b.outer.solid_angle()),
                cos: 1.0,
                delta: true,
                finite: true,
            },
            // A distant light's photons start uniformly on a disc and leave it in the directions
            // next-event estimation picks.
            Light::Sun { disc, sphere, .. } => EmissionDensity {
                emission: self.direct_density(q, q, direction) / (PI * sphere.radius * sphere.radius),
                cos: 1.0,
                delta: disc.is_delta(),
                finite: false,
            },
            Light::Triangle(triangle) => {
                let cos = triangle.normal.dot(direction);
                let cos = if triangle.both_sides { cos.abs() } else { cos };
                let per_direction = match triangle.spread {
                    Some(spread) if cos < spread.cos_half() => 0.0,
                    Some(spread) => cos / (PI * (1.0 - spread.cos_half() * spread.cos_half())),
                    None => cos / PI,
                };
                if !(cos > 0.0 && per_direction > 0.0 && triangle.area > 0.0) {
                    return None;
                }
                EmissionDensity {
                    emission: per_direction / (triangle.sides() * triangle.area),
                    cos,
                    delta: false,
                    finite: true,
                }
            }
            Light::World(world) => EmissionDensity {
                emission: self.direct_density(q, q, direction)
                    / (PI * world.sphere.radius * world.sphere.radius),
                cos: 1.0,
                delta: false,
                finite: false,
            },
        };
        (density.emission > 0.0 && density.emission.is_finite()).then_some(density)
    }

    /// The density with which [`Light::sample_surface_incident`] from `receiver` picks the point
    /// `q` of the light that sends light along the unit `direction` of travel: per area (a
    /// distant light's direction: per solid angle); 1 for a delta light.
    pub fn direct_density(&self, receiver: Vec3, q: Vec3, direction: Vec3) -> f32 {
        match self {
            Light::Sphere(sphere) if sphere.radius > 0.0 => sphere.surface_density(receiver, q),
            Light::Sphere(_) => 1.0,
            Light::Sun { direction: axis, disc, .. } => match disc.is_delta() {
                true => 1.0,
                false if disc.contains(*axis, direction) => 1.0 / disc.solid_angle(),
                false => 0.0,
            },
            Light::Triangle(triangle) => 1.0 / triangle.area,
            Light::World(world) => world.pdf(-direction),
        }
    }

    /// As [`Light::sample_incident`], but a light with a radius on its sphere, with Soft
    /// Falloff's factor on what arrives, rather than on the disc facing `p` that stands for it
    /// there: the light as vertex connection and merging meets it, one surface that every one of
    /// its techniques reaches alike (light paths leave the sphere and camera paths meet it).
    pub fn sample_surface_incident(&self, p: Vec3, u: Vec2, lambda: &Wavelengths) -> Option<LightSample> {
        match self {
            Light::Sphere(sphere) if sphere.radius > 0.0 => sphere.sample_surface(p, u, lambda),
            _ => self.sample_incident(p, u, lambda),
        }
    }
}

/// Unit direction from `p` to `q` and their distance; `None` if they coincide.
fn direction_and_distance(p: Vec3, q: Vec3) -> Option<(Vec3, f32)> {
    let d = q - p;
    let distance = d.length();
    (distance > 0.0 && distance.is_finite()).then(|| (d / distance, distance))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn triangle_light_irradiance_matches_the_closed_form() {
        // A 2 x 2 square emitter (two triangles) at height 1 above a point: irradiance is pi L
        // times the form factor 4 * 2 / (2 pi) * atan(1 / sqrt 2) / sqrt 2 (parallel rectangles).
        let s = 1.0;
        let c = [Vec3::new(-s, -s, 1.0), Vec3::new(s, -s, 1.0), Vec3::new(s, s, 1.0), Vec3::new(-s, s, 1.0)];
        let lights = [
            Light::Triangle(EmittingTriangle::new(
                [c[0], c[2], c[1]],
                Emission::Uniform(Illuminant::d65(Vec3::ONE)),
                false,
            )),
            Light::Triangle(EmittingTriangle::new(
                [c[0], c[3], c[2]],
                Emission::Uniform(Illuminant::d65(Vec3::ONE)),
                false,
            )),
        ];
        let n = 40000;
        let mut irradiance = 0.0;
        for light in &lights {
            for i in 0..n {
                let u = Vec2::new((i as f32 + 0.5) / n as f32, ((i * 7919) % n) as f32 / n as f32);
                if let Some(s) = light.sample_incident(Vec3::ZERO, u, &Wavelengths::single(555.0, 1.0)) {
                    irradiance += s.radiance_over_pdf.x * s.wi.z.max(0.0) / n as f32;
                }
            }
        }
        let form_factor = 4.0 / PI * (0.5f32.sqrt()).atan() * 0.5f32.sqrt();
        let expected = PI * form_factor * crate::spectrum::d65(555.0);
        assert!((irradiance / expected - 1.0).abs() < 0.02, "{irradiance} vs {expected}");
    }
}
