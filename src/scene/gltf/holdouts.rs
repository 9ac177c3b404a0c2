//! Copies of materials a mesh needs: holdouts, and thin walls for open glass.

use crate::scene::values::MaterialAnimation;

use super::instances::is_closed;
use super::Builder;

use crate::materials::Material;
use crate::scene::TriangleRef;

impl Builder<'_> {
    /// The material animations, each also on the thin-wall copy of its material (a holdout
    /// copy stays black).
    pub(super) fn material_animations_with_copies(&self) -> Vec<(usize, MaterialAnimation)> {
        let thin = |m: usize| self.thin_materials.get(&(m as u32)).map(|&c| c as usize);
        let all = self.material_animations.iter().flat_map(|(m, animation)| {
            std::iter::once(*m).chain(thin(*m)).map(move |c| (c, animation.clone()))
        });
        all.collect()
    }

    /// The holdout copy of `material`.
    pub(super) fn holdout_material(&mut self, material: u32) -> u32 {
        if self.materials[material as usize].holdout {
            return material;
        }
        if let Some(&copy) = self.holdout_materials.get(&material) {
            return copy;
        }
        let copy = Material { holdout: true, ..self.materials[material as usize].clone() };
        self.materials.push(copy);
        let index = self.materials.len() as u32 - 1;
        self.holdout_materials.insert(material, index);
        index
    }

    /// The thin-wall copy of `material`.
    pub(super) fn thin_material(&mut self, material: u32) -> u32 {
        if let Some(&thin) = self.thin_materials.get(&material) {
            return thin;
        }
        let mut copy = self.materials[material as usize].clone();
        copy.thin = true;
        self.materials.push(copy);
        let thin = self.materials.len() as u32 - 1;
        self.thin_materials.insert(material, thin);
        thin
    }

    /// Makes the mesh instances from `first` on holdouts: each triangle gets its material's
    /// holdout copy.
    pub(super) fn hold_out(&mut self, first: usize) {
        for i in first..self.meshes.len() {
            for t in 0..self.meshes[i].triangles.len() {
                let material = self.meshes[i].triangles[t].material;
                self.meshes[i].triangles[t].material = self.holdout_material(material);
            }
        }
    }

    /// Glass on an open mesh (a pane modelled as a plane) has no inside to refract into: its
    /// transmissive primitives get a thin-wall copy of their material, as glTF reads transmission
    /// without a volume.
    pub(super) fn thin_walls_of_open_glass(&mut self, first: usize, name: &str) {
        let is_glass = |b: &Self, t: &TriangleRef| b.materials[t.material as usize].transmission > 0.0;
        let instances = &self.meshes[first..];
        if !instances.iter().any(|m| m.triangles.iter().any(|t| is_glass(self, t))) || is_closed(instances) {
            return;
        }
        for i in first..self.meshes.len() {
            for t in 0..self.meshes[i].triangles.len() {
                let material = self.meshes[i].triangles[t].material;
                if self.materials[material as usize].transmission > 0.0 {
                    self.meshes[i].triangles[t].material = self.thin_material(material);
                }
            }
        }
        self.warnings.push(format!(
            "mesh '{name}': its glass is an open surface, rendered as a thin wall (no refraction); close the mesh for solid glass"
        ));
    }
}
