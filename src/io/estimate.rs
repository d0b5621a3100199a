//! Estimated peak memory and time per step of a scene, printed by `tumble check` and the run
//! log before a run: an estimate from a model, not a measurement.
//!
//! Memory counts the arrays the engine allocates: per grid node, the vorticity, velocity and
//! previous velocity (`Fields`; transport makes the carrying velocity in the last), with bodies the
//! density, fluid-phase density, Σχ, union φ, penalization increment and owner
//! (`BodyFields`), with the `Pressure` coupling the face coefficients, source, trial velocity,
//! conjugate-gradient vectors and φ (`PressureSolver`, `PressureState`) and where the densities
//! differ enough the multigrid hierarchy (`solvers::multigrid`), and with a flow the
//! vorticity spectrum and a work spectrum (`Spectral`); per body, its local level set (its
//! bounding box grown by the band, sampled at h) and its grid patch (φ and χ over the world box
//! its rotated bounds and band cover; the whole grid for a wall); plus the process's own
//! [`BASE_BYTES`]. Time per step is [`FLOW_SECONDS_PER_NODE`] per node with a flow, plus
//! [`BODY_GRID_SECONDS_PER_NODE`] per node with bodies in a flow (pressure projection, density,
//! penalization), plus [`SECONDS_PER_PATCH_NODE`] per patch node (level sets, contact, rigid
//! velocity), so both grow with the grid plus the bodies' total size, never with their
//! product.
//!
//! Measured against `tumble bench --steps 10` on the machine the constants come from (2
//! threads, 2026-05), estimate against bench: dkt 0.59 s and 285 MB against 0.55 s and 295 MB;
//! tank-200 0.23 s and 132 MB against 0.27 s and 122 MB; tank-200-vacuum 0.060 s and 94 MB
//! against 0.056 s and 84 MB; grains 0.091 s and 56 MB against 0.16 s (13 pressure iterations
//! a step against dkt's 7) and 54 MB; lamb-oseen 0.0041 s and 11.2 MB against 0.0038 s and
//! 10.7 MB. The time constants were fitted on dkt and tank-200, so those two agree by
//! construction; time also depends on the pressure solver's iterations, the machine and its
//! load (timings here vary 3 times between days): read it as the order of
//! magnitude.

use crate::bodies::band;
use crate::scene::{BodyCoupling, ValidScene};
use glam::{DMat3, DQuat, DVec3};

/// Process memory besides the scene's arrays (code, threads, allocator), bytes: `tumble bench
/// scenes/lamb-oseen.ron` (16,384 cells, about 1 MB of arrays) peaked at 10.7 MB, 2 cores,
/// 2026-05.
pub const BASE_BYTES: f64 = 10.0e6;

/// Seconds per grid node and step of the flow solver (transport, diffusion, Poisson,
/// diagnostics) on 2 threads: `tumble bench scenes/dkt.ron --steps 10` (864,000 cells) spent
/// 0.216 s a step in them, 2 cores, 2026-05.
pub const FLOW_SECONDS_PER_NODE: f64 = 2.5e-7;

/// Seconds per grid node and step of the bodies' grid work in a flow (pressure projection,
/// density, penalization) on 2 threads: the same dkt bench spent 0.342 s a step in them (7
/// pressure iterations a step).
pub const BODY_GRID_SECONDS_PER_NODE: f64 = 4.0e-7;

/// Seconds per patch node and step (level sets, collision, rigid velocity or free motion) on
/// 2 threads: `tumble bench scenes/tank-200.ron --steps 10` spent 0.055 s a step in them over
/// 1.72 million patch nodes (200 spheres and the box's whole grid), 2 cores, 2026-05;
/// tank-200-vacuum 0.056 s.
pub const SECONDS_PER_PATCH_NODE: f64 = 3.2e-8;

/// A scene's estimated cost.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate {
    /// Peak memory, bytes.
    pub bytes: f64,
    /// Wall time per step on 2 threads, seconds.
    pub seconds_per_step: f64,
    /// Grid nodes.
    pub nodes: f64,
    /// Σ over bodies of their grid patches' nodes.
    pub patch_nodes: f64,
    /// Σ over bodies of the nodes of their own (body-frame) level sets.
    pub local_nodes: f64,
}

/// Nodes of a box of the given side lengths at spacing `h` (at least 2 per axis), `dim` axes.
fn box_nodes(size: DVec3, h: f64, dim: usize) -> f64 {
    (0..dim)
        .map(|a| (size[a] / h).ceil().max(1.0) + 1.0)
        .product()
}

/// The estimate for `scene`.
pub fn estimate(scene: &ValidScene) -> Estimate {
    let g = scene.grid();
    let dim = g.dim;
    let n = g.len() as f64;
    let h = g.h;
    let d = dim as f64;
    let nc = g.omega_components() as f64;
    let bodies = !scene.bodies.is_empty();
    let flow = !scene.vacuum;
    let pressure = bodies && flow && scene.numerics.body_coupling == BodyCoupling::Pressure;
    // f64 arrays per node.
    let mut per_node = nc + 1.5 * d; // Fields (ω, u, and u_prev in single precision)
    if bodies {
        per_node += 4.0 + d + 0.5; // BodyFields: ρ, ρ_P, χ, φ, du, owner (u32)
    }
    if pressure {
        per_node += 3.0 * d + 4.0 + 1.0; // β, src, trial; r, z, p, ap; PressureState φ
        // The multigrid hierarchy where the densities can differ by its contrast: four weights
        // per node on every level, and each coarse level's right-hand side and correction
        // (a level has 2^-dim of the nodes of the one above it).
        if scene.resolved().params.multigrid {
            let levels = 2f64.powf(d) / (2f64.powf(d) - 1.0);
            per_node += 4.0 * levels + 2.0 * (levels - 1.0);
        }
    }
    let free_surface = scene.free_surface.is_some();
    if free_surface {
        // The liquid's level set, the free surface's φ⁰ and Jacobi buffer, 1 - χ of the walls
        // and of every body (f32 each), the walls' mask (bytes); the momentum form's carried
        // fields (ρ, q, φ_w); the pressure's rigid-wall density and reduced potential.
        per_node += 3.0 + 1.0 + 0.125 + (d + 2.0) + 2.0;
    }
    if flow {
        // Spectral: ω̂ per component and a work buffer, (nx/2 + 1) complex per nx reals.
        let nx = g.n[0] as f64;
        let half = 2.0 * (nx / 2.0 + 1.0).floor() / nx;
        per_node += (nc + 1.0) * half;
        // The no-slip of the pressure coupling without a free surface (`systems/noslip.rs`):
        // the spread force and its response, a scratch field, and the forcing's spectra
        // (`Spectral::reserve_forcing`: d + nc complex half fields).
        if pressure && scene.free_surface.is_none() {
            per_node += 2.0 * d + 1.0 + (d + nc) * half;
        }
    }
    let b = band(&g);
    let (mut local_nodes, mut patch_nodes) = (0.0, 0.0);
    for (spec, geom) in scene.bodies.iter().zip(scene.geometries()) {
        match geom.bounds() {
            Some((lo, hi)) => {
                let size = hi - lo;
                local_nodes += box_nodes(size + DVec3::splat(2.0 * b), h, dim);
                let r = crate::bodies::angular3(&spec.rotation);
                let m = if r.length() > 0.0 {
                    DMat3::from_quat(DQuat::from_scaled_axis(r))
                } else {
                    DMat3::IDENTITY
                };
                // World box of the rotated body box: |M| times the half sizes.
                let half = 0.5 * size;
                let world = DVec3::new(
                    m.row(0).abs().dot(half),
                    m.row(1).abs().dot(half),
                    m.row(2).abs().dot(half),
                );
                let patch = box_nodes(2.0 * world + DVec3::splat(2.0 * b), h, dim);
                patch_nodes += patch.min(n);
            }
            None => patch_nodes += n,
        }
    }
    let bytes = BASE_BYTES + 8.0 * (per_node * n + local_nodes + 2.0 * patch_nodes);
    let mut seconds = SECONDS_PER_PATCH_NODE * patch_nodes;
    if flow {
        seconds += FLOW_SECONDS_PER_NODE * n;
        if bodies {
            seconds += BODY_GRID_SECONDS_PER_NODE * n;
        }
    }
    Estimate {
        bytes,
        seconds_per_step: seconds,
        nodes: n,
        patch_nodes,
        local_nodes,
    }
}

/// The estimate in words: "about 124 MB peak, about 0.23 s per step on 2 threads".
pub fn words(e: &Estimate) -> String {
    format!(
        "estimated peak memory {}, estimated {} s per step on 2 threads ({} grid nodes, {} \
         body patch nodes; a model of `tumble bench` on a 2-core machine, see io::estimate)",
        crate::io::summary::human_bytes(e.bytes),
        sig2(e.seconds_per_step),
        sig2(e.nodes),
        sig2(e.patch_nodes)
    )
}

fn sig2(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    if x >= 1e5 {
        return format!("{x:.2e}");
    }
    let decimals = (1 - x.abs().log10().floor() as i32).max(0) as usize;
    format!("{x:.decimals$}")
}

/// Bytes of a `series.csv` row (up to 9 values written to full precision, about 24 characters
/// each).
pub const SERIES_ROW_BYTES: f64 = 220.0;

/// Bytes of a `bodies.csv` row (one per moving body and step: 20 values to full precision, the
/// id and the name).
pub const BODY_ROW_BYTES: f64 = 500.0;

/// Bytes of a checkpoint besides the fields (the scene's text, the run's progress, the
/// systems' records), and per body.
const CHECKPOINT_BASE_BYTES: f64 = 16.0e3;
const CHECKPOINT_BODY_BYTES: f64 = 600.0;

/// The steps and wall time of a whole run, as far as the scene tells (see
/// [`crate::scene::steps`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunLength {
    /// The largest step and what sets it; `None` when the scene does not bound the step (an
    /// adaptive step without `dt_max`, bodies, gravity on bodies or a free surface).
    pub bound: Option<crate::scene::steps::StepBound>,
    /// Steps to the end time: exactly (a fixed step) or at least (an adaptive one).
    pub steps: Option<f64>,
    /// Estimated wall seconds on 2 threads: `steps` times the estimated time per step.
    pub wall: Option<f64>,
}

/// The steps and wall time of `scene`'s run.
pub fn run_length(scene: &ValidScene) -> RunLength {
    let bound = crate::scene::steps::step_bound(scene, &scene.grid(), scene.resolved());
    let steps = bound.map(|b| b.steps(scene.numerics.end_time));
    RunLength {
        bound,
        steps,
        wall: steps.map(|n| n * estimate(scene).seconds_per_step),
    }
}

/// The files a run writes, and about how large.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Outputs {
    /// Field snapshots (the first, one per `output.every`, the last).
    pub snapshots: f64,
    /// Bytes of one snapshot in every format, before compression.
    pub snapshot_bytes: f64,
    /// Bytes of one checkpoint.
    pub checkpoint_bytes: f64,
    /// The most checkpoints on disk at once: `output.checkpoints_kept` and the one being
    /// written when checkpoints are periodic, else the one an interruption writes.
    pub checkpoints: usize,
    /// Bytes of the CSV time series over the steps of [`run_length`] (at least), `None` when
    /// the steps are not known.
    pub series_bytes: Option<f64>,
}

impl Outputs {
    /// Everything: the snapshots, the checkpoints and the time series (when known).
    pub fn total(&self) -> f64 {
        self.snapshots * self.snapshot_bytes
            + self.checkpoints as f64 * self.checkpoint_bytes
            + self.series_bytes.unwrap_or(0.0)
    }

    /// The outputs in words: "about 1.2 GB: 41 snapshots of 25 MB, 3 checkpoints of 30 MB, time
    /// series 2 MB".
    pub fn words(&self) -> String {
        let h = crate::io::summary::human_bytes;
        let series = match self.series_bytes {
            Some(b) => format!("time series at least {}", h(b)),
            None => "time series (not counted: the steps are not known)".to_string(),
        };
        format!(
            "{} snapshots of {} (before compression), {} checkpoint{} of {}, {series}",
            if self.snapshots < 1e12 {
                format!("{:.0}", self.snapshots)
            } else {
                format!("{:.3e}", self.snapshots)
            },
            h(self.snapshot_bytes),
            self.checkpoints,
            if self.checkpoints == 1 { "" } else { "s" },
            h(self.checkpoint_bytes),
        )
    }
}

/// Field snapshots of `scene`: the first, one at each multiple of `output.every`, the last.
pub fn snapshot_count(scene: &ValidScene) -> f64 {
    match scene.output.every {
        Some(e) if e > 0.0 => (scene.numerics.end_time / e).ceil() + 1.0,
        _ => 2.0,
    }
}

/// Values (per node, summed over the snapshot's fields) of one snapshot of `scene`.
pub fn snapshot_values(scene: &ValidScene) -> f64 {
    use crate::scene::FieldName;
    let g = scene.grid();
    let per_node: usize = scene
        .output
        .fields
        .iter()
        .map(|f| match f {
            FieldName::Omega => g.omega_components(),
            FieldName::Velocity => 3,
            FieldName::Density if scene.bodies.is_empty() => 0,
            FieldName::Density => 3,
        })
        .sum();
    per_node as f64 * g.len() as f64
}

/// The outputs of `scene`'s run.
pub fn outputs(scene: &ValidScene) -> Outputs {
    let g = scene.grid();
    let o = &scene.output;
    let n = g.len() as f64;
    let snapshot_bytes =
        snapshot_values(scene) * o.precision.bytes() as f64 * o.formats.len() as f64;
    // ω, u (f64) and the previous u (f32), per node.
    let per_node = 8.0 * g.omega_components() as f64 + 12.0 * g.dim as f64;
    let checkpoint_bytes =
        CHECKPOINT_BASE_BYTES + per_node * n + CHECKPOINT_BODY_BYTES * scene.bodies.len() as f64;
    let periodic = o.checkpoint_every.is_some() || o.checkpoint_wall.is_some();
    let checkpoints = if periodic {
        o.checkpoints_kept.max(1) + 1
    } else {
        1
    };
    let moving = scene
        .bodies
        .iter()
        .filter(|b| !matches!(b.kind, crate::scene::BodyKind::Static))
        .count() as f64;
    let series_bytes = run_length(scene)
        .steps
        .map(|s| (s + 1.0) * (SERIES_ROW_BYTES + moving * BODY_ROW_BYTES));
    Outputs {
        snapshots: snapshot_count(scene),
        snapshot_bytes,
        checkpoint_bytes,
        checkpoints,
        series_bytes,
    }
}

/// Seconds as a person reads them: "40 s", "12 min", "3.5 h", "2.1 days".
pub fn human_seconds(s: f64) -> String {
    if !s.is_finite() {
        format!("{s}")
    } else if s < 100.0 {
        format!("{} s", sig2(s))
    } else if s < 6000.0 {
        format!("{} min", sig2(s / 60.0))
    } else if s < 3.0 * 86400.0 {
        format!("{} h", sig2(s / 3600.0))
    } else {
        format!("{} days", sig2(s / 86400.0))
    }
}

/// Doubles per node a process holds besides a one-process run's when the grid is split: the
/// transport's z sweep in the row layout (three vorticity components and the velocity's z
/// component) and its send buffer, and the FFT's planes and send buffer (two half spectra,
/// about two doubles); the velocity's 4 ghost planes a side are not counted (a few planes).
/// Measured: Taylor-Green 128³ on 2 processes held 178 MB each against 206 MB on one
/// (2026-11-28).
const SPLIT_DOUBLES_PER_NODE: f64 = 4.0 + 1.0 + 2.0;

/// A scene's cost split over processes.
#[derive(Debug, Clone, PartialEq)]
pub struct SplitEstimate {
    /// Processes.
    pub processes: usize,
    /// z-planes of the thickest and thinnest slab.
    pub planes: (usize, usize),
    /// Peak memory of the process with the thickest slab, bytes.
    pub bytes_per_process: f64,
    /// Bytes each process sends in all-to-alls per step (the spectral solves' 9 transposes of
    /// half spectra and the z sweep's 7 transposes of real fields; the share a process keeps is
    /// not sent).
    pub transposed_bytes: f64,
    /// Why the scene cannot run split over `processes`, if it cannot.
    pub refused: Option<String>,
}

/// The estimate for `scene` split over `processes` processes (slabs of z-planes).
pub fn split_estimate(scene: &ValidScene, processes: usize) -> SplitEstimate {
    let g = scene.grid();
    let whole = estimate(scene);
    let slabs = crate::parallel::Slabs::new(g.n, processes, 0);
    let planes = (g.n[2].div_ceil(processes), (g.n[2] / processes).max(1));
    let local = whole.nodes * planes.0 as f64 / g.n[2] as f64;
    // The grid's fields and the bodies' patches are split; every process holds every body's
    // own level set whole.
    let bodies_own = 8.0 * whole.local_nodes;
    let per_node = (whole.bytes - BASE_BYTES - bodies_own) / whole.nodes;
    let mut bytes_per_process =
        BASE_BYTES + bodies_own + local * (per_node + 8.0 * SPLIT_DOUBLES_PER_NODE);
    if scene.free_surface.is_some() {
        // Rank 0's whole-grid level set and walls' mask for the snapshots' zero level (two
        // doubles a node of the whole grid; the extensions' ghost planes are a few planes),
        // and the momentum form's z sweep in the row layout: its d + 2 carried fields, the
        // velocity's z component and the bodies' level set, d more than the vorticity form's
        // four counted above.
        let d = g.dim as f64;
        bytes_per_process += whole.nodes * 16.0 + local * 8.0 * d;
    }
    let kept = 1.0 / processes as f64;
    let nxh = (g.n[0] / 2 + 1) as f64;
    let half_spectrum = 16.0 * nxh * (local / g.n[0] as f64);
    let transposed_bytes = (1.0 - kept) * (9.0 * half_spectrum + 7.0 * 8.0 * local);
    let refused = crate::sim::engine::unsplittable(scene).or(slabs.err().map(|e| e.to_string()));
    SplitEstimate {
        processes,
        planes,
        bytes_per_process,
        transposed_bytes,
        refused,
    }
}

/// The split estimate in words.
pub fn split_words(e: &SplitEstimate) -> String {
    if let Some(why) = &e.refused {
        return format!("on {} processes: cannot split ({why})", e.processes);
    }
    let slabs = if e.planes.0 == e.planes.1 {
        format!("{}", e.planes.0)
    } else {
        format!("{} to {}", e.planes.1, e.planes.0)
    };
    format!(
        "on {} processes: slabs of {slabs} z-planes, estimated peak memory {} per process, {} \
         sent per process per step in transposes",
        e.processes,
        crate::io::summary::human_bytes(e.bytes_per_process),
        crate::io::summary::human_bytes(e.transposed_bytes)
    )
}
