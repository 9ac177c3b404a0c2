//! The insides a path is in, as a stack of the transmissive closed meshes' materials it has
//! refracted into and not yet out of: each segment runs through the medium
//! ([`crate::materials::Volume`]) of the inside of highest priority among them (of equal
//! priorities, the one entered last; a clear one holds none), so a clear ice cube in tinted
//! water absorbs nothing, and where water and its glass overlap (a water surface modelled into
//! the glass wall, as artists do to avoid coincident faces) the priority says which fills the
//! overlap.
//!
//! Outside every inside, the world's fog (if the scene has one) fills the space.
//!
//! Paths start in the insides their start lies in ([`media_at`]: the camera's lens centre, each
//! light's centre), found by a ray that counts which meshes it leaves without having entered.
//! Scenes where nothing absorbs and there is no fog never look at any of this.

use glam::Vec3;

use crate::accel::Accel;
use crate::geometry::offset_origin;
use crate::materials::Volume;
use crate::scene::Scene;
use crate::spectrum::{SampledSpectrum, Wavelengths};

/// Insides a path can be in at once; entering one more leaves the outermost out.
const DEPTH: usize = 4;

/// The transmissive closed meshes' materials a path is inside, in the order entered.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Media {
    materials: [u32; DEPTH],
    len: u32,
}

impl Media {
    /// Inside nothing.
    pub const NONE: Media = Media { materials: [0; DEPTH], len: 0 };

    /// The insides entered, in order.
    fn entered(&self) -> &[u32] {
        &self.materials[..self.len as usize]
    }

    /// The material whose inside fills where the path is: the highest priority, then the last
    /// entered.
    fn filling(&self, scene: &Scene) -> Option<u32> {
        let priority = |m: u32| scene.materials[m as usize].priority;
        self.entered()
            .iter()
            .rev()
            .copied()
            .reduce(|best, m| if priority(m) > priority(best) { m } else { best })
    }

    /// The medium that fills where the path is: its inside's volume (none for a clear one), or
    /// outside every inside, the world's fog.
    pub fn medium<'s>(&self, scene: &'s Scene) -> Option<&'s Volume> {
        match self.filling(scene) {
            Some(material) => scene.materials[material as usize].volume.as_ref(),
            None => scene.fog.as_ref(),
        }
    }

    /// What a segment of `length` keeps of the light at `lambda`, unabsorbed and unscattered
    /// (`None` where nothing fills the path's place).
    pub fn transmittance(&self, scene: &Scene, lambda: &Wavelengths, length: f32) -> Option<SampledSpectrum> {
        Some(self.medium(scene)?.transmittance(lambda, length))
    }

    /// The media after a path at a surface of `material` with outward geometric normal `ng`
    /// arrived from `wo` and left toward `wi`: crossing into a transmissive closed mesh enters
    /// it, crossing out leaves it; reflection and thin walls change nothing.
    pub fn crossed(mut self, scene: &Scene, material: u32, ng: Vec3, wo: Vec3, wi: Vec3) -> Media {
        if !scene.materials[material as usize].has_inside() || ng.dot(wo) * ng.dot(wi) >= 0.0 {
            return self;
        }
        if ng.dot(wi) < 0.0 {
            self.enter(material);
        } else {
            self.leave(material);
        }
        self
    }

    fn enter(&mut self, material: u32) {
        if self.len as usize == DEPTH {
            self.materials.copy_within(1.., 0);
            self.len -= 1;
        }
        self.materials[self.len as usize] = material;
        self.len += 1;
    }

    fn leave(&mut self, material: u32) {
        if let Some(i) = self.entered().iter().rposition(|&m| m == material) {
            self.materials.copy_within(i + 1..self.len as usize, i);
            self.len -= 1;
        }
    }
}

/// Surfaces a ray from a path's start crosses, at most, looking for the insides it is in.
const MAX_CROSSINGS: usize = 64;

/// The insides `p` lies in: those of the transmissive closed meshes a ray from `p` leaves before
/// entering them, the innermost (the first left) entered last.
pub fn media_at(scene: &Scene, accel: &Accel, p: Vec3) -> Media {
    // Off every axis, so that it does not run along the faces of boxes modelled on the axes.
    let direction = Vec3::new(0.2113, 0.9331, 0.2910).normalize();
    let (mut origin, mut entered, mut left) = (p, Vec::new(), Vec::new());
    for _ in 0..MAX_CROSSINGS {
        let Some(hit) = accel.intersect(origin, direction, f32::INFINITY) else { break };
        let material = scene.triangle_material(hit.triangle);
        if scene.materials[material as usize].has_inside() {
            if hit.ng.dot(direction) < 0.0 {
                entered.push(material);
            } else if let Some(i) = entered.iter().rposition(|&e| e == material) {
                entered.remove(i);
            } else {
                left.push(material);
            }
        }
        origin = offset_origin(hit.p, hit.ng, direction, hit.scale);
    }
    let mut media = Media::NONE;
    left.iter().rev().for_each(|&material| media.enter(material));
    media
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn leaving_a_volume_removes_it_wherever_it_is_in_the_stack() {
        let mut media = Media::NONE;
        [3, 5, 7].into_iter().for_each(|m| media.enter(m));
        media.leave(5);
        assert_eq!(media.entered(), &[3, 7]);
        media.leave(9);
        assert_eq!(media.entered(), &[3, 7]);
        [1, 2, 4].into_iter().for_each(|m| media.enter(m));
        assert_eq!(media.entered(), &[7, 1, 2, 4], "the outermost is left out when full");
    }
}
