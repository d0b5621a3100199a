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
//! occupied when ũ was made and travels with the body: evaluated instead at the nodes the
//! body covers one step later (ũ kept as a grid field), the crescent it has moved into gave
//! the excess mass the velocity of the fluid that was there, a drag that grew with V Δt / h
//! (sedimentation-2d at h = 1/64: a max fall velocity of 10.13 at Δt = 3e-3 against 11.68 at
//! Δt = 7.5e-4, now 10.92 against 11.87, the default coupling's Δt dependence). (With the plain mean of u, the
//! diffusion's ν∆u acted on the whole mass: a sphere of density 2 settled 28% slow; with an
//! explicit correction (ρ_P/ρ - 1) ν Δt ∆u the error still grew with the density, -9% at 5,
//! and a body of density 0.01 blew up.) The weight of the body's mass beyond the fluid it
//! displaces, ∫(ρ_i - ρ_P)χ_i g, is added to that velocity, a force spread over the region
//! the penalization moves rigidly. (Spread as (ρ - ⟨ρ⟩) g over χ instead, a sphere at Re ≪ 1
//! settled 11% slow at every density: the part of the rigid band outside χ took the
//! backflow of the projection into the body.)
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
//! The FFT preconditioner's iterations grow with the contrast, the V-cycle's do not: at 1e-9
//! (3D, 32³, a sphere) the FFT took 2 at density ratio 1.1, 6 at 2, 11 at 5, 36 at 0.01 and
//! about 146 at 1000. With multigrid the tank of 100 bodies under a free surface at 1:100 (64³)
//! takes 7 iterations instead of 100, its pressure system 0.10 s a step instead of 0.42 s, and
//! the tank with 1 body 3 instead of 20; dkt (density ratio 1.14) stays with the FFT (5
//! iterations; 7 and twice the time with multigrid). At 1e-7 against 1e-9: dkt (60x60x240) 5
//! against 7, the tank of 100 bodies with the FFT preconditioner 100 against 137. The quick
//! tier gives the same numbers at 1e-7 as at 1e-9 to the printed seven digits in 87 of 90 rows,
//! the other three (floating bodies) within 2e-6 of their value; at 1e-6 a floating box's
//! draft moved by 6% and the waterline by 0.07 h. (A free surface's right-hand side is mostly
//! the hydrostatic balance, so the residual relative to it must stay small to resolve the
//! dynamic part.) The warm start's residual is 0.3 to 1.3 of the right-hand side's (the
//! penalization's increment changes from step to step); extrapolating φ from the last two
//! steps did not reduce the iterations (dkt 7 and 7, the tank 137 and 139). Dot products are
//! summed row by row in a fixed order, so the result does not depend on the thread count.

use crate::base::fields::{Fields, Params, SimTime};
use crate::base::grid::{Grid, RowNeighbours, for_row, line_at};
use crate::base::params::BodyCoupling;
use crate::bodies::coupling::{ExcessMomentum, PressureState};
use crate::bodies::integrals::{BodySums, integrate_n, penalized_weight};
use crate::bodies::{Body, BodyFields, GridPatch, RigidState};
use crate::solvers::Spectral;
use crate::solvers::operators::curl_add;
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
}

impl PressureSolver {
    /// Zero state for `grid`; with `multigrid`, the Poisson solver's multigrid hierarchy too.
    pub fn new(grid: &Grid, multigrid: bool) -> Self {
        let n = grid.len();
        PressureSolver {
            poisson: VariablePoisson::new(grid, multigrid),
            src: vec![vec![0.0; n]; grid.dim],
            trial: vec![vec![0.0; n]; grid.dim],
        }
    }

    /// Iterations of the last solve.
    pub fn iterations(&self) -> usize {
        self.poisson.iterations
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

/// The pressure system.
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
) {
    let state = &mut *state;
    let dt = time.dt;
    let dim = grid.dim;
    let nx = grid.n[0];
    let h = grid.h;
    let solver = &mut *solver;
    let bf = &mut *bf;
    let rho = &bf.rho;
    // β on the faces.
    for a in 0..dim {
        let beta = &mut solver.poisson.beta[a];
        beta.par_chunks_mut(nx).enumerate().for_each(|(row, o)| {
            let rn = RowNeighbours::new(&grid, row);
            let rc = &rho[rn.c0..rn.c0 + nx];
            if a == 0 {
                for_row(nx, |i, _, ip| o[i] = 2.0 / (rc[i] + rc[ip]));
            } else {
                let up = &rho[rn.above[a - 1]..rn.above[a - 1] + nx];
                for ((v, c), p) in o.iter_mut().zip(rc).zip(up) {
                    *v = 2.0 / (c + p);
                }
            }
        });
    }
    // G = ⟨ρ_P⟩ g, the mean weight of the fluid phases, carried by the mean pressure
    // gradient (the bodies' weight beyond the fluid they displace acts on their rigid
    // velocity, `rigid_velocity`).
    let phase = &bf.rho_phase;
    let rho_mean = solver.poisson.mean(nx, phase);
    let g = params.gravity;
    let gg: [f64; 3] = std::array::from_fn(|a| g[a] * rho_mean);
    // The node part of the increment: δu_pen - Δt (u·∇)u (centred differences).
    {
        let u = &fields.u;
        let du = &bf.du;
        let inv2h = 0.5 / h;
        let src = crate::base::grid::component_ptrs(&mut solver.src);
        let three = dim == 3;
        (0..grid.len() / nx).into_par_iter().for_each(|row| {
            let rn = RowNeighbours::new(&grid, row);
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
                        line_at(&u[q], rn.below[1], nx),
                        line_at(&u[q], rn.above[1], nx),
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
    // b = ∇·(face field), face field = mean of the two nodes + the gravity term, times h²
    // (A's scaling): A φ = -h² b.
    {
        let (src, beta, phase) = (&solver.src, &solver.poisson.beta, &bf.rho_phase);
        solver
            .poisson
            .rhs
            .par_chunks_mut(nx)
            .enumerate()
            .for_each(|(row, o)| {
                let rn = RowNeighbours::new(&grid, row);
                // The face between lo and hi = lo + e_a, from the values at both nodes and β
                // on it.
                let face = |a: usize, s: [f64; 2], ph: [f64; 2], b: f64| {
                    0.5 * (s[0] + s[1]) + dt * gravity_face(ph, g[a], gg[a]) * b
                };
                let ph = line_at(phase, rn.c0, nx);
                let (s0, b0) = (line_at(&src[0], rn.c0, nx), line_at(&beta[0], rn.c0, nx));
                // Per axis 1 and 2: the source, phase and β rows of this row and of the rows
                // below and above it.
                let rows = |a: usize| {
                    let (m, p) = (rn.below[a - 1], rn.above[a - 1]);
                    (
                        [
                            line_at(&src[a], m, nx),
                            line_at(&src[a], rn.c0, nx),
                            line_at(&src[a], p, nx),
                        ],
                        [line_at(phase, m, nx), line_at(phase, p, nx)],
                        [line_at(&beta[a], m, nx), line_at(&beta[a], rn.c0, nx)],
                    )
                };
                let (s1, p1, b1) = rows(1);
                let (s2, p2, b2) = if dim == 3 { rows(2) } else { (s1, p1, b1) };
                for_row(nx, |i, im, ip| {
                    let mut div = 0.0;
                    div += face(0, [s0[i], s0[ip]], [ph[i], ph[ip]], b0[i])
                        - face(0, [s0[im], s0[i]], [ph[im], ph[i]], b0[im]);
                    div += face(1, [s1[1][i], s1[2][i]], [ph[i], p1[1][i]], b1[1][i])
                        - face(1, [s1[0][i], s1[1][i]], [p1[0][i], ph[i]], b1[0][i]);
                    if dim == 3 {
                        div += face(2, [s2[1][i], s2[2][i]], [ph[i], p2[1][i]], b2[1][i])
                            - face(2, [s2[0][i], s2[1][i]], [p2[0][i], ph[i]], b2[0][i]);
                    }
                    o[i] = -h * div;
                });
            });
    }
    let with = solver.poisson.choose();
    let (it, res) = solver
        .poisson
        .solve(&grid, &mut state.phi, &mut spectral, with, TOLERANCE);
    if it >= MAX_ITERATIONS {
        tracing::warn!(
            "pressure solve: relative residual {res:.2e} after {it} iterations (asked {TOLERANCE:.0e})"
        );
    }
    // δ = δu_pen + face-to-node mean of Δt (ρ_P g - G) β - β ∇φ (the advection is not part
    // of it: transport makes it); then ω += ∇×δ.
    {
        let (phi, beta) = (&state.phi, &solver.poisson.beta);
        let phase = &bf.rho_phase;
        let u = &fields.u;
        let trial = crate::base::grid::component_ptrs(&mut solver.trial);
        let du = crate::base::grid::component_ptrs(&mut bf.du);
        let inv_h = 1.0 / h;
        (0..grid.len() / nx).into_par_iter().for_each(|row| {
            let rn = RowNeighbours::new(&grid, row);
            // The face between lo and hi = lo + e_a, from the phase density and φ at both
            // nodes and β on it.
            let face = |a: usize, ph: [f64; 2], f: [f64; 2], b: f64| {
                (dt * gravity_face(ph, g[a], gg[a]) - (f[1] - f[0]) * inv_h) * b
            };
            let (ph, fc) = (line_at(phase, rn.c0, nx), line_at(phi, rn.c0, nx));
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
                            * (face(0, [ph[im], ph[i]], [fc[im], fc[i]], bc[im])
                                + face(0, [ph[i], ph[ip]], [fc[i], fc[ip]], bc[i]));
                        out(i, corr);
                    });
                } else {
                    let (m, p) = (rn.below[a - 1], rn.above[a - 1]);
                    let (phm, php) = (line_at(phase, m, nx), line_at(phase, p, nx));
                    let (fm, fp) = (line_at(phi, m, nx), line_at(phi, p, nx));
                    let bm = line_at(&beta[a], m, nx);
                    for i in 0..nx {
                        let corr = 0.5
                            * (face(a, [phm[i], ph[i]], [fm[i], fc[i]], bm[i])
                                + face(a, [ph[i], php[i]], [fc[i], fp[i]], bc[i]));
                        out(i, corr);
                    }
                }
            }
        });
    }
    curl_add(&grid, &bf.du, fields.omega_mut());
    // The momentum of each dynamic body's excess mass, taken over the region its
    // penalization moved this step: the body carries it to the next step's rigid velocity.
    let ldt = params.numerics.lambda * dt;
    for (body, patch, st) in &bodies {
        if !body.is_dynamic() {
            continue;
        }
        if state.excess.len() <= body.id {
            state.excess.resize(body.id + 1, None);
        }
        let (rho, phase) = (&bf.rho, &bf.rho_phase);
        // Both signs of ρ - ρ_P in one pass over the patch.
        let sides = integrate_n::<2>(
            &grid,
            patch,
            st.center,
            &solver.trial,
            &mut sums,
            |c, _, g| {
                let w = penalized_weight(ldt, c);
                [1.0, -1.0].map(|sign: f64| (sign * (rho[g] - phase[g])).max(0.0) * w)
            },
        );
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
            ctx.share_resource(|w| Spectral::new(w.resource::<Grid>()));
            ctx.share_resource(|w| BodySums::new(w.resource::<Grid>()));
            let grid = ctx.world.resource::<Grid>().clone();
            let multigrid = ctx.world.resource::<Params>().multigrid;
            ctx.insert_resource(PressureSolver::new(&grid, multigrid));
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
