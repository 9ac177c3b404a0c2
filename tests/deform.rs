//! Skins and morph targets: a mesh deformed by its joints or its targets renders as the same mesh
//! moved rigidly the same way, motion blur included, and `caustic info` names what deforms.

mod common;

use common::*;
use serde_json::json;
use std::path::{Path, PathBuf};

/// A square of side 0.4 in the plane z = 0 facing +z (two triangles, six vertices).
const SQUARE: [[[f32; 3]; 3]; 2] = [
    [[-0.2, -0.2, 0.0], [0.2, -0.2, 0.0], [0.2, 0.2, 0.0]],
    [[-0.2, -0.2, 0.0], [0.2, 0.2, 0.0], [-0.2, 0.2, 0.0]],
];

/// A scene holding one emitting square (radiance 10) whose mesh node `add_square` adds, seen
/// from z = 5 at 64 x 64 with a shutter open for the whole frame, at 24 frames a second.
fn scene(dir: &Path, name: &str, add_square: impl FnOnce(&mut GltfBuilder, usize)) -> PathBuf {
    let mut gltf = GltfBuilder::default();
    let material = gltf.material(json!({"emissiveFactor": [1.0, 1.0, 1.0],
        "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 10.0}},
        "pbrMetallicRoughness": {"baseColorFactor": [0.0, 0.0, 0.0, 1.0]}}));
    add_square(&mut gltf, material);
    gltf.camera([0.0, 0.0, 5.0], [0.0, 0.0, -1.0], 0.6);
    gltf.scene_extras(json!({"resolution": [64, 64], "fps": 24.0,
        "shutter": {"length_frames": 1.0, "position": "CENTER"}}));
    gltf.write(dir, name)
}

/// The square on a node sliding from x = 0 at t = 0 to x = `distance` at t = 1 s.
fn rigid(dir: &Path, distance: f32) -> PathBuf {
    scene(dir, "rigid", |gltf, material| {
        gltf.mesh("Square", &SQUARE, material);
        let node = gltf.last_node();
        let keys = [vec![0.0, 0.0, 0.0], vec![distance, 0.0, 0.0]];
        gltf.animate(node, "translation", &[0.0, 1.0], &keys, "LINEAR");
    })
}

/// Frame `frame` of `scene` (16 passes, seed 1).
fn frame(scene: &Path, out: &Path, frame: i32) -> Image {
    let mut s = settings(scene, out, 16);
    s.frames = vec![frame];
    render(&s, 2)
}

/// The luminance-weighted mean column of `image`.
fn centroid_x(image: &Image) -> f64 {
    let (mut sum, mut weighted) = (0.0, 0.0);
    for x in 0..image.width {
        let l = image.luminance(x, x + 1, 0, image.height);
        sum += l;
        weighted += l * (x as f64 + 0.5);
    }
    weighted / sum
}

/// `deformed` and `rigid` render alike at `frame` (RMSE within 1% of the image's peak), and the
/// square has moved by more than four pixels since frame 1 (so the comparison can fail).
fn assert_moves_alike(dir: &Path, deformed: &Path, rigid: &Path, frame_number: i32) {
    let a = frame(deformed, &dir.join("deformed"), frame_number);
    let b = frame(rigid, &dir.join("rigid"), frame_number);
    let start = frame(rigid, &dir.join("start"), 1);
    let peak = b.rgb.iter().map(|p| p[1]).fold(0.0, f64::max);
    assert!(a.rmse(&b) < 0.01 * peak, "RMSE {} against a peak of {peak}", a.rmse(&b));
    let moved = centroid_x(&b) - centroid_x(&start);
    assert!(moved > 4.0, "the square moved {moved} pixels");
    assert!((centroid_x(&a) - centroid_x(&b)).abs() < 0.1, "{} vs {}", centroid_x(&a), centroid_x(&b));
}

/// A skinned square whose vertices hang half from a joint sliding 2 to the right and half from a
/// still one (whose inverse bind matrix undoes its rest offset) moves as the square sliding 1 to
/// the right, and the mesh node's own transform is ignored, as the glTF specification says.
#[test]
fn a_skinned_mesh_follows_the_blend_of_its_joints() {
    let dir = tempfile::tempdir().unwrap();
    let skinned = scene(dir.path(), "skinned", |gltf, material| {
        gltf.mesh("Square", &SQUARE, material);
        let mesh_node = gltf.last_node();
        let sliding = gltf.node(json!({"name": "Sliding joint"}));
        let keys = [vec![0.0, 0.0, 0.0], vec![2.0, 0.0, 0.0]];
        gltf.animate(sliding, "translation", &[0.0, 1.0], &keys, "LINEAR");
        let still = gltf.node(json!({"name": "Still joint", "translation": [0.0, 1.0, 0.0]}));
        let identity = glam::Mat4::IDENTITY.to_cols_array();
        let undo_offset = glam::Mat4::from_translation(glam::Vec3::new(0.0, -1.0, 0.0)).to_cols_array();
        let joints = [0u16, 1, 0, 0].repeat(6);
        let weights = [0.5f32, 0.5, 0.0, 0.0].repeat(6);
        gltf.skin(mesh_node, &[sliding, still], Some(&[identity, undo_offset]), &joints, &weights);
        // The mesh node's transform is ignored for a skinned mesh.
        gltf.set_node_translation(mesh_node, [3.0, 0.0, 0.0]);
    });
    assert_moves_alike(dir.path(), &skinned, &rigid(dir.path(), 1.0), 13);
}

/// A morph target that moves every vertex 1 to the right, its weight animated from 0 to 1 over a
/// second, moves the square as a node sliding 1 to the right does.
#[test]
fn morph_targets_move_vertices_by_their_animated_weights() {
    let dir = tempfile::tempdir().unwrap();
    let morphed = scene(dir.path(), "morphed", |gltf, material| {
        gltf.mesh("Square", &SQUARE, material);
        let node = gltf.last_node();
        gltf.morph_target(&[1.0, 0.0, 0.0].repeat(6));
        gltf.animate_weights(node, &[0.0, 1.0], &[0.0, 1.0]);
    });
    assert_moves_alike(dir.path(), &morphed, &rigid(dir.path(), 1.0), 13);
}

/// A morph target written as Blender's exporter can write it (sparse offsets without a
/// `bufferView`, normal offsets without either: zeros) shapes the mesh as the same offsets written
/// plainly do.
#[test]
fn sparse_accessors_and_accessors_without_a_buffer_view_are_read() {
    let dir = tempfile::tempdir().unwrap();
    let sparse = scene(dir.path(), "sparse", |gltf, material| {
        gltf.mesh("Square", &SQUARE, material);
        gltf.sparse_morph_target(&[1.0, 0.0, 0.0].repeat(6));
        gltf.set_node_weights(gltf.last_node(), &[0.5]);
    });
    let offset = scene(dir.path(), "offset", |gltf, material| {
        gltf.mesh("Square", &SQUARE, material);
        gltf.set_node_translation(gltf.last_node(), [0.5, 0.0, 0.0]);
    });
    let (a, b) = (frame(&sparse, &dir.path().join("a"), 1), frame(&offset, &dir.path().join("b"), 1));
    assert!((centroid_x(&a) - centroid_x(&b)).abs() < 0.1, "{} vs {}", centroid_x(&a), centroid_x(&b));
    assert!(a.rmse(&b) < 1e-3 * b.mean_all()[0].max(1e-3), "the shapes differ: RMSE {}", a.rmse(&b));
}

/// Without animation the node's default `weights` shape the mesh (a still offset of 0.5), and
/// `caustic info` names the deforming meshes and what deforms them.
#[test]
fn default_weights_shape_a_still_mesh_and_info_names_deformations() {
    let dir = tempfile::tempdir().unwrap();
    let morphed = scene(dir.path(), "still_morph", |gltf, material| {
        gltf.mesh("Square", &SQUARE, material);
        gltf.morph_target(&[1.0, 0.0, 0.0].repeat(6));
        gltf.set_node_weights(gltf.last_node(), &[0.5]);
    });
    let offset = scene(dir.path(), "offset", |gltf, material| {
        gltf.mesh("Square", &SQUARE, material);
        gltf.set_node_translation(gltf.last_node(), [0.5, 0.0, 0.0]);
    });
    let (a, b) = (frame(&morphed, &dir.path().join("a"), 1), frame(&offset, &dir.path().join("b"), 1));
    assert!((centroid_x(&a) - centroid_x(&b)).abs() < 0.1, "{} vs {}", centroid_x(&a), centroid_x(&b));
    assert!(centroid_x(&a) > 32.0 + 4.0, "the mesh kept its basis shape: {}", centroid_x(&a));
    let output = run_caustic(&["info", morphed.to_str().unwrap()]);
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let info: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    assert_eq!(info["deforming"], json!([{"mesh": "Square", "by": ["morph targets"]}]));
    assert_eq!(info["needs"]["per_time_scene"], json!(false), "a still morph needs no pose per time");
}
