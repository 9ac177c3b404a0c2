//! Materials (what the glTF file says) and BSDFs (a material resolved at a path's wavelengths).
//!
//! A [`Material`] (`material.rs`) holds the glTF metallic-roughness parameters with spectra and
//! textures ([`crate::texture`]); [`Material::bsdf`] resolves it at a surface point's inputs
//! (`inputs.rs`: texture coordinates, vertex colour, tangent) and the pass's wavelengths into a
//! closed [`Bsdf`] with a value per wavelength (directions and indices follow the hero
//! wavelength). One lobe or layer per file: `diffuse.rs`, `conductor.rs`, `dielectric.rs`,
//! `plastic.rs` (the specular layer over the base, with `layer_albedo.rs`), `rough_dielectric.rs`
//! (with `dielectric_albedo.rs`), `rough_thin_dielectric.rs`,
//! over the GGX distribution in `microfacet.rs`; `volume.rs` is the medium that fills transmissive
//! materials or the world, and `phase.rs` its scattering; `normal_map.rs` bends the shading normal and shadows the bend.
//!
//! Directions are world-space unit vectors; `wo` and `wi` both point away from the surface.

mod clearcoat;
mod conductor;
mod dielectric;
mod dielectric_albedo;
mod diffuse;
mod inputs;
mod layer_albedo;
mod layering;
mod material;
mod microfacet;
mod normal_map;
pub mod phase;
mod plastic;
mod rough_dielectric;
mod rough_thin_dielectric;
mod sheen;
mod spread;
mod volume;

use glam::{Vec2, Vec3, Vec3A, Vec4};

use crate::spectrum::SampledSpectrum;

pub use clearcoat::{Clearcoat, COAT_IOR};
pub use dielectric::fresnel_dielectric;
pub use inputs::{vertex_colour, SurfaceInputs};
pub use layer_albedo::{eta_of_f0, f0_of_eta};
pub use material::{Alpha, BaseColour, Coverage, Lobe, Material, Specular, SMOOTH_ROUGHNESS};
pub use normal_map::NormalMap;
pub use plastic::{Coat, Plastic};
pub use rough_dielectric::RoughDielectric;
pub use rough_thin_dielectric::RoughThinDielectric;
pub use sheen::Sheen;
pub use spread::Spread;
pub use volume::{transmittance, Volume};

/// Specular layers narrower than this GGX alpha (roughness 0.316) are not gathered at: eye paths
/// take direct light there and sample on through the layer's own reflection, as through a mirror,
/// or gather under it ([`Bsdf::is_gathered_at`]; metals are never gathered at, whatever their
/// roughness: `transport/sppm/visible.rs` says why).
pub const NARROW_COAT_ALPHA: f32 = 0.1;

/// A BSDF at a path's wavelengths: reflectances per wavelength, indices at the hero's.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Bsdf {
    /// Lambertian reflection of albedo in [0, 1].
    Diffuse {
        /// Albedo at each wavelength.
        albedo: SampledSpectrum,
    },
    /// A perfect mirror reflecting `weight` (chosen with its weight fixed: a smooth coat's).
    Mirror {
        /// The reflected share at each wavelength, over the probability of choosing the mirror.
        weight: SampledSpectrum,
    },
    /// A GGX dielectric layer over a Lambertian base (glTF's non-metal BRDF), or the base alone
    /// under a smooth layer: a [`Plastic`] with its coat's fields in the variant, which keeps the
    /// enum at 48 bytes (a nested struct would start at the next 16 bytes after the tag, making it
    /// 64, and a visible point larger than 144 bytes).
    Plastic {
        /// The base's albedo at each wavelength.
        base: SampledSpectrum,
        /// The coat's normal-incidence reflectance.
        f0: SampledSpectrum,
        /// The coat's index.
        eta: f32,
        /// The coat's GGX alpha (0 for a smooth coat).
        alpha: f32,
    },
    /// A perfect mirror with Schlick's Fresnel from `f0`.
    Conductor {
        /// Normal-incidence reflectance.
        f0: SampledSpectrum,
    },
    /// GGX microfacet reflection with Schlick's Fresnel.
    RoughConductor {
        /// Normal-incidence reflectance.
        f0: SampledSpectrum,
        /// GGX alpha (roughness squared).
        alpha: f32,
        /// The multiple-scattering compensation for the direction it was resolved for
        /// ([`conductor::multiple_scattering`]).
        scale: SampledSpectrum,
    },
    /// A smooth dielectric boundary: Fresnel reflection and refraction with total internal reflection.
    Dielectric {
        /// Index of refraction of the inside relative to the outside.
        ior: f32,
        /// What refraction transmits at each wavelength (the square root of the base colour: a
        /// closed mesh's two boundaries tint light by the base colour, as in Cycles).
        tint: SampledSpectrum,
    },
    /// A rough dielectric boundary: GGX reflection and refraction ([`RoughDielectric`]).
    RoughDielectric {
        /// Index of refraction of the inside relative to the outside.
        ior: f32,
        /// GGX alpha (roughness squared).
        alpha: f32,
        /// What refraction transmits at each wavelength, as for [`Bsdf::Dielectric`].
        tint: SampledSpectrum,
    },
    /// A thin dielectric wall: Fresnel reflection (with the wall's inner reflections summed) or
    /// straight transmission, never bent.
    ThinDielectric {
        /// Index of refraction of the wall.
        ior: f32,
        /// What passing through the wall transmits at each wavelength (the base colour).
        tint: SampledSpectrum,
        /// What its inside absorbs across it: the absorption coefficient times the thickness, at
        /// each wavelength (zero for a clear wall).
        depth: SampledSpectrum,
    },
    /// A rough thin dielectric wall: GGX reflection and straight-through transmission spread by
    /// the microfacets ([`RoughThinDielectric`]).
    RoughThinDielectric {
        /// Index of refraction of the wall.
        ior: f32,
        /// GGX alpha (roughness squared).
        alpha: f32,
        /// What passing through the wall transmits at each wavelength (the base colour).
        tint: SampledSpectrum,
        /// What its inside absorbs across it, as for [`Bsdf::ThinDielectric`].
        depth: SampledSpectrum,
    },
    /// A sheen's fibres (Zeltner et al.'s microfiber sheen, as Cycles renders it).
    Sheen {
        /// Its colour at each wavelength, in [0, 1].
        colour: SampledSpectrum,
        /// Its roughness.
        roughness: f32,
    },
    /// Scattering in a medium, at a point inside it rather than on a surface: the medium's
    /// scattering coefficient times its Henyey–Greenstein phase function (`phase.rs`).
    Medium {
        /// The scattering coefficient at each wavelength, per world unit.
        scattering: SampledSpectrum,
        /// Henyey–Greenstein's `g`.
        anisotropy: f32,
    },
    /// Absorbs everything (a light's own surface).
    Black,
    /// Not there: light goes on unchanged (where alpha cuts the surface away).
    PassThrough,
}

/// What a path carries: radiance (camera paths) or importance (photons). Only refraction cares.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Transport {
    /// Camera paths, gathering radiance.
    Radiance,
    /// Photon paths, carrying flux.
    Importance,
}

/// A direction sampled from a BSDF.
#[derive(Clone, Copy, Debug)]
pub struct BsdfSample {
    /// The new direction, away from the surface.
    pub wi: Vec3,
    /// `f * |cos| / pdf`: the factor the path throughput is multiplied by.
    pub weight: SampledSpectrum,
    /// The density of `wi` per solid angle (meaningless for delta lobes).
    pub pdf: f32,
    /// Whether the sample came from a delta lobe.
    pub is_delta: bool,
}

impl Bsdf {
    /// Whether every direction it scatters into is a delta (mirror or refraction).
    pub fn is_delta(&self) -> bool {
        matches!(
            self,
            Bsdf::Mirror { .. }
                | Bsdf::Conductor { .. }
                | Bsdf::Dielectric { .. }
                | Bsdf::ThinDielectric { .. }
                | Bsdf::PassThrough
        )
    }

    /// Whether photons are gathered at it: neither a delta lobe, nor a metal's GGX lobe, nor a
    /// specular layer's own reflection below [`NARROW_COAT_ALPHA`], through which a density
    /// estimate would see few photons each weighed by a tall peak, as speckle.
    pub fn is_gathered_at(&self) -> bool {
        match *self {
            Bsdf::RoughConductor { .. } | Bsdf::RoughDielectric { .. } | Bsdf::RoughThinDielectric { .. } => {
                false
            }
            Bsdf::Plastic { base, alpha, .. } => base != Vec4::ZERO || alpha >= NARROW_COAT_ALPHA,
            _ => !self.is_delta(),
        }
    }

    /// Whether some of its non-delta light crosses the surface (a rough dielectric's refraction):
    /// direct light from the far side counts. For the others it is a leak through the surface,
    /// which a shading normal tilted from the geometric one would let through.
    pub fn transmits(&self) -> bool {
        matches!(self, Bsdf::RoughDielectric { .. } | Bsdf::RoughThinDielectric { .. } | Bsdf::Medium { .. })
    }

    /// Whether light arriving from `wo` at a surface of geometric normal `ng` can leave toward
    /// `w`: on `wo`'s side, unless it transmits (a shading normal tilted from the geometric one
    /// would otherwise leak light through the surface).
    pub fn leaves_toward(&self, ng: Vec3, wo: Vec3, w: Vec3) -> bool {
        self.transmits() || ng.dot(w) * ng.dot(wo) > 0.0
    }

    /// Whether [`Bsdf::sample`] reads its `u_lobe` (a dielectric's choice between reflection and
    /// refraction); paths draw that number only then.
    fn picks_lobe(&self) -> bool {
        match self {
            Bsdf::Dielectric { .. }
            | Bsdf::ThinDielectric { .. }
            | Bsdf::RoughDielectric { .. }
            | Bsdf::RoughThinDielectric { .. } => true,
            Bsdf::Plastic { alpha, .. } => *alpha > 0.0,
            _ => false,
        }
    }

    /// A uniform number for [`Bsdf::sample`]'s `u_lobe` from `draw`, drawn only when read.
    pub fn lobe_number(&self, draw: impl FnOnce() -> f32) -> f32 {
        if self.picks_lobe() {
            draw()
        } else {
            0.0
        }
    }

    /// The BSDF value `f(wo, wi)` (zero for delta lobes) in `frame`, light arriving from `wi`.
    pub fn eval(&self, frame: ShadingFrame, wo: Vec3, wi: Vec3) -> SampledSpectrum {
        let n = frame.toward(wo);
        match *self {
            Bsdf::Diffuse { albedo } => diffuse::eval(albedo, frame, wo, wi),
            Bsdf::RoughConductor { f0, alpha, scale } => conductor::eval_rough(f0, alpha, n, wo, wi) * scale,
            Bsdf::Plastic { base, f0, eta, alpha } => Plastic::new(base, f0, eta, alpha).eval(frame, wo, wi),
            Bsdf::Sheen { colour, roughness } => sheen::eval(colour, roughness, n, wo, wi),
            Bsdf::RoughDielectric { ior, alpha, tint } => {
                RoughDielectric { ior, alpha, tint }.eval(frame, wo, wi)
            }
            Bsdf::RoughThinDielectric { ior, alpha, tint, depth } => {
                RoughThinDielectric { ior, alpha, tint, depth }.eval(frame, wo, wi)
            }
            Bsdf::Medium { scattering, anisotropy } => scattering * phase::eval(anisotropy, wo, wi),
            _ => Vec4::ZERO,
        }
    }

    /// The density per solid angle with which [`Bsdf::sample`] picks `wi` (zero for delta lobes).
    pub fn pdf(&self, frame: ShadingFrame, wo: Vec3, wi: Vec3) -> f32 {
        let n = frame.toward(wo);
        match *self {
            Bsdf::Diffuse { .. } => diffuse::pdf(n, wi),
            Bsdf::RoughConductor { alpha, .. } => conductor::pdf_rough(alpha, n, wo, wi),
            Bsdf::Plastic { base, f0, eta, alpha } => Plastic::new(base, f0, eta, alpha).pdf(frame, wo, wi),
            Bsdf::Sheen { roughness, .. } => sheen::pdf(roughness, n, wo, wi),
            Bsdf::RoughDielectric { ior, alpha, tint } => {
                RoughDielectric { ior, alpha, tint }.pdf(frame, wo, wi)
            }
            Bsdf::RoughThinDielectric { ior, alpha, tint, depth } => {
                RoughThinDielectric { ior, alpha, tint, depth }.pdf(frame, wo, wi)
            }
            Bsdf::Medium { anisotropy, .. } => phase::eval(anisotropy, wo, wi),
            _ => 0.0,
        }
    }

    /// Samples `wi` for `wo` in `frame`, for `mode`'s direction of travel.
    pub fn sample(
        &self,
        frame: ShadingFrame,
        wo: Vec3,
        u: Vec2,
        u_lobe: f32,
        mode: Transport,
    ) -> Option<BsdfSample> {
        let n = frame.n();
        match *self {
            Bsdf::Diffuse { albedo } => diffuse::sample(albedo, frame, wo, u, mode),
            Bsdf::Mirror { weight } => conductor::sample_mirror(weight, n, wo),
            Bsdf::Plastic { base, f0, eta, alpha } => {
                Plastic::new(base, f0, eta, alpha).sample(frame, wo, u, u_lobe, mode)
            }
            Bsdf::Conductor { f0 } => conductor::sample_smooth(f0, n, wo),
            Bsdf::RoughConductor { f0, alpha, scale } => conductor::sample_rough(f0, alpha, n, wo, u)
                .map(|s| BsdfSample { weight: s.weight * scale, ..s }),
            Bsdf::Dielectric { ior, tint } => dielectric::sample(ior, tint, frame, wo, u_lobe, mode),
            Bsdf::RoughDielectric { ior, alpha, tint } => {
                RoughDielectric { ior, alpha, tint }.sample(frame, wo, u, u_lobe, mode)
            }
            Bsdf::RoughThinDielectric { ior, alpha, tint, depth } => {
                RoughThinDielectric { ior, alpha, tint, depth }.sample(frame, wo, u, u_lobe)
            }
            Bsdf::ThinDielectric { ior, tint, depth } => {
                dielectric::sample_thin(ior, tint, depth, frame, wo, u_lobe)
            }
            Bsdf::Sheen { colour, roughness } => sheen::sample(colour, roughness, n, wo, u),
            Bsdf::Medium { scattering, anisotropy } => {
                let wi = phase::sample(anisotropy, wo, u);
                Some(BsdfSample {
                    wi,
                    weight: scattering,
                    pdf: phase::eval(anisotropy, wo, wi),
                    is_delta: false,
                })
            }
            Bsdf::Black => None,
            Bsdf::PassThrough => Some(BsdfSample { wi: -wo, weight: Vec4::ONE, pdf: 0.0, is_delta: true }),
        }
    }
}

/// The normals at a surface point: shading (interpolated, then bent by a normal map), geometric
/// (the triangle's) and smooth (interpolated). Held 16-byte aligned: a frame is written whole
/// and read whole at every hit, and 12-byte fields written apart and read as 16-byte words stall
/// the store buffer (measured: 9% of a photon path's time at the copy).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadingFrame {
    /// Shading normal.
    n: Vec3A,
    /// Geometric normal, pointing to the outside of the mesh.
    ng: Vec3A,
    /// The interpolated normal a normal map bent `n` from (`n` itself without one).
    smooth: Vec3A,
}

impl ShadingFrame {
    /// The frame of interpolated normal `n` on a face of normal `ng`, no normal map.
    pub const fn new(n: Vec3, ng: Vec3) -> Self {
        let n = Vec3A::new(n.x, n.y, n.z);
        ShadingFrame { n, ng: Vec3A::new(ng.x, ng.y, ng.z), smooth: n }
    }

    /// The frame of `smooth` bent to `n` by a normal map, on a face of normal `ng`.
    pub fn bent(n: Vec3, ng: Vec3, smooth: Vec3) -> Self {
        ShadingFrame { n: n.into(), ng: ng.into(), smooth: smooth.into() }
    }

    /// The shading normal.
    #[inline]
    pub fn n(&self) -> Vec3 {
        self.n.into()
    }

    /// The geometric normal, pointing to the outside of the mesh.
    #[inline]
    pub fn ng(&self) -> Vec3 {
        self.ng.into()
    }

    /// The interpolated normal a normal map bent the shading normal from.
    #[inline]
    pub fn smooth(&self) -> Vec3 {
        self.smooth.into()
    }

    /// Whether a normal map bent the shading normal.
    #[inline]
    pub fn is_bent(&self) -> bool {
        self.smooth != self.n
    }

    /// The shading normal turned to the side of the smooth normal that `w` is on (`n` turned
    /// toward `w` without a normal map: see `normal_map.rs`).
    #[inline]
    pub fn toward(&self, w: Vec3) -> Vec3 {
        if self.smooth().dot(w) < 0.0 {
            -self.n()
        } else {
            self.n()
        }
    }

    /// The frame whose shading normal glossy lobes take seen from `wo`: this one without a
    /// normal map, else the bent normal tilted back as far as the mirror image of `wo` needs to
    /// leave the surface ([`normal_map::valid_reflection`]).
    pub fn for_glossy(&self, wo: Vec3) -> Self {
        if !self.is_bent() {
            return *self;
        }
        let n = self.toward(wo);
        let valid = normal_map::valid_reflection(n, face_toward(self.ng(), wo), wo);
        if valid == n {
            return *self;
        }
        let n = if self.smooth().dot(wo) < 0.0 { -valid } else { valid };
        ShadingFrame::bent(n, self.ng(), self.smooth())
    }

    /// The factor on diffuse light arriving from `wi`: 1 without a normal map, else its
    /// shadowing ([`normal_map::shadowing`]).
    #[inline]
    pub fn diffuse_shadowing(&self, wi: Vec3) -> f32 {
        if self.is_bent() {
            normal_map::shadowing(self.smooth(), self.n(), wi)
        } else {
            1.0
        }
    }

    /// For a photon arriving from `wi` at a surface with a bent normal, the bent cosine over the
    /// geometric one its density carries (1 without a normal map: see `normal_map.rs`).
    #[inline]
    pub fn photon_cosine_ratio(&self, wi: Vec3) -> f32 {
        if self.is_bent() {
            let geometric = self.ng().dot(wi).abs();
            if geometric > 0.0 {
                self.n().dot(wi).abs() / geometric
            } else {
                0.0
            }
        } else {
            1.0
        }
    }
}

/// `n` flipped, if needed, to the side of `w`.
pub fn face_toward(n: Vec3, w: Vec3) -> Vec3 {
    if n.dot(w) < 0.0 {
        -n
    } else {
        n
    }
}

#[cfg(test)]
mod tests;
