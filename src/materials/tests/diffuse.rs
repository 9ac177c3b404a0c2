//! Tests of the Lambertian lobe.

use super::*;

#[test]
fn diffuse_sampling_matches_its_density() {
    check_sampling_against_eval(
        Bsdf::Diffuse { albedo: Vec4::new(0.7, 0.2, 0.9, 0.5) },
        Vec3::new(0.3, 0.1, 0.9).normalize(),
    );
}
