//! `high-re-sphere`: a sphere falling through water at a realistic viscosity (issue 32).
//!
//! A sphere of radius 0.1 and density 1.2 in water (ν = 1e-4 cgs, g = -980): it falls at about
//! 7 cm/s, Re = U d / ν ≈ 1.4e4, a cell Reynolds number |u| h / ν near 1000. Nothing in it is
//! resolved at the grid scale, which is what the grid-scale dissipation of the diffusion
//! system is for (before it, both runs below blew up: the closed box at t = 0.18 with the
//! sphere at rest on the floor, the open box at t = 0.198 in mid-fall).
//!
//! - The closed box (walls a `Complement(Box)`, the unit cube; released at z = 0.58): the run
//!   reaches t = 0.6, the sphere ends on the floor (its gap within the contact's range, 6 ε with
//!   ε = h) at rest (below 5% of its largest fall speed), and once it rests the fluid's kinetic
//!   energy does not grow (nothing drives it: dE/dt = -2ν⟨|ω|²⟩ minus what the dissipation
//!   removes, so growth is a numerical source). The energy the grid-scale dissipation removes
//!   over the fall (to t = 0.1) is the same within 10% at the default step and at half (and a
//!   quarter) of it, with c and every bound of the step scaled: it is a rate per unit time,
//!   not per step.
//! - The open periodic box 1 x 1 x 2 (no walls; released at z = 1.85): the run reaches t = 0.3
//!   (then the sphere nears the bottom of the box). Its fall speed is printed beside the
//!   terminal speed of the standard drag curve (Clift & Gauvin 1970), which this grid (6.4 cells
//!   per radius, a boundary layer far thinner than a cell) is not expected to reach.

use super::common::dynamic_body;
use crate::scene::Scene;
use crate::systems::diffusion::GridScaleDissipation;
use crate::validate::{Case, KnownFailure, Report, Row, RunTime};

/// The case: what it checks, against what, and the rows known to fail.
pub const CASE: Case = Case {
    name: "high-re-sphere",
    description: "a sphere of density 1.2 falling through water (nu = 1e-4 cgs, Re about 1.4e4, cell Reynolds number about 1000) with the default numerics: it runs to the end, rests on the floor of a closed box, the fluid's energy never grows once it rests, and the grid-scale dissipation removes the same energy per unit time at any step",
    reference: "energy balance of a flow with no driving (dE/dt <= 0 once the body rests); the dissipation's rate per unit time (issue 32); the standard drag curve (Clift & Gauvin 1970) for the open box, printed only",
    full: "closed box at 64^3 and 96^3 to t = 0.6, the dissipation at 1/2 and 1/4 of the step, the open periodic box 64x64x128 to t = 0.3",
    quick: "closed box at 64^3 to t = 0.6, the dissipation at 1/2 of the step",
    full_time: RunTime::Minutes,
    quick_time: RunTime::Minutes,
    run: high_re_sphere,
    known_failures: &[
        KnownFailure {
            row: "64^3: largest relative growth of the fluid's kinetic energy once the sphere rests",
            quick: true,
            full: true,
            why: "+1.57% (1% allowed) with the no-slip at surface markers (issue 45; 0 with the solve's velocity stop taken against the body's velocity before its recoil, +1.6% on the nodes inside the surface): the sphere is still moving at 2.4% of its largest speed at t = 0.6 while the contact holds it, and the solve, stopped at 0.5% of the body's velocity, exchanges energy with the fluid; the 96^3 run not re-run; issues 35 and 45",
        },
        KnownFailure {
            row: "64^3: energy removed by the grid-scale dissipation by t = 0.1 at 0.5 of the step",
            quick: true,
            full: true,
            why: "+22.4% (2.133e-2 against 1.743e-2; +20.0% with the velocity stop taken before the recoil) since the no-slip is held at surface markers (issue 45; +11.3%, 6.675e-3 against 5.998e-3, on the nodes inside the surface): the flow inside the body is fluid, and the markers' forcing, spread by the kernel, puts three times as much grid-scale content into the flow as the staircase did; see the row at 0.25 of the step; issues 32 and 45",
        },
        KnownFailure {
            row: "64^3: energy removed by the grid-scale dissipation by t = 0.1 at 0.25 of the step",
            quick: false,
            full: true,
            why: "not re-run with the no-slip at surface markers (issue 45; +20.0% at half the step with them). +21.2% (7.271e-3 against 5.998e-3; +20.9% in the build before; +11.3% at half the step) since the no-slip of systems/noslip.rs holds the sphere's inside rigid at the end of each step: its forcing on the staircase of nodes inside the surface puts grid-scale content into the flow, and the dissipation removes 6.02e-3 by t = 0.1 against 2.19e-3 without it (+19.4% and +4.8% then). The dissipation is a rate per unit time, exactly (tests/suite/spectral.rs), but the state it acts on is not: the M'4 remesh, the method's other sink at the grid scale, damps a mode by O(delta^2) per step, so over a fixed time by O(dt), and at a smaller step more energy reaches the grid scale and the dissipation removes more. Taylor-Green at 64^3 shows the same: removed by t = 5 2.79e-4, 3.61e-4, 4.51e-4 at c = 0.5, 0.25, 0.125 (a per-step filter would remove 2 and 4 times as much); issues 32 and 35",
        },
    ],
};

/// Sphere radius, density, the water's viscosity and gravity (cgs).
const RADIUS: f64 = 0.1;
const DENSITY: f64 = 1.2;
const NU: f64 = 1e-4;
const G: f64 = 980.0;

/// Wall thickness of the closed box outside the unit cube.
const WALL: f64 = 0.03125;

/// The closed box's end time, and the end of the interval over which the dissipation is
/// compared between steps: the fall, before the sphere lands at t = 0.13. After the impact
/// the flow is chaotic and the landing time moves with the step (0.1297, 0.1329 and 0.1344
/// at the default step, half and a quarter of it), which alone changes the fluid's energy at
/// t = 0.131 by a factor of two (0.068, 0.114, 0.132), so no interval that contains the impact
/// can compare what the dissipation does per unit time.
const CLOSED_END: f64 = 0.6;
const COMPARE_END: f64 = 0.1;

/// What one run measured, step by step.
#[derive(Default)]
struct Trace {
    /// (t, fluid kinetic energy per unit volume).
    energy: Vec<(f64, f64)>,
    /// (t, sphere centre height, sphere speed).
    sphere: Vec<(f64, f64, f64)>,
    /// (t, energy removed by the grid-scale dissipation since the start).
    removed: Vec<(f64, f64)>,
    /// Why the run stopped early.
    failure: Option<String>,
}

impl Trace {
    /// The energy removed by time `t`, linear between the steps around it (NaN outside the
    /// run).
    fn removed_at(&self, t: f64) -> f64 {
        let i = self.removed.partition_point(|e| e.0 < t);
        match (
            i.checked_sub(1).map(|j| self.removed[j]),
            self.removed.get(i),
        ) {
            (_, Some(&(t1, r1))) if t1 == t => r1,
            (Some((t0, r0)), Some(&(t1, r1))) => r0 + (r1 - r0) * (t - t0) / (t1 - t0),
            (None, Some(&(t1, r1))) => r1 * t / t1,
            _ => f64::NAN,
        }
    }
}

/// The scene text: `closed` a walled unit cube at n³, else the open periodic 1 x 1 x 2 box at
/// n x n x 2n; the step's c and every bound scaled by `scale`.
fn scene(closed: bool, n: usize, scale: f64, end: f64) -> String {
    let (domain, bodies) = if closed {
        (
            format!(
                "(origin: [-{WALL}, -{WALL}, -{WALL}], extent: [{e}, {e}, {e}], cells: [{n}, {n}, {n}])",
                e = 1.0 + 2.0 * WALL
            ),
            format!(
                "(name: \"box\", shape: Complement(Box(half_extents: [0.5, 0.5, 0.5])), kind: Static, position: [0.5, 0.5, 0.5]),
                 (name: \"sphere\", shape: Sphere(radius: {RADIUS}), density: {DENSITY}, position: [0.5, 0.5, 0.58])"
            ),
        )
    } else {
        (
            format!("(extent: [1.0, 1.0, 2.0], cells: [{n}, {n}, {}])", 2 * n),
            format!(
                "(name: \"sphere\", shape: Sphere(radius: {RADIUS}), density: {DENSITY}, position: [0.5, 0.5, 1.85])"
            ),
        )
    };
    format!(
        r#"Scene(
        name: "high-re-sphere",
        domain: {domain},
        fluid: (density: 1.0, viscosity: {NU}, gravity: [0.0, 0.0, -{G}]),
        numerics: (end_time: {end}, dt: Adaptive(c: {}, cfl: {}, diffusion_number: {})),
        bodies: [{bodies}],
    )"#,
        0.5 * scale,
        4.0 * scale,
        0.5 * scale
    )
}

fn run(closed: bool, n: usize, scale: f64, end: f64) -> anyhow::Result<Trace> {
    let text = scene(closed, n, scale, end);
    let mut sim =
        crate::validate::simulation(Scene::parse(&text, "high-re-sphere", "high-re-sphere")?)?;
    sim.set_stop_at(Some(end));
    let mut tr = Trace::default();
    while sim.time() < end - 1e-12 {
        if let Err(e) = sim.step() {
            tr.failure = Some(format!("{e:#}"));
            break;
        }
        let t = sim.time();
        tr.energy.push((t, sim.sample().energy));
        tr.removed
            .push((t, sim.world.resource::<GridScaleDissipation>().removed));
        let st = dynamic_body(&mut sim).ok_or_else(|| anyhow::anyhow!("no sphere"))?;
        tr.sphere.push((t, st.center.z, st.velocity.length()));
    }
    Ok(tr)
}

/// The terminal speed of the sphere on the standard drag curve of Clift & Gauvin (1970),
/// C_d = 24/Re (1 + 0.15 Re^0.687) + 0.42 / (1 + 42500 Re^-1.16), by fixed-point iteration.
fn terminal_speed() -> f64 {
    let d = 2.0 * RADIUS;
    let mut u: f64 = 10.0;
    for _ in 0..200 {
        let re = u * d / NU;
        let cd =
            24.0 / re * (1.0 + 0.15 * re.powf(0.687)) + 0.42 / (1.0 + 42500.0 * re.powf(-1.16));
        u = (4.0 / 3.0 * d * G * (DENSITY - 1.0) / cd).sqrt();
    }
    u
}

pub fn high_re_sphere(quick: bool) -> anyhow::Result<Report> {
    let mut rep = Report::new("high-re-sphere");
    let grids: &[usize] = if quick { &[64] } else { &[64, 96] };
    for &n in grids {
        let tr = run(true, n, 1.0, CLOSED_END)?;
        let h = (1.0 + 2.0 * WALL) / n as f64;
        let reached = tr.failure.is_none();
        rep.rows.push(Row::yes_no(
            match &tr.failure {
                None => format!("{n}^3 closed box: the run reaches t = {CLOSED_END}"),
                Some(e) => format!("{n}^3 closed box: the run reaches t = {CLOSED_END} ({e})"),
            },
            reached,
        ));
        if !reached {
            continue;
        }
        let peak = tr.sphere.iter().map(|s| s.2).fold(0.0, f64::max);
        let &(_, z_end, v_end) = tr.sphere.last().expect("steps were taken");
        rep.rows.push(Row::range(
            format!(
                "{n}^3: the sphere's gap to the floor at the end, in cells (the contact's range: 6)"
            ),
            0.0,
            6.0,
            (z_end - RADIUS) / h,
        ));
        rep.rows.push(Row::range(
            format!("{n}^3: the sphere's speed at the end, relative to its largest fall speed"),
            0.0,
            0.05,
            v_end / peak,
        ));
        // At rest from the first step after which its speed stays below 5% of the peak.
        let rest = tr
            .sphere
            .iter()
            .rposition(|s| s.2 >= 0.05 * peak)
            .map_or(0, |i| i + 1);
        let t_rest = tr.sphere.get(rest).map_or(f64::NAN, |s| s.0);
        // The largest growth of the energy over any interval after the sphere comes to rest.
        let mut low = f64::INFINITY;
        let mut growth = 0.0f64;
        for &(_, e) in &tr.energy[rest.min(tr.energy.len())..] {
            low = low.min(e);
            growth = growth.max(e / low - 1.0);
        }
        rep.rows.push(Row::range(
            format!(
                "{n}^3: largest relative growth of the fluid's kinetic energy once the sphere rests (from t = {t_rest:.3})"
            ),
            0.0,
            0.01,
            growth,
        ));
        rep.notes.push(format!(
            "{n}^3 closed box: largest fall speed {peak:.3}; at t = {CLOSED_END} the sphere's centre is at z = {z_end:.4}, its speed {v_end:.2e}; energy {:.3e} at rest and {:.3e} at the end; the grid-scale dissipation removed {:.3e} by t = {COMPARE_END} and {:.3e} by the end ({} steps)",
            tr.energy.get(rest).map_or(f64::NAN, |e| e.1),
            tr.energy.last().map_or(f64::NAN, |e| e.1),
            tr.removed_at(COMPARE_END),
            tr.removed.last().map_or(f64::NAN, |e| e.1),
            tr.energy.len()
        ));
        if n == 64 {
            let base = tr.removed_at(COMPARE_END);
            // The quick tier keeps the half step (its row fails as the quarter's does); the
            // quarter step's run alone is 40% of the case's time.
            let scales: &[f64] = if quick { &[0.5] } else { &[0.5, 0.25] };
            for &s in scales {
                let tr_s = run(true, n, s, COMPARE_END)?;
                let what = format!(
                    "64^3: energy removed by the grid-scale dissipation by t = {COMPARE_END} at {s} of the step, against the default step"
                );
                match tr_s.failure {
                    Some(e) => rep.rows.push(Row::yes_no(format!("{what} ({e})"), false)),
                    None => rep
                        .rows
                        .push(Row::rel(what, base, tr_s.removed_at(COMPARE_END), 0.1)),
                }
            }
        }
    }
    if !quick {
        let end = 0.3;
        let tr = run(false, 64, 1.0, end)?;
        rep.rows.push(Row::yes_no(
            match &tr.failure {
                None => format!("64x64x128 open box: the run reaches t = {end}"),
                Some(e) => format!("64x64x128 open box: the run reaches t = {end} ({e})"),
            },
            tr.failure.is_none(),
        ));
        let peak = tr.sphere.iter().map(|s| s.2).fold(0.0, f64::max);
        rep.notes.push(format!(
            "open box: largest fall speed {peak:.3} (terminal speed on the standard drag curve, Clift & Gauvin 1970: {:.3}; at 6.4 cells per radius the boundary layer is far thinner than a cell)",
            terminal_speed()
        ));
    } else {
        rep.notes.push(
            "quick: the closed box at 64^3 with the comparison at 1/2 of the step; the full case adds 96^3, the comparison at 1/4 of the step and the open box"
                .into(),
        );
    }
    Ok(rep)
}
