//! The validation cases, one file each: every file exports its [`Case`](super::Case) as
//! `CASE`, its description, references, tolerances and known failures beside its code.

pub mod added_mass;
pub mod column_collapse;
mod common;
pub mod cup;
pub mod dkt;
pub mod dt_independence;
pub mod ellipsoid_sphere;
pub mod floating;
pub mod high_re_sphere;
pub mod kleefsman;
pub mod lamb_oseen;
pub mod periodic_array;
pub mod poisson;
pub mod pool_drop;
pub mod rayleigh_taylor;
pub mod rebound_vacuum;
pub mod remesh;
pub mod sedimentation_2d;
pub mod sphere_settling;
pub mod standing_wave;
pub mod still_pool;
pub mod stokes_settling;
pub mod stratified_rest;
pub mod tank_pile;
pub mod tank_vacuum;
pub mod taylor_green_2d;
pub mod taylor_green_3d;
