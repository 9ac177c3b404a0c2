//! Absorption inside glass and water (`KHR_materials_volume`), rendered end to end against
//! Beer–Lambert's law: the light a sun straight above sends through tinted slabs, panes, nested
//! and overlapping volumes onto a dark ground, and what a camera inside a volume sees.

mod common;

use caustic::render::Method;
use caustic::spectrum::{cmf, d65, xyz_to_linear_rec709, RgbSpectrum};
use common::*;
use glam::Vec3;
use serde_json::{json, Value};
use std::path::Path;

const GROUND: [[[f32; 3]; 3]; 2] = [
    [[-1.0, 0.0, -1.0], [-1.0, 0.0, 1.0], [1.0, 0.0, 1.0]],
    [[-1.0, 0.0, -1.0], [1.0, 0.0, 1.0], [1.0, 0.0, -1.0]],
];

/// Smooth clear glass of index `ior` whose volume has attenuation colour `colour` at `distance`,
/// thickness factor `thickness` and `caustic` priority `priority`.
fn tinted(ior: f32, colour: [f32; 3], distance: f32, thickness: f32, priority: i32) -> Value {
    json!({"pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, 1.0],
        "metallicFactor": 0.0, "roughnessFactor": 0.0},
        "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1.0},
            "KHR_materials_ior": {"ior": ior},
            "KHR_materials_volume": {"attenuationColor": colour, "attenuationDistance": distance,
                "thicknessFactor": thickness}},
        "extras": {"caustic": {"priority": priority}}})
}

/// A box of glass `material` spanning heights `y` over [-0.5, 0.5] in x and z.
fn slab(y: [f32; 2]) -> Vec<[[f32; 3]; 3]> {
    box_triangles([-0.5, y[0], -0.5], [0.5, y[1], 0.5])
}

/// Half the width of the ground the camera sees, 0.4 above it (its field of view is 1.5).
const HALF_VIEW: f64 = 0.372_7;

/// The ground (albedo 0.05) seen from 0.4 above it, straight down (the 16 x 16 pixels at the
/// centre of 32 x 32, x and z in [-HALF_VIEW, HALF_VIEW] / 2), with `meshes` (a name, triangles
/// and a material each) around, in a sun straight above: each channel of what the ground
/// receives as a share of the sun. The ground is dark, so that the light it sends back up and the
/// glass returns is under 0.5% of it.
fn light_on_ground(dir: &Path, meshes: Vec<(&str, Vec<[[f32; 3]; 3]>, Value)>) -> [f64; 3] {
    light_on_ground_by(dir, meshes, Method::Sppm)
}

/// [`light_on_ground`], rendered by `method`.
fn light_on_ground_by(
    dir: &Path,
    meshes: Vec<(&str, Vec<[[f32; 3]; 3]>, Value)>,
    method: Method,
) -> [f64; 3] {
    let mut gltf = GltfBuilder::default();
    let ground = gltf.material(diffuse([0.05, 0.05, 0.05]));
    gltf.mesh("Ground", &GROUND, ground);
    for (name, triangles, material) in meshes {
        let material = gltf.material(material);
        gltf.mesh(name, &triangles, material);
    }
    gltf.light(json!({"type": "directional", "intensity": 683.0}), [0.0, 5.0, 0.0], [0.0, -1.0, 0.0]);
    gltf.camera([0.0, 0.4, 0.0], [0.0, -1.0, 0.0], 1.5);
    gltf.scene_extras(json!({"resolution": [32, 32]}));
    let path = gltf.write(dir, "volume");
    let mut s = settings(&path, dir, 48);
    s.photons = Some(40_000);
    s.method = method;
    render(&s, 2).mean(8, 24, 8, 24).map(|c| c / (0.05 / std::f64::consts::PI))
}

/// The Rec.709 colour of the sun's spectrum (D65) times `kept(λ, c(λ))`, with `c` the spectrum
/// of attenuation colour `colour`, over the sun's own colour (1, 1, 1): what a channel of the
/// ground receives.
fn under_d65(colour: [f32; 3], kept: impl Fn(f64) -> f64) -> [f64; 3] {
    let c = RgbSpectrum::reflectance(Vec3::from(colour));
    let integral = |kept: &dyn Fn(f32) -> f64| {
        let xyz: glam::DVec3 =
            (360..=830).map(|l| l as f32).map(|l| (cmf(l) * d65(l)).as_dvec3() * kept(l)).sum();
        xyz_to_linear_rec709(xyz)
    };
    let (through, white) = (integral(&|l| kept(f64::from(c.eval(l)))), integral(&|_| 1.0));
    (through / white).to_array()
}

fn assert_channels(measured: [f64; 3], expected: [f64; 3], tolerance: f64, what: &str) {
    for c in 0..3 {
        assert!(
            (measured[c] / expected[c] - 1.0).abs() < tolerance,
            "{what}, channel {c}: {measured:?} vs {expected:?}"
        );
    }
}

/// Under a slab of tinted glass 0.1 thick whose attenuation colour is reached at 0.1, and under
/// a pane of the same glass with a thickness factor of 0.1, the ground receives
/// `(1 - R)^2 a / (1 - R^2 a^2)` of the sun at each wavelength, `a` the attenuation colour's
/// spectrum (one crossing) and R = 0.04 Fresnel's reflectance head on (the inner reflections
/// summed): per channel within 2%.
#[test]
fn a_tinted_slab_passes_what_beer_lambert_and_its_inner_reflections_give() {
    let dir = tempfile::tempdir().unwrap();
    let colour = [0.2, 0.6, 0.9];
    let r = 0.04;
    let expected = under_d65(colour, |a| (1.0 - r) * (1.0 - r) * a / (1.0 - r * r * a * a));
    let glass = tinted(1.5, colour, 0.1, 0.1, 0);
    let measured = light_on_ground(dir.path(), vec![("Slab", slab([0.5, 0.6]), glass.clone())]);
    assert_channels(measured, expected, 0.02, "slab");
    let pane: Vec<_> = GROUND.iter().map(|t| t.map(|p| [p[0] / 2.0, 0.6, p[2] / 2.0])).collect();
    let measured = light_on_ground(dir.path(), vec![("Pane", pane, glass)]);
    assert_channels(measured, expected, 0.02, "pane");
}

/// The same slab rendered by vertex connection and merging: every segment and connection inside
/// the glass is weighed by Beer–Lambert's transmittance, within the same 2%.
#[test]
fn a_tinted_slab_absorbs_as_beer_lambert_says_under_vcm_too() {
    let dir = tempfile::tempdir().unwrap();
    let colour = [0.2, 0.6, 0.9];
    let r = 0.04;
    let expected = under_d65(colour, |a| (1.0 - r) * (1.0 - r) * a / (1.0 - r * r * a * a));
    let glass = tinted(1.5, colour, 0.1, 0.1, 0);
    let measured = light_on_ground_by(dir.path(), vec![("Slab", slab([0.5, 0.6]), glass)], Method::Vcm);
    assert_channels(measured, expected, 0.02, "slab under vcm");
}

/// A `caustic` medium (Blender's Volume Absorption) of coefficient (1.2, 3.6, 6.0) per unit, in
/// boxes of index 1 (no reflection at their faces) from a quarter to four times the length 1/6
/// at which its blue keeps 1/e: the ground receives per-channel Beer–Lambert's
/// `exp(-coefficient × thickness)` (Cycles' absorption) within 3% per channel, by both methods.
/// One spectrum of coefficients passed 45% too much blue at four times that length.
#[test]
fn a_tinted_medium_passes_per_channel_beer_lambert_at_every_thickness() {
    let dir = tempfile::tempdir().unwrap();
    let coefficient = [1.2, 3.6, 6.0];
    let medium = json!({"pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, 1.0],
        "metallicFactor": 0.0, "roughnessFactor": 0.0},
        "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1.0}, "KHR_materials_ior": {"ior": 1.0}},
        "extras": {"caustic": {"medium": {"absorption": coefficient}}}});
    for (scale, method) in [(0.25, Method::Sppm), (1.0, Method::Vcm), (2.0, Method::Sppm), (4.0, Method::Vcm)]
    {
        let thickness = scale / 6.0;
        let box_ = slab([0.5, 0.5 + thickness]);
        let measured = light_on_ground_by(dir.path(), vec![("Medium", box_, medium.clone())], method);
        let expected = coefficient.map(|c| (-c * f64::from(thickness)).exp());
        assert_channels(measured, expected, 0.03, &format!("{thickness} thick, {method:?}"));
    }
}

/// Volumes of index 1 (no reflection at their faces), grey attenuation colours 0.5 (A) and 0.8
/// (B) at 0.1. B inside A: the light crosses 0.1 of each, and keeps 0.5 x 0.8. B overlapping
/// the top of A (A over heights 0.5 to 0.7, B over 0.6 to 0.8): of equal priority, the one
/// entered last fills the overlap (A, over 0.2: 0.25 x 0.8 kept); B of higher priority fills
/// it (B over 0.2, A over 0.1: 0.64 x 0.5). Within 2%.
#[test]
fn nested_and_overlapping_volumes_absorb_by_the_stack_and_its_priorities() {
    let dir = tempfile::tempdir().unwrap();
    let a = |priority| tinted(1.0, [0.5; 3], 0.1, 1.0, priority);
    let b = |priority| tinted(1.0, [0.8; 3], 0.1, 1.0, priority);
    let cases = [
        ("nested", [0.55, 0.65], 0, 0.5 * 0.8),
        ("overlapping", [0.6, 0.8], 0, 0.25 * 0.8),
        ("overlapping, B first", [0.6, 0.8], 1, 0.64 * 0.5),
    ];
    for (what, b_heights, b_priority, kept) in cases {
        let inner = box_triangles([-0.4, b_heights[0], -0.4], [0.4, b_heights[1], 0.4]);
        let meshes = vec![("A", slab([0.5, 0.7]), a(0)), ("B", inner, b(b_priority))];
        assert_channels(light_on_ground(dir.path(), meshes), [kept; 3], 0.02, what);
    }
}

/// A camera inside a volume (under water) sees through it from its first segment: the ground at
/// the bottom of a box of index 1 and grey attenuation colour 0.5 at 1, filled to 1 above the
/// ground, seen from 0.4 above it, shows the sun kept over 1 and the light it sends kept over the
/// distance to the camera (0.5^1.4 head on), within 2%.
#[test]
fn a_camera_inside_a_volume_sees_through_it() {
    let dir = tempfile::tempdir().unwrap();
    let water = box_triangles([-0.8, -0.1, -0.8], [0.8, 1.0, 0.8]);
    let measured = light_on_ground(dir.path(), vec![("Water", water, tinted(1.0, [0.5; 3], 1.0, 1.0, 0))]);
    // The mean over the pixels of what the way up to the camera keeps.
    let at = |i: usize| ((i as f64 + 0.5) / 32.0 * 2.0 - 1.0) * HALF_VIEW;
    let up: f64 = (8..24)
        .flat_map(|y| (8..24).map(move |x| (at(x), at(y))))
        .map(|(x, z)| 0.5f64.powf((0.16 + x * x + z * z).sqrt()))
        .sum::<f64>()
        / 256.0;
    assert_channels(measured, [0.5 * up; 3], 0.02, "under water");
}

/// The bundled gems and glass of water (scenes/make_scenes.py, exported through the add-on) load
/// with nothing left unrendered, their absorption and priorities read as the add-on wrote them:
/// the sapphire and the water absorb, the diamond, glass and ice do not; the glass (2) and the
/// ice (3) fill what they share with the water (0).
#[test]
fn the_bundled_gems_and_glass_of_water_carry_their_volumes() {
    let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut materials = Vec::new();
    for name in ["gems.gltf", "water_glass.gltf"] {
        let description = caustic::scene::Description::load(&scenes.join(name)).unwrap();
        assert!(description.warnings.is_empty(), "{name}: {:?}", description.warnings);
        materials
            .extend(description.materials.iter().map(|m| (m.name.clone(), m.volume.is_some(), m.priority)));
    }
    let of = |name: &str| {
        materials.iter().find(|(n, ..)| n == name).map(|&(_, absorbs, priority)| (absorbs, priority))
    };
    let expected = [
        ("Sapphire", true, 0),
        ("Diamond", false, 0),
        ("Water", true, 0),
        ("Tumbler glass", false, 2),
        ("Ice", false, 3),
    ];
    for (name, absorbs, priority) in expected {
        assert_eq!(of(name), Some((absorbs, priority)), "{name}: {materials:?}");
    }
}

/// A clear volume inside an absorbing one absorbs nothing: light down through a clear box of
/// index 1 (B, 0.1 high) inside a box of grey attenuation 0.5 at 0.1 (A, 0.2 high) crosses 0.1
/// of A (0.5 kept), within 2%; entered last, the clear box fills its inside.
#[test]
fn a_clear_inside_within_an_absorbing_one_absorbs_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let clear = json!({"pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, 1.0], "roughnessFactor": 0.0},
        "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1.0}, "KHR_materials_ior": {"ior": 1.0}}});
    let inner = box_triangles([-0.4, 0.55, -0.4], [0.4, 0.65, 0.4]);
    let meshes = vec![("A", slab([0.5, 0.7]), tinted(1.0, [0.5; 3], 0.1, 1.0, 0)), ("B", inner, clear)];
    assert_channels(light_on_ground(dir.path(), meshes), [0.5; 3], 0.02, "clear inside");
}
