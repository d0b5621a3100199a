//! The physics systems, one file each, in schedule order (see `crate::schedule`).
//!
//! Each file opens with the equation it implements and the paper's equation number
//! (Coquerelle & Cottet, J. Comput. Phys. 227 (2008)).

pub mod diagnostics;
pub mod diffusion;
pub mod poisson;
pub mod transport;
