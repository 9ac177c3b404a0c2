//! Tests of the sheen layer.

use super::*;

/// A sheen samples as it evaluates.
#[test]
fn sheen_sampling_matches_its_density() {
    for roughness in [0.3, 0.7, 1.0] {
        let sheen = Bsdf::Sheen { colour: Vec4::new(1.0, 0.5, 0.2, 0.8), roughness };
        for wo in [Vec3::Z, Vec3::new(0.8, 0.1, 0.3).normalize(), Vec3::new(0.0, 0.99, 0.1).normalize()] {
            check_sampling_against_eval(sheen, wo);
        }
    }
}

/// Under a white sheen (Cycles' layering), a white Lambertian base still reflects everything
/// (a white furnace), and a black one reflects what the sheen does, as its albedo fit says,
/// more toward grazing; a sheen over a clear coat over the base too.
#[test]
fn a_sheen_conserves_energy() {
    let white = |roughness: f32, coat: Option<Clearcoat>| Material {
        base_colour: BaseColour::Constant(RgbSpectrum::constant(1.0)),
        sheen: Some(Sheen {
            colour: RgbSpectrum::constant(1.0),
            colour_texture: None,
            roughness,
            roughness_texture: None,
        }),
        clearcoat: coat,
        ..Material::default_grey()
    };
    let coat = Some(Clearcoat { factor: 1.0, roughness: 0.2, ..Clearcoat::default() });
    for roughness in [0.3, 0.8] {
        let black = Material {
            base_colour: BaseColour::Constant(RgbSpectrum::constant(0.0)),
            ..white(roughness, None)
        };
        for mu in [1.0f32, 0.5, 0.15] {
            let wo = Vec3::new((1.0 - mu * mu).sqrt(), 0.0, mu);
            for material in [white(roughness, None), white(roughness, coat.clone())] {
                let furnace = material_albedo(&material, wo);
                assert!((furnace - 1.0).abs() < 0.01, "roughness {roughness}, mu {mu}: {furnace}");
            }
            let sheen_alone = material_albedo(&black, wo);
            let table = crate::materials::sheen::albedo(mu, roughness);
            assert!(
                (sheen_alone - table).abs() < 0.01,
                "roughness {roughness}, mu {mu}: {sheen_alone} vs {table}"
            );
        }
    }
}
