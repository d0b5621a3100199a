//! The same scene gives bit-identical results with 1 and 2 threads.

use tumble::scene::Scene;
use tumble::sim::engine::Simulation;

fn run(threads: usize, text: &str) -> (Vec<Vec<f64>>, Vec<Vec<f64>>, f64) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| {
        let scene = Scene::parse(text, "det", "det").unwrap();
        let mut sim = Simulation::new(scene).unwrap();
        for _ in 0..5 {
            sim.step().unwrap();
        }
        (
            sim.fields().omega().to_vec(),
            sim.fields().u.clone(),
            sim.sample().energy,
        )
    })
}

#[test]
fn three_d_results_do_not_depend_on_threads() {
    let text = r#"Scene(
        domain: (extent: [1.0, 1.0, 2.0], cells: [16, 16, 32]),
        fluid: (viscosity: 0.001),
        initial: [VortexRing(center: [0.5, 0.5, 0.6], axis: [0.1, 0.0, 1.0], radius: 0.25,
                             core_radius: 0.08, circulation: 1.0)],
    )"#;
    let a = run(1, text);
    let b = run(2, text);
    assert!(a.0 == b.0, "vorticity differs between 1 and 2 threads");
    assert!(a.1 == b.1, "velocity differs between 1 and 2 threads");
    assert_eq!(a.2.to_bits(), b.2.to_bits());
}

#[test]
fn two_d_results_do_not_depend_on_threads() {
    let text = r#"Scene(
        domain: (extent: [1.0, 1.0], cells: [32, 32]),
        initial: [LambOseen(center: [0.4, 0.5], circulation: 1.0, core_radius: 0.1),
                  LambOseen(center: [0.6, 0.5], circulation: 0.5, core_radius: 0.08)],
    )"#;
    let a = run(1, text);
    let b = run(2, text);
    assert!(a.0 == b.0 && a.1 == b.1);
}
