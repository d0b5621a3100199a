//! `remesh`: the M'4 push-and-remesh sweeps conserve circulation to round-off and move the first
//! and second moments exactly as the particles move.

use crate::base::grid::Grid;
use crate::scene::RemeshKernel;
use crate::solvers::sweep::{LinePool, LineScratch, sweep};
use crate::validate::{Case, Report, Row, RunTime};
use std::f64::consts::PI;

/// The case: what it checks, against what, and the rows known to fail.
pub const CASE: Case = Case {
    name: "remesh",
    description: "push + M'4 remesh conserves circulation to round-off, first and second moments exactly",
    reference: "analytic",
    full: "64x64, uniform and sheared displacement",
    quick: "the full case (it takes milliseconds)",
    full_time: RunTime::Seconds,
    quick_time: RunTime::Seconds,
    run: |_| Ok(remesh()),
    known_failures: &[],
};

/// Moments of a 2D scalar field: Σω, Σωx, Σωy, Σωx², Σωy², Σωxy (grid units, cell sums).
fn moments(g: &Grid, w: &[f64]) -> [f64; 6] {
    let mut m = [0.0; 6];
    for j in 0..g.n[1] {
        for i in 0..g.n[0] {
            let v = w[g.idx(i, j, 0)];
            let (x, y) = (i as f64, j as f64);
            m[0] += v;
            m[1] += v * x;
            m[2] += v * y;
            m[3] += v * x * x;
            m[4] += v * y * y;
            m[5] += v * x * y;
        }
    }
    m
}

/// The M'4 push-and-remesh sweeps conserve circulation to round-off and move the first and
/// second moments exactly as the particles move.
fn remesh() -> Report {
    let mut rep = Report::new("remesh");
    let n = 64;
    let g = Grid::new([n, n, 1], 1.0, [0.0; 3]);
    // A smooth blob with a sign change, far from the box edges.
    let mut w = vec![0.0; g.len()];
    for j in 0..n {
        for i in 0..n {
            let (x, y) = (i as f64 - 30.3, j as f64 - 28.7);
            w[g.idx(i, j, 0)] = (1.0 + 0.3 * x - 0.2 * y) * (-(x * x + y * y) / 30.0).exp();
        }
    }
    let pool = LinePool::per_thread(move || LineScratch::new(n, 1));
    // Uniform velocity: every particle moves by d cells; Σω' = Σω, Σω'x' = Σωx + d Σω,
    // Σω'x'² = Σωx² + 2d Σωx + d² Σω.
    let m0 = moments(&g, &w);
    let (dx, dy) = (0.37, -1.63);
    let mut omega = vec![w.clone()];
    let ux = vec![dx; g.len()];
    let uy = vec![dy; g.len()];
    sweep(
        &g,
        0,
        1.0,
        &mut omega,
        &ux,
        0.0,
        RemeshKernel::M4Prime,
        &pool,
    );
    sweep(
        &g,
        1,
        1.0,
        &mut omega,
        &uy,
        0.0,
        RemeshKernel::M4Prime,
        &pool,
    );
    let m1 = moments(&g, &omega[0]);
    let scale = m0[0].abs().max(1.0);
    rep.rows.push(Row::abs(
        "uniform shift: circulation Σω",
        m0[0],
        m1[0],
        1e-12 * scale,
    ));
    rep.rows.push(Row::abs(
        "uniform shift: first moment Σωx",
        m0[1] + dx * m0[0],
        m1[1],
        1e-10 * m0[1].abs().max(1.0),
    ));
    rep.rows.push(Row::abs(
        "uniform shift: first moment Σωy",
        m0[2] + dy * m0[0],
        m1[2],
        1e-10 * m0[2].abs().max(1.0),
    ));
    rep.rows.push(Row::abs(
        "uniform shift: second moment Σωx²",
        m0[3] + 2.0 * dx * m0[1] + dx * dx * m0[0],
        m1[3],
        1e-10 * m0[3].abs().max(1.0),
    ));
    rep.rows.push(Row::abs(
        "uniform shift: second moment Σωy²",
        m0[4] + 2.0 * dy * m0[2] + dy * dy * m0[0],
        m1[4],
        1e-10 * m0[4].abs().max(1.0),
    ));
    rep.rows.push(Row::abs(
        "uniform shift: cross moment Σωxy",
        m0[5] + dx * m0[2] + dy * m0[1] + dx * dy * m0[0],
        m1[5],
        1e-10 * m0[5].abs().max(1.0),
    ));
    // A non-uniform (sheared, compressive along the line) velocity: circulation is still
    // conserved to round-off.
    let mut omega = vec![w.clone()];
    let mut us = vec![0.0; g.len()];
    for j in 0..n {
        for i in 0..n {
            us[g.idx(i, j, 0)] = 0.8 * (2.0 * PI * (i as f64 + 0.5 * j as f64) / n as f64).sin();
        }
    }
    sweep(
        &g,
        0,
        1.0,
        &mut omega,
        &us,
        0.0,
        RemeshKernel::M4Prime,
        &pool,
    );
    sweep(
        &g,
        1,
        1.0,
        &mut omega,
        &us,
        0.0,
        RemeshKernel::M4Prime,
        &pool,
    );
    let m2 = moments(&g, &omega[0]);
    rep.rows.push(Row::abs(
        "sheared flow: circulation Σω",
        m0[0],
        m2[0],
        1e-12 * scale,
    ));
    rep.notes
        .push("64x64 grid, displacement (0.37, -1.63) cells; moments in grid units".into());
    rep
}
