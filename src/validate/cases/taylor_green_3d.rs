//! `taylor-green-3d`: the 3D Taylor-Green vortex at Re = 1600: kinetic energy at t = 5 against the
//! spectral reference.

use crate::validate::PlotSpec;
use crate::validate::bundled_scene;
use crate::validate::{Case, Report, Row, RunTime};

/// The case: what it checks, against what, and the rows known to fail.
pub const CASE: Case = Case {
    name: "taylor-green-3d",
    description: "E(t = 5) within 2% of 0.1184 at Re = 1600",
    reference: "spectral DNS (Brachet et al. 1983; van Rees et al. 2011)",
    full: "64^3, 96^3 and 128^3; the grid-scale dissipation's share of the energy lost falls with h",
    quick: "48^3 (the same 2% tolerance)",
    full_time: RunTime::Minutes,
    quick_time: RunTime::Seconds,
    run: taylor_green_3d,
    known_failures: &[],
};

/// 3D Taylor-Green at Re = 1600: kinetic energy at t = 5 against the spectral reference.
fn taylor_green_3d(quick: bool) -> anyhow::Result<Report> {
    // Reference: E(5) = 0.1184 for E0 = 0.125 (spectral DNS of the Re = 1600 Taylor-Green
    // vortex, e.g. Brachet et al. 1983; van Rees et al., J. Comput. Phys. 230 (2011)).
    const E5: f64 = 0.1184;
    let mut rep = Report::new("taylor-green-3d");
    let sizes: &[usize] = if quick { &[48] } else { &[64, 96, 128] };
    let mut plot = PlotSpec::new("energy", "kinetic energy, Re = 1600", "t", "E(t)");
    // What the grid-scale dissipation removed by t = 5, relative to the energy lost.
    let mut share = Vec::new();
    for &n in sizes {
        let scene =
            bundled_scene("taylor-green-3d.ron")?.edit(|s| s.domain.cells = Some(vec![n, n, n]))?;
        let mut sim = crate::validate::simulation(scene)?;
        let e0 = sim.sample().energy;
        let start = std::time::Instant::now();
        let mut curve = vec![(sim.time(), e0)];
        sim.run_until(5.0, |s| curve.push((s.time(), s.sample().energy)))?;
        plot = plot.measured(format!("measured {n}^3"), curve);
        let e = sim.sample().energy;
        rep.rows
            .push(Row::rel(format!("{n}^3: E(t = 5)"), E5, e, 0.02));
        let removed = sim
            .world
            .resource::<crate::systems::diffusion::GridScaleDissipation>()
            .removed;
        share.push((n, removed / (e0 - e)));
        rep.notes.push(format!(
            "{n}^3: E0 = {e0:.6} (0.125 exact), {} steps, {:.1} s; the grid-scale dissipation removed {removed:.3e} by t = 5, {:.3}% of the energy lost",
            sim.steps(),
            start.elapsed().as_secs_f64(),
            100.0 * removed / (e0 - e)
        ));
    }
    if share.len() > 1 {
        rep.rows.push(Row::yes_no(
            format!(
                "the grid-scale dissipation's share of the energy lost by t = 5 falls as h does ({})",
                share
                    .iter()
                    .map(|(n, f)| format!("{n}^3: {:.3}%", 100.0 * f))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
            share.windows(2).all(|w| w[1].1 < w[0].1),
        ));
    }
    if quick {
        rep.notes
            .push("quick: 48^3 only, with the 2% tolerance the case sets for 128^3".into());
    }
    rep.plots
        .push(plot.reference_points("spectral DNS: E(5) = 0.1184", vec![(5.0, E5)]));
    Ok(rep)
}
