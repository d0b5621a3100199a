//! `lamb-oseen`: the Lamb-Oseen vortex: peak vorticity and core radius against the analytic
//! solution once the core area has doubled.

use crate::sim::engine::Simulation;
use crate::validate::PlotSpec;
use crate::validate::bundled_scene;
use crate::validate::{Case, Report, Row, RunTime};
use std::f64::consts::PI;

/// The case: what it checks, against what, and the rows known to fail.
pub const CASE: Case = Case {
    name: "lamb-oseen",
    description: "peak vorticity and core radius within 1% once the core area has doubled",
    reference: "analytic",
    full: "scenes/lamb-oseen.ron (128x128)",
    quick: "the full case (under a second)",
    full_time: RunTime::Seconds,
    quick_time: RunTime::Seconds,
    run: lamb_oseen,
    known_failures: &[],
};

/// Lamb-Oseen: peak vorticity and core radius after the core area has doubled.
fn lamb_oseen(quick: bool) -> anyhow::Result<Report> {
    // The full case takes a fraction of a second, so `quick` runs it unchanged: at 64² the
    // core (σ0 = 3.2 h) is too coarse for M'4 remeshing (peak 7% low), at 128² it is resolved.
    let _ = quick;
    let scene = bundled_scene("lamb-oseen.ron")?;
    let (gamma, s0) = match &scene.initial[0] {
        crate::scene::InitialVorticity::LambOseen {
            circulation,
            core_radius,
            ..
        } => (*circulation, *core_radius),
        _ => anyhow::bail!("lamb-oseen.ron must start with a LambOseen field"),
    };
    let nu = scene.fluid.viscosity;
    let t_end = s0 * s0 / (4.0 * nu);
    let mut sim = crate::validate::simulation(scene)?;
    let peak_of = |s: &Simulation| {
        s.fields().omega()[0]
            .iter()
            .cloned()
            .fold(f64::MIN, f64::max)
    };
    let mut peaks = vec![(sim.time(), peak_of(&sim))];
    sim.run_until(t_end, |s| peaks.push((s.time(), peak_of(s))))?;
    let g = sim.grid().clone();
    let w = &sim.fields().omega()[0];
    let s2 = s0 * s0 + 4.0 * nu * sim.time();
    let peak = w.iter().cloned().fold(f64::MIN, f64::max);
    // Second moment about the centroid: ∫r²ω / ∫ω = σ² for the Gaussian.
    let (mut m0, mut mx, mut my) = (0.0, 0.0, 0.0);
    for j in 0..g.n[1] {
        for i in 0..g.n[0] {
            let p = g.pos(i, j, 0);
            let v = w[g.idx(i, j, 0)];
            m0 += v;
            mx += v * p[0];
            my += v * p[1];
        }
    }
    let (cx, cy) = (mx / m0, my / m0);
    let mut m2 = 0.0;
    for j in 0..g.n[1] {
        for i in 0..g.n[0] {
            let p = g.pos(i, j, 0);
            m2 += w[g.idx(i, j, 0)] * ((p[0] - cx).powi(2) + (p[1] - cy).powi(2));
        }
    }
    let mut rep = Report::new("lamb-oseen");
    rep.rows.push(Row::rel(
        format!("peak vorticity at t = {:.3}", sim.time()),
        gamma / (PI * s2),
        peak,
        0.01,
    ));
    rep.rows.push(Row::rel(
        "core radius σ (from ∫r²ω/∫ω)",
        s2.sqrt(),
        (m2 / m0).sqrt(),
        0.01,
    ));
    rep.notes.push(format!(
        "{}x{} grid, ν = {nu}, σ0 = {s0}, {} steps",
        g.n[0],
        g.n[1],
        sim.steps()
    ));
    let exact: Vec<(f64, f64)> = peaks
        .iter()
        .map(|&(t, _)| (t, gamma / (PI * (s0 * s0 + 4.0 * nu * t))))
        .collect();
    rep.plots.push(
        PlotSpec::new("peak", "peak vorticity", "t", "max ω")
            .measured(format!("measured ({}x{})", g.n[0], g.n[1]), peaks)
            .reference("analytic: Γ / (π (σ0² + 4νt))", exact),
    );
    Ok(rep)
}
