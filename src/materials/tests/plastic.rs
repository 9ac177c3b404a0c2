//! Tests of the glTF dielectric BRDF: a coat over a Lambertian base.

use super::*;

/// A plastic of base albedo `base` under a coat of index 1.5 (times `tint`) and GGX `alpha`.
fn plastic(base: f32, tint: Vec4, alpha: f32) -> Bsdf {
    Plastic::new(Vec4::splat(base), tint * 0.04, 1.5, alpha).bsdf()
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
            let coat = Coat::new(tint * 0.04, 1.5, alpha);
            let table = if alpha == 0.0 { coat.fresnel(mu) } else { coat.albedo(mu) };
            assert!(black.max_element() < 1.0, "{black}");
            assert!(
                (black - table).abs().max_element() < 0.015,
                "alpha {alpha}, mu {mu}: {black} vs {table}"
            );
        }
    }
}

/// A coat's own reflection (a rough layer over nothing) samples as it evaluates.
#[test]
fn coat_sampling_matches_its_density() {
    for alpha in [0.1, 0.5] {
        for wo in [Vec3::Z, Vec3::new(0.8, 0.1, 0.3).normalize()] {
            check_sampling_against_eval(plastic(0.0, Vec4::ONE, alpha), wo);
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
            let (ab, ba) = (bsdf.eval(FRAME, a, b), bsdf.eval(FRAME, b, a));
            assert!((ab - ba).abs().max_element() <= 1e-5 * ab.max_element().max(1.0), "{ab} vs {ba}");
        }
    }
}
