//! `tumble bench`: the time of a step and of each system, as ratios to the FFT floor.

use crate::io::output::peak_memory_bytes;
use crate::parallel::Comm;
use crate::scene::ValidScene;
use crate::schedule::PluginList;
use crate::sim::engine::Simulation;
use std::path::Path;
use std::sync::Arc;

/// The median and the 90th percentile of `v` (sorted in place).
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

/// `tumble bench SCENE`: time steps, print one JSON line.
///
/// Under `mpirun` the scene runs split over the processes: a step's time is the slowest
/// process's, the time in transposes and halo exchanges is reported apart, the FFT floor is
/// the whole grid's measured by rank 0 alone, and rank 0 prints.
pub fn bench(path: &Path, steps: usize, warmup: usize, plugins: &PluginList) -> u8 {
    let scene = match super::load(path, plugins) {
        Ok(s) => s,
        Err(code) => return code,
    };
    let procs = match crate::parallel::comm::launched() {
        Ok(p) => p,
        Err(e) => {
            eprintln!("error: {e:#}");
            return 2;
        }
    };
    let comm = procs.as_ref().map(|p| p.comm.clone());
    let root = comm.as_ref().is_none_or(|c| c.is_root());
    match measure(scene, steps, warmup, plugins, comm) {
        Ok(line) => {
            if root {
                println!("{line}");
            }
            0
        }
        Err(e) => {
            eprintln!("error: {e:#}");
            1
        }
    }
}

/// Time `steps` steps of `scene` after `warmup` untimed ones: the JSON line of medians per step
/// and per system, and their ratios to the FFT floor of the grid measured now.
fn measure(
    scene: ValidScene,
    steps: usize,
    warmup: usize,
    plugins: &PluginList,
    comm: Option<Arc<Comm>>,
) -> anyhow::Result<String> {
    anyhow::ensure!(steps > 0, "--steps must be at least 1");
    // An end time the timed steps never reach (no step is shortened to land on it), yet one
    // the scene's largest step can count to (2^50 of them; see `scene::steps`).
    let far = match crate::scene::steps::step_bound(&scene, &scene.grid(), scene.resolved()) {
        Some(b) => b.dt * 2f64.powi(50),
        None => f64::MAX / 4.0,
    };
    let scene = scene.edit(|s| s.numerics.end_time = far)?;
    let name = scene.name.clone();
    let mut builder = Simulation::builder(scene).add_plugins(plugins);
    if let Some(c) = &comm {
        builder = builder.on_processes(c.clone());
    }
    let mut sim = builder.build()?;
    let comm = comm.as_deref();
    sim.set_stop_at(None);
    for _ in 0..warmup {
        sim.step()?;
    }
    let mut total = Vec::with_capacity(steps);
    let mut per: Vec<(&'static str, Vec<f64>)> = Vec::new();
    // Iterations of the variable-density pressure solve per timed step (when it runs).
    let mut iterations = Vec::new();
    let mut preconditioners = Vec::new();
    // Iterations of the no-slip solve per timed step (when it runs).
    let mut noslip = Vec::new();
    // Seconds in transposes and halo exchanges per timed step (several processes).
    let mut waiting = Vec::new();
    let processes = comm.map_or(1, |c| c.size());
    let slowest = |x: f64| comm.map_or(x, |c| c.max_one(x));
    for _ in 0..steps {
        if let Some(c) = comm {
            c.barrier();
        }
        let w0 = comm.map_or(0.0, |c| c.seconds_communicating());
        let t0 = std::time::Instant::now();
        sim.step()?;
        total.push(slowest(t0.elapsed().as_secs_f64()));
        if let Some(c) = comm {
            waiting.push(c.max_one(c.seconds_communicating() - w0));
        }
        if let Some(p) = sim
            .world
            .get_resource::<crate::systems::pressure::PressureSolver>()
        {
            iterations.push(p.iterations() as f64);
            let name = format!("{:?}", p.poisson.preconditioner).to_lowercase();
            if !preconditioners.contains(&name) {
                preconditioners.push(name);
            }
        }
        if let Some(n) = sim.world.get_resource::<crate::systems::noslip::NoSlip>() {
            noslip.push(n.iterations as f64);
        }
        for &(n, s) in &sim.timings().last {
            let s = slowest(s);
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
    let g = &sim.grid().whole();
    // Peak memory of the run (of the largest process), before the floor's own buffers.
    let peak = peak_memory_bytes().map(|p| slowest(p as f64) as u64);
    // The FFT floor of the same grid, measured now in this process (rank 0 alone, the others
    // waiting): the step as a ratio to it.
    let floor = match comm {
        Some(c) => {
            let f = if c.is_root() {
                crate::solvers::fft::floor_seconds(g, 7)
            } else {
                0.0
            };
            c.max_one(f)
        }
        None => crate::solvers::fft::floor_seconds(g, 7),
    };
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
        "processes": processes,
    });
    if !waiting.is_empty() {
        line["median_s_communicating_per_step"] = serde_json::json!(median_p90(&mut waiting).0);
    }
    if !iterations.is_empty() {
        line["median_pressure_iterations"] = serde_json::json!(median_p90(&mut iterations).0);
        line["pressure_preconditioners"] = serde_json::json!(preconditioners);
    }
    if !noslip.is_empty() {
        line["median_noslip_iterations"] = serde_json::json!(median_p90(&mut noslip).0);
    }
    Ok(line.to_string())
}
