//! Vertex attributes that only some meshes have: a second texture coordinate set, vertex colours
//! (and their alpha, where it cuts) and tangents. Each list is empty while no mesh has it, so scenes without them carry and
//! interpolate nothing; once one mesh has it, the others' vertices get its default.

use glam::{Mat3, Vec2, Vec3, Vec4};

use crate::materials::{vertex_colour, SurfaceInputs};
use crate::spectrum::{RgbSpectrum, SampledSpectrum, Wavelengths};

/// Optional vertex attributes, one entry per vertex or none.
#[derive(Clone, Debug, Default)]
pub struct VertexExtras {
    /// `TEXCOORD_1`.
    pub uvs1: Vec<Vec2>,
    /// `COLOR_0` as reflectance spectra.
    pub colours: Vec<RgbSpectrum>,
    /// `COLOR_0`'s alpha, where a mesh's alpha below 1 meets a material whose alpha cuts.
    pub alphas: Vec<f32>,
    /// `TANGENT`: xyz and handedness w.
    pub tangents: Vec<Vec4>,
}

/// `out` (holding `len` vertices' entries or none) with `added` entries more: `from`'s, or the
/// default where `from` has none; stays empty while neither has any.
fn append<T: Clone>(
    out: &mut Vec<T>,
    len: usize,
    from: &[T],
    added: usize,
    default: T,
    map: impl Fn(&T) -> T,
) {
    if out.is_empty() && from.is_empty() {
        return;
    }
    out.resize(len, default.clone());
    if from.is_empty() {
        out.resize(len + added, default);
    } else {
        out.extend(from.iter().map(map));
    }
}

impl VertexExtras {
    /// Appends `from`'s `added` vertices to these `len`, their tangents turned by `linear` (the
    /// world matrix's linear part; a mirroring one flips their handedness).
    pub fn append(&mut self, len: usize, from: &VertexExtras, added: usize, linear: Mat3) {
        let flip = linear.determinant().signum();
        append(&mut self.uvs1, len, &from.uvs1, added, Vec2::ZERO, |&uv| uv);
        append(&mut self.colours, len, &from.colours, added, RgbSpectrum::constant(1.0), |&c| c);
        append(&mut self.alphas, len, &from.alphas, added, 1.0, |&a| a);
        let turn = |t: &Vec4| (linear * t.truncate()).normalize_or_zero().extend(t.w * flip);
        append(&mut self.tangents, len, &from.tangents, added, Vec4::ZERO, turn);
    }

    /// The material inputs at barycentric weights `w` of the triangle of vertices `v` and the
    /// wavelengths `lambda`, with `uv0` the first set's coordinates there.
    #[inline]
    pub fn inputs(&self, v: [usize; 3], w: Vec3, uv0: Vec2, lambda: &Wavelengths) -> SurfaceInputs {
        let lerp2 = |a: &[Vec2]| a[v[0]] * w.x + a[v[1]] * w.y + a[v[2]] * w.z;
        let uv1 = if self.uvs1.is_empty() { Vec2::ZERO } else { lerp2(&self.uvs1) };
        let colour = match self.colours.is_empty() {
            true => SampledSpectrum::ONE,
            false => vertex_colour(v.map(|i| &self.colours[i]), w, lambda.nm),
        };
        let tangent = if self.tangents.is_empty() {
            Vec4::ZERO
        } else {
            let t = &self.tangents;
            let xyz = t[v[0]].truncate() * w.x + t[v[1]].truncate() * w.y + t[v[2]].truncate() * w.z;
            xyz.extend(t[v[0]].w)
        };
        let alpha = match self.alphas.is_empty() {
            true => 1.0,
            false => self.alphas[v[0]] * w.x + self.alphas[v[1]] * w.y + self.alphas[v[2]] * w.z,
        };
        SurfaceInputs { uv: [uv0, uv1], colour, tangent, alpha }
    }
}
