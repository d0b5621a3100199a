//! `tank-vacuum`: spheres dropped into a closed box in vacuum keep their total energy and never
//! interpenetrate deeper than ε/2.

use super::common::{
    dynamic_states, energy, energy_plot, leapfrog_mid, smallest_sphere_gap, tank_geometry,
};
use crate::bodies::RigidState;
use crate::validate::{Case, Report, Row, RunTime, bundled_scene};
use glam::DVec3;

/// The case: what it checks, against what, and the rows known to fail.
pub const CASE: Case = Case {
    name: "tank-vacuum",
    description: "spheres dropped in a box in vacuum: total energy within 5%, no overlap deeper than eps/2",
    reference: "conservation of energy",
    full: "200 spheres (scenes/tank-200-vacuum.ron)",
    quick: "the first 50 spheres to t = 0.5",
    full_time: RunTime::Minutes,
    quick_time: RunTime::Seconds,
    run: tank_vacuum,
    known_failures: &[],
};

/// Many bodies in vacuum: 200 spheres dropped into a closed box keep their total energy
/// (kinetic + gravity + contact) and never interpenetrate deeper than ε/2.
pub fn tank_vacuum(quick: bool) -> anyhow::Result<Report> {
    let mut rep = Report::new("tank-vacuum");
    let mut scene = bundled_scene("tank-200-vacuum.ron")?;
    if quick {
        // The first 50 spheres (the two bottom layers and a part of the third) for 0.5.
        scene = scene.edit(|s| {
            s.bodies.truncate(51);
            s.numerics.end_time = 0.5;
        })?;
    }
    let g = DVec3::from_array(scene.gravity());
    let eps = scene.resolved().contact.eps;
    let (lo, hi, r) = tank_geometry(&scene)?;
    let n = scene.bodies.len() - 1;
    let end = scene.numerics.end_time;
    let mut sim = crate::validate::simulation(scene)?;
    sim.set_stop_at(Some(end));
    let mut prev: Option<Vec<RigidState>> = None;
    let mut e0 = None;
    let mut dev = 0.0f64;
    let mut echange = Vec::new();
    let mut worst = f64::INFINITY;
    while sim.time() < end * (1.0 - 1e-12) {
        sim.step()?;
        let st = dynamic_states(&mut sim);
        if let Some(p) = &prev {
            // Leapfrog energy of the previous positions (see `ellipsoid_sphere`).
            let mut e = 0.0;
            for ((_, s, rho, contact), ps) in st.iter().zip(p) {
                e += energy(&leapfrog_mid(ps, s), *rho, g, DVec3::splat(lo)) + contact;
            }
            let e0 = *e0.get_or_insert(e);
            dev = dev.max(((e - e0) / e0).abs());
            echange.push((sim.time(), (e - e0) / e0));
        }
        worst = worst.min(smallest_sphere_gap(st.iter().map(|e| &e.1), r, lo, hi));
        prev = Some(st.into_iter().map(|e| e.1).collect());
    }
    rep.rows.push(Row::abs(
        "largest relative change of total energy (kinetic + gravity + contact)",
        0.0,
        dev,
        0.05,
    ));
    rep.rows.push(Row::abs(
        "deepest interpenetration / eps (sphere-sphere or sphere-wall), at most 1/2",
        0.0,
        (-worst / eps).max(0.0),
        0.5,
    ));
    rep.notes.push(format!(
        "{n} spheres to t = {end}: smallest gap {worst:.5} ({:.3} eps)",
        worst / eps
    ));
    rep.plots.push(energy_plot(echange));
    Ok(rep)
}
