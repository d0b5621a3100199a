//! # diffusion: implicit viscous diffusion of the vorticity (paper section 3.2, eq. 29)
//!
//! Solves (I - ν Δt Δ_h) ω^{n+1} = ω* with Δ_h the classical second-order 5-point (2D) or
//! 7-point (3D) Laplacian. In the periodic box Δ_h is diagonal in Fourier space, with symbol
//! -Σ_a (2 - 2 cos(k_a h))/h², so the solve is one multiplication per mode. In 3D the same pass
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
