//! Knaus & Zwicker's convergence rates, measured: with the radius sequence of parameter alpha,
//! the variance of the average falls like N^-alpha and the bias like N^-(1 - alpha).

mod common;

use common::*;
use serde_json::json;

/// The mean of channel `name` of an EXR.
fn mean_channel(path: &std::path::Path, name: &str) -> f64 {
    let image = exr::prelude::read_all_flat_layers_from_file(path).unwrap();
    let channel = image.layer_data[0].channel_data.list.iter().find(|c| c.name.to_string() == name).unwrap();
    let values: Vec<f32> = channel.sample_data.values_as_f32().collect();
    values.iter().map(|&v| f64::from(v)).sum::<f64>() / values.len() as f64
}

/// Least-squares slope of log(y) against log(x).
fn log_slope(points: &[(f64, f64)]) -> f64 {
    let logs: Vec<(f64, f64)> = points.iter().map(|&(x, y)| (x.ln(), y.ln())).collect();
    let n = logs.len() as f64;
    let (mx, my) = (logs.iter().map(|p| p.0).sum::<f64>() / n, logs.iter().map(|p| p.1).sum::<f64>() / n);
    let sxy: f64 = logs.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: f64 = logs.iter().map(|p| (p.0 - mx).powi(2)).sum();
    sxy / sxx
}

/// A spot light with a smooth falloff shines through a glass slab onto a white floor: the floor
/// under the slab is lit only by photons (its shadow for direct light), smoothly curved inside
/// and cut sharply at the slab's edge (a caustic edge). The camera, under the slab, sees the
/// curved interior.
/// Over 8 seeds of 60,000 photons a pass at 16, 64 and 256 passes (first radius 0.3, alpha 2/3):
/// the variance of the average must fall with slope -alpha = -0.667, and the bias with slope
/// -(1 - alpha) = -0.333, each within 0.15. The bias is measured without a reference: if it
/// falls like N^-b, the seeds' means at N, 4N and 16N differ by c N^-b (1 - 4^-b) and
/// c (4N)^-b (1 - 4^-b), so the ratio of those differences is 4^-b. The variance is each render's
/// own estimate from its passes (Variance.Y, averaged over pixels and seeds; it matches the spread
/// across seeds, see src/error.rs), because 8 seeds of strongly correlated pixels (the kernel
/// covers the view) would measure it only to about 40%.
#[test]
fn variance_and_bias_fall_at_knaus_and_zwickers_rates() {
    let dir = tempfile::tempdir().unwrap();
    let mut gltf = GltfBuilder::default();
    let floor = gltf.material(diffuse([1.0, 1.0, 1.0]));
    gltf.quad_y("Floor", 0.0, 4.0, true, floor);
    let glass = gltf.material(json!({"pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.0},
        "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1.0}}}));
    gltf.mesh("Slab", &box_triangles([-0.6, 0.5, -0.6], [0.6, 0.6, 0.6]), glass);
    let spot = json!({"type": "spot", "intensity": 100.0 * 683.0, "spot": {"innerConeAngle": 0.0, "outerConeAngle": 0.6}});
    gltf.light(spot, [0.0, 2.0, 0.0], [0.0, -1.0, 0.0]);
    // Under the slab, so that camera paths do not cross the glass (its Fresnel choices would add
    // noise that falls like 1/N whatever the radius).
    gltf.camera([0.0, 0.4, 0.0], [0.0, -1.0, 0.0], 0.5);
    gltf.scene_extras(json!({"resolution": [16, 16]}));
    let path = gltf.write(dir.path(), "slab");
    let seeds = 8u64;
    let mut means = Vec::new();
    let mut variances = Vec::new();
    for passes in [16u64, 64, 256] {
        let mut estimated_variance = 0.0;
        let images: Vec<Image> = (0..seeds)
            .map(|seed| {
                let out = dir.path().join(format!("{passes}_{seed}"));
                let mut s = settings(&path, &out, passes);
                s.photons = Some(60_000);
                s.radius = Some(0.3);
                s.seed = 1 + seed;
                let image = render(&s, 2);
                estimated_variance += mean_channel(&out.join("frame_0001.exr"), "Variance.Y") / seeds as f64;
                image
            })
            .collect();
        let pixels = images[0].rgb.len();
        let luminance = |image: &Image, i: usize| image.luminance(i % 16, i % 16 + 1, i / 16, i / 16 + 1);
        let (mut mean_sum, mut variance_sum) = (0.0, 0.0);
        for i in 0..pixels {
            let values: Vec<f64> = images.iter().map(|image| luminance(image, i)).collect();
            let mean = values.iter().sum::<f64>() / seeds as f64;
            mean_sum += mean;
            variance_sum += values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (seeds - 1) as f64;
        }
        eprintln!(
            "{passes} passes: image mean {:.5}, per-pixel variance across seeds {:.3e}, estimated within renders {estimated_variance:.3e}",
            mean_sum / pixels as f64,
            variance_sum / pixels as f64
        );
        means.push(mean_sum / pixels as f64);
        variances.push((passes as f64, estimated_variance));
    }
    let variance_slope = log_slope(&variances);
    let (d1, d2) = (means[0] - means[1], means[1] - means[2]);
    let bias_slope = (d2 / d1).ln() / 4f64.ln();
    eprintln!("slopes: variance {variance_slope:.3} (expected -0.667), bias {bias_slope:.3} (expected -0.333); differences {d1:.3e}, {d2:.3e}");
    assert!((variance_slope + 2.0 / 3.0).abs() < 0.15, "variance slope {variance_slope:.3}");
    assert!((bias_slope + 1.0 / 3.0).abs() < 0.15, "bias slope {bias_slope:.3}");
}
