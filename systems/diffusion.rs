//! # diffusion: implicit viscous diffusion of the vorticity (paper section 3.2, eq. 29)
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

use crate::base::fields::{Fields, Params, SimTime};
use crate::solvers::Spectral;
use bevy_ecs::prelude::*;

/// The diffusion system (skipped for an inviscid fluid; the Poisson solve then cleans the
/// divergence itself).
pub fn diffusion(
    params: Res<Params>,
    time: Res<SimTime>,
    mut fields: ResMut<Fields>,
    mut spectral: ResMut<Spectral>,
) {
    if params.nu == 0.0 {
        return;
    }
    let (omega, _, version) = fields.next_version_parts();
    spectral.diffuse(omega, params.nu * time.dt, version);
}

/// Implicit diffusion (a fluid run).
#[derive(Debug, Clone, Copy, Default)]
pub struct DiffusionPlugin;

impl crate::schedule::Plugin for DiffusionPlugin {
    fn name(&self) -> &'static str {
        "diffusion"
    }

    fn build(&self, ctx: &mut crate::schedule::PluginContext) -> anyhow::Result<()> {
        use crate::schedule::PhysicsSet;
        ctx.share_resource(|w| Spectral::new(w.resource::<crate::base::grid::Grid>()));
        if ctx.mode().fluid() {
            ctx.add_system(PhysicsSet::Diffusion, "diffusion", diffusion)?;
        }
        Ok(())
    }
}
