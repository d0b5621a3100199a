//! # penalization: rigid motion inside the bodies, implicitly (paper eqs. 13 and 27)
//!
//! u ← (u + λ Δt χ_i ū_i) / (1 + λ Δt χ_i) on each body's patch: unconditionally stable for any
//! λ (default 10⁶), so the velocity inside a body is its rigid velocity ū_i = V_i + Ω_i × r up
//! to O(1/(λΔt)), with r measured from the body's χ-centroid. The vorticity follows in the form of eq. (27): ω ← ω + ∇×(u_new - u_old) by
//! centred differences, which touches only the nodes the penalization changed. The penalized
//! velocity is what carries the particles in the transport system.
//!
//! Moving bodies are penalized first and static ones last, so where a body overlaps a wall the
//! wall's rest state wins.
//!
//! The hydrodynamic force on a static or kinematic body i (and on a dynamic one with
//! `body_coupling: Baroclinic`; with `Momentum` `rigid_velocity` reports it) is the momentum
//! the penalization takes out of the flow per
//! unit time, F_i = ∫ ρ χ_i (u_old - u_new)/Δt dx = λ ∫ ρ χ_i (u_new - ū_i) dx, and the torque
//! its moment about the centroid. The Δt there is the previous step's, the one over which the
//! flow built up the slip that the penalization removes.
//!
//! For static and kinematic bodies the penalization mask is their χ = H_ε(φ_i - δ) with
//! δ = `penalization_offset` h (default 0; `level_sets::wall_offset`), the same χ every other
//! system reads: with δ = ε the smoothed band lies inside the body, so the rigid region ends at
//! the surface instead of reaching ε into the fluid. With
//! δ = 0, a fixed cylinder at Re = 20 (12.8 cells per diameter) has C_d = 2.34, falling to 2.20
//! at 25.6 cells, first order; with δ = ε it is 2.098 and 2.090 (Dennis & Chang: 2.05
//! unbounded; this box has 5% blockage). Dynamic bodies keep δ = 0: with the mask moved
//! inside, a settling sphere fell 20-50% too fast (d = 0.3, ν = 0.02 at h = 1/32: 1.69 against
//! 1.51, even with the body's extra mass moved into the mask), so the rigid region of a body
//! that stays with the projection is the whole smoothed band, the same χ as its density and
//! mass. A body that moves by Newton-Euler is set to its rigid velocity exactly on the nodes
//! inside its surface (φ > 0) on the first step only (its initial condition); from then on the
//! flow inside it is fluid held by the no-slip at its surface markers (`systems/noslip.rs`),
//! and takes here only the contact's velocity change, which acts on the whole body.

use crate::base::fields::{Fields, Params, SimTime};
use crate::base::grid::{Grid, component_ptrs};
use crate::base::params::BodyCoupling;
use crate::bodies::contact::contact_velocity_change;
use crate::bodies::coupling::MotionLaw;
use crate::bodies::integrals::{BodySums, rigid_region};
use crate::bodies::{Body, BodyFields, ContactState, GridPatch, Hydro, Material, RigidState};
use crate::solvers::operators::{CurlHalo, curl_add};
use bevy_ecs::prelude::*;
use glam::DVec3;
use rayon::prelude::*;

/// The penalization system.
#[allow(clippy::too_many_arguments)]
pub fn penalization(
    grid: Res<Grid>,
    params: Res<Params>,
    time: Res<SimTime>,
    mut fields: ResMut<Fields>,
    mut bf: ResMut<BodyFields>,
    mut sums: ResMut<BodySums>,
    mut halo: ResMut<CurlHalo>,
    mut bodies: Query<(
        &Body,
        &GridPatch,
        &RigidState,
        &MotionLaw,
        &Material,
        &ContactState,
        &mut Hydro,
    )>,
) {
    let dt = time.dt;
    let ldt = params.numerics.lambda * dt;
    let dim = grid.dim;
    let bf = &mut *bf;
    for c in bf.du.iter_mut() {
        c.par_iter_mut().for_each(|x| *x = 0.0);
    }
    let dv = grid.cell_volume();
    // The velocity the penalization corrects was made by the previous step, so the momentum it
    // removes is spread over that step's length (equal to Δt except at output landings).
    let dt_force = if fields.dt_prev > 0.0 {
        fields.dt_prev
    } else {
        dt
    };
    let momentum = params.numerics.body_coupling == BodyCoupling::Momentum;
    let pressure = params.numerics.body_coupling == BodyCoupling::Pressure;
    let fields = &mut *fields;
    // Moving bodies first, static ones last: where a body overlaps a wall, the wall wins and
    // the fluid there is at rest, which is what stops a body at a wall.
    for pass_static in [false, true] {
        for (body, patch, state, law, mat, contact, mut hydro) in &mut bodies {
            if body.is_static() != pass_static {
                continue;
            }
            let dynamic = body.is_dynamic();
            // A Newton-Euler body's rigid region is the nodes inside its surface, set to its
            // rigid velocity exactly (the weight of its mean and its no-slip).
            let newton = dynamic && pressure && *law == MotionLaw::NewtonEuler;
            // After the first step the flow inside a Newton-Euler body is fluid, held by the
            // no-slip at its markers (`noslip`); it takes only the contact's velocity change
            // here (the contact acts on the whole body, this fluid included).
            let kick = if newton && fields.dt_prev > 0.0 {
                let (dv, dw) = contact_velocity_change(dim, mat.density, state, contact, dt);
                if dv == DVec3::ZERO && dw == DVec3::ZERO {
                    continue;
                }
                Some((dv, dw))
            } else {
                None
            };
            // With the momentum coupling a dynamic body's force is the fluid's share of its
            // momentum balance, reported by `rigid_velocity`.
            let own_force = !(dynamic && (momentum || pressure));
            let [dx, dy, _] = patch.dims;
            // (A process whose slab holds none of the patch adds zero to the force.)
            let rows = if patch.is_empty() {
                0
            } else {
                patch.len() / dx
            };
            let u = component_ptrs(&mut fields.u);
            let du = component_ptrs(&mut bf.du);
            let rho = &bf.rho;
            let st = *state;
            sums.rows_mut()[..rows]
                .par_iter_mut()
                .enumerate()
                .for_each(|(r, acc)| {
                    let (b, c) = (r % dy, r / dy);
                    // (A plane of the patch held by another process adds zero here.)
                    if !patch.holds(&grid, c) {
                        acc.fill(0.0);
                        return;
                    }
                    let nodes = patch.row(&grid, b, c);
                    let mut f = DVec3::ZERO;
                    let mut m = DVec3::ZERO;
                    for a in 0..dx {
                        let (cv, phi) = (patch.chi[r * dx + a], patch.phi[r * dx + a]);
                        // A static or kinematic body's χ is already its mask, moved into it by
                        // `numerics.penalization_offset` (`level_sets::wall_offset`).
                        let chi = if newton { rigid_region(phi) } else { cv };
                        if chi == 0.0 {
                            continue;
                        }
                        // The wrapped node for the fields, its image next to the body for
                        // the lever arm.
                        let g = nodes.index(a);
                        let p = patch.pos(&grid, a, b, c);
                        let rv = DVec3::new(p[0], p[1], p[2]) - st.centroid;
                        let ubar = st.velocity + st.angular_velocity.cross(rv);
                        let mut change = DVec3::ZERO;
                        for q in 0..dim {
                            // SAFETY: distinct patch nodes map to distinct grid nodes.
                            unsafe {
                                let old = u[q].read(g);
                                let new = if let Some((dv, dw)) = kick {
                                    old + (dv + dw.cross(rv))[q]
                                } else if newton {
                                    ubar[q]
                                } else {
                                    (old + ldt * chi * ubar[q]) / (1.0 + ldt * chi)
                                };
                                u[q].write(g, new);
                                du[q].write(g, du[q].read(g) + new - old);
                                change[q] = new - old;
                            }
                        }
                        let df = -rho[g] * change / dt_force * dv;
                        f += df;
                        m += rv.cross(df);
                    }
                    acc[..3].copy_from_slice(&f.to_array());
                    acc[3..6].copy_from_slice(&m.to_array());
                    acc[6..].fill(0.0);
                });
            if own_force {
                let mut t = [[0.0; 16]];
                sums.patch_total(&grid, patch, &mut t);
                let t = t[0];
                *hydro = Hydro {
                    force: DVec3::new(t[0], t[1], t[2]),
                    torque: DVec3::new(t[3], t[4], t[5]),
                };
            }
        }
    }
    // Under the pressure projection the increment is projected with the density first
    // (`pressure`), which then adds its curl.
    if !pressure {
        curl_add(&grid, &bf.du, fields.omega_mut(), halo.get());
    }
}

/// Implicit penalization (a fluid run with bodies).
#[derive(Debug, Clone, Copy, Default)]
pub struct PenalizationPlugin;

impl crate::schedule::Plugin for PenalizationPlugin {
    fn name(&self) -> &'static str {
        "penalization"
    }

    fn build(&self, ctx: &mut crate::schedule::PluginContext) -> anyhow::Result<()> {
        use crate::schedule::PhysicsSet;
        let mode = ctx.mode();
        if mode.fluid() && mode.has_bodies() {
            ctx.share_resource(BodySums::of_world);
            ctx.share_resource(|w| {
                crate::solvers::operators::CurlHalo::of_grid(
                    w.resource::<crate::base::grid::Grid>(),
                    w.get_resource::<crate::parallel::Decomposition>(),
                )
            });
            ctx.add_system(PhysicsSet::Penalization, "penalization", penalization)?;
        }
        Ok(())
    }
}
