//! `ellipsoid-sphere`: the paper's Fig. 9: an ellipsoid falling in vacuum on a fixed sphere turns
//! about all three axes, with the total energy conserved.

use super::common::{dynamic_states, energy, energy_plot, leapfrog_mid};
use crate::bodies::RigidState;
use crate::validate::{Case, Report, Row, RunTime, bundled_scene};
use glam::DVec3;

/// The case: what it checks, against what, and the rows known to fail.
pub const CASE: Case = Case {
    name: "ellipsoid-sphere",
    description: "after contact the ellipsoid turns about all three axes; total energy within 5%",
    reference: "paper Fig. 9",
    full: "scenes/ellipsoid-sphere.ron",
    quick: "the full case (a few seconds)",
    full_time: RunTime::Seconds,
    quick_time: RunTime::Seconds,
    run: ellipsoid_sphere,
    known_failures: &[],
};

/// Paper section 4.2.3, Fig. 9: an ellipsoid falling in vacuum on a fixed sphere turns about
/// all three axes, with the total energy conserved.
pub fn ellipsoid_sphere(quick: bool) -> anyhow::Result<Report> {
    let _ = quick;
    let mut rep = Report::new("ellipsoid-sphere");
    let scene = bundled_scene("ellipsoid-sphere.ron")?;
    let g = DVec3::from_array(scene.gravity());
    let floor = DVec3::new(0.0, 0.0, scene.bodies[0].position[2]);
    let end = scene.numerics.end_time;
    let mut sim = crate::validate::simulation(scene)?;
    // The χ volume and inertia are integrated in the first step: E0 is taken after it.
    sim.set_stop_at(Some(end));
    let mut e0 = None;
    let mut emax_dev = 0.0f64;
    let mut wmax = DVec3::ZERO;
    let mut contact = false;
    // Symplectic Euler is a leapfrog: after step k the state holds x_{k+1} and v_{k+1/2}, and
    // the contact potential of x_k. The energy of x_k is taken with v_k = (v_{k-1/2} +
    // v_{k+1/2})/2 (the standard leapfrog energy), and likewise for Ω.
    let mut prev: Option<RigidState> = None;
    let mut echange = Vec::new();
    while sim.time() < end * (1.0 - 1e-12) {
        sim.step()?;
        let st = dynamic_states(&mut sim);
        let (_, s, rho, contact_energy) = &st[0];
        if let Some(p) = prev {
            let e = energy(&leapfrog_mid(&p, s), *rho, g, floor) + contact_energy;
            let e0 = *e0.get_or_insert(e);
            emax_dev = emax_dev.max(((e - e0) / e0).abs());
            echange.push((sim.time(), (e - e0) / e0));
        }
        prev = Some(*s);
        if let Some(c) = sim
            .world
            .get_resource::<crate::systems::collision::Contacts>()
            && !c.records.is_empty()
        {
            contact = true;
        }
        if contact {
            wmax = wmax.max(s.angular_velocity.abs());
        }
    }
    rep.rows.push(Row::yes_no("contact happened", contact));
    for (a, name) in ["x", "y", "z"].iter().enumerate() {
        // "Clearly non-zero": at least 0.1 rad/time (the impact speed over the ellipsoid's
        // half-length is about 2.6 rad/time).
        rep.rows.push(Row::range(
            format!("max |omega_{name}| after contact (at least 0.1)"),
            0.1,
            f64::INFINITY,
            wmax[a],
        ));
    }
    rep.rows.push(Row::abs(
        "largest relative change of total energy (kinetic + gravity above the floor + contact)",
        0.0,
        emax_dev,
        0.05,
    ));
    rep.notes.push(format!(
        "max |omega| after contact per axis: {:.3}, {:.3}, {:.3} rad/time",
        wmax.x, wmax.y, wmax.z
    ));
    rep.plots.push(energy_plot(echange));
    Ok(rep)
}
