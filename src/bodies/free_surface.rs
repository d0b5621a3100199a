//! The free surface's data: the entity component of an air/water (gas/liquid) interface and
//! its level set on the flow grid. The systems that move it are in `systems/free_surface.rs`.
//!
//! φ_w > 0 in the liquid, < 0 in the gas; within `band` of the surface it is kept a signed
//! distance, beyond it is clipped to ±band. The density of the fluid phases is
//! ρ_P = ρ_gas + (ρ_liquid - ρ_gas) H_ε(φ_w) (written into `BodyFields::rho_phase`), the same
//! smoothed Heaviside as the bodies' χ.

use bevy_ecs::prelude::*;
use serde::{Deserialize, Serialize};

/// A free surface between a liquid and a gas (one entity per free surface).
#[derive(Component, Debug, Clone, PartialEq)]
pub struct FreeSurface {
    /// Density of the liquid (φ_w > 0), mass per volume: the scene's `fluid.density`.
    pub liquid_density: f64,
    /// Density of the gas (φ_w < 0), mass per volume.
    pub gas_density: f64,
}

/// The liquid's level set φ_w at the grid nodes, and its volume bookkeeping (checkpointed).
#[derive(Resource, Debug, Clone, Default, Serialize, Deserialize)]
pub struct LiquidLevelSet {
    /// φ_w per node (> 0 in the liquid), length.
    pub phi: Vec<f64>,
    /// Half-width of the band where φ_w is a signed distance, length; |φ_w| ≤ band.
    pub band: f64,
    /// The liquid volume the surface keeps, ∫(1 - χ)H_ε(φ_w) dV at t = 0 over the fluid outside
    /// the walls and bodies (length^d: an area in 2D).
    pub target_volume: f64,
    /// The liquid volume ∫(1 - χ)H_ε(φ_w) dV after the last step, length^d.
    pub volume: f64,
    /// The interface area ∫(1 - χ)δ_ε(φ_w) dV after the last step, length^(d-1).
    pub area: f64,
}
