//! `tumble run`: run a scene, or continue a run from its checkpoint.

use crate::io::checkpoint::{Interrupted, install_interrupt_handler};
use crate::run::{
    BadOutputDir, RefusedRun, RunOptions, RunSummary, is_refused_restart, restart_run, run_scene,
};
use std::path::Path;

/// `tumble run [SCENE] [--restart CHECKPOINT]`: exit status 0 when the run ends, 130 when it
/// is interrupted (with a checkpoint), 2 for a mistake in the scene, the output directory or
/// the checkpoint, 1 for a failure of the run.
pub fn run(scene: Option<&Path>, restart: Option<&Path>, opts: &RunOptions) -> u8 {
    let loaded = match scene.map(|s| super::load(s, &opts.plugins)).transpose() {
        Ok(s) => s,
        Err(code) => return code,
    };
    // Ctrl-C and SIGTERM stop the run after its current step, with a checkpoint.
    if let Err(e) = install_interrupt_handler() {
        eprintln!("warning: {e:#}");
    }
    let split = opts.comm.as_ref().filter(|c| c.size() > 1);
    let result = match (restart, loaded) {
        (Some(ck), loaded) if split.is_some() => crate::run::split::restart_split(
            ck,
            scene.zip(loaded),
            opts,
            split.expect("checked").clone(),
        ),
        (Some(ck), loaded) => restart_run(ck, scene.zip(loaded), opts),
        (None, Some(scene)) => run_scene(scene, opts),
        (None, None) => unreachable!("clap requires a scene without --restart"),
    };
    match result {
        Ok(s) => {
            if opts.comm.as_ref().is_none_or(|c| c.is_root()) {
                print_summary(&s);
            }
            0
        }
        Err(e) if e.downcast_ref::<Interrupted>().is_some() => {
            eprintln!("{e}");
            130
        }
        Err(e) => {
            eprintln!("error: {e:#}");
            // A bad output directory is a usage mistake, like a bad scene; so is a checkpoint
            // that cannot be restarted, and a run whose outputs would not fit on the disk.
            if e.is::<BadOutputDir>()
                || e.is::<RefusedRun>()
                || e.is::<crate::scene::SceneError>()
                || is_refused_restart(&e)
            {
                2
            } else {
                1
            }
        }
    }
}

/// The lines printed at the end of a run: steps, final state, seconds per system, and the
/// file to open.
fn print_summary(s: &RunSummary) {
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
}
