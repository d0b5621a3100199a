//! `taylor-green-2d`: the 2D Taylor-Green vortex: kinetic energy against exp(-2νk²t) over one decay
//! time.

use crate::validate::PlotSpec;
use crate::validate::bundled_scene;
use crate::validate::{Case, Report, Row, RunTime};

/// The case: what it checks, against what, and the rows known to fail.
pub const CASE: Case = Case {
    name: "taylor-green-2d",
    description: "kinetic energy against exp(-2 nu k^2 t) within 0.5% over one decay time",
    reference: "analytic",
    full: "128x128",
    quick: "64x64",
    full_time: RunTime::Seconds,
    quick_time: RunTime::Seconds,
    run: taylor_green_2d,
    known_failures: &[],
};

/// 2D Taylor-Green: kinetic energy against exp(-2νk²t) over one decay time.
fn taylor_green_2d(quick: bool) -> anyhow::Result<Report> {
    let mut scene = bundled_scene("taylor-green-2d.ron")?;
    if quick {
        scene = scene.edit(|s| s.domain.cells = Some(vec![64, 64]))?;
    }
    let k = match &scene.initial[0] {
        crate::scene::InitialVorticity::TaylorGreen2d { wavenumber, .. } => *wavenumber,
        _ => anyhow::bail!("taylor-green-2d.ron must start with a TaylorGreen2d field"),
    };
    let nu = scene.fluid.viscosity;
    let t_end = 1.0 / (2.0 * nu * 2.0 * k * k);
    let mut sim = crate::validate::simulation(scene)?;
    let e0 = sim.sample().energy;
    let mut worst = (0.0f64, 0.0f64, 0.0f64);
    let mut curve = vec![(sim.time(), 1.0)];
    sim.run_until(t_end, |s| {
        let sm = s.sample();
        let exact = e0 * (-4.0 * nu * k * k * sm.t).exp();
        let err = ((sm.energy - exact) / exact).abs();
        if err > worst.0 {
            worst = (err, sm.t, sm.energy);
        }
        curve.push((sm.t, sm.energy / e0));
    })?;
    let sm = sim.sample();
    let mut rep = Report::new("taylor-green-2d");
    rep.rows.push(Row::rel(
        format!("E(t = {:.3}) / E0 (one decay time)", sm.t),
        (-4.0 * nu * k * k * sm.t).exp(),
        sm.energy / e0,
        0.005,
    ));
    rep.rows.push(Row::rel(
        format!("worst E(t)/E0 over the run (at t = {:.3})", worst.1),
        (-4.0 * nu * k * k * worst.1).exp(),
        worst.2 / e0,
        0.005,
    ));
    rep.notes.push(format!(
        "{}x{} grid, ν = {nu}, {} steps",
        sim.grid().n[0],
        sim.grid().n[1],
        sim.steps()
    ));
    let exact: Vec<(f64, f64)> = curve
        .iter()
        .map(|&(t, _)| (t, (-4.0 * nu * k * k * t).exp()))
        .collect();
    rep.plots.push(
        PlotSpec::new("energy", "kinetic energy decay", "t", "E(t) / E0")
            .measured(
                format!("measured ({}x{})", sim.grid().n[0], sim.grid().n[1]),
                curve,
            )
            .reference("analytic: exp(-2ν|k|²t), |k|² = 2k²", exact),
    );
    Ok(rep)
}
