//! Cameras other than glTF's perspective one: orthographic, shifted, and Blender's
//! equirectangular panorama (node extras), seen as black spheres against a white world.

mod common;

use common::*;
use serde_json::{json, Value};
use std::path::Path;

/// Black spheres of radius 0.5 at `centres` under a uniform white world, seen by `camera`
/// (a glTF camera, or `None` for a node with `caustic` extras only) from the origin along -z,
/// rendered at `resolution`.
fn spheres_seen_by(
    dir: &Path,
    camera: Option<Value>,
    extras: Value,
    centres: &[[f32; 3]],
    resolution: [u32; 2],
) -> Image {
    let mut gltf = GltfBuilder::default();
    let black = gltf.material(diffuse([0.0, 0.0, 0.0]));
    for (i, &centre) in centres.iter().enumerate() {
        gltf.sphere(&format!("Ball{i}"), centre, 0.5, 48, black);
    }
    match camera {
        Some(camera) => gltf.camera_of(camera, [0.0, 0.0, 0.0], [0.0, 0.0, -1.0]),
        None => gltf.extras_node("Camera", Value::Null, [0.0, 0.0, 0.0], [0.0, 0.0, -1.0]),
    }
    if !extras.is_null() {
        gltf.set_node_extras(gltf.last_node(), extras);
    }
    gltf.scene_extras(
        json!({"resolution": resolution, "world": {"color": [1.0, 1.0, 1.0]}, "camera": "Camera"}),
    );
    let path = gltf.write(dir, "spheres");
    render(&settings(&path, dir, 4), 2)
}

/// The pixels darker than half the white world in columns `x0..x1`.
fn dark_pixels(image: &Image, x0: usize, x1: usize) -> usize {
    (0..image.height)
        .flat_map(|y| (x0..x1).map(move |x| (x, y)))
        .filter(|&(x, y)| image.luminance(x, x + 1, y, y + 1) < 0.5)
        .count()
}

/// Under an orthographic camera (ymag 2: a film 4 units high) a sphere of radius 0.5 covers
/// pi 0.25 / 16 of the film whether it is 3 or 30 units away (within 6%: the edge pixels).
#[test]
fn an_orthographic_camera_sees_near_and_far_spheres_the_same_size() {
    let dir = tempfile::tempdir().unwrap();
    let camera = json!({"type": "orthographic", "orthographic": {"xmag": 4.0, "ymag": 2.0, "znear": 0.01, "zfar": 100.0}});
    let image = spheres_seen_by(
        dir.path(),
        Some(camera),
        Value::Null,
        &[[-2.0, 0.0, -3.0], [2.0, 0.0, -30.0]],
        [128, 64],
    );
    let expected = std::f64::consts::PI * 0.25 / 16.0 * 64.0 * 64.0;
    for (side, count) in [("near", dark_pixels(&image, 0, 64)), ("far", dark_pixels(&image, 64, 128))] {
        assert!(
            (count as f64 / expected - 1.0).abs() < 0.06,
            "{side}: {count} pixels, expected {expected:.0}"
        );
    }
}

/// A lens shift of half the film's height (extras `caustic.shift`) moves a sphere straight ahead
/// from the film's centre to its bottom edge.
#[test]
fn a_lens_shift_moves_the_film() {
    let dir = tempfile::tempdir().unwrap();
    let camera =
        json!({"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.01, "aspectRatio": 1.0}});
    let image = spheres_seen_by(
        dir.path(),
        Some(camera),
        json!({"shift": [0.0, 0.5]}),
        &[[0.0, 0.0, -6.0]],
        [64, 64],
    );
    let rows: Vec<usize> = (0..64).filter(|&y| image.luminance(28, 36, y, y + 1) < 0.5).collect();
    assert!(!rows.is_empty() && *rows.last().unwrap() == 63, "the sphere's rows: {rows:?}");
    assert!(rows[0] > 50, "the sphere's rows: {rows:?}");
}

/// A full equirectangular panorama (a node with `caustic.panorama` and no glTF camera) sees a
/// sphere ahead at its centre, one to the right a quarter further right and one behind at both
/// edges.
#[test]
fn a_panorama_sees_all_around() {
    let dir = tempfile::tempdir().unwrap();
    let panorama = json!({"panorama": {"longitude_deg": [-180.0, 180.0], "latitude_deg": [-90.0, 90.0]}});
    let image = spheres_seen_by(
        dir.path(),
        None,
        panorama,
        &[[0.0, 0.0, -3.0], [3.0, 0.0, 0.0], [0.0, 0.0, 3.0]],
        [64, 32],
    );
    let dark_columns: Vec<usize> = (0..64).filter(|&x| image.luminance(x, x + 1, 15, 17) < 0.5).collect();
    for column in [0, 31, 32, 47, 48, 63] {
        assert!(dark_columns.contains(&column), "column {column} is not dark: {dark_columns:?}");
    }
    for column in [8, 16, 24, 40, 56] {
        assert!(!dark_columns.contains(&column), "column {column} is dark: {dark_columns:?}");
    }
}
