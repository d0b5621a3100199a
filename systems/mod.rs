//! The physics systems, one file each, in schedule order (see `sim::schedule`).
//!
//! Each file opens with the equation it implements and the paper's equation number
//! (Coquerelle & Cottet, J. Comput. Phys. 227 (2008)).

pub mod baroclinic;
pub mod collision;
pub mod density;
pub mod diagnostics;
pub mod diffusion;
pub mod free_motion;
pub mod level_sets;
pub mod penalization;
pub mod poisson;
pub mod rigid_update;
pub mod rigid_velocity;
pub mod transport;
