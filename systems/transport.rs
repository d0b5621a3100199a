//! # transport: vortex-in-cell advection and stretching (paper eq. 29-30, section 3.2)
//!
//! Solves ∂ω/∂t + (u·∇)ω = (ω·∇)u over one step with the velocity frozen at the mid-step
//! value u^{n+1/2} = u^n + (Δt_n / 2Δt_{n-1})(u^n - u^{n-1}), extrapolated from the last two
//! velocities (u^n is the Poisson solve of the previous step, corrected by penalization and
//! the baroclinic term when those systems run). With the velocity frozen at u^n instead
//! (`numerics.midpoint_velocity: false`, and on the first step) the step is first order in time;
//! with the mid-step velocity it is second order.
//!
//! * Stretching (3D only): (ω·∇)u with ∇u by eighth-order centred differences, integrated at
//!   every node with the midpoint rule ω ← ω + Δt G(ω + Δt/2 G ω), G = ∇u frozen. It runs
//!   before the advection sweeps on even steps and after them on odd steps, so that over two
//!   steps the splitting is symmetric (S X Y Z | Z Y X S) and second order. Always stretching
//!   first (Lie splitting) produces energy at first order in Δt: on the Re = 1600 Taylor-Green
//!   vortex at 64³ it put E(t = 5) 4% above the reference; the symmetric order brings it to 1%
//!   (as does a Strang split S/2 A S/2, which costs a second stretching pass).
//! * Advection: particles are created at the grid nodes where |ω| exceeds the cutoff, pushed
//!   with the midpoint RK2 rule x ← x + Δt u(x + Δt/2 u(x)) using velocity interpolated with
//!   the M'4 kernel (30), and remeshed onto the grid with M'4.
//!
//! The push and remesh are done one axis at a time ([`crate::solvers::sweep`]; dimensional
//! splitting, Magni & Cottet, J. Comput. Phys. 231 (2012); Cottet, Etancelin et al., ESAIM:
//! M2AN 48 (2014)), alternating the axis order every step (x y z, then z y x) so the splitting
//! is second order over two steps.
//! Each 1D remesh with M'4 is exactly the tensor-product M'4 remesh of particles displaced
//! along one axis, so circulation and the first two moments are conserved exactly, and a
//! particle touches 4 nodes per sweep instead of 4³: this is what makes a 128³ step cheap.
//! Every line of nodes is handled by one task, so results do not depend on the thread count.
//!
//! On several processes (a slab of z-planes each, [`crate::parallel`]) the x and y sweeps are
//! local; the z sweep runs on whole z-lines in the row layout, reached by the transposes the
//! FFTs use, so each line's particles move and remesh exactly as on one process; the
//! stretching reads [`R`] ghost planes of the velocity from each neighbour. The results are the
//! one-process results to round-off in the reductions (the cutoff's max|ω| is exact).
//!
//! Nodes whose vorticity is at or below the cutoff create no particle: their vorticity stays
//! where it is (circulation is kept; the error is of the size of the cutoff).
//!
//! ## The momentum form (two fluid phases)
//!
//! With a free surface the flow is carried as mass and momentum instead (`momentum_transport`):
//!
//!   ∂ρ/∂t + ∇·(ρu) = 0,   ∂(ρu)/∂t + ∇·(ρu ⊗ u) = 0   (the rest of the momentum equation,
//!   -∇p + ρg + ∇·(μ∇u) and the bodies, is made by the other systems),
//!
//! by particles created at every node with mass ρ h^d, momentum ρ u h^d and the liquid's level
//! set φ_w, pushed with the same RK2 rule and mid-step velocity and remeshed axis by axis with
//! one set of weights for all three ([`crate::solvers::carry`]: non-negative near the free
//! surface and the bodies, M'4 elsewhere). The velocity is then ũ = q̃/ρ̃ and ρ̃ the density of
//! the rest of the step. Mass and momentum cross the interface with the same fluxes, so a
//! uniform velocity stays uniform across a 1:1000 jump and the remesh cannot create kinetic
//! energy there; in vorticity form the density changes were added afterwards by the projection,
//! and a light fringe of the interface carrying the gas's velocity traded momentum with the
//! liquid (issue 44: a collapsing column sped up on the finer grid, the cup's waterline shredded
//! at 128³). There is no stretching term (it is part of ∇·(ρu ⊗ u)). The density is reset from
//! the level sets at the start of the next step (`density`), as IBAMR does (Nangia et al.,
//! J. Comput. Phys. 2019), since carried by the hat kernel it would spread a little every step.
//! On several processes its z sweep runs on whole lines in the row layout as the vorticity's
//! does (the carried fields, the velocity's z component and the bodies' level set transposed
//! there), and the reset below reads one ghost plane a side: the one-process results bit for
//! bit.
//!
//! The reset moves mass without its momentum wherever the remeshed density ρ̃ and the one the
//! level set gives, ρ(φ̃_w), differ: in the light fringe of the interface, which carries the
//! gas's velocity, that turned gas momentum into liquid momentum (issue 34's channel). So the
//! velocity is set here for the density of the next step, outside the bodies (`donor_reset`):
//! the mass δ = ρ(φ̃_w) - ρ̃ > 0 that the reset adds to a node comes with the velocity of the
//! nodes next to it that lose mass (δ < 0; their mass-weighted mean velocity, mass that the hat
//! kernel spread to the other side of the interface and the reset brings back), and a node that
//! loses mass keeps its velocity. The momentum then moves with the mass, and the mixing of the
//! two velocities at a receiving node can only lower the kinetic energy (Cauchy-Schwarz). A
//! node with no losing neighbour keeps its momentum. Measured on `column-collapse` (h = a/32):
//! keeping the velocity everywhere, the tank's kinetic + potential energy rose by 0.30 at 1:100
//! (16% of the potential energy the column releases) and 0.043 at 1:1000 as bursts of gas
//! velocity grew over the plunging front; keeping the momentum everywhere, the run blew up at
//! t = 0.50 and 0.17; keeping the momentum of a node made heavier and the velocity of one made
//! lighter, the energy never rose but fell by 0.74 by t = 2.3 at 1:1000 (40% of what the column
//! releases) and the front lagged Martin & Moyce's by 16% at t = 2; as here, the energy never
//! rises, falls by 0.13 by t = 2.3, and the front at t = 1, 1.5, 2 is 1.90, 2.70, 3.64 column
//! widths from the wall (Martin & Moyce: 1.68, 2.45, 3.40; their gate slowed the start). ρ(φ̃_w)
//! is taken before the free surface's redistancing and volume correction, which move φ_w by a
//! small fraction of a cell.
//!
//! The push uses the velocity ũ^n that this step's projection made (gravity and pressure
//! first, then the particles move with the new velocity: a symplectic Euler pair for the
//! interface, whose oscillations then neither grow nor decay from the time stepping), not the
//! mid-step extrapolation from the last two velocities: with it a standing wave at 1:1000
//! (h = 1/64) lost half its amplitude in two periods (half-period peaks 0.00978, 0.00939,
//! 0.00724, 0.00462), and the spheres of `pool-drop` blew up at t = 0.39 at the default step
//! (0.03-0.06, the gravity-wave bound); frozen, the peaks are 0.00978, 0.01053, 0.00937, 0.00975
//! and the spheres run.

use crate::base::fields::{Fields, Params, SimTime};
use crate::base::grid::{Grid, periodic_offset as wrap};
use crate::base::kernels::heaviside;
use crate::base::pool::Pool;
use crate::bodies::BodyFields;
use crate::bodies::free_surface::{FreeSurface, LiquidLevelSet};
use crate::parallel::{Decomposition, Halo, Transpose, global_max};
use crate::solvers::carry::{CarryPool, CarryScratch, NEAR_CELLS, Near, carry_sweep};
use crate::solvers::sweep::{LinePool, LineScratch, split_axes, sweep};
use bevy_ecs::prelude::*;
use rayon::prelude::*;

/// Scratch buffers for the sweeps, owned by the transport system (nothing is allocated in a
/// step).
#[derive(Resource)]
pub struct TransportScratch {
    pool: LinePool,
    /// Whether the next step sweeps axes in reverse order.
    reverse: bool,
    /// On several processes: the halo and transposes of the slab.
    split: Option<SplitScratch>,
}

/// The transport of a slab ([`Grid::slab`]): [`R`] ghost planes of the velocity on each side
/// for the stretching's differences along z, and the z sweep run on whole lines along z, in the
/// row layout ([`Transpose`]), where each line is one process's and the sweep is the one-process
/// code unchanged: the particles of a line then move and remesh exactly as on one process.
struct SplitScratch {
    /// Per velocity component, the R planes below the slab then the R planes above it (the
    /// neighbours').
    u_ghost: Halo,
    /// The vorticity's components and the velocity's z component in the row layout.
    lines: ZLines,
}

/// Whole lines along z of a slab's fields: the row layout of the FFTs' transposes
/// ([`Transpose`]), where this process holds some y rows with every z, and the grid of it.
struct ZLines {
    d: Decomposition,
    transpose: Transpose,
    /// The fields in the row layout.
    rows: Vec<Vec<f64>>,
    /// The transpose's scratch.
    packed: Vec<f64>,
    /// The grid of the row layout: this process's y rows, every z.
    grid: Grid,
}

impl ZLines {
    /// Room for `fields` fields of the slab `grid` of `d`'s.
    fn new(grid: &Grid, d: &Decomposition, fields: usize) -> Self {
        let transpose = Transpose::new(&d.slabs, grid.n[0]);
        let rows = d.slabs.my_rows();
        let whole = grid.whole();
        let mut origin = whole.origin;
        origin[1] += rows.start as f64 * grid.h;
        ZLines {
            d: d.clone(),
            rows: vec![vec![0.0; transpose.rows_len()]; fields],
            packed: vec![0.0; transpose.slab_len()],
            transpose,
            grid: Grid::new([grid.n[0], rows.len(), whole.n[2]], grid.h, origin),
        }
    }

    /// The slab's field `f` into row-layout field `c` (every process together).
    fn forward(&mut self, c: usize, f: &[f64]) {
        self.transpose
            .forward(&self.d.comm, f, &mut self.packed, &mut self.rows[c]);
    }

    /// Row-layout field `c` back into the slab's field `f` (every process together).
    fn backward(&mut self, c: usize, f: &mut [f64]) {
        self.transpose
            .backward(&self.d.comm, &self.rows[c], &mut self.packed, f);
    }
}

impl SplitScratch {
    fn new(grid: &Grid, d: &Decomposition) -> Self {
        SplitScratch {
            u_ghost: Halo::new(grid, d, R, 3),
            lines: ZLines::new(grid, d, 4),
        }
    }

    /// The sweep along z of the slab's vorticity with the velocity's z component `uz`, on
    /// whole lines.
    #[allow(clippy::too_many_arguments)]
    fn sweep_z(
        &mut self,
        dt: f64,
        omega: &mut [Vec<f64>],
        uz: &[f64],
        cutoff: f64,
        kernel: crate::base::params::RemeshKernel,
        pool: &LinePool,
    ) {
        let zl = &mut self.lines;
        let nc = omega.len();
        for (c, w) in omega.iter().enumerate() {
            zl.forward(c, w);
        }
        zl.forward(3, uz);
        let (w_rows, u_rows) = zl.rows.split_at_mut(nc);
        sweep(
            &zl.grid,
            2,
            dt,
            w_rows,
            &u_rows[u_rows.len() - 1],
            cutoff,
            kernel,
            pool,
        );
        for (c, w) in omega.iter_mut().enumerate() {
            zl.backward(c, w);
        }
    }
}

impl TransportScratch {
    /// Scratch for `grid`, a slab of `split`'s when the run is split.
    pub fn new(grid: &Grid, split: Option<&Decomposition>) -> Self {
        let nmax = *grid.n.iter().chain([&grid.nz_whole]).max().unwrap_or(&1);
        let nc = grid.omega_components();
        let pool = Pool::per_thread(move || LineScratch::new(nmax, nc));
        TransportScratch {
            pool,
            reverse: false,
            split: split.map(|d| SplitScratch::new(grid, d)),
        }
    }
}

/// A checkpoint keeps the split order, which alternates every step (the pool is scratch).
impl crate::schedule::CheckpointPart for TransportScratch {
    type Part = bool;
    fn save_part(&self) -> bool {
        self.reverse
    }
    fn restore_part(&mut self, reverse: bool) {
        self.reverse = reverse;
    }
}

/// The transport system.
pub fn transport(
    grid: Res<Grid>,
    params: Res<Params>,
    time: Res<SimTime>,
    mut fields: ResMut<Fields>,
    mut scratch: ResMut<TransportScratch>,
    split: Option<Res<Decomposition>>,
) {
    let dt = time.dt;
    let fields = &mut *fields;
    let max_omega = global_max(split.as_deref(), crate::solvers::max_norm(fields.omega()));
    let cutoff = params.numerics.remesh_cutoff * max_omega;
    let scratch = &mut *scratch;
    let a = if params.numerics.experimental.midpoint_velocity && fields.dt_prev > 0.0 {
        0.5 * dt / fields.dt_prev
    } else {
        0.0
    };
    // The mid-step velocity, made in place of the velocity (which the Poisson solve replaces
    // at the end of the step); the velocity it replaces becomes the previous one.
    let (omega, u, u_prev) = fields.transport_parts();
    mid_step_velocity(u, u_prev, a);
    let u = &*u;
    let kernel = params.numerics.experimental.remesh_kernel;
    let TransportScratch {
        pool,
        reverse,
        split,
    } = &mut *scratch;
    if let Some(sp) = split.as_mut() {
        sp.u_ghost.fill(u);
    }
    let stretch_now = |omega: &mut [Vec<f64>], split: &Option<SplitScratch>| match split {
        Some(sp) => stretch_ghosted(&grid, dt, omega, u, Some(sp.u_ghost.all())),
        None => stretch(&grid, dt, omega, u),
    };
    if grid.dim == 3 && !*reverse {
        stretch_now(omega, split);
    }
    let axes = split_axes(grid.dim, *reverse);
    for &axis in axes {
        match split.as_mut() {
            Some(sp) if axis == 2 => sp.sweep_z(dt, omega, &u[2], cutoff, kernel, pool),
            _ => sweep(&grid, axis, dt, omega, &u[axis], cutoff, kernel, pool),
        }
    }
    if grid.dim == 3 && *reverse {
        stretch_now(omega, split);
    }
    *reverse = !*reverse;
}

/// The most cells a particle of the momentum form moves along an axis in one push (the push is
/// cut into substeps beyond it): below one, so the hat kernel leaves no node without mass.
const SUBSTEP_CELLS: f64 = 0.9;

/// The momentum form's scratch: the carried fields (ρ, ρu per component, φ_w) and the line
/// buffers of their sweeps, allocated once.
#[derive(Resource)]
pub struct MomentumScratch {
    carried: Vec<Vec<f64>>,
    pool: CarryPool,
    /// On several processes: the z sweep's transposes and the reset's ghost planes.
    split: Option<MomentumSplit>,
}

/// The momentum form on a slab: the z sweep on whole lines along z in the row layout (as the
/// vorticity form's, [`SplitScratch`]), and one ghost plane a side of the carried fields and
/// of Σχ for the reset's neighbours.
struct MomentumSplit {
    /// The carried fields, the velocity's z component and the bodies' level set in the row
    /// layout.
    lines: ZLines,
    /// Ghost planes of ρ̃, q̃ (dim components), φ̃_w and Σχ, in that order.
    halo: Halo,
}

impl MomentumScratch {
    /// Scratch for `grid`, a slab of `split`'s when the run is split.
    pub fn new(grid: &Grid, split: Option<&Decomposition>) -> Self {
        let nmax = *grid.n.iter().chain([&grid.nz_whole]).max().unwrap_or(&1);
        let nf = grid.dim + 2;
        MomentumScratch {
            carried: vec![vec![0.0; grid.len()]; nf],
            pool: CarryPool::per_thread(move || CarryScratch::new(nmax, nf)),
            split: split.map(|d| MomentumSplit {
                lines: ZLines::new(grid, d, nf + 2),
                halo: Halo::new(grid, d, 1, nf + 1),
            }),
        }
    }
}

impl MomentumSplit {
    /// The carrying sweep along z of the slab's `carried` fields with the velocity's z
    /// component `uz` and the bodies' level set `solid` (empty without bodies), on whole lines.
    #[allow(clippy::too_many_arguments)]
    fn sweep_z(
        &mut self,
        dt: f64,
        carried: &mut [Vec<f64>],
        uz: &[f64],
        solid: &[f64],
        near: Near,
        pool: &CarryPool,
    ) {
        let zl = &mut self.lines;
        let nf = carried.len();
        for (c, f) in carried.iter().enumerate() {
            zl.forward(c, f);
        }
        zl.forward(nf, uz);
        if !solid.is_empty() {
            zl.forward(nf + 1, solid);
        }
        let (f_rows, rest) = zl.rows.split_at_mut(nf);
        let solid_rows: &[f64] = if solid.is_empty() { &[] } else { &rest[1] };
        carry_sweep(&zl.grid, 2, dt, f_rows, &rest[0], solid_rows, near, pool);
        for (c, f) in carried.iter_mut().enumerate() {
            zl.backward(c, f);
        }
    }
}

/// Replace the velocity `u` by the mid-step velocity u + a (u - u_prev) and keep the velocity
/// it replaces in `u_prev` (see the module doc).
fn mid_step_velocity(u: &mut [Vec<f64>], u_prev: &mut [Vec<f32>], a: f64) {
    for (u, up) in u.iter_mut().zip(u_prev.iter_mut()) {
        u.par_chunks_mut(4096)
            .zip(up.par_chunks_mut(4096))
            .for_each(|(u, up)| {
                for i in 0..u.len() {
                    let now = u[i];
                    u[i] = now + a * (now - up[i] as f64);
                    up[i] = now as f32;
                }
            });
    }
}

/// The momentum form's transport system: mass, momentum and the liquid's level set carried by
/// the same particles (see the module doc); ũ = q̃/ρ̃ into the velocity, ρ̃ into the density.
#[allow(clippy::too_many_arguments)]
pub fn momentum_transport(
    grid: Res<Grid>,
    params: Res<Params>,
    time: Res<SimTime>,
    mut fields: ResMut<Fields>,
    mut bf: ResMut<BodyFields>,
    mut ls: ResMut<LiquidLevelSet>,
    mut scratch: ResMut<MomentumScratch>,
    surfaces: Query<&FreeSurface>,
) {
    let dt = time.dt;
    let (fields, bf, scratch) = (&mut *fields, &mut *bf, &mut *scratch);
    let dim = grid.dim;
    let carried = &mut scratch.carried;
    // Mass and momentum of the particles, from the velocity the step has made so far.
    {
        let (rho_c, rest) = carried.split_at_mut(1);
        rho_c[0]
            .par_chunks_mut(4096)
            .zip(bf.rho.par_chunks(4096))
            .for_each(|(o, r)| o.copy_from_slice(r));
        for a in 0..dim {
            rest[a]
                .par_chunks_mut(4096)
                .zip(bf.rho.par_chunks(4096))
                .zip(fields.u[a].par_chunks(4096))
                .for_each(|((q, r), u)| {
                    for i in 0..q.len() {
                        q[i] = r[i] * u[i];
                    }
                });
        }
        rest[dim]
            .par_chunks_mut(4096)
            .zip(ls.phi.par_chunks(4096))
            .for_each(|(o, p)| o.copy_from_slice(p));
    }
    // The velocity is frozen at ũ^n, made by this step's projection (gravity and pressure)
    // before it moves the particles: with the level set carried by them, the interface and the
    // flow advance as a symplectic Euler pair (see the module doc). (`u_prev`, which only the
    // vorticity form's extrapolation and the baroclinic coupling read, is not kept.)
    let reach = (NEAR_CELLS + params.numerics.interface_cells) * grid.h;
    let near = Near {
        field: dim + 1,
        level_set: reach,
        solid: reach,
    };
    let axes = split_axes(dim, time.step % 2 == 1);
    // The hat kernel leaves a node empty when a particle moves a cell or more: the push is cut
    // into substeps that move no particle more than SUBSTEP_CELLS cells.
    let split = scratch.split.as_mut();
    let umax = global_max(
        split.as_ref().map(|s| &s.lines.d),
        crate::solvers::max_norm(&fields.u),
    );
    let cells = umax * dt / grid.h;
    let nsub = ((cells / SUBSTEP_CELLS).ceil() as usize).max(1);
    let dts = dt / nsub as f64;
    let mut split = split;
    for _ in 0..nsub {
        for &axis in axes {
            match split.as_mut() {
                Some(sp) if axis == 2 => {
                    sp.sweep_z(dts, carried, &fields.u[2], &bf.phi, near, &scratch.pool)
                }
                _ => carry_sweep(
                    &grid,
                    axis,
                    dts,
                    carried,
                    &fields.u[axis],
                    &bf.phi,
                    near,
                    &scratch.pool,
                ),
            }
        }
    }
    // ũ = q̃/ρ̃, ρ̃ the density of the rest of the step, φ_w carried.
    let carried = &scratch.carried;
    let (rho_c, rest) = carried.split_at(1);
    for a in 0..dim {
        fields.u[a]
            .par_chunks_mut(4096)
            .zip(rho_c[0].par_chunks(4096))
            .zip(rest[a].par_chunks(4096))
            .for_each(|((u, r), q)| {
                for i in 0..u.len() {
                    u[i] = q[i] / r[i];
                }
            });
    }
    if let Some(fs) = surfaces.iter().next() {
        let eps = params.numerics.interface_cells * grid.h;
        let (g, d) = (fs.gas_density, fs.liquid_density - fs.gas_density);
        // The density the next step resets from the level set: the mass it moves keeps its
        // momentum (see the module doc).
        let halo = split.map(|sp| {
            for (c, f) in carried.iter().chain([&bf.chi]).enumerate() {
                sp.halo.fill_one(c, f);
            }
            &sp.halo
        });
        donor_reset(&grid, carried, &bf.chi, halo, g, d, eps, &mut fields.u);
    }
    bf.rho
        .par_chunks_mut(4096)
        .zip(rho_c[0].par_chunks(4096))
        .for_each(|(o, r)| o.copy_from_slice(r));
    ls.phi
        .par_chunks_mut(4096)
        .zip(rest[dim].par_chunks(4096))
        .for_each(|(o, p)| o.copy_from_slice(p));
}

/// The velocity for the density ρ(φ̃_w) of the next step's reset, outside the bodies: the mass
/// the reset adds to a node (δ = ρ(φ̃_w) - ρ̃ > 0) comes with the velocity of the nodes around it
/// that it takes mass from (δ < 0, mass-weighted; with none, the node keeps its momentum), and a
/// node that gives mass keeps its velocity. `carried` is ρ̃, q̃ (dim components) and φ̃_w; on a
/// slab, `halo` holds their ghost planes and Σχ's (`chi`), in that order.
#[allow(clippy::too_many_arguments)]
fn donor_reset(
    grid: &Grid,
    carried: &[Vec<f64>],
    chi: &[f64],
    halo: Option<&Halo>,
    g: f64,
    d: f64,
    eps: f64,
    u: &mut [Vec<f64>],
) {
    let dim = grid.dim;
    let [nx, ny, _] = grid.n;
    let (ls, ch) = (dim + 1, dim + 2);
    // Row `j` of the plane `dk` from row `row`'s, of carried field `f` (Σχ for `ch`).
    let line = |f: usize, row: usize, j: usize, dk: isize| {
        let field: &[f64] = if f == ch { chi } else { &carried[f] };
        crate::parallel::halo::z_line(grid, field, halo, f, j + ny * (row / ny), dk)
    };
    let up = crate::base::grid::component_ptrs(u);
    let kr: &[isize] = if dim == 3 { &[-1, 0, 1] } else { &[0] };
    (0..grid.len() / nx).into_par_iter().for_each(|row| {
        let j = row % ny;
        // The 3 x 3 rows around this one (dk, dj), of ρ̃, φ̃_w and Σχ.
        let delta = |j: usize, dk: isize, i: usize| {
            if line(ch, row, j, dk)[i] > 0.0 {
                0.0
            } else {
                g + d * heaviside(line(ls, row, j, dk)[i], eps) - line(0, row, j, dk)[i]
            }
        };
        for i in 0..nx {
            let c = i + nx * row;
            let dc = delta(j, 0, i);
            if dc <= 0.0 {
                continue;
            }
            let (mut w, mut qd) = (0.0, [0.0; 3]);
            for &dk in kr {
                for dj in -1..=1 {
                    let jj = wrap(j, dj, ny);
                    let rho_n = line(0, row, jj, dk);
                    for di in -1..=1 {
                        let ii = wrap(i, di, nx);
                        let dn = delta(jj, dk, ii);
                        if dn < 0.0 {
                            w -= dn;
                            for a in 0..dim {
                                qd[a] -= dn * line(1 + a, row, jj, dk)[ii] / rho_n[ii];
                            }
                        }
                    }
                }
            }
            let (rho, q) = (&carried[0], &carried[1..=dim]);
            let next = rho[c] + dc;
            for a in 0..dim {
                let add = if w > 0.0 { dc * qd[a] / w } else { 0.0 };
                // SAFETY: node c belongs to this row's task only.
                unsafe { up[a].write(c, (q[a][c] + add) / next) };
            }
        }
    });
}

/// Half-width of the stretching's centred difference stencil.
const R: usize = STRETCH_COEFFS.len();

/// Signed weights of f(x + m h) - f(x - m h), m = 1..=R, in the eighth-order centred first
/// difference (times 1/h): 4/5, -1/5, 4/105, -1/280.
const STRETCH_COEFFS: [f64; 4] = [4.0 / 5.0, -1.0 / 5.0, 4.0 / 105.0, -1.0 / 280.0];

/// Stretching (ω·∇)u at every node, midpoint rule in time with ∇u frozen; ∇u by eighth-order
/// centred differences. Works row by row: the neighbour rows (±1..±R in y and z) are plain
/// slices, so the inner loop over x is simple indexing.
pub fn stretch(grid: &Grid, dt: f64, omega: &mut [Vec<f64>], u: &[Vec<f64>]) {
    stretch_ghosted(grid, dt, omega, u, None);
}

/// [`stretch`] on a slab: with `ghosts`, per velocity component the [`R`] planes below the
/// grid's and the R above it (the neighbouring processes' planes), which its differences along z
/// read instead of wrapping round the grid; without, the grid is periodic in z.
pub fn stretch_ghosted(
    grid: &Grid,
    dt: f64,
    omega: &mut [Vec<f64>],
    u: &[Vec<f64>],
    ghosts: Option<&[Vec<f64>]>,
) {
    let [nx, ny, nz] = grid.n;
    if let Some(g) = ghosts {
        assert!(
            nz >= R && g.iter().all(|c| c.len() == 2 * R * nx * ny),
            "stretch: {R} ghost planes a side of a slab of {nz}"
        );
    }
    let plane = nx * ny;
    let c = STRETCH_COEFFS.map(|c| c / grid.h);
    let (o0, rest) = omega.split_at_mut(1);
    let (o1, o2) = rest.split_at_mut(1);
    #[cfg(target_arch = "x86_64")]
    let avx2 = std::arch::is_x86_feature_detected!("avx2");
    o0[0]
        .par_chunks_mut(plane)
        .zip(o1[0].par_chunks_mut(plane))
        .zip(o2[0].par_chunks_mut(plane))
        .enumerate()
        .for_each(|(k, ((w0, w1), w2))| {
            for j in 0..ny {
                let row = |jj: usize, kk: usize| nx * (jj + ny * kk);
                let r = row(j, k);
                // Rows at y-m and y+m, z-m and z+m (m = 1..=R); on a slab, the rows beyond it
                // are the ghost planes' (below: planes 0..R, above: R..2R).
                let ry = offsets().map(|d| row(wrap(j, d, ny), k));
                let gu = [0, 1, 2].map(|a| {
                    let f = &u[a];
                    let rz = offsets().map(|d| match ghosts {
                        None => &f[row(j, wrap(k, d, nz))..][..nx],
                        Some(g) => {
                            let kk = k as isize + d;
                            if kk < 0 {
                                &g[a][row(j, (R as isize + kk) as usize)..][..nx]
                            } else if kk as usize >= nz {
                                &g[a][row(j, R + kk as usize - nz)..][..nx]
                            } else {
                                &f[row(j, kk as usize)..][..nx]
                            }
                        }
                    });
                    (&f[r..r + nx], ry.map(|o| &f[o..o + nx]), rz)
                });
                let w = [
                    &mut w0[nx * j..nx * (j + 1)],
                    &mut w1[nx * j..nx * (j + 1)],
                    &mut w2[nx * j..nx * (j + 1)],
                ];
                #[cfg(target_arch = "x86_64")]
                if avx2 {
                    // SAFETY: the CPU supports AVX2 (checked above); same arithmetic in the
                    // same order as the portable build, so bit-identical results.
                    unsafe { stretch_row_avx2(&gu, w, c, dt) };
                    continue;
                }
                stretch_row(&gu, w, c, dt);
            }
        });
}

/// The stencil's offsets as [-1, +1, -2, +2, ..., -R, +R].
fn offsets() -> [isize; 2 * R] {
    std::array::from_fn(|q| {
        let m = (q / 2 + 1) as isize;
        if q % 2 == 0 { -m } else { m }
    })
}

/// Nodes of a row whose stretching is computed together (the gradients of a block live on
/// the stack).
const BLOCK: usize = 32;

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn stretch_row_avx2(gu: &[Rows; 3], w: [&mut [f64]; 3], c: [f64; R], dt: f64) {
    stretch_row(gu, w, c, dt);
}

/// The stretching of one row of nodes along x: the interior in blocks of [`BLOCK`] nodes
/// (branch-free loops over contiguous slices), the R nodes at each end one by one with
/// wrapped x neighbours (`node`, the same sums in the same order).
#[inline(always)]
fn stretch_row(gu: &[Rows; 3], w: [&mut [f64]; 3], c: [f64; R], dt: f64) {
    let nx = w[0].len();
    let [w0, w1, w2] = w;
    // `x[q]` is the index of neighbour offsets()[q] along x.
    let node = |i: usize, x: [usize; 2 * R]| {
        let mut g = [[0.0; 3]; 3];
        for a in 0..3 {
            let (fr, fy, fz) = &gu[a];
            let (mut gx, mut gy, mut gz) = (0.0, 0.0, 0.0);
            for m in 0..R {
                gx += c[m] * (fr[x[2 * m + 1]] - fr[x[2 * m]]);
                gy += c[m] * (fy[2 * m + 1][i] - fy[2 * m][i]);
                gz += c[m] * (fz[2 * m + 1][i] - fz[2 * m][i]);
            }
            g[a] = [gx, gy, gz];
        }
        g
    };
    let step = |g: [[f64; 3]; 3], w: [f64; 3]| {
        let gw = |w: [f64; 3]| {
            [
                g[0][0] * w[0] + g[0][1] * w[1] + g[0][2] * w[2],
                g[1][0] * w[0] + g[1][1] * w[1] + g[1][2] * w[2],
                g[2][0] * w[0] + g[2][1] * w[1] + g[2][2] * w[2],
            ]
        };
        let s0 = gw(w);
        let wh = [
            w[0] + 0.5 * dt * s0[0],
            w[1] + 0.5 * dt * s0[1],
            w[2] + 0.5 * dt * s0[2],
        ];
        let s = gw(wh);
        [w[0] + dt * s[0], w[1] + dt * s[1], w[2] + dt * s[2]]
    };
    let off = offsets();
    let interior = R..nx.saturating_sub(R);
    // The interior in blocks of BLOCK nodes: the nine gradients of a block first (each a
    // plain loop over contiguous slices), then the step of each node; the same sums in the
    // same order as `node`, so the results are those of the per-node path.
    let mut i0 = interior.start;
    while i0 < interior.end {
        let len = BLOCK.min(interior.end - i0);
        let mut g = [[0.0f64; BLOCK]; 9];
        for a in 0..3 {
            let (fr, fy, fz) = &gu[a];
            let [gx, gy, gz] = g[3 * a..3 * a + 3].as_mut() else {
                unreachable!()
            };
            for m in 0..R {
                let cm = c[m];
                let xlo = &fr[i0 - m - 1..][..len];
                let xhi = &fr[i0 + m + 1..][..len];
                let (ylo, yhi) = (&fy[2 * m][i0..][..len], &fy[2 * m + 1][i0..][..len]);
                let (zlo, zhi) = (&fz[2 * m][i0..][..len], &fz[2 * m + 1][i0..][..len]);
                for q in 0..len {
                    gx[q] += cm * (xhi[q] - xlo[q]);
                    gy[q] += cm * (yhi[q] - ylo[q]);
                    gz[q] += cm * (zhi[q] - zlo[q]);
                }
            }
        }
        let (w0, w1, w2) = (
            &mut w0[i0..][..len],
            &mut w1[i0..][..len],
            &mut w2[i0..][..len],
        );
        for q in 0..len {
            let gq = [
                [g[0][q], g[1][q], g[2][q]],
                [g[3][q], g[4][q], g[5][q]],
                [g[6][q], g[7][q], g[8][q]],
            ];
            let r = step(gq, [w0[q], w1[q], w2[q]]);
            w0[q] = r[0];
            w1[q] = r[1];
            w2[q] = r[2];
        }
        i0 += len;
    }
    for i in (0..nx).filter(|i| !interior.contains(i)) {
        let g = node(i, off.map(|d| wrap(i, d, nx)));
        let r = step(g, [w0[i], w1[i], w2[i]]);
        w0[i] = r[0];
        w1[i] = r[1];
        w2[i] = r[2];
    }
}

/// A row of a velocity component and its y and z neighbour rows (in the order of [`offsets`]), as
/// slices of length `nx`.
type Rows<'a> = (&'a [f64], [&'a [f64]; 2 * R], [&'a [f64]; 2 * R]);

/// Particle transport (a fluid run); its scratch, which holds the split order a
/// checkpoint keeps, is there in every run.
#[derive(Debug, Clone, Copy, Default)]
pub struct TransportPlugin;

impl crate::schedule::Plugin for TransportPlugin {
    fn name(&self) -> &'static str {
        "transport"
    }

    fn build(&self, ctx: &mut crate::schedule::PluginContext) -> anyhow::Result<()> {
        use crate::schedule::PhysicsSet;
        let scratch = TransportScratch::new(
            ctx.world.resource::<Grid>(),
            ctx.world.get_resource::<Decomposition>(),
        );
        ctx.insert_resource(scratch);
        ctx.checkpoint_part::<TransportScratch>("transport", 1)?;
        let momentum = ctx.world.resource::<Params>().momentum_form();
        if ctx.mode().fluid() && momentum {
            let scratch = MomentumScratch::new(
                ctx.world.resource::<Grid>(),
                ctx.world.get_resource::<Decomposition>(),
            );
            ctx.insert_resource(scratch);
            ctx.add_system(PhysicsSet::Transport, "transport", momentum_transport)?;
        } else if ctx.mode().fluid() {
            ctx.add_system(PhysicsSet::Transport, "transport", transport)?;
        }
        Ok(())
    }
}
