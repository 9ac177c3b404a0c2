//! Progressive convergence: more passes bring the image closer to a converged one.

mod common;

use common::*;

/// The demo scene at 64x48: the RMSE against a render 16 times longer than the longest (1024
/// passes) must fall as the passes grow from 4 to 16 to 64, each step by at least 20% (SPPM
/// error falls roughly as passes^(-1/3) to passes^(-1/2), i.e. 37% to 50% per factor of 4).
#[test]
fn error_falls_as_passes_grow() {
    let dir = tempfile::tempdir().unwrap();
    let render_passes = |passes: u64, seed: u64| {
        let out = dir.path().join(format!("{passes}_{seed}"));
        let mut s = settings(&bundled_scene("cornell_glass.gltf"), &out, passes);
        s.resolution = Some([64, 48]);
        s.seed = seed;
        render(&s, 2)
    };
    let reference = render_passes(1024, 99);
    let errors: Vec<f64> = [4, 16, 64].iter().map(|&n| render_passes(n, 1).rmse(&reference)).collect();
    for pair in errors.windows(2) {
        assert!(pair[1] < 0.8 * pair[0], "RMSE did not fall enough: {errors:?}");
    }
}
