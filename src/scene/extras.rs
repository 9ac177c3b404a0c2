//! The `caustic` extras schema: what Blender's glTF exporter drops, carried in glTF `extras`.
//!
//! Every entry lives under one `caustic` key, so other tools' extras are left alone; unknown keys
//! inside it are errors (a typo must not be silently ignored). The schema is documented for users
//! in `docs/extras.md`; keep the two in step.
//!
//! - scene: `{"caustic": {"resolution": [w, h], "world": World, "fog": Medium, "fps": 24,
//!   "shutter": Shutter, "tracks": [Track]}}`
//! - node: `{"caustic": {"area_light": AreaLight}}` on an area light's (empty) node, and
//!   `{"caustic": {"sun_angle_deg": a}}` on a sun's node, `{"caustic": {"lens": Lens}}` on the
//!   camera's node;
//! - material: `{"caustic": {"glass": "BK7"}}`, or `"abbe"`, `"sellmeier"`, `"ior_table"`;
//!   `{"caustic": {"medium": Medium}}` for what fills it.

use serde::Deserialize;

/// The `caustic` entry of the scene's extras.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneExtras {
    /// Render resolution in pixels, width and height.
    pub resolution: Option<[u32; 2]>,
    /// The world's light.
    pub world: Option<WorldExtras>,
    /// The medium filling the world outside every closed transmissive mesh (Blender's world
    /// volume).
    pub fog: Option<MediumExtras>,
    /// A regression scene's analytic question (read by its tests; the renderer ignores it).
    pub regression: Option<serde_json::Value>,
    /// Frames per second: glTF time = frame / fps (default 24).
    pub fps: Option<f32>,
    /// The motion-blur shutter (absent: no motion blur).
    pub shutter: Option<ShutterExtras>,
    /// The film is transparent where the camera sees the world directly (Blender's Film >
    /// Transparent): the world lights the scene but is not seen, and alpha is 0 there.
    #[serde(default)]
    pub transparent_film: bool,
    /// The name of the camera's node to render through (absent: the first camera).
    pub camera: Option<String>,
    /// Animated values as keys on `KHR_animation_pointer` pointers, including pointers into
    /// these extras for what glTF cannot animate (an area light's power).
    #[serde(default)]
    pub tracks: Vec<super::pointers::TrackExtras>,
}

/// Blender's motion-blur shutter.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ShutterExtras {
    /// Shutter length in frames (Blender's Shutter).
    pub length_frames: f32,
    /// Where the shutter opens relative to the frame (Blender's Position; default CENTER).
    #[serde(default)]
    pub position: ShutterPosition,
}

/// Blender's shutter positions.
#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "UPPERCASE")]
pub enum ShutterPosition {
    /// Opens at the frame.
    Start,
    /// Centred on the frame.
    #[default]
    Center,
    /// Closes at the frame.
    End,
}

/// A camera's depth of field, on the camera's node.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LensExtras {
    /// f-number (Blender's F-Stop); 0 turns depth of field off.
    pub fstop: f32,
    /// Focus distance in scene units (Blender's Focus Distance, or the distance to its focus object).
    pub focus_distance: f32,
    /// Focal length in mm (Blender's Focal Length); default from the field of view and a 36 mm sensor.
    pub focal_length_mm: Option<f32>,
    /// Aperture blades (0: round).
    #[serde(default)]
    pub blades: u32,
    /// Blade rotation in degrees.
    #[serde(default)]
    pub blade_rotation_deg: f32,
}

/// Blender's equirectangular panoramic camera: the longitudes and latitudes the film spans.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PanoramaExtras {
    /// Longitudes of the film's left and right edges, degrees (0 ahead, growing to the right).
    #[serde(default = "full_longitude")]
    pub longitude_deg: [f32; 2],
    /// Latitudes of the film's bottom and top edges, degrees.
    #[serde(default = "full_latitude")]
    pub latitude_deg: [f32; 2],
}

fn full_longitude() -> [f32; 2] {
    [-180.0, 180.0]
}

fn full_latitude() -> [f32; 2] {
    [-90.0, 90.0]
}

/// The world: a uniform colour, or an equirectangular image, times a strength.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WorldExtras {
    /// Linear Rec.709 colour (default white).
    #[serde(default = "white")]
    pub color: [f32; 3],
    /// Radiance scale, W / (m^2 sr) for a white colour (default 1).
    #[serde(default = "one")]
    pub strength: f32,
    /// Path of an equirectangular `.hdr` or `.exr` image, relative to the glTF file.
    pub image: Option<String>,
    /// Rotation of the image about the up axis, in degrees.
    #[serde(default)]
    pub rotation_deg: f32,
}

/// The `caustic` entry of a node's extras.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NodeExtras {
    /// The node is an area light.
    pub area_light: Option<AreaLightExtras>,
    /// The angular diameter of the node's sun light, in degrees (soft shadows).
    pub sun_angle_deg: Option<f32>,
    /// Blender's Spot Blend of the node's spot light, in [0, 1]: its falloff is then Blender's
    /// smoothstep rather than glTF's ramp between the cones.
    pub spot_blend: Option<f32>,
    /// The radius of the node's point or spot light (Blender's): it becomes an emitting sphere.
    pub radius: Option<f32>,
    /// Whether the camera sees the node's light (a point or spot light's sphere, an area
    /// light): Blender's Ray Visibility > Camera. Reflections see it either way. Default: true.
    pub visible_to_camera: Option<bool>,
    /// Blender's Soft Falloff of the node's point or spot light with a radius: the light is a
    /// disc facing what it lights (`crate::lights::SphereLight`).
    #[serde(default)]
    pub soft_falloff: bool,
    /// The colour temperature of the node's light, kelvin (Blender's `use_temperature`): its
    /// colour is multiplied by a black body's.
    pub temperature_k: Option<f32>,
    /// The node's camera's depth of field.
    pub lens: Option<LensExtras>,
    /// The node's camera's lens shift, in film heights (Blender's shift times the side the
    /// sensor fits, over the height).
    pub shift: Option<[f32; 2]>,
    /// The node's mesh is a holdout (an object in a holdout collection): a hole in the film where
    /// the camera sees it, rendered as its materials say everywhere else.
    #[serde(default)]
    pub holdout: bool,
    /// The node is Blender's equirectangular panoramic camera (glTF has none).
    pub panorama: Option<PanoramaExtras>,
}

/// The `caustic` entry of a material's extras: how its index depends on wavelength (the first
/// given of `glass`, `sellmeier`, `ior_table`, `abbe` wins; `KHR_materials_dispersion` applies
/// when none is given).
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialExtras {
    /// A catalogue glass by name (spectra/glasses.csv).
    pub glass: Option<String>,
    /// Sellmeier coefficients (micrometres), up to four terms.
    pub sellmeier: Option<SellmeierExtras>,
    /// `[wavelength_nm, index]` pairs.
    pub ior_table: Option<Vec<[f32; 2]>>,
    /// Abbe number V_d, with the material's IOR as n_d (the `KHR_materials_dispersion` law).
    pub abbe: Option<f32>,
    /// Where its volume overlaps another's (water meeting its glass), the volume of highest
    /// priority fills the overlap (0 when not given).
    pub priority: Option<i32>,
    /// The material is Blender's Holdout shader: black, and a hole in the film where the camera
    /// sees it.
    #[serde(default)]
    pub holdout: bool,
    /// The medium that fills it (in place of `KHR_materials_volume`'s absorption).
    pub medium: Option<MediumExtras>,
    /// Blender's Normal Map Strength for `normalTexture` (see `NormalMap::strength`).
    pub normal_map_strength: Option<f32>,
    /// Whether it reads the mesh's vertex colours (`COLOR_0`): false where Blender's material has
    /// no Color Attribute node (glTF's rule, true, when not given).
    pub vertex_colours: Option<bool>,
}

/// A homogeneous medium: coefficients per world unit, as linear Rec.709 colours.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MediumExtras {
    /// The absorption coefficient (default 0).
    #[serde(default)]
    pub absorption: [f32; 3],
    /// The scattering coefficient (default 0).
    #[serde(default)]
    pub scattering: [f32; 3],
    /// Henyey–Greenstein's `g`, in (-1, 1) (default 0: scattering evenly).
    #[serde(default)]
    pub anisotropy: f32,
}

/// Sellmeier coefficients: `n^2 = 1 + sum b_k l^2 / (l^2 - c_k)`, l in micrometres.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SellmeierExtras {
    /// B coefficients.
    pub b: Vec<f64>,
    /// C coefficients, micrometres squared.
    pub c: Vec<f64>,
}

/// The shapes of Blender's area lights.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "UPPERCASE")]
pub enum AreaShape {
    /// `size` by `size`.
    Square,
    /// `size` by `size_y`.
    Rectangle,
    /// A disc of diameter `size`.
    Disk,
    /// An ellipse of diameters `size` and `size_y`.
    Ellipse,
}

/// An area light: emits from the node's local x-y plane toward its local -z, like Blender's.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AreaLightExtras {
    /// Its shape.
    pub shape: AreaShape,
    /// Size along local x (diameter for discs), in scene units.
    pub size: f32,
    /// Size along local y for rectangles and ellipses (default `size`).
    pub size_y: Option<f32>,
    /// Emitted power, W (Blender's Power).
    pub power: f32,
    /// Linear Rec.709 colour (default white).
    #[serde(default = "white")]
    pub color: [f32; 3],
    /// Blender's Spread, degrees in [0, 180] (default 180: no narrowing).
    pub spread_deg: Option<f32>,
}

fn white() -> [f32; 3] {
    [1.0; 3]
}

fn one() -> f32 {
    1.0
}

/// The `caustic` entry of raw glTF extras, or the default when absent. An error names the
/// field within the entry (`visible_to_camera: invalid type: ...`).
pub fn parse<T: Default + for<'a> Deserialize<'a>>(extras: &gltf::json::Extras) -> Result<T, String> {
    let Some(raw) = extras else {
        return Ok(T::default());
    };
    #[derive(Deserialize)]
    struct Wrapper<T> {
        caustic: Option<T>,
    }
    let mut json = serde_json::Deserializer::from_str(raw.get());
    let wrapper: Wrapper<T> = serde_path_to_error::deserialize(&mut json).map_err(|e| {
        let field = e.path().to_string();
        let field = field.strip_prefix("caustic").unwrap_or(&field).trim_start_matches('.');
        match field {
            "" => e.inner().to_string(),
            field => format!("`{field}`: {}", e.inner()),
        }
    })?;
    Ok(wrapper.caustic.unwrap_or_default())
}
