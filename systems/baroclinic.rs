//! # baroclinic: vorticity made by density gradients (paper eq. 28; Boussinesq form eq. 18)
//!
//! ∂ω/∂t = -(∇ρ/ρ) × (∂u/∂t + (u·∇)u - g), integrated over one step: with
//! `numerics.body_coupling: Baroclinic` (the default) this is how gravity reaches a body whose
//! density differs from the fluid's. With `Momentum` a body's weight and inertia act on its
//! rigid velocity instead (`rigid_velocity`), and the nodes of bodies are skipped here.
//! ∂u/∂t comes from the last two velocity fields, (u^n - u^{n-1})/Δt_{n-1} (zero on the first
//! step), and ∇ρ and (u·∇)u from centred differences; only nodes where ρ varies are touched.
//! With `numerics.boussinesq` the term is ∇ρ × g / ρ_F instead.
//!
//! ∇ρ lives on the bodies' interfaces, where the fluid moves with the body (no slip), so there
//! Du/Dt is the body's rigid acceleration A + α × r + Ω × (Ω × r), with A and α from this
//! step's and the previous step's ū (`numerics.interface_acceleration: Rigid`, the default).
//! Each node takes the acceleration of the body whose level set is largest there, with the
//! lever arm from the node's image next to the body (its patch's unwrapped position, for a
//! body straddling the periodic boundary). The
//! grid estimate ∂u/∂t + (u·∇)u (`Eulerian`, the paper's) differences the velocity across the
//! moving interface, where it has a kink: a disk falling 1.5 cells per step then felt a drag
//! that grew as Δt shrank (terminal velocity +23% from Δt = 1.5e-3 to 3.75e-4 at h = 1/128),
//! while with the rigid acceleration the fall does not depend on Δt.

use crate::base::fields::{Fields, Params, SimTime};
use crate::base::grid::Grid;
use crate::base::params::{BodyCoupling, InterfaceAcceleration};
use crate::bodies::{
    Body, BodyFields, GridPatch, Material, NO_BODY, PreviousVelocity, RigidAccel, RigidState,
};
use bevy_ecs::prelude::*;
use glam::DVec3;
use rayon::prelude::*;

/// The baroclinic system.
pub fn baroclinic(
    grid: Res<Grid>,
    params: Res<Params>,
    time: Res<SimTime>,
    mut fields: ResMut<Fields>,
    mut bf: ResMut<BodyFields>,
    bodies: Query<(&Body, &RigidState, &PreviousVelocity, &Material, &GridPatch)>,
) {
    let dt = time.dt;
    let rigid = params.numerics.interface_acceleration == InterfaceAcceleration::Rigid;
    let momentum = params.numerics.body_coupling == BodyCoupling::Momentum;
    let inv_dt_body = if fields.dt_prev > 0.0 {
        1.0 / fields.dt_prev
    } else {
        0.0
    };
    for (body, st, prev, mat, patch) in &bodies {
        bf.rigid_accel[body.id] = if body.is_static() {
            RigidAccel {
                density: params.rho_fluid,
                ..Default::default()
            }
        } else {
            RigidAccel {
                linear: (st.velocity - prev.velocity) * inv_dt_body,
                angular: (st.angular_velocity - prev.angular_velocity) * inv_dt_body,
                omega: st.angular_velocity,
                centroid: st.centroid,
                density: mat.density,
                patch_lo: patch.lo,
            }
        };
    }
    let bf = &*bf;
    let (owner, rigid_accel) = (&bf.owner, &bf.rigid_accel);
    let g = DVec3::from_array(params.gravity);
    let fields = &mut *fields;
    let inv_dtp = if fields.dt_prev > 0.0 {
        1.0 / fields.dt_prev
    } else {
        0.0
    };
    let [nx, ny, nz] = grid.n;
    let dim = grid.dim;
    let inv2h = 0.5 / grid.h;
    let rho = &bf.rho;
    let rho_f = params.rho_fluid;
    let boussinesq = params.numerics.boussinesq;
    let nb = crate::base::grid::periodic_neighbours;
    let u = std::mem::take(&mut fields.u);
    let u_prev = std::mem::take(&mut fields.u_prev);
    let omega = fields.omega_mut();
    // One task per row; each writes only its own row of ω.
    let ptrs = crate::base::grid::component_ptrs(omega);
    (0..ny * nz).into_par_iter().for_each(|row| {
        let (j, k) = (row % ny, row / ny);
        let (jm, jp) = nb(j, ny);
        let (km, kp) = if dim == 3 { nb(k, nz) } else { (0, 0) };
        for i in 0..nx {
            let (im, ip) = nb(i, nx);
            let id = |i: usize, j: usize, k: usize| i + nx * (j + ny * k);
            let c = id(i, j, k);
            let grad = |f: &[f64]| {
                DVec3::new(
                    (f[id(ip, j, k)] - f[id(im, j, k)]) * inv2h,
                    (f[id(i, jp, k)] - f[id(i, jm, k)]) * inv2h,
                    if dim == 3 {
                        (f[id(i, j, kp)] - f[id(i, j, km)]) * inv2h
                    } else {
                        0.0
                    },
                )
            };
            // With the momentum coupling the bodies' weight acts on their rigid velocity.
            if momentum && owner[c] != NO_BODY {
                continue;
            }
            let grho = grad(rho);
            if grho == DVec3::ZERO {
                continue;
            }
            let src = if boussinesq {
                grho.cross(g) / rho_f
            } else if rigid && owner[c] != NO_BODY {
                let p = grid.pos(i, j, k);
                let body = &rigid_accel[owner[c] as usize];
                let a = body.at_node(&grid, DVec3::new(p[0], p[1], p[2]));
                -(grho * (body.density / (rho[c] * rho[c]))).cross(a - g)
            } else {
                let uc = DVec3::new(u[0][c], u[1][c], if dim == 3 { u[2][c] } else { 0.0 });
                let mut acc = DVec3::ZERO;
                for q in 0..dim {
                    let dudt = (u[q][c] - u_prev[q][c] as f64) * inv_dtp;
                    acc[q] = dudt + uc.dot(grad(&u[q])) - g[q];
                }
                -(grho / rho[c]).cross(acc)
            };
            // SAFETY: node c belongs to this row only.
            unsafe {
                if dim == 2 {
                    ptrs[0].write(c, ptrs[0].read(c) + dt * src.z);
                } else {
                    for q in 0..3 {
                        ptrs[q].write(c, ptrs[q].read(c) + dt * src[q]);
                    }
                }
            }
        }
    });
    fields.u = u;
    fields.u_prev = u_prev;
}

/// Baroclinic vorticity generation (a fluid run with bodies).
#[derive(Debug, Clone, Copy, Default)]
pub struct BaroclinicPlugin;

impl crate::schedule::Plugin for BaroclinicPlugin {
    fn name(&self) -> &'static str {
        "baroclinic"
    }

    fn build(&self, ctx: &mut crate::schedule::PluginContext) -> anyhow::Result<()> {
        use crate::schedule::PhysicsSet;
        let mode = ctx.mode();
        let coupling = ctx.world.resource::<Params>().numerics.body_coupling;
        if mode.fluid() && mode.has_bodies() && coupling != BodyCoupling::Pressure {
            ctx.add_system(PhysicsSet::Baroclinic, "baroclinic", baroclinic)?;
        }
        Ok(())
    }
}
