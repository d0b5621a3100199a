//! Time stepping of `tumble run`: a `Fixed` step is the step asked for, whatever the output
//! times (snapshots come after the first step at or after each output time); and the timings
//! of a run cover the steps only, in every mode.

use std::fs;
use std::path::{Path, PathBuf};

use tumble::run::{RunOptions, RunSummary, run_scene};
use tumble::scene::Scene;
use tumble::sim::engine::Simulation;

use crate::common::Scratch;

/// This file's scratch directories.
fn scratch(test: &str) -> Scratch {
    Scratch::new("timestep", test)
}

const DT: f64 = 0.007;
const END: f64 = 0.2;

/// A vortex and a heavy disk falling in a cavity, with a fixed step that divides neither the
/// output interval nor the end time. `OUTPUT` is replaced by each test's `output: (...)`.
const FIXED: &str = r#"Scene(
    name: "fixed-dt",
    domain: (extent: [1.0, 1.0], cells: [32, 32]),
    fluid: (viscosity: 0.01, gravity: [0.0, -9.81]),
    numerics: (dt: Fixed(0.007), end_time: 0.2),
    contact: (kappa: 30.0),
    initial: [LambOseen(center: [0.3, 0.6], circulation: 0.2, core_radius: 0.08)],
    bodies: [
        (name: "cavity", shape: Complement(Rectangle(half_extents: [0.45, 0.45])), kind: Static,
         position: [0.5, 0.5]),
        (name: "disk", shape: Disk(radius: 0.1), density: 2.0, position: [0.5, 0.4]),
    ],
    OUTPUT,
)"#;

fn run(dir: &Path, name: &str, text: &str) -> (RunSummary, PathBuf) {
    let scene = Scene::parse(text, name, name).unwrap();
    let out = dir.join(name);
    let opts = RunOptions {
        out: Some(out.clone()),
        quiet: true,
        ..Default::default()
    };
    (run_scene(scene, &opts).unwrap(), out)
}

/// The `timestep` attributes of `fields.pvd`, in order.
fn pvd_times(dir: &Path) -> Vec<f64> {
    let text = fs::read_to_string(dir.join("fields.pvd")).unwrap();
    text.split("timestep=\"")
        .skip(1)
        .map(|s| s[..s.find('"').unwrap()].parse().unwrap())
        .collect()
}

/// The (t, dt) columns of `series.csv`.
fn series_times(dir: &Path) -> Vec<(f64, f64)> {
    let text = fs::read_to_string(dir.join("series.csv")).unwrap();
    text.lines()
        .skip(1)
        .map(|l| {
            let mut c = l.split(',').map(|x| x.parse::<f64>().unwrap());
            (c.next().unwrap(), c.next().unwrap())
        })
        .collect()
}

#[test]
fn fixed_dt_does_not_depend_on_output_times() {
    let d = scratch("every");
    let outputs = [
        ("every-0.1", "output: (every: 0.1)"),
        ("every-0.05", "output: (every: 0.05)"),
        ("every-none", "output: ()"),
    ];
    let runs: Vec<(RunSummary, PathBuf)> = outputs
        .iter()
        .map(|(name, o)| run(d.path(), name, &FIXED.replace("OUTPUT", o)))
        .collect();

    // Every step is the step asked for, the last one too: 0.2 / 0.007 = 28.6, so the run ends
    // after 29 steps at 29 dt = 0.203, the first step at or after the end time.
    let series = series_times(&runs[0].1);
    assert_eq!(series.len(), 1 + 29, "the t = 0 row and 29 steps");
    for (k, &(_, dt)) in series[1..].iter().enumerate() {
        assert_eq!(dt.to_bits(), DT.to_bits(), "step {}", k + 1);
    }
    assert!(
        series[29].0 >= END && series[29].0 < END + DT,
        "ends at {}",
        series[29].0
    );

    // The result does not depend on the outputs: every row of the time series, of the body
    // series and the final state, bit for bit.
    let read = |dir: &Path, f: &str| fs::read_to_string(dir.join(f)).unwrap();
    for (k, (summary, dir)) in runs.iter().enumerate().skip(1) {
        for f in ["series.csv", "bodies.csv", "contacts.csv"] {
            assert_eq!(read(dir, f), read(&runs[0].1, f), "{f} of {}", outputs[k].0);
        }
        assert_eq!(summary.steps, runs[0].0.steps);
        let (a, b) = (summary.last, runs[0].0.last);
        for (x, y) in [
            (a.t, b.t),
            (a.energy, b.energy),
            (a.enstrophy, b.enstrophy),
            (a.circulation, b.circulation),
            (a.max_omega, b.max_omega),
        ] {
            assert_eq!(x.to_bits(), y.to_bits(), "{}", outputs[k].0);
        }
    }
    // The disk fell: the body series is not trivially equal.
    assert!(runs[0].0.last.energy > 0.0);

    // Snapshots: at t = 0, after the first step at or after each output time (with that
    // step's time), and at the end.
    let step_times: Vec<f64> = series.iter().map(|s| s.0).collect();
    for (k, every) in [Some(0.1), Some(0.05), None].into_iter().enumerate() {
        let name = outputs[k].0;
        let times = pvd_times(&runs[k].1);
        let mut want = vec![0.0];
        if let Some(e) = every {
            let mut o = e;
            while o < END - 1e-9 {
                let k = step_times.iter().position(|&t| t >= o).unwrap();
                assert!(step_times[k - 1] < o);
                want.push(step_times[k]);
                o += e;
            }
        }
        want.push(*step_times.last().unwrap());
        assert_eq!(times.len(), want.len(), "{name}: {times:?}");
        for (t, w) in times.iter().zip(&want) {
            assert!((t - w).abs() < 1e-12, "{name}: snapshot at {t}, want {w}");
        }
    }
    // every 0.05 with dt = 0.007: the steps ending at 8, 15 and 22 dt are not output times.
    let t05 = pvd_times(&runs[1].1);
    for (t, k) in t05[1..4].iter().zip([8.0, 15.0, 22.0]) {
        assert!((t - k * DT).abs() < 1e-12, "{t}");
    }
}

/// A heavy disk dropped on a floor in vacuum (no flow solve).
const VACUUM: &str = r#"Scene(
    name: "timings-vacuum",
    domain: (extent: [1.0, 1.0], cells: [64, 64]),
    fluid: (gravity: [0.0, -10.0]),
    vacuum: true,
    contact: (kappa: 1.0),
    numerics: (dt: Fixed(0.001), end_time: 0.3),
    bodies: [
        (name: "floor", shape: HalfSpace(normal: [0.0, 1.0, 0.0], offset: 0.0), kind: Static,
         position: [0.5, 0.05]),
        (name: "disk", shape: Disk(radius: 0.1), position: [0.5, 0.3]),
    ],
    output: (every: 0.1, fields: []),
)"#;

/// A `Fixed` step that divides the end time takes exactly end / dt steps of dt, although the
/// clock (a sum of steps) misses the end time by a few ulps without output times to land on.
#[test]
fn fixed_dt_dividing_the_end_time_takes_whole_steps() {
    let d = scratch("whole");
    let text = VACUUM
        .replace("Fixed(0.001), end_time: 0.3", "Fixed(0.005), end_time: 1.5")
        .replace("every: 0.1", "every: 0.5");
    let (summary, dir) = run(d.path(), "whole", &text);
    assert_eq!(summary.steps, 300);
    let series = series_times(&dir);
    for &(_, dt) in &series[1..=300] {
        assert_eq!(dt.to_bits(), 0.005f64.to_bits());
    }
    // The clock is a sum of 300 steps: it reaches 1.5 to rounding.
    assert!((summary.last.t - 1.5).abs() < 1e-12, "{}", summary.last.t);
}

/// The fluid alone (no bodies).
const FLUID: &str = r#"Scene(
    name: "timings-fluid",
    domain: (extent: [1.0, 1.0], cells: [64, 64]),
    fluid: (viscosity: 0.01),
    numerics: (dt: Adaptive(c: 0.5, dt_max: 0.01), end_time: 0.1),
    initial: [LambOseen(center: [0.5, 0.5], circulation: 0.2, core_radius: 0.1)],
    output: (every: 0.05),
)"#;

/// Timings of a run cover the steps it ran: only systems of the step schedule (no start-up
/// system such as the initial Poisson solve), each of them, and no more time than the wall.
#[test]
fn timings_cover_the_steps_only() {
    let d = scratch("timings");
    let bodies = FIXED.replace("OUTPUT", "output: (every: 0.1)");
    for (name, text, mode) in [
        ("vacuum", VACUUM, "vacuum"),
        ("fluid", FLUID, "fluid"),
        ("bodies", bodies.as_str(), "bodies"),
    ] {
        let scene = Scene::parse(text, name, name).unwrap();
        let sim = Simulation::new(scene.clone()).unwrap();
        let step_systems: Vec<&str> = sim.step_systems().to_vec();
        assert_eq!(
            step_systems.contains(&"poisson"),
            mode != "vacuum",
            "{mode}: {step_systems:?}"
        );
        // After start-up the timings are the start-up systems'; after a step, the step's.
        let startup: Vec<&str> = sim.timings().last.iter().map(|e| e.0).collect();
        assert!(startup.contains(&"poisson"), "{mode}: {startup:?}");
        let mut sim = sim;
        sim.step().unwrap();
        let names: Vec<&str> = sim.timings().last.iter().map(|e| e.0).collect();
        assert_eq!(names, step_systems, "{mode}: the systems of one step");

        let (summary, dir) = run(d.path(), name, text);
        let names: Vec<&str> = summary.system_seconds.iter().map(|e| e.0).collect();
        assert_eq!(names, step_systems, "{mode}: the systems of the run");
        let sum: f64 = summary.system_seconds.iter().map(|e| e.1).sum();
        assert!(
            sum <= summary.wall,
            "{mode}: {sum} s in systems, {} s wall",
            summary.wall
        );
        assert!(summary.steps_run > 0);
        // timings.csv lists the same systems, per step the total over the steps run.
        let csv = fs::read_to_string(dir.join("timings.csv")).unwrap();
        let rows: Vec<Vec<&str>> = csv
            .lines()
            .skip(1)
            .map(|l| l.split(',').collect())
            .collect();
        assert_eq!(rows.len(), step_systems.len(), "{mode}: {csv}");
        for (row, (n, total)) in rows.iter().zip(&summary.system_seconds) {
            assert_eq!(row[0], *n);
            let t: f64 = row[1].parse().unwrap();
            let per: f64 = row[2].parse().unwrap();
            assert!((t - total).abs() <= 1e-6, "{mode}: {row:?}");
            assert!(
                (per - total / summary.steps_run as f64).abs() <= 1e-6,
                "{mode}: {row:?}"
            );
        }
    }
}

/// A flow that starts at rest has no initial vorticity for the relative guard to compare
/// with: under gravity its speed is bounded by the free fall across the box (√(2 |g| L) = 2
/// here), and a run whose speed passes √blowup_factor times that stops with a blow-up naming
/// it instead of crawling on at a collapsing time step.
#[test]
fn a_flow_from_rest_that_passes_the_free_fall_speed_stops() {
    let text = r#"Scene(
    name: "rest",
    domain: (extent: [1.0, 1.0], cells: [32, 32]),
    fluid: (density: 1.0, viscosity: 0.01, gravity: [0.0, -2.0]),
    numerics: (end_time: 1.0, blowup_factor: 100.0),
    bodies: [
        (name: "disk", shape: Disk(radius: 0.1), density: 2.0, position: [0.5, 0.6]),
    ],
)"#;
    let scene = Scene::parse(text, "rest.ron", "rest").unwrap();
    let mut sim = Simulation::new(scene).unwrap();
    // Falling: well under the limit (10 times the free fall, 20).
    for _ in 0..5 {
        sim.step().unwrap();
    }
    assert!(sim.sample().max_u < 2.0);
    // A vortex of peak speed about 100, as if the run had blown up.
    let grid = sim.grid().clone();
    let mut fields = sim.world.resource_mut::<tumble::base::fields::Fields>();
    let w = &mut fields.omega_mut()[0];
    for j in 0..32 {
        for i in 0..32 {
            let (x, y) = ((i as f64 + 0.5) / 32.0 - 0.3, (j as f64 + 0.5) / 32.0 - 0.3);
            w[grid.idx(i, j, 0)] += 2e4 * (-(x * x + y * y) / 0.005).exp();
        }
    }
    let e = sim.step().unwrap_err().to_string();
    assert!(e.contains("free fall"), "{e}");
}

/// Landing on a stop time splits the time left evenly over the fewest steps no longer than the
/// policy's step (Basilisk's `dtnext`): no sliver step before an output time, and the step
/// shrinks by at most dt / (n + 1) with n steps to go.
#[test]
fn landing_evens_out_the_steps_before_a_stop_time() {
    use tumble::systems::diagnostics::land_on;
    let dt = 0.1;
    for rest in [0.05, 0.1, 0.1000000001, 0.15, 0.2001, 0.95, 1.05, 3.333] {
        let (mut t, mut steps) = (0.0, Vec::new());
        while t < rest * (1.0 - 1e-12) {
            let s = land_on(t, dt, Some(rest));
            steps.push(s);
            t += s;
        }
        let n = (rest / dt - 1e-6).ceil().max(1.0);
        assert_eq!(steps.len() as f64, n, "rest {rest}: {steps:?}");
        assert!((t - rest).abs() < 1e-12, "rest {rest}: lands at {t}");
        for &s in &steps {
            assert!(s <= dt * (1.0 + 1e-6), "rest {rest}: step {s} beyond dt");
            assert!(
                (s - rest / n).abs() < 1e-12,
                "rest {rest}: uneven steps {steps:?}"
            );
        }
    }
    assert_eq!(land_on(0.3, dt, None), dt);
    assert_eq!(land_on(0.3, dt, Some(0.2)), dt);
}
