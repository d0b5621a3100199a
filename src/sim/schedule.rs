//! All scheduling in one place.
//!
//! One step of the method is one run of the [`Step`] schedule: the named [`PhysicsSet`]s,
//! chained once in the order of the paper's splitting (DESIGN.md, "One time step"). `First`
//! and `Last` are empty: they are where users hook their own systems. A new physics system is
//! one file in `systems/` plus one `add_systems(.. .in_set(PhysicsSet::X))` line (or
//! `.after(PhysicsSet::X).before(PhysicsSet::Y)` between two sets).
//!
//! The executor is single-threaded (the systems parallelise inside with rayon) and ambiguous
//! ordering is an error: two systems that touch the same data must be ordered.

use crate::systems::{
    baroclinic, collision, density, diagnostics, diffusion, free_motion, level_sets, penalization,
    poisson, rigid_update, rigid_velocity, transport,
};
use bevy_ecs::prelude::*;
use bevy_ecs::schedule::{LogLevel, ScheduleBuildSettings, ScheduleLabel, SingleThreadedExecutor};

/// The named stages of a step, in order. Sets without built-in systems yet are the places
/// where the body physics plugs in.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PhysicsSet {
    /// Empty: user systems that run before everything else.
    First,
    /// Sample body level sets on the grid (section 3.1).
    LevelSets,
    /// Characteristic functions and density (eq. 19).
    Density,
    /// Rigid velocity of each body from the flow (eq. 7).
    RigidVelocity,
    /// Contact forces between bodies (eqs. 20-22), added to the rigid velocities as impulses
    /// (section 3.2).
    Collision,
    /// Implicit penalization (eqs. 13, 27).
    Penalization,
    /// Baroclinic vorticity generation (eq. 28).
    Baroclinic,
    /// Particle push, stretching and remeshing (eqs. 29-30).
    Transport,
    /// Implicit diffusion.
    Diffusion,
    /// Velocity from vorticity (eq. 15).
    Poisson,
    /// Move the bodies.
    RigidUpdate,
    /// Clock, time step, global quantities, blow-up guard.
    Diagnostics,
    /// Empty: user systems that run after everything else.
    Last,
}

impl PhysicsSet {
    /// Every set, in schedule order.
    pub const ALL: [PhysicsSet; 13] = [
        PhysicsSet::First,
        PhysicsSet::LevelSets,
        PhysicsSet::Density,
        PhysicsSet::RigidVelocity,
        PhysicsSet::Collision,
        PhysicsSet::Penalization,
        PhysicsSet::Baroclinic,
        PhysicsSet::Transport,
        PhysicsSet::Diffusion,
        PhysicsSet::Poisson,
        PhysicsSet::RigidUpdate,
        PhysicsSet::Diagnostics,
        PhysicsSet::Last,
    ];
}

/// Label of the schedule that advances the simulation by one step.
#[derive(ScheduleLabel, Debug, Clone, PartialEq, Eq, Hash)]
pub struct Step;

/// Label of the schedule run once before the first step (velocity and first dt).
#[derive(ScheduleLabel, Debug, Clone, PartialEq, Eq, Hash)]
pub struct Startup;

fn configured(label: impl ScheduleLabel) -> Schedule {
    let mut s = Schedule::new(label);
    s.set_executor(SingleThreadedExecutor::new());
    s.set_build_settings(ScheduleBuildSettings {
        ambiguity_detection: LogLevel::Error,
        ..Default::default()
    });
    s
}

/// The step schedule with the built-in systems; the body systems are added when the scene
/// has bodies (a pure-fluid run does no body work at all).
pub fn step_schedule_with(bodies: bool) -> Schedule {
    let mut s = step_schedule();
    if bodies {
        s.add_systems(level_sets::level_sets.in_set(PhysicsSet::LevelSets));
        s.add_systems(density::density.in_set(PhysicsSet::Density));
        s.add_systems(rigid_velocity::rigid_velocity.in_set(PhysicsSet::RigidVelocity));
        s.add_systems(
            (collision::collision, collision::contact_impulse)
                .chain()
                .in_set(PhysicsSet::Collision),
        );
        s.add_systems(penalization::penalization.in_set(PhysicsSet::Penalization));
        s.add_systems(baroclinic::baroclinic.in_set(PhysicsSet::Baroclinic));
        s.add_systems(rigid_update::rigid_update.in_set(PhysicsSet::RigidUpdate));
    }
    s
}

/// The step schedule of vacuum mode (the flow solver off): level sets, contact, motion under
/// gravity and contact (`free_motion`, in the rigid-update set before `rigid_update`), rigid
/// update, diagnostics.
pub fn vacuum_schedule() -> Schedule {
    let mut s = configured(Step);
    for pair in PhysicsSet::ALL.windows(2) {
        s.configure_sets(pair[0].before(pair[1]));
    }
    s.add_systems(level_sets::level_sets.in_set(PhysicsSet::LevelSets));
    s.add_systems(collision::collision.in_set(PhysicsSet::Collision));
    s.add_systems(
        (free_motion::free_motion, rigid_update::rigid_update)
            .chain()
            .in_set(PhysicsSet::RigidUpdate),
    );
    s.add_systems(diagnostics::diagnostics.in_set(PhysicsSet::Diagnostics));
    s
}

/// The step schedule with the fluid systems.
pub fn step_schedule() -> Schedule {
    let mut s = configured(Step);
    // Chained once, in the order of `PhysicsSet::ALL`.
    for pair in PhysicsSet::ALL.windows(2) {
        s.configure_sets(pair[0].before(pair[1]));
    }
    s.add_systems(transport::transport.in_set(PhysicsSet::Transport));
    s.add_systems(diffusion::diffusion.in_set(PhysicsSet::Diffusion));
    s.add_systems(poisson::poisson.in_set(PhysicsSet::Poisson));
    s.add_systems(diagnostics::diagnostics.in_set(PhysicsSet::Diagnostics));
    s
}

/// The startup schedule: velocity from the initial vorticity, then the first time step.
pub fn startup_schedule() -> Schedule {
    let mut s = configured(Startup);
    s.add_systems((poisson::poisson, diagnostics::diagnostics_init).chain());
    s
}
