//! Checkpoint and restart: a run stopped and restarted gives results identical bit for bit to
//! the run that never stopped (in memory and through the command line, also after SIGKILL and
//! SIGINT), and bad checkpoints are refused with exit status 2.

#[allow(dead_code)]
#[path = "suite/common.rs"]
mod common;
#[allow(dead_code)]
#[path = "suite/vti.rs"]
mod vti;

use common::Scratch;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::OnceLock;
use std::time::{Duration, Instant};
use tumble::io::checkpoint::{self, BodyState, Checkpoint, RunProgress};
use tumble::scene::Scene;
use tumble::sim::engine::Simulation;

/// 2D: a heavy disk thrown at the floor of a static cavity (contact from the first step), a
/// kinematic paddle oscillating and turning, a vortex, adaptive time step.
const BOX_2D: &str = r#"Scene(
    name: "box2d",
    domain: (origin: [-0.0625, -0.0625], extent: [1.125, 1.125], h: 0.015625),
    fluid: (density: 1.0, viscosity: 0.01, gravity: [0.0, -10.0]),
    numerics: (dt: Adaptive(c: 0.5, dt_max: 0.004), end_time: 0.3),
    contact: (kappa: 30.0),
    initial: [LambOseen(center: [0.3, 0.6], circulation: 0.2, core_radius: 0.08)],
    bodies: [
        (name: "cavity", shape: Complement(Rectangle(half_extents: [0.5, 0.5])), kind: Static,
         position: [0.5, 0.5]),
        (name: "disk", shape: Disk(radius: 0.1), density: 1.5, position: [0.45, 0.125],
         velocity: [0.1, -0.5]),
        (name: "paddle", shape: Rectangle(half_extents: [0.08, 0.03]),
         kind: Kinematic(velocity: [0.0, 0.0], angular_velocity: [1.0], amplitude: [0.2, 0.0],
                         frequency: 2.0),
         position: [0.7, 0.7]),
    ],
    output: (every: 0.1),
)"#;

/// 3D, 32³: a heavy sphere thrown at the floor of a static box, a kinematic sphere turning, a
/// vortex ring.
const BOX_3D: &str = r#"Scene(
    name: "box3d",
    domain: (extent: [1.0, 1.0, 1.0], h: 0.03125),
    fluid: (density: 1.0, viscosity: 0.01, gravity: [0.0, 0.0, -10.0]),
    numerics: (dt: Adaptive(c: 0.5, dt_max: 0.004), end_time: 1.0),
    contact: (kappa: 30.0),
    initial: [VortexRing(center: [0.5, 0.5, 0.6], axis: [0.1, 0.0, 1.0], radius: 0.2,
                         core_radius: 0.06, circulation: 0.5)],
    bodies: [
        (name: "box", shape: Complement(Box(half_extents: [0.4, 0.4, 0.4])), kind: Static,
         position: [0.5, 0.5, 0.5]),
        (name: "ball", shape: Sphere(radius: 0.12), density: 2.0, position: [0.45, 0.5, 0.25],
         velocity: [0.1, 0.0, -0.5], angular_velocity: [0.0, 1.0, 0.0]),
        (name: "spinner", shape: Ellipsoid(radii: [0.1, 0.06, 0.05]),
         kind: Kinematic(velocity: [0.0, 0.0, 0.0], angular_velocity: [0.0, 0.0, 2.0]),
         position: [0.5, 0.5, 0.72]),
    ],
)"#;

/// Vacuum, 3D: a spinning ellipsoid drops on a floor next to a sphere (contact, angular
/// momentum carried by the free motion).
const VACUUM_3D: &str = r#"Scene(
    name: "vacuum3d",
    domain: (extent: [1.0, 1.0, 1.0], h: 0.03125),
    fluid: (gravity: [0.0, 0.0, -1.0]),
    vacuum: true,
    contact: (kappa: 5.0),
    numerics: (dt: Fixed(0.003125), end_time: 1.0),
    bodies: [
        (name: "floor", shape: HalfSpace(normal: [0.0, 0.0, 1.0], offset: 0.0), kind: Static,
         position: [0.5, 0.5, 0.1]),
        (name: "ellipsoid", shape: Ellipsoid(radii: [0.2, 0.1, 0.08]), density: 1.0,
         position: [0.5, 0.5, 0.23], rotation: [0.0, 0.3, 0.0],
         velocity: [0.0, 0.0, -0.4], angular_velocity: [1.0, 2.0, 3.0]),
        (name: "ball", shape: Sphere(radius: 0.1), density: 2.0, position: [0.5, 0.78, 0.22],
         velocity: [0.0, -0.3, 0.0]),
    ],
)"#;

fn sim(text: &str) -> Simulation {
    Simulation::new(Scene::parse(text, "test", "test").unwrap()).unwrap()
}

fn bits<T: Copy + Into<f64>>(f: &[Vec<T>]) -> Vec<Vec<u64>> {
    f.iter()
        .map(|c| c.iter().map(|&x| x.into().to_bits()).collect())
        .collect()
}

/// Every number of a body's state, as bits.
fn body_bits(b: &BodyState) -> (usize, String, Vec<u64>) {
    let r = &b.rigid;
    let mut v: Vec<f64> = Vec::new();
    for x in [r.center, r.velocity, r.angular_velocity, r.centroid] {
        v.extend(x.to_array());
    }
    v.extend(r.orientation.to_array());
    v.push(r.volume);
    v.extend(r.inertia.to_cols_array());
    v.extend(b.hydro.force.to_array());
    v.extend(b.hydro.torque.to_array());
    v.push(b.contact.kappa.unwrap_or(f64::NAN));
    v.extend(b.contact.force.to_array());
    v.extend(b.contact.torque.to_array());
    v.push(b.contact.potential);
    match b.free.angular_momentum {
        Some(l) => v.extend(l.to_array()),
        None => v.push(f64::NAN),
    }
    (
        b.id,
        b.name.clone(),
        v.iter().map(|x| x.to_bits()).collect(),
    )
}

/// The state of `sim` as bits: ω, u, u_prev, the clock, the sample, every body.
#[allow(clippy::type_complexity)]
fn state(
    sim: &mut Simulation,
) -> (
    Vec<Vec<u64>>,
    Vec<Vec<u64>>,
    Vec<Vec<u64>>,
    Vec<u64>,
    Vec<(usize, String, Vec<u64>)>,
) {
    let f = sim.fields();
    let (w, u, up) = (bits(f.omega()), bits(&f.u), bits(&f.u_prev));
    let s = sim.sample();
    let clock = [
        sim.time(),
        sim.world.resource::<tumble::base::fields::SimTime>().dt,
        f.dt_prev,
        s.energy,
        s.enstrophy,
        s.max_omega,
        s.max_u,
    ]
    .iter()
    .map(|x| x.to_bits())
    .chain([sim.steps()])
    .collect();
    let bodies = checkpoint::body_states(sim).iter().map(body_bits).collect();
    (w, u, up, clock, bodies)
}

/// Run `n` steps straight; run `m` steps, checkpoint to bytes, restore into a fresh simulation
/// and run `n - m` more: the two end states must be the same bits.
fn restart_is_bit_for_bit(text: &str, n: usize, m: usize) {
    let mut straight = sim(text);
    for _ in 0..n {
        straight.step().unwrap();
    }
    let mut first = sim(text);
    for _ in 0..m {
        first.step().unwrap();
    }
    let bytes = checkpoint::to_bytes(&mut first, &RunProgress::default());
    let ck = Checkpoint::from_bytes(&bytes, Path::new("memory")).unwrap();
    assert_eq!(ck.time.step, m as u64);
    let mut second = ck.simulation(ck.scene().unwrap()).unwrap();
    assert!(
        state(&mut second) == state(&mut first),
        "the restored state differs from the checkpointed one"
    );
    // The checkpoint of the restored simulation is the same file (the scene round-trips too).
    assert!(checkpoint::to_bytes(&mut second, &RunProgress::default()) == bytes);
    drop(first);
    for _ in m..n {
        second.step().unwrap();
    }
    let (a, b) = (state(&mut straight), state(&mut second));
    assert!(a.0 == b.0, "vorticity differs after the restart");
    assert!(a.1 == b.1, "velocity differs after the restart");
    assert!(a.2 == b.2, "previous velocity differs after the restart");
    assert!(a.3 == b.3, "clock or diagnostics differ after the restart");
    assert_eq!(a.4.len(), b.4.len());
    for (x, y) in a.4.iter().zip(&b.4) {
        assert!(x == y, "body `{}` differs after the restart", x.1);
    }
    assert!(
        checkpoint::to_bytes(&mut straight, &RunProgress::default())
            == checkpoint::to_bytes(&mut second, &RunProgress::default())
    );
}

#[test]
fn restart_2d_pressure_coupling_is_bit_for_bit() {
    // The variable-density projection carries its warm start and the velocity each step
    // ends with (a body's excess mass takes its velocity from it) across the restart.
    let text = BOX_2D.replace(
        "end_time: 0.3),",
        "end_time: 0.3, body_coupling: Pressure),",
    );
    assert!(text.contains("Pressure"));
    restart_is_bit_for_bit(&text, 30, 13);
}

/// A column of liquid collapsing in a closed 2D tank at 1:1000: a free surface, carried in
/// momentum form (mass, momentum and the liquid's level set on the same particles).
const COLUMN_2D: &str = r#"Scene(
    name: "column2d",
    domain: (extent: [3.25, 1.25], h: 0.0625),
    fluid: (density: 1.0, viscosity: 1e-4, gravity: [0.0, -1.0]),
    free_surface: Some((gas_density: 0.001, liquid: [Shape(shape: Rectangle(half_extents: [0.375, 0.5]), position: [0.5, 0.625])])),
    numerics: (end_time: 2.0),
    bodies: [
        (name: "tank", shape: Complement(Rectangle(half_extents: [1.5, 0.5])), kind: Static, position: [1.625, 0.625]),
    ],
)"#;

#[test]
fn restart_2d_free_surface_momentum_form_is_bit_for_bit() {
    // The momentum form keeps nothing of its own across steps (the carried fields are made
    // from the density, the velocity and the level set each step): the velocity, the level set
    // and the pressure's warm start restart it.
    restart_is_bit_for_bit(COLUMN_2D, 30, 11);
}

#[test]
fn restart_2d_bodies_contact_is_bit_for_bit() {
    // The disk is in contact with the floor, so the restart lands mid-contact.
    let mut s = sim(BOX_2D);
    for _ in 0..5 {
        s.step().unwrap();
    }
    let c = s
        .world
        .resource::<tumble::systems::collision::Contacts>()
        .records
        .clone();
    assert!(
        c.iter().any(|r| r.force > 0.0),
        "the test scene should have contact"
    );
    restart_is_bit_for_bit(BOX_2D, 40, 17);
}

#[test]
fn restart_3d_bodies_is_bit_for_bit() {
    restart_is_bit_for_bit(BOX_3D, 12, 5);
}

#[test]
fn restart_vacuum_is_bit_for_bit() {
    let mut s = sim(VACUUM_3D);
    for _ in 0..30 {
        s.step().unwrap();
    }
    let b = checkpoint::body_states(&mut s);
    assert!(b.iter().any(|b| b.free.angular_momentum.is_some()));
    assert!(b.iter().any(|b| b.contact.force.length() > 0.0));
    restart_is_bit_for_bit(VACUUM_3D, 60, 23);
}

#[test]
fn restart_with_the_default_kappa_is_bit_for_bit() {
    // κ left to the scene's default (a body's own κ is stored as NaN then), one body with its
    // own.
    let text = VACUUM_3D
        .replace("    contact: (kappa: 5.0),\n", "")
        .replace("density: 2.0,", "density: 2.0, kappa: 4.0,");
    let mut s = sim(&text);
    for _ in 0..30 {
        s.step().unwrap();
    }
    let b = checkpoint::body_states(&mut s);
    assert!(b.iter().any(|b| b.contact.kappa.is_none()));
    assert!(b.iter().any(|b| b.contact.kappa == Some(4.0)));
    assert!(b.iter().any(|b| b.contact.force.length() > 0.0));
    restart_is_bit_for_bit(&text, 60, 23);
}

// ---- Command line ----

fn tumble() -> Command {
    Command::new(env!("CARGO_BIN_EXE_tumble"))
}

fn tmp(name: &str) -> Scratch {
    Scratch::new("ckpt", name)
}

/// The latest complete checkpoint in the run directory `dir`.
fn latest(dir: &Path) -> PathBuf {
    checkpoint::resolve(dir).unwrap_or_else(|e| panic!("{e}"))
}

fn run(args: &[&str]) -> Output {
    tumble().args(args).output().unwrap()
}

fn ok(o: &Output) {
    assert!(
        o.status.success(),
        "{:?}\n{}",
        o.status,
        String::from_utf8_lossy(&o.stderr)
    );
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// The outputs that must match bit for bit: the time series, the `.pvd` and every snapshot.
fn assert_same_outputs(a: &Path, b: &Path) {
    let mut names: Vec<String> = std::fs::read_dir(a)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .filter(|n| (n.ends_with(".csv") && n != "timings.csv") || n.ends_with(".vti"))
        .collect();
    names.push("fields.pvd".into());
    names.sort();
    assert!(names.iter().any(|n| n == "bodies.csv"));
    for n in &names {
        let (x, y) = (std::fs::read(a.join(n)).unwrap(), std::fs::read(b.join(n)));
        assert!(
            y.as_ref().is_ok_and(|y| *y == x),
            "{n} differs between {} and {}",
            a.display(),
            b.display()
        );
    }
    let count = |d: &Path| std::fs::read_dir(d).unwrap().count();
    let vti = |d: &Path| {
        std::fs::read_dir(d)
            .unwrap()
            .filter(|e| {
                e.as_ref()
                    .unwrap()
                    .file_name()
                    .to_str()
                    .unwrap()
                    .ends_with(".vti")
            })
            .count()
    };
    assert_eq!(vti(a), vti(b), "{} vs {}", count(a), count(b));
    // The slice images (a run with a dynamic body): the same files, the same bytes.
    let slices = |d: &Path| {
        let mut v: Vec<_> = std::fs::read_dir(d.join("slices"))
            .map(|r| r.map(|e| e.unwrap().file_name()).collect())
            .unwrap_or_default();
        v.sort();
        v
    };
    assert_eq!(slices(a), slices(b), "slices/ differs");
    for m in slices(a) {
        let x = std::fs::read(a.join("slices").join(&m)).unwrap();
        let y = std::fs::read(b.join("slices").join(&m));
        assert!(y.is_ok_and(|y| y == x), "slices/{m:?} differs");
    }
}

/// The long 2D run (to t = 3) that the kill and interrupt tests stop and restart, run once
/// without stopping.
const LONG_END: &str = "3.0";

fn scene_file(dir: &Path) -> PathBuf {
    let f = dir.join("box2d.ron");
    std::fs::write(&f, BOX_2D).unwrap();
    f
}

fn reference_long() -> &'static Path {
    // The scratch directory lives as long as the process (statics are not dropped: this one
    // directory stays behind), so the tests that compare against it can share it.
    static REF: OnceLock<(Scratch, PathBuf)> = OnceLock::new();
    &REF.get_or_init(|| {
        let d = tmp("reference");
        let out = d.join("run");
        ok(&run(&[
            "run",
            s(&scene_file(&d)),
            "--out",
            s(&out),
            "--until",
            LONG_END,
            "--quiet",
        ]));
        (d, out)
    })
    .1
}

/// Wait until the run in `dir` has a checkpoint at t ≥ `t` (the child must still be running).
fn wait_for_checkpoint(child: &mut std::process::Child, dir: &Path, t: f64) -> Checkpoint {
    let start = Instant::now();
    loop {
        if let Some(ck) = checkpoint::resolve(dir)
            .ok()
            .and_then(|p| Checkpoint::load(&p).ok())
            && ck.time.t >= t
        {
            return ck;
        }
        assert!(
            child.try_wait().unwrap().is_none(),
            "the run ended before it was stopped"
        );
        assert!(start.elapsed() < Duration::from_secs(60), "no checkpoint");
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// The restarted run's log (`log`) ends with as many steps as the straight run's in `straight`.
fn assert_same_step_count(straight: &std::path::Path, log: &str) {
    let straight_log = std::fs::read_to_string(straight.join("log.txt")).unwrap();
    let steps = |l: &str| {
        l.lines()
            .filter_map(|x| x.split("finished: ").nth(1))
            .filter_map(|x| x.split(' ').next()?.parse::<usize>().ok())
            .next_back()
    };
    assert!(steps(&straight_log).is_some(), "{straight_log}");
    assert_eq!(steps(log), steps(&straight_log), "{log}");
}

#[test]
fn cli_restart_continues_the_run_bit_for_bit() {
    let d = tmp("cli");
    let scene = scene_file(&d);
    let straight = d.join("straight");
    ok(&run(&["run", s(&scene), "--out", s(&straight), "--quiet"]));
    // Stop at t = 0.2 (an output time, so the clock lands there in both runs), then restart
    // to the scene's end.
    let stopped = d.join("stopped");
    ok(&run(&[
        "run",
        s(&scene),
        "--out",
        s(&stopped),
        "--until",
        "0.2",
        "--checkpoint-every",
        "0.07",
        "--quiet",
    ]));
    let ck = latest(&stopped);
    let c = Checkpoint::load(&ck).unwrap();
    assert_eq!(c.time.t, 0.2);
    assert_eq!(c.progress.pvd.len(), 3);
    let o = run(&["run", "--restart", s(&ck), "--until", "0.3", "--quiet"]);
    ok(&o);
    assert_same_outputs(&straight, &stopped);
    let log = std::fs::read_to_string(stopped.join("log.txt")).unwrap();
    assert!(log.contains("restart from"), "{log}");
    assert_same_step_count(&straight, &log);
    // The checkpoint at t = 0.2 was deleted once two later ones were written (t = 0.21 and
    // 0.28 with checkpoints every 0.07, and the end, 0.3).
    assert!(!ck.exists(), "{} was kept", ck.display());
    assert_eq!(Checkpoint::load(&latest(&stopped)).unwrap().time.t, 0.3);
    // The scene file may be given again; it must be the checkpoint's.
    let o = run(&[
        "run",
        s(&scene),
        "--restart",
        s(&stopped),
        "--until",
        "0.35",
    ]);
    ok(&o);
}

/// The numbered checkpoints in `dir`: (step, t), by step.
fn checkpoints(dir: &Path) -> Vec<(u64, f64)> {
    checkpoint::list(dir)
        .unwrap()
        .iter()
        .map(|(step, p)| {
            let c = Checkpoint::load(p).unwrap();
            assert_eq!(c.time.step, *step, "{} is named by its step", p.display());
            (*step, c.time.t)
        })
        .collect()
}

#[test]
fn the_latest_checkpoints_are_kept_and_restart_dir_takes_the_latest() {
    let d = tmp("kept");
    let scene = scene_file(&d);
    let straight = d.join("straight");
    ok(&run(&["run", s(&scene), "--out", s(&straight), "--quiet"]));
    // Checkpoints every 0.03 to t = 0.2 (at t = 0.03, 0.06, ..., 0.18 and the end): 7 are
    // written, the default keeps the last 2.
    // A run directory without checkpoints is refused (status 2), naming it.
    let o = run(&["run", "--restart", s(&straight), "--until", "0.4"]);
    assert_eq!(o.status.code(), Some(2), "{:?}", o.status);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains(&format!("cannot restart from {}", straight.display()))
            && err.contains("no checkpoint"),
        "{err}"
    );
    let stopped = d.join("stopped");
    let args = |out: &Path, kept: Option<&str>| {
        let mut text = BOX_2D.to_string();
        if let Some(k) = kept {
            text = text.replacen("output: (", &format!("output: (checkpoints_kept: {k}, "), 1);
        }
        let f = out.with_extension("ron");
        std::fs::write(&f, text).unwrap();
        f
    };
    let scene2 = args(&stopped, None);
    ok(&run(&[
        "run",
        s(&scene2),
        "--out",
        s(&stopped),
        "--until",
        "0.2",
        "--checkpoint-every",
        "0.03",
        "--quiet",
    ]));
    let ck = checkpoints(&stopped);
    assert_eq!(ck.len(), 2, "{ck:?}");
    assert_eq!(ck[1].1, 0.2, "the last one is the run's end: {ck:?}");
    assert!(ck[0].1 >= 0.18 && ck[0].1 < 0.2, "{ck:?}");
    assert_eq!(
        latest(&stopped),
        stopped.join(checkpoint::file_name(ck[1].0))
    );
    // --restart DIR continues from the latest (t = 0.2) and matches the run that never
    // stopped.
    let o = run(&["run", "--restart", s(&stopped), "--until", "0.3", "--quiet"]);
    ok(&o);
    assert_same_outputs(&straight, &stopped);
    let log = std::fs::read_to_string(stopped.join("log.txt")).unwrap();
    let from = format!(
        "restart from {} at step {}",
        stopped.join(checkpoint::file_name(ck[1].0)).display(),
        ck[1].0
    );
    assert!(log.contains(&from), "{log}");

    // checkpoints_kept: 3 keeps 3, also when a restart goes on (to t = 0.3: checkpoints at
    // 0.21, 0.24, 0.27 and 0.3); other files in the directory are left alone.
    let three = d.join("three");
    let scene3 = args(&three, Some("3"));
    ok(&run(&[
        "run",
        s(&scene3),
        "--out",
        s(&three),
        "--until",
        "0.2",
        "--checkpoint-every",
        "0.03",
        "--quiet",
    ]));
    let ck3 = checkpoints(&three);
    assert_eq!(ck3.len(), 3, "{ck3:?}");
    assert_eq!(&ck3[1..], &ck[..], "the same latest checkpoints");
    let foreign = ["checkpoint_12.bin", "checkpoint_000001.bin.bak", "mine.bin"];
    for name in foreign {
        std::fs::write(three.join(name), b"not tumble's").unwrap();
    }
    ok(&run(&[
        "run",
        "--restart",
        s(&three),
        "--until",
        "0.3",
        "--quiet",
    ]));
    let ck3 = checkpoints(&three);
    assert_eq!(ck3.len(), 3, "{ck3:?}");
    assert_eq!(ck3[2].1, 0.3, "{ck3:?}");
    assert!(ck3[0].1 > 0.2, "{ck3:?}");
    for name in foreign {
        assert!(three.join(name).exists(), "{name} was deleted");
    }
}

#[test]
fn killed_run_leaves_whole_files_and_restarts() {
    let d = tmp("killed");
    let out = d.join("run");
    let mut child = tumble()
        .args([
            "run",
            s(&scene_file(&d)),
            "--out",
            s(&out),
            "--until",
            LONG_END,
            "--checkpoint-every",
            "0.01",
            "--quiet",
        ])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    wait_for_checkpoint(&mut child, &out, 0.3);
    child.kill().unwrap(); // SIGKILL
    child.wait().unwrap();
    // Every file that is not a temporary is whole.
    let ck = Checkpoint::load(&latest(&out)).unwrap();
    assert!(ck.time.t >= 0.3 && ck.time.t < 3.0);
    let pvd = std::fs::read_to_string(out.join("fields.pvd")).unwrap();
    assert!(pvd.trim_end().ends_with("</VTKFile>"), "{pvd}");
    let listed = pvd.matches("<DataSet").count();
    assert!(listed >= ck.progress.pvd.len());
    for e in std::fs::read_dir(&out).unwrap() {
        let name = e.unwrap().file_name().into_string().unwrap();
        if checkpoint::is_temp_file(&name) {
            continue;
        }
        if name.ends_with(".vti") {
            let v =
                vti::read_vti(&out.join(&name)).unwrap_or_else(|e| panic!("{name} is torn: {e}"));
            assert!(v.time.is_some());
        }
        if name == "scene.ron" {
            Scene::load(&out.join(&name)).unwrap();
        }
    }
    let o = run(&["run", "--restart", s(&latest(&out)), "--quiet"]);
    ok(&o);
    for e in std::fs::read_dir(&out).unwrap() {
        let name = e.unwrap().file_name().into_string().unwrap();
        assert!(!checkpoint::is_temp_file(&name), "{name} left behind");
    }
    assert_same_outputs(reference_long(), &out);
}

#[test]
fn sigint_stops_with_a_checkpoint_and_restarts() {
    let d = tmp("sigint");
    let out = d.join("run");
    let mut child = tumble()
        .args([
            "run",
            s(&scene_file(&d)),
            "--out",
            s(&out),
            "--until",
            LONG_END,
            "--checkpoint-every",
            "0.5",
            "--quiet",
        ])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // The first checkpoint shows the run is in its loop (the handler is installed).
    wait_for_checkpoint(&mut child, &out, 0.5);
    let k = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(k.success());
    let o = child.wait_with_output().unwrap();
    assert_eq!(o.status.code(), Some(130), "{:?}", o.status);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        stderr.contains("restart with tumble run --restart"),
        "{stderr}"
    );
    let ck = Checkpoint::load(&latest(&out)).unwrap();
    assert!(ck.time.t < 3.0, "the run was not stopped early");
    let log = std::fs::read_to_string(out.join("log.txt")).unwrap();
    let line = format!("interrupted at step {}, t = {}", ck.time.step, ck.time.t);
    assert!(log.contains(&line), "{log}");
    // Rows up to the checkpoint only (flushed).
    let rows = std::fs::read_to_string(out.join("series.csv")).unwrap();
    assert_eq!(rows.lines().count() as u64, ck.time.step + 2);
    let o = run(&["run", "--restart", s(&latest(&out)), "--quiet"]);
    ok(&o);
    assert_same_outputs(reference_long(), &out);
}

#[test]
fn bad_checkpoints_are_refused() {
    let d = tmp("bad");
    let scene = scene_file(&d);
    let out = d.join("run");
    ok(&run(&[
        "run",
        s(&scene),
        "--out",
        s(&out),
        "--until",
        "0.1",
        "--checkpoint-every",
        "0.05",
        "--quiet",
    ]));
    let good_path = latest(&out);
    let good = std::fs::read(&good_path).unwrap();
    let series_len = std::fs::metadata(out.join("series.csv")).unwrap().len();
    let refused = |file: &Path, extra: &[&str], what: &str| {
        let mut args = vec!["run", "--restart", s(file), "--until", "0.2"];
        args.extend_from_slice(extra);
        let o = run(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{what}: {:?} {err}", o.status);
        assert!(!err.contains("panicked"), "{what}: {err}");
        assert!(
            err.contains(&format!("cannot restart from {}", file.display())),
            "{what}: {err}"
        );
        // Nothing in the run directory was changed.
        assert_eq!(
            std::fs::metadata(out.join("series.csv")).unwrap().len(),
            series_len
        );
        err.into_owned()
    };
    let write = |name: &str, bytes: &[u8]| {
        let p = out.join(name);
        std::fs::write(&p, bytes).unwrap();
        p
    };
    let e = refused(
        &write("trunc.bin", &good[..good.len() / 2]),
        &[],
        "truncated",
    );
    assert!(e.contains("truncated"), "{e}");
    let mut flipped = good.clone();
    let mid = flipped.len() / 2;
    flipped[mid] ^= 0x5a;
    let e = refused(&write("flip.bin", &flipped), &[], "flipped byte");
    assert!(e.contains("checksum"), "{e}");
    // The tumble version string follows magic (8), format (4) and its length (one byte, a
    // postcard varint).
    let mut version = good.clone();
    let vlen = version[12] as usize;
    assert_eq!(
        &version[13..13 + vlen],
        tumble::io::checkpoint::CRATE_VERSION.as_bytes()
    );
    version[13] = b'7';
    let e = refused(&write("version.bin", &version), &[], "other version");
    assert!(e.contains("written by tumble 7"), "{e}");
    let mut format = good.clone();
    format[8] = 99;
    let e = refused(&write("format.bin", &format), &[], "other format");
    assert!(e.contains("format 99"), "{e}");
    let e = refused(&write("text.bin", b"not a checkpoint\n"), &[], "not one");
    assert!(e.contains("not a tumble checkpoint"), "{e}");
    // Another scene, given on the command line or in the run directory.
    let other = d.join("other.ron");
    std::fs::write(&other, BOX_2D.replace("viscosity: 0.01", "viscosity: 0.02")).unwrap();
    let e = refused(&good_path, &[s(&other)], "other scene");
    assert!(e.contains("other.ron"), "{e}");
    let scene_ron = out.join("scene.ron");
    let kept = std::fs::read_to_string(&scene_ron).unwrap();
    std::fs::write(
        &scene_ron,
        kept.replace("kappa: Some(30.0)", "kappa: Some(20.0)"),
    )
    .unwrap();
    let e = refused(&good_path, &[], "other scene.ron");
    assert!(e.contains("scene.ron"), "{e}");
    std::fs::write(&scene_ron, kept).unwrap();
    // The good one still restarts.
    ok(&run(&[
        "run",
        "--restart",
        s(&good_path),
        "--until",
        "0.2",
        "--quiet",
    ]));
}

/// Files that are not checkpoints of this format are refused, each with what it is and what
/// this tumble reads: a checkpoint of the earlier, hand-written format, one of a format not
/// known, bytes that are no checkpoint at all, an empty file and every cut of a good one.
#[test]
fn old_foreign_and_cut_files_are_refused_by_what_they_are() {
    use tumble::io::checkpoint::{CRATE_VERSION, FORMAT_VERSION, MAGIC};
    let file = Path::new("memory");
    let refused = |bytes: &[u8]| match Checkpoint::from_bytes(bytes, file) {
        Ok(_) => panic!("{} bytes read as a checkpoint", bytes.len()),
        Err(e) => e.to_string(),
    };
    let reads = format!("reads checkpoints of format {FORMAT_VERSION}");
    // Format 2: the magic, the format, the tumble version (u64 length and text), the rest.
    let mut old = MAGIC.to_vec();
    old.extend(2u32.to_le_bytes());
    old.extend(5u64.to_le_bytes());
    old.extend(b"0.0.9");
    old.extend([0u8; 64]);
    let e = refused(&old);
    assert!(
        e.contains("format 2") && e.contains("hand-written") && e.contains("tumble 0.0.9"),
        "{e}"
    );
    assert!(e.contains(&reads) && e.contains(CRATE_VERSION), "{e}");
    let mut newer = MAGIC.to_vec();
    newer.extend((FORMAT_VERSION + 1).to_le_bytes());
    let e = refused(&newer);
    assert!(e.contains(&format!("format {}", FORMAT_VERSION + 1)), "{e}");
    assert!(e.contains(&reads), "{e}");
    // Random bytes (a fixed sequence) and an empty file.
    let mut x = 0x9e3779b97f4a7c15u64;
    let noise: Vec<u8> = (0..4096)
        .map(|_| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x as u8
        })
        .collect();
    let e = refused(&noise);
    assert!(
        e.contains("not a tumble checkpoint") && e.contains(&reads),
        "{e}"
    );
    let e = refused(b"");
    assert!(e.contains("empty") && e.contains(&reads), "{e}");
    // Every cut of a good checkpoint: within the header, the state and the trailer.
    let mut s = sim(BOX_2D);
    s.step().unwrap();
    let good = checkpoint::to_bytes(&mut s, &RunProgress::default());
    Checkpoint::from_bytes(&good, file).unwrap();
    let n = good.len();
    let cuts = (1..64)
        .chain((1..200).map(|k| k * n / 200))
        .chain(n - 16..n);
    for cut in cuts {
        let e = refused(&good[..cut]);
        assert!(e.contains("truncated"), "cut at {cut} of {n}: {e}");
    }
}

#[test]
fn blow_up_keeps_the_last_good_checkpoint() {
    let d = tmp("blowup");
    // A guard so tight that the vorticity a falling heavy disk makes trips it after about a
    // dozen steps.
    let text = BOX_2D
        .replace("circulation: 0.2", "circulation: 0.002")
        .replace("position: [0.45, 0.125]", "position: [0.45, 0.5]")
        .replace("velocity: [0.1, -0.5]", "velocity: [0.0, 0.0]")
        .replace("end_time: 0.3", "end_time: 0.3, blowup_factor: 80.0");
    let scene = d.join("blowup.ron");
    std::fs::write(&scene, text).unwrap();
    let out = d.join("run");
    let o = run(&[
        "run",
        s(&scene),
        "--out",
        s(&out),
        "--checkpoint-every",
        "0.004",
        "--quiet",
    ]);
    assert_eq!(o.status.code(), Some(1), "{:?}", o.status);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("blow-up"), "{err}");
    let ck = Checkpoint::load(&latest(&out)).unwrap();
    assert!(ck.time.step > 0, "the guard tripped before any checkpoint");
    let named = format!(
        "the last good checkpoint is {} (step {}, t = {})",
        latest(&out).display(),
        ck.time.step,
        ck.time.t
    );
    assert!(err.contains(&named), "{err}");
    let log = std::fs::read_to_string(out.join("log.txt")).unwrap();
    assert!(log.contains(&named), "{log}");
    // The checkpoint is from before the failure: its state passed the guard.
    let sim = ck.simulation(ck.scene().unwrap()).unwrap();
    let diag = sim
        .world
        .resource::<tumble::systems::diagnostics::Diagnostics>();
    assert!(diag.sample.max_omega <= 80.0 * diag.omega0);
    assert!(ck.time.step >= 5);
}

// ---- HDF5 outputs (`--features hdf5`) ----

/// Everything an HDF5 file holds, by path (`/group/dataset`, `/group@attribute`): shape, then
/// values (floats as bits, strings as text). Not the file's bytes: depending on its version
/// and settings, the HDF5 library may stamp objects with their modification time.
#[cfg(feature = "hdf5")]
fn h5_contents(path: &Path) -> std::collections::BTreeMap<String, (Vec<usize>, Vec<String>)> {
    use hdf5::types::{TypeDescriptor as T, VarLenUnicode};
    fn values(c: &hdf5::Container, what: &str) -> (Vec<usize>, Vec<String>) {
        let v: Vec<String> = match c.dtype().unwrap().to_descriptor().unwrap() {
            T::Float(_) => c
                .read_raw::<f64>()
                .unwrap()
                .iter()
                .map(|x| format!("{:016x}", x.to_bits()))
                .collect(),
            T::Unsigned(_) => c
                .read_raw::<u64>()
                .unwrap()
                .iter()
                .map(|x| x.to_string())
                .collect(),
            T::Integer(_) => c
                .read_raw::<i64>()
                .unwrap()
                .iter()
                .map(|x| x.to_string())
                .collect(),
            T::VarLenUnicode => c
                .read_raw::<VarLenUnicode>()
                .unwrap()
                .iter()
                .map(|x| x.as_str().to_string())
                .collect(),
            d => panic!("{what}: unexpected type {d:?}"),
        };
        (c.shape(), v)
    }
    fn walk(
        g: &hdf5::Group,
        out: &mut std::collections::BTreeMap<String, (Vec<usize>, Vec<String>)>,
    ) {
        for a in g.attr_names().unwrap() {
            let key = format!("{}@{a}", g.name());
            out.insert(key.clone(), values(&g.attr(&a).unwrap(), &key));
        }
        for d in g.datasets().unwrap() {
            out.insert(d.name(), values(&d, &d.name()));
            assert!(d.attr_names().unwrap().is_empty(), "{}", d.name());
        }
        for sub in g.groups().unwrap() {
            walk(&sub, out);
        }
    }
    let file = hdf5::File::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut out = std::collections::BTreeMap::new();
    walk(&file, &mut out);
    out
}

/// The run directories `a` and `b` hold the same outputs: the same files (but the log, the
/// timings, the plots, the checkpoint and scene.ron), identical bytes but for the HDF5 files,
/// whose contents are identical.
#[cfg(feature = "hdf5")]
fn assert_same_outputs_h5(a: &Path, b: &Path) {
    let names = |d: &Path| {
        let mut v: Vec<String> = std::fs::read_dir(d)
            .unwrap()
            .map(|e| e.unwrap().file_name().into_string().unwrap())
            .filter(|n| {
                !n.ends_with(".png")
                    && checkpoint::step_of(n).is_none()
                    && !["log.txt", "timings.csv", "scene.ron"].contains(&n.as_str())
            })
            .collect();
        v.sort();
        v
    };
    let (na, nb) = (names(a), names(b));
    assert_eq!(
        na,
        nb,
        "{} and {} hold other files",
        a.display(),
        b.display()
    );
    assert!(na.iter().any(|n| n == "fields.xmf"));
    assert!(na.iter().any(|n| n == "series.h5"));
    for n in &na {
        if n.ends_with(".h5") {
            let (x, y) = (h5_contents(&a.join(n)), h5_contents(&b.join(n)));
            assert!(!x.is_empty(), "{n} is empty");
            for (k, v) in &x {
                assert!(y.get(k) == Some(v), "{n}: {k} differs after the restart");
            }
            assert_eq!(x.len(), y.len(), "{n}: other datasets or attributes");
        } else if a.join(n).is_dir() {
            // slices/: the same images.
            let list = |d: &Path| {
                let mut v: Vec<_> = std::fs::read_dir(d)
                    .unwrap()
                    .map(|e| e.unwrap().file_name())
                    .collect();
                v.sort();
                v
            };
            assert_eq!(list(&a.join(n)), list(&b.join(n)), "{n}/ differs");
            for m in list(&a.join(n)) {
                let x = std::fs::read(a.join(n).join(&m)).unwrap();
                let y = std::fs::read(b.join(n).join(&m));
                assert!(y.is_ok_and(|y| y == x), "{n}/{m:?} differs");
            }
        } else {
            let (x, y) = (std::fs::read(a.join(n)).unwrap(), std::fs::read(b.join(n)));
            assert!(
                y.as_ref().is_ok_and(|y| *y == x),
                "{n} differs between {} and {}",
                a.display(),
                b.display()
            );
        }
    }
}

/// A run with HDF5 output (`formats`) stopped at a checkpoint and restarted has the outputs of
/// the run that never stopped: `fields.xmf`, `bodies.xmf`, every `fields_*.h5` and
/// `bodies_*.h5` and `series.h5` (and with
/// VTK the `.vti` and `fields.pvd`, and the CSV time series). The restart starts from a run
/// directory that went on past the checkpoint (more snapshots, rows and series.h5 entries),
/// which it must cut back.
#[cfg(feature = "hdf5")]
fn hdf5_restart_reproduces_the_run(formats: &str, name: &str) {
    let d = tmp(name);
    let scene = d.join(format!("{name}.ron"));
    let text = BOX_2D.replace(
        "output: (every: 0.1)",
        &format!("output: (every: 0.1, formats: {formats})"),
    );
    assert_ne!(text, BOX_2D);
    std::fs::write(&scene, text).unwrap();
    let straight = d.join("straight");
    ok(&run(&["run", s(&scene), "--out", s(&straight), "--quiet"]));
    let stopped = d.join("stopped");
    ok(&run(&[
        "run",
        s(&scene),
        "--out",
        s(&stopped),
        "--until",
        "0.2",
        "--checkpoint-every",
        "0.07",
        "--quiet",
    ]));
    let ck = latest(&stopped);
    let at_02 = std::fs::read(&ck).unwrap();
    let c = Checkpoint::load(&ck).unwrap();
    assert_eq!(c.time.t, 0.2);
    assert_eq!(c.progress.snapshots, 3);
    // Go on to t = 0.45 (snapshots 3 to 5, more rows, a longer series.h5), then back to the
    // checkpoint at t = 0.2 and on to the scene's end, t = 0.3.
    ok(&run(&[
        "run",
        "--restart",
        s(&ck),
        "--until",
        "0.45",
        "--quiet",
    ]));
    assert!(stopped.join("fields_000005.h5").exists());
    std::fs::write(&ck, &at_02).unwrap();
    ok(&run(&[
        "run",
        "--restart",
        s(&ck),
        "--until",
        "0.3",
        "--quiet",
    ]));
    assert!(!stopped.join("fields_000004.h5").exists());
    assert_same_outputs_h5(&straight, &stopped);
    let xmf = std::fs::read_to_string(stopped.join("fields.xmf")).unwrap();
    assert_eq!(xmf.matches("<Time ").count(), 4, "{xmf}");
    // The body surfaces' HDF5 files and index are cut back the same way.
    assert!(!stopped.join("bodies_000004.h5").exists());
    let bxmf = std::fs::read_to_string(stopped.join("bodies.xmf")).unwrap();
    assert_eq!(bxmf.matches("<Time ").count(), 4, "{bxmf}");
    let contacts = h5_contents(&stopped.join("series.h5"));
    assert!(
        contacts
            .get("/contacts/t")
            .is_some_and(|(shape, _)| shape[0] > 0),
        "the scene should have contacts"
    );
    let log = std::fs::read_to_string(stopped.join("log.txt")).unwrap();
    assert_eq!(log.matches("restart from").count(), 2, "{log}");
    assert_same_step_count(&straight, &log);
    let _ = std::fs::remove_dir_all(&d);
}

#[cfg(feature = "hdf5")]
#[test]
fn restart_reproduces_vtk_and_hdf5_outputs() {
    hdf5_restart_reproduces_the_run("[Vtk, Hdf5]", "h5-vtk");
}

#[cfg(feature = "hdf5")]
#[test]
fn restart_reproduces_hdf5_only_outputs() {
    hdf5_restart_reproduces_the_run("[Hdf5]", "h5-only");
}

/// Plugin state for the generic checkpoint path: a counter bumped every step, its layout
/// version a parameter.
#[derive(bevy_ecs::prelude::Resource, serde::Serialize, serde::Deserialize)]
struct Counter(u64);

struct CounterPlugin(u32);

impl tumble::schedule::Plugin for CounterPlugin {
    fn name(&self) -> &'static str {
        "counter"
    }
    fn build(&self, ctx: &mut tumble::schedule::PluginContext) -> anyhow::Result<()> {
        ctx.insert_resource(Counter(0));
        ctx.checkpoint_resource::<Counter>("counter", self.0)?;
        ctx.add_system(
            tumble::schedule::PhysicsSet::Last,
            "counter",
            |mut c: bevy_ecs::prelude::ResMut<Counter>| c.0 += 1,
        )
    }
}

fn counter_sim(version: Option<u32>) -> Simulation {
    let scene = Scene::parse(BOX_2D, "test", "test").unwrap();
    match version {
        Some(v) => Simulation::builder(scene)
            .add_plugin(CounterPlugin(v))
            .build()
            .unwrap(),
        None => Simulation::new(scene).unwrap(),
    }
}

#[test]
fn plugin_state_restarts_and_is_refused_by_name_and_version() {
    let mut a = counter_sim(Some(1));
    for _ in 0..3 {
        a.step().unwrap();
    }
    let bytes = checkpoint::to_bytes(&mut a, &RunProgress::default());
    let file = Path::new("memory");
    let ck = Checkpoint::from_bytes(&bytes, file).unwrap();
    // Restored through the generic record, then stepped on.
    let mut b = counter_sim(Some(1));
    ck.restore(&mut b).unwrap();
    assert_eq!(b.world.resource::<Counter>().0, 3);
    b.step().unwrap();
    assert_eq!(b.world.resource::<Counter>().0, 4);
    // Another layout version of the record: refused, naming it and both versions.
    let e = ck
        .restore(&mut counter_sim(Some(2)))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("`counter`") && e.contains("version 1") && e.contains("version 2"),
        "{e}"
    );
    // A checkpoint without the record, restored into a simulation that keeps it: refused.
    let plain = checkpoint::to_bytes(&mut counter_sim(None), &RunProgress::default());
    let e = Checkpoint::from_bytes(&plain, file)
        .unwrap()
        .restore(&mut counter_sim(Some(1)))
        .unwrap_err()
        .to_string();
    assert!(e.contains("no state `counter`"), "{e}");
}

// ---- Runs killed without warning (issue 46) ----

/// Whether `name` is the temporary file of a checkpoint being written.
fn is_checkpoint_temp(name: &str) -> bool {
    name.starts_with(".checkpoint_") && checkpoint::is_temp_file(name)
}

/// The names of the files in `dir`.
fn names(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .map(|r| {
            r.map(|e| e.unwrap().file_name().into_string().unwrap())
                .collect()
        })
        .unwrap_or_default()
}

/// The step of a checkpoint's temporary file (`.checkpoint_NNNNNN.bin.tmp-*`).
fn temp_step(name: &str) -> Option<u64> {
    let name = name.strip_prefix('.')?;
    checkpoint::step_of(&name[..name.find(".tmp-")?])
}

/// Runs with wall-clock checkpoints after about every step (`--checkpoint-wall 0.001`) killed
/// with SIGKILL at a seeded random step, either a random moment (up to 20 ms) after a
/// checkpoint or as soon as a checkpoint's temporary file appears (in the middle of its
/// write), then continued with `--restart DIR`: every checkpoint left on disk reads back
/// whole, and the restarted run's outputs are those of the run never stopped, bit for bit.
#[test]
fn sigkill_at_random_moments_restarts_bit_for_bit() {
    let d = tmp("sigkill");
    let scene = scene_file(&d);
    // 76 steps to t = 0.3.
    let until = "0.3";
    let straight = d.join("straight");
    ok(&run(&[
        "run",
        s(&scene),
        "--out",
        s(&straight),
        "--until",
        until,
        "--checkpoint-wall",
        "0",
        "--quiet",
    ]));
    assert!(
        checkpoint::list(&straight).unwrap().is_empty(),
        "--checkpoint-wall 0 wrote a checkpoint"
    );
    let mut rng = common::Rng(46);
    let mut mid_write = 0;
    for seed in 0..6 {
        let out = d.join(format!("killed{seed}"));
        let mut child = tumble()
            .args([
                "run",
                s(&scene),
                "--out",
                s(&out),
                "--until",
                until,
                "--checkpoint-wall",
                "0.001",
                "--quiet",
            ])
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .spawn()
            .unwrap();
        let target = (35.0 + 30.0 * rng.next()) as u64; // 5 to 65
        let pause = 0.01 * (rng.next() + 1.0); // 0 to 20 ms
        let start = Instant::now();
        loop {
            let files = names(&out);
            let done = if seed % 2 == 0 {
                files
                    .iter()
                    .filter_map(|n| checkpoint::step_of(n))
                    .any(|s| s >= target)
            } else {
                files
                    .iter()
                    .filter_map(|n| temp_step(n))
                    .any(|s| s >= target)
            };
            if done {
                break;
            }
            assert!(
                child.try_wait().unwrap().is_none(),
                "seed {seed}: the run ended before step {target}"
            );
            assert!(start.elapsed() < Duration::from_secs(60), "seed {seed}");
            std::thread::sleep(Duration::from_micros(100));
        }
        if seed % 2 == 0 {
            std::thread::sleep(Duration::from_secs_f64(pause));
        }
        child.kill().unwrap(); // SIGKILL
        assert!(!child.wait().unwrap().success(), "seed {seed}: not killed");
        if names(&out).iter().any(|n| is_checkpoint_temp(n)) {
            mid_write += 1;
        }
        // Every checkpoint on disk is whole: the 2 kept, and a third when the kill falls
        // between a new one's rename and the deletion of the oldest.
        let left = checkpoint::list(&out).unwrap();
        assert!(!left.is_empty() && left.len() <= 3, "seed {seed}: {left:?}");
        for (_, p) in &left {
            Checkpoint::load(p).unwrap_or_else(|e| panic!("seed {seed}: {e}"));
        }
        // The restart goes on without checkpoints (a restart may change the interval).
        ok(&run(&[
            "run",
            "--restart",
            s(&out),
            "--checkpoint-wall",
            "0",
            "--quiet",
        ]));
        for n in names(&out) {
            assert!(
                !checkpoint::is_temp_file(&n),
                "seed {seed}: {n} left behind"
            );
        }
        assert_same_outputs(&straight, &out);
    }
    assert!(
        mid_write >= 1,
        "no kill landed in the middle of a checkpoint's write"
    );
}

/// A run whose outputs would not fit on the disk is refused before anything is written,
/// with the numbers (exit status 2).
#[test]
fn a_run_too_large_for_the_disk_is_refused() {
    let d = tmp("disk");
    // 512² cells, a snapshot every 1e-6 to t = 1: a million snapshots of 4.2 MB (ω and u).
    let f = d.join("huge.ron");
    std::fs::write(
        &f,
        "Scene(\n    domain: (extent: [1.0, 1.0], cells: [512, 512]),\n    \
         numerics: (dt: Fixed(0.001), end_time: 1.0),\n    output: (every: 1e-6),\n)",
    )
    .unwrap();
    let out = d.join("run");
    let o = run(&["run", s(&f), "--out", s(&out), "--quiet"]);
    assert_eq!(o.status.code(), Some(2), "{o:?}");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("would take about")
            && err.contains("1000001 snapshots of 4.2 MB")
            && err.contains("free on the disk of"),
        "{err}"
    );
    assert!(!out.exists(), "the refused run made its directory");
}

/// Without a terminal, the progress lines (every tenth of the run, also in the log) give the
/// time left.
#[test]
fn progress_lines_give_the_time_left() {
    let d = tmp("eta");
    let out = d.join("run");
    let o = run(&[
        "run",
        s(&scene_file(&d)),
        "--out",
        s(&out),
        "--until",
        "0.1",
    ]);
    ok(&o);
    let err = String::from_utf8_lossy(&o.stderr);
    let lines: Vec<&str> = err.lines().filter(|l| l.contains("% ")).collect();
    assert_eq!(lines.len(), 10, "{err}");
    assert!(lines.iter().all(|l| l.contains(" left")), "{err}");
    assert!(lines[9].contains("about 0 s left"), "{err}");
    let log = std::fs::read_to_string(out.join("log.txt")).unwrap();
    assert!(log.contains("progress: 50%, step "), "{log}");
}
