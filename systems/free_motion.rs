//! # free_motion: bodies in vacuum, under gravity and contact only (paper Fig. 1 and Fig. 9)
//!
//! With the flow solver off (`vacuum: true`), each dynamic body obeys Newton's laws directly:
//!
//!   m_i dV_i/dt = m_i g + F_i,   dL_i/dt = T_i,   Ω_i = J_i⁻¹ L_i,
//!
//! with F_i, T_i the contact force and torque of the collision system (eq. 22), m_i = ρ_i |S_i|
//! and J_i integrated from χ_i on the grid in the current pose (the same body the level set
//! describes). Integrated with symplectic Euler: this system updates the velocities, then
//! `rigid_update` moves the body with the new ones. Symplectic Euler keeps the energy error
//! bounded over many rebounds, where the paper's explicit Euler gains a little energy at each
//! one (section 2.2, Fig. 1). The angular momentum is carried from step to step, so a free
//! body's rotation conserves it while its inertia tensor turns with it.

use crate::base::fields::{Fields, Params, SimTime};
use crate::base::grid::Grid;
use crate::bodies::integrals::{BodySums, mass_properties};
use crate::bodies::{Body, ContactState, FreeMotion, GridPatch, Material, RigidState};
use bevy_ecs::prelude::*;
use glam::DVec3;

/// The free-motion system.
#[allow(clippy::type_complexity)]
pub fn free_motion(
    grid: Res<Grid>,
    params: Res<Params>,
    time: Res<SimTime>,
    fields: Res<Fields>,
    mut sums: ResMut<BodySums>,
    mut bodies: Query<(
        &Body,
        &GridPatch,
        &Material,
        &ContactState,
        &mut FreeMotion,
        &mut RigidState,
    )>,
) {
    let dt = time.dt;
    let g = DVec3::from_array(params.gravity);
    for (body, patch, mat, contact, mut free, mut state) in &mut bodies {
        if body.is_static() {
            continue;
        }
        if !mass_properties(&grid, patch, &fields.u, &mut sums, body, time.t, &mut state) {
            continue;
        }
        let (m, j) = (mat.density * state.volume, state.inertia);
        state.velocity += dt * (g + contact.force / m);
        if grid.dim == 2 {
            state.velocity.z = 0.0;
            let jz = mat.density * j.z_axis.z;
            if jz > 0.0 {
                state.angular_velocity = DVec3::new(
                    0.0,
                    0.0,
                    state.angular_velocity.z + dt * contact.torque.z / jz,
                );
            }
            continue;
        }
        let jr = mat.density * j;
        let l = free.angular_momentum.unwrap_or(jr * state.angular_velocity) + dt * contact.torque;
        free.angular_momentum = Some(l);
        if jr.determinant().abs() > 0.0 {
            state.angular_velocity = jr.inverse() * l;
        }
    }
}

/// Motion under gravity and contact in vacuum, before the rigid update.
#[derive(Debug, Clone, Copy, Default)]
pub struct FreeMotionPlugin;

impl crate::schedule::Plugin for FreeMotionPlugin {
    fn name(&self) -> &'static str {
        "free_motion"
    }

    fn build(&self, ctx: &mut crate::schedule::PluginContext) -> anyhow::Result<()> {
        use crate::schedule::PhysicsSet;
        if ctx.mode().vacuum {
            ctx.share_resource(BodySums::of_world);
            ctx.add_system(PhysicsSet::FreeMotion, "free_motion", free_motion)?;
        }
        Ok(())
    }
}
