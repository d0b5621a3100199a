//! # rigid_update: move the bodies (paper section 3.1)
//!
//! Over one step with the rigid velocity held constant: the centroid x_G ← x_G + V Δt, the
//! orientation is composed with the rotation by the angle |Ω| Δt about Ω/|Ω| (the paper's
//! quaternion matrix R^n), q ← rot(Ω Δt) q, and the body frame's origin c turns with it about
//! x_G: c ← x_G + rot(Ω Δt)(c - x_G). Dynamic bodies use the ū computed from the flow this step,
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
        // The body turns about its centroid and the centroid moves with V.
        let v = s.velocity;
        let arm = s.center - s.centroid;
        s.centroid += v * dt;
        let turn = s.angular_velocity * dt;
        if turn.length() > 0.0 {
            let q = DQuat::from_scaled_axis(turn);
            s.orientation = (q * s.orientation).normalize();
            s.center = s.centroid + q * arm;
        } else {
            s.center = s.centroid + arm;
        }
    }
    timer.stop(&mut timings, "rigid_update");
}
