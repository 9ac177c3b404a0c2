//! Fuzzing the scene loader (a property test, bounded so it fits in the test command): arbitrary
//! bytes, real glTF files with bytes flipped or cut, and real glTF JSON with values replaced by
//! hostile ones (huge counts, negative indices, wrong types) must load or be refused with a
//! message — never panic. What loads is also posed and rendered for one tiny pass.
//!
//! Inputs that once crashed are kept in tests/fuzz/ and loaded by `kept_crashes_stay_fixed`.
//! The test command runs 200 cases per property from a fixed seed (the same inputs every run, so
//! CI never fails by chance); to search further, `CAUSTIC_FUZZ_CASES=5000 CAUSTIC_FUZZ_SEED=random
//! cargo test --release --test fuzz` (or a number for the seed).

mod common;

use caustic::render::{self, Method, RenderSettings};
use caustic::scene::Description;
use proptest::prelude::*;
use rand::{Rng, RngExt, SeedableRng};
use serde_json::{json, Value};
use std::path::{Path, PathBuf};

fn cases() -> u32 {
    std::env::var("CAUSTIC_FUZZ_CASES").ok().and_then(|n| n.parse().ok()).unwrap_or(200)
}

fn rng_seed() -> proptest::test_runner::RngSeed {
    use proptest::test_runner::RngSeed;
    match std::env::var("CAUSTIC_FUZZ_SEED").as_deref() {
        Ok("random") => RngSeed::Random,
        Ok(n) => RngSeed::Fixed(n.parse().expect("CAUSTIC_FUZZ_SEED: a number or 'random'")),
        Err(_) => RngSeed::Fixed(0x0ca5_71c0),
    }
}

fn scenes() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes")
}

/// Loads `path` and, when it loads, renders one 4x4 pass with 16 photons by each method (SPPM,
/// and vertex connection and merging where it renders the scene); a panic anywhere fails.
fn load_and_render(path: &Path) -> Result<(), String> {
    let outcome = std::panic::catch_unwind(|| {
        if Description::load(path).is_err() {
            return;
        }
        let out = path.with_extension("out");
        let mut s = RenderSettings::new(path, &out);
        s.passes = Some(1);
        s.resolution = Some([4, 4]);
        s.photons = Some(16);
        let _ = render::render(&s);
        s.method = Method::Vcm;
        let _ = render::render(&s);
    });
    outcome.map_err(|panic| {
        let message = panic
            .downcast_ref::<String>()
            .cloned()
            .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()));
        format!("{} panicked: {}", path.display(), message.unwrap_or_default())
    })
}

/// Writes `bytes` as `name` in a fresh folder beside copies of the bundled scenes' buffers (so
/// relative references resolve) and loads it.
fn try_bytes(name: &str, bytes: &[u8]) -> Result<(), String> {
    let dir = tempfile::tempdir().unwrap();
    for bin in ["furnace.bin", "cornell_animated.bin", "spot_glass.bin"] {
        std::fs::copy(scenes().join(bin), dir.path().join(bin)).unwrap();
    }
    let path = dir.path().join(name);
    std::fs::write(&path, bytes).unwrap();
    let result = load_and_render(&path);
    if result.is_err() {
        // Keep the input for tests/fuzz/ (see kept_crashes_stay_fixed).
        let _ = std::fs::copy(&path, std::env::temp_dir().join(format!("caustic-fuzz-crash-{name}")));
    }
    result
}

/// A small PNG as a data URI.
fn png_uri(width: u32, height: u32, rgba: [u8; 4]) -> String {
    use base64::Engine;
    let mut png = Vec::new();
    image::RgbaImage::from_pixel(width, height, image::Rgba(rgba))
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .unwrap();
    format!("data:image/png;base64,{}", base64::engine::general_purpose::STANDARD.encode(png))
}

/// A scene with every texture and vertex input Caustic reads: base colour on the second
/// texture coordinate set through `KHR_texture_transform`, metallic-roughness, a normal map,
/// a specular layer, a clear coat and a sheen with their textures, `COLOR_0` (its alpha cutting),
/// `TEXCOORD_1` and `TANGENT`, under a uniform world.
fn textured_seed() -> Value {
    let mut gltf = common::GltfBuilder::default();
    let quad = [
        [[-1.0, 0.0, -1.0], [-1.0, 0.0, 1.0], [1.0, 0.0, 1.0]],
        [[-1.0, 0.0, -1.0], [1.0, 0.0, 1.0], [1.0, 0.0, -1.0]],
    ];
    let uvs: Vec<[f32; 2]> =
        quad.iter().flatten().map(|p| [(p[0] + 1.0) / 2.0, (p[2] + 1.0) / 2.0]).collect();
    let material = gltf.material(json!({
        "pbrMetallicRoughness": {"baseColorTexture": {"index": 0, "texCoord": 1,
            "extensions": {"KHR_texture_transform": {"offset": [0.5, 0.0], "rotation": 0.3, "scale": [2.0, 2.0]}}},
            "metallicRoughnessTexture": {"index": 1}},
        "normalTexture": {"index": 2, "scale": 0.5}, "alphaMode": "MASK", "alphaCutoff": 0.3,
        "extensions": {"KHR_materials_specular": {"specularFactor": 0.7, "specularTexture": {"index": 1},
                "specularColorTexture": {"index": 0, "texCoord": 1}},
            "KHR_materials_clearcoat": {"clearcoatFactor": 0.8, "clearcoatTexture": {"index": 1},
                "clearcoatRoughnessFactor": 0.2, "clearcoatRoughnessTexture": {"index": 1, "texCoord": 1},
                "clearcoatNormalTexture": {"index": 2, "scale": 0.7,
                    "extensions": {"KHR_texture_transform": {"rotation": 1.0}}}},
            "KHR_materials_sheen": {"sheenColorFactor": [0.8, 0.6, 0.4], "sheenColorTexture": {"index": 0},
                "sheenRoughnessFactor": 0.5, "sheenRoughnessTexture": {"index": 1}}}}));
    gltf.mesh_with_uvs("Ground", &quad, &uvs, material);
    gltf.attribute("TEXCOORD_1", &uvs.concat(), 2, "VEC2");
    let alphas = [1.0f32, 0.2, 0.9, 0.6, 1.0, 0.1];
    gltf.attribute("COLOR_0", &alphas.map(|a| [0.9f32, 0.5, 0.1, a]).concat(), 4, "VEC4");
    gltf.attribute("TANGENT", &[[1.0f32, 0.0, 0.0, 1.0]; 6].concat(), 4, "VEC4");
    gltf.camera([0.0, 3.0, 0.0], [0.0, -1.0, 0.0], 0.8);
    gltf.scene_extras(json!({"world": {"color": [1.0, 1.0, 1.0], "strength": 1.0}}));
    let mut doc = gltf.to_json();
    doc["images"] = json!([
        {"uri": png_uri(4, 2, [200, 50, 50, 255])},
        {"uri": png_uri(2, 2, [0, 128, 255, 255])},
        {"uri": png_uri(2, 2, [160, 128, 230, 255])},
    ]);
    doc["textures"] = json!([{"source": 0}, {"source": 1}, {"source": 2}]);
    doc["extensionsUsed"].as_array_mut().unwrap().push(json!("KHR_texture_transform"));
    doc
}

/// A scene with every volume input Caustic reads: `KHR_materials_volume` on a rough glass box
/// with a point light inside it, on water overlapping it with a `caustic` priority, a `caustic`
/// medium that scatters and the camera inside, and on a frosted thin pane with a thickness; and
/// fog in the world.
fn volume_seed() -> Value {
    let mut gltf = common::GltfBuilder::default();
    let volume = |colour: [f32; 3], roughness: f32, thickness: f32, priority: i32| {
        json!({"pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.95, 1.0, 1.0], "roughnessFactor": roughness},
            "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1.0},
                "KHR_materials_volume": {"attenuationColor": colour, "attenuationDistance": 0.5,
                    "thicknessFactor": thickness}},
            "extras": {"caustic": {"priority": priority}}})
    };
    let glass = gltf.material(volume([0.2, 0.8, 0.3], 0.3, 1.0, 1));
    gltf.mesh("Glass", &common::box_triangles([-0.5, 0.0, -0.5], [0.5, 1.0, 0.5]), glass);
    let mut water = volume([0.6, 0.8, 0.9], 0.0, 1.0, 0);
    water["extras"]["caustic"]["medium"] =
        json!({"absorption": [0.2, 0.1, 0.05], "scattering": [0.5, 0.6, 0.8], "anisotropy": 0.4});
    water["extensions"].as_object_mut().unwrap().remove("KHR_materials_volume");
    let water = gltf.material(water);
    gltf.mesh("Water", &common::box_triangles([-1.0, -0.5, -1.0], [1.0, 0.5, 1.0]), water);
    let pane = gltf.material(volume([0.9, 0.5, 0.2], 0.3, 0.05, 0));
    gltf.mesh("Pane", &[[[-1.0, 2.0, -1.0], [-1.0, 2.0, 1.0], [1.0, 2.0, 1.0]]], pane);
    gltf.light(json!({"type": "point", "intensity": 100.0}), [0.0, 0.7, 0.0], [0.0, -1.0, 0.0]);
    gltf.camera([0.0, 0.2, 0.9], [0.0, 0.0, -1.0], 0.8);
    gltf.scene_extras(json!({"fog": {"absorption": [0.01, 0.01, 0.01], "scattering": [0.1, 0.1, 0.1],
        "anisotropy": -0.2}}));
    gltf.to_json()
}

/// A scene with every camera input Caustic reads (an orthographic camera, a shifted perspective
/// one with a lens, and a panorama on a node of its own, which the scene's extras choose) and the
/// film's and lights' newer ones (a transparent film, a holdout, a spot with Blender's blend and a
/// radius hidden from the camera, a point light with a radius and Soft Falloff seen by it, an area
/// light with a spread).
fn camera_seed() -> Value {
    let mut gltf = common::GltfBuilder::default();
    let grey = gltf.material(common::diffuse([0.5, 0.5, 0.5]));
    gltf.sphere("Ball", [0.0, 0.0, -3.0], 0.5, 12, grey);
    gltf.sphere("Hole", [1.0, 0.0, -3.0], 0.3, 8, grey);
    gltf.set_node_extras(gltf.last_node(), json!({"holdout": true}));
    let spot =
        json!({"type": "spot", "intensity": 500.0, "spot": {"innerConeAngle": 0.2, "outerConeAngle": 0.5}});
    gltf.light(spot, [0.0, 2.0, -3.0], [0.0, -1.0, 0.0]);
    gltf.set_node_extras(
        gltf.last_node(),
        json!({"spot_blend": 0.4, "radius": 0.2, "visible_to_camera": false}),
    );
    gltf.light(json!({"type": "point", "intensity": 300.0}), [0.5, 0.5, -2.0], [0.0, -1.0, 0.0]);
    gltf.set_node_extras(
        gltf.last_node(),
        json!({"radius": 0.1, "visible_to_camera": true, "soft_falloff": true}),
    );
    let soft_box = json!({"area_light": {"shape": "RECTANGLE", "size": 0.5, "size_y": 0.3, "power": 50.0,
        "spread_deg": 40.0}, "visible_to_camera": false});
    gltf.extras_node("Soft box", soft_box, [0.0, 1.5, -2.5], [0.0, -1.0, 0.0]);
    let ortho = json!({"type": "orthographic", "orthographic": {"xmag": 2.0, "ymag": 1.5, "znear": 0.01, "zfar": 50.0}});
    gltf.camera_of(ortho, [0.0, 0.0, 2.0], [0.0, 0.0, -1.0]);
    gltf.camera([0.0, 1.0, 2.0], [0.0, -0.3, -1.0], 0.7);
    let lens = json!({"fstop": 2.8, "focus_distance": 4.0, "blades": 6});
    gltf.set_node_extras(gltf.last_node(), json!({"shift": [0.1, -0.2], "lens": lens}));
    let panorama = json!({"panorama": {"longitude_deg": [-120.0, 90.0], "latitude_deg": [-45.0, 60.0]}});
    gltf.extras_node("Panorama", panorama, [0.0, 0.0, 0.0], [0.0, 0.0, -1.0]);
    gltf.scene_extras(
        json!({"camera": "Panorama", "world": {"color": [1.0, 1.0, 1.0]}, "transparent_film": true}),
    );
    gltf.to_json()
}

/// A value to put in place of any JSON value.
fn hostile_value(rng: &mut impl Rng) -> Value {
    let values = [
        json!(1_000_000_000_000u64),
        json!(-1),
        json!(0),
        json!(u32::MAX),
        json!(1.5),
        json!(-1e30),
        json!(1e300),
        json!("x"),
        json!(null),
        json!([]),
        json!({}),
        json!([0, 1, 2]),
        json!(true),
        json!(65535),
    ];
    values[rng.random_range(0..values.len())].clone()
}

/// Replaces one randomly chosen value inside `value` (or deletes an object key).
fn mutate(value: &mut Value, rng: &mut impl Rng) {
    let descend = rng.random_range(0..4) != 0;
    match value {
        Value::Object(map) if !map.is_empty() && descend => {
            let key = map.keys().nth(rng.random_range(0..map.len())).unwrap().clone();
            if rng.random_range(0..8) == 0 {
                map.remove(&key);
            } else {
                mutate(map.get_mut(&key).unwrap(), rng);
            }
        }
        Value::Array(list) if !list.is_empty() && descend => {
            let i = rng.random_range(0..list.len());
            mutate(&mut list[i], rng);
        }
        _ => *value = hostile_value(rng),
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: cases(), failure_persistence: None, rng_seed: rng_seed(), ..ProptestConfig::default() })]

    #[test]
    fn arbitrary_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..2048), glb in any::<bool>()) {
        let mut bytes = bytes;
        if glb && bytes.len() >= 12 {
            // Make the header look like a glTF binary so the parser goes further.
            bytes[..4].copy_from_slice(b"glTF");
            bytes[4..8].copy_from_slice(&2u32.to_le_bytes());
        }
        let name = if glb { "fuzz.glb" } else { "fuzz.gltf" };
        prop_assert_eq!(try_bytes(name, &bytes), Ok(()));
    }

    #[test]
    fn real_files_with_bytes_flipped_or_cut_never_panic(seed in any::<u64>()) {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
        let name = ["furnace.gltf", "cornell_animated.gltf", "prism.gltf"][rng.random_range(0..3)];
        let mut bytes = std::fs::read(scenes().join(name)).unwrap();
        for _ in 0..rng.random_range(1..6) {
            let i = rng.random_range(0..bytes.len());
            bytes[i] = rng.random();
        }
        if rng.random_range(0..3) == 0 {
            bytes.truncate(rng.random_range(0..bytes.len()));
        }
        prop_assert_eq!(try_bytes("flipped.gltf", &bytes), Ok(()));
    }

    #[test]
    fn real_json_with_hostile_values_never_panics(seed in any::<u64>()) {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
        let name = ["furnace.gltf", "cornell_animated.gltf", "prism.gltf", "spot_glass.gltf", "textured", "volumes",
            "cameras", "deformed", "animated"][rng.random_range(0..9)];
        let mut doc: Value = match name {
            "textured" => textured_seed(),
            "volumes" => volume_seed(),
            "cameras" => camera_seed(),
            "deformed" => common::deformed_square(),
            "animated" => common::animated_values(),
            _ => serde_json::from_slice(&std::fs::read(scenes().join(name)).unwrap()).unwrap(),
        };
        for _ in 0..rng.random_range(1..4) {
            mutate(&mut doc, &mut rng);
        }
        prop_assert_eq!(try_bytes("mutated.gltf", doc.to_string().as_bytes()), Ok(()));
    }
}

/// The textured, volume, camera, deformation and animated-value seeds themselves load and render (so their mutations explore
/// past the loader), with no warning but the pane's (glass on an open mesh) and the cameras not
/// chosen.
#[test]
fn the_built_seeds_render() {
    let dir = tempfile::tempdir().unwrap();
    let seeds = [
        ("textured", textured_seed(), 0, "'Pane'"),
        ("volumes", volume_seed(), 1, "'Pane'"),
        ("cameras", camera_seed(), 0, ""),
        ("deformed", common::deformed_square(), 0, ""),
        ("animated", common::animated_values(), 0, ""),
    ];
    for (name, seed, expected, named) in seeds {
        let path = dir.path().join(format!("{name}.gltf"));
        std::fs::write(&path, seed.to_string()).unwrap();
        let description = Description::load(&path).unwrap();
        let warnings = &description.warnings;
        assert!(
            warnings.len() == expected && warnings.iter().all(|w| w.contains(named)),
            "{name}: {warnings:?}"
        );
        load_and_render(&path).unwrap();
    }
}

/// Inputs that crashed the loader once (tests/fuzz/*.gltf, *.glb) load or are refused cleanly.
#[test]
fn kept_crashes_stay_fixed() {
    let kept = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests").join("fuzz");
    for entry in std::fs::read_dir(&kept).unwrap() {
        let path = entry.unwrap().path();
        if matches!(path.extension().and_then(|e| e.to_str()), Some("gltf" | "glb")) {
            let bytes = std::fs::read(&path).unwrap();
            let name = path.file_name().unwrap().to_str().unwrap().to_string();
            try_bytes(&name, &bytes).unwrap();
        }
    }
}
