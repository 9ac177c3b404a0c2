//! Materials (what the glTF file says) and BSDFs (a material resolved at a path's wavelengths).
//!
//! A [`Material`] holds the glTF metallic-roughness parameters with spectra; [`Material::bsdf`]
//! resolves it at the pass's wavelengths into a closed [`Bsdf`] with a value per wavelength
//! (directions and indices follow the hero wavelength). Where the
//! glTF material mixes lobes (transmission or metallic between 0 and 1), one lobe is chosen by a
//! random number with its weight as probability, which is unbiased.
//!
//! Directions are world-space unit vectors; `wo` and `wi` both point away from the surface.

mod conductor;
mod dielectric;
mod diffuse;
mod layer_albedo;
mod microfacet;
mod plastic;
mod texture;

use std::sync::Arc;

use glam::{Vec2, Vec3, Vec4};

use crate::spectrum::{Dispersion, RgbSpectrum, SampledSpectrum, Wavelengths};

pub use dielectric::fresnel_dielectric;
pub use layer_albedo::{eta_of_f0, f0_of_eta};
pub use plastic::{Coat, Plastic};
pub use texture::Texture;

/// Roughness below this is treated as perfectly smooth (a delta BSDF).
pub const SMOOTH_ROUGHNESS: f32 = 0.02;

/// A material's base colour: a constant spectrum or a texture (with the factor baked in).
#[derive(Clone, Debug)]
pub enum BaseColour {
    /// The same reflectance everywhere.
    Constant(RgbSpectrum),
    /// A texture looked up at the surface's texture coordinates.
    Texture(Arc<Texture>),
}

/// A surface's material: glTF metallic-roughness with transmission, IOR and emission.
#[derive(Clone, Debug)]
pub struct Material {
    /// The material's name, for messages.
    pub name: String,
    /// Base colour (reflectance, or the conductor's normal-incidence reflectance).
    pub base_colour: BaseColour,
    /// glTF `metallicFactor`.
    pub metallic: f32,
    /// glTF `roughnessFactor` (perceptual; alpha = roughness^2).
    pub roughness: f32,
    /// The specular layer over a non-metal's base (glTF's dielectric BRDF); `None` for a pure
    /// Lambertian base (`KHR_materials_specular` with a factor of 0).
    pub specular: Option<Specular>,
    /// `KHR_materials_transmission` factor.
    pub transmission: f32,
    /// Index of refraction against wavelength: `KHR_materials_ior` (1.5 when absent), with
    /// `KHR_materials_dispersion` or a law from the `caustic` extras.
    pub ior: Dispersion,
    /// Emitted radiance shape (times D65) in W / (m^2 sr), or `None`.
    pub emission: Option<RgbSpectrum>,
    /// Whether emission leaves both faces (meshes) or only the front (area lights).
    pub emits_both_sides: bool,
    /// Transmission through a thin wall (an open mesh: a window pane modelled as a plane) rather
    /// than into a solid: glTF's reading of transmission without a volume.
    pub thin: bool,
}

/// A non-metal's specular layer as the file gives it: `KHR_materials_specular` over the index.
#[derive(Clone, Debug, PartialEq)]
pub struct Specular {
    /// Normal-incidence reflectance at its colour's brightest: the index's, times the specular
    /// factor and the colour's largest component (Blender folds a Specular IOR Level above 0.5
    /// into the colour).
    pub f0: f32,
    /// The colour's hue (its largest component 1), tinting `f0` but not grazing reflection.
    pub tint: RgbSpectrum,
}

impl Specular {
    /// The layer of a material of index `ior` with `KHR_materials_specular`'s factor and colour;
    /// `None` when it reflects nothing (a factor of 0: a pure Lambertian base).
    pub fn new(ior: f32, factor: f32, colour: Vec3) -> Option<Self> {
        let scale = colour.max_element();
        let f0 = (f0_of_eta(ior) * factor * scale).min(0.99);
        (f0 > 0.0).then(|| Specular { f0, tint: RgbSpectrum::reflectance(colour / scale) })
    }

    /// The coat at the wavelengths `lambda` with GGX `alpha` (0: smooth).
    fn coat(&self, lambda: &Wavelengths, alpha: f32) -> Coat {
        Coat::new(self.tint.eval_lanes(lambda.nm) * self.f0, eta_of_f0(self.f0), alpha)
    }
}

impl Material {
    /// A grey Lambertian material, for meshes without one.
    pub fn default_grey() -> Self {
        Material {
            name: "default".into(),
            base_colour: BaseColour::Constant(RgbSpectrum::constant(0.8)),
            metallic: 0.0,
            roughness: 1.0,
            specular: None,
            transmission: 0.0,
            ior: Dispersion::Constant(1.5),
            emission: None,
            emits_both_sides: true,
            thin: false,
        }
    }

    /// The base colour's reflectance at texture coordinate `uv` and the wavelengths `lambda`.
    pub fn reflectance(&self, uv: Vec2, lambda: &Wavelengths) -> SampledSpectrum {
        match &self.base_colour {
            BaseColour::Constant(spectrum) => spectrum.eval_lanes(lambda.nm),
            BaseColour::Texture(texture) => texture.eval(uv, lambda.nm),
        }
    }

    /// The emitted spectral radiance at `lambda` leaving toward `wo` from a face of normal `ng`.
    pub fn emitted(&self, lambda: &Wavelengths, ng: Vec3, wo: Vec3) -> SampledSpectrum {
        match &self.emission {
            Some(spectrum) if self.emits_both_sides || ng.dot(wo) > 0.0 => {
                spectrum.eval_lanes(lambda.nm) * lambda.d65
            }
            _ => Vec4::ZERO,
        }
    }

    /// Whether it refracts each wavelength its own way (a transmissive material whose index
    /// depends on wavelength).
    pub fn is_dispersive(&self) -> bool {
        self.transmission > 0.0 && self.ior.is_dispersive()
    }

    /// Whether `bsdf`, resolved from this material, sends each wavelength its own way: a path
    /// through it can carry only its hero wavelength.
    pub fn separates_wavelengths(&self, bsdf: &Bsdf) -> bool {
        self.ior.is_dispersive() && matches!(bsdf, Bsdf::Dielectric { .. } | Bsdf::ThinDielectric { .. })
    }

    /// Whether light passes through unchanged (a thin fully transmissive wall of index 1, as area
    /// lights are): such surfaces cast no shadow.
    pub fn is_invisible(&self) -> bool {
        self.thin && self.transmission >= 1.0 && self.ior == Dispersion::Constant(1.0)
    }

    /// The BSDF at texture coordinate `uv`, seen from `wo` at shading normal `n`, and the
    /// wavelengths `lambda`, with `u_lobe` a uniform number that picks a lobe where the material
    /// mixes several.
    pub fn bsdf(&self, uv: Vec2, n: Vec3, wo: Vec3, lambda: &Wavelengths, u_lobe: f32) -> Bsdf {
        if u_lobe < self.transmission {
            let ior = self.ior.index(lambda.hero());
            return if self.thin { Bsdf::ThinDielectric { ior } } else { Bsdf::Dielectric { ior } };
        }
        let reflectance = self.reflectance(uv, lambda);
        let u_lobe = (u_lobe - self.transmission) / (1.0 - self.transmission);
        let alpha = self.roughness * self.roughness;
        if u_lobe < self.metallic {
            if self.roughness < SMOOTH_ROUGHNESS {
                return Bsdf::Conductor { f0: reflectance };
            }
            return Bsdf::RoughConductor { f0: reflectance, alpha };
        }
        if self.emission.is_some() && reflectance == Vec4::ZERO {
            return Bsdf::Black;
        }
        let Some(specular) = &self.specular else {
            return Bsdf::Diffuse { albedo: reflectance };
        };
        let u_lobe = (u_lobe - self.metallic) / (1.0 - self.metallic);
        let smooth = self.roughness < SMOOTH_ROUGHNESS;
        let plastic =
            Plastic { base: reflectance, coat: specular.coat(lambda, if smooth { 0.0 } else { alpha }) };
        if smooth {
            return plastic::choose_smooth(plastic, n, wo, u_lobe);
        }
        Bsdf::Plastic(plastic)
    }
}

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
    /// under a smooth layer.
    Plastic(Plastic),
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
    },
    /// A smooth dielectric boundary: Fresnel reflection and refraction with total internal reflection.
    Dielectric {
        /// Index of refraction of the inside relative to the outside.
        ior: f32,
    },
    /// A thin dielectric wall: Fresnel reflection (with the wall's inner reflections summed) or
    /// straight transmission, never bent.
    ThinDielectric {
        /// Index of refraction of the wall.
        ior: f32,
    },
    /// Absorbs everything (a light's own surface).
    Black,
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
        )
    }

    /// Whether [`Bsdf::sample`] reads its `u_lobe` (a dielectric's choice between reflection and
    /// refraction); paths draw that number only then.
    fn picks_lobe(&self) -> bool {
        match self {
            Bsdf::Dielectric { .. } | Bsdf::ThinDielectric { .. } => true,
            Bsdf::Plastic(plastic) => plastic.has_rough_coat(),
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

    /// The BSDF value `f(wo, wi)` (zero for delta lobes) with shading normal `n`.
    pub fn eval(&self, n: Vec3, wo: Vec3, wi: Vec3) -> SampledSpectrum {
        match *self {
            Bsdf::Diffuse { albedo } => diffuse::eval(albedo, n, wo, wi),
            Bsdf::RoughConductor { f0, alpha } => conductor::eval_rough(f0, alpha, n, wo, wi),
            Bsdf::Plastic(plastic) => plastic.eval(n, wo, wi),
            _ => Vec4::ZERO,
        }
    }

    /// The density per solid angle with which [`Bsdf::sample`] picks `wi` (zero for delta lobes).
    pub fn pdf(&self, n: Vec3, wo: Vec3, wi: Vec3) -> f32 {
        match *self {
            Bsdf::Diffuse { .. } => diffuse::pdf(n, wo, wi),
            Bsdf::RoughConductor { alpha, .. } => conductor::pdf_rough(alpha, n, wo, wi),
            Bsdf::Plastic(plastic) => plastic.pdf(n, wo, wi),
            _ => 0.0,
        }
    }

    /// Samples `wi` for `wo` at a surface of shading normal `n` and geometric normal `ng`.
    pub fn sample(
        &self,
        frame: ShadingFrame,
        wo: Vec3,
        u: Vec2,
        u_lobe: f32,
        mode: Transport,
    ) -> Option<BsdfSample> {
        let n = frame.n;
        match *self {
            Bsdf::Diffuse { albedo } => diffuse::sample(albedo, n, wo, u),
            Bsdf::Mirror { weight } => conductor::sample_mirror(weight, n, wo),
            Bsdf::Plastic(plastic) => plastic.sample(n, wo, u, u_lobe),
            Bsdf::Conductor { f0 } => conductor::sample_smooth(f0, n, wo),
            Bsdf::RoughConductor { f0, alpha } => conductor::sample_rough(f0, alpha, n, wo, u),
            Bsdf::Dielectric { ior } => dielectric::sample(ior, frame, wo, u_lobe, mode),
            Bsdf::ThinDielectric { ior } => dielectric::sample_thin(ior, frame, wo, u_lobe),
            Bsdf::Black => None,
        }
    }
}

/// The normals at a surface point: shading (interpolated) and geometric (the triangle's).
#[derive(Clone, Copy, Debug)]
pub struct ShadingFrame {
    /// Shading normal.
    pub n: Vec3,
    /// Geometric normal, pointing to the outside of the mesh.
    pub ng: Vec3,
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
mod tests {
    use super::*;
    use crate::sampling::{square_to_sphere, stream, Stream};
    use glam::DVec4;

    const FRAME: ShadingFrame = ShadingFrame { n: Vec3::Z, ng: Vec3::Z };

    /// Every sample's weight is `f cos / pdf` as `eval` and `pdf` say, and the mean weight (the
    /// importance-sampled albedo) matches the albedo integrated with uniform directions.
    fn check_sampling_against_eval(bsdf: Bsdf, wo: Vec3) {
        let mut rng = stream(3, Stream::Eye, 0, 0);
        let n = 200_000;
        let mut sampled = DVec4::ZERO;
        for _ in 0..n {
            let Some(s) = bsdf.sample(FRAME, wo, rng.next_2d(), rng.next_1d(), Transport::Radiance) else {
                continue;
            };
            let (f, pdf) = (bsdf.eval(Vec3::Z, wo, s.wi), bsdf.pdf(Vec3::Z, wo, s.wi));
            assert!((s.pdf / pdf - 1.0).abs() < 1e-3, "{bsdf:?}: pdf {} vs {pdf}", s.pdf);
            let expected = f * s.wi.z.abs() / pdf;
            assert!((s.weight / expected - Vec4::ONE).abs().max_element() < 1e-3, "{bsdf:?}: weight");
            sampled += s.weight.as_dvec4();
        }
        let uniform: DVec4 = (0..n)
            .map(|_| {
                let wi = square_to_sphere(rng.next_2d());
                (bsdf.eval(Vec3::Z, wo, wi) * wi.z.abs() * 4.0 * std::f32::consts::PI).as_dvec4()
            })
            .sum();
        let (sampled, uniform) = (sampled / n as f64, uniform / n as f64);
        let tolerance = 0.02 * uniform.max(DVec4::splat(0.1));
        assert!((sampled - uniform).abs().cmple(tolerance).all(), "{bsdf:?}: {sampled} vs {uniform}");
    }

    #[test]
    fn diffuse_sampling_matches_its_density() {
        check_sampling_against_eval(
            Bsdf::Diffuse { albedo: Vec4::new(0.7, 0.2, 0.9, 0.5) },
            Vec3::new(0.3, 0.1, 0.9).normalize(),
        );
    }

    #[test]
    fn ggx_sampling_matches_its_density() {
        for alpha in [0.1, 0.3, 0.8] {
            for wo in [Vec3::new(0.0, 0.0, 1.0), Vec3::new(0.8, 0.1, 0.3).normalize()] {
                check_sampling_against_eval(
                    Bsdf::RoughConductor { f0: Vec4::new(0.9, 0.3, 0.6, 1.0), alpha },
                    wo,
                );
            }
        }
    }

    /// A plastic of base albedo `base` under a coat of index 1.5 (times `tint`) and GGX `alpha`.
    fn plastic(base: f32, tint: Vec4, alpha: f32) -> Bsdf {
        Bsdf::Plastic(Plastic { base: Vec4::splat(base), coat: Coat::new(tint * 0.04, 1.5, alpha) })
    }

    /// The directional albedo `int f cos dwi` for `wo`, by sampling the BSDF.
    fn albedo(bsdf: Bsdf, wo: Vec3) -> Vec4 {
        let mut rng = stream(5, Stream::Eye, 0, 0);
        let n = 400_000;
        let sum: DVec4 = (0..n)
            .filter_map(|_| bsdf.sample(FRAME, wo, rng.next_2d(), rng.next_1d(), Transport::Radiance))
            .map(|s| s.weight.as_dvec4())
            .sum();
        (sum / n as f64).as_vec4()
    }

    #[test]
    fn plastic_sampling_matches_its_density() {
        // Narrower lobes than 0.1 are beyond the uniform integral's reach in 200,000 samples.
        for alpha in [0.1, 0.4, 1.0] {
            for wo in [Vec3::Z, Vec3::new(0.8, 0.1, 0.3).normalize(), Vec3::new(0.0, 0.99, 0.1).normalize()] {
                check_sampling_against_eval(plastic(0.6, Vec4::new(1.0, 0.5, 0.2, 1.0), alpha), wo);
            }
        }
    }

    /// A white base under any coat reflects everything (a white furnace), and a black one reflects
    /// what the coat does, never more than everything.
    #[test]
    fn plastic_conserves_energy() {
        for alpha in [0.0, 0.05, 0.3, 1.0] {
            for mu in [1.0f32, 0.7, 0.3, 0.1] {
                let wo = Vec3::new((1.0 - mu * mu).sqrt(), 0.0, mu);
                // A smooth coat's mirror is a delta lobe apart from the BSDF.
                let mirror = |tint: Vec4| match alpha {
                    0.0 => Coat::new(tint * 0.04, 1.5, 0.0).fresnel(mu),
                    _ => Vec4::ZERO,
                };
                let white = albedo(plastic(1.0, Vec4::ONE, alpha), wo) + mirror(Vec4::ONE);
                assert!((white - Vec4::ONE).abs().max_element() < 0.015, "alpha {alpha}, mu {mu}: {white}");
                // A black base: what the coat reflects, as its albedo table says.
                let tint = Vec4::splat(20.0);
                let black = albedo(plastic(0.0, tint, alpha), wo) + mirror(tint);
                let Bsdf::Plastic(p) = plastic(0.0, tint, alpha) else { unreachable!() };
                let table = if alpha == 0.0 { p.coat.fresnel(mu) } else { p.coat.albedo(mu) };
                assert!(black.max_element() < 1.0, "{black}");
                assert!(
                    (black - table).abs().max_element() < 0.015,
                    "alpha {alpha}, mu {mu}: {black} vs {table}"
                );
            }
        }
    }

    #[test]
    fn plastic_is_reciprocal() {
        let mut rng = stream(9, Stream::Eye, 0, 0);
        for alpha in [0.0, 0.1, 0.6] {
            let bsdf = plastic(0.7, Vec4::new(1.0, 0.8, 0.6, 1.0), alpha);
            for _ in 0..1000 {
                let (a, b) = (square_to_sphere(rng.next_2d()), square_to_sphere(rng.next_2d()));
                let (ab, ba) = (bsdf.eval(Vec3::Z, a, b), bsdf.eval(Vec3::Z, b, a));
                assert!((ab - ba).abs().max_element() <= 1e-5 * ab.max_element().max(1.0), "{ab} vs {ba}");
            }
        }
    }

    /// The glTF BRDF at Blender's defaults: a grey base with IOR 1.5 reflects 4% at normal
    /// incidence off its coat and more toward grazing, and the base under it less.
    #[test]
    fn a_principled_default_has_a_specular_layer() {
        let at = Wavelengths::single(550.0, 1.0);
        let default = Material {
            specular: Specular::new(1.5, 1.0, Vec3::ONE),
            roughness: 0.5,
            base_colour: BaseColour::Constant(RgbSpectrum::constant(0.8)),
            ..Material::default_grey()
        };
        let Bsdf::Plastic(p) = default.bsdf(Vec2::ZERO, Vec3::Z, Vec3::Z, &at, 0.5) else { panic!() };
        assert!((p.coat.f0 - Vec4::splat(0.04)).abs().max_element() < 1e-3, "{:?}", p.coat.f0);
        let (head_on, grazing) = (p.coat.albedo(1.0).x, p.coat.albedo(0.1).x);
        assert!(head_on > 0.035 && head_on < 0.06 && grazing > 2.0 * head_on, "{head_on} {grazing}");
        let lambert = Material { specular: Specular::new(1.5, 0.0, Vec3::ONE), ..default };
        assert!(matches!(lambert.bsdf(Vec2::ZERO, Vec3::Z, Vec3::Z, &at, 0.5), Bsdf::Diffuse { .. }));
    }

    #[test]
    fn materials_pick_lobes_by_their_weights() {
        let at = |lambda_nm: f32| Wavelengths::single(lambda_nm, 1.0);
        let glass = Material { transmission: 1.0, roughness: 0.0, ..Material::default_grey() };
        assert_eq!(glass.bsdf(Vec2::ZERO, Vec3::Z, Vec3::Z, &at(550.0), 0.5), Bsdf::Dielectric { ior: 1.5 });
        assert!(!glass.is_dispersive());
        let flint = Material { ior: Dispersion::glass("SF11").unwrap(), ..glass };
        assert!(flint.is_dispersive());
        let (blue, red) = (
            flint.bsdf(Vec2::ZERO, Vec3::Z, Vec3::Z, &at(450.0), 0.5),
            flint.bsdf(Vec2::ZERO, Vec3::Z, Vec3::Z, &at(650.0), 0.5),
        );
        assert!(
            matches!((blue, red), (Bsdf::Dielectric { ior: b }, Bsdf::Dielectric { ior: r }) if b > r + 0.02)
        );
        let mirror = Material { metallic: 1.0, roughness: 0.0, ..Material::default_grey() };
        assert!(matches!(mirror.bsdf(Vec2::ZERO, Vec3::Z, Vec3::Z, &at(550.0), 0.5), Bsdf::Conductor { .. }));
        let rough = Material { metallic: 1.0, roughness: 0.5, ..Material::default_grey() };
        assert!(matches!(
            rough.bsdf(Vec2::ZERO, Vec3::Z, Vec3::Z, &at(550.0), 0.5),
            Bsdf::RoughConductor { alpha: 0.25, .. }
        ));
        let half = Material { metallic: 0.5, ..Material::default_grey() };
        assert!(matches!(half.bsdf(Vec2::ZERO, Vec3::Z, Vec3::Z, &at(550.0), 0.7), Bsdf::Diffuse { .. }));
    }
}
