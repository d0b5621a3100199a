//! `sedimentation-2d`: the paper's section 4.1: a 2D disk settling in a cavity onto its floor, with
//! contact.

use super::common::dynamic_body;
use crate::validate::PlotSpec;
use crate::validate::bundled_scene;
use crate::validate::{Case, KnownFailure, Report, Row, RunTime};

/// The case: what it checks, against what, and the rows known to fail.
pub const CASE: Case = Case {
    name: "sedimentation-2d",
    description: "a disk settling onto the floor of a cavity: max fall velocity of two grids within 2% of each other; the disk stays above the floor, rebounds and rests without oscillating; doubling kappa moves the height curve by less than 2h at every time",
    reference: "paper section 4.1",
    full: "h = 1/256 and 1/384, kappa doubled at 1/256",
    quick: "h = 1/64 and 1/96, kappa doubled at 1/64 (the same tolerances)",
    full_time: RunTime::Long,
    quick_time: RunTime::Seconds,
    run: sedimentation_2d,
    known_failures: &[
        KnownFailure {
            row: "max fall velocity, finer grid against coarser",
            quick: true,
            full: false,
            why: "the quick grids (h = 1/64 and 1/96, 8 and 12 cells per radius) refine h and dt together far from the range of the paper's 2% (h = 1/256 against 1/384, where the full case measured 1.9% with Baroclinic): 7.6% here (13.20 and 14.20; 7.2%, 13.26, when the markers landed) since the disk moves by Newton-Euler with the no-slip at its surface markers (issue 45; 6.9%, 11.92 and 12.74, with the no-slip on the nodes inside the surface, issue 35; 6.7% with the projection, 10.92 and 11.66); at a common dt = 7.5e-4 the two grids differed by 3.9% with the projection; issue 16",
        },
        KnownFailure {
            row: "h = 1/64: at rest 0.3 after the impact",
            quick: true,
            full: false,
            why: "with the no-slip at surface markers (issue 45) it rebounds by 0.008 and has 5 local minima of its height after the impact, still moving at 9.4% of its largest speed at the end (on the nodes inside the surface, issue 35, it rebounded by 0.16, e about 0.2 at a Stokes number of about 50, and landed 4 times): the contact model is elastic and the lubrication of the gap is not resolved at 8 cells per radius, so only the fluid's drag takes the energy. A wet restitution (Legendre et al. 2006) or a lubrication force is the fix; issues 35 and 45",
        },
        KnownFailure {
            row: "h = 1/96: at rest 0.3 after the impact",
            quick: true,
            full: false,
            why: "as at h = 1/64: rebound 0.006, 5 local minima and still moving at 6.1% of the fall speed at the end (on the nodes inside the surface: rebound 0.09, 5 landings, 3.7%); issues 35 and 45",
        },
    ],
};

/// What one sedimentation-2d run measured.
struct Sedimentation {
    /// Largest fall speed.
    vmax: f64,
    /// Lowest point of the disk relative to the cavity floor (negative: below it).
    ymin: f64,
    /// Largest relative deviation from rigid motion of the vertical velocity across the disk
    /// during the fall.
    dev: f64,
    /// Height of the first bounce: the first maximum of the centre's height after the impact
    /// minus the impact minimum.
    rebound: f64,
    /// Speed at the end of the run (0.3 after the first impact), relative to `vmax`.
    final_speed: f64,
    /// Local minima of the height after the first impact, deeper than 1% of the radius (1 or
    /// 2: impact, landing; more is an oscillation).
    bounces: usize,
    /// Why the run stopped early, if it did.
    failure: Option<String>,
    /// (t, vertical velocity of the disk) after every step.
    vy: Vec<(f64, f64)>,
    /// (t, height of the disk's centre) after every step.
    y: Vec<(f64, f64)>,
}

/// One sedimentation-2d run at spacing `h`, step `dt` and contact strength `kappa`.
fn sedimentation_run(h: f64, dt: f64, kappa: f64) -> anyhow::Result<Sedimentation> {
    let wall = 8.0 * h;
    let scene = bundled_scene("sedimentation-2d.ron")?.edit(|scene| {
        scene.domain.origin = Some(vec![-wall, -wall]);
        scene.domain.extent = vec![2.0 + 2.0 * wall, 6.0 + 2.0 * wall];
        scene.domain.h = Some(h);
        scene.domain.cells = None;
        scene.numerics.dt = crate::scene::TimeStep::Fixed(dt);
        scene.contact.kappa = Some(kappa);
    })?;
    let r = 0.125;
    let mut sim = crate::validate::simulation(scene)?;
    let mut out = Sedimentation {
        vmax: 0.0,
        ymin: f64::INFINITY,
        dev: 0.0,
        rebound: 0.0,
        final_speed: f64::NAN,
        bounces: 0,
        failure: None,
        vy: Vec::new(),
        y: Vec::new(),
    };
    let mut t_contact = None;
    let mut y_impact = f64::INFINITY;
    let mut ys: Vec<f64> = Vec::new();
    sim.set_stop_at(Some(1.5));
    while sim.time() < 1.5 - 1e-12 {
        if let Err(e) = sim.step() {
            out.failure = Some(e.to_string());
            break;
        }
        let Some(st) = dynamic_body(&mut sim) else {
            break;
        };
        out.vy.push((sim.time(), st.velocity.y));
        out.y.push((sim.time(), st.center.y));
        out.vmax = out.vmax.max(-st.velocity.y);
        out.ymin = out.ymin.min(st.center.y - r);
        if t_contact.is_none() && st.velocity.y >= 0.0 && sim.steps() > 10 {
            t_contact = Some(sim.time());
        }
        if t_contact.is_some() {
            y_impact = y_impact.min(st.center.y);
            ys.push(st.center.y);
            out.final_speed = st.velocity.length() / out.vmax;
        }
        if t_contact.is_some_and(|tc| sim.time() > tc + 0.3) {
            break;
        }
        // Rigidity during the fall (disk well away from the floor): on the horizontal line
        // through the centre, nodes at least one cell inside the disk.
        if st.center.y > 1.0 && st.velocity.y < -1.0 && sim.steps() % 20 == 0 {
            let g = sim.grid().clone();
            let u = &sim.fields().u;
            let j = ((st.center.y - g.origin[1]) / g.h).round() as usize;
            for i in 0..g.n[0] {
                let x = g.pos(i, j, 0);
                let d = ((x[0] - st.center.x).powi(2) + (x[1] - st.center.y).powi(2)).sqrt();
                if d < r - g.h {
                    let uy = u[1][g.idx(i, j, 0)];
                    out.dev = out.dev.max(((uy - st.velocity.y) / st.velocity.y).abs());
                }
            }
        }
    }
    // Local minima and maxima of the height after the impact, ignoring wiggles below 1% of
    // the radius: the rebound is the first maximum above the impact minimum, and more than
    // two minima (impact, landing) is an oscillation.
    let tol = 1e-2 * r;
    let mut falling = true;
    let mut extreme = ys.first().copied().unwrap_or(0.0);
    let mut first_min = None;
    let mut first_max = None;
    out.bounces = 1;
    for &y in &ys {
        if falling {
            if y > extreme + tol {
                first_min.get_or_insert(extreme);
                falling = false;
                extreme = y;
            } else {
                extreme = extreme.min(y);
            }
        } else if y < extreme - tol {
            first_max.get_or_insert(extreme);
            falling = true;
            out.bounces += 1;
            extreme = y;
        } else {
            extreme = extreme.max(y);
        }
    }
    let lo = first_min.unwrap_or(y_impact);
    let hi = first_max.unwrap_or(if falling { lo } else { extreme });
    out.rebound = hi - lo;
    Ok(out)
}

/// Paper section 4.1: a 2D disk settling in a cavity onto its floor, with contact.
fn sedimentation_2d(quick: bool) -> anyhow::Result<Report> {
    let mut rep = Report::new("sedimentation-2d");
    let runs: &[(f64, f64)] = if quick {
        &[(1.0 / 64.0, 3e-3), (1.0 / 96.0, 2e-3)]
    } else {
        &[(1.0 / 256.0, 7.5e-4), (1.0 / 384.0, 5e-4)]
    };
    let mut res = Vec::new();
    for &(h, dt) in runs {
        let s = sedimentation_run(h, dt, 30.0)?;
        rep.notes.push(format!(
            "h = 1/{:.0}, dt = {dt}, kappa = 30: max fall velocity {:.4}, lowest point of the disk {:.5} ({:.2} h above the floor), rebound {:.5}, {} local minima of the height after the impact, final speed {:.2e} of the max, max deviation from rigid motion across the disk during the fall {:.2}% (paper, Fig. 2: about 2% at h = 1/512){}",
            1.0 / h,
            s.vmax,
            s.ymin,
            s.ymin / h,
            s.rebound,
            s.bounces,
            s.final_speed,
            100.0 * s.dev,
            s.failure.as_ref().map(|f| format!("; stopped: {f}")).unwrap_or_default()
        ));
        // "Does not pass through": never h/2 (= ε/2) into the wall, the same bound as for
        // the 200-body pile of the collision issue.
        rep.rows.push(Row::yes_no(
            format!(
                "h = 1/{:.0}: the disk never reaches h/2 into the floor",
                1.0 / h
            ),
            s.ymin > -0.5 * h,
        ));
        rep.rows.push(Row::yes_no(
            format!(
                "h = 1/{:.0}: at rest 0.3 after the impact, no oscillation (speed < 1% of max, at most 2 minima > 1% r)",
                1.0 / h
            ),
            s.final_speed < 0.01 && s.bounces <= 2,
        ));
        res.push(s);
    }
    rep.rows.push(Row::rel(
        "max fall velocity, finer grid against coarser",
        res[0].vmax,
        res[1].vmax,
        0.02,
    ));
    let (h, dt) = runs[0];
    let doubled = sedimentation_run(h, dt, 60.0)?;
    // The paper found "almost no effect" of doubling κ: the height curves at the grid's scale.
    // Both runs take the same Fixed steps, so their samples are at the same times.
    let shift = res[0]
        .y
        .iter()
        .zip(&doubled.y)
        .map(|(a, b)| (a.1 - b.1).abs())
        .fold(0.0f64, f64::max);
    rep.rows.push(Row::abs(
        format!(
            "h = 1/{:.0}: largest change of the height curve with kappa = 60 against 30, in h",
            1.0 / h
        ),
        0.0,
        shift / h,
        2.0,
    ));
    rep.notes.push(format!(
        "kappa = 60: rebound {:.5} (kappa = 30: {:.5}), lowest point {:.5}",
        doubled.rebound, res[0].rebound, doubled.ymin
    ));
    // No external reference curve: the resolutions (and the stiffer contact) over each other.
    let mut velocity = PlotSpec::new("velocity", "vertical velocity of the disk", "t", "v_y");
    let mut height = PlotSpec::new("height", "height of the disk's centre", "t", "y");
    for (&(h, dt), s) in runs.iter().zip(&res) {
        let label = format!("h = 1/{:.0}, dt = {dt}, kappa = 30", 1.0 / h);
        velocity = velocity.measured(label.clone(), s.vy.clone());
        height = height.measured(label, s.y.clone());
    }
    let label = format!("h = 1/{:.0}, dt = {dt}, kappa = 60", 1.0 / h);
    velocity = velocity.measured(label.clone(), doubled.vy);
    height = height
        .measured(label, doubled.y)
        .reference_level("touching the floor (y = r)", 0.125);
    rep.plots.push(velocity);
    rep.plots.push(height);
    Ok(rep)
}
