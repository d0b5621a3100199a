//! # rigid_update: move the bodies (paper section 3.1)
//!
//! Over one step with the rigid velocity held constant: the centroid x_G ← x_G + V Δt, the
//! orientation is composed with the rotation by the angle |Ω| Δt about Ω/|Ω| (the paper's
//! quaternion matrix R^n), q ← rot(Ω Δt) q, and the body frame's origin c turns with it about
//! x_G: c ← x_G + rot(Ω Δt)(c - x_G). A kinematic body's prescription is the motion of its
//! origin c, which it follows exactly. Dynamic bodies use the ū computed from the flow this step,
//! kinematic bodies their prescribed motion, static bodies stay. The velocities used are kept
//! as the next step's previous velocity ([`PreviousVelocity`]).
//!
//! For a body that moves by Newton-Euler (`MotionLaw::NewtonEuler`) the hydrodynamic force and
//! torque reported ([`Hydro`], `bodies.csv`) are set here from the motion the step gave it:
//! F = m a - m g and T = J α + Ω × (J Ω), with m = ρ_i V_i, J = ρ_i J_i, and a, α the
//! acceleration over the step without the contact's part: the whole force of the fluid on the
//! body, buoyancy included, as the projected bodies report it. The parts the systems before
//! add up (the flow's impulse on the rigid region in `rigid_velocity`, the no-slip's reaction in
//! `noslip`) act on different masses, the rigid region's fluid and the body's mass beyond it,
//! and their sum is not the body's force (a disk of density 2 settling at its terminal
//! velocity summed to half its excess weight).
//!
//! The box is periodic: a moving body whose centre leaves it is moved back by a box length
//! along that axis (its centre and centroid together; its orientation, velocities and all
//! body-frame data are unchanged), like the fluid that leaves through one face and enters
//! through the opposite one. The stored centre, and the outputs (`bodies.csv`, snapshots),
//! are therefore always inside `[origin, origin + extent)`; a distance travelled must be
//! accumulated from the velocities, not read as a difference of positions.

use crate::base::fields::{Params, SimTime};
use crate::base::grid::Grid;
use crate::bodies::contact::contact_velocity_change;
use crate::bodies::coupling::MotionLaw;
use crate::bodies::{
    Body, ContactState, Hydro, Material, PreviousVelocity, RigidState, ShapeVolume,
    kinematic_velocity,
};
use bevy_ecs::prelude::*;
use glam::{DQuat, DVec3};

/// A body's pose, its last velocity and what its contact gave it this step.
type Moving = (
    &'static Body,
    &'static mut RigidState,
    &'static mut PreviousVelocity,
    Option<(&'static Material, &'static ContactState)>,
    Option<(&'static MotionLaw, &'static ShapeVolume, &'static mut Hydro)>,
);

/// The rigid-update system.
pub fn rigid_update(
    time: Res<SimTime>,
    grid: Res<Grid>,
    params: Res<Params>,
    mut bodies: Query<Moving>,
) {
    let dt = time.dt;
    let g = DVec3::from_array(params.gravity);
    for (body, mut s, mut prev, contact, newton) in &mut bodies {
        if body.is_static() {
            continue;
        }
        // This step's ū, for the next step's acceleration (baroclinic term).
        // The acceleration the flow and gravity gave the body over the step, the contact's
        // part taken out (a virtual mass that lagged a contact force would feed a lagged
        // spring: a disk bouncing on a floor never came to rest).
        let inv_dt = if dt > 0.0 { 1.0 / dt } else { 0.0 };
        let (dv, dw) = match contact {
            Some((mat, c)) => contact_velocity_change(grid.dim, mat.density, &s, c, dt),
            None => (DVec3::ZERO, DVec3::ZERO),
        };
        *prev = PreviousVelocity {
            velocity: s.velocity,
            angular_velocity: s.angular_velocity,
            acceleration: (s.velocity - prev.velocity - dv) * inv_dt,
            angular_acceleration: (s.angular_velocity - prev.angular_velocity - dw) * inv_dt,
        };
        if let (Some((mat, _)), Some((MotionLaw::NewtonEuler, volume, mut hydro))) =
            (contact, newton)
            && dt > 0.0
            && s.volume > 0.0
        {
            // The body's mass and inertia (the shape's exact volume where it has one, as its
            // Newton-Euler update takes).
            let v = if volume.0 > 0.0 { volume.0 } else { s.volume };
            let (m, j) = (mat.density * v, s.inertia * (mat.density * v / s.volume));
            let w = s.angular_velocity;
            // (In 2D Ω and JΩ are along z, and the gyroscopic term is zero.)
            *hydro = Hydro {
                force: m * (prev.acceleration - g),
                torque: j * prev.angular_acceleration + w.cross(j * w),
            };
        }
        if let Some((v, w)) = kinematic_velocity(&body.kind, time.t) {
            // A prescribed motion is that of the body frame's origin.
            s.velocity = v;
            s.angular_velocity = w;
            let q = DQuat::from_scaled_axis(w * dt);
            let arm = s.centroid - s.center;
            s.center += v * dt;
            s.orientation = (q * s.orientation).normalize();
            s.centroid = s.center + q * arm;
        } else {
            // A free body turns about its centroid, which moves with V.
            *s = s.advanced(dt);
        }
        wrap_into_box(&grid, &mut s);
    }
}

/// Move a body whose centre left the periodic box back by whole box lengths (centre and
/// centroid together). Nothing changes, bit for bit, when the centre is inside.
pub fn wrap_into_box(grid: &Grid, s: &mut RigidState) {
    let shift = DVec3::from_array(grid.wrap_shift(s.center.to_array()));
    if shift != DVec3::ZERO {
        s.center += shift;
        s.centroid += shift;
    }
}

/// Moves the bodies (every run with bodies; always in vacuum).
#[derive(Debug, Clone, Copy, Default)]
pub struct RigidUpdatePlugin;

impl crate::schedule::Plugin for RigidUpdatePlugin {
    fn name(&self) -> &'static str {
        "rigid_update"
    }

    fn build(&self, ctx: &mut crate::schedule::PluginContext) -> anyhow::Result<()> {
        use crate::schedule::PhysicsSet;
        let mode = ctx.mode();
        if mode.vacuum || mode.has_bodies() {
            ctx.add_system(PhysicsSet::RigidUpdate, "rigid_update", rigid_update)?;
        }
        Ok(())
    }
}
