//! glTF 2.0 as Blender 5.0's exporter writes it, plus the `caustic` extras, into a [`Scene`].
//!
//! Reads the default scene's node tree (nested transforms), triangle meshes with normals and
//! texture coordinates, metallic-roughness materials with `KHR_materials_transmission`,
//! `KHR_materials_ior` (absent means 1.5) and `KHR_materials_emissive_strength`,
//! `KHR_materials_dispersion`, `KHR_lights_punctual`, the first perspective camera, and the
//! extras schema in [`super::extras`].

use std::path::Path;
use std::sync::Arc;

use glam::{Mat3, Mat4, Vec2, Vec3};
use gltf::khr_lights_punctual::Kind;

use super::extras::{self, AreaLightExtras, MaterialExtras, NodeExtras, SceneExtras};
use super::{shapes, Scene, SceneError, TriangleRef, NOT_A_LIGHT};
use crate::camera::Camera;
use crate::geometry::Cone;
use crate::lights::{Light, World};
use crate::materials::{BaseColour, Material, Texture};
use crate::spectrum::{Dispersion, RgbSpectrum};

/// glTF photometric units to watts: Blender writes W * 683 / (4 pi) candela and W/m^2 * 683 lux.
const LUMENS_PER_WATT: f32 = 683.0;

/// What the node walk gathers before the scene is assembled.
struct Builder<'a> {
    buffers: &'a [gltf::buffer::Data],
    scene: Scene,
    camera: Option<Camera>,
    suns: Vec<usize>,
    material_offset: u32,
}

/// Loads `path` into a [`Scene`].
pub fn load(path: &Path) -> Result<Scene, SceneError> {
    let fail = |message: String| SceneError { path: path.to_path_buf(), message };
    if !path.exists() {
        return Err(fail("no such file".into()));
    }
    let (document, buffers, images) = gltf::import(path).map_err(|e| fail(describe_import_error(e)))?;
    let gltf_scene = document
        .default_scene()
        .or_else(|| document.scenes().next())
        .ok_or_else(|| fail("the file has no scene".into()))?;
    let scene_extras: SceneExtras =
        extras::parse(gltf_scene.extras()).map_err(|e| fail(format!("scene extras `caustic`: {e}")))?;
    let mut materials: Vec<Material> =
        document.materials().map(|m| material(&m, &images)).collect::<Result<_, _>>().map_err(fail)?;
    let material_offset = materials.len() as u32;
    materials.push(Material::default_grey());
    let mut builder = Builder {
        buffers: &buffers,
        scene: empty_scene(materials, scene_extras.resolution),
        camera: None,
        suns: Vec::new(),
        material_offset,
    };
    for node in gltf_scene.nodes() {
        builder.visit(&node, Mat4::IDENTITY).map_err(fail)?;
    }
    let world = scene_extras.world.map(|w| world(&w, path)).transpose().map_err(fail)?;
    builder.finish(world).map_err(fail)
}

/// A message for the gltf crate's errors that says what the user must fix.
fn describe_import_error(error: gltf::Error) -> String {
    match error {
        gltf::Error::Io(e) => format!("cannot read the file or a file it references: {e}"),
        gltf::Error::Deserialize(e) => format!("not a valid glTF file (malformed JSON): {e}"),
        gltf::Error::Validation(errors) => {
            let list: Vec<String> = errors.iter().map(|(path, e)| format!("{path}: {e}")).collect();
            format!(
                "not a valid glTF 2.0 file (unsupported required extension or invalid field): {}",
                list.join("; ")
            )
        }
        other => format!("cannot load glTF: {other}"),
    }
}

fn empty_scene(materials: Vec<Material>, resolution: Option<[u32; 2]>) -> Scene {
    Scene {
        positions: Vec::new(),
        normals: Vec::new(),
        uvs: Vec::new(),
        triangles: Vec::new(),
        materials,
        lights: Vec::new(),
        triangle_lights: Vec::new(),
        distant_lights: Vec::new(),
        camera: Camera::from_node(Mat4::IDENTITY, 1.0),
        resolution,
        aspect_ratio: None,
        warnings: Vec::new(),
    }
}

/// A glTF material as a Caustic material.
fn material(m: &gltf::Material, images: &[gltf::image::Data]) -> Result<Material, String> {
    let name = m.name().unwrap_or("unnamed").to_string();
    let pbr = m.pbr_metallic_roughness();
    let factor = Vec3::from_slice(&pbr.base_color_factor()[..3]);
    let base_colour = match pbr.base_color_texture() {
        Some(info) => {
            let image = &images[info.texture().source().index()];
            BaseColour::Texture(Arc::new(
                texture(image, factor).map_err(|e| format!("material '{name}': {e}"))?,
            ))
        }
        None => BaseColour::Constant(RgbSpectrum::reflectance(factor)),
    };
    let emission = Vec3::from(m.emissive_factor()) * m.emissive_strength().unwrap_or(1.0);
    Ok(Material {
        name,
        base_colour,
        metallic: pbr.metallic_factor().clamp(0.0, 1.0),
        roughness: pbr.roughness_factor().clamp(0.0, 1.0),
        transmission: m.transmission().map_or(0.0, |t| t.transmission_factor()).clamp(0.0, 1.0),
        ior: dispersion_law(m).map_err(|e| format!("material '{}': {e}", m.name().unwrap_or("unnamed")))?,
        emission: (emission.max_element() > 0.0).then(|| RgbSpectrum::illuminant(emission)),
        emits_both_sides: true,
    })
}

/// The material's index against wavelength: the `caustic` extras first, then
/// `KHR_materials_dispersion` (read raw: the gltf crate does not type it), then a constant.
fn dispersion_law(m: &gltf::Material) -> Result<Dispersion, String> {
    let n_d = m.ior().unwrap_or(1.5);
    let extras: MaterialExtras = extras::parse(m.extras()).map_err(|e| format!("extras `caustic`: {e}"))?;
    if let Some(name) = &extras.glass {
        return Dispersion::glass(name).ok_or_else(|| {
            format!(
                "extras `caustic.glass`: unknown glass '{name}' (the catalogue has {})",
                Dispersion::glass_names().join(", ")
            )
        });
    }
    if let Some(s) = &extras.sellmeier {
        if s.b.len() != s.c.len() || s.b.is_empty() || s.b.len() > 4 {
            return Err(
                "extras `caustic.sellmeier`: `b` and `c` need the same number of terms, 1 to 4".into()
            );
        }
        let (mut b, mut c) = ([0.0; 4], [0.0; 4]);
        b[..s.b.len()].copy_from_slice(&s.b);
        c[..s.c.len()].copy_from_slice(&s.c);
        return Ok(Dispersion::Sellmeier { b, c });
    }
    if let Some(table) = &extras.ior_table {
        return Dispersion::table(table.iter().map(|&[l, n]| (l, n)).collect())
            .map_err(|e| format!("extras `caustic.ior_table`: {e}"));
    }
    let khr = m.extension_value("KHR_materials_dispersion").and_then(|v| v["dispersion"].as_f64());
    let v_d = match (extras.abbe, khr) {
        (Some(v_d), _) if v_d > 0.0 => Some(v_d),
        (Some(v_d), _) => {
            return Err(format!("extras `caustic.abbe`: expected a positive Abbe number, got {v_d}"))
        }
        (None, Some(dispersion)) if dispersion > 0.0 => Some((20.0 / dispersion) as f32),
        _ => None,
    };
    Ok(match v_d {
        Some(v_d) => Dispersion::Abbe { n_d, v_d },
        None => Dispersion::Constant(n_d),
    })
}

fn texture(image: &gltf::image::Data, factor: Vec3) -> Result<Texture, String> {
    use gltf::image::Format;
    let channels = match image.format {
        Format::R8G8B8 => 3,
        Format::R8G8B8A8 => 4,
        other => {
            return Err(format!(
                "base colour texture format {other:?} is not supported (use 8-bit RGB or RGBA)"
            ))
        }
    };
    Ok(Texture::from_srgb8(image.width as usize, image.height as usize, channels, &image.pixels, factor))
}

/// The world from the scene extras; an image path is relative to the glTF file's folder.
fn world(w: &extras::WorldExtras, gltf_path: &Path) -> Result<World, String> {
    match &w.image {
        Some(image) => {
            let path = gltf_path.parent().unwrap_or(Path::new(".")).join(image);
            World::from_image(&path, w.strength, w.rotation_deg)
                .map_err(|e| format!("scene extras `caustic.world.image`: {e}"))
        }
        None => Ok(World::uniform(Vec3::from(w.color) * w.strength)),
    }
}

/// Blender's sun angle is the full angular diameter; without one the sun is a delta light.
fn sun_disc(extras: &NodeExtras) -> Cone {
    extras.sun_angle_deg.map_or(Cone::default(), |deg| Cone::from_half_angle(deg.to_radians() / 2.0))
}

impl Builder<'_> {
    /// Adds a node and its children, with `parent` the parent's world matrix.
    fn visit(&mut self, node: &gltf::Node, parent: Mat4) -> Result<(), String> {
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        let name = node.name().unwrap_or("unnamed");
        let extras: NodeExtras =
            extras::parse(node.extras()).map_err(|e| format!("node '{name}' extras `caustic`: {e}"))?;
        if let Some(mesh) = node.mesh() {
            self.add_mesh(&mesh, world)?;
        }
        if let Some(camera) = node.camera() {
            self.add_camera(&camera, world, name)?;
        }
        if let Some(light) = node.light() {
            self.add_punctual_light(&light, world, &extras);
        }
        if let Some(area) = &extras.area_light {
            self.add_area_light(area, world, name)?;
        }
        for child in node.children() {
            self.visit(&child, world)?;
        }
        Ok(())
    }

    fn add_camera(&mut self, camera: &gltf::Camera, world: Mat4, name: &str) -> Result<(), String> {
        if self.camera.is_some() {
            self.scene.warnings.push(format!("camera node '{name}' ignored: the first camera is used"));
            return Ok(());
        }
        match camera.projection() {
            gltf::camera::Projection::Perspective(p) => {
                self.camera = Some(Camera::from_node(world, p.yfov()));
                self.scene.aspect_ratio = p.aspect_ratio();
                Ok(())
            }
            gltf::camera::Projection::Orthographic(_) => Err(format!(
                "camera node '{name}': orthographic cameras are not supported; use a perspective camera"
            )),
        }
    }

    fn add_punctual_light(
        &mut self,
        light: &gltf::khr_lights_punctual::Light,
        world: Mat4,
        extras: &NodeExtras,
    ) {
        let colour = Vec3::from(light.color()) * light.intensity() / LUMENS_PER_WATT;
        let spectrum = RgbSpectrum::illuminant(colour);
        let position = world.transform_point3(Vec3::ZERO);
        let axis = world.transform_vector3(-Vec3::Z).normalize();
        let light = match light.kind() {
            Kind::Point => Light::Point { position, intensity: spectrum },
            Kind::Spot { inner_cone_angle, outer_cone_angle } => Light::Spot {
                position,
                axis,
                intensity: spectrum,
                inner: Cone::from_half_angle(inner_cone_angle),
                outer: Cone::from_half_angle(outer_cone_angle),
            },
            Kind::Directional => {
                self.suns.push(self.scene.lights.len());
                Light::Sun {
                    direction: axis,
                    irradiance: spectrum,
                    disc: sun_disc(extras),
                    sphere: Default::default(),
                }
            }
        };
        self.scene.lights.push(light);
    }

    /// An area light becomes one-sided emitting triangles with radiance P / (pi A).
    fn add_area_light(&mut self, area: &AreaLightExtras, world: Mat4, name: &str) -> Result<(), String> {
        if !(area.size > 0.0 && area.power >= 0.0 && area.size.is_finite() && area.power.is_finite()) {
            return Err(format!("node '{name}' area light: size must be positive and power non-negative"));
        }
        let triangles: Vec<[Vec3; 3]> = shapes::area_light_triangles(area)
            .into_iter()
            .map(|t| t.map(|v| world.transform_point3(v)))
            .collect();
        let total_area: f32 = triangles.iter().map(|[a, b, c]| (*b - *a).cross(*c - *a).length() / 2.0).sum();
        let radiance = Vec3::from(area.color) * area.power / (std::f32::consts::PI * total_area);
        let material = self.scene.materials.len() as u32;
        self.scene.materials.push(Material {
            name: format!("area light '{name}'"),
            base_colour: BaseColour::Constant(RgbSpectrum::constant(0.0)),
            emission: Some(RgbSpectrum::illuminant(radiance)),
            emits_both_sides: false,
            ..Material::default_grey()
        });
        for corners in triangles {
            let normal = (corners[1] - corners[0]).cross(corners[2] - corners[0]).normalize();
            let base = self.scene.positions.len() as u32;
            self.scene.positions.extend(corners);
            self.scene.normals.extend([normal; 3]);
            self.scene.uvs.extend([Vec2::ZERO; 3]);
            self.scene.triangles.push(TriangleRef { vertices: [base, base + 1, base + 2], material });
        }
        Ok(())
    }

    fn add_mesh(&mut self, mesh: &gltf::Mesh, world: Mat4) -> Result<(), String> {
        let name = mesh.name().unwrap_or("unnamed");
        let normal_matrix = Mat3::from_mat4(world).inverse().transpose();
        let mirrored = Mat3::from_mat4(world).determinant() < 0.0;
        for primitive in mesh.primitives() {
            if primitive.mode() != gltf::mesh::Mode::Triangles {
                self.scene.warnings.push(format!(
                    "mesh '{name}': a primitive of mode {:?} skipped (only triangles render)",
                    primitive.mode()
                ));
                continue;
            }
            let reader = primitive.reader(|b| self.buffers.get(b.index()).map(|d| &d.0[..]));
            let positions: Vec<Vec3> = reader
                .read_positions()
                .ok_or_else(|| format!("mesh '{name}': a primitive has no POSITION attribute"))?
                .map(|p| world.transform_point3(Vec3::from(p)))
                .collect();
            let normals: Option<Vec<Vec3>> = reader
                .read_normals()
                .map(|n| n.map(|n| (normal_matrix * Vec3::from(n)).normalize_or_zero()).collect());
            let uvs: Option<Vec<Vec2>> =
                reader.read_tex_coords(0).map(|t| t.into_f32().map(Vec2::from).collect());
            let indices: Vec<u32> = match reader.read_indices() {
                Some(indices) => indices.into_u32().collect(),
                None => (0..positions.len() as u32).collect(),
            };
            let material = primitive.material().index().map_or(self.material_offset, |i| i as u32);
            let base = self.scene.positions.len() as u32;
            let vertex_count = positions.len();
            self.scene.normals.extend(normals.unwrap_or_else(|| vec![Vec3::ZERO; vertex_count]));
            self.scene.uvs.extend(uvs.unwrap_or_else(|| vec![Vec2::ZERO; vertex_count]));
            let mut skipped = 0;
            for chunk in indices.chunks_exact(3) {
                if chunk.iter().any(|&i| i as usize >= vertex_count) {
                    return Err(format!(
                        "mesh '{name}': index {} out of range ({vertex_count} vertices)",
                        chunk.iter().max().unwrap_or(&0)
                    ));
                }
                let corners = [chunk[0], chunk[1], chunk[2]].map(|i| positions[i as usize]);
                if !is_valid_triangle(&corners) {
                    skipped += 1;
                    continue;
                }
                let [a, b, c] = [chunk[0], chunk[1], chunk[2]].map(|i| base + i);
                let vertices = if mirrored { [a, c, b] } else { [a, b, c] };
                self.scene.triangles.push(TriangleRef { vertices, material });
            }
            self.scene.positions.extend(positions);
            if skipped > 0 {
                self.scene.warnings.push(format!("mesh '{name}': skipped {skipped} degenerate triangles (zero area or non-finite coordinates)"));
            }
        }
        Ok(())
    }

    /// Emitting triangles become lights, distant lights learn the scene's bounds.
    fn finish(mut self, world: Option<World>) -> Result<Scene, String> {
        let scene = &mut self.scene;
        scene.camera = self.camera.ok_or("the scene has no camera: add a perspective camera")?;
        let sphere = scene.bounding_sphere();
        for &i in &self.suns {
            if let Light::Sun { sphere: s, disc, .. } = &mut scene.lights[i] {
                *s = sphere;
                if !disc.is_delta() {
                    scene.distant_lights.push(i);
                }
            }
        }
        scene.triangle_lights = vec![NOT_A_LIGHT; scene.triangles.len()];
        for (i, (t, corners)) in scene.triangles.iter().zip(scene.triangle_corners()).enumerate() {
            let material = &scene.materials[t.material as usize];
            if let Some(radiance) = material.emission {
                let both_sides = material.emits_both_sides;
                scene.triangle_lights[i] = scene.lights.len() as u32;
                scene.lights.push(Light::Triangle { corners, radiance, both_sides });
            }
        }
        if let Some(mut world) = world {
            world.sphere = sphere;
            scene.distant_lights.push(scene.lights.len());
            scene.lights.push(Light::World(world));
        }
        if scene.lights.iter().all(|l| l.power() <= 0.0) {
            scene.warnings.push("the scene has no light: the image will be black".into());
        }
        Ok(self.scene)
    }
}

fn is_valid_triangle(c: &[Vec3; 3]) -> bool {
    c.iter().all(|v| v.is_finite()) && (c[1] - c[0]).cross(c[2] - c[0]).length_squared() > 0.0
}
