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

/// How a dynamic body's motion follows from the flow under `body_coupling: Pressure`, decided
/// once when the body is made ([`newton_euler`]); no scene setting.
#[derive(Component, Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum MotionLaw {
    /// The body is heavy (or light) fluid to the variable-density projection: its density is
    /// in ρ, and its rigid velocity is the density-weighted mean of the projected flow
    /// (`systems/rigid_velocity.rs`). Stable at any density ratio, but its drag is set by the
    /// smoothing band and the time step (issue 35: -7% at 20, -59% at 1000 times the fluid's
    /// density, +6.5% at 0.01). Taken with a free surface and for unbounded shapes.
    #[default]
    Projected,
    /// Newton-Euler with the body's own mass: the flow fills the body as fluid of the
    /// phases' density, held to the body by the no-slip at its surface markers
    /// (`systems/noslip.rs`), and the body's mass beyond that fluid, E, takes its weight less
    /// buoyancy, (E + M_v) (V^{n+1} - V^n) = E g Δt + M_v a^n Δt, and the markers' recoil
    /// within the no-slip's solve, with the virtual mass M_v ([`VirtualMass`]) that keeps
    /// that solve positive definite for a body lighter than the fluid.
    NewtonEuler,
}

/// How a dynamic body of density `density` moves in a fluid of density `rho_fluid` when the
/// no-slip runs (`body_coupling: Pressure` without a free surface), decided once when it is
/// made: by Newton-Euler with its own mass and the virtual mass [`VirtualMass`] its density
/// needs, whatever the density; `Projected` for an unbounded shape. `exact_volume` is
/// the shape's exact volume (0 when it has none: the volume sampled at half the grid spacing
/// `h` is taken).
pub fn newton_euler(
    level_set: &crate::bodies::levelset::LocalLevelSet,
    h: f64,
    dim: usize,
    density: f64,
    rho_fluid: f64,
    exact_volume: f64,
) -> (MotionLaw, VirtualMass) {
    match added_mass_bound(level_set, h, dim) {
        Some((sampled, _)) => {
            let volume = if exact_volume > 0.0 {
                exact_volume
            } else {
                sampled
            };
            (
                MotionLaw::NewtonEuler,
                VirtualMass::new(volume, density, rho_fluid),
            )
        }
        None => (MotionLaw::Projected, VirtualMass::default()),
    }
}

/// The volume V of a body's shape and the largest added mass per unit fluid density its
/// shape can have, from its reference level set sampled at half the grid spacing `h` (`dim` 2
/// or 3); `None` for an unbounded shape. The added mass of a body plus its displaced fluid is
/// at most that of a circle or sphere enclosing it (m_a + ρ_F V grows with the body), which
/// is 2 π R² in 2D and 1.5 (4/3) π R³ in 3D per unit density, R the longest semi-axis of the
/// body's equivalent ellipse or ellipsoid (the one with its volume and second moments).
pub fn added_mass_bound(
    level_set: &crate::bodies::levelset::LocalLevelSet,
    h: f64,
    dim: usize,
) -> Option<(f64, f64)> {
    let (lo, hi) = level_set.bounds()?;
    let s = 0.5 * h;
    let n = |a: usize| {
        if a < dim {
            ((hi[a] - lo[a]) / s).ceil() as usize + 1
        } else {
            1
        }
    };
    let (nx, ny, nz) = (n(0), n(1), n(2));
    // Volume, first and second moments of the inside (φ > 0), sharp, in body coordinates.
    let (mut v, mut m1, mut m2) = (0.0, DVec3::ZERO, glam::DMat3::ZERO);
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let p = DVec3::new(
                    lo.x + i as f64 * s,
                    lo.y + j as f64 * s,
                    if dim == 3 { lo.z + k as f64 * s } else { 0.0 },
                );
                if level_set.phi(p) > 0.0 {
                    v += 1.0;
                    m1 += p;
                    m2 += glam::DMat3::from_cols(p * p.x, p * p.y, p * p.z);
                }
            }
        }
    }
    if v == 0.0 {
        return None;
    }
    let c = m1 / v;
    // Second moments about the centroid, per unit volume.
    let cov = m2 * (1.0 / v) - glam::DMat3::from_cols(c * c.x, c * c.y, c * c.z);
    let cell = s.powi(dim as i32);
    let volume = v * cell;
    let (r2, bound) = if dim == 2 {
        // Ellipse: ∫x² / A = a²/4 along each principal axis.
        let (a, b, d) = (cov.x_axis.x, cov.y_axis.y, cov.x_axis.y);
        let top = 0.5 * (a + b) + (0.25 * (a - b) * (a - b) + d * d).sqrt();
        let r2 = 4.0 * top;
        (r2, 2.0 * std::f64::consts::PI * r2)
    } else {
        // Ellipsoid: ∫x² / V = a²/5 along each principal axis.
        let r2 = 5.0 * largest_eigenvalue(cov);
        (r2, 1.5 * 4.0 / 3.0 * std::f64::consts::PI * r2 * r2.sqrt())
    };
    (r2 > 0.0).then_some((volume, (bound - volume).max(0.0)))
}

/// The virtual mass M_v of a body moving by Newton-Euler under the no-slip
/// (`systems/noslip.rs`), and its inertia with it: Schwarz, Kempe & Fröhlich (J. Comput.
/// Phys. 281, 2015) add M_v dV/dt to both sides of the body's momentum balance, implicit on
/// the left and extrapolated from the last step on the right,
///   (E + M_v) (V^{n+1} - V^n) / Δt = F + M_v (V^n - V^{n-1}) / Δt_{n-1},
/// which leaves every steady motion as it was. E = m - ρ_F V is the body's mass beyond the
/// fluid inside it, which the no-slip's recoil divides by (the fluid inside and outside, its
/// added mass included, is implicit in the no-slip's solve): for a body lighter than the fluid
/// E is negative and the solve would not be positive definite. M_v is the least mass that
/// keeps E + M_v at least [`VIRTUAL_FLOOR`] ρ_F V: zero for a body at least 1.1 times as
/// dense as the fluid.
#[derive(Component, Debug, Clone, Copy, Default, PartialEq)]
pub struct VirtualMass {
    /// M_v, mass units.
    pub mass: f64,
    /// M_v per unit of the body's volume: its inertia is this times the body's unit-density
    /// inertia.
    pub per_volume: f64,
}

/// The least E + M_v of a Newton-Euler body, in units of the fluid mass it displaces.
pub const VIRTUAL_FLOOR: f64 = 0.1;

impl VirtualMass {
    /// The virtual mass of a body of volume `volume` and density `density` in a fluid of
    /// density `rho_fluid`.
    pub fn new(volume: f64, density: f64, rho_fluid: f64) -> Self {
        let e = (density - rho_fluid) * volume;
        let mass = (VIRTUAL_FLOOR * rho_fluid * volume - e).max(0.0);
        VirtualMass {
            mass,
            per_volume: if volume > 0.0 { mass / volume } else { 0.0 },
        }
    }
}

/// The largest eigenvalue of a symmetric 3x3 matrix (closed form, trigonometric).
fn largest_eigenvalue(a: glam::DMat3) -> f64 {
    let (a11, a22, a33) = (a.x_axis.x, a.y_axis.y, a.z_axis.z);
    let (a12, a13, a23) = (a.y_axis.x, a.z_axis.x, a.z_axis.y);
    let p1 = a12 * a12 + a13 * a13 + a23 * a23;
    if p1 == 0.0 {
        return a11.max(a22).max(a33);
    }
    let q = (a11 + a22 + a33) / 3.0;
    let p2 = (a11 - q).powi(2) + (a22 - q).powi(2) + (a33 - q).powi(2) + 2.0 * p1;
    let p = (p2 / 6.0).sqrt();
    let b = (a - glam::DMat3::from_diagonal(DVec3::splat(q))) * (1.0 / p);
    let r = (0.5 * b.determinant()).clamp(-1.0, 1.0);
    q + 2.0 * p * (r.acos() / 3.0).cos()
}
