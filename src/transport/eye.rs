//! The start of an eye path, which both methods share: the camera ray of a pixel at the pass's
//! time and lens sample, and the state a path carries from segment to segment ([`EyeState`]),
//! which a caller can watch and resume (reuse across frames).

use glam::{Vec2, Vec3, Vec3A};

use crate::geometry::offset_origin;
use crate::materials::Bsdf;
use crate::sampling::{pixel_stream, PixelSampler};
use crate::scene::Surface;
use crate::spectrum::SampledSpectrum;
use crate::transport::context::{PassSamples, PassStats, Renderer};
use crate::transport::media::Media;

/// An eye path about to trace its next segment.
#[derive(Clone)]
pub struct EyeState {
    /// Where the segment starts (16-byte aligned, as is the direction: a state is written
    /// whole and read whole, and 12-byte fields read as 16-byte words stall the store buffer).
    pub origin: Vec3A,
    /// Its unit direction.
    pub direction: Vec3A,
    /// Throughput from the camera.
    pub beta: SampledSpectrum,
    /// The path carries its hero wavelength alone (it passed a dispersive refraction).
    pub hero_only: bool,
    /// The volumes it is in.
    pub media: Media,
    /// Radiance found so far.
    pub radiance: SampledSpectrum,
    /// Segments traced before this one.
    pub depth: u32,
    /// The vertex this segment leaves took direct light: emission it meets is already counted.
    pub lights_sampled: bool,
    /// The path is still the camera's ray: it has passed only surfaces alpha cuts away (what it
    /// meets is seen directly: a holdout, or a transparent film's world, is a hole in the film).
    pub camera_ray: bool,
    /// The path's random stream, where this segment leaves it.
    pub rng: PixelSampler,
}

/// What meeting a surface's lobe does to an eye path.
pub enum Meeting {
    /// The path ends there: a black lobe, or a holdout the camera sees (coverage 0).
    Ends {
        /// The path's coverage of the film.
        coverage: f32,
    },
    /// Alpha cuts the surface away there: the path goes on past it with the sample the last
    /// vertex drew (and took direct light for, if it did).
    PassesThrough,
    /// The path scatters there.
    Scatters,
}

impl EyeState {
    /// Meets the lobe `bsdf` of a surface (a holdout if `holdout`) seen from `wo`: moves the
    /// path past it where alpha cuts it away, and the path is no longer the camera's own ray
    /// where it scatters.
    pub fn meet(&mut self, bsdf: &Bsdf, holdout: bool, surface: &Surface, wo: Vec3) -> Meeting {
        if *bsdf == Bsdf::Black {
            return Meeting::Ends { coverage: 1.0 };
        }
        if *bsdf == Bsdf::PassThrough {
            self.origin = offset_origin(surface.p, surface.frame.ng(), -wo, surface.scale).into();
            self.depth += 1;
            return Meeting::PassesThrough;
        }
        if self.camera_ray && holdout {
            return Meeting::Ends { coverage: 0.0 };
        }
        self.camera_ray = false;
        Meeting::Scatters
    }
}

/// Pixel `pixel`'s camera ray for `pass` (the film sample and, with a lens, the aperture sample).
pub fn start_eye_path(renderer: &Renderer, pass: &PassSamples, pixel: usize) -> (EyeState, PassStats) {
    let settings = &renderer.settings;
    let camera = &renderer.scene.camera;
    let ([x, y], index) = settings.crop.image_pixel(pixel);
    let mut rng = pixel_stream(settings.seed, pass.index, index);
    let [width, height] = settings.crop.image.map(|n| n as f32);
    let film = (Vec2::new(x as f32, y as f32) + rng.next_2d()) / Vec2::new(width, height);
    let mut stats = PassStats::default();
    let aspect = width / height;
    let (origin, direction) = match camera.lens {
        Some(_) => {
            stats.lens_samples += 1;
            camera.ray_through_lens(film, aspect, rng.next_2d())
        }
        None => camera.ray(film, aspect),
    };
    (
        EyeState {
            origin: origin.into(),
            direction: direction.into(),
            beta: SampledSpectrum::ONE,
            hero_only: false,
            media: renderer.camera_media(),
            radiance: SampledSpectrum::ZERO,
            depth: 0,
            lights_sampled: false,
            camera_ray: true,
            rng,
        },
        stats,
    )
}
