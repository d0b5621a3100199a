//! How many steps a run takes, as far as the scene alone can tell: the largest step its time
//! step policy can ever take, and from it the fewest steps to the end time.
//!
//! A `Fixed` step is the step (the run ends at the first step at or after the end time). An
//! `Adaptive` step is the least of several bounds (see `systems/diagnostics.rs`,
//! `allowed_dt`); those that do not depend on the flow hold at every step: `dt_max`, the
//! diffusion number with bodies (ν dt / h² at most `diffusion_number`), the shortest gravity
//! wave with a free surface (dt at most c (h/|g|)^(1/2)) and gravity on the dynamic bodies
//! (dt at most c (h/a)^(1/2), a = |g| |ρ - ρ_F| / (ρ + ρ_F/2)). Their least is an upper bound
//! of every step (landing on an output time only shortens a step), so the end time over it is
//! a lower bound of the step count. Without any of them the steps depend on the flow and are
//! not known before the run.

use super::format::Scene;
use super::resolved::Resolved;
use crate::base::grid::Grid;
use crate::base::params::TimeStep;
use crate::bodies::BodyKind;

/// The most steps a run can count: beyond 2^53 steps of at most end_time / 2^53 each, a step
/// is below half the spacing of doubles near the end time, so adding it to the clock (a sum
/// of steps in double precision) no longer moves it.
pub const MAX_STEPS: f64 = 9_007_199_254_740_992.0;

/// The largest step of a scene's time step policy, and what sets it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepBound {
    /// The step, time units: every step is at most this long (exactly this long with a
    /// `Fixed` step, but for the last).
    pub dt: f64,
    /// What sets it, in words (`numerics.dt`, `dt_max`, ...).
    pub why: &'static str,
    /// Whether every step is this long (a `Fixed` step).
    pub exact: bool,
}

impl StepBound {
    /// The steps to `end_time`: exactly with a `Fixed` step, at least with an adaptive one.
    pub fn steps(&self, end_time: f64) -> f64 {
        (end_time / self.dt * (1.0 - 1e-12)).ceil().max(1.0)
    }
}

/// The largest step `scene` (checked, on `grid`, with its defaults `resolved`) can take, if
/// the scene alone bounds it.
pub fn step_bound(scene: &Scene, grid: &Grid, resolved: &Resolved) -> Option<StepBound> {
    let (c, dt_max, diffusion_number) = match scene.numerics.dt {
        TimeStep::Fixed(dt) => {
            return Some(StepBound {
                dt,
                why: "the fixed step numerics.dt",
                exact: true,
            });
        }
        TimeStep::Adaptive {
            c,
            dt_max,
            diffusion_number,
            ..
        } => (c, dt_max, diffusion_number),
    };
    let h = grid.h;
    let p = &resolved.params;
    let mut best: Option<StepBound> = None;
    let mut take = |dt: f64, why: &'static str| {
        if dt.is_finite() && dt > 0.0 && best.is_none_or(|b| dt < b.dt) {
            best = Some(StepBound {
                dt,
                why,
                exact: false,
            });
        }
    };
    if let Some(m) = dt_max {
        take(m, "numerics.dt.dt_max");
    }
    let viscous = p.viscous_rate(h);
    if viscous > 0.0 {
        take(
            diffusion_number / viscous,
            "the diffusion number with bodies (nu dt / h^2 at most diffusion_number)",
        );
    }
    let wave = p.wave_rate(h);
    if wave > 0.0 {
        take(
            c / wave,
            "the free surface's shortest gravity wave (dt at most c (h/|g|)^(1/2))",
        );
    }
    let g = p.gravity.iter().map(|g| g * g).sum::<f64>().sqrt();
    let rho_f = p.rho_fluid;
    let a = scene
        .bodies
        .iter()
        .zip(&resolved.densities)
        .filter(|(b, _)| matches!(b.kind, BodyKind::Dynamic))
        .map(|(_, &rho)| g * (rho - rho_f).abs() / (rho + 0.5 * rho_f))
        .fold(0.0, f64::max);
    if a > 0.0 {
        take(
            c / (a / h).sqrt(),
            "gravity on the dynamic bodies (dt at most c (h/a)^(1/2))",
        );
    }
    best
}
