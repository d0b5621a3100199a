//! The free-surface cases (issue 17's gates): a pool at rest, a standing wave against the
//! two-fluid dispersion relation, the linear Rayleigh-Taylor growth rate, and Archimedes'
//! floating and sinking bodies. All are 2D tanks closed by a floor and a lid (static
//! half-planes), periodic along x.

use super::{Report, Row};
use crate::bodies::free_surface::LiquidLevelSet;
use crate::scene::Scene;
use crate::sim::engine::Simulation;
use std::f64::consts::PI;

/// A 2D tank `width` wide: floor at y = 0, lid at y = `top`, two cells of wall beyond each,
/// grid step `h`; the liquid (density 1) fills `liquid` (a RON list of regions), the gas has
/// density `gas`; gravity -g along y. `bodies` are more RON body entries.
#[allow(clippy::too_many_arguments)]
fn tank(
    name: &str,
    width: f64,
    top: f64,
    h: f64,
    gas: f64,
    liquid: &str,
    g: f64,
    nu: f64,
    end: f64,
    bodies: &str,
) -> anyhow::Result<crate::scene::ValidScene> {
    let text = format!(
        r#"Scene(
        name: "{name}",
        domain: (origin: [0.0, {o}], extent: [{width}, {e}], h: {h}),
        fluid: (density: 1.0, viscosity: {nu}, gravity: [0.0, {mg}]),
        free_surface: Some((gas_density: {gas}, liquid: {liquid})),
        numerics: (end_time: {end}),
        bodies: [
            (name: "floor", shape: HalfSpace(normal: [0.0, 1.0, 0.0], offset: 0.0), kind: Static, position: [0.0, 0.0]),
            (name: "lid", shape: HalfSpace(normal: [0.0, -1.0, 0.0], offset: {mtop}), kind: Static, position: [0.0, 0.0]),
            {bodies}
        ],
    )"#,
        o = -2.0 * h,
        e = top + 4.0 * h,
        mg = -g,
        mtop = -top,
    );
    Ok(Scene::parse(&text, name, name)?)
}

/// Height of the free surface in column `i` (2D): the zero of φ_w nearest to `guess` along
/// y, by linear interpolation between the two nodes around it.
pub fn surface_height(sim: &Simulation, i: usize, guess: f64) -> f64 {
    let grid = sim.grid();
    let phi = &sim.world.resource::<LiquidLevelSet>().phi;
    let [nx, ny, _] = grid.n;
    let mut best = f64::NAN;
    for j in 0..ny - 1 {
        let (p, q) = (phi[i + nx * j], phi[i + nx * (j + 1)]);
        if (p > 0.0) != (q > 0.0) {
            let y = grid.pos(i, j, 0)[1] + grid.h * p / (p - q);
            if best.is_nan() || (y - guess).abs() < (best - guess).abs() {
                best = y;
            }
        }
    }
    best
}

fn ratios(quick: bool) -> &'static [f64] {
    if quick {
        &[10.0, 100.0]
    } else {
        &[10.0, 100.0, 1000.0]
    }
}

/// A pool at rest stays at rest: max |u| < 1e-3 √(g H) over 1000 steps, volume within 0.1%.
pub fn still_pool(quick: bool) -> anyhow::Result<Report> {
    let mut rep = Report::new("still-pool");
    let h = if quick { 1.0 / 64.0 } else { 1.0 / 128.0 };
    let (g, depth) = (1.0, 0.5);
    for &r in ratios(quick) {
        let scene = tank(
            "still-pool",
            1.0,
            1.0,
            h,
            1.0 / r,
            "[Below(height: 0.5)]",
            g,
            1e-3,
            1e9,
            "",
        )?;
        let mut sim = Simulation::new(scene)?;
        let mut umax = 0.0f64;
        let mut drift = 0.0f64;
        for _ in 0..1000 {
            sim.step()?;
            umax = umax.max(sim.sample().max_u);
            let ls = sim.world.resource::<LiquidLevelSet>();
            drift = drift.max((ls.volume / ls.target_volume - 1.0).abs());
        }
        rep.rows.push(Row::abs(
            format!(
                "1:{r} pool, h = 1/{}: max |u| / sqrt(g H) over 1000 steps",
                1.0 / h
            ),
            0.0,
            umax / (g * depth).sqrt(),
            1e-3,
        ));
        rep.rows.push(Row::abs(
            format!("1:{r} pool: liquid volume drift over 1000 steps"),
            0.0,
            drift,
            1e-3,
        ));
    }
    Ok(rep)
}

/// ω of a standing wave: ω² = g k (ρ₁ - ρ₂) / (ρ₁ coth k h₁ + ρ₂ coth k h₂).
fn dispersion(g: f64, k: f64, r1: f64, r2: f64, h1: f64, h2: f64) -> f64 {
    let coth = |x: f64| 1.0 / x.tanh();
    (g * k * (r1 - r2) / (r1 * coth(k * h1) + r2 * coth(k * h2))).sqrt()
}

/// A standing wave of wavelength 1 and amplitude 0.01 in a tank of depth 0.5 under 0.5 of gas,
/// ν = 1e-4 (the viscous damping 2νk² is 0.8% per unit time):
/// its frequency within 2% of the two-fluid dispersion relation, and its amplitude never grows.
pub fn standing_wave(quick: bool) -> anyhow::Result<Report> {
    let mut rep = Report::new("standing-wave");
    let h = if quick { 1.0 / 64.0 } else { 1.0 / 128.0 };
    let (g, k, a0) = (1.0, 2.0 * PI, 0.01);
    for &r in ratios(quick) {
        let w = dispersion(g, k, 1.0, 1.0 / r, 0.5, 0.5);
        let periods = if quick { 2.0 } else { 3.0 };
        let end = periods * 2.0 * PI / w + 0.1;
        let scene = tank(
            "standing-wave",
            1.0,
            1.0,
            h,
            1.0 / r,
            &format!("[Below(height: 0.5, amplitude: {a0})]"),
            g,
            1e-4,
            end,
            "",
        )?;
        let mut sim = Simulation::new(scene)?;
        let half = sim.grid().n[0] / 2;
        let mut series = vec![(0.0, 2.0 * a0)];
        while sim.time() < end - 1e-12 {
            sim.step()?;
            let d = surface_height(&sim, 0, 0.5) - surface_height(&sim, half, 0.5);
            series.push((sim.time(), d));
        }
        // Zero crossings of η(0) - η(1/2), and the largest |η(0) - η(1/2)| between them.
        let mut cross = Vec::new();
        let mut peaks = Vec::new();
        let mut peak = 0.0f64;
        for p in series.windows(2) {
            let ((t0, d0), (t1, d1)) = (p[0], p[1]);
            peak = peak.max(d1.abs());
            if d0 * d1 < 0.0 {
                cross.push(t0 + (t1 - t0) * d0 / (d0 - d1));
                peaks.push(peak);
                peak = 0.0;
            }
        }
        let measured = if cross.len() >= 2 {
            PI * (cross.len() - 1) as f64 / (cross[cross.len() - 1] - cross[0])
        } else {
            f64::NAN
        };
        rep.rows.push(Row::rel(
            format!("1:{r} wave, h = 1/{}: frequency", 1.0 / h),
            w,
            measured,
            0.02,
        ));
        // Crest and trough of a finite-amplitude standing wave differ (its second harmonic),
        // so each peak is compared with the one a period before. The peaks are sampled once
        // per step (about 40 per period): the sampled maximum can miss the true one by up to
        // 1 - cos(π/40) = 0.3%.
        let grows = peaks.windows(3).any(|p| p[2] > p[0] * 1.003);
        rep.rows.push(Row::yes_no(
            format!(
                "1:{r} wave: amplitude never grows over a period (half-period peaks {})",
                peaks
                    .iter()
                    .map(|p| format!("{:.5}", p / 2.0))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
            !grows && peaks.len() >= 3,
        ));
        rep.plots.push(
            super::PlotSpec::new(
                &format!("standing-wave-{r}"),
                format!("standing wave, density ratio 1:{r}"),
                "t",
                "eta(0) - eta(1/2)",
            )
            .measured("tumble", series.clone())
            .reference(
                "a cos(omega t), omega from the dispersion relation",
                series
                    .iter()
                    .map(|&(t, _)| (t, 2.0 * a0 * (w * t).cos()))
                    .collect(),
            ),
        );
    }
    Ok(rep)
}

/// Heavy (3) over light (1), Atwood number 0.5, wavelength 1, amplitude 0.002, ν = 1e-3:
/// from rest the amplitude grows as cosh(σ t) with σ = √(A g k + ν² k⁴) - ν k²; σ is taken
/// when the amplitude first reaches 10 times its start.
pub fn rayleigh_taylor(quick: bool) -> anyhow::Result<Report> {
    let mut rep = Report::new("rayleigh-taylor");
    let hs: &[f64] = if quick {
        &[1.0 / 64.0]
    } else {
        &[1.0 / 64.0, 1.0 / 128.0]
    };
    let (g, k, a0, nu, atwood) = (1.0, 2.0 * PI, 0.002, 1e-3, 0.5);
    let sigma = (atwood * g * k + nu * nu * k.powi(4)).sqrt() - nu * k * k;
    for &h in hs {
        // Liquid of density 1 above, gas of density 1/3 below: A = (1 - 1/3)/(1 + 1/3) = 0.5.
        let scene = tank(
            "rayleigh-taylor",
            1.0,
            2.0,
            h,
            1.0 / 3.0,
            &format!("[Above(height: 1.0, amplitude: {a0})]"),
            g,
            nu,
            4.0,
            "",
        )?;
        let mut sim = Simulation::new(scene)?;
        let half = sim.grid().n[0] / 2;
        let amp = |sim: &Simulation| {
            0.5 * (surface_height(sim, 0, 1.0) - surface_height(sim, half, 1.0)).abs()
        };
        let start = amp(&sim);
        let mut measured = f64::NAN;
        let mut series = vec![(0.0, 1.0)];
        while sim.time() < 4.0 - 1e-12 {
            sim.step()?;
            let a = amp(&sim) / start;
            series.push((sim.time(), a));
            if a >= 10.0 {
                measured = a.acosh() / sim.time();
                break;
            }
        }
        rep.rows.push(Row::rel(
            format!(
                "h = 1/{}: growth rate sigma from cosh(sigma t) at 10 times the start",
                1.0 / h
            ),
            sigma,
            measured,
            0.05,
        ));
        rep.plots.push(
            super::PlotSpec::new(
                &format!("rayleigh-taylor-{}", (1.0 / h).round()),
                format!("Rayleigh-Taylor, A = 0.5, h = 1/{}", (1.0 / h).round()),
                "t",
                "amplitude / initial amplitude",
            )
            .measured("tumble", series.clone())
            .reference(
                "cosh(sigma t), linear theory",
                series
                    .iter()
                    .map(|&(t, _)| (t, (sigma * t).cosh()))
                    .collect(),
            ),
        );
    }
    Ok(rep)
}

/// Archimedes: three flat boxes (width 0.3, height 0.1, densities 0.25, 0.5, 0.75) released
/// half immersed settle at the draft (ρ_b - ρ_g)/(ρ_w - ρ_g) × height within one cell; a disk
/// of density 0.5 released under water rises and floats with its centre within one cell of
/// the waterline; a disk of density 2 sinks to the floor. Positions are averaged over the
/// last quarter of the run (the bodies still rock a little in the closed tank).
pub fn floating(quick: bool) -> anyhow::Result<Report> {
    let mut rep = Report::new("floating");
    let (h, r): (f64, f64) = if quick {
        (1.0 / 64.0, 100.0)
    } else {
        (1.0 / 128.0, 1000.0)
    };
    let (level, g, end) = (0.6, 1.0, 24.0);
    let gas = 1.0 / r;
    let boxes = [(0.25, 0.4), (0.5, 1.0), (0.75, 1.6)];
    let mut bodies = String::new();
    for (i, (rho, x)) in boxes.iter().enumerate() {
        bodies += &format!(
            "(name: \"box{i}\", shape: Rectangle(half_extents: [0.15, 0.05]), density: {rho}, position: [{x}, {level}]),\n"
        );
    }
    bodies += "(name: \"light\", shape: Disk(radius: 0.08), density: 0.5, position: [2.2, 0.3]),\n";
    bodies += "(name: \"heavy\", shape: Disk(radius: 0.08), density: 2.0, position: [2.7, 0.4]),\n";
    let scene = tank(
        "floating",
        3.0,
        1.25,
        h,
        gas,
        &format!("[Below(height: {level})]"),
        g,
        2e-3,
        end,
        &bodies,
    )?;
    let mut sim = Simulation::new(scene)?;
    let n = 7usize;
    let mut sums = vec![0.0; n];
    let mut count = 0usize;
    // Columns between the bodies where the waterline is read.
    let cols: Vec<usize> = [0.7, 1.3, 1.9]
        .iter()
        .map(|x| (x / h).round() as usize)
        .collect();
    // A velocity 10 times the free-fall speed over the tank's height is a blow-up: the case
    // stops there and shows it as a failing row (the rest of the run would crawl at a
    // collapsed time step).
    let limit = 10.0 * (2.0 * g * 1.25f64).sqrt();
    while sim.time() < end - 1e-12 {
        sim.step()?;
        let umax = sim.sample().max_u;
        if umax.is_nan() || umax >= limit {
            let t = sim.time();
            rep.rows.push(Row::yes_no(
                format!("the run reaches t = {end} without blowing up (max |u| passed {limit:.2} at t = {t:.3})"),
                false,
            ));
            return Ok(rep);
        }
        if sim.time() >= 0.75 * end {
            let states = crate::io::checkpoint::body_states(&mut sim);
            let y = |name: &str| {
                states
                    .iter()
                    .find(|s| s.name == name)
                    .map(|s| s.rigid.center[1])
                    .unwrap_or(f64::NAN)
            };
            let water = cols
                .iter()
                .map(|&c| surface_height(&sim, c, level))
                .sum::<f64>()
                / cols.len() as f64;
            let vals = [
                y("box0"),
                y("box1"),
                y("box2"),
                y("light"),
                y("heavy"),
                water,
                0.0,
            ];
            for (s, v) in sums.iter_mut().zip(vals) {
                *s += v;
            }
            count += 1;
        }
    }
    rep.rows.push(Row::yes_no(
        format!("the run reaches t = {end} without blowing up"),
        true,
    ));
    let mean: Vec<f64> = sums.iter().map(|s| s / count.max(1) as f64).collect();
    let water = mean[5];
    for (i, (rho, _)) in boxes.iter().enumerate() {
        let draft = water - (mean[i] - 0.05);
        let want = (rho - gas) / (1.0 - gas) * 0.1;
        rep.rows.push(Row::abs(
            format!("box of density {rho}, 1:{r}, h = 1/{}: draft", 1.0 / h),
            want,
            draft,
            h,
        ));
    }
    rep.rows.push(Row::abs(
        "disk of density 0.5 released under water: centre height above the waterline",
        0.0,
        mean[3] - water,
        h,
    ));
    rep.rows.push(Row::range(
        "disk of density 2: gap to the floor at the end, in cells",
        0.0,
        2.0,
        (mean[4] - 0.08) / h,
    ));
    rep.notes.push(format!(
        "waterline {water:.4} (initial {level}; raised by the floating bodies' displaced volume)"
    ));
    Ok(rep)
}

/// The paper's Fig. 10 (section 5): a cup of density 1.2 dropped onto water. The cup enters
/// the water, its centre rises again at least briefly after the first impact, it turns, water
/// enters its cavity, the liquid volume drifts less than 1%, and it ends on the floor.
/// `scenes/cup.ron` (128³) in full, at 48³ quick (it blows up either way, issue 17; 48³ shows
/// it in 40 s instead of the 100 s of 64³). A run whose velocity passes 5 times the
/// impact speed of a free fall from the release height to the floor (a splash's jets reach a
/// few times the impact speed) stops there as a failing row.
pub fn cup(quick: bool) -> anyhow::Result<Report> {
    let mut rep = Report::new("cup");
    let mut scene = super::bundled_scene("cup.ron")?;
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
    let mut sim = Simulation::new(scene)?;
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
