//! The vortex stretching term of the transport system: its difference stencil converges at
//! the order it claims, against the analytic velocity gradient.

use tumble::base::grid::Grid;
use tumble::systems::transport::stretch;

/// Max error of one stretching step on an `n`³ grid of the 2π-periodic box, for
/// u = (sin y, sin z, sin x) and uniform ω = (1, -0.5, 2). ∇u has the one non-zero entry
/// per row G[0][1] = cos y, G[1][2] = cos z, G[2][0] = cos x, so the step's midpoint rule
/// ω + Δt G(ω + Δt/2 G ω) is known exactly and the only error is the differencing of u.
fn error(n: usize, dt: f64) -> f64 {
    let h = 2.0 * std::f64::consts::PI / n as f64;
    let grid = Grid::new([n, n, n], h, [0.0; 3]);
    let w0 = [1.0, -0.5, 2.0];
    let mut u = vec![vec![0.0; grid.len()]; 3];
    let mut omega = vec![vec![0.0; grid.len()]; 3];
    let mut expect = vec![[0.0; 3]; grid.len()];
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let c = i + n * (j + n * k);
                let [x, y, z] = grid.pos(i, j, k);
                u[0][c] = y.sin();
                u[1][c] = z.sin();
                u[2][c] = x.sin();
                for (a, w) in omega.iter_mut().enumerate() {
                    w[c] = w0[a];
                }
                let g = |w: [f64; 3]| [y.cos() * w[1], z.cos() * w[2], x.cos() * w[0]];
                let s0 = g(w0);
                let s = g(std::array::from_fn(|a| w0[a] + 0.5 * dt * s0[a]));
                expect[c] = std::array::from_fn(|a| w0[a] + dt * s[a]);
            }
        }
    }
    stretch(&grid, dt, &mut omega, &u);
    (0..grid.len())
        .flat_map(|c| (0..3).map(move |a| (c, a)))
        .map(|(c, a)| (omega[a][c] - expect[c][a]).abs())
        .fold(0.0, f64::max)
}

#[test]
fn stretching_converges_at_eighth_order() {
    let dt = 0.3;
    let errs: Vec<f64> = [8, 12, 16, 24].iter().map(|&n| error(n, dt)).collect();
    for (w, n) in errs.windows(2).zip([[8, 12], [12, 16], [16, 24]]) {
        let order = (w[0] / w[1]).ln() / (n[1] as f64 / n[0] as f64).ln();
        // The eighth-order centred difference's error is (k h)^8 / 630 times the derivative.
        assert!(
            order > 7.6 && order < 8.6,
            "order {order:.2} between n = {} and {} (errors {errs:?})",
            n[0],
            n[1]
        );
    }
    // The leading error term at n = 16: dt |w| (k h)^8 / 630 in size.
    let h: f64 = 2.0 * std::f64::consts::PI / 16.0;
    let bound = dt * 2.5 * h.powi(8) / 630.0 * 2.0;
    assert!(errs[2] < bound, "n = 16: error {:e} > {bound:e}", errs[2]);
}
