//! Stochastic progressive photon mapping (Hachisuka & Jensen 2009, with Knaus & Zwicker's radius
//! sequence): a pass traces an eye path per pixel to its first diffuse or rough vertex (the
//! visible point), photons from the lights, and gathers the photons within the pass radius of
//! each visible point.

pub(crate) mod beams;
pub(crate) mod direct;
pub(crate) mod gather;
pub(crate) mod pass;
pub(crate) mod photon_sampling;
pub(crate) mod photons;
mod reuse;
pub(crate) mod visible;
