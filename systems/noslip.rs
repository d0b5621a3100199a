//! # noslip: the no-slip held at the end of every step, at the bodies' surface markers
//!
//! The implicit diffusion lets the flow slip at a body's surface by an amount that depends on
//! ν Δt / h² (held by the penalization alone, a settling sphere's speed changed by a factor
//! 1.8 between diffusion numbers 0.125 and 2). This system restores the no-slip after the
//! diffusion and the velocity solve, for the bodies that move by Newton-Euler
//! ([`MotionLaw::NewtonEuler`]), at Lagrangian markers on their surfaces
//! ([`crate::bodies::markers`]: fixed in the body frame, about 1.5 h apart, a fraction of h
//! inside the surface), by solving for a force f_m at each marker X_m such that
//!
//!   J(u + K S f)(X_m) = V_i' + Ω_i' × r_m,
//!   E_i (V_i' - V_i) = -ρ_F Σ_m f_m h^d,   J_E,i (Ω_i' - Ω_i) = -ρ_F Σ_m r_m × f_m h^d,
//!
//! with S the spreading of the markers' forces to the grid and J the interpolation at the
//! markers (the same regularised delta, Roma's three-point kernel, so J = Sᵀ up to h^d), K f =
//! BS(∇×(m R f)) the velocity the force makes within the implicit diffusion step
//! ([`Spectral::forcing_velocity`]: R the diffusion's resolvent, m the centred curl's transfer
//! function), E_i = (ρ_i - ρ_F) V_i + M_v,i the body's mass beyond the fluid inside it (V_i the
//! exact volume of its shape) with its virtual mass ([`VirtualMass`], which keeps E_i positive
//! for a body lighter than the fluid) and J_E,i its inertia. The flow fills the body: the fluid
//! inside moves with it through the markers' forcing, so the body's whole inertia is
//! E_i + ρ_F V_i, and the fluid's force on it, added mass included, is implicit in the solve
//! (the direct forcing of Uhlmann, J. Comput. Phys. 209, 2005, with the recoil inside the solve
//! as in the fictitious-domain coupling of Glowinski et al., J. Comput. Phys. 169, 2001; the
//! fluid inside taken as moving rigidly, the d/dt ∫ u term of Uhlmann and of Kempe & Fröhlich,
//! J. Comput. Phys. 231, 2012, is ρ_F V_i dV_i/dt). Eliminating V' and Ω' leaves
//! (J K S + B M_E⁻¹ Bᵀ) f = ū - J u (B the rigid modes), symmetric and positive for E_i > 0.
//!
//! The last step's force is carried into this step ([`carry`]: spread at the markers' new
//! places, scaled to this step's length, its curl added before the implicit diffusion so the
//! flow takes it through the diffusion's resolvent as K does, its reaction given to the
//! bodies), so the solve here, by conjugate gradients from zero, only corrects it: integral
//! feedback, under which a steady motion satisfies the no-slip with no Δt in it. The solve
//! stops when the slip left is below [`SLIP_TOLERANCE`] of the slip the step made (or of the
//! carried force, if larger), below [`VELOCITY_TOLERANCE`] of the bodies' own velocity at the
//! markers, or after [`MAX_ITERATIONS`]; the next step carries the whole force, the correction
//! included.
//!
//! Measured (docs/numerics.md, "The no-slip at surface markers"): a sphere of density 2
//! settling in a periodic box at 3.2 to 6.4 cells per radius moves at 0.989-1.005 of
//! Hasimoto's velocity over offsets against the grid, and within 0.4% over diffusion numbers
//! 0.125 to 2; held on the staircase of nodes inside the surface it moved at 0.974-1.007
//! depending on the offset. dkt (two spheres of 5 cells in radius) takes a median 3 iterations
//! a step.

use crate::base::fields::{Fields, Params, SimTime};
use crate::base::grid::Grid;
use crate::bodies::coupling::{MotionLaw, VirtualMass};
use crate::bodies::integrals::solve_inertia;
use crate::bodies::markers::{Markers, Stencil};
use crate::bodies::{Body, GridPatch, Material, RigidState, ShapeVolume};
use crate::parallel::{Comm, Decomposition};
use crate::solvers::Spectral;
use crate::solvers::operators::CurlHalo;
use bevy_ecs::prelude::*;
use glam::{DMat3, DVec3};
use rayon::prelude::*;
use std::sync::Arc;

/// The solve stops when the slip left at the markers is below this fraction of the slip the
/// step made (the norm over all markers, and of the carried forcing when it is larger) ...
pub const SLIP_TOLERANCE: f64 = 1e-3;

/// ... or below this fraction of the bodies' own velocity at the markers (the norm over all
/// markers of V + Ω × r, with the recoil taken so far), whichever stops it first. The slip
/// left is not lost: the next step carries this step's whole force and corrects it again
/// (integral feedback), so a steady motion converges to the no-slip whatever this tolerance;
/// it bounds the error of a transient, a slip of 0.5% of the body's speed for one step.
pub const VELOCITY_TOLERANCE: f64 = 5e-3;

/// At most this many iterations a step (reached only in the first steps of an impulsive start,
/// from a flow the solve has not seen). Each costs about 1.4 FFT floors (3 forward and 3
/// inverse transforms and the spectral passes); the flow takes each iteration's response as it
/// comes and the vorticity of their sum at the end (3 inverse transforms), so the solution is
/// never transformed again.
pub const MAX_ITERATIONS: usize = 30;

/// The solver's scratch (allocated before the first step) and its last iteration count.
#[derive(Resource, Debug, Clone, Default)]
pub struct NoSlip {
    /// This step's markers, body after body: the kernel's stencil and the position from the
    /// body's centroid.
    nodes: Vec<(Stencil, DVec3)>,
    /// At the markers: the force (velocity units), the residual ū - J(u + K S x) with the
    /// bodies' recoil, the search direction and the operator applied to it.
    x: Vec<DVec3>,
    r: Vec<DVec3>,
    p: Vec<DVec3>,
    ap: Vec<DVec3>,
    /// The search direction spread on the grid (zero off the stencils), and K of it.
    p_grid: Vec<Vec<f64>>,
    kp_grid: Vec<Vec<f64>>,
    /// One real field for the vorticity of the forcing.
    scratch: Vec<f64>,
    /// The Newton-Euler bodies of this step.
    bodies: Vec<Recoil>,
    /// Per body (by `Body::id`), the force each of its markers took last step: the next
    /// solve's first guess. Kept in a checkpoint.
    last: Vec<Vec<DVec3>>,
    /// This step's carried forces at the markers, body after body (the last forces scaled
    /// to this step's length), already in the flow and the bodies' velocities.
    carried: Vec<DVec3>,
    /// Iterations of the last solve (0 when it did not run).
    pub iterations: usize,
    /// On several processes: their communicator (each interpolates from its slab's nodes;
    /// the values at the markers are the sums over them, so every process holds all the
    /// markers and solves the same system), a flat buffer for those sums, and the curl's halo.
    split: Option<Arc<Comm>>,
    flat: Vec<f64>,
    flat_scratch: Vec<f64>,
    curl_halo: CurlHalo,
}

/// A checkpoint keeps the last forces (the first guess), so a restart continues as the run.
impl crate::schedule::CheckpointPart for NoSlip {
    type Part = Vec<Vec<[f64; 3]>>;
    fn save_part(&self) -> Self::Part {
        self.last
            .iter()
            .map(|b| b.iter().map(|f| f.to_array()).collect())
            .collect()
    }
    fn restore_part(&mut self, part: Self::Part) {
        self.last = part
            .into_iter()
            .map(|b| b.into_iter().map(DVec3::from_array).collect())
            .collect();
    }
}

/// One Newton-Euler body in the solve.
#[derive(Debug, Clone, Copy)]
struct Recoil {
    entity: Entity,
    /// Its `Body::id`.
    id: usize,
    /// Its markers in [`NoSlip::nodes`].
    range: (usize, usize),
    /// ρ_F / E.
    inv_e: f64,
    /// J_E, the body's inertia beyond the fluid inside it.
    j_e: DMat3,
    /// Σ p h^d and Σ r × p h^d of the current search direction over the body's markers.
    p_force: DVec3,
    p_torque: DVec3,
    /// The momentum and angular momentum the fluid has taken so far, ρ_F Σ x h^d, ρ_F Σ r × x h^d.
    force: DVec3,
    torque: DVec3,
    /// The body's velocity and angular velocity before the solve.
    velocity: DVec3,
    angular_velocity: DVec3,
}

impl Recoil {
    /// Σ |V' + Ω' × r|² over the body's markers, with the body's velocities after the
    /// recoil taken so far.
    fn rigid_norm(&self, nodes: &[(Stencil, DVec3)], dim: usize, rho_f: f64) -> f64 {
        let v = self.velocity - self.force * (self.inv_e / rho_f);
        let w = self.angular_velocity - solve_inertia(dim, self.j_e, self.torque);
        let (lo, hi) = self.range;
        nodes[lo..hi]
            .iter()
            .map(|&(_, rv)| (v + w.cross(rv)).length_squared())
            .sum()
    }
}

impl NoSlip {
    /// Scratch for `grid` (the markers' buffers are sized before the first step).
    pub fn new(grid: &Grid, split: Option<&Decomposition>) -> Self {
        let n = grid.len();
        let field = || vec![vec![0.0; n]; grid.dim];
        NoSlip {
            p_grid: field(),
            kp_grid: field(),
            scratch: vec![0.0; n],
            split: split.map(|d| d.comm.clone()),
            curl_halo: CurlHalo::of_grid(grid, split),
            ..Default::default()
        }
    }

    /// Sizes the buffers for these bodies' markers (`(Body::id, marker count)`), keeping the
    /// last forces of a body whose count is unchanged (a restart's).
    pub fn reserve(&mut self, bodies: impl Iterator<Item = (usize, usize)>) {
        let mut total = 0;
        for (id, count) in bodies {
            if self.last.len() <= id {
                self.last.resize(id + 1, Vec::new());
            }
            if self.last[id].len() != count {
                self.last[id] = vec![DVec3::ZERO; count];
            }
            total += count;
        }
        for v in [
            &mut self.x,
            &mut self.r,
            &mut self.p,
            &mut self.ap,
            &mut self.carried,
        ] {
            v.reserve(total.saturating_sub(v.len()));
        }
        self.nodes.reserve(total.saturating_sub(self.nodes.len()));
        if self.split.is_some() {
            self.flat
                .reserve((9 * total).saturating_sub(self.flat.len()));
            self.flat_scratch
                .reserve((9 * total).saturating_sub(self.flat_scratch.len()));
        }
        self.bodies.reserve(self.last.len());
    }
}

/// Interpolates `field` at every marker of `nodes` into `out`: the kernel's plane sums
/// (`Stencil::interpolate_planes`, through the flat buffer `flat`), added over the processes
/// when split (each plane's are one process's: exact, `Comm::sum_disjoint`) and then in plane
/// order, so every
/// process gets the values one process would, bit for bit.
fn interpolate_all(
    grid: &Grid,
    nodes: &[(Stencil, DVec3)],
    field: &[Vec<f64>],
    split: Option<&Comm>,
    (flat, scratch): (&mut Vec<f64>, &mut Vec<f64>),
    out: &mut [DVec3],
) {
    let Some(c) = split else {
        for ((st, _), o) in nodes.iter().zip(out.iter_mut()) {
            *o = st.interpolate(grid, field);
        }
        return;
    };
    flat.clear();
    for (st, _) in nodes {
        for p in st.interpolate_planes(grid, field) {
            flat.extend_from_slice(&p.to_array());
        }
    }
    scratch.resize(flat.len(), 0.0);
    c.sum_disjoint(flat, scratch);
    for (o, f) in out.iter_mut().zip(flat.chunks_exact(9)) {
        let p = |k: usize| DVec3::new(f[3 * k], f[3 * k + 1], f[3 * k + 2]);
        *o = p(0) + p(1) + p(2);
    }
}

/// Σ a·b over the markers (in order: the result does not depend on the threads).
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
        &'static Markers,
    ),
>;

/// Whether a body is in the solve: dynamic, moving by Newton-Euler, on the grid.
fn in_solve(law: &MotionLaw, body: &Body, patch: &GridPatch) -> bool {
    *law == MotionLaw::NewtonEuler && body.is_dynamic() && patch.on_grid()
}

/// The last forces of body `id` when they are one per marker of its `n` (none before its
/// first solve, or after its markers changed).
fn last_forces(last: &[Vec<DVec3>], id: usize, n: usize) -> Option<&[DVec3]> {
    last.get(id).filter(|l| l.len() == n).map(|l| l.as_slice())
}

/// E = (ρ - ρ_F) V + M_v, the body's mass beyond the fluid inside it with its virtual mass,
/// and J_E, its inertia.
fn excess(
    mat: &Material,
    volume: &ShapeVolume,
    virt: &VirtualMass,
    state: &RigidState,
    rho_f: f64,
) -> (f64, DMat3) {
    let e = (mat.density - rho_f) * volume.0 + virt.mass;
    (e, state.inertia * (e / state.volume.max(f64::MIN_POSITIVE)))
}

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
    ns.x.clear();
    // The markers, the slip there, each body's recoil and its markers' last forces.
    for (entity, body, patch, state, law, mat, volume, virt, markers) in &bodies {
        if !in_solve(law, body, patch)
            || last_forces(&ns.last, body.id, markers.points.len()).is_none()
        {
            continue;
        }
        let start = ns.nodes.len();
        for &m in &markers.points {
            let pos = state.center + state.orientation * m;
            let rv = pos - state.centroid;
            let ubar = state.velocity + state.angular_velocity.cross(rv);
            let st = Stencil::at(&grid, pos);
            // u at the marker interpolated below; ū kept in x meanwhile.
            ns.nodes.push((st, rv));
            ns.r.push(DVec3::ZERO);
            ns.x.push(ubar);
        }
        // E + M_v (`VirtualMass`): positive for every body.
        let (e, j_e) = excess(mat, volume, virt, state, rho_f);
        ns.bodies.push(Recoil {
            entity,
            id: body.id,
            range: (start, ns.nodes.len()),
            inv_e: if e > 0.0 { rho_f / e } else { 0.0 },
            j_e,
            p_force: DVec3::ZERO,
            p_torque: DVec3::ZERO,
            force: DVec3::ZERO,
            torque: DVec3::ZERO,
            velocity: state.velocity,
            angular_velocity: state.angular_velocity,
        });
    }
    if ns.nodes.is_empty() {
        return;
    }
    // The slip ū - u at the markers; x starts from zero.
    let split = ns.split.clone();
    interpolate_all(
        &grid,
        &ns.nodes,
        &fields.u,
        split.as_deref(),
        (&mut ns.flat, &mut ns.flat_scratch),
        &mut ns.r,
    );
    for (r, x) in ns.r.iter_mut().zip(ns.x.iter_mut()) {
        *r = *x - *r;
        *x = DVec3::ZERO;
    }
    let m = ns.nodes.len();
    let nu_dt = params.nu * time.dt;
    let (omega, u, _) = fields.next_version_parts();
    spectral.forcing_reset();
    ns.ap.clear();
    ns.ap.resize(m, DVec3::ZERO);
    let rr_step = dot(&ns.r, &ns.r);
    let mut applied = false;
    ns.p.clear();
    ns.p.extend_from_slice(&ns.r);
    let mut rr = dot(&ns.r, &ns.r);
    // The slip the step would have made without the carried forcing is at least that
    // forcing's size: the solve stops at SLIP_TOLERANCE of the larger of the two.
    let carried: f64 = if ns.carried.len() == m {
        dot(&ns.carried, &ns.carried)
    } else {
        0.0
    };
    let slip_stop = SLIP_TOLERANCE.powi(2) * rr_step.max(carried);
    let rigid_norm = |ns: &NoSlip| -> f64 {
        ns.bodies
            .iter()
            .map(|b| b.rigid_norm(&ns.nodes, dim, rho_f))
            .sum()
    };
    for it in 0..MAX_ITERATIONS {
        if rr <= slip_stop.max(VELOCITY_TOLERANCE.powi(2) * rigid_norm(ns)) {
            break;
        }
        // ap = J K S p + B M_E⁻¹ Bᵀ p.
        apply(ns, &grid, &mut spectral, nu_dt, dv, rho_f);
        let pap = dot(&ns.p, &ns.ap);
        if pap <= 0.0 {
            break;
        }
        let alpha = rr / pap;
        for l in 0..m {
            ns.x[l] += alpha * ns.p[l];
            ns.r[l] -= alpha * ns.ap[l];
        }
        // The flow takes α K S p now (K S x is never formed again), its vorticity at the end.
        add_response(u, &ns.kp_grid, alpha);
        spectral.forcing_accumulate(alpha);
        applied = true;
        ns.iterations = it + 1;
        // The momentum the fluid takes, ρ_F Σ x h^d, and its moment.
        for rec in ns.bodies.iter_mut() {
            rec.force += rec.p_force * (alpha * rho_f);
            rec.torque += rec.p_torque * (alpha * rho_f);
        }

        let rr_new = dot(&ns.r, &ns.r);
        let beta = rr_new / rr;
        rr = rr_new;
        for l in 0..m {
            ns.p[l] = ns.r[l] + beta * ns.p[l];
        }
    }
    // The spread field is zero again off this step's stencils; the next step's first guess.
    for (st, _) in &ns.nodes {
        zero_on(st, &grid, &mut ns.p_grid);
    }
    // The next step carries this step's whole force: the carried part and the correction.
    if ns.carried.len() == m {
        for (x, c) in ns.x.iter_mut().zip(&ns.carried) {
            *x += *c;
        }
    }
    for rec in &ns.bodies {
        let (lo, hi) = rec.range;
        ns.last[rec.id].copy_from_slice(&ns.x[lo..hi]);
    }
    if !applied {
        return;
    }
    // The vorticity of the force the flow took; the bodies take the reaction.
    spectral.forcing_vorticity_add(omega, &mut ns.scratch);
    for rec in &ns.bodies {
        let Ok((_, _, _, mut state, _, _, _, _, _)) = bodies.get_mut(rec.entity) else {
            continue;
        };
        // rec.force = ρ_F Σ x h^d: the momentum the fluid took. (The body's reported force
        // is set from its motion by `rigid_update`.)
        state.velocity -= rec.force * (rec.inv_e / rho_f);
        state.angular_velocity -= solve_inertia(dim, rec.j_e, rec.torque);
    }
}

/// The last step's forces carried into this step (the carried forcing of SophT's virtual
/// boundary forcing and of CubismUP's iterated penalization): spread at the markers' places
/// now, scaled to this step's length, their centred curl added to the vorticity before the
/// implicit diffusion (so the flow takes them through the diffusion's resolvent, as the
/// solve's K does), and their reaction given to the bodies. The solve at the end of the step
/// then only corrects them.
#[allow(clippy::too_many_arguments)]
pub fn carry(
    grid: Res<Grid>,
    params: Res<Params>,
    time: Res<SimTime>,
    mut fields: ResMut<Fields>,
    mut ns: ResMut<NoSlip>,
    mut bodies: NewtonBodies,
) {
    let ns = &mut *ns;
    ns.carried.clear();
    let dt_prev = fields.dt_prev;
    if dt_prev <= 0.0 {
        return;
    }
    let scale = time.dt / dt_prev;
    let rho_f = params.rho_fluid;
    let dim = grid.dim;
    let dv = grid.cell_volume();
    let mut any = false;
    for (_, body, patch, mut state, law, mat, volume, virt, markers) in &mut bodies {
        if !in_solve(law, body, patch) {
            continue;
        }
        let Some(last) = last_forces(&ns.last, body.id, markers.points.len()) else {
            continue;
        };
        let (mut force, mut torque) = (DVec3::ZERO, DVec3::ZERO);
        for (&m, &f) in markers.points.iter().zip(last) {
            let f = f * scale;
            let pos = state.center + state.orientation * m;
            let rv = pos - state.centroid;
            Stencil::at(&grid, pos).visit(&grid, |g, w| {
                for (q, c) in ns.p_grid.iter_mut().enumerate() {
                    c[g] += w * f[q];
                }
            });
            ns.carried.push(f);
            force += f * dv;
            torque += rv.cross(f * dv);
            any = true;
        }
        let (e, j_e) = excess(mat, volume, virt, &state, rho_f);
        if e > 0.0 {
            state.velocity -= force * (rho_f / e);
            state.angular_velocity -= solve_inertia(dim, j_e, torque * rho_f);
        }
    }
    if !any {
        return;
    }
    crate::solvers::operators::curl_add(&grid, &ns.p_grid, fields.omega_mut(), ns.curl_halo.get());
    for (_, body, patch, state, law, _, _, _, markers) in &bodies {
        if !in_solve(law, body, patch) {
            continue;
        }
        for &m in &markers.points {
            let pos = state.center + state.orientation * m;
            zero_on(&Stencil::at(&grid, pos), &grid, &mut ns.p_grid);
        }
    }
}

/// Zeroes `field` on the nodes of stencil `st` (the spread field is zero off the stencils).
fn zero_on(st: &Stencil, grid: &Grid, field: &mut [Vec<f64>]) {
    st.visit(grid, |g, _| {
        for c in field.iter_mut() {
            c[g] = 0.0;
        }
    });
}

/// u += α K p over the whole grid.
fn add_response(u: &mut [Vec<f64>], kp: &[Vec<f64>], alpha: f64) {
    for (uc, kc) in u.iter_mut().zip(kp) {
        uc.par_iter_mut()
            .zip(kc.par_iter())
            .for_each(|(u, k)| *u += alpha * k);
    }
}

/// ap = J K S p + B M_E⁻¹ Bᵀ p for the search direction `ns.p` (K S p is left in
/// `ns.kp_grid`, each body's Σ p h^d and Σ r × p h^d in its `p_force`, `p_torque`). Each
/// marker stands for a volume h^d: its force spreads with weights that sum to one.
fn apply(ns: &mut NoSlip, grid: &Grid, spectral: &mut Spectral, nu_dt: f64, dv: f64, rho_f: f64) {
    let dim = grid.dim;
    for (st, _) in &ns.nodes {
        zero_on(st, grid, &mut ns.p_grid);
    }
    for ((st, _), p) in ns.nodes.iter().zip(&ns.p) {
        st.visit(grid, |g, w| {
            for (q, c) in ns.p_grid.iter_mut().enumerate() {
                c[g] += w * p[q];
            }
        });
    }
    spectral.forcing_velocity(&ns.p_grid, nu_dt, &mut ns.kp_grid);
    interpolate_all(
        grid,
        &ns.nodes,
        &ns.kp_grid,
        ns.split.as_deref(),
        (&mut ns.flat, &mut ns.flat_scratch),
        &mut ns.ap,
    );
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
        ctx.share_resource(|w| {
            NoSlip::new(
                w.resource::<Grid>(),
                w.get_resource::<crate::parallel::Decomposition>(),
            )
        });
        ctx.share_resource(|w| {
            Spectral::of_grid(
                w.resource::<crate::base::grid::Grid>(),
                w.get_resource::<crate::parallel::Decomposition>(),
            )
        });
        ctx.add_startup_system_in(
            PhysicsSet::NoSlip,
            "noslip_init",
            |mut s: ResMut<Spectral>,
             mut ns: ResMut<NoSlip>,
             bodies: Query<(&Body, &MotionLaw, &Markers)>| {
                s.reserve_forcing();
                ns.reserve(
                    bodies
                        .iter()
                        .filter(|(b, law, _)| **law == MotionLaw::NewtonEuler && b.is_dynamic())
                        .map(|(b, _, m)| (b.id, m.points.len())),
                );
            },
        )?;
        ctx.add_system(PhysicsSet::CarriedForcing, "noslip_carry", carry)?;
        ctx.add_system(PhysicsSet::NoSlip, "noslip", noslip)?;
        ctx.checkpoint_part::<NoSlip>("noslip", 2)?;
        Ok(())
    }
}
