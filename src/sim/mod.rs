//! The simulation: the world built from a validated scene, the schedule, initial conditions.

pub mod build;
pub mod engine;
pub mod init;
pub mod schedule;
