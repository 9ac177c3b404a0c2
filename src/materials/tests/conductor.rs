//! Tests of metals: GGX and its multiple scattering.

use super::*;

#[test]
fn ggx_sampling_matches_its_density() {
    for alpha in [0.1, 0.3, 0.8] {
        for wo in [Vec3::new(0.0, 0.0, 1.0), Vec3::new(0.8, 0.1, 0.3).normalize()] {
            check_sampling_against_eval(
                Bsdf::RoughConductor { f0: Vec4::new(0.9, 0.3, 0.6, 1.0), alpha, scale: Vec4::ONE },
                wo,
            );
        }
    }
}

/// A white rough metal, the light single scattering loses given back (Cycles' Multiscatter
/// GGX), reflects everything from every direction (a white furnace, within 1.5%: the albedo
/// table's nodes); without it, roughness 1 seen head-on reflects 31%.
#[test]
fn a_white_rough_metal_reflects_everything() {
    for alpha in [0.1, 0.4, 1.0] {
        for mu in [1.0f32, 0.5, 0.15] {
            let wo = Vec3::new((1.0 - mu * mu).sqrt(), 0.0, mu);
            let scale = crate::materials::conductor::multiple_scattering(Vec4::ONE, alpha, mu);
            let white = albedo(Bsdf::RoughConductor { f0: Vec4::ONE, alpha, scale }, wo);
            assert!((white - Vec4::ONE).abs().max_element() < 0.015, "alpha {alpha}, mu {mu}: {white}");
        }
    }
    let single = albedo(Bsdf::RoughConductor { f0: Vec4::ONE, alpha: 1.0, scale: Vec4::ONE }, Vec3::Z);
    assert!((single.x - 0.31).abs() < 0.01, "{single}");
}
