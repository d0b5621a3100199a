//! The advection sweep of the vortex-in-cell transport: particles created at the nodes of every
//! line along one axis, pushed with the midpoint RK2 rule x ← x + Δt u(x + Δt/2 u(x)) (velocity
//! interpolated along the line with the remeshing kernel) and remeshed onto the line (M'4 or
//! Λ4,2; paper eqs. 29-30). One sweep per axis is the dimensional splitting of the transport
//! (`systems/transport.rs` for the vorticity, `systems/free_surface.rs` for the liquid's level
//! set): each 1D remesh is exactly the tensor-product remesh of particles displaced along one
//! axis, so circulation and the first two moments are conserved exactly.
//!
//! A sweep is cut into a fixed number of work units and every line is handled by one of them,
//! so results do not depend on the thread count; each unit works in a [`LineScratch`] owned by
//! the caller ([`LinePool`], one per thread: nothing is allocated in a sweep).

use crate::base::grid::{Grid, SyncPtr, component_ptrs};
use crate::base::kernels::{lambda42_weights, m4prime_weights};
use crate::base::params::RemeshKernel;
use crate::base::pool::Pool;
use rayon::prelude::*;

/// Number of work units a sweep is cut into (fixed, so results never depend on threads; it
/// only sets load balance).
const CHUNKS: usize = 32;

/// Per-thread scratch of the sweeps (see [`LineScratch`]).
pub type LinePool = Pool<LineScratch>;

/// Lines pushed together: a group of `LANES` lines is stored interleaved (node p of lane l at
/// `p * LANES + l`), so the arithmetic of a particle runs on all lanes at once in vector
/// registers, and consecutive writes of the remesh go to different lanes instead of queuing
/// on the same node.
const LANES: usize = 16;

/// Ghost nodes on each side of a line's velocity, so the interpolation at the mid-step position
/// needs no wrap unless a particle moves more than `GHOST - 3` cells in half a step.
const GHOST: usize = 8;

/// Per-chunk scratch of a sweep: a group of `LANES` lines of vorticity in and out, and the
/// velocity with `GHOST` periodic ghost nodes at both ends, all interleaved by lane.
pub struct LineScratch {
    nmax: usize,
    w_in: Vec<Vec<f64>>,
    w_out: Vec<Vec<f64>>,
    u: Vec<f64>,
}

impl LineScratch {
    /// Scratch for lines of up to `nmax` nodes and `nc` vorticity components.
    pub fn new(nmax: usize, nc: usize) -> Self {
        LineScratch {
            nmax,
            w_in: vec![vec![0.0; LANES * nmax]; nc],
            w_out: vec![vec![0.0; LANES * nmax]; nc],
            u: vec![0.0; LANES * (nmax + 2 * GHOST)],
        }
    }
}

/// The order of the axes of a dimensionally split step in `dim` dimensions: x y (z), or in
/// reverse, z y x, alternated from step to step so the splitting is second order over two.
pub fn split_axes(dim: usize, reverse: bool) -> &'static [usize] {
    match (dim, reverse) {
        (2, false) => &[0, 1],
        (2, true) => &[1, 0],
        (_, false) => &[0, 1, 2],
        (_, true) => &[2, 1, 0],
    }
}

#[allow(clippy::too_many_arguments)]
/// One advection sweep along `axis`: push (RK2, kernel-interpolated velocity) and remesh
/// every line of nodes.
pub fn sweep(
    grid: &Grid,
    axis: usize,
    dt: f64,
    omega: &mut [Vec<f64>],
    u_axis: &[f64],
    cutoff: f64,
    kernel: RemeshKernel,
    pool: &LinePool,
) {
    let n = grid.n[axis];
    let [nx, ny, _] = grid.n;
    let nlines = grid.len() / n;
    let nc = omega.len();
    let ptrs = component_ptrs(omega);
    // Groups of lines: along x, LANES consecutive lines (rows j, k); across x, up to LANES
    // lines with consecutive i (and so consecutive memory) in one row.
    let groups_per_row = if axis == 0 { 1 } else { nx.div_ceil(LANES) };
    let ngroups = if axis == 0 {
        nlines.div_ceil(LANES)
    } else {
        (nlines / nx) * groups_per_row
    };
    let stride = match axis {
        0 => 1,
        1 => nx,
        _ => nx * ny,
    };
    let cdt = dt / grid.h;
    let cut2 = cutoff * cutoff;
    let per = ngroups.div_ceil(CHUNKS);
    #[cfg(target_arch = "x86_64")]
    let avx2 = std::arch::is_x86_feature_detected!("avx2");
    // One work unit: the groups of lines `chunk * per ..`.
    let sweep_chunk = |chunk: usize, s: &mut LineScratch| {
        let lo = (chunk * per).min(ngroups);
        let hi = ((chunk + 1) * per).min(ngroups);
        debug_assert!(s.nmax >= n && s.w_in.len() >= nc);
        // The first node of each lane's line, and how many lanes are real lines.
        let bases = |group: usize| {
            let mut base = [0usize; LANES];
            let count = if axis == 0 {
                let first = group * LANES;
                let count = LANES.min(nlines - first);
                for (l, b) in base.iter_mut().enumerate().take(count) {
                    *b = (first + l) * nx;
                }
                count
            } else {
                let (row, ib) = (group / groups_per_row, group % groups_per_row);
                let i0 = ib * LANES;
                let b0 = if axis == 1 {
                    i0 + nx * ny * row
                } else {
                    i0 + nx * row
                };
                for (l, b) in base.iter_mut().enumerate() {
                    *b = b0 + l;
                }
                LANES.min(nx - i0)
            };
            (base, count)
        };
        for group in lo..hi {
            let (base, count) = bases(group);
            // Only the sweeps across x prefetch (see `Group::next`).
            let next = (axis != 0 && group + 1 < hi).then(|| bases(group + 1));
            let group = Group {
                n,
                nc,
                count,
                base: &base,
                stride,
                contiguous: axis != 0,
                next: next.as_ref().map(|(b, c)| (b, *c)),
            };
            #[cfg(target_arch = "x86_64")]
            if avx2 {
                // SAFETY: the CPU supports AVX2 (checked once per sweep). The AVX2 build
                // does the same arithmetic in the same order (no fused multiply-add: Rust
                // never contracts a*b+c), so its results are bit-identical to the portable one.
                unsafe { group_avx2(s, &group, u_axis, &ptrs, cdt, cut2, kernel) };
                continue;
            }
            group_generic::<false>(s, &group, u_axis, &ptrs, cdt, cut2, kernel);
        }
    };
    (0..CHUNKS)
        .into_par_iter()
        .for_each(|chunk| pool.with(|s| sweep_chunk(chunk, s)));
}

/// One group of lines of a sweep: `count` real lines of `n` nodes whose first nodes are
/// `base` and whose nodes are `stride` apart; with `contiguous`, `base[l] = base[0] + l`.
struct Group<'a> {
    n: usize,
    nc: usize,
    count: usize,
    base: &'a [usize; LANES],
    stride: usize,
    contiguous: bool,
    /// In a sweep across x (`contiguous`), the next group's `base` and `count`, whose lines
    /// [`gather`] asks the cache for while it copies this group: their nodes are a row or a
    /// plane apart, which the hardware prefetcher does not follow. (Along x, prefetching the
    /// next group's `LANES` rows measured slower; it is not done.)
    next: Option<(&'a [usize; LANES], usize)>,
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn group_avx2(
    s: &mut LineScratch,
    g: &Group,
    u_axis: &[f64],
    ptrs: &[SyncPtr<f64>; 3],
    cdt: f64,
    cut2: f64,
    kernel: RemeshKernel,
) {
    group_generic::<true>(s, g, u_axis, ptrs, cdt, cut2, kernel);
}

/// Gather a group, push and remesh its particles, and write it back.
#[inline(always)]
fn group_generic<const AVX2: bool>(
    s: &mut LineScratch,
    g: &Group,
    u_axis: &[f64],
    ptrs: &[SyncPtr<f64>; 3],
    cdt: f64,
    cut2: f64,
    kernel: RemeshKernel,
) {
    let (n, nc) = (g.n, g.nc);
    gather(s, g, u_axis, ptrs);
    match (kernel, nc) {
        (RemeshKernel::M4Prime, 1) => {
            push_remesh_group::<4, 5, 1, 1, AVX2>(s, n, cdt, cut2, m4prime_weights)
        }
        (RemeshKernel::M4Prime, _) => {
            push_remesh_group::<4, 5, 1, 3, AVX2>(s, n, cdt, cut2, m4prime_weights)
        }
        (RemeshKernel::Lambda42, 1) => {
            push_remesh_group::<6, 7, 2, 1, AVX2>(s, n, cdt, cut2, lambda42_weights)
        }
        (RemeshKernel::Lambda42, _) => {
            push_remesh_group::<6, 7, 2, 3, AVX2>(s, n, cdt, cut2, lambda42_weights)
        }
    }
    for c in 0..nc {
        let out = &s.w_out[c];
        for p in 0..n {
            let row = &out[p * LANES..p * LANES + g.count];
            if g.contiguous {
                // SAFETY: the lines of this group belong to this task only, and with
                // `contiguous` its lanes' nodes are the `count` consecutive ones from here.
                let dst = unsafe {
                    std::slice::from_raw_parts_mut(ptrs[c].0.add(g.base[0] + p * g.stride), g.count)
                };
                if g.count == LANES {
                    dst.copy_from_slice(&out[p * LANES..(p + 1) * LANES]);
                } else {
                    dst.copy_from_slice(row);
                }
            } else {
                for (l, &v) in row.iter().enumerate() {
                    // SAFETY: the lines of this group belong to this task only.
                    unsafe { ptrs[c].write(g.base[l] + p * g.stride, v) };
                }
            }
        }
    }
}

/// Ask the cache for node `p` of the `ncount` consecutive lines starting at `nb[0]` (the next
/// group of a sweep across x): the velocity and vorticity there. A hint only: it changes no
/// value.
#[inline(always)]
fn prefetch_row(
    g: &Group,
    nb: &[usize; LANES],
    ncount: usize,
    p: usize,
    u_axis: &[f64],
    ptrs: &[SyncPtr<f64>; 3],
) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        let fetch = |at: usize| {
            // A prefetch never faults, but keep the address inside the arrays anyway.
            if at < u_axis.len() {
                // SAFETY: prefetching reads nothing observable; the addresses are in bounds.
                unsafe {
                    _mm_prefetch::<_MM_HINT_T0>(u_axis.as_ptr().add(at).cast());
                    for c in ptrs.iter().take(g.nc) {
                        _mm_prefetch::<_MM_HINT_T0>(c.0.add(at).cast::<i8>().cast_const());
                    }
                }
            }
        };
        debug_assert!(g.contiguous);
        let at = nb[0] + p * g.stride;
        fetch(at);
        fetch(at + 8);
        fetch(at + ncount - 1);
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (g, nb, ncount, p, u_axis, ptrs);
}

/// Copy a group's lines into the interleaved scratch (lanes past `count` are zero: no
/// vorticity, so they create no particle) and fill the velocity's periodic ghost nodes.
#[inline(always)]
fn gather(s: &mut LineScratch, g: &Group, u_axis: &[f64], ptrs: &[SyncPtr<f64>; 3]) {
    let (n, count) = (g.n, g.count);
    for p in 0..n {
        if let Some((nb, ncount)) = g.next {
            prefetch_row(g, nb, ncount, p, u_axis, ptrs);
        }
        let at = g.base[0] + p * g.stride;
        let u = &mut s.u[(GHOST + p) * LANES..(GHOST + p + 1) * LANES];
        if g.contiguous && count == LANES {
            // Fixed length: an inline vector copy rather than a call to memcpy.
            u.copy_from_slice(&u_axis[at..at + LANES]);
        } else if g.contiguous {
            u[..count].copy_from_slice(&u_axis[at..at + count]);
        } else {
            for l in 0..count {
                u[l] = u_axis[g.base[l] + p * g.stride];
            }
        }
        u[count..].fill(0.0);
        for c in 0..g.nc {
            let w = &mut s.w_in[c][p * LANES..(p + 1) * LANES];
            if g.contiguous {
                // SAFETY: the lines of this group belong to this task only, and with
                // `contiguous` its lanes' nodes are the `count` consecutive ones from here.
                let src = unsafe { std::slice::from_raw_parts(ptrs[c].0.add(at), count) };
                if count == LANES {
                    w.copy_from_slice(src);
                } else {
                    w[..count].copy_from_slice(src);
                }
            } else {
                for l in 0..count {
                    // SAFETY: the lines of this group belong to this task only.
                    w[l] = unsafe { ptrs[c].read(g.base[l] + p * g.stride) };
                }
            }
            w[count..].fill(0.0);
        }
    }
    fill_periodic_ghosts(&mut s.u, n, GHOST, LANES);
}

/// Fill the `ghost` periodic ghost nodes at both ends of a velocity line of `n` nodes stored
/// from node `-ghost`, interleaved by `lanes` lanes: left ghost k is node k - ghost, right
/// ghost k node n + k (both wrapped).
#[inline(always)]
pub(crate) fn fill_periodic_ghosts(u: &mut [f64], n: usize, ghost: usize, lanes: usize) {
    let ni = n as i64;
    for k in 0..ghost {
        let left = (k as i64 - ghost as i64).rem_euclid(ni) as usize;
        let right = (ni + k as i64).rem_euclid(ni) as usize;
        u.copy_within(
            (ghost + left) * lanes..(ghost + left + 1) * lanes,
            k * lanes,
        );
        u.copy_within(
            (ghost + right) * lanes..(ghost + right + 1) * lanes,
            (ghost + n + k) * lanes,
        );
    }
}

/// Push the particles of a group of `LANES` periodic lines (interleaved in `s`) and remesh
/// them with an `N`-point kernel whose first node is `LEFT` nodes left of the particle's base
/// node. Every lane does the arithmetic of the one-line algorithm in the same order, so a
/// node's value does not depend on which lines share its group.
///
/// A particle that moves less than a cell (the usual case: the time step keeps the CFL number
/// below one) lands with its `N` weights inside the `W = N + 1` nodes from `p - LEFT - 1`, at
/// one of two offsets; [`window_row`] does the whole row of lanes at once in that window,
/// branch-free. A row with a particle beyond it, or whose window wraps around the line's ends,
/// takes [`general_row`]. Both add the same products to each node in the same order (the
/// window's extra terms are exact zeros), so the result does not depend on the path.
#[inline(always)]
fn push_remesh_group<
    const N: usize,
    const W: usize,
    const LEFT: i64,
    const NC: usize,
    const AVX2: bool,
>(
    s: &mut LineScratch,
    n: usize,
    cdt: f64,
    cut2: f64,
    weights: impl Fn(f64) -> [f64; N],
) {
    debug_assert_eq!(W, N + 1);
    let u = &s.u[..(n + 2 * GHOST) * LANES];
    let w_in: [&[f64]; NC] = std::array::from_fn(|c| &s.w_in[c][..n * LANES]);
    let (o0, rest) = s.w_out.split_at_mut(1);
    let (o1, o2) = rest.split_at_mut(1.min(rest.len()));
    let mut outs: [&mut [f64]; 3] = [
        &mut o0[0][..n * LANES],
        o1.first_mut().map_or(&mut [][..], |v| &mut v[..n * LANES]),
        o2.first_mut().map_or(&mut [][..], |v| &mut v[..n * LANES]),
    ];
    for o in outs.iter_mut().take(NC) {
        o.fill(0.0);
    }
    // Rows whose window (nodes p - LEFT - 1 ..= p + N - LEFT - 1) lies inside the line.
    let first_fast = LEFT as usize + 1;
    let end_fast = (n + LEFT as usize + 1).saturating_sub(N);
    for p in 0..n {
        if (first_fast..end_fast).contains(&p)
            && window_row::<N, W, LEFT, NC, AVX2>(p, u, &w_in, &mut outs, cdt, cut2, &weights)
        {
            continue;
        }
        general_row::<N, LEFT, NC>(p, n, u, &w_in, &mut outs, cdt, cut2, &weights);
    }
}

/// The weights of particles at `x` (grid units, one per lane) on the `W` window nodes from
/// `p - LEFT - 1`: a particle whose base node is `p - 1` puts its `N` weights on window nodes
/// `0..N`, one whose base node is `p` on `1..=N`. Also whether a lane's base node is neither
/// (such a particle needs [`general_row`]).
#[inline(always)]
fn window_weights<const N: usize, const W: usize>(
    pf: f64,
    x: &[f64; LANES],
    weights: &impl Fn(f64) -> [f64; N],
    ww: &mut [[f64; LANES]; W],
    outside: &mut [bool; LANES],
) {
    for l in 0..LANES {
        let b = x[l].floor();
        let w = weights(x[l] - b);
        let shift = b < pf;
        outside[l] = b < pf - 1.0 || b > pf;
        for k in 0..W {
            let lo = if k < N { w[k] } else { 0.0 };
            let hi = if k > 0 { w[k - 1] } else { 0.0 };
            ww[k][l] = if shift { lo } else { hi };
        }
    }
}

/// Push and remesh row `p` of a group in the window of [`window_weights`], all lanes at once;
/// false (and nothing written) if a particle leaves the window.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn window_row<
    const N: usize,
    const W: usize,
    const LEFT: i64,
    const NC: usize,
    const AVX2: bool,
>(
    p: usize,
    u: &[f64],
    w_in: &[&[f64]; NC],
    outs: &mut [&mut [f64]; 3],
    cdt: f64,
    cut2: f64,
    weights: &impl Fn(f64) -> [f64; N],
) -> bool {
    let pf = p as f64;
    let row = p * LANES;
    let first = p - LEFT as usize - 1;
    // |ω|² per lane (kept as numbers: compared where needed, the comparisons stay vector
    // masks).
    let mut m2 = [0.0; LANES];
    let mut x = [0.0; LANES];
    for l in 0..LANES {
        for w in w_in {
            m2[l] += w[row + l] * w[row + l];
        }
        x[l] = pf + 0.5 * cdt * u[(GHOST + p) * LANES + l];
    }
    let mut wm = [[0.0; LANES]; W];
    let mut out_mid = [false; LANES];
    window_weights::<N, W>(pf, &x, weights, &mut wm, &mut out_mid);
    // The velocity at the mid-step position, then the new position.
    let uw = &u[(GHOST + first) * LANES..(GHOST + first + W) * LANES];
    for l in 0..LANES {
        let mut acc = 0.0;
        for k in 0..W {
            acc += wm[k][l] * uw[k * LANES + l];
        }
        x[l] = pf + cdt * acc;
    }
    let mut wn = [[0.0; LANES]; W];
    let mut out_new = [false; LANES];
    window_weights::<N, W>(pf, &x, weights, &mut wn, &mut out_new);
    let mut outside = false;
    for l in 0..LANES {
        outside |= (m2[l] > cut2) & (out_mid[l] | out_new[l]);
    }
    if outside {
        return false;
    }
    for c in 0..NC {
        // A local copy: the compiler cannot tell the scratch lines apart, and would not
        // vectorise a loop whose loads might alias its stores.
        let sv: [f64; LANES] = w_in[c][row..row + LANES].try_into().unwrap();
        let o = &mut outs[c][first * LANES..(first + W) * LANES];
        for (k, o) in o.chunks_exact_mut(LANES).enumerate() {
            // Below the cutoff a node keeps its value: weight 1 on itself (window node
            // LEFT + 1) instead of the particle's weights.
            let keep = if k == LEFT as usize + 1 { 1.0 } else { 0.0 };
            add_product::<AVX2>(o.try_into().unwrap(), &wn[k], keep, &m2, cut2, &sv);
        }
    }
    true
}

/// o += w s lane by lane, with w replaced by `keep` in lanes whose `m2` is at or below
/// `cut2`. With `AVX2` (set only under [`group_avx2`], which checked the CPU) in 256-bit
/// registers: inlined into the whole sweep, the compiler leaves this loop scalar. The same
/// products and sums either way, so the same bits.
#[inline(always)]
fn add_product<const AVX2: bool>(
    o: &mut [f64; LANES],
    w: &[f64; LANES],
    keep: f64,
    m2: &[f64; LANES],
    cut2: f64,
    s: &[f64; LANES],
) {
    #[cfg(target_arch = "x86_64")]
    if AVX2 {
        // SAFETY: AVX2 is only set under `group_avx2`, which checked the CPU.
        unsafe { add_product_avx2(o, w, keep, m2, cut2, s) };
        return;
    }
    for l in 0..LANES {
        let w = if m2[l] > cut2 { w[l] } else { keep };
        o[l] += w * s[l];
    }
}

/// [`add_product`] in AVX2 registers. A function of its own with the feature enabled, so that
/// the intrinsics are inlined into it (and it into the AVX2 sweep), not called.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn add_product_avx2(
    o: &mut [f64; LANES],
    w: &[f64; LANES],
    keep: f64,
    m2: &[f64; LANES],
    cut2: f64,
    s: &[f64; LANES],
) {
    use std::arch::x86_64::*;
    let keep = _mm256_set1_pd(keep);
    let cut2 = _mm256_set1_pd(cut2);
    for q in (0..LANES).step_by(4) {
        // SAFETY: the arrays hold LANES values, so q..q + 4 is in bounds.
        unsafe {
            let active = _mm256_cmp_pd::<_CMP_GT_OQ>(_mm256_loadu_pd(m2.as_ptr().add(q)), cut2);
            let w = _mm256_blendv_pd(keep, _mm256_loadu_pd(w.as_ptr().add(q)), active);
            let p = _mm256_mul_pd(w, _mm256_loadu_pd(s.as_ptr().add(q)));
            let r = _mm256_add_pd(_mm256_loadu_pd(o.as_ptr().add(q)), p);
            _mm256_storeu_pd(o.as_mut_ptr().add(q), r);
        }
    }
}

/// Push and remesh row `p` of a group lane by lane, for any displacement, wrapping around the
/// periodic line.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn general_row<const N: usize, const LEFT: i64, const NC: usize>(
    p: usize,
    n: usize,
    u: &[f64],
    w_in: &[&[f64]; NC],
    outs: &mut [&mut [f64]; 3],
    cdt: f64,
    cut2: f64,
    weights: &impl Fn(f64) -> [f64; N],
) {
    let ni = n as i64;
    let right = N as i64 - LEFT;
    // The velocity line with its ghosts spans node indices -GHOST .. n + GHOST.
    let lo = LEFT - GHOST as i64;
    let hi = ni + GHOST as i64 - right;
    let pf = p as f64;
    let row = p * LANES;
    // Lane-wise (vectorised): which lanes hold a particle, and the kernel weights at
    // the mid-step position x_mid = p + Δt/2 u(p) (grid units).
    let mut active = [false; LANES];
    let mut wm = [[0.0; N]; LANES];
    let mut bm = [0i64; LANES];
    for l in 0..LANES {
        let mut m2 = 0.0;
        for w in w_in {
            m2 += w[row + l] * w[row + l];
        }
        active[l] = m2 > cut2;
        let x_mid = pf + 0.5 * cdt * u[(GHOST + p) * LANES + l];
        let b = x_mid.floor();
        wm[l] = weights(x_mid - b);
        bm[l] = b as i64;
    }
    // The velocity at x_mid, then x_new = p + Δt u(x_mid).
    let mut wn = [[0.0; N]; LANES];
    let mut bn = [0i64; LANES];
    for l in 0..LANES {
        let b = bm[l];
        let w = &wm[l];
        let mut acc = 0.0;
        if b >= lo && b <= hi {
            let s0 = (b - LEFT + GHOST as i64) as usize;
            for q in 0..N {
                acc += w[q] * u[(s0 + q) * LANES + l];
            }
        } else {
            for q in 0..N {
                let t = (b - LEFT + q as i64).rem_euclid(ni) as usize;
                acc += w[q] * u[(GHOST + t) * LANES + l];
            }
        }
        let x_new = pf + cdt * acc;
        let b = x_new.floor();
        wn[l] = weights(x_new - b);
        bn[l] = b as i64;
    }
    // Remesh: a particle adds its strength times the weights to the N nodes around
    // x_new; below the cutoff the node keeps its value.
    for l in 0..LANES {
        if !active[l] {
            for c in 0..NC {
                outs[c][row + l] += w_in[c][row + l];
            }
            continue;
        }
        let b = bn[l];
        let w = &wn[l];
        if b >= LEFT && b + right <= ni {
            let s0 = (b - LEFT) as usize;
            for c in 0..NC {
                let sv = w_in[c][row + l];
                let o = &mut outs[c][s0 * LANES + l..];
                for q in 0..N {
                    o[q * LANES] += w[q] * sv;
                }
            }
        } else {
            for q in 0..N {
                let t = (b - LEFT + q as i64).rem_euclid(ni) as usize;
                for c in 0..NC {
                    outs[c][t * LANES + l] += w[q] * w_in[c][row + l];
                }
            }
        }
    }
}
