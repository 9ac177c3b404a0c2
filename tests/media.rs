//! Media that absorb and scatter (the `caustic` extras' `medium` on a material, `fog` on the
//! scene), rendered end to end against closed forms: Beer–Lambert's law through absorbing fog and
//! through a box of absorbing medium, a furnace filled with a medium that only scatters, a spot
//! beam's glow in thin fog against its single-scattering line integral; the same bits with any
//! thread count, pass ranges that merge exactly, and media that are refused or not rendered.

mod common;

use caustic::frames::{self, RenderSettings};
use common::*;
use serde_json::{json, Value};
use std::f64::consts::PI;
use std::path::{Path, PathBuf};

/// A black, glowing square of radiance `radiance` (white) facing the camera at the origin from
/// `distance` along -z, filling the view, with `caustic` scene extras `extras` and `meshes` (a
/// name, triangles and a material each) besides; 16 x 16 pixels.
fn glow_through(
    dir: &Path,
    distance: f32,
    extras: Value,
    meshes: Vec<(&str, Vec<[[f32; 3]; 3]>, Value)>,
) -> PathBuf {
    let mut gltf = GltfBuilder::default();
    let glow = gltf.material(json!({"pbrMetallicRoughness": {"baseColorFactor": [0.0, 0.0, 0.0, 1.0]},
        "emissiveFactor": [1.0, 1.0, 1.0]}));
    let (z, h) = (-distance, 10.0);
    gltf.mesh("Glow", &[[[-h, -h, z], [h, -h, z], [h, h, z]], [[-h, -h, z], [h, h, z], [-h, h, z]]], glow);
    for (name, triangles, material) in meshes {
        let material = gltf.material(material);
        gltf.mesh(name, &triangles, material);
    }
    gltf.camera([0.0, 0.0, 0.0], [0.0, 0.0, -1.0], 0.3);
    let mut extras = extras;
    extras["resolution"] = json!([16, 16]);
    gltf.scene_extras(extras);
    gltf.write(dir, "glow")
}

/// Beer–Lambert's law: a glowing square 3 units away through fog that absorbs 0.4 per unit reads
/// `exp(-1.2)` of its radiance, and through a closed box (clear boundary of index 1, 2 units deep)
/// filled with a `caustic` medium absorbing 0.3 per unit, `exp(-0.6)`. Nothing scatters, so the
/// only noise is the wavelength integral: within 1%.
#[test]
fn absorbing_media_keep_what_beer_and_lambert_say() {
    let dir = tempfile::tempdir().unwrap();
    let fog = glow_through(dir.path(), 3.0, json!({"fog": {"absorption": [0.4, 0.4, 0.4]}}), vec![]);
    let image = render(&settings(&fog, dir.path(), 64), 2);
    let expected = (-1.2f64).exp();
    for (c, mean) in image.mean_all().iter().enumerate() {
        assert!((mean / expected - 1.0).abs() < 0.01, "fog, channel {c}: {mean} against {expected}");
    }
    let clear_box = json!({"pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, 1.0],
        "metallicFactor": 0.0, "roughnessFactor": 0.0},
        "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1.0}, "KHR_materials_ior": {"ior": 1.0}},
        "extras": {"caustic": {"medium": {"absorption": [0.3, 0.3, 0.3]}}}});
    let inside = box_triangles([-5.0, -5.0, -2.5], [5.0, 5.0, -0.5]);
    let boxed = glow_through(dir.path(), 3.0, json!({}), vec![("Medium", inside, clear_box)]);
    let image = render(&settings(&boxed, dir.path(), 64), 2);
    let expected = (-0.6f64).exp();
    for (c, mean) in image.mean_all().iter().enumerate() {
        assert!((mean / expected - 1.0).abs() < 0.01, "box, channel {c}: {mean} against {expected}");
    }
}

/// The bundled furnace (a closed cube whose walls have albedo 0.5 and emit 1: radiance 2
/// everywhere inside) with `fog` filling it.
fn furnace_with_fog(dir: &Path, fog: Value) -> PathBuf {
    write_edited(&bundled_scene("furnace.gltf"), dir, |doc| {
        let scene = doc["scene"].as_u64().unwrap_or(0) as usize;
        doc["scenes"][scene]["extras"]["caustic"]["fog"] = fog;
    })
}

/// A furnace filled with a medium that scatters (1 per unit, in a cube 2 units across) and
/// absorbs nothing: what it scatters out of a ray it scatters into it, so the radiance stays 2.
/// Tolerance: the image mean within 2% (measured 1.3% low at 256 passes of 16,384 photons, 32 x 32:
/// the gather sphere reaches past the walls near them, where no photons of the medium are), and
/// forward scattering (g = 0.6) changes nothing (measured within 0.3%).
#[test]
fn a_furnace_filled_with_a_scattering_medium_keeps_its_radiance() {
    let dir = tempfile::tempdir().unwrap();
    for anisotropy in [0.0, 0.6] {
        let path =
            furnace_with_fog(dir.path(), json!({"scattering": [1.0, 1.0, 1.0], "anisotropy": anisotropy}));
        let mut s = settings(&path, dir.path(), 256);
        s.resolution = Some([32, 32]);
        s.photons = Some(16384);
        let image = render(&s, 2);
        for (c, mean) in image.mean_all().iter().enumerate() {
            assert!((mean / 2.0 - 1.0).abs() < 0.02, "g {anisotropy}, channel {c}: mean {mean}, expected 2");
        }
    }
}

/// A spot light's beam: radiant intensity 1 W/sr along its axis `axis` within glTF's cone of
/// `inner` and `outer` half-angles (radians), ramping between them as glTF's squared falloff.
struct Beam {
    position: [f64; 3],
    axis: [f64; 3],
    inner: f64,
    outer: f64,
}

impl Beam {
    /// Its intensity toward `to` (a unit direction from the light).
    fn intensity(&self, to: [f64; 3]) -> f64 {
        let cos: f64 = (0..3).map(|k| to[k] * self.axis[k]).sum();
        let (cos_inner, cos_outer) = (self.inner.cos(), self.outer.cos());
        ((cos - cos_outer) / (cos_inner - cos_outer)).clamp(0.0, 1.0).powi(2)
    }
}

/// Radiance along the ray from the origin through pixel (x, y) of an n x n image of field of
/// view `fov` looking along -z, scattered once toward the camera by fog of scattering `sigma_s`
/// and extinction `sigma_t` (isotropic) from `beam`: `integral of exp(-sigma_t t) sigma_s /
/// (4 pi) I(direction) exp(-sigma_t r) / r^2 dt`, r the distance from the ray's point to the
/// light (midpoint rule, in steps of 1/4000 to t = 20; the beam's chord lies within it).
fn single_scattering(
    beam: &Beam,
    sigma_s: f64,
    sigma_t: f64,
    fov: f64,
    n: usize,
    (x, y): (usize, usize),
) -> f64 {
    let half = (fov / 2.0).tan();
    let u = ((x as f64 + 0.5) / n as f64 * 2.0 - 1.0) * half;
    let v = (1.0 - (y as f64 + 0.5) / n as f64 * 2.0) * half;
    let length = (u * u + v * v + 1.0).sqrt();
    let d = [u / length, v / length, -1.0 / length];
    let step = 1.0 / 4000.0;
    (0..80_000)
        .map(|i| {
            let t = (i as f64 + 0.5) * step;
            let to: [f64; 3] = std::array::from_fn(|k| d[k] * t - beam.position[k]);
            let r = to.iter().map(|c| c * c).sum::<f64>().sqrt();
            let intensity = beam.intensity(to.map(|c| c / r));
            (-sigma_t * (t + r)).exp() * sigma_s / (4.0 * PI) * intensity / (r * r) * step
        })
        .sum()
}

/// A spot light (683 cd: 1 W/sr, white; cone half-angles 0.49 and 0.5) pointing down in thin fog
/// (scattering 0.004, absorption 0.001 per unit) from a unit above the camera's view axis, 0.3 to
/// its side, 2 ahead: the camera's rays cross its beam. Nothing else but a black square far below.
/// The fog's glow is light scattered once, which next-event estimation along each eye segment
/// finds (equiangular sampling toward the light), plus light scattered more than once (the
/// photons'), which grows with the fog (measured 0.5% above the integral here; 0.8% for a point
/// light in this fog, 2.3% with 2.5 times it). Tolerance: the central 8 x 8 pixels' mean within 3%
/// of the single-scattering integral.
#[test]
fn a_spot_beam_glows_in_thin_fog_as_its_line_integral() {
    let dir = tempfile::tempdir().unwrap();
    let mut gltf = GltfBuilder::default();
    let black = gltf.material(diffuse([0.0, 0.0, 0.0]));
    gltf.quad_y("Far", -40.0, 1.0, true, black);
    let beam = Beam { position: [0.3, 1.0, -2.0], axis: [0.0, -1.0, 0.0], inner: 0.49, outer: 0.5 };
    let spot =
        json!({"type": "spot", "intensity": 683.0, "spot": {"innerConeAngle": 0.49, "outerConeAngle": 0.5}});
    gltf.light(spot, [0.3, 1.0, -2.0], [0.0, -1.0, 0.0]);
    gltf.camera([0.0, 0.0, 0.0], [0.0, 0.0, -1.0], 0.4);
    gltf.scene_extras(json!({"resolution": [16, 16], "fog": {"scattering": [0.004, 0.004, 0.004],
        "absorption": [0.001, 0.001, 0.001]}}));
    let path = gltf.write(dir.path(), "glow");
    let mut s = settings(&path, dir.path(), 256);
    s.photons = Some(4096);
    let image = render(&s, 2);
    let mut expected = 0.0;
    for y in 4..12 {
        for x in 4..12 {
            expected += single_scattering(&beam, 0.004, 0.005, 0.4, 16, (x, y)) / 64.0;
        }
    }
    let measured = image.luminance(4, 12, 4, 12);
    assert!((measured / expected - 1.0).abs() < 0.03, "glow {measured} against {expected}");
}

/// The fog furnace at 24 x 24, 1,500 photons a pass, into `out`.
fn fog_settings(dir: &Path, out: &Path, passes: u64) -> RenderSettings {
    let path = furnace_with_fog(
        dir,
        json!({"scattering": [0.8, 0.6, 0.4], "absorption": [0.1, 0.1, 0.1],
        "anisotropy": 0.3}),
    );
    let mut s = settings(&path, out, passes);
    s.resolution = Some([24, 24]);
    s.photons = Some(1500);
    s
}

/// The same bits with one thread and with two, and passes 0..3 and 3..6 merged give the 6-pass
/// render (within 1e-6 relative: sums in f64 added in another order).
#[test]
fn media_render_the_same_bits_on_any_threads_and_merge_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let s = fog_settings(dir.path(), &dir.path().join("whole"), 6);
    let (one, two) = (render(&s, 1), render(&s, 2));
    assert_eq!(one.rgb, two.rgb, "one thread against two");
    let parts = dir.path().join("parts");
    for passes in [0..3, 3..6] {
        let partial = RenderSettings {
            passes: None,
            out_dir: parts.clone(),
            partial_passes: Some(passes),
            ..s.clone()
        };
        frames::render(&partial).unwrap();
    }
    let files: Vec<PathBuf> = std::fs::read_dir(&parts).unwrap().map(|e| e.unwrap().path()).collect();
    let merged = frames::merge(&files, &dir.path().join("merged"), 0.9).unwrap();
    let merged = read_exr(&merged[0].0);
    for (a, b) in merged.rgb.iter().flatten().zip(two.rgb.iter().flatten()) {
        assert!((a - b).abs() <= 1e-6 * b.abs().max(1e-30), "merged {a} against whole {b}");
    }
}

/// Media the renderer cannot render are refused, naming the material or the fog and the field.
#[test]
fn impossible_media_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        (json!({"scattering": [1.0, -0.5, 1.0]}), "scattering"),
        (json!({"absorption": [0.1, 0.1, 1e39]}), "absorption"),
        (json!({"scattering": [1.0, 1.0, 1.0], "anisotropy": 1.0}), "anisotropy"),
        (json!({"scattering": [1.0, 1.0, 1.0], "anisotropy": -1.5}), "anisotropy"),
        (json!({"density": 2.0}), "density"),
    ];
    // What rendering `scene` into `out` printed, after checking it failed without a panic.
    let refusal = |scene: &Path, out: &str| {
        let out = dir.path().join(out);
        let args =
            [scene.to_str().unwrap(), "-o", out.to_str().unwrap(), "--passes", "1", "--resolution", "8x8"];
        let output = run_caustic(&[&["render"][..], &args, &["--progress", "none"]].concat());
        let text = String::from_utf8_lossy(&output.stderr).to_string();
        assert!(
            !output.status.success() && !text.contains("panicked"),
            "{} rendered: {text}",
            scene.display()
        );
        text
    };
    for (i, (medium, field)) in cases.into_iter().enumerate() {
        let text = refusal(&furnace_with_fog(dir.path(), medium.clone()), &format!("fog{i}"));
        assert!(text.contains("fog") && text.contains(field), "{medium}: {text}");
        let material = write_edited(&bundled_scene("furnace.gltf"), dir.path(), |doc| {
            doc["materials"][0]["extras"] = json!({"caustic": {"medium": medium.clone()}});
        });
        let text = refusal(&material, &format!("m{i}"));
        assert!(text.contains("material '") && text.contains(field), "{medium}: {text}");
    }
}

/// A medium on a material light never enters (no transmission) is named in a warning, and one
/// beside `KHR_materials_volume` says it replaces its attenuation.
#[test]
fn media_that_are_not_rendered_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let path = write_edited(&bundled_scene("furnace.gltf"), dir.path(), |doc| {
        doc["materials"][0]["extras"] = json!({"caustic": {"medium": {"scattering": [1.0, 1.0, 1.0]}}});
        doc["materials"][0]["extensions"]["KHR_materials_volume"] =
            json!({"attenuationColor": [0.5, 0.5, 0.5], "attenuationDistance": 1.0, "thicknessFactor": 1.0});
    });
    let warnings = caustic::scene::Description::load(&path).unwrap().warnings;
    let name = load_json(&path)["materials"][0]["name"].as_str().unwrap_or("unnamed").to_string();
    let about = |part: &str| warnings.iter().any(|w| w.contains(&format!("'{name}'")) && w.contains(part));
    assert!(about("medium is not rendered: light does not enter"), "{warnings:?}");
    assert!(about("its `caustic` medium replaces it"), "{warnings:?}");
}
