//! `caustic info SCENE [--frames SPEC]`: what a scene needs and what the renderer will skip
//! (docs/design.md, "Leave out what a scene does not need"), as JSON.

use serde_json::{json, Value};

use crate::materials::{Material, Volume};
use crate::render::{is_animated, load_description, motion_spans, shutter, RenderSettings, Shot};
use crate::scene::description::Description;
use crate::spectrum::Wavelengths;
use crate::transport::{Method, Renderer, AUTO_VISIBLE_BELOW};

/// The lights (by node), materials and camera whose values are animated, with what is animated.
fn animated_values(description: &Description) -> Value {
    let lights = description.lights.iter().filter_map(|light| {
        let values = light.animation.as_ref()?.tracks.properties();
        Some(json!({"node": light.node, "values": values}))
    });
    let mut materials: Vec<Value> = Vec::new();
    for (m, animation) in &description.material_animations {
        let entry =
            json!({"material": description.materials[*m].name, "values": animation.tracks.properties()});
        if !materials.contains(&entry) {
            materials.push(entry);
        }
    }
    let camera = description.camera.animation.as_ref().map(|a| a.tracks.properties()).unwrap_or_default();
    json!({"lights": lights.collect::<Vec<_>>(), "materials": materials, "camera": camera})
}

/// The media of the scene: each material's inside that absorbs or scatters, and the world's fog,
/// with their coefficients at 550 nm.
fn media(description: &Description) -> Value {
    let lambda = Wavelengths::single(550.0, 1.0);
    let entry = |volume: &Volume| {
        let (scattering, anisotropy) = volume.scattering(&lambda).unwrap_or_default();
        json!({"absorption_550nm": volume.absorption(&lambda).x, "scattering_550nm": scattering.x,
               "anisotropy": anisotropy})
    };
    let materials: Vec<Value> = description
        .materials
        .iter()
        .filter_map(|m| Some(json!({"material": m.name, "medium": entry(m.volume.as_ref()?)})))
        .collect();
    json!({"materials": materials, "fog": description.fog.as_ref().map(entry)})
}

/// The JSON report for `settings.scene` over `settings.frames`.
pub fn report(settings: &RenderSettings) -> Result<Value, String> {
    let description = load_description(settings)?;
    let dispersion = description.materials.iter().any(Material::is_dispersive);
    let absorption = description.materials.iter().any(|m| m.volume.is_some()) || description.fog.is_some();
    let scattering = description.scatters();
    let media = media(&description);
    let cut_away = description.materials.iter().any(|m| m.alpha.cuts());
    let holdouts = description.materials.iter().any(|m| m.holdout);
    let transparent_film = description.transparent_film;
    let fps = description.fps;
    let projection = description.camera.projection.name();
    // Each mesh a skin or morph targets shape, once (a mesh's primitives are instances of one name).
    let mut deforming: Vec<Value> = Vec::new();
    for mesh in &description.meshes {
        let Some(deformation) = &mesh.deformation else { continue };
        let entry = json!({"mesh": mesh.name, "by": deformation.kinds()});
        if !deforming.contains(&entry) {
            deforming.push(entry);
        }
    }
    let animated = animated_values(&description);
    let spans = motion_spans(&description, &settings.frames, shutter(settings, &description));
    let animated_scene = is_animated(&description);
    let shot = Shot::new(settings, std::sync::Arc::new(description))?;
    let prepared = shot.prepared();
    let (fixed, moving) = prepared.triangle_counts();
    let instanced = prepared.instanced_triangles();
    let shutter = shot.shutter();
    let reuse = settings.frames.len() > 1 && fixed > 0 && !scattering;
    let needs = json!({
        "dispersion": dispersion,
        "absorption": absorption,
        "scattering": scattering,
        "alpha": cut_away,
        "holdouts": holdouts,
        "transparent_film": transparent_film,
        "motion_blur": shutter.length > 0.0 && prepared.has_motion(),
        "depth_of_field": prepared.lens().is_some(),
        "moving_camera": prepared.camera_moves(),
        "moving_lights": prepared.lights_move(),
        "per_time_scene": prepared.has_motion(),
        "reuse_possible": reuse,
    });
    let eye_paths_shared = reuse && !prepared.camera_moves() && !prepared.lights_move();
    // VCM shares its light paths only with its camera paths (light tracing joins them).
    let light_paths_shared = reuse && (settings.method == Method::Sppm || eye_paths_shared);
    let reuse_shares = json!({
        "photon_paths": light_paths_shared,
        "eye_paths": eye_paths_shared,
    });
    let mut skipped = Vec::new();
    if !prepared.has_motion() {
        skipped.push("posing the scene and building a BVH per pass time (nothing moves: one pose, one BVH)");
    } else if shutter.length == 0.0 {
        skipped.push("time sampling inside the shutter (no shutter: one pose per frame)");
    }
    if prepared.lens().is_none() {
        skipped.push("lens sampling (no aperture: pinhole rays)");
    }
    if !reuse {
        skipped.push("reuse across frames (one frame, no static triangles to share, or a medium scatters)");
    }
    if !dispersion {
        skipped.push("wavelength-dependent refraction (no dispersive material)");
    }
    if !absorption {
        skipped.push("absorption along paths, and the stack of insides they are in (no absorbing volume)");
    }
    if !scattering {
        skipped.push("events in media and the photons stored there (no medium scatters)");
    }
    if !cut_away {
        skipped.push("looking past cut-away surfaces (no material's alpha cuts it)");
    }
    Ok(json!({
        "scene": settings.scene.display().to_string(),
        "frames": settings.frames,
        "fps": fps,
        "camera": projection,
        "shutter_frames": shutter.length,
        "needs": needs,
        "reuse_shares": reuse_shares,
        "spans": spans,
        "triangles": {"static": fixed, "moving": moving, "instanced": instanced.0, "instanced_stored": instanced.1},
        "deforming": deforming,
        "media": media,
        "animated": animated,
        "photons": photons(settings, &shot, animated_scene, reuse),
        "skipped": skipped,
    }))
}

/// How photons are drawn: the default sampling, what pass 0's pilot finds (the fraction of
/// uniform paths a visible point sees) and so what `--photon-sampling auto` uses there; photons
/// per pass and the first radius.
fn photons(settings: &RenderSettings, shot: &Shot, animated: bool, reuse: bool) -> Value {
    let pass_settings = shot.pass_settings();
    let (scene, accel) = shot.pose(0.0);
    let (pilot_seen, settled_uniform) = Renderer::new(&scene, &accel, pass_settings.clone()).auto_at_load();
    let auto_uses = match animated || settled_uniform {
        true => "uniform",
        false => "visible",
    };
    let shared = match reuse && settings.reuse {
        true => "frames rendered together share uniform photon paths (reuse across frames); --no-reuse draws each frame's by its sampling",
        false => "each frame's photons are drawn by its sampling",
    };
    json!({
        "sampling": format!("{:?}", settings.photon_sampling).to_lowercase(),
        "auto_rule": format!("uniform where anything is animated, or where {AUTO_VISIBLE_BELOW} or more of pass 0's uniform pilot paths reach a visible point (no pass traces a pilot then); else per pass, visible where fewer than {AUTO_VISIBLE_BELOW} of its pilot's paths do"),
        "pilot_seen_fraction_pass_0": pilot_seen,
        "auto_uses_on_pass_0": auto_uses,
        "frames": shared,
        "per_pass": pass_settings.photons_per_pass,
        "initial_radius": pass_settings.initial_radius,
        "radius_from": match (settings.radius, shot.view()) {
            (Some(_), _) => json!("--radius"),
            (None, Some(view)) => json!({"view_size": view.size, "photons_per_view": view.photons_per_view}),
            (None, None) => json!("the scene's size (the camera sees no surface)"),
        },
    })
}
