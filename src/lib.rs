//! Caustic: spectral stochastic progressive photon mapping.
pub mod accel;
pub mod camera;
pub mod lights;
pub mod materials;
pub mod sampling;
pub mod spectrum;
