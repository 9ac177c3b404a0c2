//! Caustic: spectral stochastic progressive photon mapping for animated glTF shots.
//!
//! Data flows one way, one module per stage:
//!
//! ```text
//! glTF + extras --scene--> Scene --accel--> BVH
//!                            |                |
//!        spectrum, sampling, materials, lights, camera (leaf modules)
//!                            v                v
//!                 sppm::Renderer::run_pass(i) -> per-pixel estimates at lambda_i
//!                            v
//!                 film::Film (sums over passes) -> frame_NNNN.exr
//!                            ^
//!        frames (drives passes and frames) <- cli (arguments) / bench
//! ```
#![warn(missing_docs)]

pub mod accel;
pub mod bench;
pub mod camera;
pub mod cli;
pub mod error;
pub mod film;
pub mod frames;
pub mod geometry;
pub mod info;
pub mod lights;
pub mod materials;
pub mod monitor;
pub mod plot;
pub mod progress;
pub mod sampling;
pub mod scene;
pub mod spectrum;
pub mod sppm;
