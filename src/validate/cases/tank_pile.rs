//! `tank-pile`: the spheres of `tank-200` dropped into a closed box of fluid settle into a pile.

use super::common::{dynamic_states, smallest_sphere_gap, tank_geometry};
use crate::validate::{Case, PlotSpec, Report, Row, RunTime, bundled_scene};
use glam::DVec3;

/// The case: what it checks, against what, and the rows known to fail.
pub const CASE: Case = Case {
    name: "tank-pile",
    description: "spheres dropped in a box of fluid: no overlap deeper than eps/2; at the end at rest (under 2% of the Stokes velocity) and every sphere touching another or the floor",
    reference: "issue criterion (Stokes settling velocity)",
    full: "200 spheres (scenes/tank-200.ron) to t = 6",
    quick: "the bottom layer (36 spheres) to t = 1.5",
    full_time: RunTime::Long,
    quick_time: RunTime::Minutes,
    run: tank_pile,
    known_failures: &[],
};

/// Many bodies in fluid: the 200 spheres of `tank-200` (radius 0.05, density 1.5) dropped
/// into a closed box of fluid settle into a pile: at the end every sphere rests (speed under
/// 2% of a single sphere's Stokes settling velocity) and touches another sphere or the floor
/// (gap within the contact range), and over the whole run no two bodies interpenetrate deeper
/// than ε/2. The quick version drops the bottom layer (36 spheres) onto the floor.
pub fn tank_pile(quick: bool) -> anyhow::Result<Report> {
    let mut rep = Report::new("tank-pile");
    let mut scene = bundled_scene("tank-200.ron")?;
    if quick {
        scene = scene.edit(|s| {
            s.bodies.truncate(37);
            s.numerics.end_time = 1.5;
        })?;
    }
    let g = DVec3::from_array(scene.gravity()).length();
    let eps = scene.resolved().contact.eps;
    let touch = scene.contact.range * eps;
    let nu = scene.fluid.viscosity;
    let rho_f = scene.fluid.density;
    let (lo, hi, r) = tank_geometry(&scene)?;
    let rho_s = scene.resolved().densities[1];
    // Stokes settling velocity of one sphere in unbounded fluid.
    let u_stokes = 2.0 / 9.0 * (rho_s / rho_f - 1.0) * g * r * r / nu;
    let n = scene.bodies.len() - 1;
    let end = scene.numerics.end_time;
    let mut sim = crate::validate::simulation(scene)?;
    sim.set_stop_at(Some(end));
    let mut worst = f64::INFINITY;
    let mut vmax_curve = Vec::new();
    let mut top_curve = Vec::new();
    let mut last = Vec::new();
    while sim.time() < end * (1.0 - 1e-12) {
        sim.step()?;
        let st = dynamic_states(&mut sim);
        worst = worst.min(smallest_sphere_gap(st.iter().map(|e| &e.1), r, lo, hi));
        let vmax = st.iter().map(|e| e.1.velocity.length()).fold(0.0, f64::max);
        let top = st.iter().map(|e| e.1.center.z + r).fold(lo, f64::max);
        vmax_curve.push((sim.time(), vmax / u_stokes));
        top_curve.push((sim.time(), top));
        last = st.into_iter().map(|e| e.1).collect();
    }
    // At the end: the fastest sphere, and the spheres touching nothing below or beside them.
    let vmax_end = last
        .iter()
        .map(|s| s.velocity.length())
        .fold(0.0f64, f64::max);
    let mut loose = 0;
    for (a, sa) in last.iter().enumerate() {
        let mut gap = sa.center.z - lo - r;
        for (b, sb) in last.iter().enumerate() {
            if a != b {
                gap = gap.min((sb.center - sa.center).length() - 2.0 * r);
            }
        }
        if gap > touch {
            loose += 1;
        }
    }
    let top_end = last.iter().map(|s| s.center.z + r).fold(lo, f64::max);
    let fraction = n as f64 * 4.0 / 3.0 * std::f64::consts::PI * r.powi(3)
        / ((hi - lo).powi(2) * (top_end - lo));
    rep.rows.push(Row::abs(
        "deepest interpenetration / eps over the run (sphere-sphere or sphere-wall), at most 1/2",
        0.0,
        (-worst / eps).max(0.0),
        0.5,
    ));
    rep.rows.push(Row::abs(
        "fastest sphere at the end / Stokes settling velocity (at rest: under 0.02)",
        0.0,
        vmax_end / u_stokes,
        0.02,
    ));
    rep.rows.push(Row::abs(
        "spheres at the end touching no sphere and not the floor (gap > contact range)",
        0.0,
        loose as f64,
        0.0,
    ));
    rep.notes.push(format!(
        "{n} spheres to t = {end}: smallest gap over the run {worst:.5} ({:.3} eps); Stokes velocity {u_stokes:.4}; fastest sphere at the end {vmax_end:.2e}; top of the pile {top_end:.4} (floor {lo}), mean solid fraction below it {fraction:.3}",
        worst / eps
    ));
    rep.plots.push(
        PlotSpec::new(
            "speed",
            "fastest sphere / Stokes settling velocity",
            "t",
            "max |V| / U_stokes",
        )
        .measured("measured", vmax_curve)
        .reference_level("at rest: 0.02", 0.02),
    );
    rep.plots.push(
        PlotSpec::new("top", "top of the highest sphere", "t", "z")
            .measured("measured", top_curve)
            .reference_level("floor", lo),
    );
    Ok(rep)
}
