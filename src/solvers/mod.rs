//! Solvers on the periodic grid: the FFT engine ([`fft`]: plans, scratch, transforms) and the
//! spectral operators built on it ([`operators`]: Poisson, implicit diffusion, divergence
//! cleaning). Depends only on [`crate::base`].

pub mod fft;
pub mod multigrid;
pub mod operators;
pub mod variable_poisson;

pub use operators::{Spectral, TopDamping, max_norm};
