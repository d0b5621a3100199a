//! The example plugin of `examples/passive_scalar.rs`, a new physics system in one file with
//! no output or checkpoint code of its own: its settings come from the scene's `plugins`
//! section (checked with file and line), it conserves its mass and stays non-negative, its
//! field is written into the snapshots, and through tumble's command line (the example's
//! binary is `cli::main_from` with the plugin) a run stopped by Ctrl-C continues bit for bit.

#[allow(dead_code)]
#[path = "../../examples/passive_scalar.rs"]
mod passive_scalar;

use crate::common::Scratch;
use passive_scalar::{PassiveScalarPlugin, Scalar};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};
use tumble::io::checkpoint;
use tumble::scene::{Scene, ValidScene};
use tumble::schedule::PluginList;
use tumble::sim::engine::Simulation;

fn scene_file() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/passive_scalar.ron")
}

/// The example's scene with its section's `kappa: 1e-3` replaced by `kappa`.
fn scene_text(kappa: &str) -> String {
    let text = std::fs::read_to_string(scene_file()).unwrap();
    assert!(text.contains("kappa: 1e-3"));
    text.replace("kappa: 1e-3", &format!("kappa: {kappa}"))
}

fn scene(kappa: &str) -> ValidScene {
    Scene::parse(&scene_text(kappa), "passive_scalar.ron", "passive-scalar").unwrap()
}

#[test]
fn passive_scalar_reads_its_section_conserves_mass_and_stays_positive() {
    let mut sim = Simulation::builder(scene("2e-3"))
        .add_plugin(PassiveScalarPlugin)
        .build()
        .unwrap();
    let grid = sim.grid().clone();
    assert_eq!(
        sim.world.resource::<Scalar>().kappa,
        2e-3,
        "the section is not read"
    );
    // Initial mass: the Gaussian's integral 2π σ² (2D), σ = 0.08 of the box; its periodic
    // images are 6.25 σ away at the nearest, so the truncated tail is below
    // exp(-6.25²/2) ≈ 3e-9, and the trapezoidal rule on a smooth periodic function is exact
    // to that level.
    let sigma = 0.08 * grid.extent()[0];
    let exact = 2.0 * std::f64::consts::PI * sigma * sigma;
    let mass0 = sim.world.resource::<Scalar>().mass(&grid);
    let max0 = sim
        .world
        .resource::<Scalar>()
        .c
        .iter()
        .copied()
        .fold(0.0, f64::max);
    assert!(
        ((mass0 - exact) / exact).abs() < 1e-7,
        "initial mass {mass0} against 2 pi sigma^2 = {exact}"
    );
    sim.run_until(0.5, |_| {}).unwrap();
    let s = sim.world.resource::<Scalar>();
    assert!(sim.steps() >= 5, "{} steps", sim.steps());
    // Conservation: the face fluxes telescope exactly, so only rounding changes the mass, at
    // most a few ulps of each node value per sub-step plus the two summations:
    // (4 substeps + 2) N ε relative.
    let bound = (4.0 * s.substeps as f64 + 2.0) * grid.len() as f64 * f64::EPSILON;
    let drift = ((s.mass(&grid) - mass0) / mass0).abs();
    assert!(
        drift <= bound,
        "mass drift {drift:e} over the bound {bound:e}"
    );
    // Positivity under the sub-step limit (non-negative weights), and the maximum principle
    // of advection-diffusion: the peak has come down from its start.
    let min = s.c.iter().copied().fold(f64::INFINITY, f64::min);
    let max = s.c.iter().copied().fold(0.0, f64::max);
    assert!(min >= 0.0, "min c = {min}");
    assert!(
        max < max0,
        "max c = {max}, at the start {max0}: nothing diffused"
    );
}

#[test]
fn the_section_is_checked_with_its_line_and_refused_without_the_plugin() {
    // A misspelt setting: the error names the file, the line of the field and the field.
    let text = scene_text("1e-3, centre: [0.5, 0.5]");
    let line = 1 + text.lines().position(|l| l.contains("centre")).unwrap();
    let bad = Scene::parse(&text, "bad.ron", "bad").unwrap();
    let err = Simulation::builder(bad)
        .add_plugin(PassiveScalarPlugin)
        .build()
        .err()
        .expect("a misspelt setting was accepted")
        .to_string();
    assert!(err.contains(&format!("bad.ron, line {line}")), "{err}");
    assert!(
        err.contains("plugins.passive_scalar") && err.contains("centre"),
        "{err}"
    );
    // A simulation without the plugin refuses the scene, naming the section.
    let err = Simulation::new(scene("1e-3"))
        .err()
        .expect("accepted")
        .to_string();
    assert!(
        err.contains("\"passive_scalar\"") && err.contains("no plugin"),
        "{err}"
    );
}

/// Not a test: the example's command line (tumble's, with the plugin), run in a child
/// process by the test below on the arguments in `TUMBLE_EXAMPLE_ARGS` (one per line).
#[test]
#[ignore]
fn example_cli_child() {
    let Ok(args) = std::env::var("TUMBLE_EXAMPLE_ARGS") else {
        return;
    };
    let args = std::iter::once("passive_scalar").chain(args.lines());
    let code = tumble::cli::status(args, PluginList::default().with(PassiveScalarPlugin));
    std::process::exit(code.into());
}

fn example(args: &[&str]) -> Command {
    let mut c = Command::new(std::env::current_exe().unwrap());
    c.args([
        "--ignored",
        "--exact",
        "example_plugin::example_cli_child",
        "--nocapture",
        "--test-threads",
        "1",
    ])
    .env("TUMBLE_EXAMPLE_ARGS", args.join("\n"));
    c
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn sorted_files(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .filter(|n| n.ends_with(".vti") || n == "fields.pvd" || n == "series.csv")
        .collect();
    v.sort();
    v
}

#[test]
fn the_example_writes_its_field_and_continues_bit_for_bit_after_ctrl_c() {
    let d = Scratch::new("example_plugin", "cli");
    let scene = scene_file();
    // `check` through the example's command line checks and lists the section; `tumble`'s
    // own refuses the scene (exit status 2), naming the section.
    let o = example(&["check", s(&scene)]).output().unwrap();
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        out.contains("plugin sections: passive_scalar (checked)"),
        "{out}"
    );
    let o = Command::new(env!("CARGO_BIN_EXE_tumble"))
        .args(["check", s(&scene)])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("\"passive_scalar\"") && err.contains("no plugin"),
        "{err}"
    );
    let until = "4.0";
    let straight = d.join("straight");
    let o = example(&[
        "run",
        s(&scene),
        "--out",
        s(&straight),
        "--until",
        until,
        "--quiet",
    ])
    .output()
    .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let vti = std::fs::read(straight.join("fields_000001.vti")).unwrap();
    assert!(
        vti.windows(13).any(|w| w == b"Name=\"scalar\""),
        "the plugin's field is not in the snapshot"
    );

    // The same run stopped by SIGINT once it has written a checkpoint, then restarted.
    let stopped = d.join("stopped");
    let mut child = example(&[
        "run",
        s(&scene),
        "--out",
        s(&stopped),
        "--until",
        until,
        "--checkpoint-every",
        "0.25",
        "--quiet",
    ])
    .stdout(std::process::Stdio::null())
    .stderr(std::process::Stdio::piped())
    .spawn()
    .unwrap();
    let start = Instant::now();
    while checkpoint::list(&stopped).map_or(true, |l| l.is_empty()) {
        assert!(
            child.try_wait().unwrap().is_none(),
            "the run ended before it was stopped"
        );
        assert!(start.elapsed() < Duration::from_secs(120), "no checkpoint");
        std::thread::sleep(Duration::from_millis(5));
    }
    let k = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(k.success());
    let o = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(130), "{stderr}");
    assert!(
        stderr.contains("restart with tumble run --restart"),
        "{stderr}"
    );

    // tumble alone refuses the checkpoint: its scene has a section no plugin of it reads.
    let o = Command::new(env!("CARGO_BIN_EXE_tumble"))
        .args(["run", "--restart", s(&stopped), "--quiet"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("passive_scalar"),
        "{err}"
    );

    let o = example(&["run", "--restart", s(&stopped), "--quiet"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let names = sorted_files(&straight);
    assert_eq!(names, sorted_files(&stopped));
    assert!(names.len() >= 5, "{names:?}");
    for n in &names {
        let (a, b) = (
            std::fs::read(straight.join(n)).unwrap(),
            std::fs::read(stopped.join(n)).unwrap(),
        );
        assert!(a == b, "{n} differs after the restart");
    }
}
