//! The photon pass (docs/design.md, step 3): photons leave lights chosen by power, carrying the pass's
//! wavelengths, and random-walk with Russian roulette. A photon is stored at every non-delta
//! vertex from the second on: the first is direct light, which next-event estimation counts. In
//! a medium that scatters, a photon meets events by free flight (`free_flight.rs`); at each it
//! is stored (from the second vertex on, as on surfaces) and scattered by the phase function.
//!
//! A path is a [`PhotonState`] advanced segment by segment; a caller can watch each segment
//! before it is traced and resume the path later from any saved state, drawing exactly the random
//! numbers it would have drawn (reuse across frames needs both).

use glam::Vec3;

use crate::geometry::offset_origin;
use crate::materials::{Bsdf, ShadingFrame, Transport, Volume};
use crate::sampling::Uniforms;
use crate::scene::Scene;
use crate::spectrum::{hero_only, SampledSpectrum, Wavelengths, LANES};
use crate::transport::context::{PassSamples, PassStats, Renderer, MAX_DEPTH};
use crate::transport::emission::{start_photon, PhotonState};
use crate::transport::free_flight::{Crossing, Flight};

/// A stored photon.
#[derive(Clone, Copy, Debug)]
pub struct Photon {
    /// Where it landed.
    pub p: Vec3,
    /// Unit direction back toward where it came from.
    pub wi: Vec3,
    /// Geometric normal of the surface it landed on, facing `wi`; zero for a photon stored in a
    /// medium.
    pub ng: Vec3,
    /// Its flux at the pass's wavelengths, already divided by the photons per pass.
    pub flux: SampledSpectrum,
    /// Its path carries its hero wavelength alone (it passed a dispersive refraction).
    pub hero_only: bool,
}

/// Traces photon path `k` of `pass`, appending what it stores to `out`.
pub fn trace_photon(renderer: &Renderer, pass: &PassSamples, k: u64, out: &mut Vec<Photon>) -> PassStats {
    match start_photon(renderer, pass, k) {
        Some((state, _)) => continue_photon(renderer, pass, state, out, |_, _, _| {}),
        None => PassStats::default(),
    }
}

/// Traces a path from `state` to its end, appending what it stores to `out`. Before each
/// segment's photon is stored, `watch` sees the state the segment started from, the distance to
/// what it hit (infinite when it left the scene) and how many photons the path had stored.
pub fn continue_photon<R: Uniforms>(
    renderer: &Renderer,
    pass: &PassSamples,
    mut state: PhotonState<R>,
    out: &mut Vec<Photon>,
    mut watch: impl FnMut(&PhotonState<R>, f32, usize),
) -> PassStats {
    let scene = renderer.scene;
    let mut stats = PassStats::default();
    let first_stored = out.len();
    while state.depth < MAX_DEPTH {
        stats.photon_rays += 1;
        let hit = renderer.accel.intersect_opaque(state.origin.into(), state.direction.into(), f32::INFINITY);
        let length = hit.map_or(f32::INFINITY, |h| h.t);
        // What the medium it crossed absorbed joins the roulette's weight below, so that photons
        // in a dark volume end rather than carry ever less flux.
        let mut kept = SampledSpectrum::ONE;
        if renderer.has_volumes {
            match medium_segment(scene, &mut state, length, &pass.wavelengths) {
                Segment::Kept(through) => kept = through,
                Segment::Event(volume, event) => {
                    watch(&state, event.0, out.len() - first_stored);
                    let lambda = &pass.wavelengths;
                    match scatter_in_medium(&mut state, volume, event, lambda, out, &mut stats) {
                        true => continue,
                        false => break,
                    }
                }
            }
        }
        watch(&state, length, out.len() - first_stored);
        let Some(hit) = hit else {
            break;
        };
        let surface = scene.surface(&hit, &pass.wavelengths);
        let material = &scene.materials[surface.material as usize];
        let wo = -Vec3::from(state.direction);
        let rng = &mut state.rng;
        let lobe = material.lobe(&surface.inputs, surface.frame, wo, &pass.wavelengths, rng.next_1d());
        let (frame, bsdf) = (lobe.frame, &lobe.bsdf);
        let lands = bsdf.is_gathered_at() || (*bsdf != Bsdf::PassThrough && material.gathers_photons());
        if *bsdf != Bsdf::PassThrough {
            if let Some(soft) = state.soft_falloff.take() {
                state.flux *= soft.at(surface.p);
            }
        }
        if state.scattered && lands {
            let ng = if surface.frame.ng().dot(wo) < 0.0 { -surface.frame.ng() } else { surface.frame.ng() };
            out.push(Photon {
                p: surface.p,
                wi: wo,
                ng,
                flux: state.flux * kept,
                hero_only: state.hero_only,
            });
            stats.photons_stored += 1;
        }
        let u = rng.next_2d();
        let u_lobe = bsdf.lobe_number(|| rng.next_1d());
        let Some(sample) = bsdf.sample(frame, wo, u, u_lobe, Transport::Importance) else {
            break;
        };
        // Russian roulette with the throughput's change (its mean over the wavelengths) as the
        // survival probability keeps the flux of surviving photons nearly constant. The largest
        // wavelength's change instead traced 28% more photon segments a pass, for no less error
        // in equal time.
        let weight = kept * sample.weight * (lobe.weight * lobe.importance_correction(wo, sample.wi));
        let survive = (weight.element_sum() / LANES as f32).min(1.0);
        if rng.next_1d() >= survive {
            break;
        }
        if !state.hero_only && material.separates_wavelengths(bsdf) {
            state.flux = hero_only(state.flux);
            state.hero_only = true;
        }
        state.flux *= weight / survive;
        if renderer.has_volumes && *bsdf != Bsdf::PassThrough {
            state.media = state.media.crossed(scene, surface.material, surface.frame.ng(), wo, sample.wi);
        }
        state.origin = offset_origin(surface.p, surface.frame.ng(), sample.wi, surface.scale).into();
        state.direction = sample.wi.into();
        state.depth += 1;
        state.scattered |= *bsdf != Bsdf::PassThrough;
    }
    stats
}

/// What a photon's segment of `length` met in the medium it is in.
enum Segment<'s> {
    /// No event: what the medium kept of its light (all of it outside media).
    Kept(SampledSpectrum),
    /// An event in `volume`, which scatters: its distance and weight ([`Crossing::Event`]).
    Event(&'s Volume, (f32, SampledSpectrum)),
}

/// The medium of `scene` the photon of `state` is in, met along its segment of `length` (where it
/// scatters, an event drawn from the photon's stream).
fn medium_segment<'s, R: Uniforms>(
    scene: &'s Scene,
    state: &mut PhotonState<R>,
    length: f32,
    lambda: &Wavelengths,
) -> Segment<'s> {
    let Some(volume) = state.media.medium(scene) else { return Segment::Kept(SampledSpectrum::ONE) };
    if !volume.scatters() {
        return Segment::Kept(volume.transmittance(lambda, length));
    }
    match Flight::new(volume, lambda, state.hero_only).cross(length, state.rng.next_1d()) {
        Crossing::Event { t, weight } => Segment::Event(volume, (t, weight)),
        Crossing::Passed { weight } => Segment::Kept(weight),
    }
}

/// A photon's event `t` along its segment through `volume`, which scatters, its throughput
/// weighed by `weight` ([`Crossing::Event`]): stores the photon there (after a first scattering:
/// light that comes straight from a light is next-event estimation's) and scatters it by the
/// phase function, or ends it by Russian roulette (`false`).
fn scatter_in_medium<R: Uniforms>(
    state: &mut PhotonState<R>,
    volume: &Volume,
    (t, weight): (f32, SampledSpectrum),
    lambda: &Wavelengths,
    out: &mut Vec<Photon>,
    stats: &mut PassStats,
) -> bool {
    let direction = Vec3::from(state.direction);
    let p = Vec3::from(state.origin) + direction * t;
    if let Some(soft) = state.soft_falloff.take() {
        state.flux *= soft.at(p);
    }
    if state.scattered {
        out.push(Photon {
            p,
            wi: -direction,
            ng: Vec3::ZERO,
            flux: state.flux * weight,
            hero_only: state.hero_only,
        });
        stats.photons_stored += 1;
    }
    let Some((scattering, anisotropy)) = volume.scattering(lambda) else { return false };
    let wo = -direction;
    let phase = Bsdf::Medium { scattering, anisotropy };
    let Some(sample) =
        phase.sample(ShadingFrame::new(wo, wo), wo, state.rng.next_2d(), 0.0, Transport::Importance)
    else {
        return false;
    };
    let carried = weight * sample.weight;
    let survive = (carried.element_sum() / LANES as f32).min(1.0);
    if state.rng.next_1d() >= survive {
        return false;
    }
    state.flux *= carried / survive;
    state.origin = p.into();
    state.direction = sample.wi.into();
    state.depth += 1;
    state.scattered = true;
    true
}
