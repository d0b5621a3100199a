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
//! Lines are pushed [`LANES`] at a time, interleaved (node p of lane l at `p * LANES + l`), so
//! a particle's arithmetic runs on all lanes at once in vector registers; a particle that moves
//! less than a cell remeshes into a window of five nodes, branch-free. Every lane does the
//! one-line algorithm's arithmetic in the same order (the window's extra terms are exact
//! zeros), so a node's value does not depend on which lines share its group. Lines are
//! independent and each group is handled whole by one task, so results do not depend on the
//! thread count; nothing is allocated in a sweep ([`CarryPool`] holds the line buffers).

use crate::base::grid::{Grid, SyncPtr};
use crate::base::kernels::m4prime_weights;
use crate::base::pool::Pool;
use crate::solvers::sweep::fill_periodic_ghosts;
use rayon::prelude::*;

/// Cells from an interface within which a particle is remeshed with the hat kernel, beyond
/// the smoothed band's half-width: M'4's support (2 cells) plus one cell of displacement.
pub const NEAR_CELLS: f64 = 3.0;

/// The most fields a sweep carries (mass, three momentum components, the level set, one
/// more).
pub const MAX_FIELDS: usize = 6;

/// Per-thread line buffers of the carrying sweeps.
pub type CarryPool = Pool<CarryScratch>;

/// Lines pushed together, interleaved by lane.
const LANES: usize = 8;

/// Periodic ghost nodes on each side of a line's velocity: the interpolation at the mid-step
/// position needs no wrap unless a particle moves more than `GHOST - 3` cells in half a step.
const GHOST: usize = 8;

/// The window a particle that moves less than a cell remeshes into: nodes `p - 2 ..= p + 2`.
const W: usize = 5;

/// Line buffers of a group of [`LANES`] lines, interleaved by lane: the carried fields in and
/// out, the velocity along the lines (with [`GHOST`] periodic ghosts at both ends) and the
/// bodies' level set along them.
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
            fin: vec![vec![0.0; LANES * nmax]; nf],
            fout: vec![vec![0.0; LANES * nmax]; nf],
            u: vec![0.0; LANES * (nmax + 2 * GHOST)],
            solid: vec![0.0; LANES * nmax],
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

/// One group of lines: `count` real lines of `n` nodes whose first nodes are `base`, nodes
/// `stride` apart; with `contiguous`, `base[l] = base[0] + l`.
struct Group {
    n: usize,
    count: usize,
    base: [usize; LANES],
    stride: usize,
    contiguous: bool,
}

/// What a sweep reads besides its scratch.
struct Inputs<'a> {
    u_axis: &'a [f64],
    solid: &'a [f64],
    ptrs: &'a [SyncPtr<f64>],
    cdt: f64,
    ls: usize,
    near_ls: f64,
    near_solid: f64,
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
    // Groups: along x, LANES consecutive rows; across x, up to LANES lines of consecutive i in
    // one row of lines.
    let per_row = nx.div_ceil(LANES);
    let ngroups = if axis == 0 {
        nlines.div_ceil(LANES)
    } else {
        (nlines / nx) * per_row
    };
    let group = |g: usize| {
        let mut base = [0usize; LANES];
        let count = if axis == 0 {
            let first = g * LANES;
            let count = LANES.min(nlines - first);
            for (l, b) in base.iter_mut().enumerate().take(count) {
                *b = (first + l) * nx;
            }
            count
        } else {
            let (r, ib) = (g / per_row, g % per_row);
            let i0 = ib * LANES;
            let b0 = if axis == 1 {
                i0 + nx * ny * r
            } else {
                i0 + nx * r
            };
            for (l, b) in base.iter_mut().enumerate() {
                *b = b0 + l;
            }
            LANES.min(nx - i0)
        };
        Group {
            n,
            count,
            base,
            stride,
            contiguous: axis != 0,
        }
    };
    assert!(
        fields.len() <= MAX_FIELDS,
        "carry_sweep: at most {MAX_FIELDS} fields"
    );
    let mut all = [SyncPtr(std::ptr::null_mut()); MAX_FIELDS];
    for (p, f) in all.iter_mut().zip(fields.iter_mut()) {
        *p = SyncPtr(f.as_mut_ptr());
    }
    let inputs = Inputs {
        u_axis,
        solid,
        ptrs: &all[..fields.len()],
        cdt: dt / grid.h,
        ls: near.field,
        near_ls: near.level_set,
        near_solid: -near.solid,
    };
    #[cfg(target_arch = "x86_64")]
    let avx2 = std::arch::is_x86_feature_detected!("avx2");
    (0..ngroups).into_par_iter().for_each(|g| {
        pool.with(|s| {
            debug_assert!(s.nmax >= n && s.fin.len() >= inputs.ptrs.len());
            let g = group(g);
            #[cfg(target_arch = "x86_64")]
            if avx2 {
                // SAFETY: the CPU supports AVX2 (checked once per sweep). The same arithmetic
                // in the same order (Rust never contracts a*b+c), so the same bits.
                unsafe { group_avx2(s, &g, &inputs) };
                return;
            }
            group_generic(s, &g, &inputs);
        })
    });
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn group_avx2(s: &mut CarryScratch, g: &Group, inp: &Inputs) {
    group_generic(s, g, inp);
}

/// Gather a group, push and remesh its particles, and write it back.
#[inline(always)]
fn group_generic(s: &mut CarryScratch, g: &Group, inp: &Inputs) {
    let (n, count, nf) = (g.n, g.count, inp.ptrs.len());
    let has_solid = !inp.solid.is_empty();
    for p in 0..n {
        let at = g.base[0] + p * g.stride;
        let u = &mut s.u[(GHOST + p) * LANES..(GHOST + p + 1) * LANES];
        let solid = &mut s.solid[p * LANES..(p + 1) * LANES];
        if g.contiguous {
            u[..count].copy_from_slice(&inp.u_axis[at..at + count]);
            if has_solid {
                solid[..count].copy_from_slice(&inp.solid[at..at + count]);
            }
        } else {
            for l in 0..count {
                u[l] = inp.u_axis[g.base[l] + p * g.stride];
                if has_solid {
                    solid[l] = inp.solid[g.base[l] + p * g.stride];
                }
            }
        }
        u[count..].fill(0.0);
        if !has_solid {
            solid.fill(f64::NEG_INFINITY);
        }
        for c in 0..nf {
            let w = &mut s.fin[c][p * LANES..(p + 1) * LANES];
            if g.contiguous {
                // SAFETY: the lines of this group belong to this task only, and with
                // `contiguous` its lanes' nodes are the `count` consecutive ones from here.
                let src = unsafe { std::slice::from_raw_parts(inp.ptrs[c].0.add(at), count) };
                w[..count].copy_from_slice(src);
            } else {
                for l in 0..count {
                    // SAFETY: the lines of this group belong to this task only.
                    w[l] = unsafe { inp.ptrs[c].read(g.base[l] + p * g.stride) };
                }
            }
            w[count..].fill(0.0);
        }
    }
    fill_periodic_ghosts(&mut s.u, n, GHOST, LANES);
    push_remesh(s, n, nf, inp);
    for c in 0..nf {
        let out = &s.fout[c];
        for p in 0..n {
            let row = &out[p * LANES..p * LANES + count];
            if g.contiguous {
                // SAFETY: as in the gather.
                let dst = unsafe {
                    std::slice::from_raw_parts_mut(
                        inp.ptrs[c].0.add(g.base[0] + p * g.stride),
                        count,
                    )
                };
                dst.copy_from_slice(row);
            } else {
                for (l, &v) in row.iter().enumerate() {
                    // SAFETY: the lines of this group belong to this task only.
                    unsafe { inp.ptrs[c].write(g.base[l] + p * g.stride, v) };
                }
            }
        }
    }
}

/// Push and remesh every row of a gathered group: rows whose window lies inside the line take
/// [`window_row`] unless a particle leaves the window; the others [`general_row`].
#[inline(always)]
fn push_remesh(s: &mut CarryScratch, n: usize, nf: usize, inp: &Inputs) {
    for o in s.fout.iter_mut().take(nf) {
        o[..n * LANES].fill(0.0);
    }
    for p in 0..n {
        if (2..n.saturating_sub(2)).contains(&p) && window_row(s, p, nf, inp) {
            continue;
        }
        general_row(s, p, n, nf, inp);
    }
}

/// Whether each lane's particle at row `p` takes the hat kernel.
#[inline(always)]
fn hat_lanes(s: &CarryScratch, p: usize, inp: &Inputs) -> [bool; LANES] {
    let row = p * LANES;
    let ls = &s.fin[inp.ls][row..row + LANES];
    let solid = &s.solid[row..row + LANES];
    std::array::from_fn(|l| ls[l].abs() < inp.near_ls || solid[l] > inp.near_solid)
}

/// The weights at `x` (grid units, one per lane) on the window nodes `p - 2 ..= p + 2`, M'4 or
/// the hat per lane; whether any lane's base node is neither `p - 1` nor `p`.
#[inline(always)]
fn window_weights(
    pf: f64,
    x: &[f64; LANES],
    hat: &[bool; LANES],
    ww: &mut [[f64; LANES]; W],
) -> bool {
    let mut outside = false;
    for l in 0..LANES {
        let b = x[l].floor();
        let f = x[l] - b;
        let w = if hat[l] {
            hat_weights(f)
        } else {
            m4prime_weights(f)
        };
        let shift = b < pf;
        outside |= b < pf - 1.0 || b > pf;
        for k in 0..W {
            let lo = if k < 4 { w[k] } else { 0.0 };
            let hi = if k > 0 { w[k - 1] } else { 0.0 };
            ww[k][l] = if shift { lo } else { hi };
        }
    }
    outside
}

/// Push and remesh row `p` in its window, all lanes at once; false (nothing written) if a
/// particle leaves the window.
#[inline(always)]
fn window_row(s: &mut CarryScratch, p: usize, nf: usize, inp: &Inputs) -> bool {
    let pf = p as f64;
    let u = &s.u;
    let first = p - 2;
    let mut x: [f64; LANES] =
        std::array::from_fn(|l| pf + 0.5 * inp.cdt * u[(GHOST + p) * LANES + l]);
    let mut wm = [[0.0; LANES]; W];
    if window_weights(pf, &x, &[false; LANES], &mut wm) {
        return false;
    }
    // The velocity at the mid-step position (M'4), then the new position.
    let uw = &u[(GHOST + first) * LANES..(GHOST + first + W) * LANES];
    for l in 0..LANES {
        let mut acc = 0.0;
        for k in 0..W {
            acc += wm[k][l] * uw[k * LANES + l];
        }
        x[l] = pf + inp.cdt * acc;
    }
    let hat = hat_lanes(s, p, inp);
    let mut wn = [[0.0; LANES]; W];
    if window_weights(pf, &x, &hat, &mut wn) {
        return false;
    }
    let row = p * LANES;
    for c in 0..nf {
        // A local copy: the compiler cannot tell the scratch lines apart.
        let sv: [f64; LANES] = s.fin[c][row..row + LANES].try_into().unwrap();
        let o = &mut s.fout[c][first * LANES..(first + W) * LANES];
        for (k, o) in o.chunks_exact_mut(LANES).enumerate() {
            for l in 0..LANES {
                o[l] += wn[k][l] * sv[l];
            }
        }
    }
    true
}

/// Push and remesh row `p` lane by lane, for any displacement, wrapping around the periodic
/// line.
#[inline(always)]
fn general_row(s: &mut CarryScratch, p: usize, n: usize, nf: usize, inp: &Inputs) {
    let ni = n as i64;
    let pf = p as f64;
    let row = p * LANES;
    let hat = hat_lanes(s, p, inp);
    for l in 0..LANES {
        let u = &s.u;
        // M'4 interpolation of the line's velocity at `x` (grid units), periodic.
        let interp = |x: f64| {
            let b = x.floor();
            let w = m4prime_weights(x - b);
            let b = b as i64 - 1;
            let mut acc = 0.0;
            for (q, wq) in w.iter().enumerate() {
                let t = (b + q as i64).rem_euclid(ni) as usize;
                acc += wq * u[(GHOST + t) * LANES + l];
            }
            acc
        };
        let x_mid = pf + 0.5 * inp.cdt * u[(GHOST + p) * LANES + l];
        let x_new = pf + inp.cdt * interp(x_mid);
        let b = x_new.floor();
        let f = x_new - b;
        let w = if hat[l] {
            hat_weights(f)
        } else {
            m4prime_weights(f)
        };
        let b = b as i64 - 1;
        for (q, wq) in w.iter().enumerate() {
            let t = (b + q as i64).rem_euclid(ni) as usize;
            for c in 0..nf {
                let v = s.fin[c][row + l];
                s.fout[c][t * LANES + l] += wq * v;
            }
        }
    }
}
