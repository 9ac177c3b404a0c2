mod common;
use common::*;
use serde_json::json;
#[test]
fn touching() {
    let dir = std::path::Path::new("/tmp/probe");
    std::fs::create_dir_all(dir).unwrap();
    for (name, rings, gap, n) in
        [("t24", 24, 0.0, 2), ("t64", 64, 0.0, 2), ("g24", 24, 0.05, 2), ("one24", 24, 0.0, 1)]
    {
        let mut gltf = GltfBuilder::default();
        let wall = gltf.material(json!({"pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1.0], "metallicFactor": 0.0}, "emissiveFactor": [1.0, 1.0, 1.0]}));
        gltf.mesh("Furnace", &box_triangles([-1.0; 3], [1.0; 3]), wall);
        gltf.camera([0.0; 3], [0.0, 0.0, 1.0], 1.2);
        let m = gltf.material(json!({"pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, 1.0], "roughnessFactor": 0.0}, "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1.0}}}));
        gltf.sphere("Left", [-0.2 - gap, 0.0, 0.6], 0.2, rings, m);
        if n == 2 {
            gltf.sphere("Right", [0.2 + gap, 0.0, 0.6], 0.2, rings, m);
        }
        gltf.write(dir, name);
    }
}
