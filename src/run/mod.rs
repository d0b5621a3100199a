//! `tumble run`: a scene from start to end with outputs, progress and timings; checkpoints
//! and restarts (see [`crate::io::checkpoint`]).

use crate::base::fields::Sample;
use crate::io::checkpoint::{self, Checkpoint, CheckpointError, Interrupted, RunProgress};
use crate::io::output::atomic_write;
use crate::io::runlog::RunLog;
use crate::io::snapshots::Snapshots;
use crate::scene::{Scene, ValidScene};
use crate::schedule::PluginList;
use crate::sim::engine::Simulation;
use crate::systems::diagnostics::LAND_TOLERANCE;
use anyhow::Context;
pub mod csv;
pub mod outdir;
pub mod split;

pub use csv::{
    BODIES_HEADER, BodiesCsv, CONTACTS_HEADER, ContactsCsv, SeriesCsv, TIMINGS_HEADER,
    write_timings,
};
use indicatif::{ProgressBar, ProgressStyle};
pub use outdir::{MARKER, prepare_dir};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Options of a run.
#[derive(Debug, Clone, Default)]
pub struct RunOptions {
    /// Output directory (default: the scene's `output.dir`, else `runs/<name>`).
    pub out: Option<PathBuf>,
    /// End time overriding the scene's.
    pub until: Option<f64>,
    /// Replace an existing output directory, if it is one tumble made (it holds the
    /// [`MARKER`] file; see [`outdir`]).
    pub force: bool,
    /// No progress bar or progress lines.
    pub quiet: bool,
    /// Simulated time between checkpoints, overriding the scene's `output.checkpoint_every`.
    pub checkpoint_every: Option<f64>,
    /// Wall-clock seconds between checkpoints, overriding the scene's
    /// `output.checkpoint_wall`; 0 turns them off.
    pub checkpoint_wall: Option<f64>,
    /// Plugins beyond the built-in ones (a user's physics; see `tumble::cli::main_with`).
    pub plugins: PluginList,
    /// The processes the run is split over (`mpirun`; none: one process).
    pub comm: Option<std::sync::Arc<crate::parallel::Comm>>,
}

/// What a finished run reports.
#[derive(Debug, Clone)]
pub struct RunSummary {
    /// Where the outputs are.
    pub dir: PathBuf,
    /// Steps of the run (for a restarted run, counted from the start of the first run).
    pub steps: u64,
    /// Steps taken by this call (fewer than `steps` for a restarted run): what
    /// `system_seconds` covers.
    pub steps_run: u64,
    /// The final state.
    pub last: Sample,
    /// Total seconds per system over the `steps_run` steps, in schedule order.
    pub system_seconds: Vec<(&'static str, f64)>,
    /// Wall-clock seconds of the whole run.
    pub wall: f64,
}

/// An output directory that cannot be used (it exists, is a file, cannot be created, is not
/// one `--force` may replace, or is a scene's `output.dir` outside the current directory): a
/// mistake on the command line or in the scene, so `tumble run` exits with status 2.
#[derive(Debug)]
pub struct BadOutputDir(pub String);

impl std::fmt::Display for BadOutputDir {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for BadOutputDir {}

/// A run refused before it starts, with the numbers why (its outputs would not fit on the
/// disk, or the scene cannot be split over the processes `mpirun` started): `tumble run` exits
/// with status 2.
#[derive(Debug)]
pub struct RefusedRun(pub String);

impl std::fmt::Display for RefusedRun {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for RefusedRun {}

/// Refuse a run of `scene` into `dir` whose outputs would not fit on the disk (see
/// [`crate::io::estimate::outputs`]): the snapshots before compression, the checkpoints on
/// disk at once and the time series over the fewest steps the run can take, against the
/// space free on the disk of `dir` (plus, with `--force`, what the run directory it replaces
/// holds). Nothing is checked where the free space is not known.
fn check_disk(scene: &ValidScene, dir: &Path, force: bool) -> anyhow::Result<()> {
    let Some(free) = crate::io::disk::free_bytes(dir) else {
        return Ok(());
    };
    let replaced = if force && outdir::is_run_dir(dir) {
        dir_bytes(dir)
    } else {
        0
    };
    let out = crate::io::estimate::outputs(scene);
    let need = out.total();
    let have = free.saturating_add(replaced) as f64;
    if need <= have {
        return Ok(());
    }
    let h = crate::io::summary::human_bytes;
    Err(RefusedRun(format!(
        "the outputs of this run would take about {} ({}), more than the {} free on the disk \
         of {}{}; write fewer snapshots (output.every), fewer fields (output.fields) or single \
         precision (output.precision), keep fewer checkpoints (output.checkpoints_kept), or \
         choose another --out",
        h(need),
        out.words(),
        h(free as f64),
        crate::io::disk::existing_ancestor(dir).display(),
        if replaced > 0 {
            format!(
                " (with the {} of the run directory --force replaces)",
                h(replaced as f64)
            )
        } else {
            String::new()
        }
    ))
    .into())
}

/// Bytes of the files under `dir` (symbolic links not followed).
fn dir_bytes(dir: &Path) -> u64 {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return 0;
    };
    entries
        .flatten()
        .map(|e| match e.file_type() {
            Ok(t) if t.is_dir() => dir_bytes(&e.path()),
            Ok(t) if t.is_file() => e.metadata().map_or(0, |m| m.len()),
            _ => 0,
        })
        .sum()
}

/// Apply the command line's end time and checkpoint intervals to `scene`.
fn apply_overrides(scene: ValidScene, opts: &RunOptions) -> anyhow::Result<ValidScene> {
    if let Some(t) = opts.until {
        anyhow::ensure!(
            t.is_finite() && t > 0.0,
            "--until must be a positive time, got {t}"
        );
    }
    if let Some(c) = opts.checkpoint_every {
        anyhow::ensure!(
            c.is_finite() && c > 0.0,
            "--checkpoint-every must be a positive time, got {c}"
        );
    }
    if let Some(w) = opts.checkpoint_wall {
        anyhow::ensure!(
            w.is_finite() && w >= 0.0,
            "--checkpoint-wall must be a number of seconds, 0 for none, got {w}"
        );
    }
    if opts.until.is_none() && opts.checkpoint_every.is_none() && opts.checkpoint_wall.is_none() {
        return Ok(scene);
    }
    Ok(scene.edit(|scene| {
        if let Some(t) = opts.until {
            scene.numerics.end_time = t;
        }
        if let Some(c) = opts.checkpoint_every {
            scene.output.checkpoint_every = Some(c);
        }
        if let Some(w) = opts.checkpoint_wall {
            scene.output.checkpoint_wall = (w > 0.0).then_some(w);
        }
    })?)
}

/// Log an error that ends a run (an interruption is logged where it happens, as a warning).
fn log_error(e: &anyhow::Error) {
    if e.downcast_ref::<Interrupted>().is_none() {
        tracing::error!("error: {e:#}");
    }
}

/// The time series files a checkpoint records the lengths of (`None`: a run without it).
fn csv_lengths(p: &RunProgress) -> [(&'static str, Option<u64>); 3] {
    [
        ("series.csv", Some(p.series_len)),
        ("bodies.csv", p.bodies_len),
        ("contacts.csv", p.contacts_len),
    ]
}

/// Cuts the time series files in `dir` back to their lengths at the checkpoint of `p`.
fn cut_csvs(dir: &Path, p: &RunProgress) -> anyhow::Result<()> {
    for (name, len) in csv_lengths(p) {
        let Some(len) = len else { continue };
        std::fs::OpenOptions::new()
            .write(true)
            .open(dir.join(name))
            .and_then(|f| f.set_len(len))
            .with_context(|| format!("cannot cut {name} back to the checkpoint"))?;
    }
    Ok(())
}

/// A run in progress: the simulation, its open outputs and where they stand.
struct Run {
    sim: Simulation,
    dir: PathBuf,
    series: SeriesCsv,
    bodies_csv: Option<BodiesCsv>,
    contacts_csv: Option<ContactsCsv>,
    /// The field snapshots (VTK and/or HDF5, with their indexes) and `series.h5`.
    snaps: Snapshots,
    next_out: Option<f64>,
    /// The next checkpoint time, when checkpoints are periodic.
    next_ckpt: Option<f64>,
    /// (t, step, file) of the latest checkpoint, if this run wrote or started from one.
    last_ckpt: Option<(f64, u64, PathBuf)>,
    /// When this process started the run or last wrote a checkpoint (for
    /// `output.checkpoint_wall`).
    since_ckpt: Instant,
}

/// Run a scene to its end time (or `opts.until`), writing every output into the run directory.
pub fn run_scene(scene: ValidScene, opts: &RunOptions) -> anyhow::Result<RunSummary> {
    if let Some(comm) = opts.comm.as_ref().filter(|c| c.size() > 1) {
        return split::run_split(scene, opts, comm.clone());
    }
    let scene = apply_overrides(scene, opts)?;
    check_disk(&scene, &outdir::resolve(&scene, opts)?, opts.force)?;
    let dir = prepare_dir(&scene, opts)?;
    let _log = RunLog::create(&dir.join("log.txt"))?;
    start_run(scene, opts, dir).inspect_err(log_error)
}

/// [`run_scene`] once the run directory and its log are set up.
fn start_run(scene: ValidScene, opts: &RunOptions, dir: PathBuf) -> anyhow::Result<RunSummary> {
    let wall0 = Instant::now();
    let grid = scene.grid();
    tracing::info!(
        "tumble {} run of scene `{}`: {}D grid {}x{}x{} (h = {}), end time {}, {} threads, output in {}",
        env!("CARGO_PKG_VERSION"),
        scene.name,
        grid.dim,
        grid.n[0],
        grid.n[1],
        grid.n[2],
        grid.h,
        scene.numerics.end_time,
        rayon::current_num_threads(),
        dir.display()
    );
    tracing::info!("{}", crate::io::runlog::scene_summary(&scene));
    for w in scene.warnings() {
        tracing::warn!("{w}");
        if !opts.quiet {
            eprintln!("warning: {w}");
        }
    }
    atomic_write(&dir.join("scene.ron"), scene.to_ron().as_bytes())
        .context("cannot write scene.ron")?;
    let end = scene.numerics.end_time;
    let every = scene.output.every;
    let mut sim = Simulation::builder(scene)
        .add_plugins(&opts.plugins)
        .build()?;
    let mut series = SeriesCsv::create(&dir.join("series.csv"), &sim)?;
    let mut bodies_csv = BodiesCsv::create(&dir.join("bodies.csv"), &sim)?;
    let contacts_csv = ContactsCsv::create(&dir.join("contacts.csv"), &sim)?;
    let mut snaps = Snapshots::new(&dir, &sim);
    snaps.record(&mut sim);
    write_snapshot(&sim, &mut snaps)?;
    series.row(&sim)?;
    if let Some(b) = bodies_csv.as_mut() {
        b.rows(&mut sim)?;
    }
    let next_ckpt = sim.scene().output.checkpoint_every;
    let run = Run {
        sim,
        dir,
        series,
        bodies_csv,
        contacts_csv,
        snaps,
        next_out: every.map(|e| e.min(end)),
        next_ckpt,
        last_ckpt: None,
        since_ckpt: wall0,
    };
    drive(run, opts, wall0)
}

/// Continue the run of `checkpoint` (a file in its run directory, or the run directory: then
/// its latest complete checkpoint, see [`checkpoint::resolve`]) to the scene's end time (or
/// `opts.until`), appending to the run directory's outputs and its log. `scene`, if given
/// (with its file for messages), must be the checkpoint's; so must the run directory's
/// `scene.ron`. First the outputs are cut back to the checkpoint: the CSV time series to its
/// rows, the snapshots written after it removed, `fields.pvd` and `fields.xmf` to the
/// snapshots kept, `series.h5` to the checkpoint's steps.
pub fn restart_run(
    checkpoint: &Path,
    scene: Option<(&Path, ValidScene)>,
    opts: &RunOptions,
) -> anyhow::Result<RunSummary> {
    let wall0 = Instant::now();
    let checkpoint = &checkpoint::resolve(checkpoint)?;
    let ck = Checkpoint::load(checkpoint)?;
    let run_scene = ck.scene()?;
    same_scene(&ck, &run_scene, scene.as_ref())?;
    let dir = match checkpoint.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let scene_file = dir.join("scene.ron");
    if let Ok(text) = std::fs::read_to_string(&scene_file) {
        let file = scene_file.display().to_string();
        let same = Scene::parse_in(&text, &file, "", &run_scene.base_dir)
            .is_ok_and(|s| checkpoint::same_run(&s, &run_scene));
        if !same {
            return Err(ck
                .error(format!(
                    "{} describes another scene: the checkpoint does not belong to this run \
                     directory",
                    scene_file.display()
                ))
                .into());
        }
    }
    let run_scene = apply_overrides(run_scene, opts)?;
    let (t0, step0) = (ck.time.t, ck.time.step);
    let end = run_scene.numerics.end_time;
    if opts.until.is_some() && end <= t0 {
        return Err(ck
            .error(format!(
                "--until {end} is not after the checkpoint's time t = {t0}"
            ))
            .into());
    }
    let p = &ck.progress;
    for (name, len) in csv_lengths(p) {
        let Some(len) = len else { continue };
        let have = std::fs::metadata(dir.join(name)).map(|m| m.len()).ok();
        if have.is_none_or(|h| h < len) {
            return Err(ck
                .error(format!(
                    "{} has {} bytes, fewer than the {len} it had at the checkpoint: the run \
                     directory does not match the checkpoint",
                    dir.join(name).display(),
                    have.map_or("no".to_string(), |h| h.to_string())
                ))
                .into());
        }
    }
    let mut sim = Simulation::builder(run_scene)
        .add_plugins(&opts.plugins)
        .build()?;
    ck.restore(&mut sim)?;
    // The snapshots kept, their indexes and series.h5, read back (nothing is changed yet).
    let snaps = Snapshots::resume(&dir, &sim, p).map_err(|m| ck.error(m))?;
    // Checked: from here on the run directory is changed, and the log goes on.
    let _log = RunLog::append(&dir.join("log.txt"))?;
    tracing::info!(
        "tumble {} restart from {} at step {step0}, t = {t0}: end time {end}, {} threads",
        env!("CARGO_PKG_VERSION"),
        checkpoint.display(),
        rayon::current_num_threads()
    );
    continue_run(sim, snaps, &ck, &dir, opts, wall0).inspect_err(log_error)
}

/// [`restart_run`] once the checkpoint and the run directory are checked and the log is open.
fn continue_run(
    sim: Simulation,
    mut snaps: Snapshots,
    ck: &Checkpoint,
    dir: &Path,
    opts: &RunOptions,
    wall0: Instant,
) -> anyhow::Result<RunSummary> {
    let p = &ck.progress;
    checkpoint::remove_temp_files(dir)
        .with_context(|| format!("cannot clean up {}", dir.display()))?;
    let slices = dir.join(crate::io::slices::SLICE_DIR);
    if slices.is_dir() {
        checkpoint::remove_temp_files(&slices)
            .with_context(|| format!("cannot clean up {}", slices.display()))?;
    }
    // Checkpoints after this one belong to the run this restart replaces.
    checkpoint::remove_after(dir, ck.time.step)
        .with_context(|| format!("cannot remove later checkpoints in {}", dir.display()))?;
    cut_csvs(dir, p)?;
    // Snapshots written after the checkpoint are written again (or not, with another end).
    snaps.cut_back()?;
    atomic_write(&dir.join("scene.ron"), sim.scene().to_ron().as_bytes())
        .context("cannot write scene.ron")?;
    let series = SeriesCsv::append(&dir.join("series.csv"), &sim)?;
    let bodies_csv = match p.bodies_len {
        Some(_) => Some(BodiesCsv::append(&dir.join("bodies.csv"))?),
        None => None,
    };
    let contacts_csv = match p.contacts_len {
        Some(_) => Some(ContactsCsv::append(&dir.join("contacts.csv"))?),
        None => None,
    };
    let next_ckpt = sim
        .scene()
        .output
        .checkpoint_every
        .map(|c| next_multiple(ck.time.t, c));
    let run = Run {
        sim,
        dir: dir.to_path_buf(),
        series,
        bodies_csv,
        contacts_csv,
        snaps,
        next_out: p.next_out,
        next_ckpt,
        last_ckpt: Some((ck.time.t, ck.time.step, ck.file.clone())),
        since_ckpt: Instant::now(),
    };
    drive(run, opts, wall0)
}

/// An error if `given` (a scene file given with `--restart`, and its scene) is not the scene
/// `ck` was written with.
fn same_scene(
    ck: &Checkpoint,
    run_scene: &ValidScene,
    given: Option<&(&Path, ValidScene)>,
) -> anyhow::Result<()> {
    match given {
        Some((file, given)) if !checkpoint::same_run(given, run_scene) => Err(ck
            .error(format!(
                "the scene {} is not the one the checkpoint was written with (only the end \
                 time and the checkpoint interval may change on a restart; see its scene in \
                 the run directory's scene.ron)",
                file.display()
            ))
            .into()),
        _ => Ok(()),
    }
}

/// The length of `dir`'s file `name` once its data are on the disk (what a checkpoint records
/// of a time series it will cut back to).
fn synced_len(dir: &Path, name: &str) -> anyhow::Result<u64> {
    let path = dir.join(name);
    let f =
        std::fs::File::open(&path).with_context(|| format!("cannot open {}", path.display()))?;
    f.sync_all()
        .with_context(|| format!("cannot sync {}", path.display()))?;
    Ok(f.metadata()?.len())
}

/// Whether a snapshot is due after the step that reached `t` (the step `dt`): the first step at
/// or after the output time `next_out` (one missed by the rounding of the clock, a sum of steps,
/// is reached), and the end; then `next_out` moves past `t` (a step longer than `every` passes
/// several output times: one snapshot).
fn snapshot_due(t: f64, dt: f64, end: f64, every: Option<f64>, next_out: &mut Option<f64>) -> bool {
    let slack = LAND_TOLERANCE * dt;
    let due = |o: Option<f64>| o.is_some_and(|o| t >= o * (1.0 - 1e-12) - slack);
    if !(due(*next_out) || t >= end * (1.0 - 1e-12)) {
        return false;
    }
    if let Some(e) = every {
        while let Some(o) = next_out.filter(|&o| due(Some(o)) && o + e > o) {
            *next_out = Some(o + e);
        }
    }
    true
}

/// The first multiple of `every` after `t`.
fn next_multiple(t: f64, every: f64) -> f64 {
    let mut k = (t / every).floor() + 1.0;
    if k * every <= t * (1.0 + 1e-12) {
        k += 1.0;
    }
    k * every
}

impl Run {
    /// Write a checkpoint of the current state (after flushing and syncing the time series it
    /// records the lengths of, and writing `series.h5`, which a restart reads back).
    fn checkpoint(&mut self) -> anyhow::Result<()> {
        self.series.flush()?;
        if let Some(b) = self.bodies_csv.as_mut() {
            b.flush()?;
        }
        if let Some(c) = self.contacts_csv.as_mut() {
            c.flush()?;
        }
        self.snaps.finish()?;
        let synced_len = |name: &str| synced_len(&self.dir, name);
        let progress = RunProgress {
            next_out: self.next_out,
            snapshots: self.snaps.count() as u64,
            pvd: self.snaps.pvd_entries().to_vec(),
            series_len: synced_len("series.csv")?,
            bodies_len: match self.bodies_csv {
                Some(_) => Some(synced_len("bodies.csv")?),
                None => None,
            },
            contacts_len: match self.contacts_csv {
                Some(_) => Some(synced_len("contacts.csv")?),
                None => None,
            },
        };
        let (t, step) = (self.sim.time(), self.sim.steps());
        let path = self.dir.join(checkpoint::file_name(step));
        checkpoint::save(&path, &mut self.sim, &progress)
            .with_context(|| format!("cannot write {}", path.display()))?;
        tracing::info!("checkpoint at step {step}, t = {t}: {}", path.display());
        self.last_ckpt = Some((t, step, path));
        self.since_ckpt = Instant::now();
        // Only once the new one is complete are the oldest beyond output.checkpoints_kept
        // deleted.
        let kept = self.sim.scene().output.checkpoints_kept.max(1);
        for p in checkpoint::prune(&self.dir, kept)
            .with_context(|| format!("cannot remove old checkpoints in {}", self.dir.display()))?
        {
            tracing::info!("removed the old checkpoint {}", p.display());
        }
        Ok(())
    }

    /// After a step whose outputs are written: checkpoint if one is due (by simulated time,
    /// `output.checkpoint_every`, or by wall-clock time, `output.checkpoint_wall`) or a stop
    /// was asked for, and stop if so.
    fn after_step(&mut self, end: f64) -> anyhow::Result<()> {
        let t = self.sim.time();
        let wall_due = self
            .sim
            .scene()
            .output
            .checkpoint_wall
            .is_some_and(|w| self.since_ckpt.elapsed().as_secs_f64() >= w);
        let sim_due = self.next_ckpt.is_some_and(|c| t >= c * (1.0 - 1e-12));
        let stop = checkpoint::interrupt_requested() && t < end * (1.0 - 1e-12);
        if wall_due || sim_due || stop {
            self.checkpoint()?;
        }
        // The checkpoints in simulated time keep their own schedule.
        if (sim_due || stop)
            && let Some(every) = self.sim.scene().output.checkpoint_every
        {
            self.next_ckpt = Some(next_multiple(t, every));
        }
        if stop {
            return Err(Interrupted {
                step: self.sim.steps(),
                t,
                checkpoint: self.dir.join(checkpoint::file_name(self.sim.steps())),
            }
            .into());
        }
        Ok(())
    }

    /// The message of a failed step, naming the last good checkpoint if there is one.
    fn failed(&self, e: anyhow::Error) -> anyhow::Error {
        match &self.last_ckpt {
            Some((t, step, path)) => {
                anyhow::anyhow!(
                    "{e:#}; the last good checkpoint is {} (step {step}, t = {t})",
                    path.display()
                )
            }
            None => e,
        }
    }
}

/// The stepping loop of a run, then its closing outputs (`series.h5`, timings, plots, the
/// log's last lines).
fn drive(mut run: Run, opts: &RunOptions, wall0: Instant) -> anyhow::Result<RunSummary> {
    let steps0 = run.sim.steps();
    let mut progress = Progress::new(&run.sim, opts.quiet, wall0);
    let mut totals: Vec<(&'static str, f64)> = Vec::new();
    let result = run.step_to_end(&mut progress, &mut totals);
    progress.bar.finish_and_clear();
    let (summary, snapshots) = run.close(steps0, totals, wall0)?;
    log_end(&result, &summary, snapshots);
    crate::io::runlog::timings_table(&summary.system_seconds, summary.steps_run, summary.wall);
    write_timings(
        &summary.dir.join("timings.csv"),
        &summary.system_seconds,
        summary.steps_run,
    )?;
    plot(&summary.dir, opts.quiet);
    result?;
    Ok(summary)
}

impl Run {
    /// Step to the end time, writing each step's outputs, snapshots and checkpoints as they
    /// fall due; then a final checkpoint.
    fn step_to_end(
        &mut self,
        progress: &mut Progress,
        totals: &mut Vec<(&'static str, f64)>,
    ) -> anyhow::Result<()> {
        let end = self.sim.scene().numerics.end_time;
        let every = self.sim.scene().output.every;
        // The time the steps land on: the next output time with an Adaptive step, only the
        // end time with a Fixed one (see `TimeStep`), so a Fixed run does not depend on the
        // output times.
        let lands_on_outputs = self.sim.scene().numerics.dt.lands_on_outputs();
        let mut stop_at = None;
        while self.sim.time() < end * (1.0 - 1e-12) {
            let stop = match self.next_out {
                Some(o) if lands_on_outputs => o.min(end),
                _ => end,
            };
            if stop_at != Some(stop) {
                self.sim.set_stop_at(Some(stop));
                stop_at = Some(stop);
            }
            if let Err(e) = self.sim.step() {
                return Err(self.failed(e));
            }
            self.record_step()?;
            add_timings(totals, &self.sim.timings().last);
            progress.show(&self.sim, end);
            self.snapshot_if_due(end, every)?;
            self.after_step(end)?;
        }
        self.final_checkpoint()
    }

    /// The time series rows of the step just taken (series, bodies, contacts, `series.h5`).
    fn record_step(&mut self) -> anyhow::Result<()> {
        let sim = &mut self.sim;
        self.series.row(sim)?;
        if let Some(b) = self.bodies_csv.as_mut() {
            b.rows(sim)?;
        }
        if let Some(c) = self.contacts_csv.as_mut() {
            c.rows(sim)?;
        }
        self.snaps.record(sim);
        Ok(())
    }

    /// A snapshot after the first step at or after each output time (with its true time),
    /// and at the end.
    fn snapshot_if_due(&mut self, end: f64, every: Option<f64>) -> anyhow::Result<()> {
        let (t, dt) = (self.sim.time(), self.sim.sample().dt);
        if snapshot_due(t, dt, end, every, &mut self.next_out) {
            write_snapshot(&self.sim, &mut self.snaps)?;
        }
        Ok(())
    }

    /// A final checkpoint, from which the run can be continued (`--restart --until`), when
    /// checkpoints are periodic in simulated time or the run wrote or started from one (by
    /// wall-clock time, an interruption), and the last one is not of this step.
    fn final_checkpoint(&mut self) -> anyhow::Result<()> {
        if (self.sim.scene().output.checkpoint_every.is_some() || self.last_ckpt.is_some())
            && self
                .last_ckpt
                .as_ref()
                .is_none_or(|(_, s, _)| *s != self.sim.steps())
        {
            self.checkpoint()?;
        }
        Ok(())
    }

    /// Flush and close the outputs; the run's summary (`steps0` the steps before it,
    /// `totals` the seconds per system) and the number of snapshots written.
    fn close(
        self,
        steps0: u64,
        totals: Vec<(&'static str, f64)>,
        wall0: Instant,
    ) -> anyhow::Result<(RunSummary, usize)> {
        let Run {
            sim,
            dir,
            mut series,
            mut bodies_csv,
            mut contacts_csv,
            mut snaps,
            ..
        } = self;
        series.flush()?;
        if let Some(b) = bodies_csv.as_mut() {
            b.flush()?;
        }
        if let Some(c) = contacts_csv.as_mut() {
            c.flush()?;
        }
        snaps.finish()?;
        let summary = RunSummary {
            dir,
            steps: sim.steps(),
            steps_run: sim.steps() - steps0,
            last: sim.sample(),
            system_seconds: totals,
            wall: wall0.elapsed().as_secs_f64(),
        };
        Ok((summary, snaps.count()))
    }
}

/// Add one step's seconds per system to the run's totals (kept in schedule order).
fn add_timings(totals: &mut Vec<(&'static str, f64)>, last: &[(&'static str, f64)]) {
    for &(name, s) in last {
        match totals.iter_mut().find(|e| e.0 == name) {
            Some(e) => e.1 += s,
            None => totals.push((name, s)),
        }
    }
}

/// Steps in the window the time left is estimated over.
const ETA_WINDOW: usize = 50;

/// The progress a run shows: a bar on a terminal, else a line at every tenth of the run
/// (neither with `--quiet`); the line also goes to the log. Both give the time left, from the
/// wall time the last [`ETA_WINDOW`] steps took per simulated time.
struct Progress {
    bar: ProgressBar,
    /// The last tenth of the run reached, 0 to 10.
    last_tenth: u32,
    quiet: bool,
    wall0: Instant,
    /// (wall clock, simulated time) after each of the last steps, oldest first.
    window: std::collections::VecDeque<(Instant, f64)>,
}

impl Progress {
    /// The progress of a run starting from the state of `sim`.
    fn new(sim: &Simulation, quiet: bool, wall0: Instant) -> Self {
        let end = sim.scene().numerics.end_time;
        let mut window = std::collections::VecDeque::with_capacity(ETA_WINDOW + 1);
        window.push_back((Instant::now(), sim.time()));
        Progress {
            bar: progress_bar(quiet),
            last_tenth: ((sim.time() / end).clamp(0.0, 1.0) * 10.0).floor() as u32,
            quiet,
            wall0,
            window,
        }
    }

    /// Wall seconds left to `end` from simulated time `t`, at the pace of the steps in the
    /// window; `None` before a step has advanced the clock.
    fn seconds_left(&self, t: f64, end: f64) -> Option<f64> {
        let (&(w0, t0), &(w1, t1)) = (self.window.front()?, self.window.back()?);
        let dt = t1 - t0;
        (dt > 0.0).then(|| (w1 - w0).as_secs_f64() / dt * (end - t).max(0.0))
    }

    /// Show the state after a step: the bar's position and message, or a line when a new
    /// tenth of the run is reached.
    fn show(&mut self, sim: &Simulation, end: f64) {
        self.window.push_back((Instant::now(), sim.time()));
        if self.window.len() > ETA_WINDOW + 1 {
            self.window.pop_front();
        }
        let frac = (sim.time() / end).clamp(0.0, 1.0);
        let s = sim.sample();
        let left = self
            .seconds_left(sim.time(), end)
            .map_or("?".to_string(), crate::io::estimate::human_seconds);
        self.bar.set_position((frac * 1000.0) as u64);
        self.bar.set_message(format!(
            "step {} t = {:.4} dt = {:.2e} max|ω| = {:.3e}, about {left} left",
            sim.steps(),
            s.t,
            s.dt,
            s.max_omega
        ));
        let tenth = (frac * 10.0).floor() as u32;
        if tenth > self.last_tenth {
            self.last_tenth = tenth;
            let elapsed = self.wall0.elapsed().as_secs_f64();
            tracing::info!(
                "progress: {}%, step {}, t = {:.6}, {:.1} s elapsed, about {left} left",
                tenth * 10,
                sim.steps(),
                s.t,
                elapsed
            );
            if self.bar.is_hidden() && !self.quiet {
                eprintln!(
                    "  {:>3}%  step {}  t = {:.4}  max|ω| = {:.3e}  {elapsed:.1} s, about {left} left",
                    tenth * 10,
                    sim.steps(),
                    s.t,
                    s.max_omega,
                );
            }
        }
    }
}

/// Log how the run ended: finished, interrupted (a warning) or stopped by an error.
fn log_end(result: &anyhow::Result<()>, summary: &RunSummary, snapshots: usize) {
    match result {
        Ok(()) => tracing::info!(
            "finished: {} steps to t = {}, {} snapshots, {:.2} s wall",
            summary.steps,
            summary.last.t,
            snapshots,
            summary.wall
        ),
        Err(e) if e.downcast_ref::<Interrupted>().is_some() => tracing::warn!("{e}"),
        Err(_) => tracing::error!(
            "stopped at step {}, t = {} (the error follows)",
            summary.steps,
            summary.last.t
        ),
    }
}

/// PNG plots of the time series in `dir` (also after a stopped run: they show what
/// happened). A plot that cannot be drawn is a warning, not a failed run.
fn plot(dir: &Path, quiet: bool) {
    match crate::io::plot::plot_run_dir(dir) {
        Ok(files) => tracing::info!("plots: {}", files.len()),
        Err(e) => {
            tracing::warn!("no plots: {e:#}");
            if !quiet {
                eprintln!("warning: no plots: {e:#}");
            }
        }
    }
}

/// Whether `e` (from [`run_scene`] or [`restart_run`]) is a refused checkpoint or restart.
pub fn is_refused_restart(e: &anyhow::Error) -> bool {
    e.downcast_ref::<CheckpointError>().is_some()
}

fn progress_bar(quiet: bool) -> ProgressBar {
    if quiet || !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new(1000);
    bar.set_style(
        ProgressStyle::with_template("{bar:30.cyan/blue} {percent:>3}% {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    bar
}

/// Write a snapshot and log a one-line summary of the state.
fn write_snapshot(sim: &Simulation, snaps: &mut Snapshots) -> anyhow::Result<()> {
    let files = snaps.write(sim)?;
    crate::io::runlog::output_line(sim, &files);
    Ok(())
}
