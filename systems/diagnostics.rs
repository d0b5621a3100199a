//! # diagnostics: time step, global quantities and the blow-up guard (paper section 4.2.2)
//!
//! Closes a step: advances the clock, measures the state and chooses the next step
//!
//!   Δt = min(C / max|ω|, Δt_max, CFL h / max|u|, D h²/ν (only with bodies))
//!
//! (the paper's Δt = C / max|ω| keeps particles from crossing, dt |∇u| < 1), or the fixed step,
//! shortened to land exactly on [`SimTime::stop_at`]: the end time, and with an Adaptive step
//! the next output time too (`tumble run` decides, see
//! [`crate::base::params::TimeStep`]). It records kinetic energy ½⟨|u|²⟩, enstrophy
//! ½⟨|ω|²⟩ (both per unit volume), circulation and max|ω|, and stops the run with a message
//! naming the quantity, the place and the step when a value is not finite, max|ω| grows beyond
//! `blowup_factor` times its initial value, max|u| of a flow that starts at rest under gravity
//! grows beyond √`blowup_factor` times the free-fall speed across the box, or a fixed step is
//! far beyond the CFL limit.
//!
//! Sums are taken per grid row and then added in row order, so they do not depend on the
//! number of threads. Fields that no system changed since the last step (a vacuum run's) are
//! not measured again: their sample is the last one.

use crate::base::fields::{Failure, Fields, Params, Sample, SimTime};
use crate::base::grid::Grid;
use crate::base::params::TimeStep;
use crate::bodies::{Body, BodyShape, Material, RigidState};
use crate::parallel::{Decomposition, PlaneSums};
use bevy_ecs::prelude::*;
use rayon::prelude::*;

/// Diagnostics state: the latest sample and the reference for the blow-up guard (why the run
/// must stop, once it must, is the [`Failure`] resource).
#[derive(Resource, Debug, Clone)]
pub struct Diagnostics {
    /// The state after the last step.
    pub sample: Sample,
    /// max|ω| at the start (reference for the blow-up guard).
    pub omega0: f64,
    /// Fallback step when nothing else bounds dt (fluid at rest, no dt_max).
    pub dt_fallback: f64,
    rows: Vec<RowStats>,
    /// The sums of each z-plane (energy, enstrophy, circulation), added in plane order: the
    /// same on any number of processes ([`PlaneSums`]).
    planes: PlaneSums,
}

#[derive(Debug, Clone, Copy, Default)]
struct RowStats {
    u2: f64,
    w2: f64,
    wsum: [f64; 3],
    wmax2: f64,
    wmax_at: usize,
    umax2: f64,
    umax_at: usize,
    nan_at: Option<usize>,
}

/// What a checkpoint keeps of the [`Diagnostics`] (the row sums are scratch; a restored run
/// has not failed).
#[derive(Debug, Clone, Copy, serde::Serialize, serde::Deserialize)]
pub struct KeptDiagnostics {
    /// The last sample: the next adaptive step is chosen from it.
    pub sample: Sample,
    /// The blow-up guard's reference.
    pub omega0: f64,
    /// The fallback step: it depends on the end time the run started with, which a restart
    /// may change.
    pub dt_fallback: f64,
}

impl crate::schedule::CheckpointPart for Diagnostics {
    type Part = KeptDiagnostics;
    fn save_part(&self) -> KeptDiagnostics {
        KeptDiagnostics {
            sample: self.sample,
            omega0: self.omega0,
            dt_fallback: self.dt_fallback,
        }
    }
    fn restore_part(&mut self, kept: KeptDiagnostics) {
        self.sample = kept.sample;
        self.omega0 = kept.omega0;
        self.dt_fallback = kept.dt_fallback;
    }
}

/// Where the extremes of a measured state are (grid node indices).
#[derive(Debug, Clone, Copy, Default)]
pub struct Extremes {
    /// The first node whose velocity or vorticity is not finite.
    pub nan_at: Option<usize>,
    /// The node of max|ω|.
    pub omega_at: usize,
    /// The node of max|u|.
    pub u_at: usize,
}

impl Diagnostics {
    /// Diagnostics for `grid`; `dt_fallback` is used when nothing else bounds the step.
    pub fn new(grid: &Grid, dt_fallback: f64) -> Self {
        Diagnostics {
            sample: Sample::default(),
            omega0: 0.0,
            dt_fallback,
            rows: vec![RowStats::default(); grid.n[1] * grid.n[2]],
            planes: PlaneSums::new(grid.nz_whole, 5),
        }
    }

    /// Measure the fields; returns the sample and where its extremes are.
    ///
    /// Split over processes (`split`), the sample is the whole grid's, the same on every
    /// process; a location held by another process is [`ELSEWHERE`].
    pub fn measure(
        &mut self,
        grid: &Grid,
        fields: &Fields,
        split: Option<&Decomposition>,
    ) -> (Sample, Extremes) {
        let nx = grid.n[0];
        let omega = fields.omega();
        let u = &fields.u;
        self.rows.par_iter_mut().enumerate().for_each(|(r, st)| {
            let mut s = RowStats::default();
            for i in r * nx..(r + 1) * nx {
                let mut u2 = 0.0;
                for c in u {
                    u2 += c[i] * c[i];
                }
                let mut w2 = 0.0;
                for (c, comp) in omega.iter().enumerate() {
                    w2 += comp[i] * comp[i];
                    s.wsum[c] += comp[i];
                }
                if s.nan_at.is_none() && !(u2.is_finite() && w2.is_finite()) {
                    s.nan_at = Some(i);
                }
                s.u2 += u2;
                s.w2 += w2;
                if w2 > s.wmax2 {
                    s.wmax2 = w2;
                    s.wmax_at = i;
                }
                if u2 > s.umax2 {
                    s.umax2 = u2;
                    s.umax_at = i;
                }
            }
            *st = s;
        });
        let mut tot = RowStats::default();
        self.planes.clear(grid.nz_whole);
        for (k, rows) in self.rows.chunks(grid.n[1]).enumerate() {
            let mut p = [0.0; 5];
            for s in rows {
                p[0] += s.u2;
                p[1] += s.w2;
                for c in 0..3 {
                    p[2 + c] += s.wsum[c];
                }
            }
            self.planes.plane_mut(grid.k0 + k).copy_from_slice(&p);
        }
        let mut sums = [0.0; 5];
        self.planes
            .total(split.map(|d| &*d.comm), grid.nz_whole, &mut sums);
        [tot.u2, tot.w2, tot.wsum[0], tot.wsum[1], tot.wsum[2]] = sums;
        for s in &self.rows {
            if s.wmax2 > tot.wmax2 {
                tot.wmax2 = s.wmax2;
                tot.wmax_at = s.wmax_at;
            }
            if s.umax2 > tot.umax2 {
                tot.umax2 = s.umax2;
                tot.umax_at = s.umax_at;
            }
            if tot.nan_at.is_none() {
                tot.nan_at = s.nan_at;
            }
        }
        if let Some(d) = split {
            let nan = f64::from(u8::from(tot.nan_at.is_some()));
            let mut maxima = [tot.wmax2, tot.umax2, nan];
            d.comm.max(&mut maxima);
            if maxima[2] > 0.0 && tot.nan_at.is_none() {
                tot.nan_at = Some(ELSEWHERE);
            }
            if tot.wmax2 < maxima[0] {
                (tot.wmax2, tot.wmax_at) = (maxima[0], ELSEWHERE);
            }
            if tot.umax2 < maxima[1] {
                (tot.umax2, tot.umax_at) = (maxima[1], ELSEWHERE);
            }
        }
        let n = (grid.plane() * grid.nz_whole) as f64;
        let dv = grid.cell_volume();
        let circulation = if grid.dim == 2 {
            tot.wsum[0] * dv
        } else {
            (tot.wsum[0].powi(2) + tot.wsum[1].powi(2) + tot.wsum[2].powi(2)).sqrt() * dv
        };
        let sample = Sample {
            t: 0.0,
            dt: 0.0,
            energy: 0.5 * tot.u2 / n,
            enstrophy: 0.5 * tot.w2 / n,
            circulation,
            max_omega: tot.wmax2.sqrt(),
            max_u: tot.umax2.sqrt(),
        };
        let at = Extremes {
            nan_at: tot.nan_at,
            omega_at: tot.wmax_at,
            u_at: tot.umax_at,
        };
        (sample, at)
    }
}

/// What bounds an adaptive step besides the sampled flow.
#[derive(Debug, Clone, Copy, Default)]
pub struct StepBounds {
    /// ν/h² when the scene has bodies (for the diffusion-number bound), else 0.
    pub viscous: f64,
    /// √(|g|/h) with a free surface (dt ≤ c / wave), else 0.
    pub wave: f64,
    /// √(a/h), a = [`BodyMotion::gravity`], else 0: the rate at which gravity moves a dynamic
    /// body across a cell. In dt = c / rate a body that starts the step at rest moves ½ c² h
    /// at most; without it a flow at rest would have nothing to bound its first steps but the
    /// next output time, and the result would depend on `output.every`.
    pub body_gravity: f64,
    /// The fastest dynamic body's speed (dt ≤ cfl h / speed), else 0.
    pub body_speed: f64,
}

impl StepBounds {
    /// The bounds of `params` on spacing `h`, with dynamic bodies moving as `motion` says.
    pub fn new(params: &Params, h: f64, motion: BodyMotion) -> Self {
        StepBounds {
            viscous: params.viscous_rate(h),
            wave: params.wave_rate(h),
            body_gravity: (motion.gravity / h).sqrt(),
            body_speed: motion.speed,
        }
    }
}

/// What the dynamic bodies ask of the next step, from the body entities as they are.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct BodyMotion {
    /// The largest speed of a point of a dynamic body, |V| + |Ω| R with R the radius of the
    /// sphere (disk in 2D) of the body's volume.
    pub speed: f64,
    /// The largest acceleration gravity gives a dynamic body released from rest in the fluid,
    /// |g| |ρ_i - ρ_F| / (ρ_i + ρ_F/2) (a sphere's added mass; drag only slows a body down).
    pub gravity: f64,
}

/// The components [`BodyMotion::of`] reads from a body.
pub type BodyItem = (&'static Body, &'static Material, &'static RigidState);

impl BodyMotion {
    /// The motion of the dynamic ones of `bodies` in a `dim`-dimensional run of `params`.
    pub fn of<'a>(
        dim: usize,
        params: &Params,
        bodies: impl Iterator<Item = (&'a Body, &'a Material, &'a RigidState)>,
    ) -> Self {
        let g = params.gravity.iter().map(|g| g * g).sum::<f64>().sqrt();
        let rho_f = params.rho_fluid;
        bodies
            .filter(|(b, _, _)| b.is_dynamic())
            .fold(BodyMotion::default(), |m, (_, mat, st)| {
                let r = if dim == 2 {
                    (st.volume / std::f64::consts::PI).sqrt()
                } else {
                    (3.0 * st.volume / (4.0 * std::f64::consts::PI)).cbrt()
                };
                let rho = mat.density;
                BodyMotion {
                    speed: m
                        .speed
                        .max(st.velocity.length() + st.angular_velocity.length() * r),
                    gravity: m.gravity.max(g * (rho - rho_f).abs() / (rho + 0.5 * rho_f)),
                }
            })
    }
}

/// The step the policy allows for this state, before landing on the next stop time.
pub fn allowed_dt(
    policy: &TimeStep,
    sample: &Sample,
    h: f64,
    fallback: f64,
    bounds: StepBounds,
) -> f64 {
    let StepBounds {
        viscous,
        wave,
        body_gravity,
        body_speed,
    } = bounds;
    match *policy {
        TimeStep::Fixed(dt) => dt,
        TimeStep::Adaptive {
            c,
            dt_max,
            cfl,
            diffusion_number,
        } => {
            let mut dt = f64::INFINITY;
            if viscous > 0.0 {
                dt = dt.min(diffusion_number / viscous);
            }
            if sample.max_omega > 0.0 {
                dt = dt.min(c / sample.max_omega);
            }
            if wave > 0.0 {
                dt = dt.min(c / wave);
            }
            if body_gravity > 0.0 {
                dt = dt.min(c / body_gravity);
            }
            if body_speed > 0.0 {
                dt = dt.min(cfl * h / body_speed);
            }
            if let Some(m) = dt_max {
                dt = dt.min(m);
            }
            if sample.max_u > 0.0 {
                dt = dt.min(cfl * h / sample.max_u);
            }
            if dt.is_finite() { dt } else { fallback }
        }
    }
}

/// The next step: what the policy allows for `sample`; an adaptive step is landed on
/// `stop_at`, a `Fixed` one never changes (the run ends at the first step at or after its end
/// time), so a run stopped early and restarted takes the very steps of one that never stopped.
pub fn next_dt(
    params: &Params,
    sample: &Sample,
    h: f64,
    fallback: f64,
    motion: BodyMotion,
    t: f64,
    stop_at: Option<f64>,
) -> f64 {
    let bounds = StepBounds::new(params, h, motion);
    let dt = allowed_dt(&params.numerics.dt, sample, h, fallback, bounds);
    if params.numerics.dt.lands_on_outputs() {
        land_on(t, dt, stop_at)
    } else {
        dt
    }
}

/// How much longer than `dt` the last step before a stop time may be (relative): the clock is
/// a sum of steps, so after N steps of a `Fixed` dt that divides the end time it misses it by
/// up to about N² ε dt; the rest is then taken as one step rather than split in two.
pub const LAND_TOLERANCE: f64 = 1e-6;

/// Shorten `dt` so that the clock lands exactly on `stop_at`: the time left is split evenly
/// over the fewest steps no longer than `dt` (the last may be longer by [`LAND_TOLERANCE`]), as
/// Basilisk's `dtnext` does. The step then changes by at most dt/(n + 1) with n steps to go,
/// once, when the stop time comes into view, instead of a sliver step at the end: with no-slip
/// imposed once per step, a short step changes the body's drag (issue 35 measured a 4.2% jump
/// at one shortened step), so an output time must not make one.
pub fn land_on(t: f64, dt: f64, stop_at: Option<f64>) -> f64 {
    match stop_at {
        Some(stop) if stop > t => {
            let rest = stop - t;
            if rest <= dt * (1.0 + LAND_TOLERANCE) {
                return rest;
            }
            let n = (rest / (dt * (1.0 + LAND_TOLERANCE))).ceil();
            rest / n
        }
        _ => dt,
    }
}

/// The bodies, for the blow-up messages and the bodies' speed.
type Bodies<'w, 's> = Query<
    'w,
    's,
    (
        &'static Body,
        &'static BodyShape,
        &'static Material,
        &'static RigidState,
    ),
>;

/// The indices and position of the grid node `idx`.
fn node_at(grid: &Grid, idx: usize) -> ((usize, usize, usize), [f64; 3]) {
    let [nx, ny, _] = grid.n;
    let (i, j, k) = (idx % nx, (idx / nx) % ny, idx / (nx * ny));
    ((i, j, k), grid.pos(i, j, k))
}

/// The location of an extreme that another process holds (its node is not on this one's
/// slab).
pub const ELSEWHERE: usize = usize::MAX;

/// The grid node `idx` as indices and position.
fn node(grid: &Grid, idx: usize) -> String {
    if idx == ELSEWHERE {
        return "a node of another process".into();
    }
    let ((i, j, k), p) = node_at(grid, idx);
    let k = k + grid.k0;
    if grid.dim == 2 {
        format!("node ({i}, {j}) at x = ({:.4}, {:.4})", p[0], p[1])
    } else {
        format!(
            "node ({i}, {j}, {k}) at x = ({:.4}, {:.4}, {:.4})",
            p[0], p[1], p[2]
        )
    }
}

/// The grid node `idx`, and the nearest body's surface with the distance to it in cells.
fn place(grid: &Grid, idx: usize, bodies: &Bodies) -> String {
    if idx == ELSEWHERE {
        return node(grid, idx);
    }
    let x = glam::DVec3::from_array(node_at(grid, idx).1);
    let nearest = bodies
        .iter()
        .map(|(b, shape, _, st)| {
            // A moving body is seen through its periodic image nearest the node.
            let mut d = x - st.center;
            if !b.is_static() {
                d += glam::DVec3::from_array(grid.image_shift(d.to_array()));
            }
            let local = st.orientation.inverse() * d;
            (b, shape.level_set.phi(local))
        })
        .min_by(|a, b| a.1.abs().total_cmp(&b.1.abs()));
    let at = node(grid, idx);
    match nearest {
        Some((b, phi)) => {
            let side = if phi > 0.0 { "inside" } else { "outside" };
            format!(
                "{at}, {:.1} cells {side} the surface of body `{}`",
                phi.abs() / grid.h,
                b.name
            )
        }
        None => at,
    }
}

impl Diagnostics {
    /// Keep the sample `s` and choose the next step from it and the bodies' motion.
    fn keep(
        &mut self,
        s: Sample,
        grid: &Grid,
        params: &Params,
        bodies: &Bodies,
        time: &mut SimTime,
    ) {
        self.sample = s;
        let motion = BodyMotion::of(
            grid.dim,
            params,
            bodies.iter().map(|(b, _, m, st)| (b, m, st)),
        );
        time.dt = next_dt(
            params,
            &s,
            grid.h,
            self.dt_fallback,
            motion,
            time.t,
            time.stop_at,
        );
    }
}

/// Measure the initial state and choose the first step (run once before the first step).
#[allow(clippy::too_many_arguments)]
pub fn diagnostics_init(
    grid: Res<Grid>,
    params: Res<Params>,
    fields: Res<Fields>,
    bodies: Bodies,
    mut time: ResMut<SimTime>,
    mut diag: ResMut<Diagnostics>,
    mut failure: ResMut<Failure>,
    split: Option<Res<Decomposition>>,
) {
    let (mut s, at) = diag.measure(&grid, &fields, split.as_deref());
    s.t = time.t;
    diag.omega0 = s.max_omega;
    if let Some(i) = at.nan_at {
        failure.reason = Some(format!(
            "the initial fields are not finite at {}",
            place(&grid, i, &bodies)
        ));
    }
    diag.keep(s, &grid, &params, &bodies, &mut time);
}

/// For a flow that starts at rest (`omega0` = 0) under gravity: √blowup_factor times the speed
/// of a free fall across the box's longest side, √(2 |g| L). Energy bounds a gravity-driven
/// flow's speed by about √(2 |g| L ρ_max/ρ_min) (ten times the free fall at a density ratio of
/// 1:100), so this only fires on a blow-up, which the relative max|ω| guard cannot see when
/// the initial vorticity is zero.
fn rest_speed_limit(grid: &Grid, params: &Params, omega0: f64) -> Option<f64> {
    let g = params.gravity.iter().map(|g| g * g).sum::<f64>().sqrt();
    let l = grid
        .extent()
        .iter()
        .take(grid.dim)
        .fold(0.0f64, |a, &b| a.max(b));
    (omega0 == 0.0 && g > 0.0 && l > 0.0)
        .then(|| params.numerics.blowup_factor.sqrt() * (2.0 * g * l).sqrt())
}

/// The diagnostics system: closes the step.
#[allow(clippy::too_many_arguments)]
pub fn diagnostics(
    grid: Res<Grid>,
    params: Res<Params>,
    fields: Res<Fields>,
    bodies: Bodies,
    mut time: ResMut<SimTime>,
    mut diag: ResMut<Diagnostics>,
    mut failure: ResMut<Failure>,
    split: Option<Res<Decomposition>>,
) {
    time.t += time.dt;
    time.step += 1;
    // Fields no system changed since the last measure (a vacuum run's) measure the same.
    let (mut s, at) = if fields.is_changed() {
        diag.measure(&grid, &fields, split.as_deref())
    } else {
        (diag.sample, Extremes::default())
    };
    s.t = time.t;
    s.dt = time.dt;
    let step = time.step;
    if let Some(i) = at.nan_at {
        failure.reason = Some(format!(
            "blow-up: the velocity or vorticity is not finite at {} after step {step} (t = {:.6})",
            place(&grid, i, &bodies),
            time.t
        ));
    } else if let Some(limit) = rest_speed_limit(&grid, &params, diag.omega0)
        && s.max_u > limit
    {
        failure.reason = Some(format!(
            "blow-up: max|u| = {:.4e} at {} after step {step} (t = {:.6}) exceeds {limit:.4e}, √blowup_factor times the speed of a free fall across the box (a flow that starts at rest and is driven by gravity cannot get there); max|ω| = {:.4e} at {}; reduce the time step (numerics.dt) or refine the grid",
            s.max_u,
            place(&grid, at.u_at, &bodies),
            time.t,
            s.max_omega,
            place(&grid, at.omega_at, &bodies),
        ));
    } else if diag.omega0 > 0.0 && s.max_omega > params.numerics.blowup_factor * diag.omega0 {
        failure.reason = Some(format!(
            "blow-up: max|ω| = {:.4e} at {} after step {step} (t = {:.6}) exceeds {} times its initial value {:.4e}; reduce the time step (numerics.dt) or refine the grid",
            s.max_omega,
            place(&grid, at.omega_at, &bodies),
            time.t,
            params.numerics.blowup_factor,
            diag.omega0
        ));
    } else if let TimeStep::Fixed(dt) = params.numerics.dt
        && s.max_u * dt / grid.h > 20.0
    {
        failure.reason = Some(format!(
            "blow-up: max|u| dt / h = {:.1} at {} after step {step} (t = {:.6}), far beyond the CFL limit; use a smaller fixed dt or an Adaptive step",
            s.max_u * dt / grid.h,
            place(&grid, at.u_at, &bodies),
            time.t
        ));
    }
    if let Some(d) = split.as_deref() {
        d.agree_failure(&mut failure.reason);
    }
    diag.keep(s, &grid, &params, &bodies, &mut time);
}

/// Clock, time step and global quantities: the first dt at startup, then every step.
/// The fallback step is a hundredth of the end time the run starts with.
#[derive(Debug, Clone, Copy, Default)]
pub struct DiagnosticsPlugin;

impl crate::schedule::Plugin for DiagnosticsPlugin {
    fn name(&self) -> &'static str {
        "diagnostics"
    }

    fn build(&self, ctx: &mut crate::schedule::PluginContext) -> anyhow::Result<()> {
        use crate::schedule::PhysicsSet;
        let end = ctx.world.resource::<SimTime>().stop_at;
        let grid = ctx.world.resource::<Grid>();
        let diag = Diagnostics::new(grid, end.map_or(f64::INFINITY, |t| t / 100.0));
        ctx.insert_resource(diag);
        ctx.checkpoint_part::<Diagnostics>("diagnostics", 1)?;
        ctx.add_startup_system_in(
            PhysicsSet::Diagnostics,
            "diagnostics_init",
            diagnostics_init,
        )?;
        ctx.add_system(PhysicsSet::Diagnostics, "diagnostics", diagnostics)?;
        Ok(())
    }
}
