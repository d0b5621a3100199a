//! `tumble bench`: the time of a step and of each system, as ratios to the FFT floor.

use crate::io::output::peak_memory_bytes;
use crate::scene::ValidScene;
use crate::schedule::PluginList;
use crate::sim::engine::Simulation;
use std::path::Path;

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
pub fn bench(path: &Path, steps: usize, warmup: usize, plugins: &PluginList) -> u8 {
    let scene = match super::load(path, plugins) {
        Ok(s) => s,
        Err(code) => return code,
    };
    match measure(scene, steps, warmup, plugins) {
        Ok(line) => {
            println!("{line}");
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
    let mut sim = Simulation::builder(scene).add_plugins(plugins).build()?;
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
    for _ in 0..steps {
        let t0 = std::time::Instant::now();
        sim.step()?;
        total.push(t0.elapsed().as_secs_f64());
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
    let floor = crate::solvers::fft::floor_seconds(g, 7);
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
    if !noslip.is_empty() {
        line["median_noslip_iterations"] = serde_json::json!(median_p90(&mut noslip).0);
    }
    Ok(line.to_string())
}
