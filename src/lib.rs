//! tumble: an incompressible viscous fluid two-way coupled with colliding rigid bodies, by the
//! vortex level set method of Coquerelle & Cottet (J. Comput. Phys. 227, 2008).
//!
//! The engine is a `bevy_ecs` world: dense grids are resources, the physics steps are systems
//! in one explicit schedule ([`schedule`]), one file per system in `systems/`.
//!
//! The modules are layers; each uses only the ones above it in this list (a test checks it):
//! - [`base`]: grid, fields, kernels, typed parameters;
//! - [`parallel`]: the slab decomposition and the communicator (MPI or one process): all-to-all
//!   transposes, halo exchanges, reductions;
//! - [`solvers`]: the FFT engine, the spectral operators, the curl, the particle line sweeps;
//! - [`bodies`]: shapes, level sets, body components, the integrals over a body, the contact
//!   kernel;
//! - [`schedule`]: the named sets of a step, the plugin interface, timing, checkpoint state;
//! - [`systems`]: the physics systems (one file each, in `systems/`; none uses another: what
//!   two share sits in a lower layer);
//! - [`scene`]: the RON scene format and its validation;
//! - [`sim`]: the world built from a validated scene, the engine;
//! - [`io`]: snapshots, checkpoints, log, plots;
//! - [`run`] and [`validate`]: the run driver and the validation cases;
//! - [`cli`]: the command line, which the `tumble` binary and a user's own binary (with its
//!   plugins) both call.

// Numerical kernels index several arrays with one loop variable; iterators would obscure them.
#![allow(clippy::needless_range_loop)]

pub mod base;
pub mod bodies;
pub mod cli;
pub mod io;
pub mod parallel;
pub mod run;
pub mod scene;
pub mod schedule;
pub mod sim;
pub mod solvers;
#[path = "../systems/mod.rs"]
pub mod systems;
pub mod validate;
