//! One SPPM pass (DESIGN.md steps 1 to 4): pass samples, visible points, photons, gather.
//!
//! Takes the scene, its BVH and the settings; [`Renderer::run_pass`] gives every pixel's
//! estimate for pass `i`, which depends only on (scene, settings, seed, i): passes are
//! independent (Knaus & Zwicker 2011), so any pass range can be rendered anywhere and summed.

mod beams;
mod direct;
mod footprint;
mod free_flight;
mod gather;
mod grid;
mod guides;
mod media;
mod medium_light;
mod pass;
mod photon_sampling;
mod photons;
mod points;
pub mod radius;
mod renderer;
mod see_through;
mod shared;
mod vcm;
mod visible;

pub use footprint::ViewMeasure;
pub use guides::Guide;
pub use photon_sampling::AUTO_VISIBLE_BELOW;
pub use photons::Photon;
pub use renderer::{
    Crop, LightSampling, Method, PassSamples, PassStats, PhotonSampling, PixelEstimate, Renderer,
    SppmSettings, VisiblePoint, MAX_DEPTH,
};
pub use shared::{run_shared_pass, FrameEstimates, SharedPassOutput};
pub use vcm::unsupported as vcm_unsupported;
