//! # rigid_velocity: the rigid motion of each body from the flow (paper eq. 7)
//!
//! ū_i(x) = V_i + Ω_i × (x - x_G), with
//!   V_i = (1/|S_i|) ∫ χ_i u dx,   Ω_i = J_i⁻¹ ∫ χ_i (x - x_G) × u dx,
//!   |S_i| = ∫ χ_i dx,   x_G = ∫ χ_i x dx / |S_i|,   J_i = ∫ χ_i (|r|² I - r rᵀ) dx  (r = x - x_G),
//! integrated on the grid. The averages that give V_i and Ω_i use the weights the implicit
//! penalization actually applies, w_i = λΔtχ_i/(1 + λΔtχ_i) in place of χ_i, so that the body
//! that moves is exactly the body the flow is forced to move with, and penalizing towards ū_i
//! conserves momentum; the volume and inertia reported are those of χ_i. In 2D Ω is about z and J_zz = ∫χ|r|².
//!
//! With `numerics.body_coupling: Momentum` the flow inside a dynamic body is fluid of
//! density ρ_F (its vorticity equation has the one ν = μ/ρ_F), so the mean ũ, Ω̃ above is the
//! motion the fluid's forces alone give the region the penalization moves rigidly: the
//! w-region, of fluid mass M_w = ρ_F ∫w and inertia J_w = ρ_F ∫w (|r|² I - r rᵀ). The body's
//! mass beyond the fluid's, (ρ_i - ρ_F) χ, and its buoyancy enter here:
//!   (M_w + (ρ_i - ρ_F) |S_i|) (V^{n+1} - V^n) = M_w (ũ - V^n) + (ρ_i - ρ_F) |S_i| g Δt,
//!   (J_w + (ρ_i - ρ_F) J_i) Ω^{n+1} = J_w Ω̃ + (ρ_i - ρ_F) J_i^n Ω^n,
//! with V^n, Ω^n the velocities the body was given last step, J_i^n its inertia then (so the
//! excess mass keeps its angular momentum as the body turns) and Δt that step's length: the
//! momentum balance of the rigid region with its weight, the fluid's force and its whole
//! inertia, implicit in the body's own mass. (With ρ_F |S_i| in place of M_w, the fluid in the
//! outer half of the band, moved rigidly but not counted, made a settling sphere fall 91% too
//! fast.) The hydrodynamic force and torque reported are the fluid's, M_w (ũ - V^n)/Δt and
//! J_w (Ω̃ - Ω^n)/Δt. With `Baroclinic` (the default) V and Ω are ũ and Ω̃, and gravity comes
//! through the baroclinic term.
//!
//! Under `Pressure` without a free surface, a bounded body moves by Newton-Euler with its own
//! mass instead (`MotionLaw::NewtonEuler`, decided once when it is made, see
//! `bodies::coupling::newton_euler`). The density system leaves it
//! out of ρ, so the projection carries its rigid region as fluid of the phases' density ρ_P,
//! of mass M_w = ∫ρ_P w, and the body's mass beyond the fluid it displaces,
//! E = ρ_i |S_i| - ∫ρ_P χ_i, takes the fluid's impulse on the region and its weight less
//! buoyancy:
//!   (M_w + E) (V^{n+1} - V^n) = M_w (ũ - V^n) + E g Δt,
//!   (J_w + e J_i) Ω^{n+1} = J_w Ω̃ + e J_i^n Ω^n,  e = E / |S_i|,
//! the momentum balance of `Momentum` below with the projection's fluid. The excess mass
//! then never sits in ρ where the flow's uniform ν acts on it: a sphere settling at
//! 3.2 cells per radius (`stokes-settling`, h = 1/32) moves at 0.998 of Hasimoto's velocity at
//! densities 1.1, 2, 20 and 100, where as heavy fluid of the projection it moved at 0.984 (2),
//! 0.929 (20) and 0.84 (100). The lagged added mass m_a of the outside fluid makes this
//! explicit update amplify an error by m_a / (M_w + E) per step, and a light body's E is
//! negative: the body's virtual mass M_v ([`VirtualMass`], Schwarz, Kempe & Fröhlich 2015) is
//! added to both sides, with last step's acceleration a^n on the right,
//!   (M_w + E + M_v) (V^{n+1} - V^n) = M_w (ũ - V^n) + E g Δt + M_v a^n Δt,
//! and the same for the rotation with M_v's share of J_i; a steady motion is unchanged, a
//! transient lags by about M_v / (m + m_a) steps. M_v is zero for a body heavy enough for
//! its shape (a sphere from density 1.1).
//!
//! Under `Pressure` (either law) the excess weight's moment about the rigid region's
//! centroid, weight at the body's centroid and buoyancy at the centroid of the fluid it
//! displaces, turns the body over the step: the righting moment of a floating body, which the
//! projection alone does not give (it carries only the phases' weight). A box of density 0.5
//! heeled 15° in a free surface kept its heel without it.
//!
//! On the first step a dynamic body keeps the velocity and angular velocity the scene gives it
//! (the flow inside it is whatever the initial vorticity makes), and the penalization imposes
//! them on the flow; from then on they follow from the flow as above.
//!
//! The collision system, which runs next, adds the contact impulse to these velocities
//! (section 3.2). Kinematic bodies take their prescribed motion; static ones stay at rest. Sums are taken per
//! patch row and added in row order (thread-count independent).

use crate::base::fields::{Fields, Params, SimTime};
use crate::base::grid::Grid;
use crate::base::params::BodyCoupling;
use crate::bodies::coupling::{MotionLaw, PressureState, VirtualMass};
use crate::bodies::integrals::{
    BodySums, integrate_n, mass_properties, penalized_weight, rigid_region, solve_inertia,
};
use crate::bodies::{
    Body, BodyFields, GridPatch, Hydro, Material, PreviousVelocity, RigidState, ShapeVolume,
    kinematic_velocity,
};
use bevy_ecs::prelude::*;
use glam::{DMat3, DVec3};

/// What the rigid velocity reads and writes of a body.
type FreeBody = (
    &'static Body,
    &'static GridPatch,
    &'static Material,
    &'static MotionLaw,
    &'static ShapeVolume,
    &'static VirtualMass,
    &'static PreviousVelocity,
    &'static mut RigidState,
    &'static mut Hydro,
);

/// The rigid-velocity system.
#[allow(clippy::too_many_arguments)]
pub fn rigid_velocity(
    grid: Res<Grid>,
    params: Res<Params>,
    time: Res<SimTime>,
    fields: Res<Fields>,
    bf: Res<BodyFields>,
    mut sums: ResMut<BodySums>,
    mut bodies: Query<FreeBody>,
    pressure_state: Option<Res<PressureState>>,
) {
    let momentum = params.numerics.body_coupling == BodyCoupling::Momentum;
    let pressure = params.numerics.body_coupling == BodyCoupling::Pressure;
    let rho = &bf.rho;
    let phase = &bf.rho_phase;
    // Under the pressure projection the body's mass beyond the fluid's, (ρ - ρ_P), keeps the
    // momentum the last step's projection gave it (`PressureState::excess`, taken where the
    // body was then and carried with it), while the flow's change since then (transport,
    // diffusion, the velocity solve) acts on the fluid's share ρ_P, as the viscous force of
    // a fluid of dynamic viscosity ρ_P ν does.
    let excess = match pressure_state.as_deref() {
        Some(ps) if pressure && fields.dt_prev > 0.0 => Some(&ps.excess),
        _ => None,
    };
    let g = DVec3::from_array(params.gravity);
    for (body, patch, mat, law, shape_volume, virt, last, mut state, mut hydro) in &mut bodies {
        if body.is_static() {
            state.velocity = DVec3::ZERO;
            state.angular_velocity = DVec3::ZERO;
            continue;
        }
        let (v_prev, w_prev, j_prev) = (state.velocity, state.angular_velocity, state.inertia);
        if kinematic_velocity(&body.kind, time.t).is_some() {
            mass_properties(&grid, patch, &fields.u, &mut sums, body, time.t, &mut state);
            continue;
        }
        // The rigid velocity is the mean over exactly the weights the implicit penalization
        // applies, w = λΔtχ/(1 + λΔtχ), so that penalizing towards it adds no momentum to the
        // flow. (With the χ-weighted mean, the outer half of the interface band, where χ is
        // small but λΔtχ ≫ 1, is dragged along at ū every step: momentum from nothing that
        // made a settling sphere fall ~50% too fast.)
        let ldt = params.numerics.lambda * time.dt;
        // A Newton-Euler body's rigid region is the nodes inside its surface, wholly (the one
        // weight of its penalization and its no-slip, `systems/noslip.rs`).
        let newton = pressure && *law == MotionLaw::NewtonEuler;
        let weight = |c: f64, phi: f64| {
            if newton {
                rigid_region(phi)
            } else {
                penalized_weight(ldt, c)
            }
        };
        let parts = excess.and_then(|x| x.get(body.id).copied().flatten());
        // All of the body's integrals in one pass over its patch:
        // - χ: its volume, centroid and inertia (`mass_properties`);
        // - w: under the pressure projection the flow carries each region with its own
        //   density, so the rigid velocity is the density-weighted mean (the penalization then
        //   conserves momentum);
        // - the excess mass's share, each sign of ρ - ρ_P apart (see `PressureState::excess`):
        //   its momentum from the last projection replaces the flow's now, ∫(ρ - ρ_P) w u
        //   (angular momenta about the centroid of ρw);
        // - ρ_P χ: the fluid mass the body displaces.
        let [geo, main, above, below, displaced] = integrate_n::<5>(
            &grid,
            patch,
            state.center,
            &fields.u,
            &mut sums,
            |c, phi, g| {
                let excess = |sign: f64| {
                    if parts.is_some() {
                        sign * (sign * (rho[g] - phase[g])).max(0.0) * weight(c, phi)
                    } else {
                        0.0
                    }
                };
                [
                    c,
                    if pressure {
                        rho[g] * weight(c, phi)
                    } else {
                        weight(c, phi)
                    },
                    excess(1.0),
                    excess(-1.0),
                    if pressure { phase[g] * c } else { 0.0 },
                ]
            },
        );
        state.volume = geo.0;
        state.centroid = geo.1;
        state.inertia = geo.4;
        // The inertia the body had last step (this one's before the first): its excess mass
        // keeps its angular momentum J_i^n Ω^n as it turns.
        let j_old = if j_prev == DMat3::ZERO {
            state.inertia
        } else {
            j_prev
        };
        let has_volume = geo.0 > 0.0;
        if !has_volume {
            continue;
        }
        let (wvol, wcentroid, mut mom, mut ang, wj) = main;
        if let Some(parts) = parts {
            for (e, (me, xe, pu, lu, _)) in parts.iter().zip([above, below]) {
                if me != 0.0 {
                    let pe = me * e.velocity;
                    let arm = xe - wcentroid;
                    mom += pe - pu;
                    ang += me * e.spin + arm.cross(pe) - (lu + arm.cross(pu));
                }
            }
        }
        if wvol <= 0.0 {
            continue;
        }
        state.centroid = wcentroid;
        let (vol, j) = (wvol, wj);
        let v_flow = mom / vol;
        let w_flow = solve_inertia(grid.dim, j, ang);
        // Before the first step the body has the velocities the scene gives it (the flow
        // inside it does not know them yet): the first penalization imposes them.
        // Under the pressure projection, E, the body's mass beyond the fluid it displaces, and
        // the impulse of its weight over this step (`weight`), on the rigid region's mass wvol
        // (`kick`).
        // A Newton-Euler body's takes the exact volume of its shape: ∫χ is larger by the
        // smoothing (0.39 (ε/a)² of a sphere's volume, 3.8% at 3.2 cells per radius).
        let e = if newton && shape_volume.0 > 0.0 {
            (mat.density - displaced.0 / state.volume) * shape_volume.0
        } else {
            mat.density * state.volume - displaced.0
        };
        let weight = e * g * time.dt;
        let kick = if pressure { weight / wvol } else { DVec3::ZERO };
        // Its moment about the rigid region's centroid over the step: the weight acts at the
        // body's centroid, the buoyancy at the centroid of the fluid it displaces (apart
        // where the phase density varies across the body: a box heeled in a free surface).
        // This is the righting moment; without it a heeled floating box kept its heel.
        let torque_impulse = if pressure {
            ((geo.1 - wcentroid).cross(mat.density * state.volume * g)
                - (displaced.1 - wcentroid).cross(displaced.0 * g))
                * time.dt
        } else {
            DVec3::ZERO
        };
        let first = fields.dt_prev <= 0.0;
        if newton {
            // The projection carried the rigid region as fluid of the phases' density: its
            // mass is M_w = wvol, its momentum and angular momentum `mom`, `ang` (about the
            // centroid of ρw); the body's inertia beyond the displaced fluid's is e_rho J_i
            // (with the mean displaced density).
            let m_w = wvol;
            let e_rho = e / state.volume;
            // The virtual mass (`VirtualMass`) on both sides, with last step's acceleration.
            let (m_v, v_rho) = (virt.mass, virt.per_volume);
            let j_body = wj + (e_rho + v_rho) * state.inertia;
            if first {
                *hydro = Hydro::default();
                state.velocity += weight / (m_w + e + m_v);
                state.angular_velocity += solve_inertia(grid.dim, j_body, torque_impulse);
                continue;
            }
            // The flow inside is fluid, held by the no-slip at the markers, which also gives
            // the body the fluid's force (its recoil, `noslip`): here the body's mass beyond
            // that fluid takes its weight less buoyancy, with the virtual mass's lag.
            let m_e = e + m_v;
            let j_e = (e_rho + v_rho) * state.inertia;
            let lag = m_v * last.acceleration * time.dt;
            state.velocity = v_prev + (weight + lag) / m_e;
            let spin_lag = v_rho * (j_old * (w_prev + last.angular_acceleration * time.dt));
            state.angular_velocity = solve_inertia(
                grid.dim,
                j_e,
                e_rho * (j_old * w_prev) + spin_lag + torque_impulse,
            );
            *hydro = Hydro::default();
            continue;
        }
        // The same moment on the rigid region's inertia (wj: its mass there, as wvol above).
        let spin_kick = solve_inertia(grid.dim, wj, torque_impulse);
        if first {
            *hydro = Hydro::default();
            state.velocity += kick;
            state.angular_velocity += spin_kick;
            continue;
        }
        if pressure {
            // The fluid's force and torque on the body: its momentum change over the step
            // the flow has just made, less its weight. (wvol is the body's mass here.)
            let dt = fields.dt_prev;
            let mass = wvol;
            *hydro = Hydro {
                force: mass * (v_flow - v_prev) / dt - mass * g,
                torque: wj * (w_flow - w_prev) / dt,
            };
            state.velocity = v_flow + kick;
            state.angular_velocity = w_flow + spin_kick;
            continue;
        }
        if !momentum {
            state.velocity = v_flow;
            state.angular_velocity = w_flow;
            continue;
        }
        // The region the penalization moves rigidly is the w-region (volume `wvol`, inertia
        // `wj`), which the flow carries as fluid of density ρ_F; the body's mass beyond the
        // fluid's, (ρ_i - ρ_F) χ, is added to it. The flow's momentum change of the region over
        // the step it has just made is the fluid's force.
        let dt = fields.dt_prev;
        let rho_f = params.rho_fluid;
        let excess = mat.density - rho_f;
        let m_w = rho_f * wvol;
        let m = m_w + excess * state.volume;
        let p_fluid = m_w * (v_flow - v_prev);
        state.velocity = v_prev + (p_fluid + excess * state.volume * dt * g) / m;
        // Angular momentum: the fluid part's is the flow's now, the excess mass keeps its own
        // (J_i as it was, so that a tumbling body's excess part keeps J_i Ω exactly).
        let j_w = rho_f * wj;
        let l_fluid = rho_f * ang - j_w * w_prev;
        let l_body = rho_f * ang + excess * (j_old * w_prev);
        state.angular_velocity = solve_inertia(grid.dim, j_w + excess * state.inertia, l_body);
        *hydro = Hydro {
            force: p_fluid / dt,
            torque: l_fluid / dt,
        };
    }
}

/// Rigid velocities from the flow (a fluid run with bodies).
#[derive(Debug, Clone, Copy, Default)]
pub struct RigidVelocityPlugin;

impl crate::schedule::Plugin for RigidVelocityPlugin {
    fn name(&self) -> &'static str {
        "rigid_velocity"
    }

    fn build(&self, ctx: &mut crate::schedule::PluginContext) -> anyhow::Result<()> {
        use crate::schedule::PhysicsSet;
        let mode = ctx.mode();
        if mode.fluid() && mode.has_bodies() {
            ctx.share_resource(BodySums::of_world);
            ctx.add_system(PhysicsSet::RigidVelocity, "rigid_velocity", rigid_velocity)?;
        }
        Ok(())
    }
}
