//! A run split over processes (`mpirun -np N tumble run SCENE`): every process steps its slab
//! of the grid in step with the others ([`crate::parallel`]); rank 0 makes the run directory
//! and writes the time series, the log, the plots and the index of each snapshot, and every
//! process writes its piece of each snapshot ([`crate::io::snapshots::write_pieces`]).
//!
//! The clock is the one-process run's: the same output times, landed on the same way, so the
//! time series are the one-process run's to round-off (the sums over the grid are added in a
//! different order). Every decision that could differ between processes (an interruption, a
//! failed step) is taken together.
//!
//! Not yet on several processes: checkpoints and restarts, HDF5 output, bodies and free
//! surfaces (each is refused before anything is written, with the reason).

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use anyhow::Context;

use super::{Progress, RunOptions, RunSummary, SeriesCsv, add_timings, apply_overrides, plot};
use crate::io::checkpoint;
use crate::io::output::{PvdSeries, atomic_write};
use crate::io::runlog::RunLog;
use crate::parallel::Comm;
use crate::scene::{OutputFormat, ValidScene};
use crate::sim::engine::Simulation;
use crate::systems::diagnostics::LAND_TOLERANCE;

/// What a split run cannot do yet, if the scene or the options ask for it. (The wall-clock
/// checkpoints every run has by default are not written: the log says so.)
fn unsupported(scene: &ValidScene, opts: &RunOptions) -> Option<&'static str> {
    let o = &scene.output;
    if o.checkpoint_every.is_some()
        || opts.checkpoint_every.is_some()
        || opts.checkpoint_wall.is_some_and(|w| w > 0.0)
    {
        return Some("checkpoints");
    }
    if o.formats.contains(&OutputFormat::Hdf5) {
        return Some("HDF5 output");
    }
    None
}

/// Run `scene` split over the processes of `comm` (more than one).
pub fn run_split(
    scene: ValidScene,
    opts: &RunOptions,
    comm: Arc<Comm>,
) -> anyhow::Result<RunSummary> {
    let wall0 = Instant::now();
    let scene = apply_overrides(scene, opts)?;
    if let Some(what) = unsupported(&scene, opts) {
        anyhow::bail!(
            "{what} on several processes: not yet (run on one process, or switch {what} off in \
             the scene's output section)"
        );
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
    let failed = comm.max_one(f64::from(u8::from(prepared.is_err())));
    let dir = match prepared {
        Err(e) => return Err(e),
        Ok(_) if failed > 0.0 => anyhow::bail!("process 0 could not prepare the run directory"),
        Ok(d) => d,
    };
    let root = comm.is_root();
    let sim = Simulation::builder(scene.clone())
        .add_plugins(&opts.plugins)
        .on_processes(comm.clone())
        .build()?;
    if root {
        let grid = sim.grid().whole();
        tracing::info!(
            "tumble {} run of scene `{}` on {} processes: 3D grid {}x{}x{} (h = {}) in slabs of {} \
             to {} z-planes, end time {}, {} threads each, output in {}",
            env!("CARGO_PKG_VERSION"),
            scene.name,
            comm.size(),
            grid.n[0],
            grid.n[1],
            grid.n[2],
            grid.h,
            grid.n[2] / comm.size(),
            grid.n[2].div_ceil(comm.size()),
            scene.numerics.end_time,
            rayon::current_num_threads(),
            dir.display()
        );
        tracing::info!("no checkpoints: a run on several processes writes none yet");
        atomic_write(&dir.join("scene.ron"), scene.to_ron().as_bytes())
            .context("cannot write scene.ron")?;
    }
    let result = drive_split(sim, opts, &comm, dir.clone(), wall0);
    if let Err(e) = &result {
        tracing::error!("{e:#}");
    }
    drop(log);
    result
}

fn drive_split(
    mut sim: Simulation,
    opts: &RunOptions,
    comm: &Comm,
    dir: PathBuf,
    wall0: Instant,
) -> anyhow::Result<RunSummary> {
    let root = comm.is_root();
    let steps0 = sim.steps();
    let mut series = if root {
        Some(SeriesCsv::create(&dir.join("series.csv"), &sim)?)
    } else {
        None
    };
    let vtk = sim.scene().output.formats.contains(&OutputFormat::Vtk)
        && !sim.scene().output.fields.is_empty();
    let mut pvd = (root && vtk).then(|| PvdSeries::new(dir.join("fields.pvd")));
    let mut count = 0usize;
    let mut snapshot = |sim: &Simulation, pvd: &mut Option<PvdSeries>| -> anyhow::Result<()> {
        if vtk {
            let index = crate::io::snapshots::write_pieces(&dir, count, sim)?;
            if let Some(p) = pvd.as_mut() {
                p.push(sim.time(), &index)
                    .context("cannot write fields.pvd")?;
            }
            count += 1;
        }
        Ok(())
    };
    snapshot(&sim, &mut pvd)?;
    if let Some(s) = series.as_mut() {
        s.row(&sim)?;
    }
    let end = sim.scene().numerics.end_time;
    let every = sim.scene().output.every;
    let lands_on_outputs = sim.scene().numerics.dt.lands_on_outputs();
    let mut next_out = every.map(|e| e.min(end));
    let mut stop_at = None;
    let mut progress = Progress::new(&sim, opts.quiet || !root, wall0);
    let mut totals: Vec<(&'static str, f64)> = Vec::new();
    let result = (|| -> anyhow::Result<()> {
        while sim.time() < end * (1.0 - 1e-12) {
            let stop = match next_out {
                Some(o) if lands_on_outputs => o.min(end),
                _ => end,
            };
            if stop_at != Some(stop) {
                sim.set_stop_at(Some(stop));
                stop_at = Some(stop);
            }
            // Every process sees the same global quantities, so a blow-up stops them all.
            sim.step()?;
            if let Some(s) = series.as_mut() {
                s.row(&sim)?;
            }
            add_timings(&mut totals, &sim.timings().last);
            if root {
                progress.show(&sim, end);
            }
            let t = sim.time();
            let slack = LAND_TOLERANCE * sim.sample().dt;
            let due = |o: Option<f64>| o.is_some_and(|o| t >= o * (1.0 - 1e-12) - slack);
            if due(next_out) || t >= end * (1.0 - 1e-12) {
                snapshot(&sim, &mut pvd)?;
                if let Some(e) = every {
                    while let Some(o) = next_out.filter(|&o| due(Some(o)) && o + e > o) {
                        next_out = Some(o + e);
                    }
                }
            }
            let stop = checkpoint::interrupt_requested() && t < end * (1.0 - 1e-12);
            if comm.max_one(f64::from(u8::from(stop))) > 0.0 {
                anyhow::bail!(
                    "interrupted at step {} (t = {t}); a run on several processes writes no \
                     checkpoint yet",
                    sim.steps()
                );
            }
        }
        Ok(())
    })();
    progress.bar.finish_and_clear();
    if let Some(s) = series.as_mut() {
        s.flush()?;
    }
    let summary = RunSummary {
        dir: dir.clone(),
        steps: sim.steps(),
        steps_run: sim.steps() - steps0,
        last: sim.sample(),
        system_seconds: totals,
        wall: wall0.elapsed().as_secs_f64(),
    };
    if root {
        crate::io::runlog::timings_table(&summary.system_seconds, summary.steps_run, summary.wall);
        super::write_timings(
            &dir.join("timings.csv"),
            &summary.system_seconds,
            summary.steps_run,
        )?;
        plot(&dir, opts.quiet);
    }
    result?;
    Ok(summary)
}
