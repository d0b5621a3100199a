//! `tumble run`: a scene from start to end with outputs, progress and timings.

use crate::engine::Simulation;
use crate::fields::Sample;
use crate::output::{CsvWriter, atomic_write};
use crate::runlog::RunLog;
use crate::scene::Scene;
use crate::snapshots::Snapshots;
use anyhow::Context;
use indicatif::{ProgressBar, ProgressStyle};
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
    /// Replace an existing output directory.
    pub force: bool,
    /// No progress bar or progress lines.
    pub quiet: bool,
}

/// What a finished run reports.
#[derive(Debug, Clone)]
pub struct RunSummary {
    /// Where the outputs are.
    pub dir: PathBuf,
    /// Steps taken.
    pub steps: u64,
    /// The final state.
    pub last: Sample,
    /// Total seconds per system, in schedule order.
    pub system_seconds: Vec<(&'static str, f64)>,
    /// Wall-clock seconds of the whole run.
    pub wall: f64,
}

/// An output directory that cannot be used (it exists, is a file, or cannot be created): a
/// mistake on the command line or in the scene, so `tumble run` exits with status 2.
#[derive(Debug)]
pub struct BadOutputDir(pub String);

impl std::fmt::Display for BadOutputDir {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for BadOutputDir {}

/// Resolve the output directory and make it (refusing to overwrite without `force`).
pub fn prepare_dir(scene: &Scene, opts: &RunOptions) -> anyhow::Result<PathBuf> {
    let dir = match (&opts.out, &scene.output.dir) {
        (Some(d), _) => d.clone(),
        (None, Some(d)) => PathBuf::from(d),
        (None, None) => Path::new("runs").join(&scene.name),
    };
    let bad = |m: String| anyhow::Error::new(BadOutputDir(m));
    if dir.exists() {
        if !dir.is_dir() {
            return Err(bad(format!(
                "the output directory {} is a file, not a directory; choose another --out",
                dir.display()
            )));
        }
        if !opts.force {
            return Err(bad(format!(
                "the output directory {} exists; pass --force to replace it or --out to choose another",
                dir.display()
            )));
        }
        std::fs::remove_dir_all(&dir).map_err(|e| {
            bad(format!(
                "cannot remove the old output directory {}: {e}",
                dir.display()
            ))
        })?;
    }
    std::fs::create_dir_all(&dir).map_err(|e| {
        bad(format!(
            "cannot create the output directory {}: {}",
            dir.display(),
            crate::output::disk_full(&dir, e)
        ))
    })?;
    Ok(dir)
}

/// Run a scene to its end time (or `opts.until`), writing every output into the run directory.
pub fn run_scene(mut scene: Scene, opts: &RunOptions) -> anyhow::Result<RunSummary> {
    if let Some(t) = opts.until {
        anyhow::ensure!(
            t.is_finite() && t > 0.0,
            "--until must be a positive time, got {t}"
        );
        scene.numerics.end_time = t;
    }
    let dir = prepare_dir(&scene, opts)?;
    let _log = RunLog::create(&dir.join("log.txt"))?;
    run_logged(scene, opts, dir).inspect_err(|e| tracing::error!("error: {e:#}"))
}

/// [`run_scene`] once the run directory and its log are set up.
fn run_logged(scene: Scene, opts: &RunOptions, dir: PathBuf) -> anyhow::Result<RunSummary> {
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
    tracing::info!("{}", crate::runlog::scene_summary(&scene));
    atomic_write(&dir.join("scene.ron"), scene.to_ron().as_bytes())
        .context("cannot write scene.ron")?;
    let mut sim = Simulation::new(scene)?;
    let end = sim.scene().numerics.end_time;
    let every = sim.scene().output.every;
    let mut series = CsvWriter::create(
        &dir.join("series.csv"),
        &["t", "dt", "energy", "enstrophy", "circulation", "max_omega"],
    )
    .context("cannot create series.csv")?;
    let mut bodies_csv = BodiesCsv::create(&dir.join("bodies.csv"), &sim)?;
    let mut contacts_csv = ContactsCsv::create(&dir.join("contacts.csv"), &sim)?;
    let mut snaps = Snapshots::new(&dir, &sim);
    snaps.record(&mut sim);
    write_snapshot(&sim, &mut snaps)?;
    write_row(&mut series, &sim.sample())?;
    if let Some(b) = bodies_csv.as_mut() {
        b.rows(&mut sim)?;
    }

    let bar = progress_bar(opts.quiet);
    let mut totals: Vec<(&'static str, f64)> = Vec::new();
    let mut next_out = every.map(|e| e.min(end));
    let mut last_tenth = 0u32;
    let result: anyhow::Result<()> = (|| {
        while sim.time() < end * (1.0 - 1e-12) {
            let stop = next_out.map_or(end, |o| o.min(end));
            sim.set_stop_at(Some(stop));
            while sim.time() < stop * (1.0 - 1e-12) {
                sim.step()?;
                write_row(&mut series, &sim.sample())?;
                if let Some(b) = bodies_csv.as_mut() {
                    b.rows(&mut sim)?;
                }
                if let Some(c) = contacts_csv.as_mut() {
                    c.rows(&sim)?;
                }
                snaps.record(&mut sim);
                for &(name, s) in &sim.timings().last {
                    match totals.iter_mut().find(|e| e.0 == name) {
                        Some(e) => e.1 += s,
                        None => totals.push((name, s)),
                    }
                }
                let frac = (sim.time() / end).clamp(0.0, 1.0);
                let s = sim.sample();
                bar.set_position((frac * 1000.0) as u64);
                bar.set_message(format!(
                    "step {} t = {:.4} dt = {:.2e} max|ω| = {:.3e}",
                    sim.steps(),
                    s.t,
                    s.dt,
                    s.max_omega
                ));
                let tenth = (frac * 10.0).floor() as u32;
                if bar.is_hidden() && !opts.quiet && tenth > last_tenth {
                    last_tenth = tenth;
                    eprintln!(
                        "  {:>3}%  step {}  t = {:.4}  max|ω| = {:.3e}  {:.1} s",
                        tenth * 10,
                        sim.steps(),
                        s.t,
                        s.max_omega,
                        wall0.elapsed().as_secs_f64()
                    );
                }
            }
            if next_out.is_some_and(|o| sim.time() >= o * (1.0 - 1e-12))
                || sim.time() >= end * (1.0 - 1e-12)
            {
                write_snapshot(&sim, &mut snaps)?;
                if let Some(e) = every {
                    next_out = next_out.map(|o| o + e);
                }
            }
        }
        Ok(())
    })();
    bar.finish_and_clear();
    series.flush().context("cannot write series.csv")?;
    if let Some(b) = bodies_csv.as_mut() {
        b.flush()?;
    }
    if let Some(c) = contacts_csv.as_mut() {
        c.flush()?;
    }
    snaps.finish()?;
    let wall = wall0.elapsed().as_secs_f64();
    let summary = RunSummary {
        dir: dir.clone(),
        steps: sim.steps(),
        last: sim.sample(),
        system_seconds: totals,
        wall,
    };
    match &result {
        Ok(()) => tracing::info!(
            "finished: {} steps to t = {}, {} snapshots, {:.2} s wall",
            summary.steps,
            summary.last.t,
            snaps.count(),
            wall
        ),
        Err(_) => tracing::error!(
            "stopped at step {}, t = {} (the error follows)",
            summary.steps,
            summary.last.t
        ),
    }
    crate::runlog::timings_table(&summary.system_seconds, summary.steps, wall);
    let mut timing_lines = String::from("system,seconds_total,seconds_per_step\n");
    for (name, s) in &summary.system_seconds {
        timing_lines.push_str(&format!(
            "{name},{s:.6},{:.6}\n",
            s / summary.steps.max(1) as f64
        ));
    }
    atomic_write(&dir.join("timings.csv"), timing_lines.as_bytes())
        .context("cannot write timings.csv")?;
    // PNG plots of the time series (also after a stopped run: they show what happened). A
    // plot that cannot be drawn is a warning, not a failed run.
    match crate::plot::plot_run_dir(&dir) {
        Ok(files) => tracing::info!("plots: {}", files.len()),
        Err(e) => {
            tracing::warn!("no plots: {e:#}");
            if !opts.quiet {
                eprintln!("warning: no plots: {e:#}");
            }
        }
    }
    result?;
    Ok(summary)
}

fn progress_bar(quiet: bool) -> ProgressBar {
    if quiet || !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new(1000);
    bar.set_style(
        ProgressStyle::with_template("{bar:30.cyan/blue} {percent:>3}% {msg} [eta {eta}]")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    bar
}

fn write_row(series: &mut CsvWriter, s: &Sample) -> anyhow::Result<()> {
    series
        .row(&[s.t, s.dt, s.energy, s.enstrophy, s.circulation, s.max_omega])
        .context("cannot write series.csv")
}

/// Write a snapshot and log a one-line summary of the state.
fn write_snapshot(sim: &Simulation, snaps: &mut Snapshots) -> anyhow::Result<()> {
    let files = snaps.write(sim)?;
    crate::runlog::output_line(sim, &files);
    Ok(())
}

/// `bodies.csv`: one row per moving body per step.
pub struct BodiesCsv(std::io::BufWriter<std::fs::File>);

/// The header of `bodies.csv`.
pub const BODIES_HEADER: &str = "t,id,name,x,y,z,vx,vy,vz,wx,wy,wz,qw,qx,qy,qz,fx,fy,fz,tx,ty,tz";

impl BodiesCsv {
    /// Create the file if the scene has moving bodies.
    pub fn create(path: &Path, sim: &Simulation) -> anyhow::Result<Option<Self>> {
        if !sim
            .scene()
            .bodies
            .iter()
            .any(|b| !matches!(b.kind, crate::scene::BodyKind::Static))
        {
            return Ok(None);
        }
        use std::io::Write;
        let f = std::fs::File::create(path)
            .with_context(|| format!("cannot create {}", path.display()))?;
        let mut w = std::io::BufWriter::new(f);
        writeln!(w, "{BODIES_HEADER}").context("cannot write bodies.csv")?;
        Ok(Some(BodiesCsv(w)))
    }

    /// Append the current state of every moving body.
    pub fn rows(&mut self, sim: &mut Simulation) -> anyhow::Result<()> {
        use crate::bodies::{Body, Hydro, RigidState};
        use std::io::Write;
        let t = sim.time();
        let mut q = sim.world.query::<(&Body, &RigidState, &Hydro)>();
        for (b, s, h) in q.iter(&sim.world) {
            if b.is_static() {
                continue;
            }
            let o = s.orientation;
            writeln!(
                self.0,
                "{t},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
                b.id,
                b.name,
                s.center.x,
                s.center.y,
                s.center.z,
                s.velocity.x,
                s.velocity.y,
                s.velocity.z,
                s.angular_velocity.x,
                s.angular_velocity.y,
                s.angular_velocity.z,
                o.w,
                o.x,
                o.y,
                o.z,
                h.force.x,
                h.force.y,
                h.force.z,
                h.torque.x,
                h.torque.y,
                h.torque.z
            )
            .context("cannot write bodies.csv")?;
        }
        Ok(())
    }

    /// Flush to disk.
    pub fn flush(&mut self) -> anyhow::Result<()> {
        use std::io::Write;
        self.0.flush().context("cannot write bodies.csv")
    }
}

/// `contacts.csv`: one row per close pair of bodies per step.
pub struct ContactsCsv(std::io::BufWriter<std::fs::File>);

/// The header of `contacts.csv`.
pub const CONTACTS_HEADER: &str = "t,body_a,body_b,gap,normal_force";

impl ContactsCsv {
    /// Create the file if the scene has a dynamic body.
    pub fn create(path: &Path, sim: &Simulation) -> anyhow::Result<Option<Self>> {
        if !sim
            .scene()
            .bodies
            .iter()
            .any(|b| matches!(b.kind, crate::scene::BodyKind::Dynamic))
        {
            return Ok(None);
        }
        use std::io::Write;
        let f = std::fs::File::create(path)
            .with_context(|| format!("cannot create {}", path.display()))?;
        let mut w = std::io::BufWriter::new(f);
        writeln!(w, "{CONTACTS_HEADER}").context("cannot write contacts.csv")?;
        Ok(Some(ContactsCsv(w)))
    }

    /// Append this step's close pairs.
    pub fn rows(&mut self, sim: &Simulation) -> anyhow::Result<()> {
        use std::io::Write;
        let Some(c) = sim
            .world
            .get_resource::<crate::systems::collision::Contacts>()
        else {
            return Ok(());
        };
        let t = sim.time();
        let names = &sim.scene().bodies;
        for r in &c.records {
            writeln!(
                self.0,
                "{t},{},{},{},{}",
                names[r.a].name, names[r.b].name, r.gap, r.force
            )
            .context("cannot write contacts.csv")?;
        }
        Ok(())
    }

    /// Flush to disk.
    pub fn flush(&mut self) -> anyhow::Result<()> {
        use std::io::Write;
        self.0.flush().context("cannot write contacts.csv")
    }
}
