//! # rigid_update: move the bodies (paper section 3.1)
//!
//! Over one step with the rigid velocity held constant: c ← c + V Δt and the orientation is
//! composed with the rotation by the angle |Ω| Δt about Ω/|Ω| (the paper's quaternion matrix
//! R^n), q ← rot(Ω Δt) q. Dynamic bodies use the ū computed from the flow this step,
//! kinematic bodies their prescribed motion, static bodies stay.

use crate::bodies::{Body, RigidState, kinematic_velocity};
use crate::fields::{SimTime, SystemTimer, Timings};
use bevy_ecs::prelude::*;
use glam::DQuat;

/// The rigid-update system.
pub fn rigid_update(
    time: Res<SimTime>,
    mut bodies: Query<(&Body, &mut RigidState)>,
    mut timings: ResMut<Timings>,
) {
    let timer = SystemTimer::start();
    let dt = time.dt;
    for (body, mut s) in &mut bodies {
        if body.is_static() {
            continue;
        }
        if let Some((v, w)) = kinematic_velocity(&body.kind, time.t) {
            s.velocity = v;
            s.angular_velocity = w;
        }
        let v = s.velocity;
        s.center += v * dt;
        let turn = s.angular_velocity * dt;
        if turn.length() > 0.0 {
            s.orientation = (DQuat::from_scaled_axis(turn) * s.orientation).normalize();
        }
    }
    timer.stop(&mut timings, "rigid_update");
}
