//! Light paths leaving the lights, which both methods share: each path's own random stream (so
//! that a path is the same whichever thread traces it), the chunks passes split them into, the
//! emitted photon's first state ([`PhotonState`]).

use glam::Vec3A;
use rayon::prelude::*;

use crate::lights::SoftFalloff;
use crate::sampling::{stream, Sampler, Stream, Uniforms};
use crate::spectrum::SampledSpectrum;
use crate::transport::context::{PassSamples, Renderer};
use crate::transport::media::Media;

/// A photon path about to trace its next segment, drawing its uniform numbers from `R`.
#[derive(Clone)]
pub struct PhotonState<R = Sampler> {
    /// Where the segment starts (16-byte aligned, as is the direction: a state is written
    /// whole and read whole, and 12-byte fields read as 16-byte words stall the store buffer).
    pub origin: Vec3A,
    /// Its unit direction.
    pub direction: Vec3A,
    /// The flux carried.
    pub flux: SampledSpectrum,
    /// The path carries its hero wavelength alone.
    pub hero_only: bool,
    /// The volumes it is in.
    pub media: Media,
    /// Segments traced before this one.
    pub depth: u32,
    /// It has scattered off a surface (not only passed where alpha cuts one away): from here on
    /// it is not direct light, and is stored.
    pub scattered: bool,
    /// Its light's Soft Falloff, until the path first meets a surface.
    pub soft_falloff: Option<SoftFalloff>,
    /// The path's random numbers, where this segment leaves them.
    pub rng: R,
}

/// Photon paths traced together by one task.
const CHUNK: usize = 1024;

/// The photon paths `paths` in chunks for parallel tasks, in order.
pub fn photon_chunks(
    paths: std::ops::Range<usize>,
) -> impl IndexedParallelIterator<Item = std::ops::Range<u64>> {
    let (start, end) = (paths.start, paths.end);
    let chunk_paths =
        move |chunk: usize| (start + chunk * CHUNK) as u64..(start + (chunk + 1) * CHUNK).min(end) as u64;
    (0..(end - start).div_ceil(CHUNK)).into_par_iter().map(chunk_paths)
}

/// The chunk of [`photon_chunks`] (from path 0) that holds path `k`, and `k`'s place in it.
pub fn chunk_of(k: usize) -> (usize, usize) {
    (k / CHUNK, k % CHUNK)
}

/// Photon path `k` of `pass` as it leaves its light, and the index of that light; `None` when no
/// light emits at the pass's wavelengths.
pub fn start_photon(renderer: &Renderer, pass: &PassSamples, k: u64) -> Option<(PhotonState, usize)> {
    emit_photon(renderer, pass, photon_stream(renderer, pass, k))
}

/// The random stream of photon path `k` of `pass`.
pub fn photon_stream(renderer: &Renderer, pass: &PassSamples, k: u64) -> Sampler {
    stream(renderer.settings.seed, Stream::Photon, pass.index, k)
}

/// A photon path drawing from `rng` as it leaves its light, and the index of that light; `None`
/// when no light emits at the pass's wavelengths.
pub fn emit_photon<R: Uniforms>(
    renderer: &Renderer,
    pass: &PassSamples,
    mut rng: R,
) -> Option<(PhotonState<R>, usize)> {
    let (index, p_light) = renderer.light_choice.sample(rng.next_1d())?;
    let emitted =
        renderer.scene.lights[index].emit_photon(rng.next_2d(), rng.next_2d(), &pass.wavelengths)?;
    let flux = emitted.flux / (p_light * renderer.settings.photons_per_pass as f32);
    let state = PhotonState {
        origin: emitted.origin.into(),
        direction: emitted.direction.into(),
        flux,
        hero_only: false,
        media: renderer.light_media(index),
        depth: 0,
        scattered: false,
        soft_falloff: renderer.scene.lights[index].photon_falloff(),
        rng,
    };
    Some((state, index))
}
