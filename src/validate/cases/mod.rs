//! The validation cases, one file each: every file exports its [`Case`](super::Case) as
//! `CASE`, its description, references, tolerances and known failures beside its code.

pub mod added_mass;
pub(super) mod common;
pub mod dt_independence;
pub mod lamb_oseen;
pub mod poisson;
pub mod remesh;
pub mod sedimentation_2d;
pub mod sphere_settling;
pub mod stokes_settling;
pub mod stratified_rest;
pub mod taylor_green_2d;
pub mod taylor_green_3d;
