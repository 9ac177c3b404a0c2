//! Hostile input: every broken, malicious or impossible scene ends in one clear message and a
//! non-zero exit — never a panic, a hang or an unbounded allocation — and nothing already on disk
//! is lost.

mod common;

use common::*;
use serde_json::{json, Value};
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

/// Runs `command` (reading its output as it comes), failing the test if it takes more than 60
/// seconds.
fn run_within_a_minute(mut command: Command) -> Output {
    let child = command.stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().expect("start caustic");
    let pid = child.id();
    let (done, result) = std::sync::mpsc::channel();
    std::thread::spawn(move || done.send(child.wait_with_output().expect("output")));
    result.recv_timeout(Duration::from_secs(60)).unwrap_or_else(|_| {
        let _ = Command::new("kill").args(["-9", &pid.to_string()]).status();
        panic!("{command:?} still runs after a minute");
    })
}

/// The render of `scene` succeeds, with no panic, and its warnings name every part of `expected`.
fn assert_rendered_with_warning(scene: &Path, expected: &[&str]) {
    let out = tempfile::tempdir().unwrap();
    let output = run_within_a_minute(render_command(scene, out.path()));
    let text = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{} failed: {text}", scene.display());
    assert!(!text.contains("panicked") && text.contains("warning"), "{}: {text}", scene.display());
    for part in expected {
        assert!(text.contains(part), "{}: '{text}' does not mention '{part}'", scene.display());
    }
}

fn render_command(scene: &Path, out: &Path) -> Command {
    let mut command = Command::new(env!("CARGO_BIN_EXE_caustic"));
    command.args(["render", scene.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    command.args(["--passes", "1", "--resolution", "8x8", "--progress", "none"]);
    command
}

/// The render of `scene` fails with every part of `expected` in its message, and no panic.
fn assert_refused(scene: &Path, expected: &[&str]) {
    let out = tempfile::tempdir().unwrap();
    let output = run_within_a_minute(render_command(scene, out.path()));
    let text = String::from_utf8_lossy(&output.stderr);
    assert!(!output.status.success(), "{} rendered: {text}", scene.display());
    assert!(!text.contains("panicked"), "{}: {text}", scene.display());
    for part in expected {
        assert!(text.contains(part), "{}: '{text}' does not mention '{part}'", scene.display());
    }
    assert!(std::fs::read_dir(out.path()).map_or(true, |mut d| d.next().is_none()), "it left files behind");
}

/// The bundled furnace (a .gltf with its .bin) copied to `dir` with `edit` applied to its JSON.
fn furnace_edited(dir: &Path, name: &str, edit: impl FnOnce(&mut Value)) -> PathBuf {
    let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    std::fs::copy(scenes.join("furnace.bin"), dir.join("furnace.bin")).unwrap();
    let mut doc: Value =
        serde_json::from_str(&std::fs::read_to_string(scenes.join("furnace.gltf")).unwrap()).unwrap();
    edit(&mut doc);
    let path = dir.join(name);
    std::fs::write(&path, doc.to_string()).unwrap();
    path
}

#[test]
fn malformed_files_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // A truncated .glb.
    let mut gltf = GltfBuilder::default();
    let white = gltf.material(diffuse([0.8, 0.8, 0.8]));
    gltf.quad_y("Floor", 0.0, 1.0, true, white);
    gltf.camera([0.0, 1.0, 0.0], [0.0, -1.0, 0.0], 0.5);
    let glb = gltf.write_glb(d, "whole");
    let bytes = std::fs::read(&glb).unwrap();
    for (name, cut) in [("header.glb", 10), ("half.glb", bytes.len() / 2), ("last_byte.glb", bytes.len() - 1)]
    {
        std::fs::write(d.join(name), &bytes[..cut]).unwrap();
        assert_refused(&d.join(name), &[name, "glTF"]);
    }
    std::fs::write(d.join("json.gltf"), r#"{"hello": "world"}"#).unwrap();
    assert_refused(&d.join("json.gltf"), &["json.gltf", "missing field `asset`"]);
    std::fs::write(d.join("noise.gltf"), [0u8, 159, 146, 150, 7, 255]).unwrap();
    assert_refused(&d.join("noise.gltf"), &["noise.gltf", "not a valid glTF file"]);
}

#[test]
fn references_outside_the_scene_folder_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let bin = d.join("furnace.bin");
    let cases = [
        ("absolute.gltf", bin.to_str().unwrap().to_string(), "absolute paths and URLs are refused"),
        ("parent.gltf", "../furnace.bin".to_string(), "leaves the scene's folder"),
        ("encoded.gltf", "sub/%2e%2e/%2E%2E/furnace.bin".to_string(), "leaves the scene's folder"),
        ("url.gltf", "file:///etc/passwd".to_string(), "absolute paths and URLs are refused"),
    ];
    for (name, uri, why) in cases {
        let path = furnace_edited(d, name, |doc| doc["buffers"][0]["uri"] = json!(uri));
        assert_refused(&path, &[name, "buffer 0 refers to", why]);
    }
    let world = furnace_edited(d, "world.gltf", |doc| {
        doc["scenes"][0]["extras"] = json!({"caustic": {"world": {"image": "/etc/sky.hdr"}}});
    });
    assert_refused(&world, &["caustic.world.image", "absolute paths"]);
    let image = furnace_edited(d, "image.gltf", |doc| {
        doc["images"] = json!([{"uri": "../../sky.png"}]);
        doc["textures"] = json!([{"source": 0}]);
    });
    assert_refused(&image, &["image 0 refers to '../../sky.png'", "leaves the scene's folder"]);
}

#[test]
fn data_that_runs_past_its_buffer_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let cases: [(&str, fn(&mut Value), &[&str]); 7] = [
        (
            "count.gltf",
            |doc| doc["accessors"][0]["count"] = json!(1_000_000_000_000u64),
            &["accessor 0 (1000000000000 elements", "runs past buffer view 0"],
        ),
        (
            "zeros.gltf",
            |doc| {
                doc["accessors"][0].as_object_mut().unwrap().remove("bufferView");
                doc["accessors"][0]["count"] = json!(1_000_000_000_000u64);
            },
            &["accessor 0 has no data and claims 1000000000000 elements"],
        ),
        (
            "offset.gltf",
            |doc| doc["accessors"][0]["byteOffset"] = json!(1_000_000),
            &["accessor 0", "from byte 1000000", "runs past"],
        ),
        (
            "view.gltf",
            |doc| doc["bufferViews"][0]["byteLength"] = json!(1_000_000_000u64),
            &["buffer view 0", "runs past buffer 0"],
        ),
        (
            "buffer.gltf",
            |doc| doc["buffers"][0]["byteLength"] = json!(1_000_000_000_000u64),
            &["buffer 0", "expected 1000000000000 bytes"],
        ),
        (
            "base64.gltf",
            |doc| doc["buffers"][0]["uri"] = json!("data:application/octet-stream;base64,@@not base64@@"),
            &["data URI is not valid base64"],
        ),
        (
            "index.gltf",
            |doc| {
                let view = doc["accessors"]
                    [doc["meshes"][0]["primitives"][0]["indices"].as_u64().unwrap() as usize]["bufferView"]
                    .clone();
                doc["bufferViews"][view.as_u64().unwrap() as usize]["byteOffset"] = json!(0);
            },
            &["index", "out of range"],
        ),
    ];
    for (name, edit, expected) in cases {
        let path = furnace_edited(d, name, edit);
        let mut parts = vec![name];
        parts.extend_from_slice(expected);
        assert_refused(&path, &parts);
    }
    // A texture that is not an image (the scene's own .bin named as a texture) renders magenta.
    let texture = furnace_edited(d, "texture.gltf", |doc| {
        doc["images"] = json!([{"uri": "furnace.bin"}]);
        doc["textures"] = json!([{"source": 0}]);
        doc["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = json!({"index": 0});
    });
    assert_rendered_with_warning(&texture, &["texture.gltf", "furnace.bin", "cannot be decoded", "magenta"]);
}

/// A disk that fills up while a frame is written: the render fails with the reason, the frame
/// rendered before is intact and no temporary file is left (writes capped with `ulimit -f`).
#[test]
fn a_full_disk_keeps_the_previous_frame() {
    let dir = tempfile::tempdir().unwrap();
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join("furnace.gltf");
    let first = run_within_a_minute(render_command(&scene, dir.path()));
    assert!(first.status.success(), "{}", String::from_utf8_lossy(&first.stderr));
    let frame = dir.path().join("frame_0001.exr");
    let before = std::fs::read(&frame).unwrap();
    let mut capped = Command::new("bash");
    capped.arg("-c").arg("trap '' XFSZ; ulimit -f 1; exec \"$0\" \"$@\"");
    capped.arg(env!("CARGO_BIN_EXE_caustic"));
    capped.args(["render", scene.to_str().unwrap(), "-o", dir.path().to_str().unwrap()]);
    capped.args(["--passes", "2", "--resolution", "64x64", "--progress", "none"]);
    let output = run_within_a_minute(capped);
    let text = String::from_utf8_lossy(&output.stderr);
    assert!(!output.status.success(), "the capped render succeeded: {text}");
    assert!(text.contains("cannot write") && text.contains("frame_0001.exr"), "{text}");
    assert_eq!(std::fs::read(&frame).unwrap(), before, "the previous frame changed");
    let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(names, ["frame_0001.exr"], "files left behind");
}

/// Ctrl-C (SIGINT) or SIGTERM during a frame range: the render ends after its current pass with a
/// message, every frame written before is intact, nothing half-written is left, and the same
/// command with `--resume` renders the rest.
#[test]
fn an_interrupted_render_keeps_its_frames_and_resumes() {
    use std::io::BufRead;
    for signal in ["INT", "TERM"] {
        let dir = tempfile::tempdir().unwrap();
        let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join("shot.gltf");
        let args = |extra: &[&str]| {
            let mut c = Command::new(env!("CARGO_BIN_EXE_caustic"));
            c.args([
                "render",
                scene.to_str().unwrap(),
                "-o",
                dir.path().to_str().unwrap(),
                "--frames",
                "1-4",
            ]);
            c.args([
                "--no-reuse",
                "--passes",
                "300",
                "--resolution",
                "48x36",
                "--photons",
                "3000",
                "--progress",
                "json",
            ]);
            c.args(extra);
            c
        };
        let mut child = args(&[]).stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().unwrap();
        let mut lines = std::io::BufReader::new(child.stdout.take().unwrap()).lines();
        let first_written =
            lines.by_ref().map(|l| l.unwrap()).find(|l| l.contains("\"written\"")).expect("a frame");
        // Keep reading, as the add-on does, so the renderer's progress lines have somewhere to go.
        let drain = std::thread::spawn(move || lines.count());
        let sent = Instant::now();
        let killed =
            Command::new("kill").args([&format!("-{signal}"), &child.id().to_string()]).status().unwrap();
        assert!(killed.success());
        let output = child.wait_with_output().unwrap();
        let waited = sent.elapsed();
        drain.join().unwrap();
        let text = String::from_utf8_lossy(&output.stderr);
        assert!(!output.status.success(), "SIG{signal}: the render did not fail: {text}");
        assert!(text.contains("interrupted") && text.contains("--resume"), "SIG{signal}: {text}");
        assert!(waited < Duration::from_secs(20), "SIG{signal}: took {waited:?} to stop");
        assert!(first_written.contains("frame_0001.exr"), "{first_written}");
        let names = |d: &Path| {
            let mut n: Vec<String> = std::fs::read_dir(d)
                .unwrap()
                .map(|e| e.unwrap().file_name().into_string().unwrap())
                .collect();
            n.sort();
            n
        };
        let kept = names(dir.path());
        assert!(kept.iter().all(|n| n.starts_with("frame_") && n.ends_with(".exr")), "SIG{signal}: {kept:?}");
        for name in &kept {
            let image = read_exr(&dir.path().join(name));
            assert!(image.mean_all().iter().all(|c| c.is_finite() && *c > 0.0), "{name} is damaged");
        }
        let resumed = run_within_a_minute(args(&["--resume"]));
        assert!(resumed.status.success(), "{}", String::from_utf8_lossy(&resumed.stderr));
        assert_eq!(
            names(dir.path()),
            ["frame_0001.exr", "frame_0002.exr", "frame_0003.exr", "frame_0004.exr"]
        );
    }
}

/// CRC-32 (PNG's), for writing a PNG header by hand.
fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &b in bytes {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 != 0 { (crc >> 1) ^ 0xEDB8_8320 } else { crc >> 1 };
        }
    }
    !crc
}

/// An 8 x 8 PNG.
fn small_png() -> Vec<u8> {
    let mut png = Vec::new();
    image::RgbImage::from_pixel(8, 8, image::Rgb([200, 100, 50]))
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .unwrap();
    png
}

/// A PNG whose header claims 100,000 x 100,000 pixels, with a valid checksum.
fn huge_png() -> Vec<u8> {
    let mut huge = small_png();
    // The IHDR chunk's width and height (bytes 16..24) and its CRC (bytes 29..33).
    huge[16..20].copy_from_slice(&100_000u32.to_be_bytes());
    huge[20..24].copy_from_slice(&100_000u32.to_be_bytes());
    let crc = crc32(&huge[12..29]);
    huge[29..33].copy_from_slice(&crc.to_be_bytes());
    huge
}

/// Hostile textures render magenta (as Cycles renders an image it cannot read) with a warning
/// naming the image, never a panic or an out-of-memory: a truncated PNG, and a PNG that claims
/// 100,000 x 100,000 texels.
#[test]
fn hostile_textures_render_magenta() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let png = small_png();
    std::fs::write(d.join("truncated.png"), &png[..png.len() / 2]).unwrap();
    std::fs::write(d.join("huge.png"), huge_png()).unwrap();
    for image in ["truncated.png", "huge.png"] {
        let path = furnace_edited(d, &format!("{image}.gltf"), |doc| {
            doc["images"] = json!([{"uri": image}]);
            doc["textures"] = json!([{"source": 0}]);
            doc["materials"][0]["normalTexture"] = json!({"index": 0});
        });
        assert_rendered_with_warning(&path, &[image, "cannot be decoded", "magenta"]);
    }
}

/// World images that cannot light a scene make a magenta world (as in Cycles) with a warning
/// naming the file: one that is not an image, one whose header claims 100,000 x 100,000 pixels,
/// and one with a pixel that is not a number.
#[test]
fn hostile_world_images_render_magenta() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("text.hdr"), "#?RADIANCE\nnot a sky\n").unwrap();
    std::fs::write(d.join("huge.png"), huge_png()).unwrap();
    exr::prelude::write_rgb_file(d.join("nan.exr"), 4, 2, |x, y| match (x, y) {
        (1, 1) => (f32::NAN, 0.5, 0.5),
        _ => (0.5, 0.5, 0.5),
    })
    .unwrap();
    for (image, why) in [
        ("text.hdr", "cannot read environment image"),
        ("huge.png", "cannot read environment image"),
        ("nan.exr", "non-finite pixels"),
    ] {
        let path = furnace_edited(d, &format!("{image}.gltf"), |doc| {
            doc["scenes"][0]["extras"] = json!({"caustic": {"world": {"image": image, "strength": 1.0}}});
        });
        assert_rendered_with_warning(&path, &[image, why, "magenta"]);
    }
}

/// A clear coat's or a sheen's texture that names a texture the file does not have is refused with a message
/// naming the material and the reference.
#[test]
fn a_layer_texture_that_is_not_there_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let path = furnace_edited(dir.path(), "coat.gltf", |doc| {
        doc["materials"][0]["extensions"] = json!({"KHR_materials_clearcoat": {"clearcoatFactor": 1.0, "clearcoatNormalTexture": {"index": 9}}});
    });
    assert_refused(&path, &["KHR_materials_clearcoat.clearcoatNormalTexture", "texture 9", "does not have"]);
    let path = furnace_edited(dir.path(), "sheen.gltf", |doc| {
        doc["materials"][0]["extensions"] = json!({"KHR_materials_sheen": {"sheenColorFactor": [1.0, 1.0, 1.0],
            "sheenColorTexture": {"index": 4}}});
    });
    assert_refused(&path, &["KHR_materials_sheen.sheenColorTexture", "texture 4", "does not have"]);
}

/// A volume whose values mean nothing (an attenuation distance of 0 or below, a negative
/// thickness, a colour outside [0, 1] or not three numbers) is refused with a message naming the
/// material and the field.
#[test]
fn impossible_volumes_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        (json!({"attenuationDistance": 0.0, "attenuationColor": [0.5, 0.5, 0.5]}), "attenuationDistance"),
        (json!({"attenuationDistance": -2.0}), "attenuationDistance"),
        (json!({"attenuationDistance": "far"}), "attenuationDistance"),
        (json!({"thicknessFactor": -0.1}), "thicknessFactor"),
        (json!({"attenuationColor": [0.5, 1.5, 0.5], "attenuationDistance": 1.0}), "attenuationColor"),
        (json!({"attenuationColor": [0.5, 0.5], "attenuationDistance": 1.0}), "attenuationColor"),
    ];
    for (i, (volume, field)) in cases.into_iter().enumerate() {
        let path = furnace_edited(dir.path(), &format!("volume{i}.gltf"), |doc| {
            doc["materials"][0]["extensions"] = json!({"KHR_materials_transmission": {"transmissionFactor": 1.0},
                "KHR_materials_volume": volume});
        });
        assert_refused(&path, &["material '", &format!("KHR_materials_volume.{field}")]);
    }
}

/// A light's colour temperature below 100 K, or not a number, is refused, naming the node and
/// the field (or the value).
#[test]
fn an_impossible_colour_temperature_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [(json!(-5.0), "temperature_k"), (json!(0.0), "temperature_k"), (json!("warm"), "\"warm\"")];
    for (i, (kelvin, named)) in cases.into_iter().enumerate() {
        let path = furnace_edited(dir.path(), &format!("temperature{i}.gltf"), |doc| {
            doc["nodes"][0]["extras"] = json!({"caustic": {"temperature_k": kelvin}});
        });
        assert_refused(&path, &["node 'Enclosure'", named]);
    }
}

/// An orthographic camera without a positive extent, and a panorama whose ranges are empty or
/// leave the sphere, are refused naming the camera's node.
#[test]
fn impossible_cameras_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let camera_node = |doc: &Value| {
        doc["nodes"].as_array().unwrap().iter().position(|n| n.get("camera").is_some()).unwrap()
    };
    let ortho = furnace_edited(dir.path(), "ortho.gltf", |doc| {
        doc["cameras"][0] = json!({"type": "orthographic", "orthographic": {"xmag": 1.0, "ymag": 0.0, "znear": 0.1, "zfar": 10.0}});
    });
    assert_refused(&ortho, &["orthographic camera needs positive xmag and ymag"]);
    for (i, panorama) in [json!({"latitude_deg": [10.0, -10.0]}), json!({"longitude_deg": [-300.0, 300.0]})]
        .into_iter()
        .enumerate()
    {
        let path = furnace_edited(dir.path(), &format!("panorama{i}.gltf"), |doc| {
            let node = camera_node(doc);
            doc["nodes"][node]["extras"] = json!({"caustic": {"panorama": panorama}});
        });
        assert_refused(&path, &["extras `caustic.panorama`", "latitudes from low to high"]);
    }
    let spot = furnace_edited(dir.path(), "spot.gltf", |doc| {
        doc["nodes"][0]["extras"] = json!({"caustic": {"spot_blend": 1.5}});
    });
    assert_refused(
        &spot,
        &["node 'Enclosure'", "`caustic.spot_blend`: expected a blend from 0 to 1, got 1.5"],
    );
    let seen = furnace_edited(dir.path(), "seen.gltf", |doc| {
        doc["nodes"][0]["extras"] = json!({"caustic": {"visible_to_camera": "yes"}});
    });
    assert_refused(&seen, &["visible_to_camera", "expected a boolean"]);
    let spread = furnace_edited(dir.path(), "spread.gltf", |doc| {
        let area = json!({"shape": "SQUARE", "size": 1.0, "power": 10.0, "spread_deg": 270.0});
        doc["nodes"][0]["extras"] = json!({"caustic": {"area_light": area}});
    });
    assert_refused(&spread, &["node 'Enclosure' area light", "expected a spread_deg from 0 to 180, got 270"]);
}

/// Hostile texture references and attributes render with a warning naming the material or mesh:
/// a texture on a texture coordinate set Caustic does not carry, and tangents that are not
/// finite numbers.
#[test]
fn hostile_texture_references_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    image::RgbImage::from_pixel(2, 2, image::Rgb([128, 128, 255])).save(d.join("flat.png")).unwrap();
    let mut gltf = GltfBuilder::default();
    gltf.texture("flat.png");
    let material = gltf.material(json!({"name": "Bumpy", "normalTexture": {"index": 0},
        "pbrMetallicRoughness": {"baseColorTexture": {"index": 0, "texCoord": 7}}}));
    gltf.mesh("Panel", &[[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]], material);
    gltf.attribute("TANGENT", &[[f32::NAN, 0.0, 0.0, 1.0]; 3].concat(), 4, "VEC4");
    gltf.camera([0.0, 0.0, 3.0], [0.0, 0.0, -1.0], 0.5);
    gltf.scene_extras(json!({"world": {"color": [1.0, 1.0, 1.0], "strength": 1.0}}));
    let path = gltf.write(d, "hostile_refs");
    let output = run_within_a_minute(render_command(&path, d));
    let text = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{text}");
    for expected in [
        "material 'Bumpy': its base colour texture reads texture coordinate set 7",
        "mesh 'Panel': TANGENT has values that are not finite numbers; ignored",
        "mesh 'Panel': its normal map is not applied",
    ] {
        assert!(text.contains(expected), "no '{expected}' in:\n{text}");
    }
}

/// A function writing `base` under a name into `dir` with an edit made; `base` itself renders
/// (so that each refusal of an edited copy is its edit's).
fn edited_copies(base: Value, dir: &Path) -> impl Fn(&str, &dyn Fn(&mut Value)) -> PathBuf + '_ {
    let write = move |name: &str, edit: &dyn Fn(&mut Value)| {
        let mut doc = base.clone();
        edit(&mut doc);
        let path = dir.join(name);
        std::fs::write(&path, doc.to_string()).unwrap();
        path
    };
    let out = tempfile::tempdir().unwrap();
    let output = run_within_a_minute(render_command(&write("whole.gltf", &|_| {}), out.path()));
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    write
}

/// Each broken animated value (`KHR_animation_pointer` or the `caustic.tracks` extras) is refused
/// with a message naming its pointer.
#[test]
fn hostile_animated_values_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let write = edited_copies(animated_values(), dir.path());
    let pointer = |d: &mut Value, p: &str| {
        d["animations"][0]["channels"][0]["target"]["extensions"]["KHR_animation_pointer"]["pointer"] =
            json!(p)
    };
    let instancing = |d: &mut Value, key: &str, value: Value| {
        d["nodes"][1]["extensions"]["EXT_mesh_gpu_instancing"]["attributes"][key] = value
    };
    let attribute = |d: &Value, key: &str| {
        d["nodes"][1]["extensions"]["EXT_mesh_gpu_instancing"]["attributes"][key].clone()
    };
    let cases: [(&str, &dyn Fn(&mut Value), &[&str]); 11] = [
        (
            "instances_of_no_accessor.gltf",
            &|d| instancing(d, "SCALE", json!(999)),
            &["node 'Glow' EXT_mesh_gpu_instancing", "SCALE names accessor 999"],
        ),
        (
            "instances_counted_twice.gltf",
            &|d| {
                let accessor = attribute(d, "TRANSLATION").as_u64().unwrap() as usize;
                d["accessors"][accessor]["count"] = json!(2);
            },
            &["node 'Glow' EXT_mesh_gpu_instancing", "different instance counts ([2, 3, 3])"],
        ),
        (
            "instances_of_wrong_width.gltf",
            &|d| {
                let rotation = attribute(d, "ROTATION");
                instancing(d, "TRANSLATION", rotation)
            },
            &["node 'Glow' EXT_mesh_gpu_instancing", "TRANSLATION must hold 3 floats an instance"],
        ),
        (
            "no_such_light.gltf",
            &|d| pointer(d, "/extensions/KHR_lights_punctual/lights/3/intensity"),
            &["lights/3/intensity", "names light 3, but the file has 1"],
        ),
        (
            "no_such_material.gltf",
            &|d| pointer(d, "/materials/9/emissiveFactor"),
            &["'/materials/9/emissiveFactor'", "names materials 9, but the file has 2"],
        ),
        (
            "no_pointer.gltf",
            &|d| {
                d["animations"][0]["channels"][0]["target"]
                    .as_object_mut()
                    .unwrap()
                    .remove("extensions")
                    .map(drop)
                    .unwrap()
            },
            &["animation 0 channel 0", "no KHR_animation_pointer pointer"],
        ),
        (
            "colour_of_one_float.gltf",
            &|d| pointer(d, "/extensions/KHR_lights_punctual/lights/0/color"),
            &["lights/0/color", "2 key times need 6 values, found 2"],
        ),
        (
            "integer_keys.gltf",
            &|d| {
                let output = d["animations"][0]["samplers"][0]["output"].as_u64().unwrap() as usize;
                d["accessors"][output]["componentType"] = json!(5123);
            },
            &["lights/0/intensity", "must hold float scalars or vectors"],
        ),
        (
            "missing_sampler.gltf",
            &|d| d["animations"][0]["channels"][0]["sampler"] = json!(5),
            &["lights/0/intensity", "names sampler 5, but the animation has 1"],
        ),
        (
            "tracks_backwards.gltf",
            &|d| d["scenes"][0]["extras"]["caustic"]["tracks"][0]["times"] = json!([1.0, 0.0]),
            &["`caustic.tracks`", "area_light/power", "key times must increase"],
        ),
        (
            "tracks_cubic.gltf",
            &|d| d["scenes"][0]["extras"]["caustic"]["tracks"][0]["interpolation"] = json!("CUBICSPLINE"),
            &["`caustic.tracks`", "LINEAR or STEP, got CUBICSPLINE"],
        ),
    ];
    for (name, edit, expected) in cases {
        assert_refused(&write(name, edit), expected);
    }
}

/// Each broken piece of a skin or of morph targets is refused with a message naming it; weights
/// animated on a mesh without morph targets are warned of.
#[test]
fn hostile_skins_and_morph_targets_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let write = edited_copies(deformed_square(), dir.path());
    let skin = |doc: &mut Value| doc["skins"][0].clone();
    let cases: [(&str, &dyn Fn(&mut Value), &[&str]); 7] = [
        (
            "one_joint.gltf",
            &|d| d["skins"][0] = json!({"joints": [d["skins"][0]["joints"][0]]}),
            &["Square", "names joint 1", "1 joints"],
        ),
        (
            "no_joints.gltf",
            &|d| d["skins"][0] = json!({"joints": []}),
            &["node 'Square': skin 0", "1 to 65535 joints"],
        ),
        (
            "joint_not_a_node.gltf",
            &|d| d["skins"][0]["joints"] = json!([0, 999]),
            &["skins[0].joints[1]", "out of bounds"],
        ),
        (
            "bind_matrices_short.gltf",
            &|d| {
                let mut s = skin(d);
                s["joints"] = json!([s["joints"][0], s["joints"][1], s["joints"][1]]);
                d["skins"][0] = s;
            },
            &["node 'Square': skin 0", "expected 3 inverse bind matrices", "found 2"],
        ),
        (
            "no_weights.gltf",
            &|d| {
                d["meshes"][1]["primitives"][0]["attributes"].as_object_mut().unwrap().remove("WEIGHTS_0");
            },
            &["Square", "JOINTS_0 and WEIGHTS_0"],
        ),
        (
            "weights_for_two_targets.gltf",
            &|d| d["nodes"][1]["weights"] = json!([0.5, 0.5]),
            &["Square", "default morph target weights"],
        ),
        (
            "weights_keys_short.gltf",
            &|d| d["animations"][0]["samplers"][0]["interpolation"] = json!("CUBICSPLINE"),
            &["Square", "need 6 values, found 2"],
        ),
    ];
    for (name, edit, expected) in cases {
        assert_refused(&write(name, edit), expected);
    }
    // Weights animated on a mesh without morph targets (Blender's exporter writes them for shape
    // keys under modifiers it applied) render the mesh unanimated, named in a warning.
    let stray = write("weights_of_a_mesh_without_targets.gltf", &|d: &mut Value| {
        d["animations"][0]["channels"][0]["target"]["node"] = json!(0)
    });
    assert_rendered_with_warning(&stray, &["Floor", "no morph targets", "unanimated"]);
}
