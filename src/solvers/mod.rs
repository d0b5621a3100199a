//! Solvers on the periodic grid: the FFT engine and the spectral operators built on it
//! (Poisson, implicit diffusion, curl). Depends only on [`crate::base`].

pub mod spectral;
