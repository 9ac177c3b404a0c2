//! A surface's material as the file gives it (glTF metallic-roughness with its extensions,
//! textures resolved at load), and its resolution at a surface point and a path's wavelengths
//! into a closed [`Bsdf`]: where the glTF material mixes lobes (transmission or metallic between
//! 0 and 1), one lobe is chosen by a random number with its weight as probability, which is
//! unbiased.

use std::cell::OnceCell;
use std::sync::Arc;

use glam::{Vec3, Vec4};

use super::clearcoat::Clearcoat;
use super::conductor;
use super::inputs::SurfaceInputs;
use super::layer_albedo::{eta_of_f0, f0_of_eta};
use super::layering::{self, Choice, Over};
use super::normal_map::NormalMap;
use super::plastic::{self, Coat, Plastic};
use super::sheen::Sheen;
use super::spread::Spread;
use super::volume::Volume;
use super::{Bsdf, ShadingFrame, NARROW_COAT_ALPHA};
use crate::spectrum::{Dispersion, Illuminant, RgbSpectrum, SampledSpectrum, Wavelengths};
use crate::texture::{DataTexture, Texture};

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
    /// glTF `metallicRoughnessTexture` (blue: metallic, green: roughness), scaling the factors.
    pub metallic_roughness: Option<Arc<DataTexture>>,
    /// glTF `normalTexture`.
    pub normal_map: Option<NormalMap>,
    /// The specular layer over a non-metal's base (glTF's dielectric BRDF); `None` for a pure
    /// Lambertian base (`KHR_materials_specular` with a factor of 0).
    pub specular: Option<Specular>,
    /// `KHR_materials_transmission` factor.
    pub transmission: f32,
    /// Index of refraction against wavelength: `KHR_materials_ior` (1.5 when absent), with
    /// `KHR_materials_dispersion` or a law from the `caustic` extras.
    pub ior: Dispersion,
    /// Emitted radiance shape (times D65) in W / (m^2 sr), or `None`.
    pub emission: Option<Illuminant>,
    /// The emissive texture with the emission's factor and strength baked in, which replaces
    /// `emission` where it is read.
    pub emission_texture: Option<Arc<Texture>>,
    /// Whether emission leaves both faces (meshes) or only the front (area lights).
    pub emits_both_sides: bool,
    /// How an area light's Spread narrows what its front emits (`None`: a cosine law).
    pub emission_spread: Option<Spread>,
    /// Transmission through a thin wall (an open mesh: a window pane modelled as a plane) rather
    /// than into a solid: glTF's reading of transmission without a volume.
    pub thin: bool,
    /// How the base colour's alpha cuts the surface (glTF `alphaMode`).
    pub alpha: Alpha,
    /// A clear coat over everything but the sheen (`KHR_materials_clearcoat`).
    pub clearcoat: Option<Clearcoat>,
    /// A sheen over everything (`KHR_materials_sheen`).
    pub sheen: Option<Sheen>,
    /// What absorbs inside, where light is transmitted (`KHR_materials_volume`).
    pub volume: Option<Volume>,
    /// Where the insides of two transmissive closed meshes overlap, the one of highest priority
    /// fills the overlap (the `caustic` extras' `priority`; equal priorities: the one entered
    /// last).
    pub priority: i32,
    /// Where the camera sees it (directly, or through surfaces alpha cuts away), the pixel is
    /// transparent and black: Blender's holdout (the Holdout shader, or an object in a holdout
    /// collection). Elsewhere it renders as its other fields say.
    pub holdout: bool,
    /// Whether the camera sees its emission (false for a light Blender hides from the camera;
    /// reflections see it either way).
    pub seen_by_camera: bool,
    /// An area light's surface: every ray passes through it unchanged, as through a surface
    /// alpha cuts away, and it casts no shadow (Blender's lights hide nothing behind them).
    pub light_surface: bool,
    /// Whether a mesh's vertex colours (`COLOR_0`) multiply its base colour and alpha: glTF's rule,
    /// unless the file says the material does not read them (Blender's exporter writes the
    /// colours of one material on every primitive of the mesh).
    pub reads_vertex_colours: bool,
}

/// What a path meets at a surface point: a BSDF in its frame, and the factor on the path's
/// throughput that choosing it (among a material's layers) carries.
#[derive(Clone, Copy, Debug)]
pub struct Lobe {
    /// The normals the BSDF is expressed in.
    pub frame: ShadingFrame,
    /// The BSDF.
    pub bsdf: Bsdf,
    /// The factor on the path's throughput.
    pub weight: f32,
    /// The layers over it (a sheen, a clear coat) that the path went under.
    over: [Option<Over>; 2],
}

impl Lobe {
    /// For a photon that arrived from `wo` and scatters toward `wi`: the factor on its flux
    /// beyond the sample's weight, and on the BSDF evaluated for it. It is 1 but under a layer
    /// ([`Over::importance_correction`]) and on a rough metal, whose multiple-scattering
    /// compensation (Cycles' Multiscatter GGX, not reciprocal) is that of the direction the
    /// light leaves toward, as a camera path meeting the metal sees it: `wi` here, not the `wo`
    /// the lobe was resolved for.
    pub fn importance_correction(&self, wo: Vec3, wi: Vec3) -> SampledSpectrum {
        let layers: f32 =
            self.over.iter().flatten().map(|layer| layer.importance_correction(wo, wi)).product();
        match self.bsdf {
            Bsdf::RoughConductor { f0, alpha, scale } => {
                conductor::multiple_scattering(f0, alpha, self.frame.n().dot(wi).abs()) / scale * layers
            }
            _ => SampledSpectrum::splat(layers),
        }
    }
}

/// glTF `alphaMode` with the alpha it reads: the base colour factor's, times its texture's.
#[derive(Clone, Debug)]
pub enum Alpha {
    /// Alpha is ignored.
    Opaque,
    /// The surface is there where alpha reaches the cutoff, and not elsewhere.
    Mask {
        /// `alphaCutoff`.
        cutoff: f32,
        /// The factor's alpha and the texture whose alpha channel multiplies it.
        coverage: Coverage,
    },
    /// The surface is there with probability alpha (stochastic transparency).
    Blend {
        /// The factor's alpha and the texture whose alpha channel multiplies it.
        coverage: Coverage,
    },
}

/// Where alpha comes from: the base colour factor's alpha times its texture's alpha channel and
/// the vertex colour's alpha.
#[derive(Clone, Debug)]
pub struct Coverage {
    /// `baseColorFactor`'s alpha.
    pub factor: f32,
    /// The base colour texture, read for its alpha channel.
    pub texture: Option<Arc<DataTexture>>,
}

impl Coverage {
    fn at(&self, inputs: &SurfaceInputs) -> f32 {
        let factor = self.factor * inputs.alpha;
        match &self.texture {
            Some(texture) => factor * texture.eval(&inputs.uv).w,
            None => factor,
        }
    }
}

impl Alpha {
    /// The probability that the surface is there at a surface point (1 for opaque surfaces).
    pub fn opacity(&self, inputs: &SurfaceInputs) -> f32 {
        match self {
            Alpha::Opaque => 1.0,
            Alpha::Mask { cutoff, coverage } => (coverage.at(inputs) >= *cutoff) as u8 as f32,
            Alpha::Blend { coverage } => coverage.at(inputs).clamp(0.0, 1.0),
        }
    }

    /// Whether alpha can make the surface transparent anywhere.
    pub fn cuts(&self) -> bool {
        !matches!(self, Alpha::Opaque)
    }
}

/// A non-metal's specular layer as the file gives it: `KHR_materials_specular` over the index.
#[derive(Clone, Debug)]
pub struct Specular {
    /// Normal-incidence reflectance at its colour's brightest: the index's, times the specular
    /// factor and the colour's largest component (Blender folds a Specular IOR Level above 0.5
    /// into the colour).
    pub f0: f32,
    /// The colour's hue (its largest component 1), tinting `f0` but not grazing reflection.
    pub tint: RgbSpectrum,
    /// `specularTexture`: its alpha channel scales the factor.
    pub factor_texture: Option<Arc<DataTexture>>,
    /// `specularColorTexture` (sRGB): it multiplies the colour.
    pub colour_texture: Option<Arc<Texture>>,
}

impl Specular {
    /// The layer of a material of index `ior` with `KHR_materials_specular`'s factor and colour;
    /// `None` when it reflects nothing (a factor of 0: a pure Lambertian base).
    pub fn new(ior: f32, factor: f32, colour: Vec3) -> Option<Self> {
        let scale = colour.max_element();
        let f0 = (f0_of_eta(ior) * factor * scale).min(0.99);
        (f0 > 0.0).then(|| Specular {
            f0,
            tint: RgbSpectrum::reflectance(colour / scale),
            factor_texture: None,
            colour_texture: None,
        })
    }

    /// The coat at a surface point's inputs, the wavelengths `lambda`, with GGX `alpha` (0:
    /// smooth).
    fn coat(&self, inputs: &SurfaceInputs, lambda: &Wavelengths, alpha: f32) -> Coat {
        let mut tint = self.tint.eval_lanes(lambda.nm);
        let mut f0 = self.f0;
        if let Some(texture) = &self.factor_texture {
            f0 *= texture.eval(&inputs.uv).w;
        }
        if let Some(texture) = &self.colour_texture {
            tint *= texture.eval(&inputs.uv, lambda.nm);
        }
        Coat::new(tint * f0, eta_of_f0(f0.max(1e-6)), alpha)
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
            metallic_roughness: None,
            normal_map: None,
            specular: None,
            transmission: 0.0,
            ior: Dispersion::Constant(1.5),
            emission: None,
            emission_texture: None,
            emits_both_sides: true,
            emission_spread: None,
            thin: false,
            alpha: Alpha::Opaque,
            clearcoat: None,
            sheen: None,
            volume: None,
            priority: 0,
            holdout: false,
            seen_by_camera: true,
            light_surface: false,
            reads_vertex_colours: true,
        }
    }

    /// The base colour's reflectance (times the vertex colour) at a surface point and the
    /// wavelengths `lambda`.
    pub fn reflectance(&self, inputs: &SurfaceInputs, lambda: &Wavelengths) -> SampledSpectrum {
        let base = match &self.base_colour {
            BaseColour::Constant(spectrum) => spectrum.eval_lanes(lambda.nm),
            BaseColour::Texture(texture) => texture.eval(&inputs.uv, lambda.nm),
        };
        base * inputs.colour
    }

    /// Metallic and roughness at a surface point: the factors times the texture's blue and green.
    fn metallic_roughness(&self, inputs: &SurfaceInputs) -> (f32, f32) {
        match &self.metallic_roughness {
            Some(texture) => {
                let texel = texture.eval(&inputs.uv);
                (self.metallic * texel.z, self.roughness * texel.y)
            }
            None => (self.metallic, self.roughness),
        }
    }

    /// The shading frame at a surface point: the interpolated normal, bent by the normal map.
    fn shading_frame(&self, inputs: &SurfaceInputs, frame: ShadingFrame) -> ShadingFrame {
        match &self.normal_map {
            Some(map) => map.apply(inputs, frame),
            None => frame,
        }
    }

    /// The emitted spectral radiance at a surface point and `lambda` leaving toward `wo` from a
    /// face of normal `ng`, times the probability that alpha leaves the surface there (a path
    /// passes where it is cut away, so its emission counts where it is there).
    pub fn emitted(
        &self,
        inputs: &SurfaceInputs,
        lambda: &Wavelengths,
        ng: Vec3,
        wo: Vec3,
    ) -> SampledSpectrum {
        let radiance = match (&self.emission, &self.emission_texture) {
            (Some(_), _) if !self.emits_both_sides && ng.dot(wo) <= 0.0 => Vec4::ZERO,
            (Some(_), Some(texture)) => texture.eval(&inputs.uv, lambda.nm) * lambda.d65,
            (Some(spectrum), None) => spectrum.eval(lambda),
            (None, _) => Vec4::ZERO,
        };
        let radiance = match self.emission_spread {
            Some(spread) => radiance * spread.attenuation(ng.dot(wo)),
            None => radiance,
        };
        if self.alpha.cuts() {
            radiance * self.alpha.opacity(inputs)
        } else {
            radiance
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
        self.ior.is_dispersive()
            && matches!(
                bsdf,
                Bsdf::Dielectric { .. } | Bsdf::ThinDielectric { .. } | Bsdf::RoughDielectric { .. }
            )
    }

    /// Whether a path refracting into it is inside it until it refracts out: transmissive on a
    /// closed mesh (not a thin wall).
    pub fn has_inside(&self) -> bool {
        self.transmission > 0.0 && !self.thin
    }

    /// What a path arriving from `wo` meets at a surface point whose interpolated frame is
    /// `frame`, at the wavelengths `lambda`, with `u_lobe` a uniform number that picks a layer or
    /// lobe where the material has several. A Lambertian material resolves here, without a call.
    #[inline(always)]
    pub fn lobe(
        &self,
        inputs: &SurfaceInputs,
        frame: ShadingFrame,
        wo: Vec3,
        lambda: &Wavelengths,
        u_lobe: f32,
    ) -> Lobe {
        if self.is_lambertian() {
            let bsdf = Bsdf::Diffuse { albedo: self.reflectance(inputs, lambda) };
            return Lobe { frame: self.shading_frame(inputs, frame), bsdf, weight: 1.0, over: [None; 2] };
        }
        self.layered_lobe(inputs, frame, wo, lambda, u_lobe)
    }

    /// Whether a visible point can lie on it: whether some lobe of it is gathered at (not glass
    /// alone, nor a metal alone). Photons that reach it are stored whichever lobe
    /// they go on by, since a visible point there picks its own.
    pub fn gathers_photons(&self) -> bool {
        let metal = self.metallic >= 1.0 && self.metallic_roughness.is_none();
        self.transmission < 1.0 && !metal
    }

    /// Whether it is a Lambertian surface and nothing else (no specular layer, metal, glass,
    /// emission, alpha or coat), as most are.
    fn is_lambertian(&self) -> bool {
        self.specular.is_none()
            && self.transmission == 0.0
            && self.metallic == 0.0
            && self.emission.is_none()
            && !self.alpha.cuts()
            && self.clearcoat.is_none()
            && self.sheen.is_none()
    }

    /// [`Material::lobe`] where layers or lobes are mixed: alpha first, then the sheen or what
    /// lies under it, then the clear coat or what lies under it (Cycles' order), then glass, metal
    /// or the glTF dielectric BRDF.
    #[inline(never)]
    fn layered_lobe(
        &self,
        inputs: &SurfaceInputs,
        frame: ShadingFrame,
        wo: Vec3,
        lambda: &Wavelengths,
        u_lobe: f32,
    ) -> Lobe {
        let Some(mut u) = self.alpha_remainder(inputs, u_lobe).filter(|_| !self.light_surface) else {
            return Lobe { frame, bsdf: Bsdf::PassThrough, weight: 1.0, over: [None; 2] };
        };
        let (mut weight, mut over) = (1.0, [None; 2]);
        let shading = self.shading_frame(inputs, frame);
        // The base colour is looked up once, if at all (a texture read), for every layer's pick.
        let reflectance = OnceCell::new();
        let reflectance = || *reflectance.get_or_init(|| self.reflectance(inputs, lambda));
        let under = || reflectance().element_sum() / 4.0;
        if let Some(sheen) = self.sheen.as_ref().and_then(|s| s.at(&inputs.uv, shading, lambda)) {
            match layering::pick(Over::from(&sheen).reflected(wo), 1.0, under(), u) {
                Choice::Layer { weight } => {
                    let bsdf = Bsdf::Sheen { colour: sheen.colour, roughness: sheen.roughness };
                    return Lobe { frame: shading, bsdf, weight, over };
                }
                Choice::Under { weight: w, u: rest } => {
                    (weight, u, over[0]) = (w, rest, Some(Over::from(&sheen)))
                }
            }
        }
        if let Some(coat) = self.clearcoat.as_ref().and_then(|c| c.at(inputs, frame)) {
            match layering::pick(Over::from(&coat).reflected(wo), coat.factor, under(), u) {
                Choice::Layer { weight: w } => {
                    return Lobe { frame: coat.frame, bsdf: coat.bsdf(wo), weight: weight * w, over };
                }
                Choice::Under { weight: w, u: rest } => {
                    (weight, u, over[1]) = (weight * w, rest, Some(Over::from(&coat)))
                }
            }
        }
        let glossy = shading.for_glossy(wo);
        let (bsdf, w) = self.opaque_bsdf(inputs, reflectance, glossy.n(), wo, lambda, u);
        let frame = match bsdf {
            Bsdf::Conductor { .. } | Bsdf::RoughConductor { .. } | Bsdf::Mirror { .. } => glossy,
            _ => shading,
        };
        Lobe { frame, bsdf, weight: weight * w, over }
    }

    /// Where alpha cuts the surface away (`u_lobe` beyond the opacity), `None`; else `u_lobe`
    /// spread again over [0, 1).
    fn alpha_remainder(&self, inputs: &SurfaceInputs, u_lobe: f32) -> Option<f32> {
        if !self.alpha.cuts() {
            return Some(u_lobe);
        }
        let opacity = self.alpha.opacity(inputs);
        (u_lobe < opacity).then(|| u_lobe / opacity)
    }

    /// The BSDF where the surface is there (alpha and coat left aside), at shading normal `n`,
    /// and the factor on the path's throughput its choice carries; `reflectance` gives the base
    /// colour, read only where a lobe needs it.
    fn opaque_bsdf(
        &self,
        inputs: &SurfaceInputs,
        reflectance: impl FnOnce() -> SampledSpectrum,
        n: Vec3,
        wo: Vec3,
        lambda: &Wavelengths,
        u_lobe: f32,
    ) -> (Bsdf, f32) {
        let reflectance = reflectance();
        let (metallic, roughness) = self.metallic_roughness(inputs);
        let alpha = if roughness < SMOOTH_ROUGHNESS { 0.0 } else { roughness * roughness };
        if u_lobe < self.transmission {
            return (self.transmission_bsdf(self.ior.index(lambda.hero()), alpha, reflectance, lambda), 1.0);
        }
        let u_lobe = (u_lobe - self.transmission) / (1.0 - self.transmission);
        if u_lobe < metallic {
            if alpha == 0.0 {
                return (Bsdf::Conductor { f0: reflectance }, 1.0);
            }
            let scale = conductor::multiple_scattering(reflectance, alpha, n.dot(wo).abs());
            return (Bsdf::RoughConductor { f0: reflectance, alpha, scale }, 1.0);
        }
        if self.emission.is_some() && reflectance == Vec4::ZERO {
            return (Bsdf::Black, 1.0);
        }
        let Some(specular) = &self.specular else {
            return (Bsdf::Diffuse { albedo: reflectance }, 1.0);
        };
        let u_lobe = (u_lobe - metallic) / (1.0 - metallic);
        let plastic = Plastic { base: reflectance, coat: specular.coat(inputs, lambda, alpha) };
        if alpha < NARROW_COAT_ALPHA {
            return plastic::choose_layer(plastic, n, wo, u_lobe);
        }
        (plastic.bsdf(), 1.0)
    }

    /// The transmissive lobe of index `ior` and GGX `alpha` for base colour `base` at `lambda`: a
    /// thin wall tints what passes by the base colour and absorbs across its volume's thickness, a
    /// closed mesh's boundary tints by the base colour's square root, so that light through both
    /// boundaries is tinted by the base colour (Cycles' Principled BSDF); what the closed mesh's
    /// volume absorbs, the path's segments inside take.
    fn transmission_bsdf(&self, ior: f32, alpha: f32, base: SampledSpectrum, lambda: &Wavelengths) -> Bsdf {
        let tint = base.max(Vec4::ZERO);
        let depth = || self.volume.as_ref().map_or(Vec4::ZERO, |v| v.absorption(lambda) * v.thickness);
        match (self.thin, alpha) {
            (true, 0.0) => Bsdf::ThinDielectric { ior, tint, depth: depth() },
            (true, _) => Bsdf::RoughThinDielectric { ior, alpha, tint, depth: depth() },
            (false, 0.0) => Bsdf::Dielectric { ior, tint: tint.sqrt() },
            (false, _) => Bsdf::RoughDielectric { ior, alpha, tint: tint.sqrt() },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A photon leaves a rough metal as a camera path there sees the light: the lobe resolved
    /// for a photon arriving from `l`, evaluated toward `v` with its importance correction,
    /// equals the lobe resolved for a camera at `v` evaluated for light from `l` (the multiple-
    /// scattering compensation is the viewer's direction's, as in Cycles). Without the
    /// correction they differ by up to 88% at roughness 1 and 11% at roughness 0.3.
    #[test]
    fn a_photon_leaves_a_rough_metal_as_a_camera_path_sees_it() {
        let frame = ShadingFrame::new(Vec3::Z, Vec3::Z);
        let f0 = Vec4::new(0.9, 0.6, 0.3, 0.8);
        let lobe_for = |alpha: f32, wo: Vec3| Lobe {
            frame,
            bsdf: Bsdf::RoughConductor { f0, alpha, scale: conductor::multiple_scattering(f0, alpha, wo.z) },
            weight: 1.0,
            over: [None; 2],
        };
        for alpha in [0.09, 0.36, 1.0] {
            for (l, v) in [(0.1, 0.9), (0.95, 0.2), (0.5, 0.5), (0.05, 0.05)] {
                let l = Vec3::new((1.0f32 - l * l).sqrt(), 0.0, l);
                let v = Vec3::new(-(1.0f32 - v * v).sqrt() * 0.6, (1.0f32 - v * v).sqrt() * 0.8, v);
                let camera = lobe_for(alpha, v).bsdf.eval(frame, v, l);
                let photon = lobe_for(alpha, l);
                let leaving = photon.bsdf.eval(frame, v, l) * photon.importance_correction(l, v);
                let off = (leaving / camera - Vec4::ONE).abs().max_element();
                assert!(off < 1e-5, "alpha {alpha}, l {l}, v {v}: photon {leaving}, camera {camera}");
            }
        }
    }
}
