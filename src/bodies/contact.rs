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
    /// κ of a pair whose bodies do not give their own (the scene's `contact.kappa` unset).
    pub default: KappaDefault,
}

impl ContactParams {
    /// κ of the pair (a, b) given the bodies' own values (`None`: the pair's default).
    pub fn kappa(&self, a: usize, b: usize, ka: Option<f64>, kb: Option<f64>) -> f64 {
        let key = (a.min(b), a.max(b));
        match self.pairs.binary_search_by(|p| (p.0, p.1).cmp(&key)) {
            Ok(i) => self.pairs[i].2,
            Err(_) => self.unnamed_kappa(a, b, ka, kb),
        }
    }

    /// κ of the pair (a, b) if `pairs` does not name it: the mean of the bodies' own values,
    /// the pair's default standing in for a missing one.
    pub fn unnamed_kappa(&self, a: usize, b: usize, ka: Option<f64>, kb: Option<f64>) -> f64 {
        match (ka, kb) {
            (Some(ka), Some(kb)) => 0.5 * (ka + kb),
            _ => {
                let d = self.default.pair(a, b);
                0.5 * (ka.unwrap_or(d) + kb.unwrap_or(d))
            }
        }
    }
}

/// The dimensionless factor C of the default κ = C L² a (see [`KappaDefault`]): 3 in 3D, 2 in
/// 2D. Measured with a body dropped in vacuum on a flat floor (`tests/suite/contact_units.rs` has
/// the scene): with a = |g| a body resting on the floor holds its weight at a gap of about
/// ε/2 (3D: 0.43 ε at r = 3.2 ε, 0.51 ε at 16 ε, by quadrature of the continuous model; 2D:
/// 0.48 ε at r = 5 ε, 1.07 ε at 32 ε, a disk's line contact growing stiffer as ε shrinks), and
/// with a = U²/ε a body arriving at speed U stops at a gap of 0.6 ε (3D) to 1.0 ε (2D), the
/// same for drops of 4 ε to 64 ε.
pub fn default_kappa_factor(dim: usize) -> f64 {
    if dim == 2 { 2.0 } else { 3.0 }
}

/// The equivalent radius of a body of area (2D) or volume (3D) `size`: that of the disk or
/// ball of the same size, length.
pub fn equivalent_radius(size: f64, dim: usize) -> f64 {
    if dim == 2 {
        (size / std::f64::consts::PI).sqrt()
    } else {
        (0.75 * size / std::f64::consts::PI).cbrt()
    }
}

/// The default κ of the pairs of a scene that leaves `contact.kappa` unset (the scene format
/// documents it; `scene/kappa.rs` reads its scales from the scene): κ = C L² a, length³/time²,
/// with C the factor of [`default_kappa_factor`], L the equivalent radius of the pair's
/// smaller bounded dynamic body, and a = max(|g|, U²/ε) the acceleration the contact must hold
/// or absorb: the weight of a resting body, or a body arriving at speed U stopped within ε.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct KappaDefault {
    /// C, dimensionless.
    pub factor: f64,
    /// |g|, length/time².
    pub gravity: f64,
    /// U, length/time: the fastest a body can meet another.
    pub speed: f64,
    /// ε, length.
    pub eps: f64,
    /// Per body id: the equivalent radius of a bounded dynamic body, length; ∞ for the others
    /// (static, kinematic, unbounded), which leave the scale to the body they push.
    pub lengths: Vec<f64>,
}

impl KappaDefault {
    /// a = max(|g|, U²/ε), length/time².
    pub fn acceleration(&self) -> f64 {
        let impact = if self.eps > 0.0 {
            self.speed * self.speed / self.eps
        } else {
            0.0
        };
        self.gravity.max(impact)
    }

    /// The default κ of the pair (a, b), length³/time²: 0 if neither is a bounded dynamic
    /// body.
    pub fn pair(&self, a: usize, b: usize) -> f64 {
        let l = |i: usize| self.lengths.get(i).copied().unwrap_or(f64::INFINITY);
        let l = l(a).min(l(b));
        if l.is_finite() {
            self.factor * l * l * self.acceleration()
        } else {
            0.0
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

/// (ρJ)⁻¹ of a body of density `rho` in state `s` (J from χ; see
/// [`crate::bodies::integrals::inertia_inverse`]).
pub fn inverse_inertia(dim: usize, rho: f64, s: &crate::bodies::RigidState) -> glam::DMat3 {
    crate::bodies::integrals::inertia_inverse(dim, rho * s.inertia)
}

/// The change of velocity and angular velocity the step's contact force and torque give a
/// body of density `rho` over `dt`: F Δt/m and (ρJ)⁻¹ T Δt with the mass and inertia of χ
/// (zero for an empty body).
pub fn contact_velocity_change(
    dim: usize,
    rho: f64,
    state: &crate::bodies::RigidState,
    contact: &crate::bodies::ContactState,
    dt: f64,
) -> (glam::DVec3, glam::DVec3) {
    let m = rho * state.volume;
    if m <= 0.0 {
        return (glam::DVec3::ZERO, glam::DVec3::ZERO);
    }
    (
        dt * contact.force / m,
        dt * (inverse_inertia(dim, rho, state) * contact.torque),
    )
}
