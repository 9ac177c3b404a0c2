//! Light transport: one pass of either method (docs/design.md, steps 1 to 4), and what both use.
//!
//! Takes the scene, its BVH and the settings; [`Renderer::run_pass`] gives every pixel's
//! estimate for pass `i`, which depends only on (scene, settings, seed, i): passes are
//! independent (Knaus & Zwicker 2011), so any pass range can be rendered anywhere and summed.
//!
//! - [`sppm`]: stochastic progressive photon mapping, a gather at each pixel's visible point;
//! - [`vcm`]: vertex connection and merging (Georgiev et al. 2012), merging and connections
//!   weighed by multiple importance sampling;
//! - what both use: the per-pass context ([`Renderer`], `context.rs`), the start of eye paths
//!   (`eye.rs`) and of light paths (`emission.rs`), the kernel and its walls (`kernel.rs`), the
//!   photon grid (`grid.rs`), the radius sequence (`radius.rs`), media (`media.rs`,
//!   `free_flight.rs`, `medium_light.rs`), shadow rays (`shadow.rs`, through alpha: `see_through.rs`);
//! - reuse across frames (`reuse.rs`, Weiss & Grosch's DSPPM): paths on static geometry traced
//!   once for a block of frames.

mod context;
mod emission;
mod eye;
mod footprint;
mod free_flight;
mod grid;
mod guides;
mod kernel;
mod media;
mod medium_light;
mod method;
mod points;
pub mod radius;
mod reuse;
mod see_through;
mod shadow;
mod sppm;
mod vcm;

pub use context::{
    Crop, LightSampling, PassSamples, PassSettings, PassStats, PhotonSampling, PixelEstimate, Renderer,
    VisiblePoint, MAX_DEPTH,
};
pub use footprint::ViewMeasure;
pub use guides::Guide;
pub use method::{Capabilities, Method};
pub use reuse::{run_shared_pass, FrameEstimates, SharedPassOutput};
pub use sppm::photon_sampling::AUTO_VISIBLE_BELOW;
pub use sppm::photons::Photon;
