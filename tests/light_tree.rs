//! The light tree (`--light-sampling tree`, the default) against choosing lights by power alone:
//! the same image within noise on the demo scene and on the many-light scene (2400 small bulbs),
//! and the same bits with any thread count.

mod common;

use caustic::render::LightSampling;
use common::*;

/// `scene` at 64x48 with `passes` passes, its lights chosen by `sampling`.
fn render_with(scene: &str, sampling: LightSampling, passes: u64, threads: usize) -> Image {
    let dir = tempfile::tempdir().unwrap();
    let mut settings = settings(&bundled_scene(scene), dir.path(), passes);
    settings.resolution = Some([64, 48]);
    settings.light_sampling = sampling;
    render(&settings, threads)
}

/// The tree's image equals power sampling's: the whole image's mean within 2%, and each 8x8
/// block's within 4 / sqrt(passes) (the two images' noise together), or 0.003 where dark.
fn assert_same_image(scene: &str, passes: u64) {
    let tree = render_with(scene, LightSampling::Tree, passes, 2);
    let power = render_with(scene, LightSampling::Power, passes, 2);
    let (a, b) = (tree.luminance(0, 64, 0, 48), power.luminance(0, 64, 0, 48));
    assert!((a / b - 1.0).abs() < 0.02, "{scene}: mean luminance {a} with the tree, {b} by power");
    let (tree, power) = (block_means(&tree, 8), block_means(&power, 8));
    let tolerance = 4.0 / (passes as f64).sqrt();
    for y in 0..tree.height {
        for x in 0..tree.width {
            let (a, b) = (tree.luminance(x, x + 1, y, y + 1), power.luminance(x, x + 1, y, y + 1));
            assert!(
                (a - b).abs() <= (tolerance * b).max(0.003),
                "{scene}: block ({x}, {y}): {a} with the tree, {b} by power"
            );
        }
    }
}

#[test]
fn the_tree_renders_the_demo_as_power_sampling_does() {
    assert_same_image("cornell_glass.gltf", 256);
}

#[test]
fn the_tree_renders_many_lights_as_power_sampling_does() {
    assert_same_image("many_lights.gltf", 256);
}

#[test]
fn the_tree_gives_the_same_bits_with_any_thread_count() {
    let one = render_with("many_lights.gltf", LightSampling::Tree, 4, 1);
    let two = render_with("many_lights.gltf", LightSampling::Tree, 4, 2);
    assert_eq!(one.rgb, two.rgb);
}
