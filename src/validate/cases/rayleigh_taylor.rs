//! `rayleigh-taylor`: the linear Rayleigh-Taylor growth rate (issue 17's gates; a 2D tank closed by
//! a floor and a lid, periodic along x).

use super::common::{surface_height, tank};
use crate::sim::engine::Simulation;
use crate::validate::{Case, PlotSpec, Report, Row, RunTime};
use std::f64::consts::PI;

/// The case: what it checks, against what, and the rows known to fail.
pub const CASE: Case = Case {
    name: "rayleigh-taylor",
    description: "heavy over light, Atwood 0.5, single mode of amplitude 0.002 from rest: growth rate within 5% of sqrt(A g k + nu^2 k^4) - nu k^2",
    reference: "linear theory (Chandrasekhar 1961)",
    full: "2D, h = 1/64 and 1/128",
    quick: "2D, h = 1/64",
    full_time: RunTime::Minutes,
    quick_time: RunTime::Seconds,
    run: rayleigh_taylor,
    known_failures: &[],
};

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
        let mut sim = crate::validate::simulation(scene)?;
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
            PlotSpec::new(
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
