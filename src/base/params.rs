//! Typed numerical parameters shared by the systems and the scene format: the scene's
//! `numerics` section ([`Numerics`]) with its time-step policy, body coupling and remeshing
//! kernel. The scene file deserializes into these types; the systems read them from
//! [`crate::base::fields::Params`], which holds the scene's `Numerics` as they are.

use serde::{Deserialize, Serialize};

/// How the time step is chosen.
///
/// Output times and the end time (what `tumble run` does; see [`TimeStep::lands_on_outputs`]):
/// - `Fixed`: every step is the step asked for, so the result depends neither on
///   `output.every` nor on where a run was stopped and restarted. A snapshot is written after
///   the first step at or after each output time and carries that step's time (not the output
///   time); the run ends at the first step at or after the end time (to rounding: a `dt` that
///   divides the end time ends on it), so it may end up to one step past it.
/// - `Adaptive`: steps are shortened to land exactly on each output time and on the end time,
///   so snapshots are at the output times: the time left to the next one is split evenly over
///   the fewest steps the policy allows (no sliver step before an output time). The steps
///   depend on the state, so the result depends on `output.every`, within the time
///   discretization error (the shortened steps still meet every bound of the policy).
#[derive(Deserialize, Serialize, Debug, Clone, PartialEq)]
#[serde(deny_unknown_fields)]
pub enum TimeStep {
    /// A fixed time step, time units (shortened only to land on the end time).
    Fixed(f64),
    /// dt = min(c / max|ω|, dt_max, cfl h / max|u|) (paper section 4.2.2), shortened to land
    /// on each output time and the end time.
    Adaptive {
        /// Lagrangian CFL number c (dimensionless): particles do not cross within a step while
        /// dt |∇u| < 1. Default: 0.5.
        #[serde(default = "default_c")]
        c: f64,
        /// Upper bound on dt, time units. Default: no bound.
        #[serde(default)]
        dt_max: Option<f64>,
        /// Upper bound on max|u| dt / h (dimensionless). Default: 4 (particle methods are not
        /// bound by the Eulerian CFL; this only guards against runaway velocities).
        #[serde(default = "default_cfl")]
        cfl: f64,
        /// With bodies: upper bound on the diffusion number ν Δt / h² (dimensionless). The
        /// penalization enforces no-slip once per step, and implicit diffusion carries
        /// vorticity across the body's surface by about √(ν Δt)/h cells per step in between.
        /// That softens the no-slip surface by a fraction of a cell growing like √(ν Δt)/h,
        /// which offsets part of the O(h) thickening of the rigid region, so at a given h the
        /// drag on a body depends on this bound and is not converged in Δt. Measured on a
        /// settling sphere (d = 0.2, ν = 0.1, h = 1/48, U at t = 1.2): U = 0.2383 at 0.5,
        /// 0.2253 at 0.25, 0.2158 at 0.125 (about √(ν Δt) behaviour; the paper has 0.256 at
        /// h = 1/64); at 2 (h = 1/64) the sphere fell about 10% faster than at 0.5.
        /// Default: 0.5.
        #[serde(default = "default_diffusion_number")]
        diffusion_number: f64,
    },
}

fn default_diffusion_number() -> f64 {
    0.5
}

fn default_c() -> f64 {
    0.5
}
fn default_cfl() -> f64 {
    4.0
}

impl TimeStep {
    /// Whether steps are shortened to land exactly on output times (`Adaptive`), or only on
    /// the end time (`Fixed`: the step asked for, whatever the outputs).
    pub fn lands_on_outputs(&self) -> bool {
        matches!(self, TimeStep::Adaptive { .. })
    }
}

impl Default for TimeStep {
    fn default() -> Self {
        TimeStep::Adaptive {
            c: default_c(),
            dt_max: None,
            cfl: default_cfl(),
            diffusion_number: default_diffusion_number(),
        }
    }
}

/// How gravity and a dynamic body's inertia reach the body (see `Numerics::body_coupling`).
///
/// `Pressure` is the model (issue 16): one variable-density projection carries buoyancy and
/// added mass for every density ratio; within it, a body at least twice as heavy as the
/// largest added mass of its shape moves by Newton-Euler with its own mass (issue 35,
/// `bodies::coupling::MotionLaw`; the numbers below are the projection's, before that). The
/// other two are research variants kept for comparison. Measured on a sphere (radius 0.1, h = 1/32) settling at Re ≈ 2e-4 in a
/// periodic unit box, against Hasimoto's Stokes drag for a cubic array (`stokes-settling`),
/// and on a disk and a sphere launched in still inviscid fluid (`added-mass`):
/// - `Pressure` (the default): settling +7.9%, +2.4%, -0.6%, -5.9%, -16%, -59% at ρ_i = 0.01,
///   0.5, 2, 20, 100, 1000 (the drag grows with the density: 2.4 times Hasimoto's at 1000);
///   no blow-up or step-to-step oscillation in any run made, densities 0.001 to 1000 in 2D
///   and 3D (releases over 8 steps, settling runs of hundreds to thousands). What is
///   still wrong (issue 16): the drag depends on the diffusion number ν Δt / h² (at density
///   2: 0.84, 0.99, 1.46 of Hasimoto at 0.125, 0.5, 2), because the no-slip is imposed once
///   per step; and the smoothed band the penalization moves rigidly (about ε beyond the
///   surface) adds fluid to the body's mass, which matters for bodies lighter than the fluid
///   (launched disk at density 0.1: 0.159 of V0 against 0.091).
/// - `Baroclinic` (research; the paper's explicit eq. 28, ∂u/∂t lagged a step) with
///   `interface_acceleration: Eulerian` gives the body the buoyancy ρ_F ln(ρ_i/ρ_F) V g in
///   place of (ρ_i - ρ_F) V g (30.6% slow at ρ_i = 2); with `Rigid`: -8% at ρ_i = 1.1, +13%
///   at 2, blow-up at 4 (the excess inertia is lagged by a step).
/// - `Momentum` (research): settling within 1.3% from 0.01 to 20, but the flow carries the
///   body's region as fluid of density ρ_F and the excess inertia is explicit in the rigid
///   update: the launched disk oscillates and blows up at ρ_i = 0.1.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum BodyCoupling {
    /// Research variant: gravity through the explicit baroclinic term on the body's
    /// interface (paper eq. 28); ū is the mean of the flow over the body. Wrong for bodies
    /// denser than about 2.5 ρ_F.
    Baroclinic,
    /// Research variant: (M_w + (ρ_i - ρ_F) V) (ū^{n+1} - ū^n) = M_w (ũ - ū^n) +
    /// (ρ_i - ρ_F) V g Δt on the rigid velocity (and the same with the inertia tensors for
    /// the rotation).
    Momentum,
    /// The variable-density projection (the default), ω ← ω + ∇×(δu_pen + Δt (ρ_P g -
    /// G)β - β∇φ) with ∇·(β∇φ) = ∇·(δu_pen + Δt (ρ_P g - G)β - Δt (u·∇)u), β = 1/ρ; the
    /// body's excess mass keeps its momentum between steps and its excess weight acts on ū.
    #[default]
    Pressure,
}

/// How the baroclinic term estimates Du/Dt where the density varies.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum InterfaceAcceleration {
    /// The acceleration of the rigid motion of the body the node belongs to.
    #[default]
    Rigid,
    /// ∂u/∂t + (u·∇)u on the grid, from the last two velocity fields.
    Eulerian,
}

/// The kernel that interpolates velocity onto particles and remeshes them.
#[derive(Deserialize, Serialize, Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum RemeshKernel {
    /// M'4 (paper eq. 30): 4 nodes per axis, third order, conserves moments up to the second.
    #[default]
    M4Prime,
    /// Λ4,2 (Cottet et al. 2014): 6 nodes per axis, fourth order, C², conserves moments up to
    /// the third; more accurate for under-resolved small scales.
    Lambda42,
}

/// Time stepping and particle parameters.
#[derive(Deserialize, Serialize, Debug, Clone, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct Numerics {
    /// Time step policy. Default: `Adaptive(c: 0.5)`.
    pub dt: TimeStep,
    /// Simulated time at which the run ends, time units, > 0. An adaptive run lands on it
    /// exactly (the time left split evenly over the fewest steps the policy allows); a
    /// `Fixed` run ends at the first step at or after it. Default: 1.
    pub end_time: f64,
    /// Particle creation cutoff, relative to max|ω| (dimensionless, in [0, 1)): grid nodes with
    /// |ω| at or below `remesh_cutoff * max|ω|` create no particle and keep their (small)
    /// vorticity in place. Default: 1e-8.
    pub remesh_cutoff: f64,
    /// Stop the run as blown up when max|ω| exceeds this multiple of its initial value
    /// (dimensionless); for a flow that starts at rest under gravity (no initial vorticity),
    /// when max|u| exceeds its square root times the free-fall speed across the box,
    /// √(2 |g| L) with L the box's longest side. Default: 1e4.
    pub blowup_factor: f64,
    /// Penalization coefficient λ, 1/time, > 0 (implicit, so any value is stable). Default: 1e6.
    pub lambda: f64,
    /// Half-width of the smoothed Heaviside χ = H(φ), in cells (> 0). Default: 1.
    pub interface_cells: f64,
    /// Where the mask of static and kinematic bodies (walls, obstacles) sits relative to
    /// their surface, in cells: their χ is H_ε(φ - offset h) for every system that reads it
    /// (the penalization; with a free surface also the projection's walls, the reduced
    /// gravity and the remeshing kernels' choice), so with an offset of one half-width the
    /// smoothed band lies inside the body and the rigid region does not reach into the fluid
    /// (a fixed cylinder's drag then converges from the first grid). The liquid's volume is
    /// kept with the centred weight whatever the offset. Dynamic bodies always use the
    /// centred χ = H_ε(φ). In [0, 2 interface_cells]. Default: 0 (measured against 1 in
    /// docs/numerics.md, "The walls' offset").
    pub penalization_offset: f64,
    /// How gravity and a dynamic body's own inertia reach the body. `Pressure` (the
    /// default, and the model for every density): the variable-density projection of
    /// `systems/pressure.rs` gives buoyancy, pressure forces and added mass at any density
    /// ratio, and the body's rigid velocity is the density-weighted mean of the flow over it.
    /// `Baroclinic` (research, the paper's): gravity makes vorticity on the body's interface
    /// (eq. 28, in the form `boussinesq` and `interface_acceleration` choose) and ū is the
    /// flow's mean over the body; wrong for bodies denser than about 2.5 ρ_F. `Momentum`
    /// (research): the body's buoyancy and excess inertia act on its rigid velocity directly.
    /// Measurements of all three in [`BodyCoupling`]. Default: Pressure.
    pub body_coupling: BodyCoupling,
    /// Use the Boussinesq form of the baroclinic term, ∇ρ × g / ρ_F (eq. 18), instead of the
    /// full form (eq. 28); only with `body_coupling: Baroclinic`. Default: false.
    pub boussinesq: bool,
    /// The fluid acceleration Du/Dt on the bodies' interfaces in the baroclinic term (eq. 28):
    /// `Rigid`, the acceleration of the body's rigid motion (no slip), or `Eulerian`, the grid
    /// estimate ∂u/∂t + (u·∇)u from the last two velocity fields (the paper's); only with
    /// `body_coupling: Baroclinic`. Default: Rigid.
    pub interface_acceleration: InterfaceAcceleration,
    /// Unsupported numerical variants kept for experiments: no bundled scene, validation case
    /// or test uses a non-default value, and they may be removed without notice. Written as
    /// `numerics: (experimental: (midpoint_velocity: false))`. Default: every entry at its
    /// default.
    #[serde(skip_serializing_if = "Experimental::is_default")]
    pub experimental: Experimental,
}

/// Unsupported numerical variants (`numerics.experimental`): may be removed; the defaults are
/// what tumble is validated with.
#[derive(Deserialize, Serialize, Debug, Clone, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct Experimental {
    /// Carry the particles (and stretch the vorticity) with the mid-step velocity
    /// u^{n+1/2} = u^n + (Δt_n / 2Δt_{n-1}) (u^n - u^{n-1}) instead of the frozen u^n, which makes
    /// the step second order in time; `false` gives a first-order step. Default: true.
    pub midpoint_velocity: bool,
    /// Interpolation and remeshing kernel: `M4Prime` (the paper's eq. 30) or `Lambda42`
    /// (fourth order, 6 points per axis). Default: `M4Prime`.
    pub remesh_kernel: RemeshKernel,
}

impl Default for Experimental {
    fn default() -> Self {
        Experimental {
            midpoint_velocity: true,
            remesh_kernel: RemeshKernel::M4Prime,
        }
    }
}

impl Experimental {
    /// Whether every entry has its default (then it is not written back to RON).
    pub fn is_default(&self) -> bool {
        *self == Experimental::default()
    }
}

impl Default for Numerics {
    fn default() -> Self {
        Numerics {
            dt: TimeStep::default(),
            end_time: 1.0,
            remesh_cutoff: 1e-8,
            blowup_factor: 1e4,
            lambda: 1e6,
            interface_cells: 1.0,
            penalization_offset: 0.0,
            body_coupling: BodyCoupling::default(),
            boussinesq: false,
            interface_acceleration: InterfaceAcceleration::Rigid,
            experimental: Experimental::default(),
        }
    }
}
