//! The physics systems, one file each. The order they run in is stated once, by the sets
//! they are added to: [`crate::schedule::PhysicsSet::ALL`].
//!
//! Each file opens with the equation it implements and the paper's equation number
//! (Coquerelle & Cottet, J. Comput. Phys. 227 (2008)), and ends with its plugin: the
//! resources it needs, its systems and their sets. [`builtin`] lists them all, once. No file
//! here uses another (`tests/suite/layers.rs` checks it): what two systems share lives in a
//! lower layer ([`crate::solvers`], [`crate::bodies`], [`crate::base`]).
//!
//! A new system is one file here and one line in [`builtin`] (or, outside the crate, one
//! `Simulation::builder(scene).add_plugin(..)` call; see `examples/passive_scalar.rs`).

use crate::schedule::Plugin;

pub mod baroclinic;
pub mod collision;
pub mod density;
pub mod diagnostics;
pub mod diffusion;
pub mod free_motion;
pub mod free_surface;
pub mod level_sets;
pub mod noslip;
pub mod penalization;
pub mod poisson;
pub mod pressure;
pub mod rigid_update;
pub mod rigid_velocity;
pub mod transport;

/// The built-in plugins; each decides from the run's [`crate::schedule::Mode`] which of its
/// systems a run needs. The order of this list is the order they are built in (of their
/// resources and checkpoint records), not the order their systems run in: each built-in set
/// holds one plugin's systems.
pub fn builtin() -> Vec<Box<dyn Plugin>> {
    vec![
        Box::new(level_sets::LevelSetsPlugin),
        Box::new(free_surface::FreeSurfacePlugin),
        Box::new(density::DensityPlugin),
        Box::new(rigid_velocity::RigidVelocityPlugin),
        Box::new(collision::CollisionPlugin),
        Box::new(penalization::PenalizationPlugin),
        Box::new(baroclinic::BaroclinicPlugin),
        Box::new(pressure::PressurePlugin),
        Box::new(transport::TransportPlugin),
        Box::new(diffusion::DiffusionPlugin),
        Box::new(poisson::PoissonPlugin),
        Box::new(noslip::NoSlipPlugin),
        Box::new(free_motion::FreeMotionPlugin),
        Box::new(rigid_update::RigidUpdatePlugin),
        Box::new(diagnostics::DiagnosticsPlugin),
    ]
}
