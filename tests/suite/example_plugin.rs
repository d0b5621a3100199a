//! The example plugin of `examples/passive_scalar.rs` (a new physics system in one file,
//! registered with one `add_plugin` line): it runs a bundled scene, writes its field,
//! conserves its mass, stays non-negative, and restarts bit for bit from a checkpoint through
//! the generic serde state path.

#[allow(dead_code)]
#[path = "../../examples/passive_scalar.rs"]
mod passive_scalar;

use std::path::Path;
use tumble::io::checkpoint::Checkpoint;
use tumble::scene::{Scene, ValidScene};
use tumble::sim::engine::Simulation;

fn scene() -> ValidScene {
    Scene::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/taylor-green-2d.ron")).unwrap()
}

#[test]
fn passive_scalar_runs_conserves_and_restarts_bit_for_bit() {
    let out = std::env::temp_dir().join(format!("tumble-example-plugin-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let r = passive_scalar::run(&scene(), &out, 0.5).unwrap();
    assert!(r.steps >= 5, "{} steps", r.steps);
    assert!(r.restart_identical, "the restarted run differs");

    // Initial mass: the Gaussian's integral 2π σ² (2D); the blob's periodic images are 6.25 σ
    // away at the nearest, so the truncated tail is below exp(-6.25²/2) ≈ 3e-9, and the
    // trapezoidal rule on a smooth periodic function is exact to that level.
    let exact = 2.0 * std::f64::consts::PI * r.sigma * r.sigma;
    assert!(
        ((r.mass0 - exact) / exact).abs() < 1e-7,
        "initial mass {} against 2 pi sigma^2 = {exact}",
        r.mass0
    );
    // Conservation: the face fluxes telescope exactly, so only rounding changes the mass, at
    // most a few ulps of each node value per sub-step plus the two summations:
    // (4 substeps + 2) N ε relative.
    let bound = (4.0 * r.substeps as f64 + 2.0) * r.nodes as f64 * f64::EPSILON;
    let drift = ((r.mass - r.mass0) / r.mass0).abs();
    assert!(
        drift <= bound,
        "mass drift {drift:e} over the bound {bound:e}"
    );
    // Positivity under the sub-step limit (non-negative weights).
    assert!(r.min >= 0.0, "min c = {}", r.min);

    // The field and the mass series are written.
    let csv = std::fs::read_to_string(out.join("scalar.csv")).unwrap();
    assert_eq!(csv.lines().next(), Some("t,mass,min,max"));
    assert_eq!(csv.lines().count() as u64, r.steps + 2);
    assert!(out.join("scalar.vti").metadata().unwrap().len() > 8 * r.nodes as u64);

    // The checkpoint holds the plugin's record: a simulation without the plugin refuses it,
    // naming the record.
    let ck = Checkpoint::from_bytes(&r.checkpoint, &out.join("memory")).unwrap();
    assert!(ck.state.iter().any(|s| s.name == "passive_scalar"));
    let mut plain = Simulation::new(scene()).unwrap();
    let err = ck.restore(&mut plain).unwrap_err().to_string();
    assert!(err.contains("passive_scalar"), "{err}");
    let _ = std::fs::remove_dir_all(&out);
}
