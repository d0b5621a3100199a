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
/// once when the body is made, from its density and shape ([`motion_law`]); no scene setting.
#[derive(Component, Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum MotionLaw {
    /// The body is heavy fluid to the variable-density projection: its density is in ρ, and
    /// its rigid velocity is the density-weighted mean of the projected flow
    /// (`systems/rigid_velocity.rs`). Stable at any density ratio; its drag grows with the
    /// density (issue 35: -7% at 20, -59% at 1000 times the fluid's).
    #[default]
    Projected,
    /// Newton-Euler with the body's own mass: the projection sees fluid of the phases'
    /// density inside the body, and the body's mass beyond the fluid it displaces takes the
    /// fluid's impulse on its rigid region and its own weight less buoyancy,
    /// (M_w + E) (V^{n+1} - V^n) = M_w (ũ - V^n) + E g Δt. Explicit in the added mass of the
    /// fluid outside, so only for bodies heavy enough for their shape.
    NewtonEuler,
}

/// Whether a dynamic body of density `density` moves by Newton-Euler in a fluid of density
/// `rho_fluid` (the liquid's with a free surface): when its own mass is at least twice the
/// largest added mass its shape can have. The lagged added mass m_a of the fluid outside the
/// body, against the body's mass m, makes the explicit update amplify an error by m_a / m per
/// step; the added mass of a body plus its displaced fluid is at most that of a circle or
/// sphere enclosing it (m_a + ρ_F V grows with the body), which is 2 ρ_F π R² in 2D and
/// 1.5 ρ_F (4/3) π R³ in 3D. R is the longest semi-axis of the body's equivalent ellipse or
/// ellipsoid (the one with its volume and second moments), from its reference level set
/// sampled at half the grid spacing `h` (`dim` 2 or 3): a sphere moves by Newton-Euler from
/// density 1 (m_a = V/2), a disk from 2 (m_a = A), an ellipse of aspect ratio 10 from about 38
/// (its broadside added mass is ten times its own fluid's). Unbounded shapes stay `Projected`.
pub fn motion_law(
    level_set: &crate::bodies::levelset::LocalLevelSet,
    h: f64,
    dim: usize,
    density: f64,
    rho_fluid: f64,
) -> MotionLaw {
    let Some((lo, hi)) = level_set.bounds() else {
        return MotionLaw::Projected;
    };
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
        return MotionLaw::Projected;
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
    let added = (rho_fluid * (bound - volume)).max(0.0);
    if r2 > 0.0 && density * volume >= 2.0 * added {
        MotionLaw::NewtonEuler
    } else {
        MotionLaw::Projected
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
