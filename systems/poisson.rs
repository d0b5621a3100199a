//! # poisson: velocity from vorticity (paper eq. 15, section 3.2)
//!
//! Solves Δψ = -ω and u = ∇×ψ (so ∇·u = 0 and ∇×u = ω) with real FFTs in the periodic box.
//! Derivatives are spectral, so a band-limited vorticity gives the exact velocity. In 3D the
//! vorticity is first made divergence-free (ω̂ ← ω̂ - k (k·ω̂)/|k|²) unless the diffusion
//! system already did so for the same vorticity. The mean (k = 0) velocity is the scene's
//! uniform background velocity. It replaces the mid-step velocity transport left in `u` (the
//! velocity before it is kept as the previous one, for the mid-step extrapolation in transport
//! and for ∂u/∂t in the baroclinic term).
//!
//! In momentum form (a free surface) the velocity is carried, not solved for: this step then
//! only takes the vorticity of it, ω = ∇×u by centred differences, for the time step, the
//! grid-scale dissipation's rate, the diagnostics and the output.

use crate::base::fields::{Fields, Params, SimTime};
use crate::solvers::Spectral;
use bevy_ecs::prelude::*;
use rayon::prelude::*;

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

/// The momentum form's step: ω = ∇×u (centred differences) of the carried velocity.
pub fn vorticity(
    grid: Res<crate::base::grid::Grid>,
    time: Res<SimTime>,
    mut fields: ResMut<Fields>,
    mut halo: ResMut<crate::solvers::operators::CurlHalo>,
) {
    let fields = &mut *fields;
    fields.dt_prev = time.dt;
    let (omega, u, _) = fields.next_version_parts();
    for w in omega.iter_mut() {
        w.par_iter_mut().for_each(|x| *x = 0.0);
    }
    crate::solvers::operators::curl_add(&grid, u, omega, halo.get());
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
        ctx.share_resource(|w| {
            Spectral::of_grid(
                w.resource::<crate::base::grid::Grid>(),
                w.get_resource::<crate::parallel::Decomposition>(),
            )
        });
        ctx.add_startup_system_in(PhysicsSet::Poisson, "poisson", poisson)?;
        let momentum = ctx.world.resource::<Params>().momentum_form();
        if ctx.mode().fluid() && momentum {
            ctx.share_resource(|w| {
                crate::solvers::operators::CurlHalo::of_grid(
                    w.resource::<crate::base::grid::Grid>(),
                    w.get_resource::<crate::parallel::Decomposition>(),
                )
            });
            ctx.add_system(PhysicsSet::Poisson, "vorticity", vorticity)?;
        } else if ctx.mode().fluid() {
            ctx.add_system(PhysicsSet::Poisson, "poisson", poisson)?;
        }
        Ok(())
    }
}
