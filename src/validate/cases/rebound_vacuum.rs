//! `rebound-vacuum`: the paper's Fig. 1: a disk dropped in vacuum on a plane rebounds to its drop
//! height.

use super::common::dynamic_states;
use crate::validate::{Case, PlotSpec, Report, Row, RunTime, bundled_scene};

/// The case: what it checks, against what, and the rows known to fail.
pub const CASE: Case = Case {
    name: "rebound-vacuum",
    description: "three rebounds within 2% of the drop height; smallest gap in [0.1, 3] eps",
    reference: "paper Fig. 1",
    full: "scenes/rebound-vacuum.ron",
    quick: "the full case (a few seconds)",
    full_time: RunTime::Seconds,
    quick_time: RunTime::Seconds,
    run: rebound_vacuum,
    known_failures: &[],
};

/// Paper Fig. 1: a disk dropped in vacuum on a plane rebounds to its drop height.
pub fn rebound_vacuum(quick: bool) -> anyhow::Result<Report> {
    // The full case takes a few seconds, so `quick` runs it unchanged.
    let _ = quick;
    let mut rep = Report::new("rebound-vacuum");
    let scene = bundled_scene("rebound-vacuum.ron")?;
    let r = 0.1;
    let y0 = scene.bodies[1].position[1];
    let eps = scene.resolved().contact.eps;
    let end = scene.numerics.end_time;
    let mut sim = crate::validate::simulation(scene)?;
    let mut ys = vec![(sim.time(), y0)];
    sim.set_stop_at(Some(end));
    while sim.time() < end * (1.0 - 1e-12) {
        sim.step()?;
        let st = dynamic_states(&mut sim);
        ys.push((sim.time(), st[0].1.center.y));
    }
    let drop = y0 - r;
    let mut apexes = Vec::new();
    let mut gaps = Vec::new();
    for w in ys.windows(3) {
        let (a, b, c) = (w[0].1, w[1].1, w[2].1);
        if b > a && b >= c {
            apexes.push(b);
        }
        if b < a && b <= c {
            gaps.push(b - r);
        }
    }
    for k in 0..3 {
        let apex = apexes.get(k).copied().unwrap_or(f64::NAN);
        rep.rows.push(Row::rel(
            format!("rebound {}: height of the disk's lowest point", k + 1),
            drop,
            apex - r,
            0.02,
        ));
    }
    let gmin = gaps.iter().copied().fold(f64::INFINITY, f64::min);
    // Between 0.1 ε and 3 ε.
    rep.rows
        .push(Row::range("smallest gap / eps", 0.1, 3.0, gmin / eps));
    rep.notes.push(format!(
        "drop height {drop}; rebound heights {}; smallest gaps / eps {}",
        apexes
            .iter()
            .take(3)
            .map(|a| format!("{:.6}", a - r))
            .collect::<Vec<_>>()
            .join(", "),
        gaps.iter()
            .take(3)
            .map(|g| format!("{:.3}", g / eps))
            .collect::<Vec<_>>()
            .join(", ")
    ));
    rep.plots.push(
        PlotSpec::new("height", "height of the disk's centre", "t", "y")
            .measured("measured", ys)
            .reference_level(format!("drop height (centre at y = {y0})"), y0)
            .reference_level(format!("touching the plane (y = r = {r})"), r),
    );
    Ok(rep)
}
