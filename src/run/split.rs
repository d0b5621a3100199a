//! A run split over processes (`mpirun -np N tumble run SCENE`): every process steps its slab
//! of the grid in step with the others ([`crate::parallel`]); rank 0 makes the run directory
//! and writes the time series, the log, the plots and the index of each snapshot, and every
//! process writes its piece of each snapshot ([`crate::io::snapshots::write_pieces`]) and of
//! each checkpoint ([`checkpoint::piece_file_name`]: rank 0's is the usual
//! `checkpoint_NNNNNN.bin`, which carries the scene and the run's progress). With HDF5 output
//! each process writes its piece of each snapshot and rank 0 a file of virtual datasets that
//! reads as the whole snapshot, `fields.xmf` and `series.h5`
//! ([`crate::io::snapshots::SplitHdf5`]).
//!
//! The clock is the one-process run's: the same output times, landed on the same way, and every
//! sum over the grid is taken per z-plane and then plane after plane
//! ([`crate::parallel::PlaneSums`]), so the outputs are the one-process run's bit for bit. Every decision that could differ between processes (a wall-clock
//! checkpoint, an interruption) is taken together. A restart (`mpirun -np N tumble run
//! --restart DIR`) needs the same number of processes and continues bit for bit.
//!
//! The bodies are held whole by every process (their sums over the grid are added over the
//! processes, bit for bit the same on each), so rank 0 writes `bodies.csv` and `contacts.csv` from its own copy, and with HDF5
//! output their series in `series.h5`.
//!
//! Rank 0 also writes the body surfaces (`bodies_NNNNNN.vtp`, `bodies.pvd`), and with HDF5
//! output their HDF5 form (`bodies_NNNNNN.h5`, `bodies.xmf`), the one-process files
//! ([`crate::io::snapshots::write_split_surfaces`]); a restart cuts both back to the checkpoint.
//!
//! With a free surface rank 0 adds its zero level to them, from the whole grid's level set that
//! every process holds.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use anyhow::Context;

use super::{
    BodiesCsv, ContactsCsv, Progress, RunOptions, RunSummary, SeriesCsv, add_timings,
    apply_overrides, next_multiple, plot,
};
use crate::io::checkpoint::{self, Checkpoint, RunProgress};
use crate::io::output::{PvdSeries, atomic_write};
use crate::io::runlog::RunLog;
use crate::io::snapshots::SplitHdf5;
use crate::io::surfaces::SurfaceSeries;
use crate::parallel::Comm;
use crate::scene::{OutputFormat, ValidScene};
use crate::sim::engine::Simulation;

/// The state of a split run's outputs: rank 0's files, and where every process stands.
struct Outputs {
    dir: PathBuf,
    /// `series.csv` (rank 0).
    series: Option<SeriesCsv>,
    /// `bodies.csv` and `contacts.csv` (rank 0, a scene with bodies).
    bodies: Option<BodiesCsv>,
    contacts: Option<ContactsCsv>,
    /// `fields.pvd` (rank 0, VTK output with fields).
    pvd: Option<PvdSeries>,
    /// Whether snapshots have fields to write.
    vtk: bool,
    /// HDF5 snapshots and `series.h5` (a scene asking for them).
    hdf5: Option<SplitHdf5>,
    /// The body surfaces, `bodies_NNNNNN.vtp` and `bodies.pvd` (rank 0, a scene with bodies).
    surfaces: Option<SurfaceSeries>,
    /// With a free surface: its level set gathered onto rank 0 for the surfaces (every process).
    level_set: Option<crate::io::snapshots::WholeLevelSet>,
    /// Snapshots written.
    count: usize,
    next_out: Option<f64>,
    next_ckpt: Option<f64>,
    /// (step, rank 0's file) of the latest checkpoint.
    last_ckpt: Option<(u64, PathBuf)>,
    since_ckpt: Instant,
}

/// Run `scene` split over the processes of `comm` (more than one).
pub fn run_split(
    scene: ValidScene,
    opts: &RunOptions,
    comm: Arc<Comm>,
) -> anyhow::Result<RunSummary> {
    let wall0 = Instant::now();
    let scene = apply_overrides(scene, opts)?;
    // A scene that cannot split is refused (exit status 2) before anything is written.
    if let Err(e) = crate::sim::engine::split_scene(&scene, comm.clone()) {
        return Err(super::RefusedRun(format!("{e:#}")).into());
    }
    // Rank 0 makes the directory; the others learn whether it could.
    let mut log = None;
    let prepared: anyhow::Result<PathBuf> = if comm.is_root() {
        super::check_disk(&scene, &super::outdir::resolve(&scene, opts)?, opts.force)
            .and_then(|()| super::prepare_dir(&scene, opts))
            .and_then(|dir| {
                log = Some(RunLog::create(&dir.join("log.txt"))?);
                Ok(dir)
            })
    } else {
        super::outdir::resolve(&scene, opts)
    };
    let dir = agree(&comm, prepared, "prepare the run directory")?;
    let root = comm.is_root();
    let built = Simulation::builder(scene.clone())
        .add_plugins(&opts.plugins)
        .on_processes(comm.clone())
        .build();
    let sim = agree(&comm, built, "set the simulation up")?;
    if root {
        log_start(&sim, &comm, &dir, "run");
        atomic_write(&dir.join("scene.ron"), scene.to_ron().as_bytes())
            .context("cannot write scene.ron")?;
    }
    let every = scene.output.every;
    let end = scene.numerics.end_time;
    let out = Outputs {
        series: if root {
            Some(SeriesCsv::create(&dir.join("series.csv"), &sim)?)
        } else {
            None
        },
        bodies: if root {
            BodiesCsv::create(&dir.join("bodies.csv"), &sim)?
        } else {
            None
        },
        contacts: if root {
            ContactsCsv::create(&dir.join("contacts.csv"), &sim)?
        } else {
            None
        },
        pvd: (root && vtk(&sim)).then(|| PvdSeries::new(dir.join("fields.pvd"))),
        vtk: vtk(&sim),
        hdf5: SplitHdf5::new(&dir, &sim, root),
        surfaces: if root {
            crate::io::snapshots::split_surfaces(&dir, &sim)
        } else {
            None
        },
        level_set: crate::io::snapshots::WholeLevelSet::new(&sim),
        count: 0,
        next_out: every.map(|e| e.min(end)),
        next_ckpt: scene.output.checkpoint_every,
        last_ckpt: None,
        since_ckpt: wall0,
        dir,
    };
    logged(drive_split(sim, opts, &comm, out, wall0, true), log)
}

/// Continue a split run from its checkpoint `path` (rank 0's file, or the run directory: then
/// the latest checkpoint of which every process's piece reads back) on the processes of `comm`,
/// as many as wrote it. `scene`, if given (with its file for messages), must be the
/// checkpoint's, as on one process.
pub fn restart_split(
    path: &Path,
    scene: Option<(&Path, ValidScene)>,
    opts: &RunOptions,
    comm: Arc<Comm>,
) -> anyhow::Result<RunSummary> {
    let wall0 = Instant::now();
    let (rank, ranks) = (comm.rank(), comm.size());
    let found = resolve(path, ranks);
    let (dir, step) = agree(&comm, found, "find the checkpoint")?;
    let loaded = Checkpoint::load(&dir.join(checkpoint::file_name(step)))
        .and_then(|c0| {
            Ok((
                Checkpoint::load(&dir.join(checkpoint::piece_file_name(step, rank, ranks)))?,
                c0,
            ))
        })
        .map_err(anyhow::Error::from);
    let (mine, ck0) = agree(&comm, loaded, "read the checkpoint")?;
    let run_scene = ck0.scene()?;
    super::same_scene(&ck0, &run_scene, scene.as_ref())?;
    let scene = apply_overrides(run_scene, opts)?;
    let built = Simulation::builder(scene.clone())
        .add_plugins(&opts.plugins)
        .on_processes(comm.clone())
        .build()
        .and_then(|mut sim| {
            mine.restore(&mut sim)?;
            Ok(sim)
        });
    let sim = agree(&comm, built, "restore the checkpoint")?;
    let p = &ck0.progress;
    let root = comm.is_root();
    // The HDF5 snapshots kept and series.h5, read back by rank 0 (nothing is changed yet).
    let resumed = SplitHdf5::resume(&dir, &sim, p.snapshots as usize, root)
        .map_err(|m| anyhow::Error::from(ck0.error(m)));
    let mut hdf5 = agree(&comm, resumed, "read the run's HDF5 files back")?;
    let mut log = None;
    // Rank 0's files cut back to the checkpoint; every process drops its later checkpoints.
    type Csvs = (
        SeriesCsv,
        Option<BodiesCsv>,
        Option<ContactsCsv>,
        Option<SurfaceSeries>,
    );
    let cut: anyhow::Result<Option<Csvs>> = (|| {
        for (s, _) in checkpoint::list(&dir)?
            .into_iter()
            .filter(|(s, _)| *s > step)
        {
            let own = dir.join(checkpoint::piece_file_name(s, rank, ranks));
            if own.is_file() {
                std::fs::remove_file(&own)
                    .with_context(|| format!("cannot remove {}", own.display()))?;
            }
        }
        // The snapshots written after the checkpoint are written again as the run gets there:
        // each process removes its pieces of them, rank 0 their indexes.
        for k in p.snapshots as usize.. {
            let piece = dir.join(format!("fields_{k:06}_{rank}.vti"));
            let index = dir.join(format!("fields_{k:06}.pvti"));
            if !piece.is_file() && !index.is_file() {
                break;
            }
            for f in [piece, index].iter().filter(|f| f.is_file()) {
                if root || f.extension().is_some_and(|e| e == "vti") {
                    std::fs::remove_file(f)
                        .with_context(|| format!("cannot remove {}", f.display()))?;
                }
            }
        }
        if let Some(h) = hdf5.as_mut() {
            h.cut_back(&dir, p.snapshots as usize, rank)?;
        }
        if !root {
            return Ok(None);
        }
        log = Some(RunLog::append(&dir.join("log.txt"))?);
        // The body surfaces after the checkpoint go too; those kept are read back.
        for k in p.snapshots as usize.. {
            let f = dir.join(format!("bodies_{k:06}.vtp"));
            if !f.is_file() {
                break;
            }
            std::fs::remove_file(&f).with_context(|| format!("cannot remove {}", f.display()))?;
        }
        let surfaces = crate::io::snapshots::resume_surfaces(&dir, &sim, p.snapshots as usize)
            .map_err(|m| anyhow::Error::from(ck0.error(m)))?;
        if let Some(s) = &surfaces {
            s.pvd().write().context("cannot write bodies.pvd")?;
        }
        super::cut_csvs(&dir, p)?;
        let bodies = match p.bodies_len {
            Some(_) => Some(BodiesCsv::append(&dir.join("bodies.csv"))?),
            None => None,
        };
        let contacts = match p.contacts_len {
            Some(_) => Some(ContactsCsv::append(&dir.join("contacts.csv"))?),
            None => None,
        };
        Ok(Some((
            SeriesCsv::append(&dir.join("series.csv"), &sim)?,
            bodies,
            contacts,
            surfaces,
        )))
    })();
    // Every process has listed the later checkpoints before any is removed.
    comm.barrier();
    let csvs = agree(&comm, cut, "cut the run's files back to the checkpoint")?;
    let (series, bodies, contacts, surfaces) = match csvs {
        Some((s, b, c, f)) => (Some(s), b, c, f),
        None => (None, None, None, None),
    };
    if root {
        log_start(&sim, &comm, &dir, &format!("restart from step {step}"));
        atomic_write(&dir.join("scene.ron"), scene.to_ron().as_bytes())
            .context("cannot write scene.ron")?;
    }
    let out = Outputs {
        series,
        bodies,
        contacts,
        pvd: (root && vtk(&sim))
            .then(|| PvdSeries::with_entries(dir.join("fields.pvd"), p.pvd.clone())),
        vtk: vtk(&sim),
        hdf5,
        surfaces,
        level_set: crate::io::snapshots::WholeLevelSet::new(&sim),
        count: p.snapshots as usize,
        next_out: p.next_out,
        next_ckpt: scene
            .output
            .checkpoint_every
            .map(|c| next_multiple(ck0.time.t, c)),
        last_ckpt: Some((step, ck0.file.clone())),
        since_ckpt: Instant::now(),
        dir,
    };
    logged(drive_split(sim, opts, &comm, out, wall0, false), log)
}

/// `result`, its error logged (rank 0's log, while it is open).
fn logged(result: anyhow::Result<RunSummary>, log: Option<RunLog>) -> anyhow::Result<RunSummary> {
    if let Err(e) = &result {
        tracing::error!("{e:#}");
    }
    drop(log);
    result
}

/// The run directory and step of the checkpoint `path` names, with every process's piece
/// present and whole.
fn resolve(path: &Path, ranks: usize) -> anyhow::Result<(PathBuf, u64)> {
    let (dir, steps): (PathBuf, Vec<u64>) = if path.is_dir() {
        let mut s: Vec<u64> = checkpoint::list(path)?
            .into_iter()
            .map(|(s, _)| s)
            .collect();
        s.reverse();
        (path.to_path_buf(), s)
    } else {
        let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("");
        let step = checkpoint::step_of(name).ok_or_else(|| {
            anyhow::anyhow!(
                "{}: not rank 0's checkpoint file (checkpoint_NNNNNN.bin) of a run",
                path.display()
            )
        })?;
        let dir = path.parent().filter(|d| !d.as_os_str().is_empty());
        (
            dir.map_or(PathBuf::from("."), Path::to_path_buf),
            vec![step],
        )
    };
    for &step in &steps {
        let whole = (0..ranks).all(|r| {
            Checkpoint::load(&dir.join(checkpoint::piece_file_name(step, r, ranks))).is_ok()
        });
        if whole {
            return Ok((dir, step));
        }
    }
    anyhow::bail!(
        "{} holds no checkpoint written by {ranks} processes with every piece whole \
         (checkpoint_NNNNNN.bin and checkpoint_NNNNNN.rankRof{ranks}.bin); a split run restarts \
         on as many processes as wrote it",
        path.display()
    )
}

/// `r` on every process if it is `Ok` on every process; otherwise this process's error, or on
/// the processes where it went well an error naming what another could not do.
fn agree<T>(comm: &Comm, r: anyhow::Result<T>, what: &str) -> anyhow::Result<T> {
    let failed = comm.max_one(f64::from(u8::from(r.is_err())));
    match r {
        Err(e) => Err(e),
        Ok(_) if failed > 0.0 => anyhow::bail!("another process could not {what}"),
        Ok(v) => Ok(v),
    }
}

/// Whether `sim`'s snapshots hold field files.
fn vtk(sim: &Simulation) -> bool {
    sim.scene().output.formats.contains(&OutputFormat::Vtk) && !sim.scene().output.fields.is_empty()
}

/// The log's first line of a split run (rank 0).
fn log_start(sim: &Simulation, comm: &Comm, dir: &Path, what: &str) {
    let grid = sim.grid().whole();
    tracing::info!(
        "tumble {} {what} of scene `{}` on {} processes: 3D grid {}x{}x{} (h = {}), end time {}, \
         {} threads each, output in {}",
        env!("CARGO_PKG_VERSION"),
        sim.scene().name,
        comm.size(),
        grid.n[0],
        grid.n[1],
        grid.n[2],
        grid.h,
        sim.scene().numerics.end_time,
        rayon::current_num_threads(),
        dir.display()
    );
    let e = crate::io::estimate::split_estimate(sim.scene(), comm.size());
    tracing::info!("{}", crate::io::estimate::split_words(&e));
}

impl Outputs {
    fn snapshot(&mut self, sim: &Simulation) -> anyhow::Result<()> {
        if self.vtk {
            let index = crate::io::snapshots::write_pieces(&self.dir, self.count, sim)?;
            if let Some(p) = self.pvd.as_mut() {
                p.push(sim.time(), &index)
                    .context("cannot write fields.pvd")?;
            }
        }
        if let Some(h) = self.hdf5.as_mut() {
            h.snapshot(&self.dir, self.count, sim)?;
        }
        if let Some(l) = self.level_set.as_mut() {
            l.gather(sim);
        }
        if let Some(s) = self.surfaces.as_mut() {
            crate::io::snapshots::write_split_surfaces(
                &self.dir,
                s,
                self.count,
                sim,
                self.hdf5.as_mut(),
                self.level_set.as_ref(),
            )?;
        }
        if self.vtk || self.hdf5.is_some() || self.surfaces.is_some() {
            self.count += 1;
        }
        Ok(())
    }

    /// Every process writes its piece of a checkpoint (rank 0's with the run's progress), then
    /// each removes its pieces of the checkpoints beyond `output.checkpoints_kept`.
    fn checkpoint(&mut self, sim: &mut Simulation, comm: &Comm) -> anyhow::Result<()> {
        // series.h5 holds every step up to the checkpoint (a restart reads it back).
        if let Some(h) = self.hdf5.as_mut() {
            h.finish(&self.dir)?;
        }
        let series_len = match self.series.as_mut() {
            Some(s) => {
                s.flush()?;
                super::synced_len(&self.dir, "series.csv")?
            }
            None => 0,
        };
        let bodies_len = match self.bodies.as_mut() {
            Some(b) => {
                b.flush()?;
                Some(super::synced_len(&self.dir, "bodies.csv")?)
            }
            None => None,
        };
        let contacts_len = match self.contacts.as_mut() {
            Some(c) => {
                c.flush()?;
                Some(super::synced_len(&self.dir, "contacts.csv")?)
            }
            None => None,
        };
        let progress = RunProgress {
            next_out: self.next_out,
            snapshots: self.count as u64,
            pvd: self
                .pvd
                .as_ref()
                .map(|p| p.entries().to_vec())
                .unwrap_or_default(),
            series_len,
            bodies_len,
            contacts_len,
        };
        let (rank, ranks, step) = (comm.rank(), comm.size(), sim.steps());
        let path = self
            .dir
            .join(checkpoint::piece_file_name(step, rank, ranks));
        let saved = checkpoint::save(&path, sim, &progress)
            .with_context(|| format!("cannot write {}", path.display()));
        agree(comm, saved, "write its piece of the checkpoint")?;
        // Every piece is whole: the checkpoint is complete. The old ones, as every process
        // sees them before any is removed.
        let kept = sim.scene().output.checkpoints_kept.max(1);
        let all = checkpoint::list(&self.dir)?;
        let old: Vec<u64> = all
            .iter()
            .take(all.len().saturating_sub(kept))
            .map(|(s, _)| *s)
            .collect();
        comm.barrier();
        for s in old {
            let own = self.dir.join(checkpoint::piece_file_name(s, rank, ranks));
            std::fs::remove_file(&own)
                .with_context(|| format!("cannot remove the old checkpoint {}", own.display()))?;
        }
        if comm.is_root() {
            tracing::info!(
                "checkpoint at step {step}, t = {}: {} and {} more pieces",
                sim.time(),
                path.display(),
                ranks - 1
            );
        }
        self.last_ckpt = Some((step, self.dir.join(checkpoint::file_name(step))));
        self.since_ckpt = Instant::now();
        Ok(())
    }
}

fn drive_split(
    mut sim: Simulation,
    opts: &RunOptions,
    comm: &Comm,
    mut out: Outputs,
    wall0: Instant,
    first: bool,
) -> anyhow::Result<RunSummary> {
    let root = comm.is_root();
    let steps0 = sim.steps();
    if first {
        if let Some(h) = out.hdf5.as_mut() {
            h.record(&mut sim);
        }
        out.snapshot(&sim)?;
        if let Some(s) = out.series.as_mut() {
            s.row(&sim)?;
        }
        if let Some(b) = out.bodies.as_mut() {
            b.rows(&mut sim)?;
        }
    }
    let end = sim.scene().numerics.end_time;
    let every = sim.scene().output.every;
    let ckpt_every = sim.scene().output.checkpoint_every;
    let wall = sim.scene().output.checkpoint_wall.filter(|&w| w > 0.0);
    let lands_on_outputs = sim.scene().numerics.dt.lands_on_outputs();
    let mut stop_at = None;
    let mut progress = Progress::new(&sim, opts.quiet || !root, wall0);
    let mut totals: Vec<(&'static str, f64)> = Vec::new();
    let result = (|| -> anyhow::Result<()> {
        while sim.time() < end * (1.0 - 1e-12) {
            let stop = match out.next_out {
                Some(o) if lands_on_outputs => o.min(end),
                _ => end,
            };
            if stop_at != Some(stop) {
                sim.set_stop_at(Some(stop));
                stop_at = Some(stop);
            }
            // Every process sees the same global quantities, so a blow-up stops them all.
            if let Err(e) = sim.step() {
                return Err(match &out.last_ckpt {
                    Some((s, p)) => anyhow::anyhow!(
                        "{e:#}; the last good checkpoint is {} (step {s})",
                        p.display()
                    ),
                    None => e,
                });
            }
            if let Some(s) = out.series.as_mut() {
                s.row(&sim)?;
            }
            if let Some(b) = out.bodies.as_mut() {
                b.rows(&mut sim)?;
            }
            if let Some(c) = out.contacts.as_mut() {
                c.rows(&sim)?;
            }
            if let Some(h) = out.hdf5.as_mut() {
                h.record(&mut sim);
            }
            add_timings(&mut totals, &sim.timings().last);
            if root {
                progress.show(&sim, end);
            }
            let t = sim.time();
            if super::snapshot_due(t, sim.sample().dt, end, every, &mut out.next_out) {
                out.snapshot(&sim)?;
            }
            // Rank 0's clock decides a wall-clock checkpoint; anyone's Ctrl-C stops them all.
            let wall_due =
                root && wall.is_some_and(|w| out.since_ckpt.elapsed().as_secs_f64() >= w);
            let interrupted = checkpoint::interrupt_requested() && t < end * (1.0 - 1e-12);
            let mut flags = [
                f64::from(u8::from(wall_due)),
                f64::from(u8::from(interrupted)),
            ];
            comm.max(&mut flags);
            let sim_due = out.next_ckpt.is_some_and(|c| t >= c * (1.0 - 1e-12));
            let stop = flags[1] > 0.0;
            if flags[0] > 0.0 || sim_due || stop {
                out.checkpoint(&mut sim, comm)?;
            }
            if (sim_due || stop)
                && let Some(e) = ckpt_every
            {
                out.next_ckpt = Some(next_multiple(t, e));
            }
            if stop {
                return Err(checkpoint::Interrupted {
                    step: sim.steps(),
                    t,
                    checkpoint: out.dir.join(checkpoint::file_name(sim.steps())),
                }
                .into());
            }
        }
        // A final checkpoint when they are periodic or the run wrote or started from one.
        if (ckpt_every.is_some() || out.last_ckpt.is_some())
            && out
                .last_ckpt
                .as_ref()
                .is_none_or(|(s, _)| *s != sim.steps())
        {
            out.checkpoint(&mut sim, comm)?;
        }
        Ok(())
    })();
    progress.bar.finish_and_clear();
    if let Some(s) = out.series.as_mut() {
        s.flush()?;
    }
    if let Some(b) = out.bodies.as_mut() {
        b.flush()?;
    }
    if let Some(c) = out.contacts.as_mut() {
        c.flush()?;
    }
    if let Some(h) = out.hdf5.as_mut() {
        h.finish(&out.dir)?;
    }
    let summary = RunSummary {
        dir: out.dir.clone(),
        steps: sim.steps(),
        steps_run: sim.steps() - steps0,
        last: sim.sample(),
        system_seconds: totals,
        wall: wall0.elapsed().as_secs_f64(),
    };
    if root {
        crate::io::runlog::timings_table(&summary.system_seconds, summary.steps_run, summary.wall);
        super::write_timings(
            &out.dir.join("timings.csv"),
            &summary.system_seconds,
            summary.steps_run,
        )?;
        plot(&out.dir, opts.quiet);
    }
    result?;
    Ok(summary)
}
