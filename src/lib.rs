//! Caustic: spectral stochastic progressive photon mapping for animated glTF shots.
//!
//! Data flows one way, one module per stage:
//!
//! ```text
//! glTF + extras --scene--> Description --pose--> Prepared (fixed part, once per frame range)
//!                                                    | pose(time) per pass when things move
//!                                                    v
//!        spectrum, sampling, geometry, texture, Scene --accel--> BVHs (fixed + moving)
//!        materials, lights, camera (leaves)          |
//!                                                    v
//!            transport::Renderer::run_pass(i) -> per-pixel estimates at lambda_i, time_i
//!                     (transport::sppm's gather, or transport::vcm's connections and merging,
//!                      over what both share: eye-path start, emission, kernel, grid, media)
//!            transport::run_shared_pass(i) -> the same for a block of frames, sharing the
//!                                             paths on static triangles (reuse, DSPPM)
//!                                                    v
//!                 film::Film (sums over passes) -> error (bounds) -> monitor (log, stop)
//!                                                    v
//!        render (drives frames and passes, writes frame_NNNN.exr) <- cli / info / bench
//!        plot (reads --log files), progress (bar or JSON lines), memory (peak heap)
//! ```
#![warn(missing_docs)]

pub mod accel;
pub mod bench;
pub mod camera;
pub mod cli;
pub mod error;
pub mod film;
pub mod geometry;
pub mod info;
pub mod lights;
pub mod materials;
pub mod memory;
pub mod monitor;
pub mod output;
pub mod plot;
pub mod progress;
pub mod render;
pub mod sampling;
pub mod scene;
pub mod spectrum;
pub mod texture;
pub mod transport;
