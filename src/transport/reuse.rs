//! Reuse across frames (Weiss & Grosch 2012, "Stochastic Progressive Photon Mapping for Dynamic
//! Scenes"; docs/design.md, "Frames, and reuse across frames"): the frames of a block render the
//! same pass (the same wavelengths, shutter point, radius and random streams), so the paths that
//! meet only static triangles are the same in every frame. Each method traces them once, against
//! the static triangles alone, and each frame traces again only what its moving triangles change:
//! SPPM in `sppm/reuse.rs`, VCM in `vcm/reuse.rs`.

use glam::Vec3;

use super::context::{PassSamples, PassStats, PixelEstimate, Renderer};
use super::method::Method;
use super::shadow::ShadowRay;
use crate::geometry::ray_meets_box;

/// The box every frame's moving triangles lie in this pass, grown a little for rounding.
#[derive(Clone, Copy)]
pub(super) struct Swept(pub(super) Option<(Vec3, Vec3)>);

impl Swept {
    /// The box of the moving triangles of every frame of `frames`.
    pub(super) fn of(frames: &[Renderer]) -> Self {
        let union = frames
            .iter()
            .filter_map(|r| r.accel.moving_bounds())
            .reduce(|(a, b), (c, d)| (a.min(c), b.max(d)));
        Swept(union.map(|(lo, hi)| {
            let margin = (hi - lo).length() * 1e-4 + lo.abs().max(hi.abs()).max_element() * 1e-6;
            (lo - Vec3::splat(margin), hi + Vec3::splat(margin))
        }))
    }

    /// Whether the ray could meet a moving triangle in some frame.
    pub(super) fn meets(self, ray: ShadowRay) -> bool {
        self.0.is_some_and(|b| ray_meets_box(ray.origin, ray.direction, ray.t_max, b))
    }
}

/// What [`run_shared_pass`] hands each frame.
pub struct SharedPassOutput<'a> {
    /// The frame's index in the block.
    pub frame: usize,
    /// Its pixel estimates.
    pub estimates: FrameEstimates<'a>,
    /// Tests against its moving triangles and the paths traced again in it.
    pub stats: PassStats,
}

/// A frame's pixel estimates for one pass.
pub enum FrameEstimates<'a> {
    /// Every pixel's, row-major.
    Every(Vec<PixelEstimate>),
    /// Where the frame differs from the block's common estimates. Every other pixel's estimate
    /// is the common one (the same paths, summed in another order).
    Beside {
        /// Every pixel's estimate from the paths shared by every frame (the same slice for every
        /// frame of the pass).
        common: &'a [PixelEstimate],
        /// The frame's own estimates at the pixels where its paths differ, in pixel order.
        differing: Vec<(u32, PixelEstimate)>,
    },
}

/// Renders `pass` for every frame of `frames` (each posed at its own time for this pass, all
/// choosing lights as `statics` does), sharing what they can through `statics`: the same scene
/// with the static triangles alone. `share_eyes` when neither the camera nor a light moves.
/// Hands each frame's estimates to `consume` in frame order; returns the work done once and the
/// time it took (before any frame's own work).
pub fn run_shared_pass(
    statics: &Renderer,
    frames: &[Renderer],
    pass: &PassSamples,
    share_eyes: bool,
    mut consume: impl FnMut(SharedPassOutput),
) -> (PassStats, std::time::Duration) {
    match statics.settings.method {
        Method::Sppm => statics.run_shared_sppm_pass(frames, pass, share_eyes, &mut consume),
        Method::Vcm => statics.run_shared_vcm_pass(frames, pass, share_eyes, &mut consume),
    }
}
