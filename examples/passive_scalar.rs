//! # passive_scalar: a concentration carried by the flow, as a plugin in one file
//!
//! Solves, in the periodic box,
//!
//!   ∂c/∂t + ∇·(u c) = κ Δc
//!
//! (for the solenoidal flow of tumble, ∇·(u c) = u·∇c: the advection-diffusion of a passive
//! scalar). Finite volumes on the flow grid, explicit in time: the flux through the face
//! between nodes i and i+1 is donor-cell upwind, F = u_f c_upwind with u_f = (u_i + u_(i+1))/2,
//! and the diffusion is the 5-point (2D) / 7-point (3D) Laplacian. Every face flux is computed
//! once with the same operands for both of its nodes, so the total mass Σ c h^d telescopes: it
//! is conserved exactly but for rounding. A step of length Δt is split into sub-steps of
//! length τ with τ (2 Σ_a max|u_a| / h + 2 d κ / h²) ≤ 1, under which every new value is a
//! combination of old ones with non-negative weights, so c stays non-negative.
//!
//! The plugin runs in the `First` set, where the velocity, time and step are those at the
//! start of the step. Its field is kept across a checkpoint through the generic serde path
//! ([`PluginContext::checkpoint_resource`]): no encoder is written for it.
//!
//! Registered with one line: `Simulation::builder(scene).add_plugin(PassiveScalar::default())`.
//!
//! Run: `cargo run --release --example passive_scalar -- [SCENE] [OUT_DIR] [T_END]`
//! (default `scenes/taylor-green-2d.ron`, `runs/passive-scalar`, 0.5). It runs the scene to
//! T_END with a checkpoint half-way, restarts a second simulation from that checkpoint, checks
//! that both end bit for bit alike and that the mass is conserved, and writes `scalar.csv`
//! (t, mass, min, max per step) and `scalar.vti` (the final field) to OUT_DIR.

use bevy_ecs::prelude::*;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use tumble::base::fields::{Fields, SimTime};
use tumble::base::grid::Grid;
use tumble::io::checkpoint::{self, Checkpoint, RunProgress};
use tumble::io::output::{CsvWriter, VtkField, write_vti};
use tumble::scene::{Scene, ValidScene};
use tumble::schedule::{PhysicsSet, Plugin, PluginContext};
use tumble::sim::engine::Simulation;

/// The passive scalar's settings.
#[derive(Debug, Clone, Copy)]
pub struct PassiveScalar {
    /// Diffusivity κ (length²/time).
    pub kappa: f64,
    /// Centre of the initial Gaussian blob, as fractions of the box.
    pub center: [f64; 3],
    /// Its standard deviation, as a fraction of the box's x extent.
    pub width: f64,
}

impl Default for PassiveScalar {
    fn default() -> Self {
        PassiveScalar {
            kappa: 1e-3,
            center: [0.3, 0.5, 0.5],
            width: 0.08,
        }
    }
}

/// The concentration at the grid nodes (the state a checkpoint keeps).
#[derive(Resource, Debug, Clone, Serialize, Deserialize)]
pub struct Scalar {
    /// Diffusivity κ.
    pub kappa: f64,
    /// c at every node, in the grid's flat order.
    pub c: Vec<f64>,
    /// Sub-steps taken so far.
    pub substeps: u64,
}

impl Scalar {
    /// Total mass Σ c h^d.
    pub fn mass(&self, grid: &Grid) -> f64 {
        self.c.iter().sum::<f64>() * grid.cell_volume()
    }
}

impl Plugin for PassiveScalar {
    fn name(&self) -> &'static str {
        "passive_scalar"
    }

    fn build(&self, ctx: &mut PluginContext) -> anyhow::Result<()> {
        if !ctx.mode().fluid() {
            anyhow::bail!("a passive scalar needs a flow (the scene runs in vacuum)");
        }
        if !(self.kappa >= 0.0 && self.width > 0.0) {
            anyhow::bail!("kappa must be >= 0 and width > 0");
        }
        let grid = ctx.world.resource::<Grid>().clone();
        let ext = grid.extent();
        let s = self.width * ext[0];
        let mut c = vec![0.0; grid.len()];
        for k in 0..grid.n[2] {
            for j in 0..grid.n[1] {
                for i in 0..grid.n[0] {
                    let p = grid.pos(i, j, k);
                    let r2: f64 = (0..grid.dim)
                        .map(|a| {
                            // Nearest periodic image of the centre.
                            let x0 = grid.origin[a] + self.center[a] * ext[a];
                            let d = p[a] - x0;
                            let d = d - ext[a] * (d / ext[a]).round();
                            d * d
                        })
                        .sum();
                    c[grid.idx(i, j, k)] = (-r2 / (2.0 * s * s)).exp();
                }
            }
        }
        ctx.insert_resource(Scalar {
            kappa: self.kappa,
            c,
            substeps: 0,
        });
        ctx.checkpoint_resource::<Scalar>("passive_scalar", 1)?;
        ctx.add_system(PhysicsSet::First, "passive_scalar", advect_diffuse)
    }
}

/// One step of the passive scalar (sub-stepped for positivity, see the module docs).
fn advect_diffuse(
    grid: Res<Grid>,
    time: Res<SimTime>,
    fields: Res<Fields>,
    mut scalar: ResMut<Scalar>,
) {
    let (h, d, kappa) = (grid.h, grid.dim, scalar.kappa);
    let u = &fields.u;
    let umax: f64 = (0..d)
        .map(|a| u[a].iter().fold(0.0f64, |m, v| m.max(v.abs())))
        .sum();
    let rate = 2.0 * umax / h + 2.0 * d as f64 * kappa / (h * h);
    let subs = (time.dt * rate).ceil().max(1.0) as usize;
    let tau = time.dt / subs as f64;
    let mut next = vec![0.0; grid.len()];
    for _ in 0..subs {
        sub_step(&grid, u, kappa, tau, &scalar.c, &mut next);
        std::mem::swap(&mut scalar.c, &mut next);
    }
    scalar.substeps += subs as u64;
}

/// c ← c - τ/h Σ_a (F_(a,+) - F_(a,-)) + κ τ/h² Σ_a (c_+ + c_- - 2c), periodic neighbours.
fn sub_step(grid: &Grid, u: &[Vec<f64>], kappa: f64, tau: f64, c: &[f64], out: &mut [f64]) {
    let n = grid.n;
    let (ta, td) = (tau / grid.h, kappa * tau / (grid.h * grid.h));
    for k in 0..n[2] {
        for j in 0..n[1] {
            for i in 0..n[0] {
                let me = grid.idx(i, j, k);
                let (mut adv, mut lap) = (0.0, 0.0);
                for a in 0..grid.dim {
                    let mut ijk_p = [i, j, k];
                    let mut ijk_m = [i, j, k];
                    ijk_p[a] = (ijk_p[a] + 1) % n[a];
                    ijk_m[a] = (ijk_m[a] + n[a] - 1) % n[a];
                    let p = grid.idx(ijk_p[0], ijk_p[1], ijk_p[2]);
                    let m = grid.idx(ijk_m[0], ijk_m[1], ijk_m[2]);
                    adv += face_flux(u[a][me], u[a][p], c[me], c[p])
                        - face_flux(u[a][m], u[a][me], c[m], c[me]);
                    lap += c[p] + c[m] - 2.0 * c[me];
                }
                out[me] = c[me] - ta * adv + td * lap;
            }
        }
    }
}

/// Donor-cell flux through the face from node `l` to node `r`.
fn face_flux(ul: f64, ur: f64, cl: f64, cr: f64) -> f64 {
    let uf = 0.5 * (ul + ur);
    if uf > 0.0 { uf * cl } else { uf * cr }
}

/// What [`run`] measured.
#[derive(Debug, Clone)]
pub struct Report {
    /// Steps taken.
    pub steps: u64,
    /// Sub-steps of the scalar taken.
    pub substeps: u64,
    /// Standard deviation of the initial blob.
    pub sigma: f64,
    /// Mass at the start and at the end.
    pub mass0: f64,
    /// Mass at the end.
    pub mass: f64,
    /// Smallest and largest c at the end, and the largest at the start.
    pub min: f64,
    /// Largest c at the end.
    pub max: f64,
    /// Largest c at the start.
    pub max0: f64,
    /// Nodes of the grid.
    pub nodes: usize,
    /// Whether the restarted run ended with the same c, ω and u, bit for bit.
    pub restart_identical: bool,
    /// The checkpoint written half-way.
    pub checkpoint: Vec<u8>,
}

fn bits(v: &[f64]) -> Vec<u64> {
    v.iter().map(|x| x.to_bits()).collect()
}

fn state_bits(sim: &Simulation) -> Vec<Vec<u64>> {
    let f = sim.fields();
    let mut out = vec![bits(&sim.world.resource::<Scalar>().c)];
    out.extend(f.omega().iter().map(|c| bits(c)));
    out.extend(f.u.iter().map(|c| bits(c)));
    out
}

/// Run `scene` with the passive scalar to `t_end`, checkpointing half-way, restart a second
/// simulation from the checkpoint, and write `scalar.csv` and `scalar.vti` to `out`.
pub fn run(scene: &ValidScene, out: &Path, t_end: f64) -> anyhow::Result<Report> {
    std::fs::create_dir_all(out)?;
    let plugin = PassiveScalar::default();
    let mut sim = Simulation::builder(scene.clone())
        .add_plugin(plugin)
        .build()?;
    let grid = sim.grid().clone();
    let extremes = |sim: &Simulation| {
        let c = &sim.world.resource::<Scalar>().c;
        let min = c.iter().copied().fold(f64::INFINITY, f64::min);
        let max = c.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        (min, max)
    };
    let mass0 = sim.world.resource::<Scalar>().mass(&grid);
    let max0 = extremes(&sim).1;
    let mut csv = CsvWriter::create(&out.join("scalar.csv"), &["t", "mass", "min", "max"])?;
    let mut row = |sim: &Simulation| -> std::io::Result<()> {
        let (min, max) = extremes(sim);
        let mass = sim.world.resource::<Scalar>().mass(sim.grid());
        csv.row(&[sim.time(), mass, min, max])
    };
    row(&sim)?;
    let mut err = Ok(());
    let mut each = |s: &Simulation| {
        if err.is_ok() {
            err = row(s);
        }
    };
    sim.run_until(0.5 * t_end, &mut each)?;
    let bytes = checkpoint::to_bytes(&mut sim, &RunProgress::default());
    sim.run_until(t_end, &mut each)?;
    err?;
    csv.flush()?;
    let c = &sim.world.resource::<Scalar>().c;
    write_vti(
        &out.join("scalar.vti"),
        &grid,
        sim.time(),
        &[VtkField {
            name: "c",
            components: &[c],
        }],
    )?;

    // A second simulation, restarted from the checkpoint.
    let ck = Checkpoint::from_bytes(&bytes, &out.join("memory"))?;
    let mut again = Simulation::builder(scene.clone())
        .add_plugin(plugin)
        .build()?;
    ck.restore(&mut again)?;
    again.run_until(t_end, |_| {})?;
    let (min, max) = extremes(&sim);
    Ok(Report {
        steps: sim.steps(),
        substeps: sim.world.resource::<Scalar>().substeps,
        sigma: plugin.width * grid.extent()[0],
        mass0,
        mass: sim.world.resource::<Scalar>().mass(&grid),
        min,
        max,
        max0,
        nodes: grid.len(),
        restart_identical: again.steps() == sim.steps() && state_bits(&again) == state_bits(&sim),
        checkpoint: bytes,
    })
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let scene_path = PathBuf::from(
        args.first()
            .map_or("scenes/taylor-green-2d.ron", String::as_str),
    );
    let out = PathBuf::from(args.get(1).map_or("runs/passive-scalar", String::as_str));
    let t_end: f64 = match args.get(2) {
        Some(t) => t.parse().map_err(|e| anyhow::anyhow!("T_END `{t}`: {e}"))?,
        None => 0.5,
    };
    let scene = Scene::load(&scene_path)?;
    let r = run(&scene, &out, t_end)?;
    let drift = (r.mass - r.mass0).abs() / r.mass0;
    println!(
        "{} steps: mass {:.15e} -> {:.15e} (relative change {drift:.2e}), c in [{:.3e}, {:.3e}] \
         (max at start {:.3e}); restart bit for bit: {}; wrote {}",
        r.steps,
        r.mass0,
        r.mass,
        r.min,
        r.max,
        r.max0,
        r.restart_identical,
        out.display()
    );
    if !r.restart_identical {
        anyhow::bail!("the restarted run differs from the uninterrupted one");
    }
    Ok(())
}
