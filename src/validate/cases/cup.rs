//! `cup`: the paper's Fig. 10 (section 5): a cup of density 1.2 dropped onto water.

use crate::bodies::free_surface::LiquidLevelSet;
use crate::sim::engine::Simulation;
use crate::validate::{Case, KnownFailure, Report, Row, RunTime, bundled_scene};

/// The case: what it checks, against what, and the rows known to fail.
pub const CASE: Case = Case {
    name: "cup",
    description: "the paper's Fig. 10: a cup of density 1.2 dropped onto water enters it, rises again briefly after the impact, turns, fills and ends on the floor; liquid volume within 1%",
    reference: "Coquerelle & Cottet 2008, section 5, Fig. 10",
    full: "scenes/cup.ron (128^3, ratio 1:1000) to t = 0.6",
    quick: "scenes/cup.ron at 48^3 (about 2 minutes on 2 cores)",
    full_time: RunTime::Long,
    quick_time: RunTime::Minutes,
    run: cup,
    known_failures: &[
        KnownFailure {
            row: "the run reaches t = 0.6 without blowing up",
            quick: false,
            full: true,
            why: "not run to its end since the momentum form (issue 44; hours on 2 cores): at 1:1000 the 128^3 run passes the impact cleanly (measured to t = 0.04: the flow's mean |u|^2/2 peaks at 1.37 at t = 0.0123, then falls to 0.32; max |vorticity| 6.3e3 at the impact, 1.0e3 to 3.1e3 after t = 0.02; the step 8e-5 at the impact, then 1.6e-4 to 4.1e-4; a smooth waterline around the cup at t = 0.02). In vorticity form at 1:100 its energy climbed from 1.86 at t = 0.024 to 200 at 0.036 (max |vorticity| 5e4, the step 3e-6), in the gas at the waterline; issues 34 and 44",
        },
        KnownFailure {
            row: "the cup ends on the floor",
            quick: true,
            full: true,
            why: "in momentum form (issue 44) the 48^3 run at the paper's 1:1000 reaches t = 0.6: the cup enters the water, its centre rises 0.083 after the impact, it turns (7.6 rad per unit time), the liquid volume outside the bodies holds to 2e-12, but at t = 0.6 its centre is still 0.77 cup heights above the floor (0.71 asked; 0.87 when the volume kept counted the liquid continued inside the cup; 0.79 at 1:100; 1.21 at 1:100 in vorticity form): it has not filled and sunk yet; the bodies in a free surface move by the projection (by Newton-Euler with its virtual mass the cup ended at 0.84, and floating boxes capsized: docs/numerics.md); issues 34 and 44",
        },
    ],
};

/// The paper's Fig. 10 (section 5): a cup of density 1.2 dropped onto water. The cup enters
/// the water, its centre rises again at least briefly after the first impact, it turns, water
/// enters its cavity, the liquid volume drifts less than 1%, and it ends on the floor.
/// `scenes/cup.ron` (128³) in full, at 48³ quick (it blows up either way, issue 17; 48³ shows
/// it in 40 s instead of the 100 s of 64³). A run whose velocity passes 5 times the
/// impact speed of a free fall from the release height to the floor (a splash's jets reach a
/// few times the impact speed) stops there as a failing row.
pub fn cup(quick: bool) -> anyhow::Result<Report> {
    let mut rep = Report::new("cup");
    let mut scene = bundled_scene("cup.ron")?;
    if quick {
        scene = scene.edit(|s| s.domain.cells = Some(vec![48, 48, 48]))?;
    }
    let g = glam::DVec3::from_array(scene.gravity()).length();
    let end = scene.numerics.end_time;
    let surface = match scene.free_surface.as_ref().and_then(|f| f.liquid.first()) {
        Some(crate::scene::LiquidRegion::Below { height, .. }) => *height,
        _ => anyhow::bail!("cup.ron: the liquid is not a pool"),
    };
    let z0 = scene.bodies[1].position[2];
    let floor = 0.5 - 0.47;
    let limit = 5.0 * (2.0 * g * (z0 - floor)).sqrt();
    let mut sim = crate::validate::simulation(scene)?;
    sim.set_stop_at(Some(end));
    let cup_state = |sim: &mut Simulation| {
        crate::io::checkpoint::body_states(sim)
            .into_iter()
            .find(|s| s.name == "cup")
            .map(|s| s.rigid)
    };
    let (mut zmin, mut rebound, mut entered) = (f64::INFINITY, 0.0f64, false);
    let (mut spin, mut drift) = (0.0f64, 0.0f64);
    let mut blew_up = None;
    while sim.time() < end - 1e-12 {
        sim.step()?;
        let umax = sim.sample().max_u;
        if umax.is_nan() || umax >= limit {
            blew_up = Some(sim.time());
            break;
        }
        let Some(st) = cup_state(&mut sim) else {
            anyhow::bail!("cup.ron: no body named cup");
        };
        let z = st.center[2];
        // The cup is in the water once its centre is below the surface.
        entered |= z < surface;
        if z < zmin {
            zmin = z;
        } else if entered {
            rebound = rebound.max(z - zmin);
        }
        spin = spin.max(st.angular_velocity.length());
        let ls = sim.world.resource::<LiquidLevelSet>();
        drift = drift.max((ls.volume / ls.target_volume - 1.0).abs());
    }
    let t = sim.time();
    rep.rows.push(Row::yes_no(
        match blew_up {
            Some(t) => format!(
                "the run reaches t = {end} without blowing up (max |u| passed {limit:.0} at t = {t:.4})"
            ),
            None => format!("the run reaches t = {end} without blowing up"),
        },
        blew_up.is_none(),
    ));
    if blew_up.is_some() {
        rep.notes.push(format!(
            "stopped at t = {t:.4}: centre lowest {zmin:.4}, largest |angular velocity| {spin:.2}, volume drift {drift:.2e}"
        ));
        return Ok(rep);
    }
    let h = sim.grid().h;
    let last = cup_state(&mut sim).map(|s| s.center[2]).unwrap_or(f64::NAN);
    rep.rows
        .push(Row::yes_no("the cup enters the water", entered));
    rep.rows.push(Row::yes_no(
        format!("its centre rises again after the first impact (by {rebound:.4})"),
        rebound > 0.0,
    ));
    rep.rows.push(Row::yes_no(
        format!("it turns (largest |angular velocity| {spin:.2} rad per unit time)"),
        spin > 1.0,
    ));
    rep.rows.push(Row::abs(
        "liquid volume drift over the run",
        0.0,
        drift,
        0.01,
    ));
    // Outer height 0.2: on the floor its centre is about 0.1 above it (tilted, a little more).
    rep.rows.push(Row::range(
        "the cup ends on the floor: centre height above the floor, in cup heights",
        0.0,
        0.5 + 2.0 * h / 0.2,
        (last - floor) / 0.2,
    ));
    Ok(rep)
}
