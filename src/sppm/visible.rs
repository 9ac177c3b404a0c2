//! The eye pass (DESIGN.md step 2): a camera ray per pixel, followed through delta bounces to the
//! first non-delta surface, where direct light is estimated by next-event estimation and a
//! visible point is left for the photons to be gathered at (direct light: [`DirectLight`]).
//!
//! Like photon paths, an eye path is an [`EyeState`] advanced segment by segment, which a caller
//! can watch and resume (reuse across frames).

use glam::{Vec2, Vec3};

use super::direct::{DirectLight, DirectTerm};
use super::renderer::{PassSamples, PassStats, Renderer, VisiblePoint, MAX_DEPTH};
use crate::geometry::offset_origin;
use crate::materials::{Bsdf, Lobe, Transport};
use crate::sampling::{pixel_stream, PixelSampler};
use crate::spectrum::{hero_only, SampledSpectrum};

/// A pixel's eye path: the radiance found along it, and its visible point if it has one.
#[derive(Clone, Copy, Debug)]
pub struct EyeResult {
    /// Emission seen along the path plus direct light at the visible point, times throughput.
    pub radiance: SampledSpectrum,
    /// Where photons are gathered.
    pub point: Option<VisiblePoint>,
}

/// An eye path about to trace its next segment.
#[derive(Clone)]
pub struct EyeState {
    /// Where the segment starts.
    pub origin: Vec3,
    /// Its unit direction.
    pub direction: Vec3,
    /// Throughput from the camera.
    pub beta: SampledSpectrum,
    /// The path carries its hero wavelength alone (it passed a dispersive refraction).
    pub hero_only: bool,
    /// Radiance found so far.
    pub radiance: SampledSpectrum,
    /// Segments traced before this one.
    pub depth: u32,
    /// The path's random stream, where this segment leaves it.
    pub rng: PixelSampler,
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

/// Pixel `pixel`'s camera ray for `pass` (the film sample and, with a lens, the aperture sample).
pub fn start_eye_path(renderer: &Renderer, pass: &PassSamples, pixel: usize) -> (EyeState, PassStats) {
    let settings = &renderer.settings;
    let camera = &renderer.scene.camera;
    let mut rng = pixel_stream(settings.seed, pass.index, pixel as u64);
    let (width, height) = (settings.width as usize, settings.height as usize);
    let film = (Vec2::new((pixel % width) as f32, (pixel / width) as f32) + rng.next_2d())
        / Vec2::new(width as f32, height as f32);
    let mut stats = PassStats::default();
    let aspect = width as f32 / height as f32;
    let (origin, direction) = match camera.lens {
        Some(_) => {
            stats.lens_samples += 1;
            camera.ray_through_lens(film, aspect, rng.next_2d())
        }
        None => camera.ray(film, aspect),
    };
    (
        EyeState {
            origin,
            direction,
            beta: SampledSpectrum::ONE,
            hero_only: false,
            radiance: SampledSpectrum::ZERO,
            depth: 0,
            rng,
        },
        stats,
    )
}

/// Traces pixel `pixel`'s camera path for `pass`.
pub fn trace_eye_path(renderer: &Renderer, pass: &PassSamples, pixel: usize) -> (EyeResult, PassStats) {
    let (state, start_stats) = start_eye_path(renderer, pass, pixel);
    let (end, stats) = continue_eye_path(renderer, pass, state, |_, _| {});
    (end.result, start_stats + stats)
}

/// Traces an eye path from `state` to its end. Before a segment's hit is shaded, `watch` sees
/// the state the segment started from and the distance to what it hit (infinite when it left
/// the scene).
pub fn continue_eye_path(
    renderer: &Renderer,
    pass: &PassSamples,
    mut state: EyeState,
    mut watch: impl FnMut(&EyeState, f32),
) -> (EyeEnd, PassStats) {
    let scene = renderer.scene;
    let mut stats = PassStats::default();
    let mut point = None;
    let mut direct = [DirectTerm::ZERO; 2];
    let mut radiance_before = SampledSpectrum::ZERO;
    while state.depth < MAX_DEPTH {
        stats.eye_rays += 1;
        let hit = renderer.accel.intersect(state.origin, state.direction, f32::INFINITY);
        watch(&state, hit.map_or(f32::INFINITY, |h| h.t));
        let Some(hit) = hit else {
            state.radiance += state.beta * scene.escaped_radiance(state.direction, &pass.wavelengths);
            break;
        };
        let surface = scene.surface(&hit, &pass.wavelengths);
        let material = &scene.materials[surface.material as usize];
        let wo = -state.direction;
        state.radiance +=
            state.beta * material.emitted(&surface.inputs, &pass.wavelengths, surface.frame.ng, wo);
        let rng = &mut state.rng;
        let Lobe { frame, bsdf, weight, .. } =
            material.lobe(&surface.inputs, surface.frame, wo, &pass.wavelengths, rng.next_1d());
        if bsdf == Bsdf::Black {
            break;
        }
        state.beta *= weight;
        if !bsdf.is_delta() {
            let visible = VisiblePoint {
                p: surface.p,
                frame,
                wo,
                bsdf,
                beta: state.beta,
                hero_only: state.hero_only,
                scale: surface.scale,
            };
            direct = DirectLight { renderer, wavelengths: &pass.wavelengths, point: &visible }
                .estimate(rng, &mut stats);
            radiance_before = state.radiance;
            state.radiance = with_direct(radiance_before, state.beta, direct.map(|t| t.value));
            point = Some(visible);
            break;
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
        state.origin = offset_origin(surface.p, surface.frame.ng, sample.wi, surface.scale);
        state.direction = sample.wi;
        state.depth += 1;
    }
    let result = EyeResult { radiance: state.radiance, point };
    (EyeEnd { result, radiance_before, direct }, stats)
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
