//! `stokes-settling`: a sphere settling at Re ≪ 1 in a periodic box against the drag of Hasimoto
//! (1959) and Sangani & Acrivos (1982).

use super::common::{MODEL, dynamic_body};
use crate::scene::Scene;
use crate::validate::{Case, KnownFailure, Report, Row, RunTime};
use std::f64::consts::PI;

/// The case: what it checks, against what, and the rows known to fail.
pub const CASE: Case = Case {
    name: "stokes-settling",
    description: "a sphere settling at Re << 1 in a periodic box: U within 2% of Hasimoto's for body/fluid densities 0.01 to 1000 at diffusion number 0.5 (and, in the full tier, at three offsets of the centre against the grid), and within 1% of each other at diffusion numbers 0.125, 0.5 and 2 (density 2); in the full tier the mean error over the densities smaller at 4.8 than at 3.2 cells per radius",
    reference: "Hasimoto 1959, Sangani & Acrivos 1982",
    full: "h = 1/32 and 1/48, densities 0.01, 0.1, 0.5, 1.1, 2, 5, 20, 100, 1000; density 2 also at three offsets of the centre against the grid",
    quick: "h = 1/32, densities 0.01, 0.5, 2 and 20 (100 and 1000 relax over 0.2 and 2.2 time units: thousands of steps)",
    full_time: RunTime::Long,
    quick_time: RunTime::Minutes,
    run: stokes_settling,
    known_failures: &[KnownFailure {
        row: "mean |U / U_Hasimoto - 1| over the densities smaller at h = 1/48",
        quick: false,
        full: true,
        why: "0.574% at h = 1/48 (4.8 cells per radius) against 0.039% at 1/32 (3.2), every value within 1% (measured 2026-11-28): the markers' retraction r = 0.40 + 0.50 H h is fitted over 3.2 to 6.4 cells per radius (docs/numerics.md), and at 3.2 it happens to sit on Hasimoto's value; the calibration runs had the largest error falling from 1.85% to 0.5% at 6.4 cells, so the error is not monotone in h between 3.2 and 4.8; issue 45",
    }],
};

/// Velocity along gravity of a sphere of radius 0.1 and density `rho` settling in a periodic
/// unit box of fluid (ρ_F = 1, ν = 1) on `n`³ nodes under gravity of magnitude `g`, with the
/// adaptive step at diffusion number `d` and the coupling `coupling` (a line of `numerics`),
/// its centre off the node at the box's centre by `offset` grid spacings along each axis.
/// Returns (t, U) after every step to `t_end`, U > 0 when the body moves the way its excess
/// weight pulls it (down if heavier than the fluid, up if lighter); the error of the run if it
/// fails (a blow-up).
fn periodic_settling(
    n: usize,
    rho: f64,
    g: f64,
    d: f64,
    coupling: &str,
    t_end: f64,
    offset: [f64; 3],
) -> anyhow::Result<Vec<(f64, f64)>> {
    let h = 1.0 / n as f64;
    let [px, py, pz] = offset.map(|o| 0.5 + o * h);
    let text = format!(
        r#"Scene(
        name: "stokes-settling",
        domain: (extent: [1.0, 1.0, 1.0], cells: [{n}, {n}, {n}]),
        fluid: (viscosity: 1.0, gravity: [0.0, 0.0, {}]),
        numerics: (end_time: {}, dt: Adaptive(diffusion_number: {d}), {coupling}),
        bodies: [(name: "sphere", shape: Sphere(radius: 0.1), density: {rho},
                  position: [{px}, {py}, {pz}])],
    )"#,
        -g,
        2.0 * t_end
    );
    let mut sim =
        crate::validate::simulation(Scene::parse(&text, "stokes-settling", "stokes-settling")?)?;
    // No landing on t_end: every step is the policy's own.
    sim.set_stop_at(None);
    let sign = if rho > 1.0 { -1.0 } else { 1.0 };
    let mut curve = Vec::new();
    while sim.time() < t_end {
        sim.step()?;
        let st = dynamic_body(&mut sim).ok_or_else(|| anyhow::anyhow!("no sphere"))?;
        curve.push((sim.time(), sign * st.velocity.z));
    }
    Ok(curve)
}

/// The steady value of a velocity that relaxes exponentially: Aitken's Δ² on the samples
/// nearest to t_end - 2s, t_end - s and t_end (exact for U∞ + C e^{-t/τ}); the last sample
/// when the second difference is below 1e-9 of it (already steady).
fn steady_value(curve: &[(f64, f64)], s: f64) -> f64 {
    let at = |t0: f64| {
        curve
            .iter()
            .min_by(|x, y| (x.0 - t0).abs().total_cmp(&(y.0 - t0).abs()))
            .map_or(f64::NAN, |e| e.1)
    };
    let t_end = curve.last().map_or(0.0, |e| e.0);
    let (u1, u2, u3) = (at(t_end - 2.0 * s), at(t_end - s), at(t_end));
    let dd = u3 - 2.0 * u2 + u1;
    if dd.abs() <= 1e-9 * u3.abs() {
        u3
    } else {
        u3 - (u3 - u2) * (u3 - u2) / dd
    }
}

/// A sphere settling at Re ≪ 1 in a periodic box (a simple cubic array) against the analytic
/// drag of Hasimoto (1959) and Sangani & Acrivos (1982), for body/fluid density ratios from
/// 0.01 to 1000 and for three diffusion numbers.
fn stokes_settling(quick: bool) -> anyhow::Result<Report> {
    let mut rep = Report::new("stokes-settling");
    let (a, mu, g0) = (0.1f64, 1.0, 1.0);
    let c = 4.0 * PI * a.powi(3) / 3.0;
    let k = 1.0 - 1.7601 * c.cbrt() + c - 1.5593 * c * c;
    // g = g0 / |ρ - 1|: every density settles (or rises) at the same U_Hasimoto, Re = U a / ν
    // = 2.0e-4, far inside the Stokes regime the reference assumes.
    let u_h = 2.0 * g0 * a * a / (9.0 * mu) * k;
    let grids: &[usize] = if quick { &[32] } else { &[32, 48] };
    let t0 = if quick { 0.15 } else { 0.3 };
    let densities: &[f64] = if quick {
        &[0.01, 0.5, 2.0, 20.0]
    } else {
        &[0.01, 0.1, 0.5, 1.1, 2.0, 5.0, 20.0, 100.0, 1000.0]
    };
    // U / U_Hasimoto at density 2, h = 1/32, diffusion number 0.5 (also the middle of the
    // diffusion-number row).
    let mut rho2 = None;
    // Per grid, the mean over the densities of |U / U_Hasimoto - 1|.
    let mut mean_err = Vec::new();
    for &n in grids {
        let mut line = Vec::new();
        let mut errs = Vec::new();
        for &rho in densities {
            // The slowest relaxations: the periodic flow's, e^{-4π²νt} (0.25% left at
            // t = 0.15, 6e-6 at 0.3), and the sphere's, τ = (2ρ_s/ρ_F + 1) a²/(9ν) (0.2 at
            // density 100, 2.2 at 1000). Past t0 only the sphere's is left, a single
            // exponential, and U∞ is Aitken's extrapolation from three samples s apart.
            let tau = (2.0 * rho + 1.0) * a * a / (9.0 * mu);
            let s = (0.5 * tau).clamp(0.01, 0.25 * 2.2);
            let t_end = t0 + 2.0 * s;
            let g = g0 / (rho - 1.0).abs();
            let row = format!(
                "h = 1/{n} ({:.1} cells per radius), density {rho}: U / U_Hasimoto",
                a * n as f64
            );
            match periodic_settling(n, rho, g, 0.5, MODEL, t_end, [0.0; 3]) {
                Ok(curve) => {
                    let u = steady_value(&curve, s);
                    if n == 32 && rho == 2.0 {
                        rho2 = Some(u / u_h);
                    }
                    line.push(format!("{rho}: {:+.1}%", 100.0 * (u / u_h - 1.0)));
                    errs.push((u / u_h - 1.0).abs());
                    rep.rows.push(Row::rel(row, 1.0, u / u_h, 0.02));
                }
                Err(e) => {
                    line.push(format!("{rho}: failed"));
                    rep.notes.push(format!("h = 1/{n}, density {rho}: {e}"));
                    rep.rows.push(Row::rel(row, 1.0, f64::NAN, 0.02));
                    errs.push(f64::NAN);
                }
            }
        }
        mean_err.push((n, errs.iter().sum::<f64>() / errs.len() as f64));
        rep.notes.push(format!(
            "h = 1/{n}, diffusion number 0.5, U against Hasimoto by density: {}",
            line.join(", ")
        ));
    }
    // The error must shrink with h (full tier: two grids).
    if let [(n0, e0), (n1, e1)] = mean_err[..] {
        rep.rows.push(Row::yes_no(
            format!(
                "mean |U / U_Hasimoto - 1| over the densities smaller at h = 1/{n1} than at 1/{n0} (the error shrinking with h)"
            ),
            e1 < e0,
        ));
        rep.notes.push(format!(
            "mean |U / U_Hasimoto - 1| over the densities: {:.3}% at h = 1/{n0}, {:.3}% at 1/{n1}",
            100.0 * e0,
            100.0 * e1
        ));
    }
    // The drag must not depend on where the surface cuts the grid (full tier): density 2 with
    // the centre off the nodes by three fixed offsets (in grid spacings; the centred sphere
    // is the row above), at both grids.
    // Density 2's relaxation time and the case's sampling interval for it.
    let tau2 = 5.0 * a * a / (9.0 * mu);
    let s2 = (0.5 * tau2).max(0.01);
    if !quick {
        for &n in grids {
            let mut line = Vec::new();
            for off in [[0.37, 0.21, 0.5], [0.5, 0.5, 0.5], [0.13, 0.71, 0.29]] {
                let row = format!(
                    "h = 1/{n} ({:.1} cells per radius), density 2, centre off the nodes by ({}, {}, {}) h: U / U_Hasimoto",
                    a * n as f64,
                    off[0],
                    off[1],
                    off[2]
                );
                let curve = periodic_settling(n, 2.0, g0, 0.5, MODEL, t0 + 2.0 * s2, off)?;
                let u = steady_value(&curve, s2) / u_h;
                line.push(format!("{u:.4}"));
                rep.rows.push(Row::rel(row, 1.0, u, 0.02));
            }
            rep.notes.push(format!(
                "h = 1/{n}, density 2, U / U_Hasimoto at the three offsets: {}",
                line.join(" / ")
            ));
        }
    }
    // The drag must not depend on the time step: density 2 at diffusion numbers 0.125, 0.5
    // and 2 (Δt = d h²/ν), h = 1/32.
    let n = 32;
    let mut us = Vec::new();
    for d in [0.125, 0.5, 2.0] {
        if let (0.5, Some(r)) = (d, rho2) {
            us.push((d, r));
            continue;
        }
        let curve = periodic_settling(n, 2.0, g0, d, MODEL, t0 + 2.0 * s2, [0.0; 3])?;
        us.push((d, steady_value(&curve, s2) / u_h));
    }
    let (lo, hi) = us.iter().fold((f64::INFINITY, 0.0f64), |(l, h), &(_, r)| {
        (l.min(r), h.max(r))
    });
    rep.rows.push(Row::abs(
        format!(
            "h = 1/{n}, density 2: (max - min) / min of U over diffusion numbers 0.125, 0.5, 2"
        ),
        0.0,
        hi / lo - 1.0,
        0.01,
    ));
    rep.notes.push(format!(
        "h = 1/{n}, density 2, U / U_Hasimoto by diffusion number: {}",
        us.iter()
            .map(|(d, r)| format!("{d}: {r:.4}"))
            .collect::<Vec<_>>()
            .join(", ")
    ));
    rep.notes.push(format!(
        "{MODEL}; Re = U a / ν = {:.1e}; volume fraction {c:.4}, U_Hasimoto / U_Stokes = {k:.4}",
        u_h * a / mu
    ));
    Ok(rep)
}
