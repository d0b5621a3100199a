//! The integration tests, one binary (one link instead of one per file). Separate binaries:
//! `hdf5.rs` and `checkpoint.rs` (the `hdf5` feature's run builds them alone) and `alloc.rs`
//! (its counting allocator wraps the whole process).
//! Run one file's tests with `cargo test --release --test suite NAME::`.

mod bodies;
mod carry;
mod check_summary;
mod cli;
mod common;
mod compressed;
mod contact;
mod contact_units;
mod cup_mesh;
mod dam_break;
mod determinism;
mod distributed;
mod example_plugin;
mod free_surface_output;
mod generators;
mod kernels;
mod layers;
mod motion_law;
mod multigrid;
mod output;
mod periodic_bodies;
mod plot;
mod readme;
mod reports;
mod scene_errors;
mod scene_fuzz;
mod scenes;
mod schedule;
mod shapes;
mod spectral;
mod stretching;
mod surfaces;
mod timestep;
mod validation;
mod vti;
