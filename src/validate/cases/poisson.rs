//! `poisson`: velocity from a smooth periodic vorticity against the analytic velocity, 2D and 3D.

use crate::base::grid::Grid;
use crate::solvers::Spectral;
use crate::validate::{Case, Report, Row, RunTime};
use std::f64::consts::PI;

/// The case: what it checks, against what, and the rows known to fail.
pub const CASE: Case = Case {
    name: "poisson",
    description: "velocity from a smooth periodic vorticity, 2D and 3D, within 1e-10",
    reference: "analytic",
    full: "2D 128x192, 3D 64x48x80",
    quick: "2D 32x48, 3D 16x24x20",
    full_time: RunTime::Seconds,
    quick_time: RunTime::Seconds,
    run: |quick| Ok(poisson(quick)),
    known_failures: &[],
};

/// Velocity from a smooth periodic vorticity against the analytic velocity (2D and 3D).
fn poisson(quick: bool) -> Report {
    let mut rep = Report::new("poisson");
    // 2D: ψ = sin(2πx/Lx) cos(4πy/Ly) on a non-square box; ω = -Δψ, u = ∂ψ/∂y, v = -∂ψ/∂x.
    let (nx, ny) = if quick { (32, 48) } else { (128, 192) };
    let (lx, ly) = (1.0, 1.5);
    let g = Grid::new([nx, ny, 1], lx / nx as f64, [0.3, -0.2, 0.0]);
    let (a, b) = (2.0 * PI / lx, 4.0 * PI / ly);
    let mut omega = vec![vec![0.0; g.len()]];
    let mut exact = vec![vec![0.0; g.len()]; 2];
    for j in 0..ny {
        for i in 0..nx {
            let p = g.pos(i, j, 0);
            let (x, y) = (p[0] - g.origin[0], p[1] - g.origin[1]);
            let idx = g.idx(i, j, 0);
            omega[0][idx] = (a * a + b * b) * (a * x).sin() * (b * y).cos();
            exact[0][idx] = -b * (a * x).sin() * (b * y).sin();
            exact[1][idx] = -a * (a * x).cos() * (b * y).cos();
        }
    }
    let mut u = vec![vec![0.0; g.len()]; 2];
    Spectral::new(&g).velocity(&mut omega, 1, [0.0; 3], &mut u);
    rep.rows.push(Row::abs(
        format!("2D {nx}x{ny}: max |u - u_exact|"),
        0.0,
        max_diff(&u, &exact),
        1e-10,
    ));
    // 3D: ψ = (sin(ky y) sin(kz z), sin(kz z) sin(kx x), sin(kx x) sin(ky y)) (div ψ = 0),
    // ω = -Δψ, u = ∇×ψ.
    let n = if quick { [16, 24, 20] } else { [64, 48, 80] };
    let h = 2.0 * PI / n[0] as f64;
    let g = Grid::new(n, h, [0.0; 3]);
    let ext = g.extent();
    let k = [2.0 * PI / ext[0], 4.0 * PI / ext[1], 2.0 * PI / ext[2]];
    let mut omega = vec![vec![0.0; g.len()]; 3];
    let mut exact = vec![vec![0.0; g.len()]; 3];
    for kk in 0..n[2] {
        for j in 0..n[1] {
            for i in 0..n[0] {
                let p = g.pos(i, j, kk);
                let (sx, cx) = (k[0] * p[0]).sin_cos();
                let (sy, cy) = (k[1] * p[1]).sin_cos();
                let (sz, cz) = (k[2] * p[2]).sin_cos();
                let idx = g.idx(i, j, kk);
                omega[0][idx] = (k[1] * k[1] + k[2] * k[2]) * sy * sz;
                omega[1][idx] = (k[2] * k[2] + k[0] * k[0]) * sz * sx;
                omega[2][idx] = (k[0] * k[0] + k[1] * k[1]) * sx * sy;
                // u = ∇×ψ
                exact[0][idx] = k[1] * sx * cy - k[2] * sx * cz;
                exact[1][idx] = k[2] * sy * cz - k[0] * cx * sy;
                exact[2][idx] = k[0] * cx * sz - k[1] * cy * sz;
            }
        }
    }
    let mut u = vec![vec![0.0; g.len()]; 3];
    Spectral::new(&g).velocity(&mut omega, 1, [0.0; 3], &mut u);
    rep.rows.push(Row::abs(
        format!("3D {}x{}x{}: max |u - u_exact|", n[0], n[1], n[2]),
        0.0,
        max_diff(&u, &exact),
        1e-10,
    ));
    rep
}

fn max_diff(a: &[Vec<f64>], b: &[Vec<f64>]) -> f64 {
    a.iter()
        .zip(b)
        .flat_map(|(x, y)| x.iter().zip(y).map(|(p, q)| (p - q).abs()))
        .fold(0.0, f64::max)
}
