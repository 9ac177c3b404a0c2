//! Tests of glass: rough refraction and thin walls.

use super::*;

/// A rough glass of index 1.5 and GGX `alpha` whose refraction is tinted.
fn rough_glass(alpha: f32) -> Bsdf {
    Bsdf::RoughDielectric { ior: 1.5, alpha, tint: Vec4::new(1.0, 0.7, 0.4, 0.9) }
}

/// Seen from outside and from inside (where light beyond the critical angle is all
/// reflected), a rough dielectric samples as it evaluates, reflection and refraction alike.
#[test]
fn rough_dielectric_sampling_matches_its_density() {
    for alpha in [0.05, 0.2, 0.5, 1.0] {
        for wo in [
            Vec3::Z,
            Vec3::new(0.8, 0.1, 0.3).normalize(),
            Vec3::new(0.3, 0.1, -0.9).normalize(),
            Vec3::new(0.8, 0.1, -0.3).normalize(),
        ] {
            // Refraction narrower than alpha 1 is beyond the uniform integral's reach in
            // 200,000 samples (2% off at 0.5, and at 0.2 head on even in 4 million); the
            // chi-square test of the samples' density is not.
            match alpha {
                a if a < 1.0 => {
                    _ = check_sampling_density(
                        rough_glass(alpha),
                        wo,
                        200_000,
                        &mut stream(3, Stream::Eye, 0, 0),
                    )
                }
                _ => check_sampling_against_eval(rough_glass(alpha), wo),
            }
        }
    }
}

/// A white rough dielectric scatters all the flux it receives (photons: no 1 / eta^2), from
/// outside and inside, total internal reflection included: within 0.3% at small roughness,
/// and within 1.5% at alpha 0.25 and 1 where single scattering alone loses up to 58%
/// (`dielectric_albedo.rs` gives it back), except seen at grazing from inside (cosine 0.15),
/// within 3%.
#[test]
fn a_rough_dielectric_conserves_energy() {
    for ior in [1.33, 1.5, 2.4] {
        for alpha in [1e-4, 0.01, 0.25, 1.0] {
            let glass = Bsdf::RoughDielectric { ior, alpha, tint: Vec4::ONE };
            for mu in [1.0f32, 0.5, 0.15, -1.0, -0.5, -0.15] {
                let wo = Vec3::new((1.0 - mu * mu).sqrt(), 0.0, mu);
                let energy = scattered(glass, wo, Transport::Importance).x;
                let tolerance = match alpha {
                    a if a <= 0.01 => 0.003,
                    _ if mu == -0.15 => 0.03,
                    _ => 0.015,
                };
                assert!((energy - 1.0).abs() < tolerance, "ior {ior}, alpha {alpha}, mu {mu}: {energy}");
            }
        }
    }
}

/// Radiance through a boundary is scaled by the squared ratio of the indices, so the
/// single-scattering BSDF is reciprocal once each side's index is multiplied in:
/// `f(a, b) n(b)^2 = f(b, a) n(a)^2` (Veach 1997, 5.2). (Its energy compensation depends on
/// the outgoing direction alone: `rough_dielectric.rs`.)
#[test]
fn rough_dielectric_is_reciprocal_up_to_the_indices() {
    let mut rng = stream(11, Stream::Eye, 0, 0);
    let index = |w: Vec3| if w.z > 0.0 { 1.0 } else { 1.5f32 * 1.5 };
    for alpha in [0.1, 0.6] {
        let glass = RoughDielectric { ior: 1.5, alpha, tint: Vec4::new(1.0, 0.7, 0.4, 0.9) };
        let f = |a, b| glass.single_scattering(FRAME, a, b);
        for _ in 0..2000 {
            let (a, b) = (square_to_sphere(rng.next_2d()), square_to_sphere(rng.next_2d()));
            let (ab, ba) = (f(a, b) * index(b), f(b, a) * index(a));
            assert!((ab - ba).abs().max_element() <= 1e-4 * ab.max_element().max(1.0), "{ab} vs {ba}");
        }
    }
}

/// As roughness goes to 0 the rough dielectric becomes the smooth one: the same choices
/// between reflection and refraction, the same directions and weights.
#[test]
fn a_rough_dielectric_of_no_roughness_is_the_smooth_one() {
    let mut rng = stream(13, Stream::Eye, 0, 0);
    let tint = Vec4::new(1.0, 0.5, 0.3, 0.8);
    let rough = Bsdf::RoughDielectric { ior: 1.5, alpha: 1e-6, tint };
    let smooth = Bsdf::Dielectric { ior: 1.5, tint };
    for wo in [Vec3::new(0.6, 0.0, 0.8), Vec3::new(0.5, 0.0, -0.866), Vec3::new(0.8, 0.0, -0.6)] {
        for mode in [Transport::Radiance, Transport::Importance] {
            for i in 0..1000 {
                let u_lobe = (i as f32 + 0.5) / 1000.0;
                let r = rough.sample(FRAME, wo, rng.next_2d(), u_lobe, mode).unwrap();
                let s = smooth.sample(FRAME, wo, Vec2::ZERO, u_lobe, mode).unwrap();
                assert!((r.wi - s.wi).length() < 1e-3, "{wo}: {} vs {}", r.wi, s.wi);
                assert!((r.weight - s.weight).abs().max_element() < 1e-3, "{} vs {}", r.weight, s.weight);
            }
        }
    }
}

/// A rough thin wall of index 1.5, GGX `alpha`, a tint and some absorption.
fn rough_pane(alpha: f32, depth: f32) -> Bsdf {
    Bsdf::RoughThinDielectric {
        ior: 1.5,
        alpha,
        tint: Vec4::new(1.0, 0.7, 0.4, 0.9),
        depth: Vec4::splat(depth),
    }
}

/// A rough thin wall samples as it evaluates, from either face, reflection and transmission
/// alike; its single scattering is symmetric (`f(a, b) = f(b, a)`: no index ratio across a
/// wall); a clear white one scatters all it receives (within 1.5%: the albedo table); one of
/// no roughness is the smooth wall.
#[test]
fn a_rough_thin_wall_samples_as_it_evaluates_and_keeps_energy() {
    let mut rng = stream(17, Stream::Eye, 0, 0);
    for alpha in [0.05, 0.3, 0.8] {
        for wo in [Vec3::Z, Vec3::new(0.8, 0.1, 0.3).normalize(), Vec3::new(0.3, 0.1, -0.9).normalize()] {
            // As for rough glass, only the widest lobe is within the uniform integral's reach.
            match alpha {
                0.8 => check_sampling_against_eval(rough_pane(alpha, 0.3), wo),
                _ => _ = check_sampling_density(rough_pane(alpha, 0.3), wo, 200_000, &mut rng),
            }
        }
    }
    let pane = RoughThinDielectric {
        ior: 1.5,
        alpha: 0.4,
        tint: Vec4::new(1.0, 0.7, 0.4, 0.9),
        depth: Vec4::splat(0.3),
    };
    for _ in 0..2000 {
        let (a, b) = (square_to_sphere(rng.next_2d()), square_to_sphere(rng.next_2d()));
        let (ab, ba) = (pane.single_scattering(FRAME, a, b), pane.single_scattering(FRAME, b, a));
        assert!((ab - ba).abs().max_element() <= 1e-4 * ab.max_element().max(1.0), "{ab} vs {ba}");
    }
    for alpha in [0.05, 0.3, 1.0] {
        for mu in [1.0f32, 0.34, -0.6] {
            let wo = Vec3::new((1.0 - mu * mu).sqrt(), 0.0, mu);
            let white = Bsdf::RoughThinDielectric { ior: 1.5, alpha, tint: Vec4::ONE, depth: Vec4::ZERO };
            let energy = scattered(white, wo, Transport::Importance).x;
            assert!((energy - 1.0).abs() < 0.015, "alpha {alpha}, mu {mu}: {energy}");
        }
    }
    let tint = Vec4::new(1.0, 0.5, 0.3, 0.8);
    let rough = Bsdf::RoughThinDielectric { ior: 1.5, alpha: 1e-6, tint, depth: Vec4::splat(0.2) };
    let smooth = Bsdf::ThinDielectric { ior: 1.5, tint, depth: Vec4::splat(0.2) };
    for wo in [Vec3::new(0.6, 0.0, 0.8), Vec3::new(0.5, 0.0, -0.866)] {
        for i in 0..1000 {
            let u_lobe = (i as f32 + 0.5) / 1000.0;
            let r = rough.sample(FRAME, wo, rng.next_2d(), u_lobe, Transport::Radiance).unwrap();
            let s = smooth.sample(FRAME, wo, Vec2::ZERO, u_lobe, Transport::Radiance).unwrap();
            assert!((r.wi - s.wi).length() < 1e-3, "{wo}: {} vs {}", r.wi, s.wi);
            assert!((r.weight - s.weight).abs().max_element() < 1e-3, "{} vs {}", r.weight, s.weight);
        }
    }
}
