//! The `tumble` command line, as a library function: the `tumble` binary is
//! `cli::main_with(PluginList::default())`, and a user's binary with physics of its own is the
//! same line with its plugins (see `examples/passive_scalar.rs`): it runs, checks, restarts,
//! benchmarks and plots scenes whose `plugins` sections its plugins read, exactly as `tumble`
//! does. One function per subcommand.

mod bench;
mod mesh;
mod run;
mod validate;

use crate::scene::{Scene, SceneError, ValidScene};
use crate::schedule::{Plugin, PluginList};
use clap::{Parser, Subcommand};
use mesh::MeshShape;
use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

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
        /// Write a checkpoint every S seconds of wall-clock time (0: never), overriding the
        /// scene's output.checkpoint_wall (default 900, every 15 minutes), so that a run killed
        /// without warning loses at most about S seconds of work.
        #[arg(long, value_name = "S")]
        checkpoint_wall: Option<f64>,
        /// Continue a run from a checkpoint, appending to its run directory (the checkpoint's):
        /// a checkpoint file, or a run directory (then its latest complete checkpoint).
        #[arg(long, value_name = "DIR|CHECKPOINT", conflicts_with_all = ["out", "force"])]
        restart: Option<PathBuf>,
    },
    /// Load and validate a scene, print what it will compute, run nothing.
    Check {
        /// The scene file (RON).
        scene: PathBuf,
        /// Also say how the scene would split over this many processes (`mpirun -np N`):
        /// slabs, memory per process, transposes per step.
        #[arg(long, value_name = "N")]
        processes: Option<usize>,
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

/// The `tumble` command line with `plugins` beyond the built-in ones, on this process's
/// arguments.
pub fn main_with(plugins: PluginList) -> ExitCode {
    main_from(std::env::args_os(), plugins)
}

/// The `tumble` command line with `plugins`, on `args` (the first is the program's name).
pub fn main_from(
    args: impl IntoIterator<Item = impl Into<OsString> + Clone>,
    plugins: PluginList,
) -> ExitCode {
    ExitCode::from(status(args, plugins))
}

/// [`main_from`]'s exit status: 0 done, 1 a failed run or case, 2 a mistake in the command,
/// the scene, the output directory or the checkpoint, 130 a run interrupted (with a
/// checkpoint).
pub fn status(
    args: impl IntoIterator<Item = impl Into<OsString> + Clone>,
    plugins: PluginList,
) -> u8 {
    let cli = Cli::parse_from(args);
    if let Some(code) = set_threads(cli.threads) {
        return code;
    }
    // Under mpirun only `run`, `bench` and `validate` split their work; every other command
    // would run once per process, writing the same files.
    if !matches!(
        cli.command,
        Command::Run { .. } | Command::Bench { .. } | Command::Validate { .. }
    ) && let Some(n) = crate::parallel::comm::launcher_size().filter(|&n| n > 1)
    {
        eprintln!(
            "error: started by mpirun on {n} processes: only `tumble run`, `tumble bench` and \
             `tumble validate` run on several processes (run this command without mpirun)"
        );
        return 2;
    }
    match cli.command {
        Command::Run {
            scene,
            out,
            until,
            force,
            quiet,
            checkpoint_every,
            checkpoint_wall,
            restart,
        } => {
            // Under mpirun, the processes of the run (kept until it ends).
            let procs = match processes() {
                Ok(p) => p,
                Err(code) => return code,
            };
            let opts = crate::run::RunOptions {
                out,
                until,
                force,
                quiet,
                checkpoint_every,
                checkpoint_wall,
                plugins,
                comm: procs.as_ref().map(|p| p.comm.clone()),
            };
            run::run(scene.as_deref(), restart.as_deref(), &opts)
        }
        Command::Check { scene, processes } => check(&scene, &plugins, processes),
        Command::Validate {
            cases,
            quick,
            list,
            write_docs,
            plots,
        } => {
            // Under mpirun, the processes the cases split over (kept until they end).
            let procs = match processes() {
                Ok(p) => p,
                Err(code) => return code,
            };
            validate::validate(
                &cases,
                quick,
                list,
                write_docs.as_deref(),
                &plots,
                procs.as_ref().map(|p| p.comm.clone()),
            )
        }
        Command::Bench {
            scene,
            steps,
            warmup,
        } => bench::bench(&scene, steps, warmup, &plugins),
        Command::Plot { run_dir } => plot(&run_dir),
        Command::Mesh { shape } => mesh::mesh(shape),
    }
}

/// Size rayon's global pool; an exit code if `--threads` is 0 or the pool cannot be made.
/// The processes of `mpirun` when started by it (MPI initialized), or the exit status of an
/// error said on stderr (a build without MPI started on several processes).
fn processes() -> Result<Option<crate::parallel::comm::Processes>, u8> {
    crate::parallel::comm::launched().map_err(|e| {
        eprintln!("error: {e:#}");
        2
    })
}

fn set_threads(threads: Option<usize>) -> Option<u8> {
    let n = threads?;
    if n == 0 {
        eprintln!("error: --threads must be at least 1");
        return Some(2);
    }
    if let Err(e) = rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build_global()
    {
        eprintln!("error: cannot set up {n} threads: {e}");
        return Some(2);
    }
    None
}

/// `tumble check`: load and validate a scene (its meshes and its plugin sections included),
/// print what it will compute.
fn check(path: &Path, plugins: &PluginList, processes: Option<usize>) -> u8 {
    let scene = match load(path, plugins) {
        Ok(s) => s,
        Err(code) => return code,
    };
    for b in &scene.bodies {
        if let Err(e) = b.shape.build(&scene.base_dir) {
            eprintln!("error: body `{}`: {e}", b.name);
            return 2;
        }
    }
    print!("{}", crate::io::summary::describe(&scene));
    if let Some(p) = processes {
        if p == 0 {
            eprintln!("error: --processes must be at least 1");
            return 2;
        }
        let e = crate::io::estimate::split_estimate(&scene, p);
        println!("  {}", crate::io::estimate::split_words(&e));
    }
    println!("scene `{}` is valid", scene.name);
    0
}

/// `tumble plot`: PNG plots next to a run's CSV files.
fn plot(run_dir: &Path) -> u8 {
    match crate::io::plot::plot_run_dir(run_dir) {
        Ok(paths) => {
            for p in paths {
                println!("{}", p.display());
            }
            0
        }
        Err(e) => {
            eprintln!("error: {e:#}");
            1
        }
    }
}

/// Load and check a scene file, its plugin sections against the built-in plugins and
/// `plugins`; on an error, print it and give exit status 2.
fn load(path: &Path, plugins: &PluginList) -> Result<ValidScene, u8> {
    let fail = |e: &dyn std::fmt::Display| {
        eprintln!("error: {e}");
        2
    };
    let scene = Scene::load(path).map_err(|e: SceneError| fail(&e))?;
    let builtin = crate::systems::builtin();
    let all = builtin
        .iter()
        .map(|p| p.as_ref())
        .chain(plugins.0.iter().map(|p| p.as_ref() as &dyn Plugin));
    scene.plugin_sections().check(all).map_err(|e| fail(&e))?;
    Ok(scene)
}
