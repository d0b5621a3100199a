//! # poisson: velocity from vorticity (paper eq. 15, section 3.2)
//!
//! Solves Δψ = -ω and u = ∇×ψ (so ∇·u = 0 and ∇×u = ω) with real FFTs in the periodic box.
//! Derivatives are spectral, so a band-limited vorticity gives the exact velocity. In 3D the
//! vorticity is first made divergence-free (ω̂ ← ω̂ - k (k·ω̂)/|k|²) unless the diffusion
//! system already did so for the same vorticity. The mean (k = 0) velocity is the scene's
//! uniform background velocity. It replaces the mid-step velocity transport left in `u` (the
//! velocity before it is kept as the previous one, for the mid-step extrapolation in transport
//! and for ∂u/∂t in the baroclinic term).

use crate::base::fields::{Fields, Params, SimTime};
use crate::solvers::Spectral;
use bevy_ecs::prelude::*;

/// The Poisson system.
pub fn poisson(
    params: Res<Params>,
    time: Res<SimTime>,
    mut fields: ResMut<Fields>,
    mut spectral: ResMut<Spectral>,
) {
    let fields = &mut *fields;
    fields.dt_prev = time.dt;
    let (omega, u, version) = fields.same_version_parts();
    spectral.velocity(omega, version, params.background, u);
}

/// Velocity from vorticity: at startup in every run, every step in a fluid run.
#[derive(Debug, Clone, Copy, Default)]
pub struct PoissonPlugin;

impl crate::schedule::Plugin for PoissonPlugin {
    fn name(&self) -> &'static str {
        "poisson"
    }

    fn build(&self, ctx: &mut crate::schedule::PluginContext) -> anyhow::Result<()> {
        use crate::schedule::PhysicsSet;
        ctx.share_resource(|w| Spectral::new(w.resource::<crate::base::grid::Grid>()));
        ctx.add_startup_system_in(PhysicsSet::Poisson, "poisson", poisson)?;
        if ctx.mode().fluid() {
            ctx.add_system(PhysicsSet::Poisson, "poisson", poisson)?;
        }
        Ok(())
    }
}
