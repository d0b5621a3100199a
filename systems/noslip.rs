//! # noslip: the no-slip held at the end of every step (issue 35)
//!
//! The penalization (eq. 13) makes the flow rigid inside the bodies before the particles move;
//! the diffusion that follows lets it slip again, by an amount that depends on ν Δt / h² (a
//! settling sphere's speed changed by a factor 1.8 between diffusion numbers 0.125 and 2).
//! This system restores it after the diffusion and the velocity solve, for the bodies that
//! move by Newton-Euler ([`MotionLaw::NewtonEuler`]), by solving for a force f on their rigid
//! regions W_i (the nodes inside the surface, φ_i > 0) such that
//!
//!   u + K f = V_i' + Ω_i' × r  on W_i,
//!   E_i (V_i' - V_i) = -ρ_F Σ_{W_i} f h^d,   J_E,i (Ω_i' - Ω_i) = -ρ_F Σ_{W_i} r × f h^d,
//!
//! with K f = BS(∇×(m R f)) the velocity the force makes within the implicit diffusion step
//! ([`Spectral::forcing_velocity`]: R the diffusion's resolvent, m the centred curl's transfer
//! function), E_i = (ρ_i - ρ_F) V_i + M_v,i the body's mass beyond the fluid it displaces (V_i
//! the exact volume of its shape) with its virtual mass ([`VirtualMass`], which keeps E_i
//! positive for a body lighter than the fluid; its lagged part is in the rigid velocity) and
//! J_E,i its inertia. The bodies take the reaction within the solve: with the reaction lagged a
//! step, a sphere of density 1.1 blew up. Eliminating V' and Ω' leaves
//! (W K W + W B M_E⁻¹ B^T W) f = W (ū - u) (B the rigid modes), symmetric and positive for
//! E_i > 0, solved by conjugate gradients. When every body barely moves ([`WARM_SHIFT`]) the
//! solve starts from the last step's force and stops when the slip left is below
//! [`SLIP_TOLERANCE`] of the slip the step made; otherwise it starts from zero and stops when
//! an iteration changes the force by less than [`TOLERANCE`] of the bodies' hydrodynamic
//! impulse over the step; both after at most [`MAX_ITERATIONS`]. This is the iterative
//! Brinkman penalization of Hejlesen,
//! Koumoutsakos, Leonard & Walther (J. Comput. Phys. 280, 2015) written as the linear system of
//! Gillis, Winckelmans & Chatelain (J. Comput. Phys. 347, 2017), with the bodies' recoil inside
//! it (the fictitious-domain coupling of Glowinski et al., J. Comput. Phys. 169, 2001).
//!
//! Measured (settling sphere of density 2 in a periodic box against Hasimoto, h = 1/32, 3.2
//! cells per radius; docs/numerics.md): solved to the end, U/U_H = 0.9733 / 0.9732 / 0.9738 at
//! diffusion numbers 0.125 / 0.5 / 2 (0.83 / 1.00 / 1.52 with the penalization alone), and
//! 0.9742 again at h = 1/48 and 0.9938 at 1/64 (warm-started); centred off the nodes the same
//! sphere moves at 1.0133 at h = 1/32: the staircase of rigid nodes sets the wall, within a few
//! per cent at 3.2 cells per radius depending on where the surface cuts the grid; within 0.4%
//! over band half-widths of 0.5 to 2 cells (1.17 to 0.77 before). With m = 1 (the spectral curl) it fell
//! 10% too fast at h = 1/32 and 5.6% at 1/48: a sharp forcing seen through the spectral curl
//! acts as if the wall were half a cell inside the surface. With the virtual mass, bodies
//! lighter than the fluid settle (rise) as the heavy ones: 0.994 of Hasimoto at densities
//! 0.5, 0.1, 0.01 and 0.001 (+1.3% to +6.7% with the projection they had before).

use crate::base::fields::{Fields, Params, SimTime};
use crate::base::grid::Grid;
use crate::bodies::coupling::{MotionLaw, VirtualMass};
use crate::bodies::integrals::{rigid_region, solve_inertia};
use crate::bodies::{Body, GridPatch, Hydro, Material, RigidState, ShapeVolume};
use crate::solvers::Spectral;
use bevy_ecs::prelude::*;
use glam::{DMat3, DVec3};
use rayon::prelude::*;

/// While some body moves faster than [`WARM_SHIFT`], the solve stops when the force increment
/// of an iteration is below this fraction of the bodies' hydrodynamic impulse over the step
/// (Hejlesen et al. 2015 stop at 1% of the force; CubismUP_3D at 0.2%), or after
/// [`MAX_ITERATIONS`].
pub const TOLERANCE: f64 = 1e-2;

/// When every body moves slower than [`WARM_SHIFT`], the solve is warm-started and stops when
/// the slip left on the rigid regions is below this fraction of the slip the step made (the
/// norm over their nodes): it is then solved, in about one iteration a step. A settling sphere
/// (density 2, h = 1/32, 3.2 cells per radius) moves at 0.9742 of Hasimoto so, and at 0.9733 /
/// 0.9732 / 0.9738 at diffusion numbers 0.125 / 0.5 / 2 solved to the end: the solved
/// no-slip does not depend on the time step. Stopped on the force increment after at most six
/// iterations it moved at 0.988 / 0.992 / 0.996: the step dependence of a truncated solve.
pub const SLIP_TOLERANCE: f64 = 1e-3;

/// A body whose surface moves less than this fraction of a cell over the step starts from the
/// last step's force on the nodes it keeps (a warm start, scaled by least squares so that it
/// never leaves more slip than a start from zero): the settling sphere then needs 544
/// iterations over 512 steps. A faster body starts from zero: at dkt's speeds (0.8 cells a
/// step) the last force, seen on nodes the surface has left, removed 10% of the slip at its
/// best scale.
pub const WARM_SHIFT: f64 = 0.05;

/// At most this many iterations a step. From zero, a sphere at 3.2 cells per radius and
/// ν Δt / h² of 0.125 to 2 needs 5 to 8 to meet [`TOLERANCE`], and does not meet
/// [`SLIP_TOLERANCE`] in 30 at 0.125 (the slip stalls at 1-4%; at 0.5 it reaches 0.4% in 27).
/// At ν Δt / h² well below 1 (dkt: about 0.06) the slip the transport leaves is a grid-scale
/// layer, which the operator transmits weakly (m → 0 at the Nyquist wavenumber): after six
/// iterations 20-50% of it is left, after thirty 4-9%. (The part of the slip that is a centred
/// gradient on the rigid nodes, which no force removes, is only 1% of it: removing it first
/// did not change the stall; nor did preconditioning with the inverse of m R.) Each iteration
/// costs about 1.7 FFT floors (3 forward and 3 inverse transforms and the spectral passes);
/// the flow takes each iteration's response as it comes and the vorticity of their sum at the
/// end (3 inverse transforms), so the solution is never transformed again.
pub const MAX_ITERATIONS: usize = 6;

/// The solver's scratch (allocated once) and its last iteration count. The unknowns live on
/// the rigid regions' nodes only (a compact list); the transforms see them scattered on the
/// grid.
#[derive(Resource, Debug, Clone, Default)]
pub struct NoSlip {
    /// Whether a node is already in the list (reset after each solve).
    taken: Vec<bool>,
    /// The rigid regions' nodes, body after body: grid index, position from the body's
    /// centroid.
    nodes: Vec<(usize, DVec3)>,
    /// On the nodes: the force (velocity units), the residual W(ū - u - K x) with the bodies'
    /// recoil, the search direction and the operator applied to it.
    x: Vec<DVec3>,
    r: Vec<DVec3>,
    p: Vec<DVec3>,
    ap: Vec<DVec3>,
    /// The search direction scattered on the grid (zero off the nodes), and K of it.
    p_grid: Vec<Vec<f64>>,
    kp_grid: Vec<Vec<f64>>,
    /// One real field for the vorticity of the forcing.
    scratch: Vec<f64>,
    /// The Newton-Euler bodies of this step.
    bodies: Vec<Recoil>,
    /// The last solve's force on its nodes (grid index, force): the next solve's first guess
    /// on the nodes of the bodies that barely move ([`WARM_SHIFT`]). Kept in a checkpoint.
    warm: Vec<(usize, DVec3)>,
    /// Iterations of the last solve (0 when it did not run).
    pub iterations: usize,
}

/// A checkpoint keeps the last force (the warm start's), so a restart continues as the run.
impl crate::schedule::CheckpointPart for NoSlip {
    type Part = Vec<(usize, [f64; 3])>;
    fn save_part(&self) -> Self::Part {
        self.warm.iter().map(|&(g, f)| (g, f.to_array())).collect()
    }
    fn restore_part(&mut self, part: Self::Part) {
        let n = self.taken.len();
        self.warm.clear();
        self.warm.extend(
            part.into_iter()
                .filter(|&(g, _)| g < n)
                .map(|(g, f)| (g, DVec3::from_array(f))),
        );
    }
}

/// One Newton-Euler body in the solve.
#[derive(Debug, Clone, Copy)]
struct Recoil {
    entity: Entity,
    /// Its nodes in [`NoSlip::nodes`].
    range: (usize, usize),
    /// ρ_F / E.
    inv_e: f64,
    /// J_E, the body's inertia beyond the fluid it displaces.
    j_e: DMat3,
    /// Σ p h^d and Σ r × p h^d of the current search direction over the body's region.
    p_force: DVec3,
    p_torque: DVec3,
    /// The momentum and angular momentum the fluid has taken so far, ρ_F Σ x h^d, ρ_F Σ r × x h^d.
    force: DVec3,
    torque: DVec3,
    /// Whether its surface moves less than [`WARM_SHIFT`] of a cell over the step (its nodes
    /// start from the last force).
    warm: bool,
    /// Its radius of gyration (torque over it compares with force).
    gyration: f64,
    /// The fluid's impulse on the body earlier in the step (`rigid_velocity`: the projected
    /// flow's momentum change over its rigid region) and its moment: with the no-slip's
    /// reaction, the hydrodynamic impulse of the step.
    impulse: DVec3,
    angular_impulse: DVec3,
}

impl NoSlip {
    /// Scratch for `grid`.
    pub fn new(grid: &Grid) -> Self {
        let n = grid.len();
        let field = || vec![vec![0.0; n]; grid.dim];
        NoSlip {
            taken: vec![false; n],
            nodes: Vec::with_capacity(n),
            x: Vec::with_capacity(n),
            r: Vec::with_capacity(n),
            p: Vec::with_capacity(n),
            ap: Vec::with_capacity(n),
            p_grid: field(),
            kp_grid: field(),
            scratch: vec![0.0; n],
            bodies: Vec::new(),
            warm: Vec::with_capacity(n),
            iterations: 0,
        }
    }
}

/// Σ a·b over the nodes (in order: the result does not depend on the threads).
fn dot(a: &[DVec3], b: &[DVec3]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x.dot(*y)).sum()
}

type NewtonBodies<'w, 's> = Query<
    'w,
    's,
    (
        Entity,
        &'static Body,
        &'static GridPatch,
        &'static mut RigidState,
        &'static MotionLaw,
        &'static Material,
        &'static ShapeVolume,
        &'static VirtualMass,
        &'static mut Hydro,
    ),
>;

/// The no-slip system.
#[allow(clippy::too_many_arguments)]
pub fn noslip(
    grid: Res<Grid>,
    params: Res<Params>,
    time: Res<SimTime>,
    mut fields: ResMut<Fields>,
    mut spectral: ResMut<Spectral>,
    mut ns: ResMut<NoSlip>,
    mut bodies: NewtonBodies,
) {
    let ns = &mut *ns;
    ns.iterations = 0;
    let rho_f = params.rho_fluid;
    let dim = grid.dim;
    let dv = grid.cell_volume();
    ns.bodies.clear();
    ns.nodes.clear();
    ns.r.clear();
    // The rigid regions, the slip there, and each body's recoil.
    for (entity, body, patch, state, law, mat, volume, virt, hydro) in &bodies {
        if !(*law == MotionLaw::NewtonEuler && body.is_dynamic() && !patch.is_empty()) {
            continue;
        }
        let start = ns.nodes.len();
        let mut reach = 0.0f64;
        let [dx, dy, _] = patch.dims;
        for row in 0..patch.len() / dx {
            let (b, c) = (row % dy, row / dy);
            let nodes = patch.row(&grid, b, c);
            for a in 0..dx {
                if rigid_region(patch.phi[row * dx + a]) == 0.0 {
                    continue;
                }
                // The wrapped node for the fields, its image next to the body for the arm.
                let g = nodes.index(a);
                if ns.taken[g] {
                    continue;
                }
                ns.taken[g] = true;
                let pos = patch.pos(&grid, a, b, c);
                let rv = DVec3::new(pos[0], pos[1], pos[2]) - state.centroid;
                let ubar = state.velocity + state.angular_velocity.cross(rv);
                reach = reach.max(ubar.length());
                let mut u = DVec3::ZERO;
                for q in 0..dim {
                    u[q] = fields.u[q][g];
                }
                ns.nodes.push((g, rv));
                ns.r.push(ubar - u);
            }
        }
        // E + M_v (`VirtualMass`): positive for every body.
        let e = (mat.density - rho_f) * volume.0 + virt.mass;
        let j_e = state.inertia * (e / state.volume.max(f64::MIN_POSITIVE));
        let gyration = (state.inertia.x_axis.x + state.inertia.y_axis.y + state.inertia.z_axis.z)
            .max(0.0)
            .sqrt()
            / state.volume.max(f64::MIN_POSITIVE).sqrt();
        ns.bodies.push(Recoil {
            entity,
            range: (start, ns.nodes.len()),
            inv_e: if e > 0.0 { rho_f / e } else { 0.0 },
            j_e,
            p_force: DVec3::ZERO,
            p_torque: DVec3::ZERO,
            force: DVec3::ZERO,
            torque: DVec3::ZERO,
            warm: reach * time.dt < WARM_SHIFT * grid.h,
            gyration: gyration.max(grid.h),
            impulse: hydro.force * time.dt,
            angular_impulse: hydro.torque * time.dt,
        });
    }
    if ns.nodes.is_empty() {
        return;
    }
    let m = ns.nodes.len();
    let nu_dt = params.nu * time.dt;
    let (omega, u, _) = fields.next_version_parts();
    spectral.forcing_reset();
    for c in ns.p_grid.iter_mut() {
        c.par_iter_mut().for_each(|v| *v = 0.0);
    }
    ns.ap.clear();
    ns.ap.resize(m, DVec3::ZERO);
    // The first guess: the last force on the nodes of the bodies that barely move, zero
    // elsewhere.
    ns.x.clear();
    ns.x.resize(m, DVec3::ZERO);
    let warm = warm_start(ns, dim);
    let rr_step = dot(&ns.r, &ns.r);
    let mut applied = false;
    if warm {
        // Scaled by least squares, x0 = s x_last with s = (b·A x_last)/|A x_last|²: never
        // more slip than from zero.
        ns.p.clear();
        ns.p.extend_from_slice(&ns.x);
        apply(ns, &mut spectral, nu_dt, dim, dv, rho_f);
        let (ba, aa) = (dot(&ns.r, &ns.ap), dot(&ns.ap, &ns.ap));
        let scale = if aa > 0.0 && ba > 0.0 { ba / aa } else { 0.0 };
        if scale > 0.0 {
            for l in 0..m {
                ns.x[l] *= scale;
                ns.r[l] -= scale * ns.ap[l];
            }
            for rec in ns.bodies.iter_mut() {
                rec.force = rec.p_force * (scale * rho_f);
                rec.torque = rec.p_torque * (scale * rho_f);
            }
            add_response(u, &ns.kp_grid, scale);
            spectral.forcing_accumulate(scale);
            applied = true;
        } else {
            ns.x.iter_mut().for_each(|x| *x = DVec3::ZERO);
        }
    }
    ns.p.clear();
    ns.p.extend_from_slice(&ns.r);
    let mut rr = dot(&ns.r, &ns.r);
    // Every body slow: solved to SLIP_TOLERANCE; else stopped on the force increment.
    let solved = ns.bodies.iter().all(|b| b.warm);
    // (0 when not solved: only an exact solution stops it before the force increment does.)
    let stop = if solved {
        SLIP_TOLERANCE * SLIP_TOLERANCE * rr_step
    } else {
        0.0
    };
    for it in 0..MAX_ITERATIONS {
        if rr <= stop {
            break;
        }
        // ap = W K p + W B M_E⁻¹ B^T p.
        apply(ns, &mut spectral, nu_dt, dim, dv, rho_f);
        let pap = dot(&ns.p, &ns.ap);
        if pap <= 0.0 {
            break;
        }
        let alpha = rr / pap;
        for l in 0..m {
            ns.x[l] += alpha * ns.p[l];
            ns.r[l] -= alpha * ns.ap[l];
        }
        // The flow takes α K p now (K x is never formed again), its vorticity at the end.
        add_response(u, &ns.kp_grid, alpha);
        spectral.forcing_accumulate(alpha);
        applied = true;
        ns.iterations = it + 1;
        // The momentum the fluid takes, ρ_F Σ x h^d, its moment, and their increments.
        let (mut df, mut f) = (0.0, 0.0);
        for rec in ns.bodies.iter_mut() {
            let (inc_f, inc_l) = (
                rec.p_force * (alpha * rho_f),
                rec.p_torque * (alpha * rho_f),
            );
            rec.force += inc_f;
            rec.torque += inc_l;
            df += inc_f.length() + inc_l.length() / rec.gyration;
            f += (rec.impulse - rec.force).length()
                + (rec.angular_impulse - rec.torque).length() / rec.gyration;
        }
        if !solved && df <= TOLERANCE * f {
            break;
        }
        let rr_new = dot(&ns.r, &ns.r);
        let beta = rr_new / rr;
        rr = rr_new;
        for l in 0..m {
            ns.p[l] = ns.r[l] + beta * ns.p[l];
        }
    }
    for &(g, _) in &ns.nodes {
        ns.taken[g] = false;
    }
    // The next step's first guess.
    ns.warm.clear();
    ns.warm
        .extend(ns.nodes.iter().zip(&ns.x).map(|(&(g, _), &x)| (g, x)));
    if !applied {
        return;
    }
    // The vorticity of the force the flow took; the bodies take the reaction.
    spectral.forcing_vorticity_add(omega, &mut ns.scratch);
    for rec in &ns.bodies {
        let Ok((_, _, _, mut state, _, _, _, _, _)) = bodies.get_mut(rec.entity) else {
            continue;
        };
        // rec.force = ρ_F Σ W x h^d: the momentum the fluid took. (The body's reported force
        // is set from its motion by `rigid_update`.)
        state.velocity -= rec.force * (rec.inv_e / rho_f);
        state.angular_velocity -= solve_inertia(dim, rec.j_e, rec.torque);
    }
}

/// Puts the last force into `ns.x` on the nodes of the bodies marked warm (`ns.x` is zero on
/// entry and `ns.p_grid` zero on entry and exit); whether any node got a guess.
fn warm_start(ns: &mut NoSlip, dim: usize) -> bool {
    if !ns.bodies.iter().any(|b| b.warm) || ns.warm.is_empty() {
        return false;
    }
    for &(g, f) in &ns.warm {
        for q in 0..dim {
            ns.p_grid[q][g] = f[q];
        }
    }
    let mut any = false;
    for rec in ns.bodies.iter().filter(|b| b.warm) {
        let (lo, hi) = rec.range;
        for (&(g, _), x) in ns.nodes[lo..hi].iter().zip(&mut ns.x[lo..hi]) {
            for q in 0..dim {
                x[q] = ns.p_grid[q][g];
            }
            any |= *x != DVec3::ZERO;
        }
    }
    for &(g, _) in &ns.warm {
        for q in 0..dim {
            ns.p_grid[q][g] = 0.0;
        }
    }
    any
}

/// u += α K p over the whole grid.
fn add_response(u: &mut [Vec<f64>], kp: &[Vec<f64>], alpha: f64) {
    for (uc, kc) in u.iter_mut().zip(kp) {
        uc.par_iter_mut()
            .zip(kc.par_iter())
            .for_each(|(u, k)| *u += alpha * k);
    }
}

/// ap = W K p + W B M_E⁻¹ B^T p for the search direction `ns.p` (K p is left in
/// `ns.kp_grid`, each body's Σ p h^d and Σ r × p h^d in its `p_force`, `p_torque`).
fn apply(ns: &mut NoSlip, spectral: &mut Spectral, nu_dt: f64, dim: usize, dv: f64, rho_f: f64) {
    for (&(g, _), p) in ns.nodes.iter().zip(&ns.p) {
        for q in 0..dim {
            ns.p_grid[q][g] = p[q];
        }
    }
    spectral.forcing_velocity(&ns.p_grid, nu_dt, &mut ns.kp_grid);
    for (&(g, _), ap) in ns.nodes.iter().zip(ns.ap.iter_mut()) {
        let mut v = DVec3::ZERO;
        for q in 0..dim {
            v[q] = ns.kp_grid[q][g];
        }
        *ap = v;
    }
    for rec in ns.bodies.iter_mut() {
        let (lo, hi) = rec.range;
        let (mut pf, mut pl) = (DVec3::ZERO, DVec3::ZERO);
        for (&(_, rv), p) in ns.nodes[lo..hi].iter().zip(&ns.p[lo..hi]) {
            pf += *p * dv;
            pl += rv.cross(*p * dv);
        }
        (rec.p_force, rec.p_torque) = (pf, pl);
        let (dvel, dspin) = (pf * rec.inv_e, solve_inertia(dim, rec.j_e, pl * rho_f));
        for (&(_, rv), ap) in ns.nodes[lo..hi].iter().zip(&mut ns.ap[lo..hi]) {
            let add = dvel + dspin.cross(rv);
            for q in 0..dim {
                ap[q] += add[q];
            }
        }
    }
}

/// The no-slip held at the end of the step for the bodies moving by Newton-Euler: runs after
/// the velocity solve when the bodies are coupled by the pressure projection without a free
/// surface (the only runs with Newton-Euler bodies).
#[derive(Debug, Clone, Copy, Default)]
pub struct NoSlipPlugin;

impl crate::schedule::Plugin for NoSlipPlugin {
    fn name(&self) -> &'static str {
        "noslip"
    }

    fn build(&self, ctx: &mut crate::schedule::PluginContext) -> anyhow::Result<()> {
        use crate::base::params::BodyCoupling;
        use crate::schedule::PhysicsSet;
        let p = ctx.params();
        if !(ctx.mode().fluid()
            && ctx.mode().has_bodies()
            && p.numerics.body_coupling == BodyCoupling::Pressure
            && !p.free_surface)
        {
            return Ok(());
        }
        ctx.share_resource(|w| NoSlip::new(w.resource::<Grid>()));
        ctx.share_resource(|w| Spectral::new(w.resource::<Grid>()));
        ctx.add_startup_system_in(
            PhysicsSet::NoSlip,
            "noslip_init",
            |mut s: ResMut<Spectral>| s.reserve_forcing(),
        )?;
        ctx.add_system(PhysicsSet::NoSlip, "noslip", noslip)?;
        ctx.checkpoint_part::<NoSlip>("noslip", 1)?;
        Ok(())
    }
}
