//! Integration tests of the periodic FFT engine and spectral operators (`tumble::solvers`).

use std::f64::consts::PI;
use std::time::Instant;

use crate::common::{Rng, on_threads};
use tumble::base::grid::Grid;
use tumble::solvers::fft::*;
use tumble::solvers::operators::*;

// ---------------------------------------------------------------------------------------------
// Helpers

fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

fn max_abs(a: &[f64]) -> f64 {
    a.iter().map(|x| x.abs()).fold(0.0, f64::max)
}

/// Samples `f(x, y, z)` on every node.
fn sample(grid: &Grid, f: impl Fn([f64; 3]) -> f64) -> Vec<f64> {
    let mut v = Vec::with_capacity(grid.len());
    for k in 0..grid.n[2] {
        for j in 0..grid.n[1] {
            for i in 0..grid.n[0] {
                v.push(f(grid.pos(i, j, k)));
            }
        }
    }
    v
}

/// One Fourier term `amp sin(k . x + phase)` of component `comp` of a vector potential, with
/// integer mode numbers `m` (so `k_a = 2 pi m_a / L_a`).
#[derive(Clone, Copy)]
struct Term {
    comp: usize,
    m: [i32; 3],
    amp: f64,
    phase: f64,
}

impl Term {
    fn k(&self, grid: &Grid) -> [f64; 3] {
        let e = grid.extent();
        std::array::from_fn(|a| {
            if e[a] > 0.0 {
                2.0 * PI * self.m[a] as f64 / e[a]
            } else {
                0.0
            }
        })
    }
    fn arg(&self, grid: &Grid, x: [f64; 3]) -> f64 {
        let k = self.k(grid);
        k[0] * x[0] + k[1] * x[1] + k[2] * x[2] + self.phase
    }
    fn k2(&self, grid: &Grid) -> f64 {
        self.k(grid).iter().map(|v| v * v).sum()
    }
}

/// Analytic vorticity (`-Lap psi`) and velocity (`curl psi`, plus `background`) of a potential
/// made of `terms` (a scalar stream function in 2D: all `comp == 0`).
fn analytic(grid: &Grid, terms: &[Term], background: [f64; 3]) -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
    let ncomp = grid.omega_components();
    let omega: Vec<Vec<f64>> = (0..ncomp)
        .map(|c| {
            sample(grid, |x| {
                terms
                    .iter()
                    .filter(|t| t.comp == c)
                    .map(|t| t.k2(grid) * t.amp * t.arg(grid, x).sin())
                    .sum()
            })
        })
        .collect();
    // d psi_c / d x_a
    let dpsi = |c: usize, a: usize, x: [f64; 3]| -> f64 {
        terms
            .iter()
            .filter(|t| t.comp == c)
            .map(|t| t.amp * t.k(grid)[a] * t.arg(grid, x).cos())
            .sum()
    };
    let u: Vec<Vec<f64>> = (0..grid.dim)
        .map(|c| {
            sample(grid, |x| {
                background[c]
                    + if grid.dim == 2 {
                        if c == 0 {
                            dpsi(0, 1, x)
                        } else {
                            -dpsi(0, 0, x)
                        }
                    } else {
                        let (a, b) = ((c + 1) % 3, (c + 2) % 3);
                        dpsi(b, a, x) - dpsi(a, b, x)
                    }
            })
        })
        .collect();
    (omega, u)
}

/// Spectral divergence (Nyquist wavenumbers zeroed) of a 3D field, as max |div_hat| over
/// max |k| max |w_hat|.
fn relative_divergence(grid: &Grid, sp: &mut Spectral, w: &[Vec<f64>]) -> f64 {
    let [nx, ny, nz] = grid.n;
    let e = grid.extent();
    let nxh = nx / 2 + 1;
    let kd = |m: usize, n: usize, l: f64| {
        if 2 * m == n { 0.0 } else { wavenumber(m, n, l) }
    };
    let hats: Vec<Vec<C64>> = w
        .iter()
        .map(|c| {
            let mut o = vec![C64::default(); sp.complex_len()];
            sp.forward(c, &mut o);
            o
        })
        .collect();
    let (mut dmax, mut wmax, mut kmax) = (0.0f64, 0.0f64, 0.0f64);
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nxh {
                let idx = i + nxh * (j + ny * k);
                let kv = [kd(i, nx, e[0]), kd(j, ny, e[1]), kd(k, nz, e[2])];
                let d = hats[0][idx] * kv[0] + hats[1][idx] * kv[1] + hats[2][idx] * kv[2];
                dmax = dmax.max(d.norm());
                for (a, h) in hats.iter().enumerate() {
                    wmax = wmax.max(h[idx].norm());
                    kmax = kmax.max(kv[a].abs());
                }
            }
        }
    }
    dmax / (wmax * kmax)
}

// ---------------------------------------------------------------------------------------------
// Transforms

#[test]
fn wavenumbers_are_signed_with_positive_nyquist() {
    let l = 2.0 * PI;
    assert_eq!(wavenumber(0, 8, l), 0.0);
    assert!((wavenumber(3, 8, l) - 3.0).abs() < 1e-15);
    assert!((wavenumber(4, 8, l) - 4.0).abs() < 1e-15);
    assert!((wavenumber(5, 8, l) + 3.0).abs() < 1e-15);
    assert!((wavenumber(2, 5, l) - 2.0).abs() < 1e-15);
    assert!((wavenumber(3, 5, l) + 2.0).abs() < 1e-15);
    assert!((wavenumber(1, 4, 0.5) - 4.0 * PI).abs() < 1e-13);
}

#[test]
fn roundtrip_random_2d_3d_odd_even() {
    let sizes = [
        [12, 10, 8],
        [9, 7, 5],
        [8, 5, 7],
        [7, 6, 4],
        [9, 6, 1],
        [8, 10, 1],
        [1, 4, 1],
        [5, 1, 3],
    ];
    let mut rng = Rng(42);
    for n in sizes {
        let grid = Grid::new(n, 0.1, [0.0; 3]);
        let mut sp = Spectral::new(&grid);
        assert_eq!(sp.complex_len(), (n[0] / 2 + 1) * n[1] * n[2]);
        let f = rng.field(grid.len());
        let mut hat = vec![C64::default(); sp.complex_len()];
        sp.forward(&f, &mut hat);
        let mut back = vec![0.0; grid.len()];
        sp.inverse(&mut hat, &mut back);
        let err = max_diff(&f, &back);
        assert!(err < 1e-12, "roundtrip {n:?}: error {err:e}");
    }
}

#[test]
fn forward_matches_naive_dft() {
    for n in [[6, 5, 4], [5, 4, 1], [4, 3, 3]] {
        let grid = Grid::new(n, 1.0, [0.0; 3]);
        let mut sp = Spectral::new(&grid);
        let f = Rng(7).field(grid.len());
        let mut hat = vec![C64::default(); sp.complex_len()];
        sp.forward(&f, &mut hat);
        let nxh = n[0] / 2 + 1;
        for k in 0..n[2] {
            for j in 0..n[1] {
                for i in 0..nxh {
                    let mut s = C64::default();
                    for z in 0..n[2] {
                        for y in 0..n[1] {
                            for x in 0..n[0] {
                                let ph = -2.0
                                    * PI
                                    * ((i * x) as f64 / n[0] as f64
                                        + (j * y) as f64 / n[1] as f64
                                        + (k * z) as f64 / n[2] as f64);
                                s += C64::from_polar(f[grid.idx(x, y, z)], ph);
                            }
                        }
                    }
                    let got = hat[i + nxh * (j + n[1] * k)];
                    assert!(
                        (got - s).norm() < 1e-12,
                        "{n:?} ({i},{j},{k}): {got} vs {s}"
                    );
                }
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Velocity

fn check_velocity(grid: &Grid, terms: &[Term], background: [f64; 3], tol: f64) {
    let (mut omega, u_exact) = analytic(grid, terms, background);
    let omega0 = omega.clone();
    let mut sp = Spectral::new(grid);
    let mut u = vec![vec![0.0; grid.len()]; grid.dim];
    sp.velocity(&mut omega, 1, background, &mut u);
    for c in 0..grid.dim {
        let err = max_diff(&u[c], &u_exact[c]);
        assert!(err < tol, "{:?} u[{c}] error {err:e}", grid.n);
    }
    // The analytic vorticity is divergence-free: cleaning must leave it as it was.
    for c in 0..omega.len() {
        let err = max_diff(&omega[c], &omega0[c]);
        assert!(err < tol, "{:?} omega[{c}] changed by {err:e}", grid.n);
    }
}

#[test]
fn velocity_2d_unit_square_2pi() {
    // psi = sin x cos 2y, omega = 5 sin x cos 2y, u = -2 sin x sin 2y, v = -cos x cos 2y.
    let grid = Grid::new([32, 32, 1], 2.0 * PI / 32.0, [0.0; 3]);
    let half = PI / 2.0;
    let terms = [
        // sin x cos 2y = (sin(x + 2y) + sin(x - 2y)) / 2
        Term {
            comp: 0,
            m: [1, 2, 0],
            amp: 0.5,
            phase: 0.0,
        },
        Term {
            comp: 0,
            m: [1, -2, 0],
            amp: 0.5,
            phase: 0.0,
        },
    ];
    check_velocity(&grid, &terms, [0.0; 3], 1e-10);
    // Cross-check the explicit formulas given in the docs.
    let (omega, u) = analytic(&grid, &terms, [0.0; 3]);
    let w2 = sample(&grid, |x| 5.0 * x[0].sin() * (2.0 * x[1]).cos());
    let u2 = sample(&grid, |x| -2.0 * x[0].sin() * (2.0 * x[1]).sin());
    let v2 = sample(&grid, |x| -x[0].cos() * (2.0 * x[1]).cos());
    assert!(max_diff(&omega[0], &w2) < 1e-13);
    assert!(max_diff(&u[0], &u2) < 1e-13);
    assert!(max_diff(&u[1], &v2) < 1e-13);
    // Plus a background flow and a shifted origin.
    let grid = Grid::new([24, 20, 1], 2.0 * PI / 24.0, [0.3, -1.0, 0.0]);
    let terms = [
        Term {
            comp: 0,
            m: [1, 2, 0],
            amp: 0.7,
            phase: half,
        },
        Term {
            comp: 0,
            m: [3, -1, 0],
            amp: -0.4,
            phase: 0.2,
        },
    ];
    check_velocity(&grid, &terms, [0.25, -0.5, 0.0], 1e-10);
}

#[test]
fn velocity_2d_box_not_2pi() {
    // [0,1] x [0,3]: ky = 2 pi m / 3.
    let grid = Grid::new([16, 48, 1], 1.0 / 16.0, [0.0; 3]);
    let terms = [
        Term {
            comp: 0,
            m: [1, 2, 0],
            amp: 1.0,
            phase: 0.0,
        },
        Term {
            comp: 0,
            m: [-2, 1, 0],
            amp: 0.3,
            phase: 1.0,
        },
        Term {
            comp: 0,
            m: [0, 5, 0],
            amp: 0.2,
            phase: -0.5,
        },
        Term {
            comp: 0,
            m: [3, 0, 0],
            amp: 0.1,
            phase: 0.7,
        },
    ];
    check_velocity(&grid, &terms, [1.0, 2.0, 0.0], 1e-10);
    // Odd sizes too.
    let grid = Grid::new([15, 21, 1], 0.05, [0.0; 3]);
    check_velocity(&grid, &terms, [0.0; 3], 1e-10);
}

#[test]
fn velocity_3d_non_cubic_box() {
    // n = 32 x 24 x 40, h = 2 pi / 32: box [0, 2pi] x [0, 1.5 pi] x [0, 2.5 pi].
    let grid = Grid::new([32, 24, 40], 2.0 * PI / 32.0, [0.0; 3]);
    // Each term of component c is independent of x_c, so div psi = 0.
    let terms = [
        Term {
            comp: 0,
            m: [0, 1, 2],
            amp: 1.0,
            phase: 0.3,
        },
        Term {
            comp: 1,
            m: [2, 0, -1],
            amp: 0.7,
            phase: 1.1,
        },
        Term {
            comp: 2,
            m: [1, -2, 0],
            amp: -0.5,
            phase: -0.4,
        },
        Term {
            comp: 0,
            m: [0, 3, 1],
            amp: 0.2,
            phase: 0.9,
        },
        Term {
            comp: 2,
            m: [4, 1, 0],
            amp: 0.1,
            phase: 0.0,
        },
    ];
    check_velocity(&grid, &terms, [0.0; 3], 1e-10);
    check_velocity(&grid, &terms, [0.3, -0.2, 0.1], 1e-10);
    // Odd sizes.
    let grid = Grid::new([15, 9, 11], 0.4, [1.0, 2.0, 3.0]);
    check_velocity(&grid, &terms, [0.3, -0.2, 0.1], 1e-10);
    // Few z-planes (x and y transforms not fused), even and odd.
    let grid = Grid::new([16, 12, 6], 0.3, [0.0; 3]);
    check_velocity(&grid, &terms, [0.3, -0.2, 0.1], 1e-10);
    let grid = Grid::new([11, 10, 5], 0.3, [0.0; 3]);
    check_velocity(&grid, &terms, [0.0; 3], 1e-10);
}

#[test]
fn velocity_cached_equals_fresh() {
    for n in [[16, 12, 10], [12, 9, 1]] {
        let grid = Grid::new(n, 0.2, [0.0; 3]);
        let ncomp = grid.omega_components();
        let mut rng = Rng(3);
        let mut omega: Vec<Vec<f64>> = (0..ncomp).map(|_| rng.field(grid.len())).collect();
        let mut sp = Spectral::new(&grid);
        let bg = [0.1, 0.2, 0.3];
        sp.diffuse(&mut omega, 0.05, TopDamping::NONE, 7);
        assert_eq!(sp.cached_version(), Some(7));
        let mut u1 = vec![vec![0.0; grid.len()]; grid.dim];
        sp.velocity(&mut omega, 7, bg, &mut u1);

        // Fresh solver: forward transform of the (already clean) omega.
        let mut omega2 = omega.clone();
        let mut sp2 = Spectral::new(&grid);
        let mut u2 = vec![vec![0.0; grid.len()]; grid.dim];
        sp2.velocity(&mut omega2, 0, bg, &mut u2);
        // Same solver, new version: transforms again.
        let mut omega3 = omega.clone();
        let mut u3 = vec![vec![0.0; grid.len()]; grid.dim];
        sp.velocity(&mut omega3, 8, bg, &mut u3);
        assert_eq!(sp.cached_version(), Some(8));
        let scale = u1.iter().map(|c| max_abs(c)).fold(0.0, f64::max);
        for c in 0..grid.dim {
            assert!(
                max_diff(&u1[c], &u2[c]) < 1e-12 * scale,
                "{n:?} fresh u[{c}]"
            );
            assert!(
                max_diff(&u1[c], &u3[c]) < 1e-12 * scale,
                "{n:?} re-made u[{c}]"
            );
        }
        for c in 0..ncomp {
            assert!(max_diff(&omega[c], &omega2[c]) < 1e-12, "{n:?} omega[{c}]");
        }
        // A changed omega with a stale version is ignored (cache used) ...
        let mut zero: Vec<Vec<f64>> = vec![vec![0.0; grid.len()]; ncomp];
        let mut u4 = vec![vec![0.0; grid.len()]; grid.dim];
        sp.velocity(&mut zero, 8, bg, &mut u4);
        assert_eq!(u4, u3);
        // ... and picked up with a new one.
        sp.velocity(&mut zero, 9, bg, &mut u4);
        for c in 0..grid.dim {
            assert!(u4[c].iter().all(|&v| (v - bg[c]).abs() < 1e-14));
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Diffusion and divergence cleaning

#[test]
fn diffuse_single_mode_decays_exactly() {
    let nu_dt = 0.013;
    // 2D
    let grid = Grid::new([16, 12, 1], 0.3, [0.1, 0.2, 0.0]);
    for m in [[1, 0, 0], [3, -2, 0], [8, 6, 0], [0, 5, 0]] {
        let t = Term {
            comp: 0,
            m,
            amp: 1.3,
            phase: 0.4,
        };
        // Implicit Euler with the exact Laplacian of the mode.
        let f = 1.0 / (1.0 + nu_dt * t.k2(&grid));
        let w0 = sample(&grid, |x| t.amp * t.arg(&grid, x).sin());
        let mut w = vec![w0.clone()];
        let mut sp = Spectral::new(&grid);
        sp.diffuse(&mut w, nu_dt, TopDamping::NONE, 1);
        let expect: Vec<f64> = w0.iter().map(|v| v * f).collect();
        let err = max_diff(&w[0], &expect);
        assert!(err < 1e-12, "2D mode {m:?}: {err:e}");
    }
    // 3D: divergence-free single modes (component c independent of x_c).
    let grid = Grid::new([16, 12, 10], 0.3, [0.0; 3]);
    let mut sp = Spectral::new(&grid);
    for (c, m) in [
        (2, [2, 3, 0]),
        (0, [0, -1, 4]),
        (1, [8, 0, 5]),
        (0, [0, 6, 5]),
    ] {
        let t = Term {
            comp: c,
            m,
            amp: 0.8,
            phase: -0.3,
        };
        // Implicit Euler with the exact Laplacian of the mode.
        let f = 1.0 / (1.0 + nu_dt * t.k2(&grid));
        let w0 = sample(&grid, |x| t.amp * t.arg(&grid, x).cos());
        let mut w = vec![vec![0.0; grid.len()]; 3];
        w[c] = w0.clone();
        sp.diffuse(&mut w, nu_dt, TopDamping::NONE, 2);
        for (a, wa) in w.iter().enumerate() {
            let err = if a == c {
                let expect: Vec<f64> = w0.iter().map(|v| v * f).collect();
                max_diff(wa, &expect)
            } else {
                max_abs(wa)
            };
            assert!(err < 1e-12, "3D mode {m:?} comp {a}: {err:e}");
        }
    }
}

/// ½⟨|u|²⟩ of the velocity of a 3D vorticity field.
fn energy_of(grid: &Grid, sp: &mut Spectral, w: &[Vec<f64>], version: u64) -> f64 {
    let mut w = w.to_vec();
    let mut u = vec![vec![0.0; grid.len()]; 3];
    sp.velocity(&mut w, version, [0.0; 3], &mut u);
    let sum: f64 = (0..grid.len())
        .map(|i| u.iter().map(|c| c[i] * c[i]).sum::<f64>())
        .sum();
    0.5 * sum / grid.len() as f64
}

#[test]
fn top_damping_is_exact_per_unit_time_and_spares_resolved_modes() {
    // Divergence-free single modes on a 16 x 12 x 10 grid (h = 0.3, k_N = pi/h): one on an
    // axis at the Nyquist wavenumber of y, one at |k| = k_N/2, one beyond the sphere of
    // radius k_N. Each is multiplied by exp(-S (|k|/k_N)^(2p)) whatever the number of steps
    // S is cut into, and the energy the damping reports removed is the drop of ½<|u|^2>.
    let grid = Grid::new([16, 12, 10], 0.3, [0.0; 3]);
    let kn = PI / grid.h;
    let (total, order) = (0.7, 8);
    for (c, m) in [(0, [0, 6, 0]), (2, [4, 0, 0]), (1, [8, 0, 5])] {
        let t = Term {
            comp: c,
            m,
            amp: 0.9,
            phase: 0.2,
        };
        let q = t.k2(&grid) / (kn * kn);
        let expect_factor = (-total * q.powi(order)).exp();
        let w0 = sample(&grid, |x| t.amp * t.arg(&grid, x).cos());
        for steps in [1, 2, 5] {
            let mut sp = Spectral::new(&grid);
            let mut w = vec![vec![0.0; grid.len()]; 3];
            w[c] = w0.clone();
            let e_before = energy_of(&grid, &mut sp, &w, 100);
            let damp = TopDamping {
                strength: total / steps as f64,
                order,
            };
            let mut removed = 0.0;
            for s in 0..steps {
                removed += sp.diffuse(&mut w, 0.0, damp, s as u64);
            }
            let expect: Vec<f64> = w0.iter().map(|v| v * expect_factor).collect();
            let err = max_diff(&w[c], &expect) / max_abs(&w0);
            assert!(
                err < 1e-12,
                "mode {m:?}, {steps} steps: factor error {err:e}"
            );
            let e_after = energy_of(&grid, &mut sp, &w, 200);
            let drop = e_before - e_after;
            // The energy scale of the mode (a Nyquist mode has no velocity: both are 0).
            let scale = 0.5 * t.amp * t.amp / t.k2(&grid);
            assert!(
                (removed - drop).abs() <= 1e-12 * scale,
                "mode {m:?}, {steps} steps: removed {removed:e}, energy drop {drop:e}"
            );
        }
        if m == [4, 0, 0] {
            // |k| = k_N/2: a resolved mode loses 2^-16 of the rate at the Nyquist wavenumber.
            assert!(
                (1.0 - expect_factor) < 1.1e-5,
                "k_N/2 damped by {expect_factor}"
            );
        }
        if m == [8, 0, 5] {
            // Beyond the sphere |k| = k_N (|k|/k_N = 1.19): removed within the interval.
            assert!(expect_factor < 0.01, "corner mode kept {expect_factor}");
        }
    }
    // A random field: the energy accounting holds over the whole half spectrum (the x
    // Nyquist plane and the conjugate pairs), on an odd and an even grid.
    for n in [[12, 10, 8], [9, 7, 6]] {
        let grid = Grid::new(n, 0.25, [0.0; 3]);
        let mut sp = Spectral::new(&grid);
        let mut rng = Rng(5);
        let mut w: Vec<Vec<f64>> = (0..3).map(|_| rng.field(grid.len())).collect();
        sp.diffuse(&mut w, 0.0, TopDamping::NONE, 1);
        let before = energy_of(&grid, &mut sp, &w, 2);
        let damp = TopDamping {
            strength: 0.5,
            order: 8,
        };
        let removed = sp.diffuse(&mut w, 0.01, damp, 3);
        // The same diffusion without the damping, for the energy it alone leaves.
        let mut sp2 = Spectral::new(&grid);
        let mut rng = Rng(5);
        let mut w2: Vec<Vec<f64>> = (0..3).map(|_| rng.field(grid.len())).collect();
        sp2.diffuse(&mut w2, 0.0, TopDamping::NONE, 1);
        sp2.diffuse(&mut w2, 0.01, TopDamping::NONE, 3);
        let diffused = energy_of(&grid, &mut sp2, &w2, 4);
        let after = energy_of(&grid, &mut sp, &w, 5);
        let drop = diffused - after;
        assert!(
            drop > 0.01 * before,
            "{n:?}: the damping removed only {drop:e} of {before:e}"
        );
        assert!(
            (removed - drop).abs() < 1e-10 * before,
            "{n:?}: removed {removed:e}, energy drop {drop:e}"
        );
    }
}

#[test]
fn diffuse_cleans_divergence_3d() {
    for n in [[12, 10, 8], [9, 7, 5]] {
        let grid = Grid::new(n, 0.25, [0.0; 3]);
        let mut sp = Spectral::new(&grid);
        let mut rng = Rng(11);
        let mut w: Vec<Vec<f64>> = (0..3).map(|_| rng.field(grid.len())).collect();
        let before = relative_divergence(&grid, &mut sp, &w);
        assert!(before > 0.1, "random field should not be divergence-free");
        sp.diffuse(&mut w, 0.0, TopDamping::NONE, 1);
        let after = relative_divergence(&grid, &mut sp, &w);
        assert!(after < 1e-12, "{n:?}: divergence after cleaning {after:e}");
        // Cleaning (without diffusion) a divergence-free field changes nothing.
        let clean = w.clone();
        sp.diffuse(&mut w, 0.0, TopDamping::NONE, 2);
        for c in 0..3 {
            let err = max_diff(&w[c], &clean[c]);
            assert!(err < 1e-12, "{n:?}: idempotence comp {c}: {err:e}");
        }
        // With diffusion too.
        let mut w: Vec<Vec<f64>> = (0..3).map(|_| rng.field(grid.len())).collect();
        sp.diffuse(&mut w, 0.3, TopDamping::NONE, 3);
        let after = relative_divergence(&grid, &mut sp, &w);
        assert!(after < 1e-12, "{n:?}: divergence after diffusion {after:e}");
    }
    // An analytic divergence-free field is unchanged.
    let grid = Grid::new([32, 24, 40], 2.0 * PI / 32.0, [0.0; 3]);
    let terms = [
        Term {
            comp: 0,
            m: [0, 1, 2],
            amp: 1.0,
            phase: 0.3,
        },
        Term {
            comp: 1,
            m: [2, 0, -1],
            amp: 0.7,
            phase: 1.1,
        },
        Term {
            comp: 2,
            m: [1, -2, 0],
            amp: -0.5,
            phase: -0.4,
        },
    ];
    let (omega0, _) = analytic(&grid, &terms, [0.0; 3]);
    let mut omega = omega0.clone();
    let mut sp = Spectral::new(&grid);
    sp.diffuse(&mut omega, 0.0, TopDamping::NONE, 1);
    for c in 0..3 {
        let err = max_diff(&omega[c], &omega0[c]);
        assert!(err < 1e-12, "analytic comp {c}: {err:e}");
    }
}

// ---------------------------------------------------------------------------------------------
// Determinism and allocation

/// Everything the solver computes on a fixed input, as bits.
fn run_all(n: [usize; 3]) -> Vec<u64> {
    let grid = Grid::new(n, 0.17, [0.0; 3]);
    let mut sp = Spectral::new(&grid);
    let mut rng = Rng(99);
    let ncomp = grid.omega_components();
    let mut omega: Vec<Vec<f64>> = (0..ncomp).map(|_| rng.field(grid.len())).collect();
    let mut out = Vec::new();
    let mut hat = vec![C64::default(); sp.complex_len()];
    sp.forward(&omega[0], &mut hat);
    out.extend(hat.iter().flat_map(|z| [z.re.to_bits(), z.im.to_bits()]));
    let mut back = vec![0.0; grid.len()];
    sp.inverse(&mut hat, &mut back);
    out.extend(back.iter().map(|v| v.to_bits()));
    let mut u = vec![vec![0.0; grid.len()]; grid.dim];
    sp.velocity(&mut omega, 1, [0.1, 0.2, 0.3], &mut u);
    out.extend(u.iter().flatten().map(|v| v.to_bits()));
    sp.diffuse(&mut omega, 0.02, TopDamping::NONE, 2);
    out.extend(omega.iter().flatten().map(|v| v.to_bits()));
    sp.velocity(&mut omega, 2, [0.0; 3], &mut u);
    out.extend(u.iter().flatten().map(|v| v.to_bits()));
    out
}

#[test]
fn bit_identical_across_thread_counts() {
    for n in [
        [24, 20, 18],
        [17, 12, 9],
        [20, 18, 6],
        [40, 30, 1],
        [33, 21, 1],
    ] {
        // 12 threads also changes the number of scratch workers (chunks).
        let results: Vec<Vec<u64>> = [1, 2, 3, 12]
            .iter()
            .map(|&t| on_threads(t, || run_all(n)))
            .collect();
        for (t, r) in results.iter().enumerate().skip(1) {
            assert!(
                *r == results[0],
                "{n:?}: thread count #{t} differs from 1 thread"
            );
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Timing (run with `cargo test --release --test suite -- --ignored --nocapture spectral::`)

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    v[v.len() / 2]
}

#[test]
#[ignore]
fn timing_128_cubed() {
    let n = 128;
    let grid = Grid::new([n, n, n], 2.0 * PI / n as f64, [0.0; 3]);
    let mut sp = Spectral::new(&grid);
    let mut rng = Rng(1);
    let mut omega: Vec<Vec<f64>> = (0..3).map(|_| rng.field(grid.len())).collect();
    let mut hats: Vec<Vec<C64>> = (0..3)
        .map(|_| vec![C64::default(); sp.complex_len()])
        .collect();
    let mut out = vec![0.0; grid.len()];
    let mut u = vec![vec![0.0; grid.len()]; 3];
    let mut raw = Vec::new();
    let mut step = Vec::new();
    for it in 0..6 {
        let t0 = Instant::now();
        for c in 0..3 {
            sp.forward(&omega[c], &mut hats[c]);
        }
        for r in 0..6 {
            sp.inverse(&mut hats[r % 3], &mut out);
        }
        let t1 = Instant::now();
        sp.diffuse(&mut omega, 1e-3, TopDamping::NONE, it);
        sp.velocity(&mut omega, it, [0.0; 3], &mut u);
        let t2 = Instant::now();
        if it > 0 {
            raw.push((t1 - t0).as_secs_f64());
            step.push((t2 - t1).as_secs_f64());
        }
    }
    println!(
        "128^3 on {} rayon threads: 3 forward + 6 inverse: median {:.4} s (min {:.4}); \
         diffuse + cached velocity: median {:.4} s",
        rayon::current_num_threads(),
        median(raw.clone()),
        raw.iter().cloned().fold(f64::INFINITY, f64::min),
        median(step)
    );
}

// ---------------------------------------------------------------------------------------------
// The no-slip's forcing response (systems/noslip.rs)

fn dot(a: &[Vec<f64>], b: &[Vec<f64>]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| x.iter().zip(y).map(|(p, q)| p * q).sum::<f64>())
        .sum()
}

/// f ↦ u = BS(∇×(m R f)) is symmetric and positive semi-definite (conjugate gradients rely on
/// it): ⟨a, K b⟩ = ⟨K a, b⟩ and ⟨a, K a⟩ ≥ 0 to round-off, for random fields in 2D and 3D on
/// grids of odd and even sizes.
#[test]
fn forcing_response_is_symmetric_positive() {
    for (n, dim) in [([12, 10, 8], 3), ([9, 8, 11], 3), ([16, 14, 1], 2)] {
        let grid = Grid::new(n, 0.1, [0.0; 3]);
        let mut s = Spectral::new(&grid);
        s.reserve_forcing();
        let mut rng = Rng(7);
        let a: Vec<Vec<f64>> = (0..dim).map(|_| rng.field(grid.len())).collect();
        let b: Vec<Vec<f64>> = (0..dim).map(|_| rng.field(grid.len())).collect();
        let mut ka = vec![vec![0.0; grid.len()]; dim];
        let mut kb = ka.clone();
        s.forcing_velocity(&a, 0.003, &mut ka);
        s.forcing_velocity(&b, 0.003, &mut kb);
        let (ab, ba) = (dot(&a, &kb), dot(&ka, &b));
        let scale = dot(&a, &a).sqrt() * dot(&kb, &kb).sqrt();
        assert!((ab - ba).abs() < 1e-12 * scale, "{n:?}: {ab} against {ba}");
        let aa = dot(&a, &ka);
        assert!(aa > 0.0, "{n:?}: <a, K a> = {aa}");
    }
}

/// The vorticity the forcing adds carries exactly the velocity it returned: the velocity of
/// ω + Δω is that of ω plus u, to round-off (2D and 3D).
#[test]
fn forcing_vorticity_carries_the_forcing_velocity() {
    for (n, dim) in [([12, 10, 8], 3), ([16, 14, 1], 2)] {
        let grid = Grid::new(n, 0.1, [0.0; 3]);
        let mut s = Spectral::new(&grid);
        s.reserve_forcing();
        let mut rng = Rng(11);
        let ncomp = if dim == 3 { 3 } else { 1 };
        let f: Vec<Vec<f64>> = (0..dim).map(|_| rng.field(grid.len())).collect();
        // A divergence-free vorticity (the curl of a random velocity, spectrally).
        let mut omega = vec![vec![0.0; grid.len()]; ncomp];
        let mut w0 = f.clone();
        s.forcing_reset();
        s.forcing_velocity(&f, 0.0, &mut w0);
        s.forcing_accumulate(1.0);
        s.forcing_vorticity_add(&mut omega, &mut vec![0.0; grid.len()]);
        let mut u0 = vec![vec![0.0; grid.len()]; dim];
        s.velocity(&mut omega, 1, [0.0; 3], &mut u0);
        // A combination of two forcings' responses, as the no-slip's iterations make one:
        // du = 0.7 K f + 0.3 K g, and its vorticity from the accumulated spectra.
        let g: Vec<Vec<f64>> = (0..dim).map(|_| rng.field(grid.len())).collect();
        let (mut kf, mut kg) = (f.clone(), f.clone());
        s.forcing_reset();
        s.forcing_velocity(&f, 0.002, &mut kf);
        s.forcing_accumulate(0.7);
        s.forcing_velocity(&g, 0.002, &mut kg);
        s.forcing_accumulate(0.3);
        let du: Vec<Vec<f64>> = kf
            .iter()
            .zip(&kg)
            .map(|(a, b)| a.iter().zip(b).map(|(x, y)| 0.7 * x + 0.3 * y).collect())
            .collect();
        s.forcing_vorticity_add(&mut omega, &mut vec![0.0; grid.len()]);
        let mut u1 = vec![vec![0.0; grid.len()]; dim];
        s.velocity(&mut omega, 2, [0.0; 3], &mut u1);
        let top = du.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
        for q in 0..dim {
            let expect: Vec<f64> = u0[q].iter().zip(&du[q]).map(|(a, b)| a + b).collect();
            assert!(
                max_diff(&u1[q], &expect) < 1e-12 * top.max(1.0),
                "{n:?} component {q}: {}",
                max_diff(&u1[q], &expect)
            );
        }
    }
}

/// For one divergence-free Fourier mode f = a sin(k·x), a ⊥ k, the forcing's velocity is
/// m(k) R(k) f: R = 1/(1 + νΔt|k|²) the diffusion's resolvent and m = Σ k_a sin(k_a h) / (h|k|²)
/// the centred curl's transfer function against the spectral one (2D and 3D).
#[test]
fn forcing_response_of_one_mode_is_its_symbol() {
    for (n, dim) in [([16, 12, 10], 3), ([16, 12, 1], 2)] {
        let h = 0.1;
        let grid = Grid::new(n, h, [0.0; 3]);
        let mut s = Spectral::new(&grid);
        s.reserve_forcing();
        let len = |a: usize| n[a] as f64 * h;
        let m_int = [3.0, 2.0, if dim == 3 { 1.0 } else { 0.0 }];
        let k: Vec<f64> = (0..3).map(|a| 2.0 * PI * m_int[a] / len(a)).collect();
        // a ⊥ k: (k_y, -k_x, 0).
        let amp = [k[1], -k[0], 0.0];
        let f: Vec<Vec<f64>> = (0..dim)
            .map(|c| {
                sample(&grid, |x| {
                    amp[c] * (k[0] * x[0] + k[1] * x[1] + k[2] * x[2]).sin()
                })
            })
            .collect();
        let nu_dt = 0.002;
        let k2: f64 = k.iter().map(|v| v * v).sum();
        let m = k.iter().map(|v| v * (v * h).sin()).sum::<f64>() / (h * k2);
        let factor = m / (1.0 + nu_dt * k2);
        let mut u = vec![vec![0.0; grid.len()]; dim];
        s.forcing_velocity(&f, nu_dt, &mut u);
        for c in 0..dim {
            let expect: Vec<f64> = f[c].iter().map(|v| v * factor).collect();
            let err = max_diff(&u[c], &expect);
            assert!(
                err < 1e-12 * max_abs(&f[c]).max(1.0),
                "{n:?} component {c}: {err}"
            );
        }
    }
}
