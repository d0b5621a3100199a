//! The simulation: the world built from a validated scene, initial conditions.

pub mod build;
pub mod engine;
pub mod init;
