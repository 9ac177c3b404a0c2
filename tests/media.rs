//! Media that absorb and scatter (the `caustic` extras' `medium` on a material, `fog` on the
//! scene), rendered end to end against closed forms: Beer–Lambert's law through absorbing fog and
//! through a box of absorbing medium, a furnace filled with a medium that only scatters, a spot
//! beam's glow in thin fog against its single-scattering line integral; the same bits with any
//! thread count, pass ranges that merge exactly, and media that are refused or not rendered.

mod common;

use caustic::render::{self, RenderSettings};
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
/// Tolerance: the image mean within 2% (measured 1.4% low at 256 passes of 16,384 photons, 32 x 32,
/// and 0.7% low with forward scattering, g = 0.6; the gather in a sphere that this beam estimate
/// replaced measured 1.3% low).
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
        render::render(&partial).unwrap();
    }
    let files: Vec<PathBuf> = std::fs::read_dir(&parts).unwrap().map(|e| e.unwrap().path()).collect();
    let merged = render::merge(&files, &dir.path().join("merged"), 0.9).unwrap();
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

/// Where the lens-law scene's light is measured: `|x| <= 1` (the orthographic film's width) and
/// `0.25 <= y < 1`, any z.
const CONE_REGION: ([f64; 2], [f64; 2]) = ([-1.0, 1.0], [0.25, 1.0]);

/// Light's extinction in the lens-law scene's fog, per unit, and the camera's distance along z.
const CONE_FOG: f64 = 0.02;
const CONE_CAMERA_Z: f64 = 5.0;

/// The integral, along the ray from `o` in the unit direction `d` up to `t_end`, within
/// [`CONE_REGION`], of what the fog keeps of light from the lamp (which has come `before` through
/// fog to `o`) to the point and from the point to the camera.
fn seen_in_region(o: [f64; 3], d: [f64; 3], t_end: f64, before: f64) -> f64 {
    let (mut t0, mut t1) = (0.0f64, t_end);
    for (axis, [lo, hi]) in [(0, CONE_REGION.0), (1, CONE_REGION.1)] {
        if d[axis] == 0.0 {
            if o[axis] < lo || o[axis] >= hi {
                return 0.0;
            }
            continue;
        }
        let (a, b) = ((lo - o[axis]) / d[axis], (hi - o[axis]) / d[axis]);
        (t0, t1) = (t0.max(a.min(b)), t1.min(a.max(b)));
    }
    if t0 >= t1 {
        return 0.0;
    }
    // exp(-s (before + t)) exp(-s (camera_z - o_z - d_z t)) integrated over t.
    let rate = CONE_FOG * (1.0 - d[2]).max(1e-9);
    let scale = (-CONE_FOG * (before + CONE_CAMERA_Z - o[2])).exp();
    scale * ((-rate * t0).exp() - (-rate * t1).exp()) / rate
}

/// Unpolarised Fresnel reflectance from index `n1` into `n2` at incidence cosine `cos_i`
/// (1 past the critical angle).
fn fresnel(cos_i: f64, n1: f64, n2: f64) -> f64 {
    let sin_t2 = (n1 / n2).powi(2) * (1.0 - cos_i * cos_i);
    if sin_t2 >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin_t2).sqrt();
    let rs = (n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t);
    let rp = (n2 * cos_i - n1 * cos_t) / (n2 * cos_i + n1 * cos_t);
    (rs * rs + rp * rp) / 2.0
}

/// What a ray of unit power from `o` along `d` (having come `before` through fog) leaves in
/// [`CONE_REGION`] (as [`seen_in_region`]) through a glass ball of index `n` and radius `radius`
/// at `centre`, split at every surface into its reflection and refraction by Fresnel's law, for
/// `depth` more surfaces.
fn through_ball(
    o: [f64; 3],
    d: [f64; 3],
    before: f64,
    inside: bool,
    ball: ([f64; 3], f64, f64),
    depth: u32,
) -> f64 {
    let (centre, radius, n) = ball;
    let oc: [f64; 3] = std::array::from_fn(|k| o[k] - centre[k]);
    let b = (0..3).map(|k| oc[k] * d[k]).sum::<f64>();
    let c = (0..3).map(|k| oc[k] * oc[k]).sum::<f64>() - radius * radius;
    let disc = b * b - c;
    let t = if disc <= 0.0 {
        None
    } else if inside {
        Some(-b + disc.sqrt())
    } else {
        Some(-b - disc.sqrt()).filter(|&t| t > 1e-9)
    };
    let Some(t) = t else { return if inside { 0.0 } else { seen_in_region(o, d, f64::INFINITY, before) } };
    let outside_here = if inside { 0.0 } else { seen_in_region(o, d, t, before) };
    if depth == 0 {
        return outside_here;
    }
    let before = if inside { before } else { before + t };
    let p: [f64; 3] = std::array::from_fn(|k| o[k] + t * d[k]);
    let mut normal: [f64; 3] = std::array::from_fn(|k| (p[k] - centre[k]) / radius);
    if inside {
        normal = normal.map(|v| -v);
    }
    let cos_i = -(0..3).map(|k| d[k] * normal[k]).sum::<f64>();
    let (n1, n2) = if inside { (n, 1.0) } else { (1.0, n) };
    let reflectance = fresnel(cos_i, n1, n2);
    let reflected: [f64; 3] = std::array::from_fn(|k| d[k] + 2.0 * cos_i * normal[k]);
    let mut total = outside_here + reflectance * through_ball(p, reflected, before, inside, ball, depth - 1);
    if reflectance < 1.0 {
        let eta = n1 / n2;
        let cos_t = (1.0 - eta * eta * (1.0 - cos_i * cos_i)).sqrt();
        let refracted: [f64; 3] = std::array::from_fn(|k| eta * d[k] + (eta * cos_i - cos_t) * normal[k]);
        total += (1.0 - reflectance) * through_ball(p, refracted, before, !inside, ball, depth - 1);
    }
    total
}

/// The lens law's scene: a spot light (cone 0.24 rad, sharp) straight down from y = 3 into thin
/// fog that only scatters (0.02 per unit, isotropic), seen from the side by an orthographic camera
/// (a film 2 x 2 units centred at y = 1, 32 x 32 pixels), with a ball of glass (index 1.5, radius
/// 0.25, centred at y = 2: the whole cone falls on it) or without.
fn lens_law_scene(dir: &Path, ball: bool) -> PathBuf {
    let mut gltf = GltfBuilder::default();
    if ball {
        let glass = gltf.material(json!({"pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, 1.0],
            "metallicFactor": 0.0, "roughnessFactor": 0.0},
            "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1.0}, "KHR_materials_ior": {"ior": 1.5}}}));
        gltf.sphere("Ball", [0.0, 2.0, 0.0], 0.25, 64, glass);
    }
    let spot = json!({"type": "spot", "intensity": 683.0, "spot": {"innerConeAngle": 0.2399, "outerConeAngle": 0.24}});
    gltf.light(spot, [0.0, 3.0, 0.0], [0.0, -1.0, 0.0]);
    let camera = json!({"type": "orthographic", "orthographic": {"xmag": 1.0, "ymag": 1.0, "znear": 0.01, "zfar": 100.0}});
    gltf.camera_of(camera, [0.0, 1.0, CONE_CAMERA_Z as f32], [0.0, 0.0, -1.0]);
    let fog = CONE_FOG as f32;
    gltf.scene_extras(json!({"resolution": [32, 32], "fog": {"scattering": [fog, fog, fog], "absorption": [0.0, 0.0, 0.0]}}));
    gltf.write(dir, if ball { "ball" } else { "hole" })
}

/// The lens law: a glass ball in a spot light's beam focuses it into a cone of light behind it
/// that carries the beam's power, less what the glass reflects. The fog's glow below the ball,
/// summed over the film (`0.25 <= y < 1`, below the focus), is the scattering coefficient over
/// 4 pi times the integral of the light's power along its paths there; its ratio to the same sum
/// with the ball taken away (the beam itself, found by next-event estimation, where the cone is
/// the photons') is the ratio of those integrals, found here by tracing the spot's rays (a 400 x
/// 400 grid over its cone) through a perfect sphere, split by Fresnel's law at every surface, with
/// the fog's attenuation. Tolerance 3%: light scattered more than once (about 2% of either sum)
/// cancels mostly in the ratio; the ball's 64 rings of facets bend rays by under 0.1%.
#[test]
fn a_glass_ball_focuses_the_beams_power_into_the_cone_behind_it() {
    let dir = tempfile::tempdir().unwrap();
    let sum_below = |ball: bool| {
        let path = lens_law_scene(dir.path(), ball);
        let mut s = settings(&path, &dir.path().join(if ball { "out_ball" } else { "out_hole" }), 32);
        s.photons = Some(40_000);
        let image = render(&s, 2);
        image.luminance(0, 32, 16, 28)
    };
    let measured = sum_below(true) / sum_below(false);
    let (cone, n) = (0.24f64, 400);
    let mut through = [0.0, 0.0];
    for i in 0..n {
        let cos = 1.0 - (1.0 - cone.cos()) * (i as f64 + 0.5) / n as f64;
        let sin = (1.0 - cos * cos).sqrt();
        for j in 0..n {
            let phi = 2.0 * PI * (j as f64 + 0.5) / n as f64;
            let d = [sin * phi.cos(), -cos, sin * phi.sin()];
            through[0] += through_ball([0.0, 3.0, 0.0], d, 0.0, false, ([0.0, 2.0, 0.0], 0.25, 1.5), 6);
            through[1] += seen_in_region([0.0, 3.0, 0.0], d, f64::INFINITY, 0.0);
        }
    }
    let expected = through[0] / through[1];
    assert!(
        (measured / expected - 1.0).abs() < 0.03,
        "cone against beam {measured:.4}, the lens law {expected:.4}"
    );
}
