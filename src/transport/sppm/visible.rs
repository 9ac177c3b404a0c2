//! The eye pass (docs/design.md, step 2): a camera ray per pixel, followed through delta bounces and
//! glossy lobes to the first surface photons are gathered at
//! ([`crate::materials::Bsdf::is_gathered_at`]), where direct light is estimated by next-event
//! estimation and a visible point is left for the photons (direct light: [`DirectLight`]).
//!
//! At a glossy vertex the path takes direct light too (a light sample and a BSDF sample, by
//! multiple importance sampling: a small light's highlight in a glossy metal or coat is found
//! either way), then samples on through the lobe; the emission its next segment meets is then
//! already counted. Which lobes are gathered at and which are gone through was chosen by
//! measurement (`tests/bench/glossy.py`: a gold sphere beside a glass ball under an area light,
//! the sphere's relative MSE at equal CPU time). A density estimate in a GGX lobe weighs each of
//! the few photons the lobe sees by its peak and carries the kernel's blur into a sharp
//! reflection; a sample through the lobe reaches a diffuse surface whose estimate is smooth.
//! Going on through a metal rather than gathering in it cuts the error at roughness 0.7 by 2.5x at
//! 10 CPU s and 7.2x at 60 CPU s (this code against the gathering one); a build that also went
//! through rough specular layers (the floor's) cut it at roughness 0.5 and 1.0 by 5x and 1.3x at
//! 10 CPU s, 9x and 3.2x at 60 CPU s, but at 0.7 did 1.4x worse than this code. So a metal is
//! never gathered at, whatever its roughness (as pbrt-v4 and Hachisuka's SPPM notes treat every
//! glossy lobe), while a specular layer over a diffuse base is gathered at with its base unless
//! the layer is narrow (GGX alpha below [`crate::materials::NARROW_COAT_ALPHA`]): then the path
//! picks the layer's own reflection, gone through, or the base, gathered at.
//!
//! Like photon paths, an eye path is an [`EyeState`] advanced segment by segment, which a caller
//! can watch and resume (reuse across frames).

use glam::Vec3;

use super::direct::{DirectLight, DirectTerm};
use crate::geometry::offset_origin;
use crate::materials::{Lobe, Transport, Volume};
use crate::spectrum::{hero_only, SampledSpectrum, Wavelengths};
use crate::transport::context::{PassSamples, PassStats, Renderer, VisiblePoint, MAX_DEPTH};
use crate::transport::eye::{start_eye_path, EyeState, Meeting};
use crate::transport::medium_light::in_scattered;
use crate::transport::shadow::ShadowRay;

/// A pixel's eye path: the radiance found along it, and its visible point if it has one.
#[derive(Clone, Copy, Debug)]
pub struct EyeResult {
    /// Emission seen along the path plus direct light at the visible point, times throughput.
    pub radiance: SampledSpectrum,
    /// Where photons are gathered.
    pub point: Option<VisiblePoint>,
    /// How much of the film the path covers: 0 where the camera sees through to a transparent
    /// film's world or sees a holdout, else 1 (the pixel's alpha is its mean).
    pub coverage: f32,
}

/// An eye path's end: its result, and the direct-light terms whose sum (times the throughput)
/// it added at the visible point.
#[derive(Clone, Copy, Debug)]
pub struct EyeEnd {
    /// The pixel's result.
    pub result: EyeResult,
    /// Radiance found before the visible point.
    pub radiance_before: SampledSpectrum,
    /// Light-sampled and BSDF-sampled direct light at the visible point.
    pub direct: [DirectTerm; 2],
}

/// Traces pixel `pixel`'s camera path for `pass`.
pub fn trace_eye_path(renderer: &Renderer, pass: &PassSamples, pixel: usize) -> (EyeResult, PassStats) {
    let (state, start_stats) = start_eye_path(renderer, pass, pixel);
    let (end, stats) = continue_eye_path(renderer, pass, state, |_| {});
    (end.result, start_stats + stats)
}

/// What a caller watching an eye path sees.
pub enum EyeEvent<'a> {
    /// Before a segment's hit is shaded: the state the segment started from and the distance to
    /// what it hit (infinite when it left the scene).
    Segment(&'a EyeState, f32),
    /// A ray of direct light taken at a glossy vertex on the way, which must be free for its term
    /// to count.
    Shadow(ShadowRay),
}

/// Traces an eye path from `state` to its end, showing `watch` its segments and the rays of
/// direct light on the way (those at the visible point are in the [`EyeEnd`]).
pub fn continue_eye_path(
    renderer: &Renderer,
    pass: &PassSamples,
    mut state: EyeState,
    mut watch: impl FnMut(EyeEvent),
) -> (EyeEnd, PassStats) {
    let scene = renderer.scene;
    let mut stats = PassStats::default();
    let mut point = None;
    let mut direct = [DirectTerm::ZERO; 2];
    let mut radiance_before = SampledSpectrum::ZERO;
    let mut coverage = 1.0;
    while state.depth < MAX_DEPTH {
        stats.eye_rays += 1;
        let hit = renderer.accel.intersect(state.origin.into(), state.direction.into(), f32::INFINITY);
        let length = hit.map_or(f32::INFINITY, |h| h.t);
        watch(EyeEvent::Segment(&state, length));
        let medium = match renderer.has_volumes {
            true => through_medium(renderer, &pass.wavelengths, &mut state, length),
            false => None,
        };
        if !state.lights_sampled && !scene.sphere_lights.is_empty() {
            state.radiance +=
                state.beta * spheres_seen(renderer, &state, (length, medium), &pass.wavelengths);
        }
        if let Some(medium) = medium {
            state.beta *= medium.transmittance(&pass.wavelengths, length);
        }
        let Some(hit) = hit else {
            if state.camera_ray && scene.transparent_film {
                coverage = 0.0;
            } else if !state.lights_sampled {
                state.radiance +=
                    state.beta * scene.escaped_radiance(state.direction.into(), &pass.wavelengths);
            }
            break;
        };
        let surface = scene.surface(&hit, &pass.wavelengths);
        let material = &scene.materials[surface.material as usize];
        let wo = -Vec3::from(state.direction);
        // A holdout the camera sees shows nothing, its emission neither.
        if !state.lights_sampled && !(state.camera_ray && (material.holdout || !material.seen_by_camera)) {
            state.radiance +=
                state.beta * material.emitted(&surface.inputs, &pass.wavelengths, surface.frame.ng(), wo);
        }
        let Lobe { frame, bsdf, weight, .. } =
            material.lobe(&surface.inputs, surface.frame, wo, &pass.wavelengths, state.rng.next_1d());
        match state.meet(&bsdf, material.holdout, &surface, wo) {
            Meeting::Ends { coverage: seen } => {
                coverage = seen;
                break;
            }
            Meeting::PassesThrough => continue,
            Meeting::Scatters => {}
        }
        let rng = &mut state.rng;
        state.beta *= weight;
        let vertex =
            VisiblePoint::new(surface.p, frame, wo, bsdf, state.beta, state.hero_only, surface.scale);
        let direct_light = DirectLight {
            renderer,
            wavelengths: &pass.wavelengths,
            point: &vertex,
            media: state.media,
            material: surface.material,
        };
        if bsdf.is_gathered_at() {
            direct = direct_light.estimate(rng, &mut stats);
            radiance_before = state.radiance;
            state.radiance = with_direct(radiance_before, state.beta, direct.map(|t| t.value));
            point = Some(vertex);
            break;
        }
        state.lights_sampled = !bsdf.is_delta();
        if state.lights_sampled {
            let terms = direct_light.estimate(rng, &mut stats);
            terms.iter().filter_map(|t| t.ray).for_each(|ray| watch(EyeEvent::Shadow(ray)));
            state.radiance = with_direct(state.radiance, state.beta, terms.map(|t| t.value));
        }
        let u = rng.next_2d();
        let u_lobe = bsdf.lobe_number(|| rng.next_1d());
        let Some(sample) = bsdf.sample(frame, wo, u, u_lobe, Transport::Radiance) else {
            break;
        };
        if !state.hero_only && material.separates_wavelengths(&bsdf) {
            state.beta = hero_only(state.beta);
            state.hero_only = true;
        }
        state.beta *= sample.weight;
        if renderer.has_volumes {
            state.media = state.media.crossed(scene, surface.material, surface.frame.ng(), wo, sample.wi);
        }
        state.origin = offset_origin(surface.p, surface.frame.ng(), sample.wi, surface.scale).into();
        state.direction = sample.wi.into();
        state.depth += 1;
    }
    let result = EyeResult { radiance: state.radiance, point, coverage };
    (EyeEnd { result, radiance_before, direct }, stats)
}

/// The radiance of the sphere lights an eye segment from `state` of `length` meets (the
/// camera's own ray sees only those visible to the camera), each times what the medium it runs
/// through, of extinction `extinction` (none outside media), keeps of it over its distance.
fn spheres_seen(
    renderer: &Renderer,
    state: &EyeState,
    (length, medium): (f32, Option<&Volume>),
    lambda: &Wavelengths,
) -> SampledSpectrum {
    let direction = Vec3::from(state.direction);
    renderer
        .scene
        .spheres_met(state.origin.into(), direction, length)
        .filter(|(_, sphere, _)| sphere.seen_by_camera || !state.camera_ray)
        .map(|(_, sphere, t)| {
            sphere.radiance(-direction, lambda)
                * medium.map_or(SampledSpectrum::ONE, |m| m.transmittance(lambda, t))
        })
        .sum()
}

/// The medium the eye path of `state` runs through along its segment of `length` (`None` outside
/// media). In one that scatters, the direct light it
/// scatters toward the path along the segment is added to the path's radiance; the light it
/// scatters there that has scattered before is the photons', gathered along the segment as a
/// beam (`beams.rs`).
#[inline(always)]
fn through_medium<'s>(
    renderer: &Renderer<'s>,
    lambda: &Wavelengths,
    state: &mut EyeState,
    length: f32,
) -> Option<&'s Volume> {
    let volume = state.media.medium(renderer.scene)?;
    if volume.scatters() {
        let rng = &mut state.rng;
        let u = [rng.next_1d(), rng.next_1d(), rng.next_1d(), rng.next_1d()];
        let segment = (state.origin.into(), state.direction.into(), length);
        state.radiance += state.beta * in_scattered(renderer, lambda, segment, volume, u);
    }
    Some(volume)
}

/// The radiance of an eye path: what it found before its visible point plus the direct light
/// there (one function, so that a path resumed in another frame adds in the same order).
pub fn with_direct(
    radiance_before: SampledSpectrum,
    beta: SampledSpectrum,
    [light, bsdf]: [SampledSpectrum; 2],
) -> SampledSpectrum {
    radiance_before + beta * (light + bsdf)
}
