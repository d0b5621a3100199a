//! # density: characteristic functions and the density field (paper eq. 19)
//!
//! ρ = ρ_P (1 - Σ_i χ_i) + Σ_i ρ_i χ_i, with χ_i = H(φ_i) from the level-set system and ρ_P
//! the density of the fluid phases (`BodyFields::rho_phase`: ρ_F unless a plugin writes a
//! second phase). Static bodies (walls) count with the fluid's density, so that gravity makes
//! no vorticity at walls.
//! Also keeps Σχ_i and the union level set max_i φ_i for output, and at each node the body
//! whose level set is the largest there (its owner, for the baroclinic term). Computed also
//! at startup, so that the state at t = 0 holds the bodies.

use crate::base::grid::Grid;
use crate::bodies::coupling::MotionLaw;
use crate::bodies::{Body, BodyFields, GridPatch, Material, NO_BODY};
use bevy_ecs::prelude::*;
use rayon::prelude::*;

/// The density system.
pub fn density(
    grid: Res<Grid>,
    bodies: Query<(&Body, &Material, &GridPatch, &MotionLaw)>,
    mut out: ResMut<BodyFields>,
) {
    let out = &mut *out;
    // The fluid phases first (ρ_F everywhere unless a plugin wrote a second phase).
    let (rho, phase) = (&mut out.rho, &out.rho_phase);
    rho.par_iter_mut()
        .zip(phase.par_iter())
        .for_each(|(r, p)| *r = *p);
    out.chi.par_iter_mut().for_each(|c| *c = 0.0);
    out.phi.par_iter_mut().for_each(|p| *p = f64::NEG_INFINITY);
    out.owner.par_iter_mut().for_each(|o| *o = NO_BODY);
    // Bodies in spawn order, so overlapping patches add up in a fixed order.
    for (body, mat, patch, law) in &bodies {
        // Walls and bodies that move by Newton-Euler are fluid of the phases' density here.
        let moving = !body.is_static() && *law == MotionLaw::Projected;
        let density = mat.density;
        let [dx, dy, _] = patch.dims;
        if patch.is_empty() {
            continue;
        }
        let rows = patch.len() / dx;
        let (rho, chi, phi, owner) = (
            crate::base::grid::SyncPtr(out.rho.as_mut_ptr()),
            crate::base::grid::SyncPtr(out.chi.as_mut_ptr()),
            crate::base::grid::SyncPtr(out.phi.as_mut_ptr()),
            crate::base::grid::SyncPtr(out.owner.as_mut_ptr()),
        );
        let id = body.id as u32;
        let phase = &out.rho_phase;
        (0..rows).into_par_iter().for_each(|r| {
            let (b, c) = (r % dy, r / dy);
            // (A plane of the patch held by another process.)
            if !patch.holds(&grid, c) {
                return;
            }
            let nodes = patch.row(&grid, b, c);
            for a in 0..dx {
                let g = nodes.index(a);
                let l = r * dx + a;
                // SAFETY: distinct patch nodes map to distinct grid nodes (a patch is at
                // most `n` nodes long along each axis, see `GridPatch`).
                unsafe {
                    // ρ_i - ρ_P at this node; static bodies count as the fluid around them.
                    let d = if moving { density - phase[g] } else { 0.0 };
                    rho.write(g, rho.read(g) + d * patch.chi[l]);
                    chi.write(g, chi.read(g) + patch.chi[l]);
                    if patch.phi[l] > phi.read(g) {
                        phi.write(g, patch.phi[l]);
                        owner.write(g, id);
                    }
                }
            }
        });
    }
}

/// Characteristic functions and density (a fluid run with bodies).
#[derive(Debug, Clone, Copy, Default)]
pub struct DensityPlugin;

impl crate::schedule::Plugin for DensityPlugin {
    fn name(&self) -> &'static str {
        "density"
    }

    fn build(&self, ctx: &mut crate::schedule::PluginContext) -> anyhow::Result<()> {
        use crate::schedule::PhysicsSet;
        let mode = ctx.mode();
        if mode.fluid() && mode.has_bodies() {
            ctx.add_system(PhysicsSet::Density, "density", density)?;
            // The same before the first step (after `level_sets_init` and the phases' density),
            // for the t = 0 state; the first step computes it again from the same patches.
            ctx.add_startup_system_in(PhysicsSet::Density, "density_init", density)?;
        }
        Ok(())
    }
}
