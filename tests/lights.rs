//! Light units, one light at a time, against closed forms: the value of the ground straight
//! under (or the emitter straight in front of) a camera with a narrow view.
//!
//! Each light is set so the ground of albedo 1 receives irradiance pi, i.e. reflects radiance 1.
//! Tolerance 2% (wavelength integration at 128 passes; the view's 0.05 rad spread is below 0.1%).

mod common;

use common::*;
use serde_json::{json, Value};
use std::f32::consts::PI;
use std::path::PathBuf;

/// A white ground (albedo 1) at y = 0 seen straight down from y = 1, with `add_light` adding the light.
fn ground_scene(add_light: impl FnOnce(&mut GltfBuilder)) -> GltfBuilder {
    let mut gltf = GltfBuilder::default();
    let material = gltf.material(diffuse([1.0, 1.0, 1.0]));
    gltf.quad_y("Ground", 0.0, 20.0, true, material);
    gltf.camera([0.0, 1.0, 0.0], [0.0, -1.0, 0.0], 0.05);
    gltf.scene_extras(json!({"resolution": [8, 8]}));
    add_light(&mut gltf);
    gltf
}

fn mean_luminance(path: &PathBuf, dir: &std::path::Path) -> f64 {
    render(&settings(path, dir, 128), 2).luminance(0, 8, 0, 8)
}

fn assert_near(value: f64, expected: f64, what: &str) {
    assert!((value / expected - 1.0).abs() < 0.02, "{what}: {value}, expected {expected}");
}

/// A point light of 4 pi W/sr (glTF candela = W/sr * 683) 2 above the ground: E = I / d^2 = pi.
#[test]
fn point_light_intensity_is_candela_over_683() {
    let dir = tempfile::tempdir().unwrap();
    let light = json!({"type": "point", "intensity": 4.0 * PI * 683.0, "color": [1.0, 1.0, 1.0]});
    let gltf = ground_scene(|g| g.light(light, [0.0, 2.0, 0.0], [0.0, -1.0, 0.0]));
    assert_near(mean_luminance(&gltf.write(dir.path(), "point"), dir.path()), 1.0, "point light");
}

/// The same point light with a radius of 0.3 (a sphere of light, Blender's radius in the
/// extras) emits the same power: the ground under it receives the same irradiance (a sphere
/// wholly above a point lights it as its centre would), and the camera sees the sphere's
/// radiance I / (pi r^2) where it looks at it. A sun's
/// radius is named in a warning.
#[test]
fn a_point_light_with_a_radius_is_a_sphere_of_the_same_power() {
    let dir = tempfile::tempdir().unwrap();
    let light = json!({"type": "point", "intensity": 4.0 * PI * 683.0, "color": [1.0, 1.0, 1.0]});
    let mut doc = ground_scene(|g| g.light(light, [0.0, 2.0, 0.0], [0.0, -1.0, 0.0])).to_json();
    let nodes = doc["nodes"].as_array_mut().unwrap();
    let node = nodes.iter_mut().find(|n| n.get("extensions").is_some()).unwrap();
    node["extras"] = json!({"caustic": {"radius": 0.3}});
    let path = dir.path().join("sphere.gltf");
    std::fs::write(&path, doc.to_string()).unwrap();
    assert_near(mean_luminance(&path, dir.path()), 1.0, "under a sphere light");
    // Seen from below, straight up into it: radiance 4 pi / (pi 0.3^2) over its disc.
    doc["nodes"].as_array_mut().unwrap().iter_mut().filter(|n| n.get("camera").is_some()).for_each(|n| {
        n["rotation"] = json!([std::f32::consts::FRAC_1_SQRT_2, 0.0, 0.0, std::f32::consts::FRAC_1_SQRT_2]);
    });
    std::fs::write(&path, doc.to_string()).unwrap();
    let expected = 4.0 / (0.3f64 * 0.3);
    let seen = mean_luminance(&path, dir.path());
    assert!((seen / expected - 1.0).abs() < 0.02, "the sphere's radiance: {seen} vs {expected}");
    // A sun's radius is not rendered, and says so.
    let sun = json!({"type": "directional", "intensity": 683.0});
    let mut doc = ground_scene(|g| g.light(sun, [0.0, 2.0, 0.0], [0.0, -1.0, 0.0])).to_json();
    let nodes = doc["nodes"].as_array_mut().unwrap();
    nodes.iter_mut().find(|n| n.get("extensions").is_some()).unwrap()["extras"] =
        json!({"caustic": {"radius": 0.3}});
    std::fs::write(&path, doc.to_string()).unwrap();
    let warnings = caustic::scene::Description::load(&path).unwrap().warnings;
    assert!(
        warnings.iter().any(|w| w.contains("radius is rendered for point and spot lights only")),
        "{warnings:?}"
    );
}

/// A spot light with a radius (Blender's: a sphere of light inside the spot's cone) lights the
/// ground under it as the spot's point does (a sphere wholly above a point lights it as its
/// centre would), and casts a soft shadow: a small disc just under it shades the ground below
/// it partly, where a point spot's shadow is whole.
#[test]
fn a_spot_light_with_a_radius_lights_as_its_point_and_softens_shadows() {
    let dir = tempfile::tempdir().unwrap();
    let render_spot = |radius: f32, blocker: bool| {
        let spot = json!({"type": "spot", "intensity": 4.0 * PI * 683.0, "spot": {"innerConeAngle": 0.5, "outerConeAngle": 0.6}});
        let mut gltf = ground_scene(|g| g.light(spot, [0.0, 2.0, 0.0], [0.0, -1.0, 0.0]));
        gltf.set_node_extras(gltf.last_node(), json!({"radius": radius}));
        if blocker {
            let black = gltf.material(diffuse([0.0, 0.0, 0.0]));
            gltf.mesh(
                "Blocker",
                &[
                    [[-0.05, 1.2, -0.05], [0.05, 1.2, 0.05], [0.05, 1.2, -0.05]],
                    [[-0.05, 1.2, -0.05], [-0.05, 1.2, 0.05], [0.05, 1.2, 0.05]],
                ],
                black,
            );
        }
        mean_luminance(&gltf.write(dir.path(), "spot_sphere"), dir.path())
    };
    assert_near(render_spot(0.3, false), 1.0, "under a spot sphere");
    let (hard, soft) = (render_spot(0.0, true), render_spot(0.3, true));
    assert!(hard < 0.02, "a point spot's shadow is whole: {hard}");
    assert!(soft > 0.3 && soft < 0.95, "a spot sphere's shadow is partial: {soft}");
}

/// A spot light of the same intensity pointing down lights the ground under it the same, and
/// nothing outside its outer cone.
#[test]
fn spot_light_lights_only_inside_its_cone() {
    let dir = tempfile::tempdir().unwrap();
    let spot = |direction: [f32; 3]| {
        let light: Value = json!({"type": "spot", "intensity": 4.0 * PI * 683.0, "color": [1.0, 1.0, 1.0],
            "spot": {"innerConeAngle": 0.3, "outerConeAngle": 0.4}});
        let gltf = ground_scene(|g| g.light(light, [0.0, 2.0, 0.0], direction));
        mean_luminance(&gltf.write(dir.path(), "spot"), dir.path())
    };
    assert_near(spot([0.0, -1.0, 0.0]), 1.0, "inside the cone");
    let outside = spot([1.0, -1.0, 0.0]);
    assert!(outside < 1e-3, "outside the cone: {outside}");
}

/// A Blender area light (caustic extras) of power P, small (0.1 wide) and 2 above the ground
/// facing down: E = P / (pi d^2) (radiance P / (pi A) over solid angle A / d^2), so P = 4 pi^2.
#[test]
fn area_light_power_is_watts() {
    let dir = tempfile::tempdir().unwrap();
    let area = json!({"area_light": {"shape": "SQUARE", "size": 0.1, "power": 4.0 * PI * PI}});
    let gltf = ground_scene(|g| g.extras_node("Area", area, [0.0, 2.0, 0.0], [0.0, -1.0, 0.0]));
    assert_near(mean_luminance(&gltf.write(dir.path(), "area"), dir.path()), 1.0, "area light");
}

/// Blender's Spread narrows an area light into a beam that keeps its power (Cycles' soft-box
/// model): a small light (0.02 wide, so that what the camera sees lies within 0.7 degrees of its
/// axis) 2 above the ground, of the power of `area_light_power_is_watts`, with a spread of 120
/// degrees lights the ground straight under it tan(60) / (tan(60) - pi / 3) times as brightly,
/// and ground 63 degrees off its axis not at all.
#[test]
fn an_area_lights_spread_narrows_it_into_a_beam_of_the_same_power() {
    let dir = tempfile::tempdir().unwrap();
    let lit = |name: &str, at: [f32; 3], spread_deg: f32| {
        let area = json!({"area_light": {"shape": "SQUARE", "size": 0.02, "power": 4.0 * PI * PI,
            "spread_deg": spread_deg}});
        let gltf = ground_scene(|g| g.extras_node("Area", area, at, [0.0, -1.0, 0.0]));
        mean_luminance(&gltf.write(dir.path(), name), dir.path())
    };
    let half = 60f32.to_radians();
    assert_near(
        lit("beam", [0.0, 2.0, 0.0], 120.0),
        f64::from(half.tan() / (half.tan() - half)),
        "under the beam",
    );
    assert_near(lit("wide", [0.0, 2.0, 0.0], 180.0), 1.0, "under a light of spread 180");
    let beside = lit("beside", [4.0, 2.0, 0.0], 120.0);
    assert!(beside == 0.0, "63 degrees off the beam's axis: {beside}");
}

/// Area lights are not surfaces, as in Blender: a wide one hung between the light above and the
/// ground, facing up, casts no shadow, so the ground still reflects radiance 1.
#[test]
fn area_lights_cast_no_shadow() {
    let dir = tempfile::tempdir().unwrap();
    let area = json!({"area_light": {"shape": "SQUARE", "size": 0.1, "power": 4.0 * PI * PI}});
    let screen = json!({"area_light": {"shape": "SQUARE", "size": 3.0, "power": 10.0}});
    let gltf = ground_scene(|g| {
        g.extras_node("Area", area, [0.0, 2.0, 0.0], [0.0, -1.0, 0.0]);
        g.extras_node("Screen", screen, [0.0, 1.5, 0.0], [0.0, 1.0, 0.0]);
    });
    assert_near(mean_luminance(&gltf.write(dir.path(), "screened"), dir.path()), 1.0, "ground under a light");
}

/// An emissive surface seen straight on has radiance emissiveFactor * emissive_strength (no 683).
#[test]
fn emissive_strength_scales_the_emitted_radiance() {
    let dir = tempfile::tempdir().unwrap();
    let mut gltf = GltfBuilder::default();
    let material = gltf.material(json!({"emissiveFactor": [0.5, 0.5, 0.5],
        "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 4.0}},
        "pbrMetallicRoughness": {"baseColorFactor": [0.0, 0.0, 0.0, 1.0]}}));
    gltf.quad_y("Panel", 0.0, 5.0, true, material);
    gltf.camera([0.0, 1.0, 0.0], [0.0, -1.0, 0.0], 0.05);
    gltf.scene_extras(json!({"resolution": [8, 8]}));
    let path = gltf.write(dir.path(), "panel");
    assert_near(render(&settings(&path, dir.path(), 128), 2).luminance(0, 8, 0, 8), 2.0, "emissive panel");
}

/// The same scene as `.gltf` (buffer in a data URI) and `.glb` (buffer in the BIN chunk) renders
/// the same bits.
#[test]
fn glb_and_gltf_render_the_same() {
    let dir = tempfile::tempdir().unwrap();
    let light = json!({"type": "point", "intensity": 4.0 * PI * 683.0, "color": [1.0, 0.5, 0.2]});
    let gltf = ground_scene(|g| g.light(light, [0.0, 2.0, 0.0], [0.0, -1.0, 0.0]));
    let images: Vec<Image> = [gltf.write(dir.path(), "scene"), gltf.write_glb(dir.path(), "scene")]
        .iter()
        .map(|path| render(&settings(path, &dir.path().join(path.extension().unwrap()), 4), 1))
        .collect();
    assert_eq!(images[0].rgb, images[1].rgb);
}

/// A base-colour texture (8-bit sRGB PNG, two red texels then two blue ones) times the factor
/// colours the ground: each half reflects its texels' linear colour (2%, plus 0.003 absolute for
/// channels near zero, whose values are small differences of large XYZ terms; measured away from
/// where the bilinear lookup blends red into blue).
#[test]
fn base_colour_textures_colour_the_ground() {
    let dir = tempfile::tempdir().unwrap();
    let texels = image::RgbImage::from_fn(4, 1, |x, _| {
        if x < 2 {
            image::Rgb([200, 40, 40])
        } else {
            image::Rgb([30, 60, 220])
        }
    });
    texels.save(dir.path().join("checker.png")).unwrap();
    let mut gltf = GltfBuilder::default();
    let texture = gltf.texture("checker.png");
    let material = gltf.material(json!({"pbrMetallicRoughness": {"baseColorTexture": {"index": texture},
        "baseColorFactor": [1.0, 1.0, 1.0, 1.0], "metallicFactor": 0.0},
        "extensions": {"KHR_materials_specular": {"specularFactor": 0.0}}}));
    // The ground spans x in [-1, 1]: u = (x + 1) / 2, so the red texels are at x < 0.
    let (a, b, c, d) = ([-1.0, 0.0, -1.0], [-1.0, 0.0, 1.0], [1.0, 0.0, 1.0], [1.0, 0.0, -1.0]);
    let uv = |p: [f32; 3]| [(p[0] + 1.0) / 2.0, (p[2] + 1.0) / 2.0];
    gltf.mesh_with_uvs(
        "Ground",
        &[[a, b, c], [a, c, d]],
        &[uv(a), uv(b), uv(c), uv(a), uv(c), uv(d)],
        material,
    );
    gltf.light(json!({"type": "directional", "intensity": PI * 683.0}), [0.0, 5.0, 0.0], [0.0, -1.0, 0.0]);
    gltf.camera([0.0, 4.0, 0.0], [0.0, -1.0, 0.0], 0.5);
    gltf.scene_extras(json!({"resolution": [32, 32]}));
    let path = gltf.write(dir.path(), "textured");
    let image = render(&settings(&path, dir.path(), 512), 2);
    let linear = |c: u8| {
        let c = f64::from(c) / 255.0;
        if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    };
    // The view spans x in [-1.02, 1.02]: pixels 6..10 see x in [-0.64, -0.39], all red.
    for (x0, texel) in [(6, [200, 40, 40]), (22, [30, 60, 220])] {
        let mean = image.mean(x0, x0 + 4, 14, 18);
        for ch in 0..3 {
            let expected = linear(texel[ch]);
            assert!(
                (mean[ch] - expected).abs() < 0.02 * expected + 0.003,
                "texel {texel:?} channel {ch}: {} vs {expected}",
                mean[ch]
            );
        }
    }
}

/// A sun with an angular diameter (Blender's angle, in the node's caustic extras) still delivers
/// its irradiance: the ground reflects 1 as under a delta sun, but through light sampling and
/// BSDF sampling of the sun's disc combined.
#[test]
fn a_sun_with_an_angular_diameter_keeps_its_irradiance() {
    let dir = tempfile::tempdir().unwrap();
    let gltf = ground_scene(|g| {
        g.light(json!({"type": "directional", "intensity": PI * 683.0}), [0.0, 5.0, 0.0], [0.0, -1.0, 0.0]);
    });
    let mut doc = gltf.to_json();
    let sun = doc["nodes"].as_array().unwrap().len() - 1;
    doc["nodes"][sun]["extras"] = json!({"caustic": {"sun_angle_deg": 20.0}});
    let path = dir.path().join("sun.gltf");
    std::fs::write(&path, doc.to_string()).unwrap();
    assert_near(mean_luminance(&path, dir.path()), 1.0, "sun of 20 degrees");
}

/// Node transforms nest: a point light 1 above its parent, which is 1 above the ground, is 2
/// above the ground (E = pi, radiance 1), not 1 (which would give 4).
#[test]
fn node_transforms_nest() {
    let dir = tempfile::tempdir().unwrap();
    let light = json!({"type": "point", "intensity": 4.0 * PI * 683.0});
    let gltf = ground_scene(|g| g.light(light, [0.0, 1.0, 0.0], [0.0, -1.0, 0.0]));
    let mut doc = gltf.to_json();
    let nodes = doc["nodes"].as_array_mut().unwrap();
    let light_node = nodes.len() - 1;
    nodes.push(json!({"name": "Parent", "translation": [0.0, 1.0, 0.0], "children": [light_node]}));
    let parent = nodes.len() - 1;
    let roots: Vec<usize> = (0..parent).filter(|&n| n != light_node).chain([parent]).collect();
    doc["scenes"][0]["nodes"] = json!(roots);
    let path = dir.path().join("nested.gltf");
    std::fs::write(&path, doc.to_string()).unwrap();
    assert_near(mean_luminance(&path, dir.path()), 1.0, "nested point light");
}
