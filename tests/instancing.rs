//! `EXT_mesh_gpu_instancing`: a node's instances render as the same meshes written out one node
//! each, a still mesh is stored once however many instances draw it (a two-level BVH), and an
//! expansion too large for memory is refused by name.

mod common;

use common::*;
use serde_json::json;

/// A thousand instances of a box (rotated, scaled, some mirrored) in a 10 x 10 x 10 grid on a
/// node that is itself moved and turned, over a lit floor: `instanced` draws them through the
/// extension, otherwise each is a child node of the same transform.
fn grid(dir: &std::path::Path, instanced: bool) -> std::path::PathBuf {
    let mut gltf = GltfBuilder::default();
    let white = gltf.material(diffuse([0.8, 0.8, 0.8]));
    gltf.quad_y("Floor", 0.0, 4.0, true, white);
    let red = gltf.material(diffuse([0.8, 0.3, 0.2]));
    gltf.mesh("Box", &box_triangles([-0.05, 0.0, -0.05], [0.05, 0.12, 0.05]), red);
    let node = gltf.last_node();
    let mesh = gltf.to_json()["nodes"][node]["mesh"].clone();
    let (mut translations, mut rotations, mut scales) = (Vec::new(), Vec::new(), Vec::new());
    for k in 0..1000 {
        let (i, j, l) = ((k % 10) as f32, ((k / 10) % 10) as f32, (k / 100) as f32);
        translations.push([i * 0.25 - 1.1, j * 0.2, l * 0.25 - 1.1]);
        let q = glam::Quat::from_euler(glam::EulerRot::YXZ, k as f32 * 0.7, k as f32 * 0.3, 0.0);
        rotations.push(q.to_array());
        let mirror = if k % 7 == 0 { -1.0 } else { 1.0 };
        scales.push([mirror * (0.6 + 0.05 * (k % 9) as f32), 1.0, 0.8]);
    }
    let place =
        json!({"translation": [0.1, 0.05, -0.1], "rotation": glam::Quat::from_rotation_y(0.3).to_array()});
    if instanced {
        gltf.instance(node, &translations, &rotations, &scales);
        gltf.set_node_transform(node, place);
    } else {
        gltf.set_node_transform(node, place);
        gltf.remove_mesh(node);
        for k in 0..1000 {
            let child = gltf.child_node(
                node,
                json!({"name": format!("Box{k}"), "mesh": mesh, "translation": translations[k],
                "rotation": rotations[k], "scale": scales[k]}),
            );
            assert!(child > node);
        }
    }
    gltf.light(json!({"type": "point", "intensity": 3000.0}), [1.0, 3.0, 1.0], [0.0, -1.0, 0.0]);
    gltf.camera([0.0, 3.0, 4.0], [0.0, -2.5, -4.0], 0.8);
    gltf.scene_extras(json!({"resolution": [96, 96]}));
    gltf.write(dir, if instanced { "instanced" } else { "written_out" })
}

/// The instanced grid (two levels: rays go into each box's space) renders as the written-out one
/// (flattened to world space) within float rounding: a relative RMSE under 1e-4.
#[test]
fn instances_render_as_the_same_meshes_written_out() {
    let dir = tempfile::tempdir().unwrap();
    let render_scene = |path: &std::path::Path, out: &str| {
        let mut s = settings(path, &dir.path().join(out), 8);
        s.photons = Some(5000);
        render(&s, 2)
    };
    let instanced = render_scene(&grid(dir.path(), true), "a");
    let written = render_scene(&grid(dir.path(), false), "b");
    let mean = written.mean_all().iter().sum::<f64>() / 3.0;
    let relative = instanced.rmse(&written) / mean;
    let boxes = instanced.mean(30, 66, 30, 66);
    eprintln!("relative RMSE {relative:.2e} between the instanced and the written-out grid; the grid's mean {boxes:?}");
    assert!(boxes[0] > 1.5 * boxes[2], "the red boxes are in view: {boxes:?}");
    assert!(
        relative < 1e-4,
        "the instances differ from the written-out meshes (relative RMSE {relative:.2e})"
    );
}

/// Ten thousand instances of a 20,000-triangle ball are kept as one mesh and a list of
/// placements (two levels), and render: 200 million triangles drawn, 20,000 stored.
#[test]
fn ten_thousand_instances_store_one_mesh() {
    let dir = tempfile::tempdir().unwrap();
    let mut gltf = GltfBuilder::default();
    let white = gltf.material(diffuse([0.8, 0.8, 0.8]));
    gltf.quad_y("Floor", -0.05, 6.0, true, white);
    gltf.sphere("Ball", [0.0, 0.0, 0.0], 0.04, 71, white);
    let node = gltf.last_node();
    let grid: Vec<[f32; 3]> =
        (0..10_000).map(|k| [(k % 100) as f32 * 0.1 - 5.0, 0.0, (k / 100) as f32 * 0.1 - 5.0]).collect();
    gltf.instance(node, &grid, &vec![[0.0, 0.0, 0.0, 1.0]; grid.len()], &vec![[1.0; 3]; grid.len()]);
    gltf.light(json!({"type": "point", "intensity": 3000.0}), [0.0, 3.0, 0.0], [0.0, -1.0, 0.0]);
    gltf.camera([0.0, 2.0, 6.0], [0.0, -2.0, -6.0], 0.8);
    gltf.scene_extras(json!({"resolution": [64, 64]}));
    let path = gltf.write(dir.path(), "ten_thousand");
    let mut s = settings(&path, &dir.path().join("out"), 2);
    s.photons = Some(2000);
    let info = caustic::info::report(&s).unwrap();
    let stored = info["triangles"]["instanced_stored"].as_u64().unwrap();
    let drawn = info["triangles"]["instanced"].as_u64().unwrap();
    eprintln!("{drawn} instanced triangles drawn, {stored} stored");
    assert!((19_000..21_000).contains(&stored) && drawn == 10_000 * stored, "{info}");
    let image = render(&s, 2);
    assert!(image.mean_all()[0] > 0.0, "the balls and the floor are lit");
}

/// Instances that must be expanded (of an emitting mesh: each instance is a light of its own)
/// past what fits in memory are refused, naming the node and the count, before anything is
/// expanded.
#[test]
fn too_many_expanded_triangles_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let mut gltf = GltfBuilder::default();
    let glow = gltf.material(json!({"emissiveFactor": [1.0, 1.0, 1.0]}));
    gltf.sphere("Ball", [0.0, 0.0, 0.0], 0.1, 100, glow);
    let node = gltf.last_node();
    let count = 600;
    gltf.instance(node, &vec![[0.0; 3]; count], &vec![[0.0, 0.0, 0.0, 1.0]; count], &vec![[1.0; 3]; count]);
    gltf.camera([0.0, 0.0, 4.0], [0.0, 0.0, -1.0], 0.8);
    let path = gltf.write(dir.path(), "too_many");
    let Err(error) = caustic::scene::description::Description::load(&path) else {
        panic!("600 instances of an emitting 40,000-triangle ball were expanded");
    };
    let error = error.to_string();
    assert!(
        error.contains("node 'Ball' EXT_mesh_gpu_instancing: 600 instances of")
            && error.contains("more than the 20000000"),
        "{error}"
    );
}
