//! Core data: the grid, the dense fields, the interpolation kernels and the typed numerical
//! parameters. Knows nothing of bodies, solvers, scenes, files or the command line.

pub mod fields;
pub mod grid;
pub mod kernels;
pub mod params;
pub mod pool;
