//! The run log, `log.txt` in the run directory, written through `tracing`.
//!
//! [`RunLog::create`] installs a `tracing_subscriber` formatter writing plain text (no ANSI
//! colours) to the file as the *scoped* default of the calling thread, so every `tracing`
//! event the run emits on that thread (`info!`, `warn!`, `error!`) lands in its own run's
//! log. Nothing global is set: several runs in one process (the tests) each get their own
//! log, and dropping the [`RunLog`] restores whatever was there before.

use anyhow::Context;
use std::fs::File;
use std::path::Path;
use std::sync::Mutex;
use tracing::subscriber::DefaultGuard;

/// The log of one run; events go to its file while it is alive (on the creating thread).
pub struct RunLog {
    _guard: DefaultGuard,
}

impl RunLog {
    /// Create (truncate) `path` and make it the log of this thread until the value is dropped.
    pub fn create(path: &Path) -> anyhow::Result<Self> {
        let file = File::create(path)
            .map_err(|e| crate::io::output::disk_full(path, e))
            .with_context(|| format!("cannot create {}", path.display()))?;
        Ok(Self::to_file(file))
    }

    /// Open `path` for appending (a restarted run, see `tumble::run::restart_run`) and make
    /// it the log of this thread until the value is dropped.
    pub fn append(path: &Path) -> anyhow::Result<Self> {
        let file = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(path)
            .map_err(|e| crate::io::output::disk_full(path, e))
            .with_context(|| format!("cannot open {}", path.display()))?;
        Ok(Self::to_file(file))
    }

    fn to_file(file: File) -> Self {
        let subscriber = tracing_subscriber::fmt()
            .with_writer(Mutex::new(file))
            .with_ansi(false)
            .with_target(false)
            .with_max_level(tracing::Level::INFO)
            .finish();
        RunLog {
            _guard: tracing::subscriber::set_default(subscriber),
        }
    }
}

/// One paragraph summarising a scene for the log: bodies, fluid and the time step policy.
pub fn scene_summary(scene: &crate::scene::ValidScene) -> String {
    use crate::scene::BodyKind;
    let count = |f: fn(&BodyKind) -> bool| scene.bodies.iter().filter(|b| f(&b.kind)).count();
    let dynamic = count(|k| matches!(k, BodyKind::Dynamic));
    let stat = count(|k| matches!(k, BodyKind::Static));
    let kinematic = count(|k| matches!(k, BodyKind::Kinematic { .. }));
    let f = &scene.fluid;
    let flow = if scene.vacuum {
        "vacuum (no flow)".to_string()
    } else {
        format!(
            "fluid density {}, viscosity {}, gravity {:?}",
            f.density, f.viscosity, f.gravity
        )
    };
    format!(
        "scene: {} bodies ({dynamic} dynamic, {stat} static, {kinematic} kinematic), {flow}, \
         {} initial vorticity field(s), dt {:?}, end time {}, snapshots every {}, formats {:?}, \
         contact kappa {}; {}",
        scene.bodies.len(),
        scene.initial.len(),
        scene.numerics.dt,
        scene.numerics.end_time,
        scene
            .output
            .every
            .map_or("(first and last only)".to_string(), |e| e.to_string()),
        scene.output.formats,
        crate::io::summary::kappa_in_use(scene),
        crate::io::estimate::words(&crate::io::estimate::estimate(scene))
    )
}

/// Log the one-line summary of an output step: step, time, dt, energy, max|ω|, the fastest
/// moving body's speed (scenes with bodies) and the files just written.
pub fn output_line(sim: &crate::sim::engine::Simulation, files: &[String]) {
    let s = sim.sample();
    let mut fastest: Option<(f64, &str)> = None;
    let mut q = sim
        .world
        .try_query::<(&crate::bodies::Body, &crate::bodies::RigidState)>();
    if let Some(q) = q.as_mut() {
        for (b, st) in q.iter(&sim.world) {
            let v = st.velocity.length();
            if !b.is_static() && fastest.is_none_or(|(f, _)| v > f) {
                fastest = Some((v, &b.name));
            }
        }
    }
    let bodies = fastest.map_or(String::new(), |(v, n)| {
        format!(", fastest body `{n}` at {v:.4e}")
    });
    tracing::info!(
        "output: step {}, t = {:.6}, dt = {:.3e}, energy {:.6e}, max|omega| {:.4e}{bodies}; wrote {}",
        sim.steps(),
        s.t,
        s.dt,
        s.energy,
        s.max_omega,
        files.join(", ")
    );
}

/// Log the per-system timings: total seconds, seconds per step and share of the stepping time.
pub fn timings_table(system_seconds: &[(&'static str, f64)], steps: u64, wall: f64) {
    let total: f64 = system_seconds.iter().map(|(_, s)| s).sum();
    let width = system_seconds
        .iter()
        .map(|(n, _)| n.len())
        .max()
        .unwrap_or(6)
        .max(6);
    let mut t = format!(
        "timings over {steps} steps ({total:.3} s in systems, {wall:.3} s wall):\n  {:<width$} {:>12} {:>14} {:>7}",
        "system", "seconds", "s/step", "share"
    );
    for (name, s) in system_seconds {
        t.push_str(&format!(
            "\n  {name:<width$} {s:>12.4} {:>14.6} {:>6.1}%",
            s / steps.max(1) as f64,
            if total > 0.0 { 100.0 * s / total } else { 0.0 }
        ));
    }
    tracing::info!("{t}");
}
