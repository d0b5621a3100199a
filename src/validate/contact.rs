//! Validation of the collision model: the paper's Fig. 1 (rebound in vacuum), Fig. 9 (ellipsoid
//! on a sphere) and section 4.2.2 (drafting, kissing and tumbling).

use super::{PlotSpec, Report, Row, bundled_scene};
use crate::bodies::{Body, ContactState, Material, RigidState};
use crate::sim::engine::Simulation;
use glam::DVec3;

/// State of every dynamic body: (name, state, density, contact potential).
fn dynamic_states(sim: &mut Simulation) -> Vec<(String, RigidState, f64, f64)> {
    let mut q = sim
        .world
        .query::<(&Body, &RigidState, &Material, &ContactState)>();
    let mut v: Vec<_> = q
        .iter(&sim.world)
        .filter(|(b, _, _, _)| b.is_dynamic())
        .map(|(b, s, m, c)| (b.id, b.name.clone(), *s, m.density, c.potential))
        .collect();
    v.sort_by_key(|e| e.0);
    v.into_iter().map(|(_, n, s, d, p)| (n, s, d, p)).collect()
}

/// Kinetic plus potential energy of a body (potential zero at height `z0` along gravity `g`).
fn energy(s: &RigidState, density: f64, g: DVec3, x0: DVec3) -> f64 {
    let m = density * s.volume;
    let jw = density * (s.inertia * s.angular_velocity);
    0.5 * m * s.velocity.length_squared() + 0.5 * s.angular_velocity.dot(jw)
        - m * g.dot(s.center - x0)
}

/// The leapfrog state at the previous positions: symplectic Euler leaves x_{k+1} and
/// v_{k+1/2} after step k, so the energy of x_k is taken with v_k = (v_{k-1/2} + v_{k+1/2})/2
/// (and likewise Ω); `prev` is the state after step k-1, `s` after step k.
fn leapfrog_mid(prev: &RigidState, s: &RigidState) -> RigidState {
    RigidState {
        center: prev.center,
        velocity: 0.5 * (prev.velocity + s.velocity),
        angular_velocity: 0.5 * (prev.angular_velocity + s.angular_velocity),
        ..*s
    }
}

/// The smallest gap among spheres of radius `r` (pairwise) and between them and the walls of
/// the box [lo, hi]³ (negative: an overlap).
fn smallest_sphere_gap<'a>(
    states: impl Iterator<Item = &'a RigidState> + Clone,
    r: f64,
    lo: f64,
    hi: f64,
) -> f64 {
    let mut worst = f64::INFINITY;
    for (a, sa) in states.clone().enumerate() {
        for ax in 0..3 {
            let c = sa.center[ax];
            worst = worst.min((c - lo - r).min(hi - c - r));
        }
        for sb in states.clone().skip(a + 1) {
            worst = worst.min((sb.center - sa.center).length() - 2.0 * r);
        }
    }
    worst
}

/// The geometry of a `tank-200` scene, read from the scene itself: the walls of the cubic box
/// (the first body, the outside of a centred box) as [lo, hi] on every axis, and the radius of
/// the spheres (the second body).
fn tank_geometry(scene: &crate::scene::Scene) -> anyhow::Result<(f64, f64, f64)> {
    use crate::bodies::shapes::Shape;
    let (Some(tank), Some(sphere)) = (scene.bodies.first(), scene.bodies.get(1)) else {
        anyhow::bail!("the tank scene needs the box and at least one sphere");
    };
    let Shape::Complement(inner) = &tank.shape else {
        anyhow::bail!("the tank scene's first body must be the outside of a box");
    };
    let Shape::Box { half_extents } = **inner else {
        anyhow::bail!("the tank scene's first body must be the outside of a box");
    };
    let Shape::Sphere { radius } = sphere.shape else {
        anyhow::bail!("the tank scene's second body must be a sphere");
    };
    let c = tank.position.first().copied().unwrap_or(0.0);
    Ok((c - half_extents[0], c + half_extents[0], radius))
}

/// The relative change of the total energy against t, with the exact value 0 (the cases allow
/// 5%; the tolerance is not drawn, it would flatten the curve).
fn energy_plot(echange: Vec<(f64, f64)>) -> PlotSpec {
    PlotSpec::new(
        "energy",
        "total energy (kinetic + gravity + contact)",
        "t",
        "(E - E0) / E0",
    )
    .measured("measured", echange)
    .reference_level("exact: conserved", 0.0)
}

/// Paper Fig. 1: a disk dropped in vacuum on a plane rebounds to its drop height.
pub fn rebound_vacuum(quick: bool) -> anyhow::Result<Report> {
    // The full case takes a few seconds, so `quick` runs it unchanged.
    let _ = quick;
    let mut rep = Report::new("rebound-vacuum");
    let scene = bundled_scene("rebound-vacuum.ron")?;
    let r = 0.1;
    let y0 = scene.bodies[1].position[1];
    let h = scene.grid().h;
    let eps = scene.contact.eps.unwrap_or(h);
    let end = scene.numerics.end_time;
    let mut sim = Simulation::new(scene)?;
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

/// Paper section 4.2.3, Fig. 9: an ellipsoid falling in vacuum on a fixed sphere turns about
/// all three axes, with the total energy conserved.
pub fn ellipsoid_sphere(quick: bool) -> anyhow::Result<Report> {
    let _ = quick;
    let mut rep = Report::new("ellipsoid-sphere");
    let scene = bundled_scene("ellipsoid-sphere.ron")?;
    let g = DVec3::from_array(scene.gravity());
    let floor = DVec3::new(0.0, 0.0, scene.bodies[0].position[2]);
    let end = scene.numerics.end_time;
    let mut sim = Simulation::new(scene)?;
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

/// Paper section 4.2.2: drafting, kissing and tumbling of two spheres.
pub fn dkt(_quick: bool) -> anyhow::Result<Report> {
    let mut rep = Report::new("dkt");
    let scene = bundled_scene("dkt.ron")?;
    // The whole case takes about 30 s on two cores, so `quick` runs it unchanged (at
    // h = 1/30 the spheres would be 2.5 cells in radius, too coarse to test anything).
    let h = scene.grid().h;
    let r = 0.083;
    let end = 0.7;
    let mut sim = Simulation::new(scene)?;
    sim.set_stop_at(Some(end));
    let mut t_kiss = None;
    let mut gmin = f64::INFINITY;
    let mut vrel_max = 0.0f64;
    let mut sep = Vec::new();
    while sim.time() < end * (1.0 - 1e-12) {
        sim.step()?;
        let st = dynamic_states(&mut sim);
        let (a, b) = (&st[0].1, &st[1].1);
        let d = b.center - a.center;
        let gap = d.length() - 2.0 * r;
        gmin = gmin.min(gap);
        let t = sim.time();
        if gap < 2.0 * h {
            t_kiss.get_or_insert(t);
        }
        // Velocities while kissing: the first 0.1 time units after the kiss, before the
        // pair reaches the floor.
        if gap < 2.0 * h && t_kiss.is_some_and(|tk| t < tk + 0.1) {
            let vmax = a.velocity.length().max(b.velocity.length());
            vrel_max = vrel_max.max((a.velocity - b.velocity).length() / vmax);
        }
        sep.push((t, (d.x * d.x + d.y * d.y).sqrt(), gap));
    }
    rep.plots.push(
        PlotSpec::new("gap", "gap between the spheres", "t", "gap / h")
            .measured(
                "measured",
                sep.iter().map(|&(t, _, gap)| (t, gap / h)).collect(),
            )
            .reference_level("paper: gap ≈ h while kissing", 1.0),
    );
    rep.plots.push(
        PlotSpec::new(
            "horizontal",
            "horizontal distance of the centres",
            "t",
            "distance",
        )
        .measured("measured", sep.iter().map(|&(t, d, _)| (t, d)).collect())
        .reference_level(format!("one radius ({r}): exceeded at t = 0.6"), r),
    );
    let tk = t_kiss.unwrap_or(f64::NAN);
    rep.rows.push(Row::range(
        "time the gap first drops under 2h (kiss)",
        0.25,
        0.4,
        tk,
    ));
    rep.rows.push(Row::range(
        "smallest gap / h (never negative, about 1)",
        0.1,
        2.0,
        gmin / h,
    ));
    rep.rows.push(Row::abs(
        "largest |v_a - v_b| / |v| while kissing (gap < 2h, 0.1 after the kiss)",
        0.0,
        vrel_max,
        0.25,
    ));
    let at = |t0: f64| {
        sep.iter()
            .min_by(|x, y| (x.0 - t0).abs().total_cmp(&(y.0 - t0).abs()))
            .map(|e| e.1)
            .unwrap_or(f64::NAN)
    };
    let (s6, s65) = (at(0.6), at(0.65));
    rep.rows.push(Row::yes_no(
        "horizontal distance of the centres at t = 0.6 exceeds one radius",
        s6 > r,
    ));
    rep.rows.push(Row::yes_no(
        "and is still growing from t = 0.6 to 0.65",
        s65 > s6,
    ));
    rep.notes.push(format!(
        "h = 1/{:.0}, to t = {end}: kiss at t = {tk:.3}, smallest gap {:.4} ({:.2} h), largest relative velocity difference while kissing {vrel_max:.3}, horizontal distance {:.4} at t = 0.6 and {:.4} at t = 0.65 (radius {r})",
        1.0 / h,
        gmin,
        gmin / h,
        s6,
        s65
    ));
    Ok(rep)
}

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
    let h = scene.grid().h;
    let eps = scene.contact.eps.unwrap_or(h);
    let (lo, hi, r) = tank_geometry(&scene)?;
    let n = scene.bodies.len() - 1;
    let end = scene.numerics.end_time;
    let mut sim = Simulation::new(scene)?;
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
    let h = scene.grid().h;
    let eps = scene.contact.eps.unwrap_or(h);
    let touch = scene.contact.range * eps;
    let nu = scene.fluid.viscosity;
    let rho_f = scene.fluid.density;
    let (lo, hi, r) = tank_geometry(&scene)?;
    let rho_s = scene.resolved().densities[1];
    // Stokes settling velocity of one sphere in unbounded fluid.
    let u_stokes = 2.0 / 9.0 * (rho_s / rho_f - 1.0) * g * r * r / nu;
    let n = scene.bodies.len() - 1;
    let end = scene.numerics.end_time;
    let mut sim = Simulation::new(scene)?;
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
