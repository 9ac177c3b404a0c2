//! The multiple importance sampling weights of vertex connection and merging, all in one place.
//!
//! Georgiev, Křivánek, Davidovič & Slusallek (2012) and their technical report's recursive form:
//! each subpath carries three partial sums (`vcm`, `vc`, `vm`) of the ratios of the densities with
//! which the other techniques would have sampled its vertices, so that every estimator's weight
//! is found from the two subpaths' sums and the densities at its own vertices. With the power
//! heuristic (`mis(x) = x^2`), and merging counted as a technique of density `pi r^2` times the
//! light paths of the pass (its acceptance probability).
//!
//! Densities are of the hero wavelength's BSDF (every technique uses the same ones, so the
//! weights of a path still sum to one), and leave Russian roulette out (every technique leaves it
//! out alike).

/// The heuristic: the power heuristic's square.
#[inline]
pub fn mis(x: f32) -> f32 {
    x * x
}

/// The weight of a technique whose density, relative to the others' summed in `others` (each
/// over its own), is 1. Where the sums overflow (a vertex seen at a grazing angle, two vertices
/// nearly touching) and make no number, the sample is left out: weight 0.
#[inline]
fn share(others: f32) -> f32 {
    let weight = 1.0 / (1.0 + others);
    if weight.is_nan() {
        0.0
    } else {
        weight
    }
}

/// What every weight of a pass shares: its merging radius and light path count.
#[derive(Clone, Copy, Debug)]
pub struct PassWeights {
    /// `mis(eta)`, `eta = pi r^2 n`: merging's density over a connection's.
    pub vm_factor: f32,
    /// `mis(1 / eta)`.
    pub vc_factor: f32,
    /// Light paths in the pass (`n`).
    pub light_paths: f32,
}

impl PassWeights {
    /// The weights of a pass of `light_paths` light paths, merging within `radius`.
    pub fn new(radius: f32, light_paths: usize) -> Self {
        let eta = std::f32::consts::PI * radius * radius * light_paths as f32;
        PassWeights { vm_factor: mis(eta), vc_factor: mis(1.0 / eta), light_paths: light_paths as f32 }
    }
}

/// A subpath's partial sums, as they stand at its last vertex.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Partials {
    /// Connection-or-merging at the vertex before.
    pub vcm: f32,
    /// Connections.
    pub vc: f32,
    /// Merging.
    pub vm: f32,
}

/// The densities of a scattering at a vertex: of the direction sampled (`forward`) and of the way
/// back (`reverse`), per solid angle; the cosine of the sampled direction; a delta lobe's.
#[derive(Clone, Copy, Debug)]
pub struct Scatter {
    /// Density of the sampled direction.
    pub forward: f32,
    /// Density of the reverse direction, sampled from the sampled one.
    pub reverse: f32,
    /// Cosine between the sampled direction and the shading normal.
    pub cos_out: f32,
    /// The lobe is a delta.
    pub delta: bool,
}

impl Partials {
    /// A light path leaving a light whose emission density is `emission` (choice included),
    /// whose next-event density is `direct` (choice at the receiver still to come: see
    /// [`Partials::chosen_at`]), at `cos` from its normal.
    pub fn leaving_light(
        pass: &PassWeights,
        emission: f32,
        direct: f32,
        cos: f32,
        delta: bool,
        finite: bool,
    ) -> Self {
        let vcm = mis(direct / emission);
        let vc = match (delta, finite) {
            (true, _) => 0.0,
            (false, true) => mis(cos / emission),
            (false, false) => mis(1.0 / emission),
        };
        Partials { vcm, vc, vm: vc * pass.vc_factor }
    }

    /// The camera path through one pixel, whose direction's density per solid angle in units of
    /// pixels is `camera_pdf`; light tracing (light paths meeting the camera) takes part when
    /// `light_tracing`.
    pub fn leaving_camera(pass: &PassWeights, camera_pdf: f32, light_tracing: bool) -> Self {
        let vcm = if light_tracing { mis(pass.light_paths / camera_pdf) } else { 0.0 };
        Partials { vcm, vc: 0.0, vm: 0.0 }
    }

    /// A light path's first vertex: next-event estimation there chooses its light with
    /// probability `p_choice`.
    pub fn chosen_at(self, p_choice: f32) -> Self {
        Partials { vcm: self.vcm * mis(p_choice), ..self }
    }

    /// Arriving at a vertex at `distance` (`None` for the first segment from a distant light),
    /// at `cos` from its shading normal.
    pub fn arrived(self, distance: Option<f32>, cos: f32) -> Self {
        let vcm = distance.map_or(self.vcm, |d| self.vcm * mis(d * d));
        let inv = 1.0 / mis(cos.abs().max(1e-7));
        Partials { vcm: vcm * inv, vc: self.vc * inv, vm: self.vm * inv }
    }

    /// Leaving a vertex by `scatter`.
    pub fn scattered(self, pass: &PassWeights, s: Scatter) -> Self {
        if s.delta {
            return Partials { vcm: 0.0, vc: self.vc * mis(s.cos_out), vm: self.vm * mis(s.cos_out) };
        }
        let out = mis(s.cos_out / s.forward);
        Partials {
            vc: out * (self.vc * mis(s.reverse) + self.vcm + pass.vm_factor),
            vm: out * (self.vm * mis(s.reverse) + self.vcm * pass.vc_factor + 1.0),
            vcm: mis(1.0 / s.forward),
        }
    }
}

/// The weight of a camera path meeting an emitter: `direct` the density with which next-event
/// estimation at the vertex before would have picked the point (per area, choice included; per
/// solid angle for distant lights), `emission` the light's density of emitting the path's last
/// segment (choice included). A camera ray meeting it first has weight 1.
pub fn emitter_met(camera: &Partials, direct: f32, emission: f32) -> f32 {
    share(mis(direct) * camera.vcm + mis(emission) * camera.vc)
}

/// The weight of next-event estimation: a light picked with probability `p_choice` and a
/// direction of density `direct` (per solid angle; a delta light's: the squared distance, or 1
/// when distant), which the BSDF samples with density `bsdf_forward` (0 for a delta light) and
/// the reverse with `bsdf_reverse`; the light emits the ray with `emission` (choice included), at
/// `cos_light` from its normal, arriving at `cos_here`.
pub struct DirectWeight {
    /// Choice probability of the light.
    pub p_choice: f32,
    /// Density of the direction, per solid angle.
    pub direct: f32,
    /// The BSDF's density of the direction toward the light.
    pub bsdf_forward: f32,
    /// The BSDF's density of the way back.
    pub bsdf_reverse: f32,
    /// The light's emission density of the ray, choice included.
    pub emission: f32,
    /// Cosine at the light.
    pub cos_light: f32,
    /// Cosine at the receiving vertex.
    pub cos_here: f32,
}

impl DirectWeight {
    /// The weight, for a camera path whose sums are `camera`.
    pub fn weight(&self, pass: &PassWeights, camera: &Partials) -> f32 {
        let w_light = mis(self.bsdf_forward / (self.p_choice * self.direct));
        let w_camera = mis(self.emission * self.cos_here / (self.p_choice * self.direct * self.cos_light))
            * (pass.vm_factor + camera.vcm + camera.vc * mis(self.bsdf_reverse));
        share(w_light + w_camera)
    }
}

/// One end of a connection: the subpath's sums, and at its vertex the BSDF's density of the
/// connecting direction (`forward`) and of the way back (`reverse`), and the cosine there.
#[derive(Clone, Copy, Debug)]
pub struct End {
    /// The subpath's sums.
    pub partials: Partials,
    /// Density of the connecting direction from this end's incoming one.
    pub forward: f32,
    /// Density of the incoming direction from the connecting one.
    pub reverse: f32,
    /// Cosine of the connecting direction at this end.
    pub cos: f32,
}

/// The weight of connecting a light vertex to a camera vertex `distance2` apart (squared).
pub fn connection(pass: &PassWeights, light: &End, camera: &End, distance2: f32) -> f32 {
    // Each end's density of the other's vertex, per area there.
    let camera_to_light = camera.forward * light.cos / distance2;
    let light_to_camera = light.forward * camera.cos / distance2;
    let w_light =
        mis(camera_to_light) * (pass.vm_factor + light.partials.vcm + light.partials.vc * mis(light.reverse));
    let w_camera = mis(light_to_camera)
        * (pass.vm_factor + camera.partials.vcm + camera.partials.vc * mis(camera.reverse));
    share(w_light + w_camera)
}

/// The weight of merging a light vertex of sums `light` at a camera vertex of sums `camera`,
/// whose BSDF samples the light vertex's incoming direction with density `forward` and its own
/// incoming one from it with `reverse`.
pub fn merging(pass: &PassWeights, light: &Partials, camera: &Partials, forward: f32, reverse: f32) -> f32 {
    let w_light = light.vcm * pass.vc_factor + light.vm * mis(forward);
    let w_camera = camera.vcm * pass.vc_factor + camera.vm * mis(reverse);
    share(w_light + w_camera)
}

/// The weight of a light vertex of sums `light` seen by the camera (light tracing): the camera's
/// density of the vertex per area, in pixels (`camera_area`), and the BSDF's density of the
/// light vertex's incoming direction from the camera's (`reverse`).
pub fn light_traced(pass: &PassWeights, light: &Partials, camera_area: f32, reverse: f32) -> f32 {
    let w_light =
        mis(camera_area / pass.light_paths) * (pass.vm_factor + light.vcm + light.vc * mis(reverse));
    share(w_light)
}
