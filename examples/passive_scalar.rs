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
//! The plugin is the whole feature, and the file holds only its physics:
//! - its settings are the scene's section `plugins: {"passive_scalar": (kappa: .., ..)}`
//!   ([`PassiveScalar`], checked with file and line like every other scene field);
//! - its field `scalar` is written into the snapshots (`fields.pvd`, HDF5) with the built-in
//!   ones;
//! - its state ([`Scalar`]) is kept by checkpoints, so Ctrl-C and `--restart` continue bit for
//!   bit;
//! - it runs in the `First` set, where the velocity, time and step are those at the start of
//!   the step.
//!
//! The binary is tumble's command line with this plugin added ([`tumble::cli::main_with`]):
//! `run`, `check`, `bench`, `plot` and `--restart` work as they do for `tumble`. Without
//! arguments it runs `examples/passive_scalar.ron` into `runs/passive-scalar`:
//!
//! `cargo run --release --example passive_scalar [-- run SCENE --out DIR ...]`

use bevy_ecs::prelude::*;
use serde::{Deserialize, Serialize};
use std::process::ExitCode;
use tumble::base::fields::{Fields, SimTime};
use tumble::base::grid::Grid;
use tumble::schedule::{OutputField, PhysicsSet, Plugin, PluginContext, PluginList, Section};

/// The passive scalar's settings: the scene's `plugins: {"passive_scalar": (..)}` section.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PassiveScalar {
    /// Diffusivity κ, length²/time, ≥ 0. Default: 1e-3.
    pub kappa: f64,
    /// Centre of the initial Gaussian blob, as fractions of the box's extent, one entry per
    /// dimension. Default: [0.3, 0.5, 0.5] (its first two entries in 2D).
    pub center: Vec<f64>,
    /// The blob's standard deviation, as a fraction of the box's x extent, > 0. Default: 0.08.
    pub width: f64,
}

impl Default for PassiveScalar {
    fn default() -> Self {
        PassiveScalar {
            kappa: 1e-3,
            center: vec![0.3, 0.5, 0.5],
            width: 0.08,
        }
    }
}

impl PassiveScalar {
    /// The initial field: the Gaussian blob, its centre's nearest periodic image at each node.
    pub fn initial(&self, grid: &Grid) -> Vec<f64> {
        let ext = grid.extent();
        let s = self.width * ext[0];
        let mut c = vec![0.0; grid.len()];
        for k in 0..grid.n[2] {
            for j in 0..grid.n[1] {
                for i in 0..grid.n[0] {
                    let p = grid.pos(i, j, k);
                    let r2: f64 = (0..grid.dim)
                        .map(|a| {
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
        c
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

/// The plugin: one `PluginList::default().with(PassiveScalarPlugin)` away from any run.
#[derive(Debug, Clone, Copy)]
pub struct PassiveScalarPlugin;

impl Plugin for PassiveScalarPlugin {
    fn name(&self) -> &'static str {
        "passive_scalar"
    }

    fn section(&self) -> Option<Section> {
        Some(Section::of::<PassiveScalar>())
    }

    fn build(&self, ctx: &mut PluginContext) -> anyhow::Result<()> {
        let settings: PassiveScalar = ctx.settings()?;
        if !ctx.mode().fluid() {
            anyhow::bail!("a passive scalar needs a flow (the scene runs in vacuum)");
        }
        let grid = ctx.world.resource::<Grid>();
        if !(settings.kappa >= 0.0 && settings.width > 0.0) {
            anyhow::bail!("kappa must be >= 0 and width > 0");
        }
        if settings.center.len() < grid.dim {
            anyhow::bail!("center needs {} entries", grid.dim);
        }
        let c = settings.initial(grid);
        ctx.insert_resource(Scalar {
            kappa: settings.kappa,
            c,
            substeps: 0,
        });
        ctx.checkpoint_resource::<Scalar>("passive_scalar", 1)?;
        ctx.output_field(OutputField {
            name: "scalar",
            read: |world| vec![world.resource::<Scalar>().c.as_slice()],
        })?;
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

fn main() -> ExitCode {
    let mut args: Vec<std::ffi::OsString> = std::env::args_os().collect();
    if args.len() == 1 {
        let default = ["run", "examples/passive_scalar.ron", "--force"];
        args.extend(default.map(Into::into));
    }
    tumble::cli::main_from(args, PluginList::default().with(PassiveScalarPlugin))
}
