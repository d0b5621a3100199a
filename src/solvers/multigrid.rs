//! A geometric multigrid V-cycle for A = -h²∇·(β∇) on the periodic grid, as the preconditioner
//! of a conjugate-gradient solve when β varies by orders of magnitude (a free surface at 1:1000,
//! bodies far denser or lighter than the fluid), where the constant-coefficient FFT inverse
//! loses its grip: its iterations grow with the contrast, the V-cycle's hardly do.
//!
//! - Levels: each axis is coarsened by 2 when its node count is even, by 3 when it is an odd
//!   multiple of 3, and otherwise by 2 with the axis' last aggregate three nodes wide (so a
//!   node count with a large prime factor, 71 or 2·13, coarsens as well as a power of two),
//!   while the coarse spacing along it stays within twice the finest spacing of the level,
//!   until the level has at most [`COARSEST`] nodes.
//! - Transfer: piecewise constant. A coarse node is the aggregate of the fine nodes of its
//!   block (`f₀ f₁ f₂` of them, or a wider last aggregate); restriction sums them,
//!   prolongation copies the coarse value to each.
//! - Coarse operator: the face coefficient between two coarse nodes along axis a is the sum of
//!   the fine coefficients crossing that coarse face, divided by the distance between the two
//!   aggregates' centres in fine spacings (f_a between uniform aggregates). The Galerkin
//!   product PᵀAP with piecewise-constant P sums them; its energy of a smooth field is that
//!   distance times too large (the aggregate's jumps), which the division removes. For β = 1
//!   this is the coarse finite-volume Laplacian, and across a density jump it keeps the fine
//!   faces' harmonic weighting (Basilisk's multigrid restricts its face coefficients the same
//!   way).
//! - Smoother: red-black Gauss-Seidel, red then black before the coarse correction and black
//!   then red after it, so the cycle is a symmetric operator; on a level with an odd node count
//!   (where red-black colouring breaks at the periodic wrap) damped Jacobi instead. On the
//!   coarsest level a fixed number of symmetric (forward then backward) Gauss-Seidel sweeps.
//!
//! The cycle is a fixed linear, symmetric and positive operator (`tests/suite/multigrid.rs`
//! checks both on every kind of coarsening), so it preconditions CG. Every update of a node
//! reads only nodes of the other colour (or the last sweep's values), and the coarsest sweeps
//! run in one thread: the result does not depend on the thread count.
//!
//! On several processes ([`Multigrid::split`]) each holds its slab of z-planes of r and z, and
//! the cycle gives the bits of the one-process cycle on the whole grid, so that a run is
//! bit-identical on any number of processes:
//!
//! - Distributed levels: a level stays split while it is not the coarsest, every process holds
//!   two planes or more of it and every slab starts on an aggregate of its coarsening along z
//!   (never inside one, nor inside the wider last one). Then the restriction of a process's
//!   planes gives whole planes of the next level, which it holds in turn; the coarse
//!   coefficients are coarsened from the process's own fine nodes. The smoother, the residual
//!   and the inverse diagonal read one ghost plane of the iterate a side and the z-face
//!   coefficients of the plane below, exchanged with the neighbours before each red-black
//!   colour pass (the colour taken from the whole grid's plane index), each Jacobi sweep and
//!   the restriction. Every node is computed from the same values with the same terms in the
//!   same order as on the whole grid: a colour pass reads only the other colour, which is what
//!   the one-process sweep (both colours fused in one pass through memory) computes too.
//! - Gathered levels: from the first level that cannot stay split every process gathers that
//!   level's right-hand side (and, once, its coefficients) in rank order
//!   ([`crate::parallel::Comm::all_gather_varcount`]), runs the rest of the cycle whole with
//!   the one-process code, and takes its planes of the correction. Coarse levels are small,
//!   so the redundant work is cheap, and the coarsest level's sequential sweeps need the
//!   whole level anyway. Slabs that start inside an aggregate of the finest coarsening (odd
//!   plane counts on uneven slabs) gather the finest level: the result is the same, the work
//!   that of one process.

use crate::base::grid::{Grid, RowNeighbours, SyncPtr, periodic_neighbours};
use crate::parallel::{Decomposition, Gather, Slabs};
use rayon::prelude::*;

/// A level with at most this many nodes is the coarsest.
pub const COARSEST: usize = 512;
/// Symmetric Gauss-Seidel sweeps (forward and backward) on the coarsest level.
pub const COARSEST_SWEEPS: usize = 20;
/// The most nodes a coarsest level may have for the hierarchy to be worth using: the coarsest
/// level's sweeps (one thread) neither converge nor stay cheap on a large grid. Every axis of
/// two or more nodes coarsens, so only a grid whose smallest spacing lies along an axis of one
/// node (a 3D grid one node thick) can stop above it.
pub const MAX_COARSEST: usize = 4096;
/// Weight of the damped Jacobi smoother.
const JACOBI_WEIGHT: f64 = 0.8;
/// Smoothing sweeps before and after the coarse correction (each red-black sweep is one
/// Gauss-Seidel pass over both colours; each Jacobi sweep one pass).
const SWEEPS: usize = 2;
const JACOBI_SWEEPS: usize = 4;

/// Per node: the coefficients of its faces toward +x, +y, +z (in 2D the third is 0) and the
/// inverse of the sum of its six (four) face coefficients, side by side so that a node's update
/// reads one cache line. (In single precision the tank of 100 bodies under a free surface took
/// 14 iterations instead of 7.)
type Weights = [f64; 4];

/// One level of the hierarchy: its grid, operator and scratch, and the next coarser level's
/// right-hand side and correction (empty on the coarsest level).
#[derive(Debug, Clone)]
struct Level {
    /// The level's grid: whole, or on a distributed level this process's slab of it.
    grid: Grid,
    /// Coarsening factors to the next level, per axis.
    f: [usize; 3],
    w: Vec<Weights>,
    /// Damped Jacobi's scratch (levels without red-black colouring; empty otherwise).
    tmp: Vec<f64>,
    red_black: bool,
    /// The next level's first plane that `coarse_x` and `coarse_b` start at (0 unless this
    /// level is distributed).
    coarse_k0: usize,
    coarse_x: Vec<f64>,
    coarse_b: Vec<f64>,
    /// On a distributed level: the ghost planes (empty on a whole level).
    ghosts: Ghosts,
}

/// A distributed level's ghost planes: of the iterate, the plane below the slab then the plane
/// above; of the z-face coefficients (`w[.][2]`), the plane below (then the plane above,
/// unused), and the slab's first and last planes of them to send.
#[derive(Debug, Clone, Default)]
struct Ghosts {
    x: Vec<f64>,
    wz: Vec<f64>,
    send: Vec<f64>,
}

/// The hierarchy on several processes: the levels `..whole` are distributed (each process holds
/// its planes), the levels from `whole` on are held whole by every process.
#[derive(Debug, Clone)]
struct Split {
    d: Decomposition,
    /// The first level held whole (gathered).
    whole: usize,
    /// The gather of level `whole` from the processes' planes of it: of values (one per node)
    /// and of weights (four per node).
    gather: Gather,
    gather4: Gather,
    /// This process's nodes of level `whole`.
    mine: std::ops::Range<usize>,
    /// Level `whole`'s right-hand side and correction, whole.
    b: Vec<f64>,
    x: Vec<f64>,
    /// This process's planes of level `whole`'s weights (coarsened from the last distributed
    /// level, then gathered; unused when level 0 is gathered).
    w_mine: Vec<Weights>,
}

/// The multigrid hierarchy of one grid: the levels' operators and scratch, allocated once.
#[derive(Debug, Clone)]
pub struct Multigrid {
    levels: Vec<Level>,
    /// On several processes, how the levels are split.
    split: Option<Split>,
}

/// Factors by which to coarsen each axis of a level with `n` nodes (1 = not coarsened): 3 if
/// the count is an odd multiple of 3, else 2 (the last aggregate three wide when the count is
/// odd), only where the axis' spacing `s` (in fine spacings) is less than twice the smallest
/// spacing of the level. The coarse level has `n / f` nodes (rounded down) along each axis.
fn factors(n: [usize; 3], s: [usize; 3], dim: usize) -> [usize; 3] {
    let smin = (0..dim).map(|a| s[a]).min().unwrap_or(1);
    std::array::from_fn(|a| {
        if a >= dim || s[a] >= 2 * smin || n[a] < 2 {
            1
        } else if !n[a].is_multiple_of(2) && n[a].is_multiple_of(3) {
            3
        } else {
            2
        }
    })
}

/// The fine nodes `[start, end)` of aggregate `c` along an axis of `n` fine nodes coarsened by
/// `f` to `n / f` aggregates: `f` wide, the last one taking the remainder.
#[inline(always)]
fn block(c: usize, f: usize, n: usize) -> (usize, usize) {
    let last = n / f - 1;
    (c * f, if c == last { n } else { (c + 1) * f })
}

/// The aggregate of fine node `i` along an axis of `n` fine nodes coarsened by `f`.
#[inline(always)]
fn aggregate(i: usize, f: usize, n: usize) -> usize {
    (i / f).min(n / f - 1)
}

/// The node counts of the levels of `grid`'s hierarchy, finest first, with each level's
/// coarsening factors to the next (`[1, 1, 1]` on the coarsest); nothing is allocated per node.
pub fn plan(grid: &Grid) -> Vec<([usize; 3], [usize; 3])> {
    let dim = grid.dim;
    let mut n = grid.n;
    let mut s = [1usize; 3];
    let mut out = Vec::new();
    loop {
        let f = if n.iter().product::<usize>() <= COARSEST {
            [1; 3]
        } else {
            factors(n, s, dim)
        };
        out.push((n, f));
        if f == [1; 3] {
            return out;
        }
        for a in 0..3 {
            s[a] *= f[a];
            n[a] /= f[a];
        }
    }
}

/// Whether `grid`'s coarsening reaches a level of at most [`MAX_COARSEST`] nodes (otherwise
/// the FFT preconditioner is the better choice at any contrast).
pub fn coarsens_fully(grid: &Grid) -> bool {
    plan(grid)
        .last()
        .is_some_and(|(n, _)| n.iter().product::<usize>() <= MAX_COARSEST)
}

/// A level of `n` nodes (whole) coarsened by `f`: its own nodes `planes` along z (all of them
/// when whole), the next level's `coarse` planes.
fn level(
    n: [usize; 3],
    f: [usize; 3],
    h: f64,
    planes: Option<std::ops::Range<usize>>,
    coarse: std::ops::Range<usize>,
) -> Level {
    let whole = Grid::new(n, h, [0.0; 3]);
    let dim = whole.dim;
    let distributed = planes.is_some();
    let grid = match planes {
        Some(p) => whole.slab(p),
        None => whole,
    };
    let len = grid.len();
    let coarsens = f != [1; 3];
    let red_black = (0..dim).all(|a| n[a].is_multiple_of(2));
    let clen = if coarsens {
        (n[0] / f[0]) * (n[1] / f[1]) * coarse.len()
    } else {
        0
    };
    let plane = grid.plane();
    let ghost = |planes: usize| vec![0.0; if distributed { planes * plane } else { 0 }];
    Level {
        grid,
        f,
        w: vec![[0.0; 4]; len],
        tmp: vec![0.0; if red_black || !coarsens { 0 } else { len }],
        red_black,
        coarse_k0: coarse.start,
        coarse_x: vec![0.0; clen],
        coarse_b: vec![0.0; clen],
        ghosts: Ghosts {
            x: ghost(2),
            wz: ghost(2),
            send: ghost(2),
        },
    }
}

/// The first plane of every rank's slab, then the plane count, of the levels of `plan` split
/// as `slabs` splits the finest: one entry per distributed level and one for the first level
/// held whole. A level is distributed while it is not the coarsest, every slab holds two planes
/// or more, and every slab starts on an aggregate of the coarsening along z (not inside the
/// wider last one): its restriction then gives each rank whole planes of the next level.
fn split_bounds(plan: &[([usize; 3], [usize; 3])], slabs: &Slabs) -> Vec<Vec<usize>> {
    let ranks = slabs.ranks;
    let mut bounds: Vec<usize> = (0..ranks)
        .map(|r| slabs.planes(r).start)
        .chain([slabs.n[2]])
        .collect();
    let mut out = Vec::new();
    for &(n, f) in plan {
        let nc = n[2] / f[2];
        let thick = bounds.windows(2).all(|b| b[1] >= b[0] + 2);
        let aligned = bounds[1..ranks]
            .iter()
            .all(|&a| a.is_multiple_of(f[2]) && a / f[2] < nc);
        let coarse: Vec<usize> = bounds
            .iter()
            .map(|&a| if a == n[2] { nc } else { a / f[2] })
            .collect();
        out.push(std::mem::replace(&mut bounds, coarse));
        if f == [1; 3] || !thick || !aligned {
            break;
        }
    }
    out
}

/// How many of the finest levels of the hierarchy of a grid of `n` nodes split over `ranks`
/// processes are distributed ([`Multigrid::split`]); the others are held whole by every
/// process.
pub fn distributed_levels(n: [usize; 3], ranks: usize) -> usize {
    let grid = Grid::new(n, 1.0, [0.0; 3]);
    split_bounds(&plan(&grid), &Slabs { n, ranks, rank: 0 }).len() - 1
}

impl Multigrid {
    /// The hierarchy of `grid` (operators zero until [`Multigrid::set_coefficients`]).
    pub fn new(grid: &Grid) -> Self {
        let levels = plan(grid)
            .into_iter()
            .map(|(n, f)| level(n, f, grid.h, None, 0..n[2] / f[2]))
            .collect();
        Multigrid {
            levels,
            split: None,
        }
    }

    /// The hierarchy of the whole grid `grid` is a slab of, this process holding its planes of
    /// every vector ([`Decomposition`]): [`Multigrid::apply`] gives the bits
    /// [`Multigrid::new`]'s gives on the whole grid, on this process's planes. The levels are
    /// distributed while every process's slab starts on an aggregate of the coarsening along z
    /// and holds two planes or more; from the first level where that fails (at the latest the
    /// coarsest) every process holds the rest of the hierarchy whole. Every process calls it,
    /// and every method after it, together.
    pub fn split(grid: &Grid, d: &Decomposition) -> Self {
        let whole = grid.whole();
        assert!(
            grid.dim == 3 && d.slabs.n == whole.n && d.slabs.my_planes().start == grid.k0,
            "multigrid: the grid is not this process's slab of the decomposition"
        );
        let plan = plan(&whole);
        let rank = d.slabs.rank;
        let bounds = split_bounds(&plan, &d.slabs);
        let split_at = bounds.len() - 1;
        let mut levels = Vec::with_capacity(plan.len());
        for (l, &(n, f)) in plan[..split_at].iter().enumerate() {
            levels.push(level(
                n,
                f,
                grid.h,
                Some(bounds[l][rank]..bounds[l][rank + 1]),
                bounds[l + 1][rank]..bounds[l + 1][rank + 1],
            ));
        }
        for &(n, f) in &plan[split_at..] {
            levels.push(level(n, f, grid.h, None, 0..n[2] / f[2]));
        }
        let (n, bounds) = (plan[split_at].0, &bounds[split_at]);
        let plane = n[0] * n[1];
        let mine = plane * bounds[rank]..plane * bounds[rank + 1];
        let len: usize = n.iter().product();
        Multigrid {
            levels,
            split: Some(Split {
                d: d.clone(),
                whole: split_at,
                gather: Gather::of_planes(d, plane, bounds),
                gather4: Gather::of_planes(d, 4 * plane, bounds),
                w_mine: vec![[0.0; 4]; mine.len()],
                mine,
                b: vec![0.0; len],
                x: vec![0.0; len],
            }),
        }
    }

    /// Node counts of the levels (of the whole grid), finest first.
    pub fn level_sizes(&self) -> Vec<[usize; 3]> {
        self.levels
            .iter()
            .map(|l| [l.grid.n[0], l.grid.n[1], l.grid.nz_whole])
            .collect()
    }

    /// How many of the finest levels are distributed over the processes (0 on one grid, or
    /// when every process holds the whole hierarchy).
    pub fn distributed_levels(&self) -> usize {
        self.split.as_ref().map_or(0, |s| s.whole)
    }

    /// Builds the levels' operators from the fine face coefficients `beta` (β on the face
    /// between node i and i + e_a, stored at i, per axis: the stencil weights of A; this
    /// process's planes of them when split).
    pub fn set_coefficients(&mut self, beta: &[Vec<f64>]) {
        let first_whole = self.split.as_ref().map_or(0, |s| s.whole);
        if let Some(sp) = self.split.as_mut()
            && sp.whole == 0
        {
            // Level 0 is held whole: gather β.
            let l0 = &mut self.levels[0];
            for (a, b) in beta.iter().enumerate() {
                sp.gather.whole(b, &mut sp.x);
                l0.w.par_iter_mut()
                    .zip(sp.x.par_iter())
                    .for_each(|(o, v)| o[a] = *v);
            }
        } else {
            let l0 = &mut self.levels[0];
            let nx = l0.grid.n[0];
            l0.w.par_chunks_mut(nx).enumerate().for_each(|(row, o)| {
                for (i, o) in o.iter_mut().enumerate() {
                    let c = row * nx + i;
                    for (a, b) in beta.iter().enumerate() {
                        o[a] = b[c];
                    }
                }
            });
        }
        for l in 0..self.levels.len() {
            if l > 0 {
                let (before, after) = self.levels.split_at_mut(l);
                let (fine, lv) = (&before[l - 1], &mut after[0]);
                match self.split.as_mut() {
                    Some(sp) if l == sp.whole => {
                        // The last distributed level's coarsening gives this process's planes
                        // of the first whole level: gather them.
                        coarsen(fine, &mut sp.w_mine);
                        sp.gather4
                            .whole(sp.w_mine.as_flattened(), lv.w.as_flattened_mut());
                    }
                    _ => coarsen(fine, &mut lv.w),
                }
            }
            match self.split.as_ref() {
                Some(sp) if l < first_whole => {
                    let lv = &mut self.levels[l];
                    fill_wz(lv, &sp.d);
                    split_inverse_diagonal(lv);
                }
                _ => inverse_diagonal(&mut self.levels[l]),
            }
        }
    }

    /// z = M r: one V-cycle from z = 0 (with the coefficients of the last
    /// [`Multigrid::set_coefficients`]; this process's planes of r and z when split).
    pub fn apply(&mut self, r: &[f64], z: &mut [f64]) {
        match self.split.as_mut() {
            None => cycle(&mut self.levels, z, r),
            Some(sp) if sp.whole == 0 => {
                sp.gather.whole(r, &mut sp.b);
                cycle(&mut self.levels, &mut sp.x, &sp.b);
                z.copy_from_slice(&sp.x[sp.mine.clone()]);
            }
            Some(sp) => {
                let dist = sp.whole;
                split_cycle(&mut self.levels, dist, sp, z, r);
            }
        }
    }
}

/// Fills the fourth weight of every node: 1 / (the sum of its face coefficients), 0 where
/// they are all zero.
fn inverse_diagonal(lv: &mut Level) {
    let g = lv.grid.clone();
    let nx = g.n[0];
    let dim = g.dim;
    // The weights as one array, four per node.
    let wp = SyncPtr(lv.w.as_mut_ptr() as *mut f64);
    (0..g.len() / nx).into_par_iter().for_each(|row| {
        let rn = RowNeighbours::new(&g, row);
        for i in 0..nx {
            let im = if i == 0 { nx - 1 } else { i - 1 };
            // SAFETY: every task writes only the fourth weight of the nodes of its row, and
            // reads only the first three weights of any node (in bounds: m < len).
            let get = |m: usize, a: usize| unsafe { wp.read(4 * m + a) };
            let c = rn.c0 + i;
            let mut d = get(c, 0) + get(rn.c0 + im, 0);
            d += get(c, 1) + get(rn.below[0] + i, 1);
            if dim == 3 {
                d += get(c, 2) + get(rn.below[1] + i, 2);
            }
            let inv = if d > 0.0 { 1.0 / d } else { 0.0 };
            unsafe { wp.write(4 * c + 3, inv) };
        }
    });
}

/// The coarse level's face coefficients from the fine level's: the sum of the fine
/// coefficients crossing each coarse face, divided by the distance between the centres of the
/// two aggregates it separates (in fine spacings; f between uniform aggregates). On a
/// distributed level `out` is the coarse planes from `fine.coarse_k0` on, whose blocks lie in
/// the fine level's own planes (an aggregate never straddles two processes).
fn coarsen(fine: &Level, out: &mut [Weights]) {
    let (g, f) = (&fine.grid, fine.f);
    let n = [g.n[0], g.n[1], g.nz_whole];
    let cn: [usize; 3] = std::array::from_fn(|a| n[a] / f[a]);
    let (k0, ck0) = (g.k0, fine.coarse_k0);
    let dim = g.dim;
    out.par_chunks_mut(cn[0]).enumerate().for_each(|(crow, o)| {
        let (cj, ck) = (crow % cn[1], ck0 + crow / cn[1]);
        for (ci, o) in o.iter_mut().enumerate() {
            let c = [ci, cj, ck];
            // The block's fine nodes along each axis.
            let blocks: [(usize, usize); 3] = std::array::from_fn(|b| block(c[b], f[b], n[b]));
            for a in 0..dim {
                // The fine nodes of the block's last layer along a.
                let mut lo = blocks.map(|r| r.0);
                let hi = blocks.map(|r| r.1);
                lo[a] = hi[a] - 1;
                let mut s = 0.0;
                for k in lo[2]..hi[2] {
                    for j in lo[1]..hi[1] {
                        for i in lo[0]..hi[0] {
                            s += fine.w[g.idx(i, j, k - k0)][a];
                        }
                    }
                }
                let next = block((c[a] + 1) % cn[a], f[a], n[a]);
                let width = (hi[a] - blocks[a].0) + (next.1 - next.0);
                o[a] = 2.0 * s / width as f64;
            }
        }
    });
}

/// (Σ over the node's faces of coefficient × neighbour value, Σ of the coefficients) for node
/// `i` of the row `rn`, reading the field through `x` (so the smoother can read a field other
/// tasks write elsewhere) and the weights from `w`.
#[inline(always)]
fn neighbour_sum(
    w: &[Weights],
    rn: &RowNeighbours,
    three: bool,
    i: usize,
    nx: usize,
    x: impl Fn(usize) -> f64,
) -> f64 {
    let im = if i == 0 { nx - 1 } else { i - 1 };
    let ip = if i + 1 == nx { 0 } else { i + 1 };
    let c = rn.c0 + i;
    let wc = w[c];
    let (ym, zm) = (rn.below[0] + i, rn.below[1] + i);
    let mut s = wc[0] * x(rn.c0 + ip) + w[rn.c0 + im][0] * x(rn.c0 + im);
    s += wc[1] * x(rn.above[0] + i) + w[ym][1] * x(ym);
    if three {
        s += wc[2] * x(rn.above[1] + i) + w[zm][2] * x(zm);
    }
    s
}

/// The Gauss-Seidel update of the nodes of colour `colour` ((i + j + k) mod 2) in plane `k`
/// (the slowest axis: z in 3D, y in 2D).
///
/// # Safety
/// No other task writes the nodes this reads (the other colour in planes k - 1, k, k + 1) or
/// reads or writes the nodes this writes.
unsafe fn red_black_plane(lv: &Level, xp: SyncPtr<f64>, b: &[f64], colour: usize, plane: usize) {
    let g = &lv.grid;
    let [nx, ny, _] = g.n;
    let three = g.dim == 3;
    let rows = if three {
        plane * ny..(plane + 1) * ny
    } else {
        plane..plane + 1
    };
    let (x, w, b) = (xp.0, lv.w.as_ptr(), b.as_ptr());
    for row in rows {
        let rn = RowNeighbours::new(g, row);
        let (c0, [ym, zm], [yp, zp]) = (rn.c0, rn.below, rn.above);
        // SAFETY: every index is a node of this level (the row and its neighbour rows), and
        // the caller guarantees no other task touches the nodes read or written here.
        let node = |i: usize, im: usize, ip: usize| unsafe {
            let c = c0 + i;
            let wc = *w.add(c);
            let mut s = wc[0] * *x.add(c0 + ip) + (*w.add(c0 + im))[0] * *x.add(c0 + im);
            s += wc[1] * *x.add(yp + i) + (*w.add(ym + i))[1] * *x.add(ym + i);
            if three {
                s += wc[2] * *x.add(zp + i) + (*w.add(zm + i))[2] * *x.add(zm + i);
            }
            *x.add(c) = (*b.add(c) + s) * wc[3];
        };
        // The row's nodes of this colour: the first and last with the periodic wrap.
        let mut i = (colour + row % ny + row / ny) % 2;
        if i == 0 {
            node(0, nx - 1, 1 % nx);
            i = 2;
        }
        while i + 1 < nx {
            node(i, i - 1, i + 1);
            i += 2;
        }
        if i + 1 == nx {
            node(i, i - 1, 0);
        }
    }
}

/// One red-black Gauss-Seidel sweep, colour `first` then the other: the same result as a pass
/// over all nodes of one colour followed by a pass over the other (every neighbour of a node
/// has the other colour, each periodic axis having an even node count), in one pass through
/// memory. The planes are split into slabs; in each, the second colour of plane k - 1 follows
/// the first colour of plane k, and the second colour of the slab's two end planes, which
/// needs the first colour of the neighbouring slabs, is done after all slabs.
fn red_black_sweep(lv: &Level, x: &mut [f64], b: &[f64], first: usize) {
    let g = &lv.grid;
    let planes = if g.dim == 3 { g.n[2] } else { g.n[1] };
    let slabs = (2 * rayon::current_num_threads()).min(planes / 4).max(1);
    let bounds = |s: usize| (s * planes / slabs, (s + 1) * planes / slabs);
    let (a, bc) = (first, 1 - first);
    let xp = SyncPtr(x.as_mut_ptr());
    // SAFETY (both phases): within a phase, the planes written by different slabs are more than
    // one plane apart, or are written in different colours (see the function's doc).
    (0..slabs).into_par_iter().for_each(|s| {
        let (k0, k1) = bounds(s);
        for k in k0..k1 {
            unsafe { red_black_plane(lv, xp, b, a, k) };
            if k >= k0 + 2 {
                unsafe { red_black_plane(lv, xp, b, bc, k - 1) };
            }
        }
    });
    (0..slabs).into_par_iter().for_each(|s| {
        let (k0, k1) = bounds(s);
        unsafe { red_black_plane(lv, xp, b, bc, k0) };
        if k1 - 1 > k0 {
            unsafe { red_black_plane(lv, xp, b, bc, k1 - 1) };
        }
    });
}

/// One damped Jacobi sweep: x ← x + ω D⁻¹(b - Ax), through `tmp`.
fn jacobi(lv: &mut Level, x: &mut [f64], b: &[f64]) {
    let g = &lv.grid;
    let nx = g.n[0];
    let three = g.dim == 3;
    let (w, xr) = (&lv.w, &*x);
    lv.tmp.par_chunks_mut(nx).enumerate().for_each(|(row, o)| {
        let rn = RowNeighbours::new(g, row);
        for (i, o) in o.iter_mut().enumerate() {
            let c = rn.c0 + i;
            let s = neighbour_sum(w, &rn, three, i, nx, |m| xr[m]);
            let jac = (b[c] + s) * w[c][3];
            *o = xr[c] + JACOBI_WEIGHT * (jac - xr[c]);
        }
    });
    x.copy_from_slice(&lv.tmp);
}

/// The coarse right-hand side: the block sums of the residual b - A x (computed on the fly).
fn restrict_residual(lv: &mut Level, x: &[f64], b: &[f64]) {
    let g = &lv.grid;
    let f = lv.f;
    let nx = g.n[0];
    let three = g.dim == 3;
    let cn: [usize; 3] = std::array::from_fn(|a| g.n[a] / f[a]);
    let w = &lv.w;
    lv.coarse_b
        .par_chunks_mut(cn[0])
        .enumerate()
        .for_each(|(crow, o)| {
            o.fill(0.0);
            let (cj, ck) = (crow % cn[1], crow / cn[1]);
            let ((j0, j1), (k0, k1)) = (block(cj, f[1], g.n[1]), block(ck, f[2], g.n[2]));
            for k in k0..k1 {
                for j in j0..j1 {
                    let rn = RowNeighbours::new(g, j + g.n[1] * k);
                    let (c0, [ym, zm], [yp, zp]) = (rn.c0, rn.below, rn.above);
                    let row = |at: usize| &x[at..at + nx];
                    let (xc, xym, xyp) = (row(c0), row(ym), row(yp));
                    let (xzm, xzp) = if three { (row(zm), row(zp)) } else { (xc, xc) };
                    let (wc, wym) = (&w[c0..c0 + nx], &w[ym..ym + nx]);
                    let wzm = if three { &w[zm..zm + nx] } else { wc };
                    let bc = &b[c0..c0 + nx];
                    for i in 0..nx {
                        let im = if i == 0 { nx - 1 } else { i - 1 };
                        let ip = if i + 1 == nx { 0 } else { i + 1 };
                        let (wi, wm) = (wc[i], wc[im][0]);
                        let mut ax = wi[0] * (xc[i] - xc[ip]) + wm * (xc[i] - xc[im]);
                        ax += wi[1] * (xc[i] - xyp[i]) + wym[i][1] * (xc[i] - xym[i]);
                        if three {
                            ax += wi[2] * (xc[i] - xzp[i]) + wzm[i][2] * (xc[i] - xzm[i]);
                        }
                        o[aggregate(i, f[0], nx)] += bc[i] - ax;
                    }
                }
            }
        });
}

/// x += the coarse correction copied to every node of its block (prolongation).
fn prolong(lv: &Level, x: &mut [f64]) {
    let g = &lv.grid;
    let [nx, ny, _] = g.n;
    let f = lv.f;
    let nz = g.nz_whole;
    let cn = [nx / f[0], ny / f[1]];
    let (k0, ck0) = (g.k0, lv.coarse_k0);
    let xc = &lv.coarse_x;
    x.par_chunks_mut(nx).enumerate().for_each(|(row, o)| {
        let (j, k) = (row % ny, k0 + row / ny);
        let c0 = cn[0] * (aggregate(j, f[1], ny) + cn[1] * (aggregate(k, f[2], nz) - ck0));
        for (i, o) in o.iter_mut().enumerate() {
            *o += xc[c0 + aggregate(i, f[0], nx)];
        }
    });
}

/// Symmetric Gauss-Seidel sweeps in one thread (the coarsest level), from x = 0.
fn coarsest(lv: &Level, x: &mut [f64], b: &[f64]) {
    let g = &lv.grid;
    let nx = g.n[0];
    let rows = g.len() / nx;
    let three = g.dim == 3;
    x.fill(0.0);
    let node = |x: &mut [f64], row: usize, i: usize| {
        let rn = RowNeighbours::new(g, row);
        let s = neighbour_sum(&lv.w, &rn, three, i, nx, |m| x[m]);
        let c = rn.c0 + i;
        x[c] = (b[c] + s) * lv.w[c][3];
    };
    for _ in 0..COARSEST_SWEEPS {
        for row in 0..rows {
            for i in 0..nx {
                node(x, row, i);
            }
        }
        for row in (0..rows).rev() {
            for i in (0..nx).rev() {
                node(x, row, i);
            }
        }
    }
}

/// The V-cycle on `levels[0]`: x ≈ A⁻¹ b, from x = 0.
fn cycle(levels: &mut [Level], x: &mut [f64], b: &[f64]) {
    let Some((lv, rest)) = levels.split_first_mut() else {
        return;
    };
    if rest.is_empty() {
        coarsest(lv, x, b);
        return;
    }
    x.par_iter_mut().for_each(|v| *v = 0.0);
    smooth(lv, x, b, 0);
    restrict_residual(lv, x, b);
    cycle(rest, &mut lv.coarse_x, &lv.coarse_b);
    prolong(lv, x);
    smooth(lv, x, b, 1);
}

/// The smoothing sweeps before (`first` = 0: red then black) or after (`first` = 1: black then
/// red) the coarse correction.
fn smooth(lv: &mut Level, x: &mut [f64], b: &[f64], first: usize) {
    if lv.red_black {
        for _ in 0..SWEEPS {
            red_black_sweep(lv, x, b, first);
        }
    } else {
        for _ in 0..JACOBI_SWEEPS {
            jacobi(lv, x, b);
        }
    }
}

// The distributed levels: each process holds its planes, with one ghost plane a side of the
// iterate and the z-face coefficients of the plane below. Each kernel computes every node as
// its whole-grid counterpart does, the same terms added in the same order, so the bits are the
// whole grid's.

/// The ghost planes of `x` from the neighbours (every process together).
fn fill_x(lv: &mut Level, d: &Decomposition, x: &[f64]) {
    let p = lv.grid.plane();
    let (below, above) = lv.ghosts.x.split_at_mut(p);
    d.comm
        .exchange(&d.slabs, &x[..p], &x[x.len() - p..], below, above);
}

/// The z-face coefficients of the plane below the slab from the neighbour below.
fn fill_wz(lv: &mut Level, d: &Decomposition) {
    let p = lv.grid.plane();
    let last = lv.w.len() - p;
    let Ghosts { wz, send, .. } = &mut lv.ghosts;
    for i in 0..p {
        send[i] = lv.w[i][2];
        send[p + i] = lv.w[last + i][2];
    }
    let (below, above) = wz.split_at_mut(p);
    d.comm
        .exchange(&d.slabs, &send[..p], &send[p..], below, above);
}

/// Where a row's neighbour row along z is on a distributed level: in the field (its first
/// node) or in the ghosts (its first node there).
#[derive(Clone, Copy)]
enum ZRow {
    Field(usize),
    Ghost(usize),
}

/// The rows along y (below, above) and along z (below, above) of the row `row` of a slab.
#[inline(always)]
fn slab_rows(g: &Grid, row: usize) -> ([usize; 2], [ZRow; 2]) {
    let [nx, ny, nz] = g.n;
    let (j, k) = (row % ny, row / ny);
    let (jm, jp) = periodic_neighbours(j, ny);
    let p = nx * ny;
    let zm = if k == 0 {
        ZRow::Ghost(j * nx)
    } else {
        ZRow::Field(nx * (j + ny * (k - 1)))
    };
    let zp = if k + 1 == nz {
        ZRow::Ghost(p + j * nx)
    } else {
        ZRow::Field(nx * (j + ny * (k + 1)))
    };
    ([nx * (jm + ny * k), nx * (jp + ny * k)], [zm, zp])
}

/// [`inverse_diagonal`] on a distributed level (after [`fill_wz`]).
fn split_inverse_diagonal(lv: &mut Level) {
    let g = lv.grid.clone();
    let nx = g.n[0];
    let gwz = &lv.ghosts.wz;
    let wp = SyncPtr(lv.w.as_mut_ptr() as *mut f64);
    (0..g.len() / nx).into_par_iter().for_each(|row| {
        let ([ym, _], [zm, _]) = slab_rows(&g, row);
        let c0 = row * nx;
        for i in 0..nx {
            let im = if i == 0 { nx - 1 } else { i - 1 };
            // SAFETY: every task writes only the fourth weight of the nodes of its row, and
            // reads only the first three weights of any node (in bounds: m < len).
            let get = |m: usize, a: usize| unsafe { wp.read(4 * m + a) };
            let c = c0 + i;
            let wzm = match zm {
                ZRow::Field(at) => get(at + i, 2),
                ZRow::Ghost(at) => gwz[at + i],
            };
            let mut d = get(c, 0) + get(c0 + im, 0);
            d += get(c, 1) + get(ym + i, 1);
            d += get(c, 2) + wzm;
            let inv = if d > 0.0 { 1.0 / d } else { 0.0 };
            unsafe { wp.write(4 * c + 3, inv) };
        }
    });
}

/// The Gauss-Seidel update of the nodes of colour `colour` ((i + j + k) mod 2, k the whole
/// grid's plane) of a distributed level (after [`fill_x`]): every node reads only nodes of the
/// other colour, so the pass is a colour pass of [`red_black_sweep`].
fn split_colour(lv: &Level, x: &mut [f64], b: &[f64], colour: usize) {
    let g = &lv.grid;
    let [nx, ny, _] = g.n;
    let (w, gx, gwz) = (&lv.w, &lv.ghosts.x, &lv.ghosts.wz);
    let xp = SyncPtr(x.as_mut_ptr());
    (0..g.len() / nx).into_par_iter().for_each(|row| {
        let ([ym, yp], [zm, zp]) = slab_rows(g, row);
        let c0 = row * nx;
        // SAFETY: this task writes the nodes of colour `colour` of its row; every node it
        // reads has the other colour (or is a ghost), which no task writes in this pass.
        let xr = |m: usize| unsafe { xp.read(m) };
        let xz = |r: ZRow, i: usize| match r {
            ZRow::Field(at) => xr(at + i),
            ZRow::Ghost(at) => gx[at + i],
        };
        let wzm = |i: usize| match zm {
            ZRow::Field(at) => w[at + i][2],
            ZRow::Ghost(at) => gwz[at + i],
        };
        let mut i = (colour + row % ny + g.k0 + row / ny) % 2;
        while i < nx {
            let (im, ip) = periodic_neighbours(i, nx);
            let c = c0 + i;
            let wc = w[c];
            let mut s = wc[0] * xr(c0 + ip) + w[c0 + im][0] * xr(c0 + im);
            s += wc[1] * xr(yp + i) + w[ym + i][1] * xr(ym + i);
            s += wc[2] * xz(zp, i) + wzm(i) * xz(zm, i);
            unsafe { xp.write(c, (b[c] + s) * wc[3]) };
            i += 2;
        }
    });
}

/// [`jacobi`] on a distributed level (after [`fill_x`]).
fn split_jacobi(lv: &mut Level, x: &mut [f64], b: &[f64]) {
    let Level {
        grid: g,
        w,
        tmp,
        ghosts,
        ..
    } = lv;
    let nx = g.n[0];
    let (gx, gwz, xr) = (&ghosts.x, &ghosts.wz, &*x);
    tmp.par_chunks_mut(nx).enumerate().for_each(|(row, o)| {
        let ([ym, yp], [zm, zp]) = slab_rows(g, row);
        let c0 = row * nx;
        let xz = |r: ZRow, i: usize| match r {
            ZRow::Field(at) => xr[at + i],
            ZRow::Ghost(at) => gx[at + i],
        };
        let wzm = |i: usize| match zm {
            ZRow::Field(at) => w[at + i][2],
            ZRow::Ghost(at) => gwz[at + i],
        };
        for (i, o) in o.iter_mut().enumerate() {
            let (im, ip) = periodic_neighbours(i, nx);
            let c = c0 + i;
            let wc = w[c];
            let mut s = wc[0] * xr[c0 + ip] + w[c0 + im][0] * xr[c0 + im];
            s += wc[1] * xr[yp + i] + w[ym + i][1] * xr[ym + i];
            s += wc[2] * xz(zp, i) + wzm(i) * xz(zm, i);
            let jac = (b[c] + s) * wc[3];
            *o = xr[c] + JACOBI_WEIGHT * (jac - xr[c]);
        }
    });
    x.copy_from_slice(tmp);
}

/// [`restrict_residual`] on a distributed level (after [`fill_x`]): this process's planes of
/// the coarse right-hand side, whose blocks lie in its own fine planes.
fn split_restrict(lv: &mut Level, x: &[f64], b: &[f64]) {
    let Level {
        grid: g,
        f,
        w,
        coarse_b,
        coarse_k0,
        ghosts,
        ..
    } = lv;
    let (f, ck0) = (*f, *coarse_k0);
    let [nx, ny, _] = g.n;
    let (nz, k0) = (g.nz_whole, g.k0);
    let cn = [nx / f[0], ny / f[1]];
    let (gx, gwz) = (&ghosts.x, &ghosts.wz);
    coarse_b
        .par_chunks_mut(cn[0])
        .enumerate()
        .for_each(|(crow, o)| {
            o.fill(0.0);
            let (cj, ck) = (crow % cn[1], ck0 + crow / cn[1]);
            let ((j0, j1), (ka, kb)) = (block(cj, f[1], ny), block(ck, f[2], nz));
            for k in ka - k0..kb - k0 {
                for j in j0..j1 {
                    let row = j + ny * k;
                    let ([ym, yp], [zm, zp]) = slab_rows(g, row);
                    let c0 = row * nx;
                    let xz = |r: ZRow, i: usize| match r {
                        ZRow::Field(at) => x[at + i],
                        ZRow::Ghost(at) => gx[at + i],
                    };
                    let wzm = |i: usize| match zm {
                        ZRow::Field(at) => w[at + i][2],
                        ZRow::Ghost(at) => gwz[at + i],
                    };
                    for i in 0..nx {
                        let (im, ip) = periodic_neighbours(i, nx);
                        let xc = x[c0 + i];
                        let (wi, wm) = (w[c0 + i], w[c0 + im][0]);
                        let mut ax = wi[0] * (xc - x[c0 + ip]) + wm * (xc - x[c0 + im]);
                        ax += wi[1] * (xc - x[yp + i]) + w[ym + i][1] * (xc - x[ym + i]);
                        ax += wi[2] * (xc - xz(zp, i)) + wzm(i) * (xc - xz(zm, i));
                        o[aggregate(i, f[0], nx)] += b[c0 + i] - ax;
                    }
                }
            }
        });
}

/// The smoothing sweeps of a distributed level (see [`smooth`]), a ghost exchange before each
/// colour pass or Jacobi sweep.
fn split_smooth(lv: &mut Level, d: &Decomposition, x: &mut [f64], b: &[f64], first: usize) {
    if lv.red_black {
        for _ in 0..SWEEPS {
            for colour in [first, 1 - first] {
                fill_x(lv, d, x);
                split_colour(lv, x, b, colour);
            }
        }
    } else {
        for _ in 0..JACOBI_SWEEPS {
            fill_x(lv, d, x);
            split_jacobi(lv, x, b);
        }
    }
}

/// The V-cycle from `levels[0]`, of which the first `dist` are distributed (at least one):
/// x ≈ A⁻¹ b on this process's planes, from x = 0. Past the last distributed level the coarse
/// right-hand side is gathered, the rest of the cycle run whole on every process, and each
/// takes its planes of the correction.
fn split_cycle(levels: &mut [Level], dist: usize, sp: &mut Split, x: &mut [f64], b: &[f64]) {
    let (lv, rest) = levels
        .split_first_mut()
        .expect("multigrid: a distributed level has a coarser one");
    x.par_iter_mut().for_each(|v| *v = 0.0);
    split_smooth(lv, &sp.d, x, b, 0);
    fill_x(lv, &sp.d, x);
    split_restrict(lv, x, b);
    if dist > 1 {
        split_cycle(rest, dist - 1, sp, &mut lv.coarse_x, &lv.coarse_b);
    } else {
        sp.gather.whole(&lv.coarse_b, &mut sp.b);
        cycle(rest, &mut sp.x, &sp.b);
        lv.coarse_x.copy_from_slice(&sp.x[sp.mine.clone()]);
    }
    prolong(lv, x);
    split_smooth(lv, &sp.d, x, b, 1);
}
