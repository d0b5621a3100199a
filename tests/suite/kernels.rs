//! The grid's nearest node and the remeshing kernels' moments.

use tumble::base::grid::Grid;
use tumble::base::kernels::*;

/// Nodes sit at origin + i h: a coordinate takes the nearest, wrapped into the box.
#[test]
fn nearest_node_wraps_periodically() {
    let g = Grid::new([8, 4, 1], 0.5, [1.0, -1.0, 0.0]);
    assert_eq!(g.nearest(0, 1.0 + 3.0 * 0.5 + 0.2), 3);
    assert_eq!(g.nearest(0, 1.0 + 3.0 * 0.5 + 0.3), 4);
    assert_eq!(g.nearest(0, 1.0 + 8.4 * 0.5), 0);
    assert_eq!(g.nearest(0, 1.0 - 0.6 * 0.5), 7);
    assert_eq!(g.nearest(1, -1.0 - 2.0 * 0.5), 2);
}

#[test]
fn lambda42_reproduces_cubics() {
    for &f in &[0.0, 0.1, 0.37, 0.5, 0.99] {
        let w = lambda42_weights(f);
        for m in 0..4 {
            let mom: f64 = (0..6).map(|q| w[q] * (q as f64 - 2.0 - f).powi(m)).sum();
            let exact = if m == 0 { 1.0 } else { 0.0 };
            assert!((mom - exact).abs() < 1e-11, "f={f} m={m} {mom}");
        }
    }
    assert_eq!(lambda42(0.0), 1.0);
    for x in [1.0, 2.0, 3.0] {
        assert!(lambda42(x).abs() < 1e-13);
    }
}

#[test]
fn m4prime_reproduces_quadratics() {
    for &f in &[0.0, 0.1, 0.37, 0.5, 0.99] {
        let w = m4prime_weights(f);
        for m in 0..3 {
            let mom: f64 = (0..4).map(|q| w[q] * (q as f64 - 1.0 - f).powi(m)).sum();
            let exact = if m == 0 { 1.0 } else { 0.0 };
            assert!((mom - exact).abs() < 1e-11, "f={f} m={m} {mom}");
        }
    }
}

#[test]
fn weights_match_kernel() {
    for &f in &[0.0, 0.1, 0.37, 0.5, 0.99] {
        let w = m4prime_weights(f);
        let k = [
            m4prime(1.0 + f),
            m4prime(f),
            m4prime(1.0 - f),
            m4prime(2.0 - f),
        ];
        for q in 0..4 {
            assert!((w[q] - k[q]).abs() < 1e-15, "f={f} q={q} {} {}", w[q], k[q]);
        }
    }
}
