//! The dense fluid fields and the small resources every system shares.
//!
//! Dense grids are resources, never entities: one `Vec<f64>` per component, indexed by
//! [`Grid::idx`]. In 2D the vorticity is a scalar (one component) and the velocity has two.

use crate::base::grid::Grid;
use crate::base::params::Numerics;
use bevy_ecs::prelude::Resource;

/// Vorticity (a new version), velocity and previous velocity, as [`Fields::transport_parts`]
/// hands them out.
pub type TransportParts<'a> = (&'a mut [Vec<f64>], &'a mut [Vec<f64>], &'a mut [Vec<f32>]);

/// Vorticity and velocity on the grid.
///
/// The vorticity carries a version number that changes whenever it is handed out mutably, so
/// that the spectral solver can reuse a transform it already holds (diffusion leaves ω̂ behind
/// and the Poisson solve picks it up) and can never use a stale one.
#[derive(Resource, Debug, Clone)]
pub struct Fields {
    omega: Vec<Vec<f64>>,
    omega_version: u64,
    /// Velocity, `grid.dim` components.
    pub u: Vec<Vec<f64>>,
    /// The velocity of the previous step, as transport found it, in single precision.
    ///
    /// It only enters differences with `u` over one step, whose own error (the mid-step
    /// extrapolation's, or the first-order ∂u/∂t of the baroclinic term) is O(Δt² ∂²u/∂t²)
    /// in the difference; the rounding, 2⁻²⁴ |u|, is below that whenever
    /// Δt² |∂²u/∂t²|/|u| > 2⁻²⁴, i.e. at any usable step (in a steady flow it adds at most
    /// 2⁻²⁴ |u|/Δt to ∂u/∂t: 6e-5 for |u| = 1, Δt = 1e-3, against g = 9.81). It saves a vector
    /// field of doubles (12 B per node in 3D).
    ///
    /// Transport stores the velocity it found here (and leaves the mid-step velocity that
    /// carried the particles in `u`, which the Poisson solve then replaces).
    pub u_prev: Vec<Vec<f32>>,
    /// The step between `u_prev` and `u`; 0 until there is a previous velocity.
    pub dt_prev: f64,
}

impl Fields {
    /// Zero fields for `grid`.
    pub fn new(grid: &Grid) -> Self {
        Fields {
            omega: vec![vec![0.0; grid.len()]; grid.omega_components()],
            omega_version: 0,
            u: vec![vec![0.0; grid.len()]; grid.dim],
            u_prev: vec![vec![0.0f32; grid.len()]; grid.dim],
            dt_prev: 0.0,
        }
    }

    /// Vorticity components (1 in 2D, 3 in 3D).
    pub fn omega(&self) -> &[Vec<f64>] {
        &self.omega
    }

    /// Mutable vorticity; marks every cached transform of it stale.
    pub fn omega_mut(&mut self) -> &mut [Vec<f64>] {
        self.omega_version += 1;
        &mut self.omega
    }

    /// The current vorticity version.
    pub fn omega_version(&self) -> u64 {
        self.omega_version
    }

    /// Start a new vorticity version and hand out vorticity and velocity together, for a solver
    /// that records the returned version with whatever it caches.
    pub fn next_version_parts(&mut self) -> (&mut [Vec<f64>], &mut [Vec<f64>], u64) {
        self.omega_version += 1;
        (&mut self.omega, &mut self.u, self.omega_version)
    }

    /// Start a new vorticity version and hand out vorticity, velocity and previous velocity
    /// together (transport, which turns the velocity into the mid-step one and keeps the
    /// velocity it found as the previous one).
    pub fn transport_parts(&mut self) -> TransportParts<'_> {
        self.omega_version += 1;
        (&mut self.omega, &mut self.u, &mut self.u_prev)
    }

    /// Vorticity and velocity together without starting a new version: only for a solver that
    /// keeps its cache for the current version consistent with what it writes (the Poisson
    /// solve, whose divergence cleaning is a projection it caches).
    pub fn same_version_parts(&mut self) -> (&mut [Vec<f64>], &mut [Vec<f64>], u64) {
        (&mut self.omega, &mut self.u, self.omega_version)
    }
}

/// Physical and numerical parameters, fixed for a run.
#[derive(Resource, Debug, Clone)]
pub struct Params {
    /// Kinematic viscosity ν.
    pub nu: f64,
    /// Fluid density ρ_F.
    pub rho_fluid: f64,
    /// Gravity.
    pub gravity: [f64; 3],
    /// Uniform background velocity (k = 0 mode).
    pub background: [f64; 3],
    /// The scene's `numerics` section: the time-step policy, the particles' cutoff and
    /// kernel, the penalization and the body coupling.
    pub numerics: Numerics,
    /// Whether the scene has bodies.
    pub has_bodies: bool,
    /// Whether the scene has a free surface.
    pub free_surface: bool,
    /// Whether the pressure solve keeps a multigrid hierarchy: the densities of the run (the
    /// fluid's, a free surface's gas, the moving bodies') can differ by its contrast and the
    /// grid coarsens fully.
    pub multigrid: bool,
}

impl Params {
    /// Whether the flow is carried in momentum form: each particle carries mass and momentum
    /// (and the liquid's level set) remeshed with the same weights, the velocity is their
    /// quotient and the variable-density projection makes it divergence-free
    /// (`systems/transport.rs`). Decided by the scene: a free surface (two fluid phases) is
    /// carried in momentum form, one fluid in vorticity form.
    pub fn momentum_form(&self) -> bool {
        self.free_surface
    }

    /// √(|g|/h) when the scene has a free surface, else 0: the frequency of the shortest
    /// gravity wave the grid holds (ω² = g k at k = 1/h), which an adaptive step resolves
    /// (dt ≤ c / rate, with the Lagrangian CFL number c).
    pub fn wave_rate(&self, h: f64) -> f64 {
        if self.free_surface {
            (self.gravity.iter().map(|g| g * g).sum::<f64>().sqrt() / h).sqrt()
        } else {
            0.0
        }
    }

    /// ν/h² when the scene has bodies (the diffusion-number bound applies), else 0.
    pub fn viscous_rate(&self, h: f64) -> f64 {
        if self.has_bodies {
            self.nu / (h * h)
        } else {
            0.0
        }
    }
}

/// Simulated time.
#[derive(Resource, Debug, Clone, Default, serde::Serialize, serde::Deserialize)]
pub struct SimTime {
    /// Current time.
    pub t: f64,
    /// The step the next schedule run takes (set by diagnostics at the end of each step).
    pub dt: f64,
    /// Steps taken.
    pub step: u64,
    /// The next time the step must land on exactly (an output time or the end), if any.
    pub stop_at: Option<f64>,
}

/// Why the run must stop, once it must: what went wrong, where and when (`None` while all is
/// well). Set by the systems that check the state (a body leaving the box in `level_sets`, a
/// blow-up in `diagnostics`); the simulation stops after the step that set it.
#[derive(Resource, Debug, Clone, Default)]
pub struct Failure {
    /// The message the run stops with.
    pub reason: Option<String>,
}

/// Global diagnostics of the current state.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Sample {
    /// Time.
    pub t: f64,
    /// The step that led here (0 at the start).
    pub dt: f64,
    /// Kinetic energy per unit volume, ½⟨|u|²⟩.
    pub energy: f64,
    /// Enstrophy per unit volume, ½⟨|ω|²⟩.
    pub enstrophy: f64,
    /// Circulation ∫ω dA in 2D; |∫ω dV| in 3D.
    pub circulation: f64,
    /// max|ω| over the grid.
    pub max_omega: f64,
    /// max|u| over the grid.
    pub max_u: f64,
}

/// Per-system wall-clock time of the last step, seconds.
#[derive(Resource, Debug, Clone, Default)]
pub struct Timings {
    /// (system, seconds) for the last step, in schedule order.
    pub last: Vec<(&'static str, f64)>,
}

impl Timings {
    /// Record the time a system took in this step.
    pub fn record(&mut self, name: &'static str, secs: f64) {
        if let Some(e) = self.last.iter_mut().find(|e| e.0 == name) {
            e.1 = secs;
        } else {
            self.last.push((name, secs));
        }
    }
}
