//! Tests of layers and lobes picked by a whole material.

use super::*;

/// Under a clear coat (Cycles' layering), a white Lambertian base still reflects everything
/// (a white furnace), and a black one reflects what the coat does: 4% head-on, more toward
/// grazing, never more than everything.
#[test]
fn a_clear_coat_conserves_energy() {
    for roughness in [0.0, 0.1, 0.5] {
        let coat = Some(Clearcoat { factor: 1.0, roughness, ..Clearcoat::default() });
        let white = Material {
            base_colour: BaseColour::Constant(RgbSpectrum::constant(1.0)),
            clearcoat: coat.clone(),
            ..Material::default_grey()
        };
        let black =
            Material { base_colour: BaseColour::Constant(RgbSpectrum::constant(0.0)), ..white.clone() };
        for mu in [1.0f32, 0.5, 0.15] {
            let wo = Vec3::new((1.0 - mu * mu).sqrt(), 0.0, mu);
            let furnace = material_albedo(&white, wo);
            assert!((furnace - 1.0).abs() < 0.01, "roughness {roughness}, mu {mu}: {furnace}");
            let coat_alone = material_albedo(&black, wo);
            let expected = Coat::new(Vec4::splat(0.04), 1.5, roughness * roughness);
            let expected = if roughness == 0.0 { expected.fresnel(mu).x } else { expected.albedo(mu).x };
            assert!(
                (coat_alone - expected).abs() < 0.01,
                "roughness {roughness}, mu {mu}: {coat_alone} vs {expected}"
            );
            assert!(coat_alone > 0.035 && coat_alone < 1.0);
        }
    }
}

/// The glTF BRDF at Blender's defaults: a grey base with IOR 1.5 reflects 4% at normal
/// incidence off its coat and more toward grazing, and the base under it less.
#[test]
fn a_principled_default_has_a_specular_layer() {
    let at = Wavelengths::single(550.0, 1.0);
    let default = Material {
        specular: Specular::new(1.5, 1.0, Vec3::ONE),
        roughness: 0.5,
        base_colour: BaseColour::Constant(RgbSpectrum::constant(0.8)),
        ..Material::default_grey()
    };
    let Bsdf::Plastic { f0, eta, alpha, .. } =
        default.lobe(&SurfaceInputs::default(), FRAME, Vec3::Z, &at, 0.5).bsdf
    else {
        panic!()
    };
    assert!((f0 - Vec4::splat(0.04)).abs().max_element() < 1e-3, "{f0:?}");
    let coat = Coat::new(f0, eta, alpha);
    let (head_on, grazing) = (coat.albedo(1.0).x, coat.albedo(0.1).x);
    assert!(head_on > 0.035 && head_on < 0.06 && grazing > 2.0 * head_on, "{head_on} {grazing}");
    let lambert = Material { specular: Specular::new(1.5, 0.0, Vec3::ONE), ..default };
    assert!(matches!(
        lambert.lobe(&SurfaceInputs::default(), FRAME, Vec3::Z, &at, 0.5).bsdf,
        Bsdf::Diffuse { .. }
    ));
}

#[test]
fn materials_pick_lobes_by_their_weights() {
    let at = |lambda_nm: f32| Wavelengths::single(lambda_nm, 1.0);
    let glass = Material { transmission: 1.0, roughness: 0.0, ..Material::default_grey() };
    assert_eq!(
        glass.lobe(&SurfaceInputs::default(), FRAME, Vec3::Z, &at(550.0), 0.5).bsdf,
        Bsdf::Dielectric { ior: 1.5, tint: Vec4::splat(0.8f32.sqrt()) }
    );
    let frosted = Material { roughness: 0.5, ..glass.clone() };
    assert!(matches!(
        frosted.lobe(&SurfaceInputs::default(), FRAME, Vec3::Z, &at(550.0), 0.5).bsdf,
        Bsdf::RoughDielectric { ior: 1.5, alpha: 0.25, .. }
    ));
    let pane = Material { thin: true, ..frosted };
    assert_eq!(
        pane.lobe(&SurfaceInputs::default(), FRAME, Vec3::Z, &at(550.0), 0.5).bsdf,
        Bsdf::RoughThinDielectric { ior: 1.5, alpha: 0.25, tint: Vec4::splat(0.8), depth: Vec4::ZERO }
    );
    let clear_pane = Material { roughness: 0.0, ..pane };
    assert_eq!(
        clear_pane.lobe(&SurfaceInputs::default(), FRAME, Vec3::Z, &at(550.0), 0.5).bsdf,
        Bsdf::ThinDielectric { ior: 1.5, tint: Vec4::splat(0.8), depth: Vec4::ZERO }
    );
    assert!(!glass.is_dispersive());
    let flint = Material { ior: Dispersion::glass("SF11").unwrap(), ..glass };
    assert!(flint.is_dispersive());
    let (blue, red) = (
        flint.lobe(&SurfaceInputs::default(), FRAME, Vec3::Z, &at(450.0), 0.5).bsdf,
        flint.lobe(&SurfaceInputs::default(), FRAME, Vec3::Z, &at(650.0), 0.5).bsdf,
    );
    assert!(
        matches!((blue, red), (Bsdf::Dielectric { ior: b, .. }, Bsdf::Dielectric { ior: r, .. }) if b > r + 0.02)
    );
    let mirror = Material { metallic: 1.0, roughness: 0.0, ..Material::default_grey() };
    assert!(matches!(
        mirror.lobe(&SurfaceInputs::default(), FRAME, Vec3::Z, &at(550.0), 0.5).bsdf,
        Bsdf::Conductor { .. }
    ));
    let rough = Material { metallic: 1.0, roughness: 0.5, ..Material::default_grey() };
    assert!(matches!(
        rough.lobe(&SurfaceInputs::default(), FRAME, Vec3::Z, &at(550.0), 0.5).bsdf,
        Bsdf::RoughConductor { alpha: 0.25, .. }
    ));
    let half = Material { metallic: 0.5, ..Material::default_grey() };
    assert!(matches!(
        half.lobe(&SurfaceInputs::default(), FRAME, Vec3::Z, &at(550.0), 0.7).bsdf,
        Bsdf::Diffuse { .. }
    ));
}
