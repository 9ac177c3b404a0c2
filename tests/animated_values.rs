//! Animated values (`KHR_animation_pointer` and the `caustic.tracks` extras): a light's intensity
//! and colour, a material's emission, an area light's power and a camera's zoom, at frames where
//! the answer is known.

mod common;

use caustic::scene::description::Description;
use common::*;
use serde_json::json;
use std::path::{Path, PathBuf};

/// Frames per second of the scenes: frame f is at f / 24 s.
const FPS: f32 = 24.0;

/// The values the lit-floor scene animates between frame 0 and frame 10, and what its file
/// says at rest (which no frame shows once a track sets the value).
struct Lit {
    intensity: [f32; 2],
    colour: [[f32; 3]; 2],
    strength: [f32; 2],
    area_power: [f32; 2],
}

const LIT: Lit = Lit {
    intensity: [100.0, 500.0],
    colour: [[1.0, 1.0, 1.0], [1.0, 0.5, 0.25]],
    strength: [1.0, 5.0],
    area_power: [20.0, 80.0],
};

/// A grey floor lit by a point light and an area light, with a glowing square on it, seen from
/// above; the light's intensity and colour, the square's emission strength and the area light's
/// power are animated from frame 0 to frame 10 (`animated`), or fixed at `still`'s values.
fn lit_floor(dir: &Path, name: &str, still: Option<[f32; 4]>, colour: [f32; 3]) -> PathBuf {
    let [intensity, strength, area_power] = match still {
        Some([i, s, a, _]) => [i, s, a],
        None => [7.0, 0.3, 3.0],
    };
    let mut gltf = GltfBuilder::default();
    let grey = gltf.material(diffuse([0.5, 0.5, 0.5]));
    gltf.quad_y("Floor", 0.0, 2.0, true, grey);
    let glow = gltf.material(json!({"emissiveFactor": [1.0, 0.8, 0.6],
        "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": strength}},
        "pbrMetallicRoughness": {"baseColorFactor": [0.0, 0.0, 0.0, 1.0]}}));
    gltf.quad_y("Glow", 0.01, 0.3, true, glow);
    gltf.light(
        json!({"type": "point", "intensity": intensity, "color": colour}),
        [0.8, 1.5, 0.0],
        [0.0, -1.0, 0.0],
    );
    gltf.extras_node(
        "Area",
        json!({"area_light": {"shape": "SQUARE", "size": 0.5, "power": area_power, "color": [1.0, 1.0, 1.0]}}),
        [-0.8, 1.5, 0.0],
        [0.0, -1.0, 0.0],
    );
    let area = gltf.last_node();
    gltf.camera([0.0, 4.0, 0.01], [0.0, -1.0, -0.0025], 0.9);
    let mut extras = json!({"resolution": [64, 64], "fps": FPS});
    if still.is_none() {
        let times = [0.0, 10.0 / FPS];
        let pair = |a: f32, b: f32| [vec![a], vec![b]];
        gltf.animate_pointer(
            "/extensions/KHR_lights_punctual/lights/0/intensity",
            &times,
            &pair(LIT.intensity[0], LIT.intensity[1]),
            "LINEAR",
        );
        gltf.animate_pointer(
            "/extensions/KHR_lights_punctual/lights/0/color",
            &times,
            &[LIT.colour[0].to_vec(), LIT.colour[1].to_vec()],
            "LINEAR",
        );
        let strength = "/materials/1/extensions/KHR_materials_emissive_strength/emissiveStrength";
        gltf.animate_pointer(strength, &times, &pair(LIT.strength[0], LIT.strength[1]), "LINEAR");
        extras["tracks"] = json!([{"pointer": format!("/nodes/{area}/extras/caustic/area_light/power"),
            "times": times, "values": LIT.area_power}]);
    }
    gltf.scene_extras(extras);
    gltf.write(dir, name)
}

/// The value at `frame` of a LINEAR track from `pair[0]` at frame 0 to `pair[1]` at frame 10.
fn at(pair: [f32; 2], frame: u32) -> f32 {
    pair[0] + (pair[1] - pair[0]) * frame as f32 / 10.0
}

fn render_frame(path: &Path, out: &Path, frame: u32) -> Image {
    let mut s = settings(path, out, 16);
    s.photons = Some(2000);
    // The photons (the few the glowing square's specular layer sends back to the floor) are
    // chosen among the lights by the animated lights' peak powers, but by the still scene's
    // own: their noise differs. A radius like 2% of the scene keeps it under the tolerance; the
    // default, a fifth of a view that the probe finds no photon in, gathers 50 times as many.
    s.radius = Some(0.11);
    s.frames = vec![frame as i32];
    render(&s, 2)
}

/// Frames 3 and 10 of the animated scene equal the still scene written with each value at that
/// frame (within float rounding: the same light paths, the same seed), and the values at rest in
/// the file are not what is seen.
#[test]
fn animated_light_emission_and_area_power_match_their_keys() {
    let dir = tempfile::tempdir().unwrap();
    let animated = lit_floor(dir.path(), "animated", None, [0.2, 0.2, 1.0]);
    for frame in [3, 10] {
        let colour = std::array::from_fn(|c| at([LIT.colour[0][c], LIT.colour[1][c]], frame));
        let values = [at(LIT.intensity, frame), at(LIT.strength, frame), at(LIT.area_power, frame), 0.0];
        let still = lit_floor(dir.path(), &format!("still{frame}"), Some(values), colour);
        let a = render_frame(&animated, &dir.path().join(format!("a{frame}")), frame);
        let b = render_frame(&still, &dir.path().join(format!("b{frame}")), frame);
        let scale = b.mean_all().iter().copied().fold(0.0, f64::max);
        let rmse = a.rmse(&b) / scale;
        eprintln!("frame {frame}: relative RMSE {rmse:.2e} between the animated and the still scene");
        assert!(scale > 0.01, "the scene is lit");
        assert!(
            rmse < 1e-4,
            "frame {frame}: the animated scene differs from its keys' values (relative RMSE {rmse:.2e})"
        );
    }
    // At rest the file says an intensity of 7 and a strength of 0.3: a renderer that ignored the
    // tracks would show frame 10 far darker.
    let rest = lit_floor(dir.path(), "rest", Some([7.0, 0.3, 3.0, 0.0]), [0.2, 0.2, 1.0]);
    let a = render_frame(&animated, &dir.path().join("a10b"), 10);
    let r = render_frame(&rest, &dir.path().join("rest10"), 10);
    assert!(a.mean_all()[0] > 5.0 * r.mean_all()[0], "{:?} vs rest {:?}", a.mean_all(), r.mean_all());
}

/// A camera zooming from a field of view of 0.8 to 0.4 rad: a glowing square's width at frames 0
/// and 10 is its projection at that field of view (within 1 pixel), twice as wide zoomed in,
/// and the same file as a GLB gives the same frame.
#[test]
fn a_camera_zoom_scales_the_projected_size() {
    let dir = tempfile::tempdir().unwrap();
    let mut gltf = GltfBuilder::default();
    let glow = gltf.material(json!({"emissiveFactor": [1.0, 1.0, 1.0],
        "pbrMetallicRoughness": {"baseColorFactor": [0.0, 0.0, 0.0, 1.0]}}));
    gltf.quad_y("Glow", 0.0, 0.25, true, glow);
    gltf.camera([0.0, 5.0, 0.0], [0.0, -1.0, -0.0001], 0.8);
    let yfov = [0.8, 0.4];
    gltf.animate_pointer(
        "/cameras/0/perspective/yfov",
        &[0.0, 10.0 / FPS],
        &[vec![yfov[0]], vec![yfov[1]]],
        "LINEAR",
    );
    gltf.scene_extras(json!({"resolution": [96, 96], "fps": FPS}));
    let path = gltf.write(dir.path(), "zoom");
    let glb = gltf.write_glb(dir.path(), "zoom");
    let mut widths = Vec::new();
    for (frame, fov) in [(0, yfov[0]), (10, yfov[1])] {
        let image = render_frame(&path, &dir.path().join(format!("zoom{frame}")), frame);
        let row: Vec<f64> = (0..96).map(|x| image.luminance(x, x + 1, 47, 49)).collect();
        let lit = row.iter().filter(|&&v| v > 0.5).count() as f64;
        // Half the square (0.25) at 5 units, over the half-height of the film at that field of view.
        let expected = 96.0 * 0.25 / (5.0 * (f64::from(fov) / 2.0).tan());
        eprintln!("frame {frame}: the square is {lit} px wide, its projection {expected:.1} px");
        assert!((lit - expected).abs() <= 1.0, "frame {frame}: {lit} px, expected {expected:.1}");
        widths.push(lit);
        if frame == 10 {
            let from_glb = render_frame(&glb, &dir.path().join("zoom_glb"), frame);
            assert_eq!(from_glb.rgb, image.rgb, "the GLB renders as the .gltf does");
        }
    }
    assert!(widths[1] > 1.9 * widths[0], "zoomed in, the square is about twice as wide: {widths:?}");
}

/// A pointer Caustic does not render is named in a warning; the scene still renders its value
/// at rest.
#[test]
fn an_unrendered_pointer_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let mut gltf = GltfBuilder::default();
    let grey = gltf.material(diffuse([0.5, 0.5, 0.5]));
    gltf.quad_y("Floor", 0.0, 2.0, true, grey);
    gltf.light(json!({"type": "point", "intensity": 50.0, "range": 10.0}), [0.0, 1.5, 0.0], [0.0, -1.0, 0.0]);
    gltf.camera([0.0, 4.0, 0.01], [0.0, -1.0, 0.0], 0.9);
    let pointer = "/extensions/KHR_lights_punctual/lights/0/range";
    gltf.animate_pointer(pointer, &[0.0, 1.0], &[vec![10.0], vec![20.0]], "LINEAR");
    let path = gltf.write(dir.path(), "range");
    let scene = Description::load(&path).unwrap();
    let expected = format!("animation pointer '{pointer}' is not rendered");
    assert!(scene.warnings.iter().any(|w| w == &expected), "{:?}", scene.warnings);
}

/// `caustic info` lists what is animated: the light (by node) and its values, the materials
/// (the area light's too) and the camera's field of view; the light and the camera change, so
/// they are not shared across frames.
#[test]
fn info_lists_the_animated_values() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("animated.gltf");
    std::fs::write(&path, animated_values().to_string()).unwrap();
    let output = run_caustic(&["info", path.to_str().unwrap(), "--frames", "1-24"]);
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let info: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    let animated = &info["animated"];
    assert_eq!(animated["lights"], json!([{"node": 2, "values": ["intensity", "colour"]}]), "{animated}");
    assert_eq!(animated["materials"][0], json!({"material": "Glow", "values": ["emissive_strength"]}));
    assert_eq!(animated["materials"][1]["values"], json!(["emissive_strength"]), "the area light's power");
    assert_eq!(animated["camera"], json!(["yfov"]));
    assert_eq!(
        (info["needs"]["moving_lights"].as_bool(), info["needs"]["moving_camera"].as_bool()),
        (Some(true), Some(true))
    );
}

/// A sun's caustic under a glass ball, next to a point light whose intensity is animated: photons
/// choose the animated light by its peak power and the sun by its own, so the sun's caustic (which
/// only photons carry) is as bright as in the same scene with nothing animated, within 5%; with
/// and without a world (the world is the last light, which an animated light once shifted).
#[test]
fn a_sun_keeps_its_photons_beside_an_animated_light() {
    for world in [false, true] {
        sun_beside_an_animated_light(world);
    }
}

fn sun_beside_an_animated_light(world: bool) {
    let dir = tempfile::tempdir().unwrap();
    let scene = |animated: bool| {
        let mut gltf = GltfBuilder::default();
        let white = gltf.material(diffuse([0.8, 0.8, 0.8]));
        gltf.quad_y("Floor", 0.0, 3.0, true, white);
        let glass = gltf.material(json!({"pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.0},
            "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1.0}}}));
        gltf.sphere("Ball", [0.0, 0.6, 0.0], 0.4, 24, glass);
        gltf.light(json!({"type": "directional", "intensity": 2000.0}), [0.0, 5.0, 0.0], [0.0, -1.0, 0.0]);
        gltf.light(json!({"type": "point", "intensity": 50.0}), [2.5, 1.0, 0.0], [0.0, -1.0, 0.0]);
        if animated {
            let keys = [vec![50.0], vec![400.0]];
            gltf.animate_pointer(
                "/extensions/KHR_lights_punctual/lights/1/intensity",
                &[0.0, 1.0],
                &keys,
                "LINEAR",
            );
        }
        gltf.camera([0.0, 3.0, 0.01], [0.0, -1.0, -0.0025], 0.5);
        let mut extras = json!({"resolution": [64, 64]});
        if world {
            extras["world"] = json!({"color": [0.3, 0.3, 0.3], "strength": 1.0});
        }
        gltf.scene_extras(extras);
        gltf.write(dir.path(), if animated { "animated" } else { "still" })
    };
    let caustic = |path: &Path, out: &str| {
        let mut s = settings(path, &dir.path().join(out), 64);
        s.photons = Some(20_000);
        s.frames = vec![0];
        render(&s, 2).luminance(28, 36, 28, 36)
    };
    let (animated, still) = (caustic(&scene(true), "a"), caustic(&scene(false), "b"));
    eprintln!(
        "the sun's caustic (world {world}): {animated:.3} beside an animated light, {still:.3} without"
    );
    assert!((animated / still - 1.0).abs() < 0.05, "{animated} against {still}");
}
