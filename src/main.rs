//! The `tumble` command line.

use clap::{Parser, Subcommand};
use std::path::PathBuf;
use std::process::ExitCode;
use tumble::bodies::meshgen::CupParams;
use tumble::io::output::peak_memory_bytes;
use tumble::run::{RunOptions, run_scene};
use tumble::scene::{Scene, SceneError, ValidScene};
use tumble::sim::engine::Simulation;
use tumble::validate::{CASES, find_case};

#[derive(Parser)]
#[command(
    name = "tumble",
    version,
    about = "Incompressible viscous flow with colliding rigid bodies (vortex level set method)"
)]
struct Cli {
    /// Worker threads (default: all cores).
    #[arg(long, global = true)]
    threads: Option<usize>,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run a scene and write its outputs (series.csv, snapshots in the scene's formats, log),
    /// or continue a run from its checkpoint.
    Run {
        /// The scene file (RON). With --restart it may be left out; if given, it must be the
        /// checkpoint's scene.
        #[arg(required_unless_present = "restart")]
        scene: Option<PathBuf>,
        /// Output directory (default: runs/<scene name>).
        #[arg(long)]
        out: Option<PathBuf>,
        /// End time, overriding the scene's numerics.end_time.
        #[arg(long)]
        until: Option<f64>,
        /// Replace the output directory if it exists and tumble made it (it holds .tumble-run).
        #[arg(long)]
        force: bool,
        /// No progress output.
        #[arg(long)]
        quiet: bool,
        /// Write a checkpoint (checkpoint_NNNNNN.bin in the run directory, named by step; the
        /// latest output.checkpoints_kept are kept) every T of simulated time, overriding the
        /// scene's output.checkpoint_every.
        #[arg(long, value_name = "T")]
        checkpoint_every: Option<f64>,
        /// Continue a run from a checkpoint, appending to its run directory (the checkpoint's):
        /// a checkpoint file, or a run directory (then its latest complete checkpoint).
        #[arg(long, value_name = "DIR|CHECKPOINT", conflicts_with_all = ["out", "force"])]
        restart: Option<PathBuf>,
    },
    /// Load and validate a scene, print what it will compute, run nothing.
    Check {
        /// The scene file (RON).
        scene: PathBuf,
    },
    /// Rerun the validation cases and compare with analytic and published values: the full
    /// tier by default, the quick tier (what `cargo test --release` runs) with --quick.
    Validate {
        /// Cases to run (default: all).
        cases: Vec<String>,
        /// Reduced versions: the quick tier (as `cargo test --release` runs it).
        #[arg(long)]
        quick: bool,
        /// List the cases (name, run time of the full and quick versions, reference) and run
        /// nothing.
        #[arg(long)]
        list: bool,
        /// Write the results as Markdown to FILE (e.g. docs/validation.md): every case's rows,
        /// the date, the machine, the wall time and the cases not run. FILE must be new or a
        /// page this option wrote; any other file is refused (exit status 2) before the run.
        #[arg(long, value_name = "FILE")]
        write_docs: Option<PathBuf>,
        /// Write the PNG plots (measured curves over their references) to DIR, as
        /// `<case>[-quick]-<name>.png`.
        #[arg(long, value_name = "DIR", default_value = "validation")]
        plots: PathBuf,
    },
    /// Time steps of a scene; prints one JSON line.
    Bench {
        /// The scene file (RON).
        scene: PathBuf,
        /// Timed steps.
        #[arg(long, default_value_t = 10)]
        steps: usize,
        /// Untimed steps before timing.
        #[arg(long, default_value_t = 2)]
        warmup: usize,
    },
    /// Write PNG plots (energy, enstrophy, bodies, contacts) next to a run's CSV files.
    Plot {
        /// The run directory (holds series.csv).
        run_dir: PathBuf,
    },
    /// Generate a closed triangle mesh for a `Mesh` body.
    Mesh {
        #[command(subcommand)]
        shape: MeshShape,
    },
}

#[derive(Subcommand)]
enum MeshShape {
    /// A cup: a solid of revolution about z (outer wall, flat bottom, open top with a flat
    /// rim), its centre of volume at the origin. Lengths in scene units.
    Cup {
        /// Outer radius R.
        #[arg(long, default_value_t = CupParams::default().radius)]
        radius: f64,
        /// Total height H, base to rim.
        #[arg(long, default_value_t = CupParams::default().height)]
        height: f64,
        /// Wall thickness t (inner radius R - t).
        #[arg(long, default_value_t = CupParams::default().wall)]
        wall: f64,
        /// Bottom thickness b.
        #[arg(long, default_value_t = CupParams::default().bottom)]
        bottom: f64,
        /// Sides of the polygons standing for the circles (at least 8).
        #[arg(long, default_value_t = CupParams::default().segments)]
        segments: u32,
        /// The file to write: .obj (Wavefront OBJ) or .stl (binary STL), by its extension.
        #[arg(long, value_name = "FILE")]
        out: PathBuf,
        /// Replace FILE if it exists and tumble wrote it (its header says so).
        #[arg(long)]
        force: bool,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    if let Some(n) = cli.threads {
        if n == 0 {
            eprintln!("error: --threads must be at least 1");
            return ExitCode::from(2);
        }
        if let Err(e) = rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build_global()
        {
            eprintln!("error: cannot set up {n} threads: {e}");
            return ExitCode::from(2);
        }
    }
    match cli.command {
        Command::Run {
            scene,
            out,
            until,
            force,
            quiet,
            checkpoint_every,
            restart,
        } => {
            let loaded = match scene.as_deref().map(load).transpose() {
                Ok(s) => s,
                Err(code) => return code,
            };
            let opts = RunOptions {
                out,
                until,
                force,
                quiet,
                checkpoint_every,
            };
            // Ctrl-C and SIGTERM stop the run after its current step, with a checkpoint.
            if let Err(e) = tumble::io::checkpoint::install_interrupt_handler() {
                eprintln!("warning: {e:#}");
            }
            let result = match (restart, loaded) {
                (Some(ck), loaded) => {
                    let given = scene.as_deref().zip(loaded);
                    tumble::run::restart_run(&ck, given, &opts)
                }
                (None, Some(scene)) => run_scene(scene, &opts),
                (None, None) => unreachable!("clap requires a scene without --restart"),
            };
            match result {
                Ok(s) => {
                    println!(
                        "done: {} steps to t = {:.6} in {:.1} s; outputs in {}",
                        s.steps,
                        s.last.t,
                        s.wall,
                        s.dir.display()
                    );
                    println!(
                        "  final energy {:.6e}, enstrophy {:.6e}, max|ω| {:.4e}",
                        s.last.energy, s.last.enstrophy, s.last.max_omega
                    );
                    let steps = s.steps_run.max(1) as f64;
                    let per: Vec<String> = s
                        .system_seconds
                        .iter()
                        .map(|(n, t)| format!("{n} {:.4}", t / steps))
                        .collect();
                    println!("  seconds per step: {}", per.join(", "));
                    let index = ["fields.pvd", "fields.xmf", "bodies.pvd"]
                        .map(|f| s.dir.join(f))
                        .into_iter()
                        .find(|p| p.exists())
                        .unwrap_or_else(|| s.dir.join("fields.pvd"));
                    println!("  open {} in ParaView", index.display());
                    ExitCode::SUCCESS
                }
                Err(e)
                    if e.downcast_ref::<tumble::io::checkpoint::Interrupted>()
                        .is_some() =>
                {
                    eprintln!("{e}");
                    ExitCode::from(130)
                }
                Err(e) => {
                    eprintln!("error: {e:#}");
                    // A bad output directory is a usage mistake, like a bad scene; so is a
                    // checkpoint that cannot be restarted.
                    if e.is::<tumble::run::BadOutputDir>() || tumble::run::is_refused_restart(&e) {
                        ExitCode::from(2)
                    } else {
                        ExitCode::from(1)
                    }
                }
            }
        }
        Command::Check { scene } => {
            let scene = match load(&scene) {
                Ok(s) => s,
                Err(code) => return code,
            };
            for b in &scene.bodies {
                if let Err(e) = b.shape.build(&scene.base_dir) {
                    eprintln!("error: body `{}`: {e}", b.name);
                    return ExitCode::from(2);
                }
            }
            print!("{}", tumble::io::summary::describe(&scene));
            println!("scene `{}` is valid", scene.name);
            ExitCode::SUCCESS
        }
        Command::Validate {
            cases,
            quick,
            list,
            write_docs,
            plots,
        } => {
            if list {
                for c in CASES {
                    println!(
                        "{}: {}\n    reference: {}\n    full ({}): {}\n    quick ({}): {}",
                        c.name,
                        c.description,
                        c.reference,
                        c.full_time,
                        c.full,
                        c.quick_time,
                        c.quick
                    );
                }
                return ExitCode::SUCCESS;
            }
            let mut selected = Vec::new();
            for name in &cases {
                match find_case(name) {
                    Some(c) => selected.push(c),
                    None => {
                        println!(
                            "== {name}\n  error: unknown validation case `{name}`; the cases are: {}\nFAIL {name}",
                            CASES.iter().map(|c| c.name).collect::<Vec<_>>().join(", ")
                        );
                        return ExitCode::from(1);
                    }
                }
            }
            if cases.is_empty() {
                selected = CASES.iter().collect();
            }
            // Refuse before the (possibly hours-long) run, not after it.
            if let Some(file) = &write_docs
                && let Err(e) = tumble::validate::docs::may_write(file)
            {
                eprintln!("error: {e}");
                return ExitCode::from(2);
            }
            let start = std::time::Instant::now();
            let mut reports = Vec::new();
            for case in selected {
                let rep = case.run(quick);
                println!("{rep}");
                println!("  ({:.1} s)", rep.seconds);
                write_validation_plots(&rep, &plots);
                reports.push(rep);
            }
            let wall = start.elapsed().as_secs_f64();
            let failed = reports.iter().filter(|r| !r.passed()).count();
            println!(
                "{} passed, {} failed ({wall:.1} s)",
                reports.len() - failed,
                failed
            );
            if let Some(file) = write_docs {
                let date = std::time::SystemTime::now()
                    .duration_since(std::time::UNIX_EPOCH)
                    .map(|d| tumble::validate::docs::utc_date(d.as_secs()))
                    .unwrap_or_else(|_| "unknown".into());
                let mut machine = format!(
                    "nproc {}, {} worker threads",
                    std::thread::available_parallelism().map_or(0, |n| n.get()),
                    rayon::current_num_threads()
                );
                // On Linux: the load at the end (other work inflates the wall times) and the
                // CPU time of this run (user + system, /proc/self/stat fields 14 and 15 in
                // clock ticks of 1/100 s).
                if let Ok(load) = std::fs::read_to_string("/proc/loadavg") {
                    let l: Vec<&str> = load.split_whitespace().take(3).collect();
                    machine += &format!("; load average {} at the end", l.join(" "));
                }
                if let Ok(stat) = std::fs::read_to_string("/proc/self/stat")
                    && let Some(rest) = stat.rsplit(')').next()
                {
                    let f: Vec<f64> = rest
                        .split_whitespace()
                        .skip(11)
                        .take(2)
                        .filter_map(|x| x.parse().ok())
                        .collect();
                    if f.len() == 2 {
                        machine += &format!(
                            "; CPU time of the run {:.1} s (user + system)",
                            (f[0] + f[1]) / 100.0
                        );
                    }
                }
                let text = tumble::validate::docs::markdown(&reports, quick, &date, &machine, wall);
                if let Err(e) = std::fs::write(&file, text) {
                    eprintln!("error: cannot write {}: {e}", file.display());
                    return ExitCode::from(1);
                }
                println!("wrote {}", file.display());
            }
            if failed > 0 {
                ExitCode::from(1)
            } else {
                ExitCode::SUCCESS
            }
        }
        Command::Bench {
            scene,
            steps,
            warmup,
        } => {
            let scene = match load(&scene) {
                Ok(s) => s,
                Err(code) => return code,
            };
            match bench(scene, steps, warmup) {
                Ok(line) => {
                    println!("{line}");
                    ExitCode::SUCCESS
                }
                Err(e) => {
                    eprintln!("error: {e:#}");
                    ExitCode::from(1)
                }
            }
        }
        Command::Plot { run_dir } => match tumble::io::plot::plot_run_dir(&run_dir) {
            Ok(paths) => {
                for p in paths {
                    println!("{}", p.display());
                }
                ExitCode::SUCCESS
            }
            Err(e) => {
                eprintln!("error: {e:#}");
                ExitCode::from(1)
            }
        },
        Command::Mesh {
            shape:
                MeshShape::Cup {
                    radius,
                    height,
                    wall,
                    bottom,
                    segments,
                    out,
                    force,
                },
        } => {
            let params = CupParams {
                radius,
                height,
                wall,
                bottom,
                segments,
            };
            match write_cup(&params, &out, force) {
                Ok(summary) => {
                    println!("{summary}");
                    ExitCode::SUCCESS
                }
                Err(e) => {
                    eprintln!("error: {e:#}");
                    ExitCode::from(2)
                }
            }
        }
    }
}

/// The first bytes of every mesh file `tumble mesh` writes (an OBJ comment, a binary STL
/// header): `--force` replaces only files that start with them.
const MESH_MARK: &str = "tumble mesh ";

/// Writes the cup `params` to `out` (.obj or .stl by extension); refuses to replace an existing
/// file unless `force` is set and the file starts with [`MESH_MARK`] (tumble wrote it).
fn write_cup(params: &CupParams, out: &std::path::Path, force: bool) -> anyhow::Result<String> {
    use anyhow::{Context, bail};
    use std::io::{Read, Write};
    let ext = out
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase());
    let obj = match ext.as_deref() {
        Some("obj") => true,
        Some("stl") => false,
        _ => bail!(
            "{}: unsupported mesh format (the file name must end in .obj or .stl)",
            out.display()
        ),
    };
    let mesh = params.mesh().map_err(anyhow::Error::msg)?;
    let command = format!(
        "{MESH_MARK}cup --radius {} --height {} --wall {} --bottom {} --segments {}",
        params.radius, params.height, params.wall, params.bottom, params.segments
    );
    let bytes = if obj {
        let header = format!(
            "{command}\nclosed, outward oriented; axis z, centre of volume at the origin; {} vertices, {} triangles",
            mesh.vertices.len(),
            mesh.triangles.len()
        );
        mesh.to_obj(&header).into_bytes()
    } else {
        mesh.to_binary_stl(&command)
    };
    let mut file = match std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(out)
    {
        Ok(f) => f,
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
            if !force {
                bail!(
                    "{} exists; pass --force to replace it (only a file tumble mesh wrote)",
                    out.display()
                );
            }
            let mut head = vec![0u8; MESH_MARK.len() + 2];
            let n = std::fs::File::open(out)
                .and_then(|mut f| f.read(&mut head))
                .with_context(|| format!("cannot read {}", out.display()))?;
            let head = &head[..n];
            let ours = head.starts_with(MESH_MARK.as_bytes())
                || head
                    .strip_prefix(b"# ")
                    .is_some_and(|h| h.starts_with(MESH_MARK.as_bytes()));
            if !ours {
                bail!(
                    "{} exists and tumble did not write it (it does not start with `{MESH_MARK}`); not replacing it",
                    out.display()
                );
            }
            std::fs::File::create(out).with_context(|| format!("cannot write {}", out.display()))?
        }
        Err(e) => return Err(e).with_context(|| format!("cannot create {}", out.display())),
    };
    file.write_all(&bytes)
        .and_then(|()| file.sync_all())
        .with_context(|| format!("cannot write {}", out.display()))?;
    Ok(format!(
        "wrote {} ({} vertices, {} triangles, volume {:.6e})",
        out.display(),
        mesh.vertices.len(),
        mesh.triangles.len(),
        params.volume()
    ))
}

fn load(path: &std::path::Path) -> Result<ValidScene, ExitCode> {
    Scene::load(path).map_err(|e: SceneError| {
        eprintln!("error: {e}");
        ExitCode::from(2)
    })
}

fn median_p90(v: &mut [f64]) -> (f64, f64) {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n == 0 {
        return (f64::NAN, f64::NAN);
    }
    let med = if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    };
    let p90 = v[((0.9 * n as f64).ceil() as usize).clamp(1, n) - 1];
    (med, p90)
}

fn bench(scene: ValidScene, steps: usize, warmup: usize) -> anyhow::Result<String> {
    anyhow::ensure!(steps > 0, "--steps must be at least 1");
    let scene = scene.edit(|s| s.numerics.end_time = f64::MAX / 4.0)?;
    let name = scene.name.clone();
    let mut sim = Simulation::new(scene)?;
    sim.set_stop_at(None);
    for _ in 0..warmup {
        sim.step()?;
    }
    let mut total = Vec::with_capacity(steps);
    let mut per: Vec<(&'static str, Vec<f64>)> = Vec::new();
    // Iterations of the variable-density pressure solve per timed step (when it runs).
    let mut iterations = Vec::new();
    let mut preconditioners = Vec::new();
    for _ in 0..steps {
        let t0 = std::time::Instant::now();
        sim.step()?;
        total.push(t0.elapsed().as_secs_f64());
        if let Some(p) = sim
            .world
            .get_resource::<tumble::systems::pressure::PressureSolver>()
        {
            iterations.push(p.iterations() as f64);
            let name = format!("{:?}", p.poisson.preconditioner).to_lowercase();
            if !preconditioners.contains(&name) {
                preconditioners.push(name);
            }
        }
        for &(n, s) in &sim.timings().last {
            match per.iter_mut().find(|e| e.0 == n) {
                Some(e) => e.1.push(s),
                None => per.push((n, vec![s])),
            }
        }
    }
    let (med, p90) = median_p90(&mut total);
    let mut systems = serde_json::Map::new();
    for (n, mut v) in per {
        systems.insert(n.to_string(), serde_json::json!(median_p90(&mut v).0));
    }
    let g = sim.grid();
    // Peak memory of the run, before the floor's own buffers.
    let peak = peak_memory_bytes();
    // The FFT floor of the same grid, measured now in this process: the step as a ratio to it.
    let floor = tumble::solvers::fft::floor_seconds(g, 7);
    let mut floors = serde_json::Map::new();
    for (n, s) in &systems {
        floors.insert(
            n.clone(),
            serde_json::json!(s.as_f64().unwrap_or(0.0) / floor),
        );
    }
    let mut line = serde_json::json!({
        "scene": name,
        "cells": g.len(),
        "grid": &g.n[..g.dim],
        "bodies": sim.scene().bodies.len(),
        "steps": steps,
        "threads": rayon::current_num_threads(),
        "median_s_per_step": med,
        "p90_s_per_step": p90,
        "median_s_per_system": systems,
        "fft_floor_s": floor,
        "step_per_fft_floor": med / floor,
        "system_per_fft_floor": floors,
        "peak_memory_bytes": peak,
    });
    if !iterations.is_empty() {
        line["median_pressure_iterations"] = serde_json::json!(median_p90(&mut iterations).0);
        line["pressure_preconditioners"] = serde_json::json!(preconditioners);
    }
    Ok(line.to_string())
}

/// Writes the plots of a validation report to `dir` (created if needed), printing one line
/// per file written; a plot that cannot be written is a warning, not a failure of the case.
fn write_validation_plots(rep: &tumble::validate::Report, dir: &std::path::Path) {
    if rep.plots.is_empty() {
        return;
    }
    if let Err(e) = std::fs::create_dir_all(dir) {
        eprintln!(
            "warning: {}: cannot create the plot directory {}: {e}",
            rep.case,
            dir.display()
        );
        return;
    }
    for (path, res) in rep.write_plots(dir) {
        match res {
            Ok(()) => println!("  plot {}", path.display()),
            Err(e) => eprintln!("warning: {}: plot not written: {e:#}", rep.case),
        }
    }
}
