//! # diffusion: implicit viscous diffusion of the vorticity (paper section 3.2, eq. 29), and the
//! dissipation of the grid scale in 3D
//!
//! Solves (I - ν Δt ∆) ω^{n+1} = ω* (implicit Euler) with ∆ the spectral Laplacian of the
//! periodic grid, symbol -|k|² (Nyquist included): the same operator the velocity solve
//! inverts, so the solve is one multiplication per mode. The second-order 5/7-point
//! Laplacian used before, symbol -Σ_a (2 - 2 cos(k_a h))/h², is 8% weaker at k h = 1 and left the small
//! scales decaying too slowly: TG3D at Re 1600, E(5) +0.64% at 64³ with it against +0.33% with
//! |k|² (reference 0.1184). (The exact factor exp(-ν|k|²Δt) was tried too: the same on TG3D,
//! but it removes the grid-scale vorticity the penalization puts at a body's surface within
//! one step, and a sphere settling at 3.2 cells per radius went from -0.6% to -5.9% of
//! Hasimoto's velocity at density 2.) In 3D the same pass
//! removes the divergence of ω (ω̂ ← ω̂ - k (k·ω̂)/|k|²). The transform of the result is left
//! in the spectral solver for the Poisson system, which then needs no forward transform.
//!
//! ## The grid scale in 3D
//!
//! In 3D the same pass also damps the top of the resolved spectrum,
//!
//!   ∂ω̂/∂t = -σ(k) ω̂,   σ(k) = C_s² π² S (|k|/k_N)^{2p},   ω̂ ← ω̂ exp(-Δt σ(k)),
//!
//! with k_N = π/h the Nyquist wavenumber of one axis, S = max|ω| the flow's largest rate of
//! rotation (a bound on its strain rate where the strain is a shear), C_s = 0.17 the
//! Smagorinsky constant and p = [`ORDER`]. At |k| = k_N this is exactly the Smagorinsky eddy
//! viscosity (C_s h)² S times |k|²; below, the weight (|k|/k_N)^{2p-2} confines it to the top
//! of the spectrum (at p = 8 a mode at |k| = k_N/2 is damped 2·10⁻⁵ times as fast), and beyond
//! it, in the corners of the cube of resolved wavenumbers that no direction resolves (up to
//! |k| = √3 k_N), it removes what is there within a step (a spectral vanishing viscosity,
//! Tadmor 1989, with the strength of a subgrid model;
//! the variational multiscale idea of acting on the small scales only, Hughes et al. 2001,
//! Jeanmart & Winckelmans 2007). It is a rate per unit time applied exactly, so what it does to
//! a given state over an interval does not depend on Δt, except where it saturates within a
//! step in those corners (see [`ORDER`]); the state itself does depend on Δt through the M'4
//! remesh's own grid-scale damping, O(δ²) per step (docs/numerics.md). It has no user setting.
//!
//! Why: at cell Reynolds numbers in the hundreds (a body in water, ν = 1e-4 cgs) nothing else
//! removes what the stretching and the penalization put at the grid scale where particles
//! barely move (the M'4 remesh dissipates only in proportion to the displacement). Measured
//! without it (issue 32): a sphere of density 1.2 at rest on the floor of a closed 64³ water
//! box blew up at t = 0.18 with node-to-node alternating vorticity next to it, and the same
//! sphere blew up in mid-fall in an open periodic box at t = 0.198; with it both run to the end.
//! In 2D there is no stretching and no forward energy cascade, and nothing is damped.
//!
//! ## The momentum form
//!
//! With a free surface the carried field is the velocity (`transport`'s momentum form): each of
//! its components is diffused the same way, (I - ν Δt ∆) u^{n+1} = ũ, and in 3D damped by the
//! same grid-scale factor, with no divergence removed (the variable-density projection of the
//! next step makes it divergence-free). The viscosity is kinematic and uniform, ν in both
//! phases (the paper's choice for the cup). In momentum form the grid scale is damped in 2D
//! too: the projection works on the nodes (its divergence and gradient are centred), so a
//! node-to-node alternating velocity is in its null space and nothing else removes it. Measured
//! (issue 44): a collapsing column at 1:1000 and h = a/64 grew such noise in the gas's shear
//! layer above the liquid from t = 1.55 and its kinetic energy went from 0.046 to 3.6 by
//! t = 1.90 (the step down to 1.3e-4); with the damping it stays at 0.07-0.08 to t = 2.3.

use crate::base::fields::{Fields, Params, SimTime};
use crate::solvers::{Spectral, TopDamping};
use bevy_ecs::prelude::*;
use serde::{Deserialize, Serialize};

/// The Smagorinsky constant C_s of the grid-scale dissipation (Lilly's value for isotropic
/// turbulence).
pub const SMAGORINSKY: f64 = 0.17;

/// Half the power p of |k|/k_N in the grid-scale dissipation's weight (|k|/k_N)^{2p}.
/// Measured on the Re = 1600 Taylor-Green vortex (E(5) against 0.1184; +0.329% at 64³ and
/// +0.068% at 128³ without the dissipation): p = 4 gave -0.587% and +0.009%, p = 8 gives
/// -0.338% and +0.013%; both held the two spheres of issue 32. The weight is of |k|, so the
/// corners of the cube of wavenumbers (up to |k| = √3 k_N) are damped up to 3^p times as fast
/// as an axis's Nyquist mode, and in a step whatever its length: the node-to-node alternating
/// noise of issue 32 lives there. A weight summed per axis, Σ_a (k_a/k_N)^{2p}, which damps no
/// mode faster than three times the Nyquist rate (so per unit time at any step), let the
/// closed-box sphere blow up at t = 0.227; the price of the |k| form is that it acts per step
/// on what the penalization puts in those corners at every step (`dt-independence` at
/// h = 1/32: a shortened step moves the sphere by 4.2% instead of 0.65%; 1.1% per axis).
pub const ORDER: i32 = 8;

/// What the grid-scale dissipation did, for diagnostics; a resource kept across a restart.
#[derive(Resource, Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct GridScaleDissipation {
    /// Kinetic energy per unit volume it removed since the start of the run.
    pub removed: f64,
}

/// The rate at |k| = k_N of the grid-scale dissipation for a flow whose largest vorticity is
/// `max_omega`: C_s² π² max|ω|.
pub fn grid_scale_rate(max_omega: f64) -> f64 {
    SMAGORINSKY * SMAGORINSKY * std::f64::consts::PI * std::f64::consts::PI * max_omega
}

/// The diffusion system (skipped for an inviscid 2D fluid; the Poisson solve then cleans the
/// divergence itself).
pub fn diffusion(
    params: Res<Params>,
    time: Res<SimTime>,
    mut fields: ResMut<Fields>,
    mut spectral: ResMut<Spectral>,
    mut gsd: ResMut<GridScaleDissipation>,
    split: Option<Res<crate::parallel::Decomposition>>,
) {
    let three_d = fields.omega().len() == 3;
    let momentum = params.momentum_form();
    if params.nu == 0.0 && !three_d && !momentum {
        return;
    }
    let damp = if three_d || momentum {
        TopDamping {
            strength: grid_scale_rate(crate::parallel::global_max(
                split.as_deref(),
                crate::solvers::max_norm(fields.omega()),
            )) * time.dt,
            order: ORDER,
        }
    } else {
        TopDamping::NONE
    };
    if params.momentum_form() {
        gsd.removed += spectral.diffuse_components(&mut fields.u, params.nu * time.dt, damp);
        return;
    }
    let (omega, _, version) = fields.next_version_parts();
    gsd.removed += spectral.diffuse(omega, params.nu * time.dt, damp, version);
}

/// Implicit diffusion and the grid-scale dissipation (a fluid run).
#[derive(Debug, Clone, Copy, Default)]
pub struct DiffusionPlugin;

impl crate::schedule::Plugin for DiffusionPlugin {
    fn name(&self) -> &'static str {
        "diffusion"
    }

    fn build(&self, ctx: &mut crate::schedule::PluginContext) -> anyhow::Result<()> {
        use crate::schedule::PhysicsSet;
        ctx.share_resource(|w| {
            Spectral::of_grid(
                w.resource::<crate::base::grid::Grid>(),
                w.get_resource::<crate::parallel::Decomposition>(),
            )
        });
        if ctx.mode().fluid() {
            ctx.insert_resource(GridScaleDissipation::default());
            ctx.checkpoint_resource::<GridScaleDissipation>("grid_scale_dissipation", 1)?;
            ctx.add_system(PhysicsSet::Diffusion, "diffusion", diffusion)?;
        }
        Ok(())
    }
}
