//! The sweep of the momentum form: mass, momentum and the liquid's level set carried together
//! by the same particles, remeshed with the same weights.
//!
//! Every node is a particle. Along one axis it is pushed with the midpoint RK2 rule
//! x ← x + Δt u(x + Δt/2 u(x)) (velocity interpolated along the line with M'4, as in
//! [`crate::solvers::sweep`]) and each of its fields is remeshed onto the line with one set of
//! weights: the linear hat kernel (weights 1 - f and f on the two nodes around it, never
//! negative) for a particle within [`NEAR_CELLS`] cells of the free surface or of a body, M'4
//! elsewhere. Both kernels conserve the zeroth and first moments, so mass and momentum are
//! conserved exactly and a uniform velocity stays uniform across any density jump: the remeshed
//! velocity q̃/ρ̃ of particles that all carry u is u. Where the weights are non-negative the
//! remesh cannot create kinetic energy (Σ q̃²/ρ̃ ≤ Σ m u², Cauchy-Schwarz node by node) nor a
//! negative density; M'4's negative lobes (down to -1/16 of a particle's mass at 1.5 cells)
//! would give a gas node next to water a density of -60 at 1:1000. Far from an interface the
//! density is uniform and M'4 keeps its second-order accuracy and low dissipation.
//!
//! Which kernel a particle takes is decided by its own carried level set and the bodies' level
//! set at its starting node, so every field of a particle moves with the same weights. The
//! threshold holds the M'4 particles' support (2 cells past a displacement of at most one
//! cell) out of the smoothed interface band (`interface_cells` half-width). Where neighbouring
//! particles take different kernels the weights a node receives do not sum to one: a uniform
//! density dips there by up to 7% (an M'4 particle displaced by 0.7 cells puts -0.0735 of
//! itself on the node 1.3 cells away, which no hat particle compensates). The velocity stays
//! exact (the same weights carry mass and momentum), and the density is reset from the level
//! set every step; a kernel that blends the two would remove the dip.
//!
//! Lines are independent and each is handled whole by one task, so results do not depend on
//! the thread count; nothing is allocated in a sweep ([`CarryPool`] holds the line buffers).

use crate::base::grid::{Grid, SyncPtr};
use crate::base::kernels::m4prime_weights;
use crate::base::pool::Pool;
use rayon::prelude::*;

/// Cells from an interface within which a particle is remeshed with the hat kernel, beyond
/// the smoothed band's half-width: M'4's support (2 cells) plus one cell of displacement.
pub const NEAR_CELLS: f64 = 3.0;

/// The most fields a sweep carries (mass, three momentum components, the level set, one
/// more).
pub const MAX_FIELDS: usize = 6;

/// Per-thread line buffers of the carrying sweeps.
pub type CarryPool = Pool<CarryScratch>;

/// Lines handled together by one task: across x, their nodes at one position along the sweep
/// are consecutive in memory, so gathering and scattering a group reads and writes whole cache
/// lines instead of one value per line.
const GROUP: usize = 8;

/// Line buffers of a group of [`GROUP`] lines: the carried fields in and out, the velocity
/// along the lines and the bodies' level set along them (line `l` at `l * nmax ..`).
pub struct CarryScratch {
    nmax: usize,
    fin: Vec<Vec<f64>>,
    fout: Vec<Vec<f64>>,
    u: Vec<f64>,
    solid: Vec<f64>,
}

impl CarryScratch {
    /// Buffers for lines of up to `nmax` nodes and `nf` carried fields.
    pub fn new(nmax: usize, nf: usize) -> Self {
        CarryScratch {
            nmax,
            fin: vec![vec![0.0; GROUP * nmax]; nf],
            fout: vec![vec![0.0; GROUP * nmax]; nf],
            u: vec![0.0; GROUP * nmax],
            solid: vec![0.0; GROUP * nmax],
        }
    }
}

/// The weights of a hat kernel at fractional offset `f ∈ [0, 1)` from node `i0`, on nodes
/// `i0 - 1 ..= i0 + 2` (the layout of [`m4prime_weights`]).
#[inline(always)]
pub fn hat_weights(f: f64) -> [f64; 4] {
    [0.0, 1.0 - f, f, 0.0]
}

/// The thresholds of [`carry_sweep`]: a particle whose carried level set is below
/// `level_set` in magnitude, or whose node has a bodies' level set above `-solid`, is
/// remeshed with the hat kernel.
#[derive(Debug, Clone, Copy)]
pub struct Near {
    /// Index of the carried field that is the liquid's level set.
    pub field: usize,
    /// |φ_w| below which the hat kernel is used (length).
    pub level_set: f64,
    /// Distance outside a body within which the hat kernel is used (length).
    pub solid: f64,
}

/// One carrying sweep along `axis`: every node's particle pushed with `u_axis` over `dt`
/// and its `fields` remeshed together (see the module doc). `solid` is the bodies' union
/// level set per node (> 0 inside; empty when there are no bodies).
#[allow(clippy::too_many_arguments)]
pub fn carry_sweep(
    grid: &Grid,
    axis: usize,
    dt: f64,
    fields: &mut [Vec<f64>],
    u_axis: &[f64],
    solid: &[f64],
    near: Near,
    pool: &CarryPool,
) {
    let n = grid.n[axis];
    let [nx, ny, _] = grid.n;
    let nlines = grid.len() / n;
    let stride = match axis {
        0 => 1,
        1 => nx,
        _ => nx * ny,
    };
    // Groups: along x, GROUP consecutive rows; across x, up to GROUP lines of consecutive i in
    // one row of lines.
    let per_row = nx.div_ceil(GROUP);
    let ngroups = if axis == 0 {
        nlines.div_ceil(GROUP)
    } else {
        (nlines / nx) * per_row
    };
    // The first node of each line of group `g`, and how many lines it has.
    let bases = |g: usize| {
        let mut base = [0usize; GROUP];
        let count = if axis == 0 {
            let first = g * GROUP;
            let count = GROUP.min(nlines - first);
            for (l, b) in base.iter_mut().enumerate().take(count) {
                *b = (first + l) * nx;
            }
            count
        } else {
            let (r, ib) = (g / per_row, g % per_row);
            let i0 = ib * GROUP;
            let b0 = if axis == 1 {
                i0 + nx * ny * r
            } else {
                i0 + nx * r
            };
            for (l, b) in base.iter_mut().enumerate() {
                *b = b0 + l;
            }
            GROUP.min(nx - i0)
        };
        (base, count)
    };
    assert!(
        fields.len() <= MAX_FIELDS,
        "carry_sweep: at most {MAX_FIELDS} fields"
    );
    let mut all = [SyncPtr(std::ptr::null_mut()); MAX_FIELDS];
    for (p, f) in all.iter_mut().zip(fields.iter_mut()) {
        *p = SyncPtr(f.as_mut_ptr());
    }
    let ptrs = &all[..fields.len()];
    let cdt = dt / grid.h;
    let (near_ls, near_solid) = (near.level_set, -near.solid);
    let has_solid = !solid.is_empty();
    (0..ngroups).into_par_iter().for_each(|g| {
        pool.with(|s| {
            let (base, count) = bases(g);
            let (nf, m) = (ptrs.len(), s.nmax);
            for p in 0..n {
                for (l, &b) in base.iter().enumerate().take(count) {
                    let at = b + p * stride;
                    s.u[l * m + p] = u_axis[at];
                    s.solid[l * m + p] = if has_solid {
                        solid[at]
                    } else {
                        f64::NEG_INFINITY
                    };
                }
                for c in 0..nf {
                    for (l, &b) in base.iter().enumerate().take(count) {
                        // SAFETY: the lines of group `g` belong to this task only.
                        s.fin[c][l * m + p] = unsafe { ptrs[c].read(b + p * stride) };
                    }
                }
            }
            for l in 0..count {
                line(s, l, n, nf, cdt, near.field, near_ls, near_solid);
            }
            for c in 0..nf {
                for p in 0..n {
                    for (l, &b) in base.iter().enumerate().take(count) {
                        // SAFETY: the lines of group `g` belong to this task only.
                        unsafe { ptrs[c].write(b + p * stride, s.fout[c][l * m + p]) };
                    }
                }
            }
        })
    });
}

/// Push and remesh line `l` (of `n` nodes, periodic) of the group held in `s`.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn line(
    s: &mut CarryScratch,
    l: usize,
    n: usize,
    nf: usize,
    cdt: f64,
    ls: usize,
    near_ls: f64,
    near_solid: f64,
) {
    let ni = n as i64;
    let off = l * s.nmax;
    for o in s.fout.iter_mut().take(nf) {
        o[off..off + n].fill(0.0);
    }
    let u = &s.u[off..off + n];
    let solid = &s.solid[off..off + n];
    // M'4 interpolation of the line's velocity at `x` (grid units), periodic.
    let interp = |x: f64| {
        let b = x.floor();
        let w = m4prime_weights(x - b);
        let b = b as i64 - 1;
        let mut acc = 0.0;
        if b >= 0 && b + 3 < ni {
            let s0 = b as usize;
            for q in 0..4 {
                acc += w[q] * u[s0 + q];
            }
        } else {
            for (q, wq) in w.iter().enumerate() {
                acc += wq * u[(b + q as i64).rem_euclid(ni) as usize];
            }
        }
        acc
    };
    for p in 0..n {
        let pf = p as f64;
        let x_mid = pf + 0.5 * cdt * u[p];
        let x_new = pf + cdt * interp(x_mid);
        let b = x_new.floor();
        let f = x_new - b;
        let hat = s.fin[ls][off + p].abs() < near_ls || solid[p] > near_solid;
        let w = if hat {
            hat_weights(f)
        } else {
            m4prime_weights(f)
        };
        let b = b as i64 - 1;
        if b >= 0 && b + 3 < ni {
            let s0 = off + b as usize;
            for c in 0..nf {
                let v = s.fin[c][off + p];
                let o = &mut s.fout[c][s0..s0 + 4];
                for q in 0..4 {
                    o[q] += w[q] * v;
                }
            }
        } else {
            for (q, wq) in w.iter().enumerate() {
                let t = off + (b + q as i64).rem_euclid(ni) as usize;
                for c in 0..nf {
                    let v = s.fin[c][off + p];
                    s.fout[c][t] += wq * v;
                }
            }
        }
    }
}
