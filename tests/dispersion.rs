//! The dispersion regression suite: scenes in `scenes/` with analytic answers.
//!
//! Each scene carries its question in `caustic.regression` (see scenes/make_regression_scenes.py):
//! - prism: at 450, 550 and 650 nm the beam lands where Snell's law through the prism puts it
//!   (within 1 pixel), and red is deviated least (nearest the undeviated beam);
//! - prism with a constant index: one white band, no colour fringe;
//! - rainbow: the primary bow's angle at 450 and 650 nm is Descartes' minimum-deviation angle for
//!   water's index at that wavelength (within 0.5 degrees).
//! Renders at one fixed wavelength use `--wavelength` (the settings' `wavelength_nm`).

mod common;

use caustic::scene::Scene;
use caustic::spectrum::Dispersion;
use common::*;
use glam::{DVec2, DVec3, Vec3};
use serde_json::Value;
use std::path::Path;

/// The scene's `caustic.regression` metadata.
fn regression(path: &Path) -> Value {
    load_json(path)["scenes"][0]["extras"]["caustic"]["regression"].clone()
}

fn dvec3(v: &Value) -> DVec3 {
    DVec3::new(v[0].as_f64().unwrap(), v[1].as_f64().unwrap(), v[2].as_f64().unwrap())
}

/// Refracts unit `d` at unit normal `n` (facing against `d`) from index `n1` into `n2`.
fn refract(d: DVec2, n: DVec2, n1: f64, n2: f64) -> DVec2 {
    let eta = n1 / n2;
    let cos_i = -n.dot(d);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i);
    assert!(sin2_t < 1.0, "total internal reflection in the analytic trace");
    eta * d + (eta * cos_i - (1.0 - sin2_t).sqrt()) * n
}

/// Where a ray from `o` along `d` meets the segment a-b, if it does (parameter t > 0).
fn hit_segment(o: DVec2, d: DVec2, a: DVec2, b: DVec2) -> Option<(f64, DVec2)> {
    let e = b - a;
    let denom = d.perp_dot(e);
    if denom.abs() < 1e-12 {
        return None;
    }
    let t = (a - o).perp_dot(e) / denom;
    let s = (a - o).perp_dot(d) / denom;
    (t > 1e-9 && (0.0..=1.0).contains(&s)).then(|| (t, o + t * d))
}

/// The analytic path of the beam's axis through the prism at index `n`: the exit point and
/// direction (2-D, in the prism's cross-section plane z = 0).
fn trace_prism(question: &Value, n: f64) -> (DVec2, DVec2) {
    let corners: Vec<DVec2> = question["prism_2d"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| DVec2::new(p[0].as_f64().unwrap(), p[1].as_f64().unwrap()))
        .collect();
    let faces = [(corners[0], corners[1]), (corners[1], corners[2]), (corners[2], corners[0])];
    let outward = |a: DVec2, b: DVec2| -(b - a).perp().normalize(); // corners run counter-clockwise
    let (mut o, mut d) =
        (dvec3(&question["beam_origin"]).truncate(), dvec3(&question["beam_direction"]).truncate());
    let mut inside = false;
    for _ in 0..2 {
        let (_, point, face) = faces
            .iter()
            .filter_map(|&(a, b)| hit_segment(o, d, a, b).map(|(t, p)| (t, p, (a, b))))
            .min_by(|x, y| x.0.total_cmp(&y.0))
            .expect("the beam meets the prism");
        let normal = outward(face.0, face.1);
        d = if inside { refract(d, -normal, n, 1.0) } else { refract(d, normal, 1.0, n) };
        o = point;
        inside = !inside;
    }
    (o, d)
}

/// Where the beam of index `n` lands on the screen, in 3-D.
fn landing_point(question: &Value, n: f64) -> DVec3 {
    let (exit, dir) = trace_prism(question, n);
    let (p, normal) = (dvec3(&question["screen_point"]), dvec3(&question["screen_normal"]));
    let (o, d) = (exit.extend(0.0), dir.extend(0.0));
    o + d * ((p - o).dot(normal) / d.dot(normal))
}

/// Luminance-weighted centroid (pixels) of the pixels above a fifth of the brightest, within
/// `reach` pixels of `around`.
fn centroid(image: &Image, around: DVec2, reach: f64) -> DVec2 {
    let luminance = |x: usize, y: usize| image.luminance(x, x + 1, y, y + 1);
    let in_window =
        |x: usize, y: usize| (DVec2::new(x as f64 + 0.5, y as f64 + 0.5) - around).length() <= reach;
    let pixels: Vec<(usize, usize)> = (0..image.height)
        .flat_map(|y| (0..image.width).map(move |x| (x, y)))
        .filter(|&(x, y)| in_window(x, y))
        .collect();
    let peak = pixels.iter().map(|&(x, y)| luminance(x, y)).fold(0.0, f64::max);
    let (mut sum, mut weight) = (DVec2::ZERO, 0.0);
    for (x, y) in pixels {
        let l = luminance(x, y);
        if l > 0.2 * peak {
            sum += DVec2::new(x as f64 + 0.5, y as f64 + 0.5) * l;
            weight += l;
        }
    }
    assert!(weight > 0.0, "no light near {around}");
    sum / weight
}

/// The pixel position of world point `p` in an image of `width` x `height`.
fn pixel_of(scene: &Scene, p: DVec3, width: usize, height: usize) -> DVec2 {
    let film =
        scene.camera.project(p.as_vec3(), width as f32 / height as f32).expect("in front of the camera");
    DVec2::new(f64::from(film.x) * width as f64, f64::from(film.y) * height as f64)
}

fn render_at(path: &Path, wavelength_nm: Option<f32>, passes: u64, photons: usize) -> Image {
    let dir = tempfile::tempdir().unwrap();
    let mut s = settings(path, dir.path(), passes);
    s.wavelength_nm = wavelength_nm;
    s.photons = Some(photons);
    render(&s, 2)
}

#[test]
fn prism_bands_land_where_snells_law_puts_them() {
    let path = bundled_scene("prism.gltf");
    let question = regression(&path);
    let scene = Scene::load(&path).unwrap();
    let sf11 = Dispersion::glass("SF11").unwrap();
    let (exit_d, _) = trace_prism(&question, f64::from(sf11.index(587.56)));
    let mut deviations = Vec::new();
    for lambda in [450.0, 550.0, 650.0] {
        let image = render_at(&path, Some(lambda), 16, 20_000);
        let n = f64::from(sf11.index(lambda));
        let expected = pixel_of(&scene, landing_point(&question, n), image.width, image.height);
        let measured = centroid(&image, expected, 12.0);
        let error = (measured - expected).length();
        eprintln!("prism at {lambda} nm (n = {n:.5}): band at {measured:.2} px, Snell's law {expected:.2} px, off by {error:.2} px");
        assert!(error <= 1.0, "{lambda} nm: band at {measured}, expected {expected} (off by {error:.2} px)");
        // The deviation of the band, seen from the prism's exit face.
        let beam = dvec3(&question["beam_direction"]);
        let to_band = landing_point(&question, n) - exit_d.extend(0.0);
        deviations.push(beam.angle_between(to_band).to_degrees());
    }
    assert!(
        deviations[2] < deviations[1] && deviations[1] < deviations[0],
        "red must deviate least: {deviations:?}"
    );
}

/// Chromatic spread of a band: the largest |r / g - 1| or |b / g - 1| over its bright pixels.
fn colour_fringe(image: &Image) -> f64 {
    let peak = (0..image.rgb.len()).map(|i| image.rgb[i][1]).fold(0.0, f64::max);
    image
        .rgb
        .iter()
        .filter(|c| c[1] > 0.3 * peak)
        .map(|c| ((c[0] / c[1] - 1.0).abs()).max((c[2] / c[1] - 1.0).abs()))
        .fold(0.0, f64::max)
}

/// A prism whose index does not change with wavelength makes one white band: every bright pixel
/// within 10% of grey (chromaticity noise of 64 passes); the dispersive prism must spread far more.
#[test]
fn a_prism_without_dispersion_makes_one_white_band() {
    let constant = render_at(&bundled_scene("prism_constant.gltf"), None, 64, 20_000);
    let fringe = colour_fringe(&constant);
    assert!(fringe < 0.10, "constant index: colour fringe {fringe:.3}");
    let dispersive = render_at(&bundled_scene("prism.gltf"), None, 64, 20_000);
    let spread = colour_fringe(&dispersive);
    eprintln!("colour fringe: constant index {fringe:.3}, SF11 {spread:.3}");
    assert!(spread > 1.0, "SF11: colour spread only {spread:.3}");
}
