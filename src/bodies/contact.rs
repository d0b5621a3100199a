//! The level-set contact model's data: its parameters and the cut-off profile ζ (paper
//! eqs. 20-22). The force itself is computed by `systems/collision.rs`.

use bevy_ecs::prelude::*;

/// Contact parameters of the scene.
#[derive(Resource, Debug, Clone)]
pub struct ContactParams {
    /// Range ε of the repulsion (length).
    pub eps: f64,
    /// Cut-off distance in units of ε.
    pub range: f64,
    /// κ for named pairs: (smaller id, larger id, κ), sorted.
    pub pairs: Vec<(usize, usize, f64)>,
    /// Evaluate the force at the poses the bodies will have at the end of the step if they
    /// keep their velocities (with the flow on), instead of at the current poses (vacuum).
    pub predict: bool,
}

impl ContactParams {
    /// κ of the pair (a, b) given the bodies' own values.
    pub fn kappa(&self, a: usize, b: usize, ka: f64, kb: f64) -> f64 {
        let key = (a.min(b), a.max(b));
        match self.pairs.binary_search_by(|p| (p.0, p.1).cmp(&key)) {
            Ok(i) => self.pairs[i].2,
            Err(_) => 0.5 * (ka + kb),
        }
    }
}

/// The one-sided cut-off ζ(s) = 1 - cos 2πs on (0, 1), zero elsewhere; ∫ζ = 1.
#[inline]
pub fn zeta(s: f64) -> f64 {
    if s <= 0.0 || s >= 1.0 {
        0.0
    } else {
        1.0 - (2.0 * std::f64::consts::PI * s).cos()
    }
}
