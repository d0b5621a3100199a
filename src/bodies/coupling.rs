//! What the variable-density pressure projection carries from one step to the next
//! ([`PressureState`], kept in a checkpoint): written by the pressure system
//! (`systems/pressure.rs`, which explains it), read by the rigid velocity
//! (`systems/rigid_velocity.rs`): a dynamic body's mass beyond the fluid's keeps the momentum
//! the last projection gave it.

use bevy_ecs::prelude::*;
use glam::DVec3;

/// The momentum a dynamic body's mass beyond the fluid's had at the end of the last step's
/// projection, per unit of that mass: it travels with the body to the next step.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ExcessMomentum {
    /// Its mean velocity, ∫(ρ - ρ_P) w ũ / ∫(ρ - ρ_P) w.
    pub velocity: DVec3,
    /// Its angular momentum about its own centroid per unit mass,
    /// ∫(ρ - ρ_P) w r × ũ / ∫(ρ - ρ_P) w.
    pub spin: DVec3,
}

/// What the pressure projection carries from one step to the next (checkpointed): the last
/// potential (the warm start) and the momentum of each dynamic body's excess mass.
#[derive(Resource, Debug, Clone, Default, serde::Serialize, serde::Deserialize)]
pub struct PressureState {
    /// Δt p' of the last solve (periodic part), per node.
    pub phi: Vec<f64>,
    /// Per body (indexed by `Body::id`; `None` for the others and before the first
    /// projection): the momentum of its mass beyond the fluid's, from ũ = u + the projected
    /// increments over the region its penalization moved (see `systems/pressure.rs`).
    /// Split by the sign of ρ - ρ_P: [the part heavier than the fluid phase, the lighter
    /// part], each a mean over a weight of one sign. (One mean over the whole excess mass
    /// divides by ∫(ρ - ρ_P) w, which passes through zero for a body floating at its
    /// waterline: a floating box's rigid velocity jumped to 1e4 in one step.)
    pub excess: Vec<Option<[ExcessMomentum; 2]>>,
}
