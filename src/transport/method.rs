//! The two transport methods, and what each can do, in one table ([`Capabilities`]).

use crate::scene::{media_scatter, Scene};

/// How a pass combines camera paths and light paths into its estimate.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Method {
    /// Stochastic progressive photon mapping: photons gathered at each pixel's first vertex that
    /// is not a delta or glossy lobe.
    #[default]
    Sppm,
    /// Vertex connection and merging: photon merging where SPPM gathers and at glossy vertices
    /// before, combined with connections, light tracing and path tracing by multiple importance
    /// sampling.
    Vcm,
}

/// What a method can do: every choice that depends on the method reads this table.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Capabilities {
    /// Knaus & Zwicker's alpha where none is given. SPPM's is their 2/3, which balances the
    /// gather's variance and bias. Merging carries less of VCM's image and shrinks more slowly
    /// with 0.8 (Georgiev et al.'s implementation uses 0.75; measured in docs/benchmarks.md).
    pub default_alpha: f64,
    /// Whether the frames of a block share the paths on static geometry (reuse across frames).
    pub reuses_across_frames: bool,
    /// Whether it renders media that scatter (volume scattering, fog).
    pub renders_scattering_media: bool,
    /// Whether its light paths can follow what the camera sees (`--photon-sampling visible`).
    pub samples_photons_by_visibility: bool,
}

impl Method {
    /// What it can do.
    pub const fn capabilities(self) -> Capabilities {
        match self {
            Method::Sppm => Capabilities {
                default_alpha: 2.0 / 3.0,
                reuses_across_frames: true,
                renders_scattering_media: true,
                samples_photons_by_visibility: true,
            },
            Method::Vcm => Capabilities {
                default_alpha: 0.8,
                reuses_across_frames: true,
                renders_scattering_media: false,
                samples_photons_by_visibility: false,
            },
        }
    }

    /// Knaus & Zwicker's alpha where none is given.
    pub fn default_alpha(self) -> f64 {
        self.capabilities().default_alpha
    }

    /// What of `scene` it does not render, named (`None`: it renders all of it).
    pub fn unsupported(self, scene: &Scene) -> Option<String> {
        let scatters = media_scatter(&scene.materials, &scene.fog);
        (scatters && !self.capabilities().renders_scattering_media)
            .then(|| "media that scatter (volume scattering or fog)".into())
    }

    /// Its name on the command line.
    pub fn flag(self) -> &'static str {
        match self {
            Method::Sppm => "sppm",
            Method::Vcm => "vcm",
        }
    }
}
