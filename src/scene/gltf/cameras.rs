//! The camera the scene names: its projection (perspective, orthographic, panoramic), lens and
//! shutter.

use crate::scene::values::CameraAnimation;

use super::Builder;
use glam::Vec2;

use crate::camera::Projection;
use crate::scene::description::{CameraInstance, LensSettings, Shutter};
use crate::scene::extras::{self, NodeExtras, ShutterExtras, ShutterPosition};

/// The shutter in frames relative to the frame, from Blender's length and position.
pub(super) fn shutter(extras: Option<&ShutterExtras>) -> Result<Shutter, String> {
    let Some(s) = extras else { return Ok(Shutter::CLOSED) };
    if !(s.length_frames >= 0.0 && s.length_frames.is_finite()) {
        return Err(format!(
            "scene extras `caustic.shutter.length_frames`: expected a length >= 0, got {}",
            s.length_frames
        ));
    }
    let open = match s.position {
        ShutterPosition::Start => 0.0,
        ShutterPosition::Center => -s.length_frames / 2.0,
        ShutterPosition::End => -s.length_frames,
    };
    Ok(Shutter { open, length: s.length_frames })
}

/// An orthographic camera from glTF's half extents: the film's half height is `ymag` (its width
/// follows the image's aspect).
pub(super) fn orthographic_projection(xmag: f32, ymag: f32, name: &str) -> Result<Projection, String> {
    if !(ymag > 0.0 && ymag.is_finite() && xmag > 0.0 && xmag.is_finite()) {
        return Err(format!(
            "camera node '{name}': an orthographic camera needs positive xmag and ymag, got {xmag} and {ymag}"
        ));
    }
    Ok(Projection::Orthographic { half_height: ymag })
}

/// A panorama's projection from its extras, refused where its ranges are empty or beyond the sphere.
pub(super) fn panorama_projection(
    panorama: &extras::PanoramaExtras,
    name: &str,
) -> Result<Projection, String> {
    let [lon0, lon1] = panorama.longitude_deg;
    let [lat0, lat1] = panorama.latitude_deg;
    let valid = lon0 < lon1 && lon1 - lon0 <= 360.0 && -90.0 <= lat0 && lat0 < lat1 && lat1 <= 90.0;
    if !valid {
        return Err(format!(
            "camera node '{name}' extras `caustic.panorama`: expected longitudes from low to high spanning at most \
             360 degrees and latitudes from low to high within [-90, 90], got {:?} and {:?}",
            panorama.longitude_deg, panorama.latitude_deg
        ));
    }
    Ok(Projection::Equirectangular {
        longitude: [lon0.to_radians(), lon1.to_radians()],
        latitude: [lat0.to_radians(), lat1.to_radians()],
    })
}

impl Builder<'_> {
    /// Adds the camera of a node: its glTF camera, or the panorama of its extras (which wins).
    pub(super) fn add_camera(
        &mut self,
        camera: Option<&gltf::Camera>,
        node: usize,
        name: &str,
        extras: &NodeExtras,
    ) -> Result<(), String> {
        match &self.wanted_camera {
            Some(wanted) if wanted != name => return Ok(()),
            None if self.camera.is_some() => {
                self.warnings.push(format!("camera node '{name}' ignored: the first camera is used"));
                return Ok(());
            }
            _ => {}
        }
        let lens = extras.lens.as_ref();
        if let Some(lens) = lens {
            if !(lens.fstop >= 0.0 && lens.focus_distance >= 0.0 && lens.fstop.is_finite()) {
                return Err(format!(
                    "camera node '{name}' extras `caustic.lens`: f-stop and focus distance must be >= 0"
                ));
            }
        }
        let (projection, aspect_ratio) = match (&extras.panorama, camera.map(|c| c.projection())) {
            (Some(panorama), _) => {
                if lens.is_some_and(|l| l.fstop > 0.0) {
                    self.warnings
                        .push(format!("camera node '{name}': depth of field is not rendered on a panorama"));
                }
                (panorama_projection(panorama, name)?, None)
            }
            (None, Some(gltf::camera::Projection::Perspective(p))) => {
                (Projection::Perspective { tan_half_fov_y: (p.yfov() / 2.0).tan() }, p.aspect_ratio())
            }
            (None, Some(gltf::camera::Projection::Orthographic(o))) => {
                (orthographic_projection(o.xmag(), o.ymag(), name)?, Some(o.xmag() / o.ymag()))
            }
            (None, None) => return Err(format!("camera node '{name}' has neither a camera nor a panorama")),
        };
        let shift = extras.shift.map_or(Vec2::ZERO, Vec2::from);
        if !shift.is_finite() {
            return Err(format!(
                "camera node '{name}' extras `caustic.shift`: expected two numbers, got {shift}"
            ));
        }
        // Blender's sensor fit: a 36 mm sensor across the wider side of the image.
        let aspect = aspect_ratio.unwrap_or(1.0).max(1e-6);
        let tan_half_wide = match projection {
            Projection::Perspective { tan_half_fov_y } => tan_half_fov_y * aspect.max(1.0),
            _ => 1.0,
        };
        let focal_length_mm = lens.and_then(|l| l.focal_length_mm).unwrap_or(18.0 / tan_half_wide);
        let tracks = camera.and_then(|c| self.animations.cameras.get(&c.index()));
        let animation = tracks.map(|tracks| Box::new(CameraAnimation { tracks: tracks.clone() }));
        if animation.is_some() && !matches!(projection, Projection::Perspective { .. }) {
            self.warnings.push(format!(
                "camera node '{name}': its animated field of view is rendered for perspective cameras only"
            ));
        }
        self.camera = Some(CameraInstance {
            animation,
            node,
            projection,
            shift,
            aspect_ratio,
            focal_length_mm,
            lens: lens.map(|l| LensSettings {
                fstop: l.fstop,
                focus_distance: l.focus_distance,
                blades: l.blades,
                blade_rotation_deg: l.blade_rotation_deg,
            }),
        });
        Ok(())
    }
}
