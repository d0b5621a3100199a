//! Solvers on the periodic grid: the FFT engine ([`fft`]: plans, scratch, transforms), the
//! operators built on it ([`operators`]: Poisson, implicit diffusion, divergence cleaning, the
//! centred curl), the variable-density Poisson solver ([`variable_poisson`], [`multigrid`]) and
//! the particle push-and-remesh sweep along one axis ([`sweep`]). Depends only on
//! [`crate::base`].

pub mod carry;
pub mod fft;
pub mod multigrid;
pub mod operators;
pub mod sweep;
pub mod variable_poisson;

pub use operators::{Spectral, TopDamping, max_norm};
