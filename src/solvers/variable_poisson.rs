//! The variable-coefficient Poisson solve -∇·(β∇φ) = b on the periodic grid: conjugate
//! gradients on A = -h²∇·(β∇) (the compact 5/7-point stencil, β given on the faces),
//! preconditioned by the inverse of the constant-coefficient Laplacian (one real FFT pair,
//! exact when β is uniform) or by one multigrid V-cycle ([`crate::solvers::multigrid`]),
//! started from the φ it is given. Dot products are summed row by row in a fixed order, so the
//! result does not depend on the thread count.
//!
//! On several processes each holds its slab of every vector: the operator reads one ghost plane
//! of the iterate and of β a side ([`Halo`]), the dot products are added over the processes in
//! rank order, the FFT preconditioner is the split one and the multigrid hierarchy the split one
//! ([`Multigrid::split`]), so a solve gives the one-process solve's bits whatever the
//! preconditioner.

use crate::base::grid::{Grid, RowNeighbours, for_row, line_at};
use crate::parallel::halo::z_line;
use crate::parallel::{Comm, Decomposition, Halo, RowSums};
use crate::solvers::Spectral;
use crate::solvers::multigrid::Multigrid;
use rayon::prelude::*;
use std::sync::Arc;

/// Iteration cap of the solve.
pub const MAX_ITERATIONS: usize = 2000;
/// The ratio max β / min β from which a solve is preconditioned by multigrid.
///
/// On a sphere of density ratio c in a 64³ box (a random right-hand side, from zero, to a
/// relative residual of 1e-7) the FFT preconditioner took 9, 14, 18, 23, 30, 38 and 45
/// iterations at c = 2, 5, 10, 20, 50, 0.01 and 1000, and multigrid 5, 6, 6, 6, 6, 7 and 7.
/// One V-cycle costs about two to two and a half FFT iterations: from c = 2 to 5 the two solves
/// took the same time within the machine's noise (0.04 to 0.08 s), at 10 multigrid 0.067 s
/// against 0.093 to 0.105 s (2 cores, 2026-11-25).
pub const MULTIGRID_CONTRAST: f64 = 5.0;

/// Whether a scene whose fluid phases and moving bodies have these `densities` wants the
/// multigrid hierarchy: they span a ratio of [`MULTIGRID_CONTRAST`] or more, and `grid`
/// coarsens far enough ([`crate::solvers::multigrid::coarsens_fully`]).
pub fn wants_multigrid(grid: &Grid, densities: impl IntoIterator<Item = f64>) -> bool {
    let (lo, hi) = densities
        .into_iter()
        .fold((f64::INFINITY, 0.0f64), |(lo, hi), d| {
            (lo.min(d), hi.max(d))
        });
    hi >= MULTIGRID_CONTRAST * lo && crate::solvers::multigrid::coarsens_fully(grid)
}

/// The preconditioner of the conjugate gradients.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Preconditioner {
    /// The inverse of the constant-coefficient Laplacian (one FFT pair an iteration).
    #[default]
    Spectral,
    /// One multigrid V-cycle an iteration.
    Multigrid,
}

/// The solver's coefficients and scratch, allocated once.
#[derive(Debug, Clone)]
pub struct VariablePoisson {
    /// β on the face between node i and node i + e_a, stored at i, per axis.
    pub beta: Vec<Vec<f64>>,
    /// The right-hand side b, scaled as h² b (set before [`VariablePoisson::solve`]; the
    /// residual afterwards).
    pub rhs: Vec<f64>,
    z: Vec<f64>,
    p: Vec<f64>,
    ap: Vec<f64>,
    /// Per-row partial sums (fixed order, thread-count independent).
    partial: Vec<f64>,
    /// The multigrid hierarchy, where the scene can make a contrast of
    /// [`MULTIGRID_CONTRAST`] or more.
    multigrid: Option<Multigrid>,
    /// The preconditioner of the last solve.
    pub preconditioner: Preconditioner,
    /// Iterations of the last solve.
    pub iterations: usize,
    /// Relative residual reached by the last solve.
    pub residual: f64,
    /// On several processes: the ghost planes of the iterate (0) and of β along z (1).
    split: Option<Halo>,
    /// On several processes: their communicator (for the contrast over the whole grid).
    comm: Option<Arc<Comm>>,
    /// The sums over the rows (the same on any number of processes).
    sums: RowSums,
}

impl VariablePoisson {
    /// Zero state for `grid`; with `multigrid`, the multigrid hierarchy too (which
    /// [`VariablePoisson::choose`] then picks where β varies by [`MULTIGRID_CONTRAST`] or
    /// more), unless the grid's node counts do not coarsen far enough
    /// ([`crate::solvers::multigrid::coarsens_fully`]).
    pub fn new(grid: &Grid, multigrid: bool, split: Option<&Decomposition>) -> Self {
        let n = grid.len();
        // Decided on the whole grid, the same on every process.
        let multigrid = multigrid && crate::solvers::multigrid::coarsens_fully(&grid.whole());
        VariablePoisson {
            beta: vec![vec![0.0; n]; grid.dim],
            rhs: vec![0.0; n],
            z: vec![0.0; n],
            p: vec![0.0; n],
            ap: vec![0.0; n],
            partial: vec![0.0; n / grid.n[0]],
            multigrid: multigrid.then(|| match split {
                Some(d) if d.slabs.ranks > 1 => Multigrid::split(grid, d),
                _ => Multigrid::new(grid),
            }),
            preconditioner: Preconditioner::Spectral,
            iterations: 0,
            residual: 0.0,
            split: split.map(|d| Halo::new(grid, d, 1, 2)),
            comm: split.map(|d| d.comm.clone()),
            sums: RowSums::new(grid, split),
        }
    }

    /// On a slab, fills the ghost planes of β along z from the neighbours (after `beta` is
    /// set, before [`VariablePoisson::beta_halo`] is read or the solve); nothing on one
    /// process.
    pub fn fill_beta_halo(&mut self, grid: &Grid) {
        if let Some(h) = &mut self.split
            && grid.dim == 3
        {
            h.fill_one(1, &self.beta[2]);
        }
    }

    /// The halo whose component 1 holds β along z's ghost planes (filled by
    /// [`VariablePoisson::fill_beta_halo`]), on a slab.
    pub fn beta_halo(&self) -> Option<&Halo> {
        self.split.as_ref()
    }

    /// The right-hand side to set, with β and its halo (see [`VariablePoisson::beta_halo`]).
    pub fn rhs_beta(&mut self) -> (&mut [f64], &[Vec<f64>], Option<&Halo>) {
        (&mut self.rhs, &self.beta, self.split.as_ref())
    }

    /// Solves -h²∇·(β∇φ) = `rhs` to a relative residual `tolerance` from the φ given, with
    /// `beta` and `rhs` as set, preconditioned by `with` (the FFT inverse if the solver has no
    /// multigrid hierarchy); returns (iterations, relative residual).
    pub fn solve(
        &mut self,
        grid: &Grid,
        phi: &mut [f64],
        spectral: &mut Spectral,
        with: Preconditioner,
        tolerance: f64,
    ) -> (usize, f64) {
        let with = if self.multigrid.is_some() {
            with
        } else {
            Preconditioner::Spectral
        };
        let (it, res) = solve(grid, self, phi, spectral, with, tolerance);
        self.preconditioner = with;
        self.iterations = it;
        self.residual = res;
        (it, res)
    }

    /// The preconditioner for the β set now: multigrid if the solver has its hierarchy and
    /// max β / min β ≥ [`MULTIGRID_CONTRAST`] over the whole grid, else the FFT inverse (the
    /// same on every process, which call it together).
    ///
    /// Whether it has the hierarchy: [`VariablePoisson::has_multigrid`].
    pub fn choose(&self) -> Preconditioner {
        if self.multigrid.is_none() {
            return Preconditioner::Spectral;
        }
        let (lo, hi) = self
            .beta
            .par_iter()
            .flat_map(|b| b.par_iter())
            .fold(
                || (f64::INFINITY, 0.0f64),
                |(lo, hi), &v| (lo.min(v), hi.max(v)),
            )
            .reduce(
                || (f64::INFINITY, 0.0f64),
                |a, b| (a.0.min(b.0), a.1.max(b.1)),
            );
        let (lo, hi) = match &self.comm {
            Some(c) => {
                let mut v = [-lo, hi];
                c.max(&mut v);
                (-v[0], v[1])
            }
            None => (lo, hi),
        };
        if hi >= MULTIGRID_CONTRAST * lo {
            Preconditioner::Multigrid
        } else {
            Preconditioner::Spectral
        }
    }

    /// Whether the solver holds a multigrid hierarchy.
    pub fn has_multigrid(&self) -> bool {
        self.multigrid.is_some()
    }

    /// Mean of a field over the whole grid (rows in order, thread-count independent).
    pub fn mean(&mut self, nx: usize, a: &[f64]) -> f64 {
        mean(&mut self.partial, nx, a, &mut self.sums)
    }
}

/// `out = A x` with A = -∇·(β∇) (compact stencil, periodic), times h², and x·Ax in the same
/// pass (per row into `partial`, then the rows in order: the same sum as [`dot`]). Row by row,
/// with the neighbour rows as slices and the interior of a row in one branch-free loop. On a
/// slab the rows beyond it come from `halo` (component 0: `x`, filled here; 1: β along z).
fn apply<'a>(
    grid: &Grid,
    beta: &'a [Vec<f64>],
    x: &'a [f64],
    out: &mut [f64],
    partial: &mut [f64],
    split: Option<&'a mut Halo>,
    sums: &mut RowSums,
) -> f64 {
    let nx = grid.n[0];
    let three = grid.dim == 3;
    let halo = split.map(|h| {
        if three {
            h.fill_one(0, x);
        }
        &*h
    });
    out.par_chunks_mut(nx)
        .zip(partial.par_iter_mut())
        .enumerate()
        .for_each(|(row, (o, xax))| {
            let rn = RowNeighbours::new(grid, row);
            let line = |f: &'a [f64], at: usize| line_at(f, at, nx);
            let (xc, bx) = (line(x, rn.c0), line(&beta[0], rn.c0));
            let (ym, yp) = (line(x, rn.below[0]), line(x, rn.above[0]));
            let (by, bym) = (line(&beta[1], rn.c0), line(&beta[1], rn.below[0]));
            let (zm, zp, bz, bzm) = if three {
                (
                    z_line(grid, x, halo, 0, row, -1),
                    z_line(grid, x, halo, 0, row, 1),
                    line(&beta[2], rn.c0),
                    z_line(grid, &beta[2], halo, 1, row, -1),
                )
            } else {
                (xc, xc, bx, bx)
            };
            let node = |i: usize, im: usize, ip: usize| {
                let c = xc[i];
                let mut s = 0.0;
                s += bx[i] * (c - xc[ip]) + bx[im] * (c - xc[im]);
                s += by[i] * (c - yp[i]) + bym[i] * (c - ym[i]);
                if three {
                    s += bz[i] * (c - zp[i]) + bzm[i] * (c - zm[i]);
                }
                s
            };
            for_row(nx, |i, im, ip| o[i] = node(i, im, ip));
            *xax = xc.iter().zip(o.iter()).map(|(x, y)| x * y).sum();
        });
    sums.total(partial)
}

/// Σ a_i b_i, summed per row and then over rows in order (and processes).
fn dot(partial: &mut [f64], nx: usize, a: &[f64], b: &[f64], sums: &mut RowSums) -> f64 {
    partial.par_iter_mut().enumerate().for_each(|(row, s)| {
        let r = row * nx..(row + 1) * nx;
        *s = a[r.clone()].iter().zip(&b[r]).map(|(x, y)| x * y).sum();
    });
    sums.total(partial)
}

/// Mean of a field over the whole grid (rows in order, then processes).
fn mean(partial: &mut [f64], nx: usize, a: &[f64], sums: &mut RowSums) -> f64 {
    partial
        .par_iter_mut()
        .enumerate()
        .for_each(|(row, s)| *s = a[row * nx..(row + 1) * nx].iter().sum());
    sums.total(partial) / sums.whole_len(nx) as f64
}

/// Solves A φ = b (A = -h²∇·(β∇)) by preconditioned conjugate gradients from the φ it holds.
/// Returns (iterations, relative residual).
fn solve(
    grid: &Grid,
    s: &mut VariablePoisson,
    phi: &mut [f64],
    spectral: &mut Spectral,
    with: Preconditioner,
    tolerance: f64,
) -> (usize, f64) {
    let nx = grid.n[0];
    let VariablePoisson {
        beta,
        rhs: r,
        z,
        p,
        ap,
        partial,
        multigrid,
        split,
        sums,
        ..
    } = s;
    if let (Preconditioner::Multigrid, Some(mg)) = (with, multigrid.as_mut()) {
        mg.set_coefficients(beta);
    }
    // r holds b on entry; remove its mean (zero up to round-off: it is a divergence).
    let mb = mean(partial, nx, r, sums);
    r.par_iter_mut().for_each(|v| *v -= mb);
    let bnorm = dot(partial, nx, r, r, sums).sqrt();
    if bnorm == 0.0 {
        phi.par_iter_mut().for_each(|v| *v = 0.0);
        return (0, 0.0);
    }
    apply(grid, beta, phi, ap, partial, split.as_mut(), sums);
    r.par_iter_mut()
        .zip(ap.par_iter())
        .for_each(|(r, a)| *r -= a);
    let mut rnorm = dot(partial, nx, r, r, sums).sqrt();
    if rnorm <= tolerance * bnorm {
        return (0, rnorm / bnorm);
    }
    // The preconditioner z = M r: M = A⁻¹ for β = 1, (-h² Lap_h)⁻¹ (one FFT pair), or one
    // multigrid V-cycle; returns r·z (the scaling and the dot product in one pass).
    let inv_h2 = 1.0 / (grid.h * grid.h);
    let mut precondition = |spectral: &mut Spectral,
                            sums: &mut RowSums,
                            partial: &mut [f64],
                            r: &[f64],
                            z: &mut [f64]| {
        let scale = match with {
            Preconditioner::Spectral => {
                spectral.solve_laplacian(r, z);
                inv_h2
            }
            Preconditioner::Multigrid => {
                if let Some(mg) = multigrid.as_mut() {
                    mg.apply(r, z);
                }
                1.0
            }
        };
        partial
            .par_iter_mut()
            .zip(z.par_chunks_mut(nx))
            .zip(r.par_chunks(nx))
            .for_each(|((s, z), r)| {
                if scale != 1.0 {
                    for v in z.iter_mut() {
                        *v *= scale;
                    }
                }
                *s = r.iter().zip(z.iter()).map(|(x, y)| x * y).sum();
            });
        sums.total(partial)
    };
    let mut rz = precondition(spectral, sums, partial, r, z);
    p.copy_from_slice(z);
    let mut it = 0;
    while it < MAX_ITERATIONS {
        it += 1;
        let pap = apply(grid, beta, p, ap, partial, split.as_mut(), sums);
        if pap <= 0.0 {
            break;
        }
        let alpha = rz / pap;
        // φ += α p, r -= α Ap and |r|² in one pass (per row, then rows in order).
        partial
            .par_iter_mut()
            .zip(phi.par_chunks_mut(nx))
            .zip(r.par_chunks_mut(nx))
            .zip(p.par_chunks(nx).zip(ap.par_chunks(nx)))
            .for_each(|(((s, x), r), (p, a))| {
                for i in 0..x.len() {
                    x[i] += alpha * p[i];
                    r[i] -= alpha * a[i];
                }
                *s = r.iter().map(|v| v * v).sum();
            });
        rnorm = sums.total(partial).sqrt();
        if rnorm <= tolerance * bnorm {
            break;
        }
        let rz_new = precondition(spectral, sums, partial, r, z);
        let b = rz_new / rz;
        rz = rz_new;
        p.par_iter_mut()
            .zip(z.par_iter())
            .for_each(|(p, z)| *p = z + b * *p);
    }
    (it, rnorm / bnorm)
}
