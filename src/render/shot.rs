//! The shot: the scene loaded and prepared once for its frames, and `render`, which takes it
//! through its frames span by span.

use std::sync::Arc;

use super::partial;
use super::settings::{
    check_resolution, crop, default_radius, fingerprint, is_animated, lens_settings, photon_sampling,
    resolution, seconds, shutter, time_range, RenderSettings,
};
use crate::accel::{Accel, BuildFor, Bvh, InstancedBvh};
use crate::sampling::pass_time_sample;
use crate::scene::description::{Lens, Shutter};
use crate::scene::pose::{lens, Motion};
use crate::scene::{Description, Prepared, Scene, TimeRange};
use crate::transport::PhotonSampling;

use crate::transport::{PassSettings, Renderer, ViewMeasure};

/// A render of one scene over its frames: the prepared time range and what every frame shares.
pub struct Shot {
    pub(super) prepared: Prepared,
    pub(super) fixed_bvh: Arc<Bvh>,
    /// The still instances' two-level BVH (built once), if any.
    pub(super) instanced_bvh: Option<Arc<InstancedBvh>>,
    pub(super) still: Option<(Scene, Accel)>,
    pub(super) shutter: Shutter,
    pub(super) pass_settings: PassSettings,
    /// For partial results: the scene's SHA-256 and the settings that shape every pass.
    pub(super) identity: Option<(String, serde_json::Value)>,
    /// The view the first radius was measured from.
    pub(super) view: Option<ViewMeasure>,
}

impl Shot {
    /// Prepares `description` for the frames and settings of `settings`.
    pub fn new(settings: &RenderSettings, description: Arc<Description>) -> Result<Self, String> {
        let [full_width, full_height] = resolution(settings, &description);
        check_resolution([full_width, full_height])?;
        let crop = crop(settings.crop, [full_width, full_height])?;
        let [width, height] = crop.size;
        let shutter = shutter(settings, &description);
        let range = time_range(&settings.frames, shutter, description.fps);
        let photon_sampling = photon_sampling(settings, &description);
        let lens_settings = lens_settings(settings, &description);
        if let Some(l) = lens_settings.filter(|l| l.fstop > 0.0 && !(l.focus_distance > 0.0)) {
            return Err(format!(
                "depth of field (f-stop {}) needs a positive focus distance, got {} (set --focus-distance or the camera's)",
                l.fstop, l.focus_distance
            ));
        }
        let lens = lens(lens_settings, description.camera.focal_length_mm);
        let prepared = Prepared::with_lens(description, range, lens);
        let fixed_bvh = Arc::new(prepared.fixed_bvh());
        let instanced_bvh = prepared.instanced_bvh();
        let first = prepared.pose(range.start);
        let photons_per_pass = settings.photons.unwrap_or((full_width * full_height) as usize);
        let pass_settings = PassSettings {
            width,
            height,
            crop,
            photons_per_pass,
            alpha: settings.alpha.unwrap_or(settings.method.default_alpha()),
            // Measured from the view below when not given.
            initial_radius: settings.radius.unwrap_or(0.0),
            seed: settings.seed,
            fixed_wavelength_nm: settings.wavelength_nm,
            light_sampling: settings.light_sampling,
            photon_sampling,
            method: settings.method,
        };
        if let Some(what) = settings.method.unsupported(&first) {
            return Err(format!(
                "--method {} does not render {what} yet; render this scene with --method sppm",
                settings.method.flag()
            ));
        }
        let still_accel =
            || Accel::new(Arc::clone(&fixed_bvh), Bvh::empty()).with_instances(instanced_bvh.clone());
        let still = (!prepared.has_motion()).then(|| (first, still_accel()));
        let mut shot = Shot {
            prepared,
            fixed_bvh,
            instanced_bvh,
            still,
            shutter,
            pass_settings,
            identity: None,
            view: None,
        };
        shot.settle_from_view(lens, settings.radius.is_none());
        if settings.partial_passes.is_some() {
            let fingerprint = fingerprint(&shot.pass_settings, shutter, &shot.prepared, settings);
            shot.identity = Some((partial::scene_sha256(&settings.scene)?, fingerprint));
        }
        Ok(shot)
    }

    /// Settles what is measured on the scene's view: the first radius when `default_radius`
    /// (none was given), then whether `auto` photon sampling needs chains at all (where pass 0's
    /// pilot finds a quarter of its paths seen or more, every pass is uniform, and pays nothing
    /// for a pilot). An animated scene's view is measured at frame 1 (Blender's first), prepared
    /// for that instant alone: every frame range, a farm task's or a whole shot's, gets the same
    /// radius.
    pub(super) fn settle_from_view(&mut self, lens: Option<Lens>, default_radius: bool) {
        let description = Arc::clone(&self.prepared.description);
        if default_radius {
            let measure = |scene: &Scene, accel: &Accel| {
                let view = Renderer::new(scene, accel, self.pass_settings.clone()).measure_view();
                (view, self::default_radius(scene, view, self.pass_settings.photons_per_pass))
            };
            let (view, radius) = match &self.still {
                Some((scene, accel)) if !is_animated(&description) => measure(scene, accel),
                _ => {
                    let time = seconds(1.0 + self.shutter.open, description.fps);
                    let instant =
                        Prepared::with_lens(description, TimeRange { start: time, end: time }, lens);
                    let accel = Accel::new(Arc::new(instant.fixed_bvh()), Bvh::empty())
                        .with_instances(instant.instanced_bvh());
                    measure(&instant.pose(time), &accel)
                }
            };
            (self.view, self.pass_settings.initial_radius) = (view, radius);
        }
        let mostly_seen = match (&self.still, self.pass_settings.photon_sampling) {
            (Some((scene, accel)), PhotonSampling::Auto) => {
                Renderer::new(scene, accel, self.pass_settings.clone()).auto_at_load().1
            }
            _ => false,
        };
        if mostly_seen {
            self.pass_settings.photon_sampling = PhotonSampling::Uniform;
        }
    }

    /// The view the first radius was measured from (`None` where the radius was given or the
    /// camera sees no surface).
    pub fn view(&self) -> Option<ViewMeasure> {
        self.view
    }

    /// The SPPM settings every pass uses.
    pub fn pass_settings(&self) -> &PassSettings {
        &self.pass_settings
    }

    /// The shutter.
    pub fn shutter(&self) -> Shutter {
        self.shutter
    }

    /// The prepared scene (what moves, the lens).
    pub fn prepared(&self) -> &Prepared {
        &self.prepared
    }

    /// The scene and its BVHs at `time`.
    pub fn pose(&self, time: f32) -> (Scene, Accel) {
        let scene = self.prepared.pose(time);
        let moving = scene.moving.bvh(&scene.materials, BuildFor::Pose);
        let accel =
            Accel::new(Arc::clone(&self.fixed_bvh), moving).with_instances(self.instanced_bvh.clone());
        (scene, accel)
    }

    /// The fixed part's BVH alone (what paths shared between frames are traced against).
    pub(super) fn fixed_accel(&self) -> Accel {
        Accel::new(Arc::clone(&self.fixed_bvh), Bvh::empty()).with_instances(self.instanced_bvh.clone())
    }

    /// The pose `frame` renders pass `pass` in (its `own` when it has one for all its passes);
    /// counts the poses made.
    pub(super) fn posed<'a>(
        &'a self,
        frame: i32,
        own: &'a Option<(Scene, Accel)>,
        pass: u64,
        poses: &mut u64,
    ) -> Posed<'a> {
        match (&self.still, own) {
            (Some((scene, accel)), _) | (None, Some((scene, accel))) => Posed::Borrowed(scene, accel),
            (None, None) => {
                *poses += 1;
                let (scene, accel) = self.pose(self.pass_time(frame, pass));
                Posed::Owned(scene, accel)
            }
        }
    }

    /// The time of pass `index` of `frame`: one point of the shutter, the same for every frame.
    pub(super) fn pass_time(&self, frame: i32, index: u64) -> f32 {
        let offset =
            self.shutter.open + pass_time_sample(self.pass_settings.seed, index) * self.shutter.length;
        seconds(frame as f32 + offset, self.prepared.description.fps)
    }
}

/// `frames` split, in order, into spans over which the same things move. A span's time is cut
/// into pieces: its first frame's shutter, then for each next frame the time from the frame
/// before's shutter closing to its own closing. A frame joins the span before it when its piece
/// changes what the span's pieces change (a shutter of no length changes nothing and agrees with
/// anything). So an object that moves only between frames 10 and 12 of 1 to 24 makes spans 1-10,
/// 11-12 and 13-24, and is static geometry in the first and the last.
pub fn motion_spans(description: &Description, frames: &[i32], shutter: Shutter) -> Vec<Vec<i32>> {
    let fps = description.fps;
    let close = |frame: i32| seconds(frame as f32 + shutter.open + shutter.length, fps);
    let mut spans: Vec<(Vec<i32>, Option<Motion>)> = Vec::new();
    for &frame in frames {
        if let Some((span, moving)) = spans.last_mut() {
            let (a, b) = (close(span[span.len() - 1]), close(frame));
            let piece = Motion::within(description, TimeRange { start: a.min(b), end: a.max(b) });
            if moving.as_ref().is_none_or(|m| *m == piece) {
                span.push(frame);
                *moving = Some(piece);
                continue;
            }
        }
        let own = (shutter.length > 0.0)
            .then(|| Motion::within(description, time_range(&[frame], shutter, description.fps)));
        spans.push((vec![frame], own));
    }
    spans.into_iter().map(|(span, _)| span).collect()
}

/// A pose to render a pass in: the shot's still one, a frame's own, or one made for the pass.
pub(super) enum Posed<'a> {
    Borrowed(&'a Scene, &'a Accel),
    Owned(Scene, Accel),
}

impl Posed<'_> {
    pub(super) fn parts(&self) -> (&Scene, &Accel) {
        match self {
            Posed::Borrowed(scene, accel) => (scene, accel),
            Posed::Owned(scene, accel) => (scene, accel),
        }
    }
}
