//! tumble: an incompressible viscous fluid two-way coupled with colliding rigid bodies, by the
//! vortex level set method of Coquerelle & Cottet (J. Comput. Phys. 227, 2008).
//!
//! The engine is a `bevy_ecs` world: dense grids are resources, the physics steps are systems
//! in one explicit schedule ([`schedule`]), one file per system in `systems/`.

// Numerical kernels index several arrays with one loop variable; iterators would obscure them.
#![allow(clippy::needless_range_loop)]

pub mod bodies;
pub mod checkpoint;
pub mod engine;
pub mod fields;
pub mod grid;
#[cfg(feature = "hdf5")]
pub mod hdf5_out;
pub mod init;
pub mod kernels;
pub mod levelset;
pub mod output;
pub mod overlap;
pub mod plot;
pub mod run;
pub mod runlog;
pub mod scene;
pub mod schedule;
pub mod shapes;
pub mod snapshots;
pub mod spectral;
pub mod validate;
pub mod xdmf;

#[path = "../systems/mod.rs"]
pub mod systems;
