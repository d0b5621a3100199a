//! # pressure: the variable-density pressure projection (paper eqs. 14 and 16)
//!
//! The default body coupling (`numerics.body_coupling: Pressure`); see `BodyCoupling` for what
//! it measures today and issue 16 for what is still wrong.
//!
//! The momentum equation of the one flow that fills the box, bodies included, is
//! ρ Du/Dt = -∇p + μ∆u + ρ g + f_pen. Its curl, divided by ρ, is the vorticity equation with
//! the baroclinic term of eq. (14), ∂ω/∂t = … + ∇×(-∇p/ρ) = … + (∇ρ/ρ²) × ∇p, with p from the
//! divergence of the momentum equation (eq. 16).
//!
//! The transport and diffusion systems and the Biot-Savart solve carry the flow as if its
//! density were uniform: together they make u + Δt P(-(u·∇)u + ν∆u), with P the
//! constant-density projection. This system adds what a density ρ changes, P_ρ being the
//! projection of the density ρ, δu_pen the velocity change of this step's implicit
//! penalization (eq. 13) and ρ_P the density of the fluid phases alone:
//!
//! ∇·(β∇φ) = ∇·(δu_pen + Δt (ρ_P g - G) β - Δt (u·∇)u),  β = 1/ρ,
//! ω ← ω + ∇×(δu_pen + Δt (ρ_P g - G) β - β∇φ)
//!
//! (φ = Δt p; the advection is in the source but not in the increment: transport makes it).
//! P_ρ conserves the momentum ∫ρu, so a body takes its added mass from the same solve at any
//! density ratio.
//!
//! The bodies (`rigid_velocity`): a body's momentum is ∫ρ_P w u + P_e over the region w its
//! penalization moves, where u is the flow's velocity now and P_e = ∫(ρ - ρ_P) w ũ the
//! momentum of the body's mass beyond the fluid's at the end of the last step here, ũ being
//! the velocity this system leaves before transport and diffusion (`PressureState::excess`,
//! per unit of that mass, and the same for the angular momentum): the body's excess mass
//! keeps the velocity the projection gave it, and the flow's change since then (transport,
//! diffusion, the velocity solve) acts on the fluid's share. That is the viscous force of a
//! fluid of dynamic viscosity ρ_P ν on the body. P_e is taken over the region the body
//! occupied when ũ was made and travels with the body. The weight of the body's mass beyond
//! the fluid it displaces, ∫(ρ_i - ρ_P)χ_i g, is added to that velocity, a force spread over
//! the region the penalization moves rigidly.
//!
//! Walls with a free surface: the static bodies are held at rest by the penalization before
//! this projection (δu_pen), but as fluid of the phases' density inside it they would move
//! again, and in a box whose gas is a thousandth of the liquid's density the walls' fluid falls
//! through the gas each step, and the gas's compensating velocity, Biot-Savart's zero mean
//! applied, reaches the liquid: one step of a collapsing water column at 1:100 gave the liquid
//! 40 times the kinetic energy of a free fall (issue 34). So with a free surface the projection
//! sees the walls with the density ρ (1 + λΔt χ_s) = ρ / (1 - w_s), w_s the weight with which
//! the penalization holds them (`rigid_walls`): what the penalization holds, the projection
//! cannot move, and the face coefficient falls to zero across a wall (no flux through it).
//!
//! The hydrostatic part of p is not periodic: p = G·x + p' with G = ⟨ρ_P⟩ g, the mean weight
//! of the fluid phases, carried by the mean pressure gradient. Only p' is solved for.
//!
//! Discretisation: ρ at the nodes; β on the faces between two nodes, 1/ρ̄ with ρ̄ the mean of
//! the two; the divergence of a node field is taken of its face averages (the centred
//! difference), the operator ∇·(β∇) is the compact 5/7-point one and ∇φ is differenced on the
//! faces and averaged back to the nodes. The gravity term is evaluated on the faces with the
//! same β, so that a fluid at rest whose density varies along g alone has exactly the
//! hydrostatic face gradient and makes no vorticity.
//!
//! Solver (`solvers::variable_poisson`): conjugate gradients on -∇·(β∇), warm-started from
//! the last step's φ, to a relative residual of 1e-7, preconditioned by the inverse of the
//! constant-coefficient 5/7-point Laplacian (one real FFT pair, exact when ρ is uniform) where
//! max β / min β < 5, else by one multigrid V-cycle (`solvers::multigrid`; the hierarchy is
//! built only for a scene whose fluid phases and moving bodies differ that much in density).
//! Dot products are summed row by row in a fixed order, so the result does not depend on the
//! thread count.
//!
//! The step (`pressure`), in named steps: β on the faces (`face_beta`), G (`face_gravity`),
//! the node part of the source (`node_increment`), its divergence (`divergence`), φ
//! (`solve_phi`), the projected increment and ũ (`project`), its curl added to ω, and the
//! bodies' excess momentum (`excess_momentum`).
//!
//! The measurements behind these choices (where P_e and the excess weight are taken, the
//! preconditioners' iterations, the tolerance) are in docs/numerics.md, section "The pressure
//! projection's measurements".

use crate::base::fields::{Fields, Params, SimTime};
use crate::base::grid::{Grid, RowNeighbours, for_row, line_at};
use crate::base::params::BodyCoupling;
use crate::bodies::coupling::{ExcessMomentum, PressureState};
use crate::bodies::integrals::{BodySums, integrate_n, penalized_weight};
use crate::bodies::{Body, BodyFields, GridPatch, RigidState};
use crate::parallel::halo::z_line;
use crate::parallel::{Decomposition, Halo, RowSums, global_max};
use crate::solvers::Spectral;
use crate::solvers::operators::{CurlHalo, curl_add};
use crate::solvers::variable_poisson::{MAX_ITERATIONS, VariablePoisson};
use bevy_ecs::prelude::*;
use rayon::prelude::*;

/// Relative residual at which the pressure solve stops.
pub const TOLERANCE: f64 = 1e-7;

/// The pressure solver's scratch: the variable-coefficient Poisson solver (face coefficients,
/// conjugate-gradient vectors, multigrid hierarchy) and the increments, allocated once.
#[derive(Resource, Debug, Clone)]
pub struct PressureSolver {
    /// The solve of ∇·(β∇φ) = ∇·(…); its last iterations and residual.
    pub poisson: VariablePoisson,
    /// The velocity increment to project, per node and component (scratch).
    src: Vec<Vec<f64>>,
    /// ũ, the velocity the step ends with before transport and diffusion (scratch).
    trial: Vec<Vec<f64>>,
    /// With a free surface: the density the projection sees, ρ (1 + λΔt χ_s) with χ_s the
    /// walls' (static bodies') characteristic function (scratch; empty otherwise).
    rigid_rho: Vec<f64>,
    /// In momentum form: the reduced gravity's potential g·x - c per node (scratch; empty
    /// otherwise).
    potential: Vec<f64>,
    /// Per-row partial sums of the potential's interface mean: the weighted potential's for
    /// every row, then the weights' (scratch).
    potential_partial: Vec<f64>,
    /// The sums of those partials over the whole grid.
    potential_sums: RowSums,
    /// On several processes: one ghost plane a side of three fields, for the differences
    /// along z.
    halo: Option<Halo>,
    /// The curl's halo.
    curl_halo: CurlHalo,
}

impl PressureSolver {
    /// Zero state for `grid`; with `multigrid`, the Poisson solver's multigrid hierarchy too.
    pub fn new(
        grid: &Grid,
        multigrid: bool,
        rigid_walls: bool,
        momentum: bool,
        split: Option<&Decomposition>,
    ) -> Self {
        let n = grid.len();
        PressureSolver {
            halo: split.map(|d| Halo::new(grid, d, 1, 3)),
            curl_halo: CurlHalo::of_grid(grid, split),
            poisson: VariablePoisson::new(grid, multigrid, split),
            src: vec![vec![0.0; n]; grid.dim],
            trial: vec![vec![0.0; n]; grid.dim],
            rigid_rho: if rigid_walls {
                vec![0.0; n]
            } else {
                Vec::new()
            },
            potential: if momentum { vec![0.0; n] } else { Vec::new() },
            potential_partial: if momentum {
                vec![0.0; 2 * (n / grid.n[0])]
            } else {
                Vec::new()
            },
            potential_sums: RowSums::new(grid, split),
        }
    }

    /// Iterations of the last solve.
    pub fn iterations(&self) -> usize {
        self.poisson.iterations
    }

    /// In momentum form, the reduced gravity's potential g·x - c of the last solve per node
    /// (0 inside the walls; empty otherwise): the pressure there is p = φ/Δt + ρ_P (g·x - c),
    /// φ = `PressureState::phi` and Δt that solve's step.
    pub fn reduced_potential(&self) -> &[f64] {
        &self.potential
    }
}

/// The gravity force density on the face between nodes `lo` and `hi = lo + e_a`,
/// (ρ_P g - G)_a, with ρ_P the mean of the two nodes' phase densities `phase` and `g`, `gg`
/// the a-components of g and G; times the face's β it
/// is an acceleration (the same β as the operator's, so a fluid whose density varies along g
/// alone is exactly hydrostatic).
#[inline]
fn gravity_face(phase: [f64; 2], g: f64, gg: f64) -> f64 {
    0.5 * (phase[0] + phase[1]) * g - gg
}

/// The gravity of a step, for [`FaceGravity::impulse`]: g, G = ⟨ρ_P⟩ g and Δt, or the
/// reduced form.
#[derive(Debug, Clone, Copy)]
struct FaceGravity {
    /// The step's Δt.
    dt: f64,
    /// The acceleration of gravity g.
    g: [f64; 3],
    /// G = ⟨ρ_P⟩ g, the mean pressure gradient.
    gg: [f64; 3],
    /// The reduced form (momentum form): the force density -(g·x - c) ∇ρ_P on the faces, with
    /// g·x - c the node field `PressureSolver::potential` (see the module doc); 1/h then.
    reduced: Option<f64>,
}

impl FaceGravity {
    /// The gravity impulse on the face between nodes `lo` and `hi = lo + e_a` of phase densities
    /// `phase` and potentials `pot` (the reduced form's g·x - c; unused otherwise):
    /// Δt (ρ_P g - G)_a ([`gravity_face`] times Δt), or in the reduced form
    /// -Δt (pot_lo + pot_hi)/2 (ρ_P,hi - ρ_P,lo)/h.
    #[inline]
    fn impulse(&self, a: usize, phase: [f64; 2], pot: [f64; 2]) -> f64 {
        match self.reduced {
            Some(inv_h) => -self.dt * 0.5 * (pot[0] + pot[1]) * (phase[1] - phase[0]) * inv_h,
            None => self.dt * gravity_face(phase, self.g[a], self.gg[a]),
        }
    }
}

/// The pressure system: the projection ∇·(β∇φ) = ∇·(δu_pen + Δt (ρ_P g - G) β - Δt (u·∇)u),
/// ω ← ω + ∇×(δu_pen + Δt (ρ_P g - G) β - β∇φ) (eqs. 14 and 16), then each dynamic body's
/// excess momentum P_e = ∫(ρ - ρ_P) w ũ.
#[allow(clippy::too_many_arguments)]
pub fn pressure(
    grid: Res<Grid>,
    params: Res<Params>,
    time: Res<SimTime>,
    mut fields: ResMut<Fields>,
    mut bf: ResMut<BodyFields>,
    mut solver: ResMut<PressureSolver>,
    mut state: ResMut<PressureState>,
    mut spectral: ResMut<Spectral>,
    mut sums: ResMut<BodySums>,
    bodies: Query<(&Body, &GridPatch, &RigidState)>,
    split: Option<Res<Decomposition>>,
) {
    let (solver, bf, state) = (&mut *solver, &mut *bf, &mut *state);
    let dt = time.dt;
    let ldt = params.numerics.lambda * dt;
    if solver.rigid_rho.is_empty() {
        face_beta(
            &grid,
            &bf.rho,
            &mut solver.poisson.beta,
            solver.halo.as_mut(),
        );
    } else {
        rigid_walls(&grid, &bodies, &bf.rho, ldt, &mut solver.rigid_rho);
        face_beta(
            &grid,
            &solver.rigid_rho,
            &mut solver.poisson.beta,
            solver.halo.as_mut(),
        );
    }
    solver.poisson.fill_beta_halo(&grid);
    let momentum = params.momentum_form();
    let mut gravity = face_gravity(
        &grid,
        &mut solver.poisson,
        &bf.rho_phase,
        params.gravity,
        dt,
    );
    if momentum {
        gravity.reduced = Some(1.0 / grid.h);
        let split = split.as_deref();
        reduced_potential(&grid, &bodies, &bf.rho_phase, params.gravity, split, solver);
        // The whole velocity is projected: it is carried, not made divergence-free by a
        // velocity solve.
        for (s, u) in solver.src.iter_mut().zip(&fields.u) {
            s.par_chunks_mut(4096)
                .zip(u.par_chunks(4096))
                .for_each(|(s, u)| s.copy_from_slice(u));
        }
    } else {
        node_increment(
            &grid,
            &fields.u,
            &bf.du,
            dt,
            &mut solver.src,
            solver.halo.as_mut(),
        );
    }
    divergence(&grid, solver, &bf.rho_phase, gravity);
    solve_phi(&grid, &mut solver.poisson, &mut state.phi, &mut spectral);
    project(&grid, solver, &state.phi, bf, &fields.u, gravity);
    if momentum {
        for (u, t) in fields.u.iter_mut().zip(&solver.trial) {
            u.par_chunks_mut(4096)
                .zip(t.par_chunks(4096))
                .for_each(|(u, t)| u.copy_from_slice(t));
        }
    } else {
        curl_add(&grid, &bf.du, fields.omega_mut(), solver.curl_halo.get());
    }
    excess_momentum(&grid, &bodies, bf, &solver.trial, &mut sums, state, ldt);
}

/// The reduced form's potential g·x - c at the nodes, into `solver.potential`: c is the mean
/// of g·x over the interface (weighted by (ρ_P - min ρ_P)(max ρ_P - ρ_P), which vanishes away
/// from it), so the potential is small where ∇ρ_P is not; inside the walls (static bodies,
/// χ_s > 0) it is 0, so the periodic seam that runs through them makes no force.
fn reduced_potential(
    grid: &Grid,
    bodies: &Query<(&Body, &GridPatch, &RigidState)>,
    phase: &[f64],
    g: [f64; 3],
    split: Option<&Decomposition>,
    solver: &mut PressureSolver,
) {
    let (nx, ny) = (grid.n[0], grid.n[1]);
    let (lo, hi) = phase
        .par_iter()
        .fold(
            || (f64::INFINITY, f64::NEG_INFINITY),
            |(a, b), &r| (a.min(r), b.max(r)),
        )
        .reduce(
            || (f64::INFINITY, f64::NEG_INFINITY),
            |(a, b), (c, d)| (a.min(c), b.max(d)),
        );
    let (lo, hi) = (-global_max(split, -lo), global_max(split, hi));
    let gx = |row: usize, i: usize| {
        let x = grid.pos(i, row % ny, row / ny);
        g[0] * x[0] + g[1] * x[1] + g[2] * x[2]
    };
    // Per row: Σ w g·x and Σ w, summed in row order afterwards.
    let pot = &mut solver.potential;
    let rows = pot.len() / nx;
    let (num_p, den_p) = solver.potential_partial.split_at_mut(rows);
    pot.par_chunks_mut(nx)
        .zip(num_p.par_iter_mut().zip(den_p.par_iter_mut()))
        .enumerate()
        .for_each(|(row, (o, (num, den)))| {
            let ph = &phase[row * nx..(row + 1) * nx];
            let mut sw = [0.0; 2];
            for i in 0..nx {
                let w = (ph[i] - lo) * (hi - ph[i]);
                let v = gx(row, i);
                o[i] = v;
                sw[0] += w * v;
                sw[1] += w;
            }
            (*num, *den) = (sw[0], sw[1]);
        });
    let num = solver.potential_sums.total(num_p);
    let den = solver.potential_sums.total(den_p);
    let c = if den > 0.0 { num / den } else { 0.0 };
    pot.par_iter_mut().for_each(|v| *v -= c);
    for (body, patch, _) in bodies {
        if !body.is_static() || patch.is_empty() {
            continue;
        }
        let dx = patch.dims[0];
        let dy = patch.dims[1];
        let o = crate::base::grid::SyncPtr(pot.as_mut_ptr());
        (0..patch.len() / dx).into_par_iter().for_each(|r| {
            let (b, c) = (r % dy, r / dy);
            if !patch.holds(grid, c) {
                return;
            }
            let nodes = patch.row(grid, b, c);
            for a in 0..dx {
                if patch.chi[r * dx + a] > 0.0 {
                    let g = nodes.index(a);
                    // SAFETY: distinct patch nodes map to distinct grid nodes.
                    unsafe { o.write(g, 0.0) };
                }
            }
        });
    }
}

/// The density the projection sees with a free surface: ρ (1 + λΔt χ_s) = ρ / (1 - w_s) at
/// the nodes of the walls (static bodies), w_s = λΔt χ_s / (1 + λΔt χ_s) being the weight with
/// which the penalization holds them at rest (the `penalized_weight` of their χ_s), into `out`.
/// The projection then cannot move what the penalization holds, and its face coefficient
/// falls to zero across a wall: a Neumann condition at the wall instead of a wall of fluid.
fn rigid_walls(
    grid: &Grid,
    bodies: &Query<(&Body, &GridPatch, &RigidState)>,
    rho: &[f64],
    ldt: f64,
    out: &mut [f64],
) {
    out.par_chunks_mut(4096)
        .zip(rho.par_chunks(4096))
        .for_each(|(o, r)| o.copy_from_slice(r));
    for (body, patch, _) in bodies {
        if !body.is_static() || patch.is_empty() {
            continue;
        }
        let dx = patch.dims[0];
        let dy = patch.dims[1];
        let o = crate::base::grid::SyncPtr(out.as_mut_ptr());
        (0..patch.len() / dx).into_par_iter().for_each(|r| {
            let (b, c) = (r % dy, r / dy);
            if !patch.holds(grid, c) {
                return;
            }
            let nodes = patch.row(grid, b, c);
            for a in 0..dx {
                let chi = patch.chi[r * dx + a];
                if chi > 0.0 {
                    let g = nodes.index(a);
                    // SAFETY: distinct patch nodes map to distinct grid nodes.
                    unsafe { o.write(g, o.read(g) * (1.0 + ldt * chi)) };
                }
            }
        });
    }
}

/// β on the faces: β_a = 2 / (ρ_lo + ρ_hi) on the face between nodes `lo` and
/// `hi = lo + e_a`, stored at `lo`.
fn face_beta(grid: &Grid, rho: &[f64], beta: &mut [Vec<f64>], halo: Option<&mut Halo>) {
    let nx = grid.n[0];
    let halo = halo.map(|h| {
        if grid.dim == 3 {
            h.fill_one(0, rho);
        }
        &*h
    });
    for (a, beta) in beta.iter_mut().enumerate().take(grid.dim) {
        beta.par_chunks_mut(nx).enumerate().for_each(|(row, o)| {
            let rn = RowNeighbours::new(grid, row);
            let rc = &rho[rn.c0..rn.c0 + nx];
            if a == 0 {
                for_row(nx, |i, _, ip| o[i] = 2.0 / (rc[i] + rc[ip]));
            } else {
                let up = if a == 2 {
                    z_line(grid, rho, halo, 0, row, 1)
                } else {
                    &rho[rn.above[0]..rn.above[0] + nx]
                };
                for ((v, c), p) in o.iter_mut().zip(rc).zip(up) {
                    *v = 2.0 / (c + p);
                }
            }
        });
    }
}

/// G = ⟨ρ_P⟩ g, the mean weight of the fluid phases `phase`, carried by the mean pressure
/// gradient (the bodies' weight beyond the fluid they displace acts on their rigid velocity,
/// `rigid_velocity`); with g and Δt, the gravity of the step.
fn face_gravity(
    grid: &Grid,
    poisson: &mut VariablePoisson,
    phase: &[f64],
    g: [f64; 3],
    dt: f64,
) -> FaceGravity {
    let rho_mean = poisson.mean(grid.n[0], phase);
    let gg: [f64; 3] = std::array::from_fn(|a| g[a] * rho_mean);
    FaceGravity {
        dt,
        g,
        gg,
        reduced: None,
    }
}

/// The node part of the increment, s = δu_pen - Δt (u·∇)u (centred differences), into `src`.
fn node_increment(
    grid: &Grid,
    u: &[Vec<f64>],
    du: &[Vec<f64>],
    dt: f64,
    src: &mut [Vec<f64>],
    halo: Option<&mut Halo>,
) {
    let (dim, nx) = (grid.dim, grid.n[0]);
    let halo = halo.map(|h| {
        if dim == 3 {
            h.fill(u);
        }
        &*h
    });
    let inv2h = 0.5 / grid.h;
    let src = crate::base::grid::component_ptrs(src);
    let three = dim == 3;
    (0..grid.len() / nx).into_par_iter().for_each(|row| {
        let rn = RowNeighbours::new(grid, row);
        let (u0, u1) = (line_at(&u[0], rn.c0, nx), line_at(&u[1], rn.c0, nx));
        let u2 = if three { line_at(&u[2], rn.c0, nx) } else { u0 };
        for q in 0..dim {
            // SAFETY: the row belongs to this task only.
            let out = unsafe { src[q].slice_mut(rn.c0, nx) };
            let (uq, duq) = (line_at(&u[q], rn.c0, nx), line_at(&du[q], rn.c0, nx));
            let (ym, yp) = (
                line_at(&u[q], rn.below[0], nx),
                line_at(&u[q], rn.above[0], nx),
            );
            let (zm, zp) = if three {
                (
                    z_line(grid, &u[q], halo, q, row, -1),
                    z_line(grid, &u[q], halo, q, row, 1),
                )
            } else {
                (uq, uq)
            };
            for_row(nx, |i, im, ip| {
                let mut adv = 0.0;
                adv += u0[i] * (uq[ip] - uq[im]) * inv2h;
                adv += u1[i] * (yp[i] - ym[i]) * inv2h;
                if three {
                    adv += u2[i] * (zp[i] - zm[i]) * inv2h;
                }
                out[i] = duq[i] - dt * adv;
            });
        }
    });
}

/// The right-hand side, b = ∇·(s̄ + Δt (ρ_P g - G) β) with s̄ the face mean of the two nodes'
/// `src`, times h² (A's scaling): A φ = -h² b, into the solver's `rhs`.
fn divergence(grid: &Grid, solver: &mut PressureSolver, phase: &[f64], gravity: FaceGravity) {
    let (dim, nx, h) = (grid.dim, grid.n[0], grid.h);
    // The reduced form's potential (the phase density stands in when it is not used).
    let pot: &[f64] = if solver.potential.is_empty() {
        phase
    } else {
        &solver.potential
    };
    // On a slab: the source's z component, the phase density and the potential one plane
    // beyond it (0, 1, 2), β along z's from the Poisson solver's halo.
    if let Some(h) = solver.halo.as_mut()
        && dim == 3
    {
        h.fill(&[&solver.src[2][..], phase, pot]);
    }
    let halo = solver.halo.as_ref();
    let src = &solver.src;
    let (rhs, beta, beta_halo) = solver.poisson.rhs_beta();
    rhs.par_chunks_mut(nx).enumerate().for_each(|(row, o)| {
        let rn = RowNeighbours::new(grid, row);
        // The face between lo and hi = lo + e_a, from the values at both nodes and β
        // on it.
        let face = |a: usize, s: [f64; 2], ph: [f64; 2], pt: [f64; 2], b: f64| {
            0.5 * (s[0] + s[1]) + gravity.impulse(a, ph, pt) * b
        };
        let ph = line_at(phase, rn.c0, nx);
        let pc = line_at(pot, rn.c0, nx);
        let (s0, b0) = (line_at(&src[0], rn.c0, nx), line_at(&beta[0], rn.c0, nx));
        // Per axis 1 and 2: the source, phase, potential and β rows of this row and of the
        // rows below and above it.
        let rows = |a: usize| {
            if a == 2 {
                return (
                    [
                        z_line(grid, &src[2], halo, 0, row, -1),
                        line_at(&src[2], rn.c0, nx),
                        z_line(grid, &src[2], halo, 0, row, 1),
                    ],
                    [
                        z_line(grid, phase, halo, 1, row, -1),
                        z_line(grid, phase, halo, 1, row, 1),
                    ],
                    [
                        z_line(grid, pot, halo, 2, row, -1),
                        z_line(grid, pot, halo, 2, row, 1),
                    ],
                    [
                        z_line(grid, &beta[2], beta_halo, 1, row, -1),
                        line_at(&beta[2], rn.c0, nx),
                    ],
                );
            }
            let (m, p) = (rn.below[a - 1], rn.above[a - 1]);
            (
                [
                    line_at(&src[a], m, nx),
                    line_at(&src[a], rn.c0, nx),
                    line_at(&src[a], p, nx),
                ],
                [line_at(phase, m, nx), line_at(phase, p, nx)],
                [line_at(pot, m, nx), line_at(pot, p, nx)],
                [line_at(&beta[a], m, nx), line_at(&beta[a], rn.c0, nx)],
            )
        };
        let (s1, p1, q1, b1) = rows(1);
        let (s2, p2, q2, b2) = if dim == 3 { rows(2) } else { (s1, p1, q1, b1) };
        for_row(nx, |i, im, ip| {
            let mut div = 0.0;
            div += face(0, [s0[i], s0[ip]], [ph[i], ph[ip]], [pc[i], pc[ip]], b0[i])
                - face(0, [s0[im], s0[i]], [ph[im], ph[i]], [pc[im], pc[i]], b0[im]);
            div += face(
                1,
                [s1[1][i], s1[2][i]],
                [ph[i], p1[1][i]],
                [pc[i], q1[1][i]],
                b1[1][i],
            ) - face(
                1,
                [s1[0][i], s1[1][i]],
                [p1[0][i], ph[i]],
                [q1[0][i], pc[i]],
                b1[0][i],
            );
            if dim == 3 {
                div += face(
                    2,
                    [s2[1][i], s2[2][i]],
                    [ph[i], p2[1][i]],
                    [pc[i], q2[1][i]],
                    b2[1][i],
                ) - face(
                    2,
                    [s2[0][i], s2[1][i]],
                    [p2[0][i], ph[i]],
                    [q2[0][i], pc[i]],
                    b2[0][i],
                );
            }
            o[i] = -h * div;
        });
    });
}

/// φ = Δt p' from -∇·(β∇φ) = -b (conjugate gradients to [`TOLERANCE`], warm-started from
/// the last step's `phi`, preconditioned as [`VariablePoisson::choose`] says); warns when it
/// stops at [`MAX_ITERATIONS`].
fn solve_phi(grid: &Grid, poisson: &mut VariablePoisson, phi: &mut [f64], spectral: &mut Spectral) {
    let with = poisson.choose();
    let (it, res) = poisson.solve(grid, phi, spectral, with, TOLERANCE);
    if it >= MAX_ITERATIONS {
        tracing::warn!(
            "pressure solve: relative residual {res:.2e} after {it} iterations (asked {TOLERANCE:.0e})"
        );
    }
}

/// The projected increment δ = δu_pen + c, c the face-to-node mean of Δt (ρ_P g - G) β - β∇φ
/// (the advection is not part of it: transport makes it): c is added to the bodies' `du`
/// (which holds δu_pen), and ũ = u + c written to the solver's `trial`.
fn project(
    grid: &Grid,
    solver: &mut PressureSolver,
    phi: &[f64],
    bf: &mut BodyFields,
    u: &[Vec<f64>],
    gravity: FaceGravity,
) {
    let (dim, nx) = (grid.dim, grid.n[0]);
    let phase = &bf.rho_phase;
    let pot: &[f64] = if solver.potential.is_empty() {
        phase
    } else {
        &solver.potential
    };
    // On a slab: the phase density, the potential and φ one plane beyond it (0, 1, 2), β
    // along z's from the Poisson solver's halo.
    if let Some(h) = solver.halo.as_mut()
        && dim == 3
    {
        h.fill(&[phase, pot, phi]);
    }
    let halo = solver.halo.as_ref();
    let beta_halo = solver.poisson.beta_halo();
    let beta = &solver.poisson.beta;
    let trial = crate::base::grid::component_ptrs(&mut solver.trial);
    let du = crate::base::grid::component_ptrs(&mut bf.du);
    let inv_h = 1.0 / grid.h;
    (0..grid.len() / nx).into_par_iter().for_each(|row| {
        let rn = RowNeighbours::new(grid, row);
        // The face between lo and hi = lo + e_a, from the phase density and φ at both
        // nodes and β on it.
        let face = |a: usize, ph: [f64; 2], pt: [f64; 2], f: [f64; 2], b: f64| {
            (gravity.impulse(a, ph, pt) - (f[1] - f[0]) * inv_h) * b
        };
        let (ph, fc) = (line_at(phase, rn.c0, nx), line_at(phi, rn.c0, nx));
        let pc = line_at(pot, rn.c0, nx);
        for a in 0..dim {
            let (ua, bc) = (line_at(&u[a], rn.c0, nx), line_at(&beta[a], rn.c0, nx));
            // SAFETY: the row belongs to this task only.
            let (du_a, tr_a) =
                unsafe { (du[a].slice_mut(rn.c0, nx), trial[a].slice_mut(rn.c0, nx)) };
            let mut out = |i: usize, corr: f64| {
                du_a[i] += corr;
                tr_a[i] = ua[i] + corr;
            };
            if a == 0 {
                for_row(nx, |i, im, ip| {
                    let corr = 0.5
                        * (face(0, [ph[im], ph[i]], [pc[im], pc[i]], [fc[im], fc[i]], bc[im])
                            + face(0, [ph[i], ph[ip]], [pc[i], pc[ip]], [fc[i], fc[ip]], bc[i]));
                    out(i, corr);
                });
            } else {
                let (m, p) = (rn.below[a - 1], rn.above[a - 1]);
                let ((phm, php), (pm, pp), (fm, fp), bm) = if a == 2 {
                    (
                        (
                            z_line(grid, phase, halo, 0, row, -1),
                            z_line(grid, phase, halo, 0, row, 1),
                        ),
                        (
                            z_line(grid, pot, halo, 1, row, -1),
                            z_line(grid, pot, halo, 1, row, 1),
                        ),
                        (
                            z_line(grid, phi, halo, 2, row, -1),
                            z_line(grid, phi, halo, 2, row, 1),
                        ),
                        z_line(grid, &beta[2], beta_halo, 1, row, -1),
                    )
                } else {
                    (
                        (line_at(phase, m, nx), line_at(phase, p, nx)),
                        (line_at(pot, m, nx), line_at(pot, p, nx)),
                        (line_at(phi, m, nx), line_at(phi, p, nx)),
                        line_at(&beta[a], m, nx),
                    )
                };
                for i in 0..nx {
                    let corr = 0.5
                        * (face(a, [phm[i], ph[i]], [pm[i], pc[i]], [fm[i], fc[i]], bm[i])
                            + face(a, [ph[i], php[i]], [pc[i], pp[i]], [fc[i], fp[i]], bc[i]));
                    out(i, corr);
                }
            }
        }
    });
}

/// The momentum of each dynamic body's excess mass per unit of that mass,
/// P_e / ∫(ρ - ρ_P) w = ∫(ρ - ρ_P) w ũ / ∫(ρ - ρ_P) w (and the same for the angular
/// momentum), split by the sign of ρ - ρ_P and taken over the region its penalization moved
/// this step (weight w from `ldt` = λΔt): the body carries it to the next step's rigid
/// velocity, in `state.excess`.
fn excess_momentum(
    grid: &Grid,
    bodies: &Query<(&Body, &GridPatch, &RigidState)>,
    bf: &BodyFields,
    trial: &[Vec<f64>],
    sums: &mut BodySums,
    state: &mut PressureState,
    ldt: f64,
) {
    for (body, patch, st) in bodies {
        if !body.is_dynamic() {
            continue;
        }
        if state.excess.len() <= body.id {
            state.excess.resize(body.id + 1, None);
        }
        let (rho, phase) = (&bf.rho, &bf.rho_phase);
        // Both signs of ρ - ρ_P in one pass over the patch.
        let sides = integrate_n::<2>(grid, patch, st.center, trial, sums, |c, _, g| {
            let w = penalized_weight(ldt, c);
            [1.0, -1.0].map(|sign: f64| (sign * (rho[g] - phase[g])).max(0.0) * w)
        });
        state.excess[body.id] = Some(sides.map(|(m, _, p, l, _)| {
            if m != 0.0 {
                ExcessMomentum {
                    velocity: p / m,
                    spin: l / m,
                }
            } else {
                ExcessMomentum::default()
            }
        }));
    }
}

/// The variable-density pressure projection (a fluid run with bodies, under
/// `body_coupling: Pressure`).
#[derive(Debug, Clone, Copy, Default)]
pub struct PressurePlugin;

impl crate::schedule::Plugin for PressurePlugin {
    fn name(&self) -> &'static str {
        "pressure"
    }

    fn build(&self, ctx: &mut crate::schedule::PluginContext) -> anyhow::Result<()> {
        use crate::schedule::PhysicsSet;
        let mode = ctx.mode();
        let coupling = ctx.world.resource::<Params>().numerics.body_coupling;
        if mode.fluid() && mode.has_bodies() && coupling == BodyCoupling::Pressure {
            ctx.share_resource(|w| {
                Spectral::of_grid(
                    w.resource::<crate::base::grid::Grid>(),
                    w.get_resource::<crate::parallel::Decomposition>(),
                )
            });
            ctx.share_resource(BodySums::of_world);
            let grid = ctx.world.resource::<Grid>().clone();
            let multigrid = ctx.world.resource::<Params>().multigrid;
            // Walls rigid in the projection need the multigrid preconditioner (a contrast of
            // λΔt); without a hierarchy (a grid that does not coarsen) they stay fluid.
            let rigid_walls = ctx.world.resource::<Params>().free_surface && multigrid;
            let momentum = ctx.world.resource::<Params>().momentum_form();
            let split = ctx
                .world
                .get_resource::<crate::parallel::Decomposition>()
                .cloned();
            ctx.insert_resource(PressureSolver::new(
                &grid,
                multigrid,
                rigid_walls,
                momentum,
                split.as_ref(),
            ));
            // One slot per body id (the bodies are spawned before the plugins are built), so
            // the step does not allocate.
            let ids = ctx
                .world
                .query::<&Body>()
                .iter(ctx.world)
                .map(|b| b.id + 1)
                .max()
                .unwrap_or(0);
            ctx.insert_resource(PressureState {
                phi: vec![0.0; grid.len()],
                excess: vec![None; ids],
            });
            ctx.checkpoint_resource::<PressureState>("pressure", 3)?;
            ctx.add_system(PhysicsSet::Pressure, "pressure", pressure)?;
        }
        Ok(())
    }
}
