//! The FFT engine of the periodic grid: real-to-complex 2D/3D transforms with their plans and
//! per-thread scratch, all allocated by [`FftEngine::new`]; no other method allocates (unless
//! the engine runs on more threads than it was made with: then the scratch grows once). The
//! operators built on it (Poisson, diffusion, curl) are in [`crate::solvers::operators`].
//!
//! # Layout of a complex field
//!
//! The forward transform of a real field of `nx * ny * nz` nodes (x fastest) is a complex field of
//! [`FftEngine::complex_len`] `= (nx/2 + 1) * ny * nz` coefficients, stored with the same axis
//! order: coefficient `(i, j, k)` sits at `i + (nx/2 + 1) * (j + ny * k)`, with `i` in
//! `0..=nx/2` the (non-negative) x wavenumber index and `j`, `k` the usual FFT indices of y and z
//! (signed wavenumber via [`wavenumber`]). In 2D (`nz == 1`) there is no z work at all.
//!
//! # Algorithm
//!
//! * x: one real-to-complex transform per row (realfft), copying the row into a per-worker real
//!   scratch first (realfft destroys its input).
//! * y: gather lines into a worker scratch with y fastest (blocked transposes), run rustfft on
//!   the whole scratch (it transforms consecutive lines), scatter back. In 3D with at least
//!   `MIN_FUSED_PLANES` z-planes the x and y transforms of one z-plane run fused (the r2c rows go
//!   straight into the y-fastest scratch, one plane per unit); otherwise (2D, thin 3D) x rows and
//!   y line bundles (blocks of x indices, so that a single 2D plane still splits) are separate
//!   passes.
//! * z (3D only): per y index, gather the `(nx/2+1) x nz` slab with z fastest, transform, scatter.
//! * the inverse runs the same passes in reverse order and normalizes by `1/(nx ny nz)` once,
//!   right after the complex-to-real transform of each row.
//!
//! # Split over processes
//!
//! [`FftEngine::split`] transforms one process's slab of z-planes ([`crate::parallel::Slabs`]):
//! the x and y passes above run on its planes, one all-to-all ([`Comm::all_to_all`]) hands every
//! process its range of y rows with every z, and the z pass runs there. The spectrum a process
//! holds has the layout above with `ny` replaced by its row count (coefficient `(i, j, k)` of its
//! rows `j0..j0 + rows` at `i + (nx/2 + 1) * ((j - j0) + rows * k)`), so an operator that works on
//! the whole spectrum works on a process's share once it reads the y wavenumbers of its rows.
//! The inverse runs the same steps backwards. Each process's blocks are copied to and from the
//! transpose's buffer in one parallel pass; the receiving side needs none, since a process's
//! planes of another's rows are one contiguous range of the latter's spectrum.
//!
//! Work is split into a fixed set of units (rows, planes or line bundles) that depends on the
//! grid only; each unit is transformed by exactly the same code whichever worker or thread runs
//! it, and there is no reduction, so results are bit-identical for any rayon thread count.

use std::f64::consts::PI;
use std::ops::Range;
use std::sync::Arc;

use rayon::prelude::*;
use realfft::{ComplexToReal, FftError, RealFftPlanner, RealToComplex};
use rustfft::num_complex::Complex;
use rustfft::{Fft, FftPlanner};

use crate::base::grid::{Grid, SyncPtr};
use crate::base::pool::Pool;
use crate::parallel::{Comm, DecompositionError, Slabs, Transpose};

/// Double precision complex number.
pub type C64 = Complex<f64>;

/// Minimum number of parallel chunks of a pass. Only scheduling depends on it, never results
/// (and not memory: the scratch is per thread).
const MIN_WORKERS: usize = 32;

/// Minimum number of z-planes for the fused x/y plane passes (one plane per unit) in 3D.
const MIN_FUSED_PLANES: usize = 8;

/// Number of line bundles a y or z pass aims for (so that 2D planes still split in parallel).
const TARGET_UNITS: usize = 64;

/// Signed wavenumber `2 pi m' / len` of FFT index `m` on a periodic axis of `n` points and length
/// `len`, where `m' = m` for `m <= n/2` and `m - n` otherwise (so `m'` lies in `-n/2+1..=n/2`
/// for even `n`, the Nyquist index `n/2` being counted positive).
pub fn wavenumber(m: usize, n: usize, len: f64) -> f64 {
    let s = if 2 * m <= n {
        m as f64
    } else {
        m as f64 - n as f64
    };
    2.0 * PI * s / len
}

/// Tile height of the blocked transposes between row (x fastest) and line (y or z fastest)
/// layouts: `TILE` consecutive line points (two cache lines of complex values) are written or
/// read together.
const TILE: usize = 8;

/// Scratch space of one task (the engine keeps one per thread, see [`Pool`]); every unit
/// overwrites what it reads of it.
struct Worker {
    /// A real row (`nx`), since realfft's forward transform destroys its input.
    real: Vec<f64>,
    /// `TILE` complex rows (`TILE * (nx/2+1)`), for the fused x/y plane passes.
    rows: Vec<C64>,
    /// Gathered line bundle of a y or z pass (or a whole plane, y fastest).
    line: Vec<C64>,
    /// FFT scratch, as long as the longest scratch any plan needs.
    scratch: Vec<C64>,
}

/// Blocked transpose into line layout: `line[ii * l + t] = src[t * stride + ii]` for `t < l`,
/// `ii < w`.
///
/// # Safety
/// Every `src[t * stride + ii]` read is in bounds and not written concurrently.
#[inline]
unsafe fn gather(src: *const C64, stride: usize, l: usize, w: usize, line: &mut [C64]) {
    debug_assert!(line.len() >= w * l);
    for t0 in (0..l).step_by(TILE) {
        let tb = TILE.min(l - t0);
        for ii in 0..w {
            let dst = &mut line[ii * l + t0..ii * l + t0 + tb];
            for (tt, d) in dst.iter_mut().enumerate() {
                // SAFETY: guaranteed by the caller.
                *d = unsafe { *src.add((t0 + tt) * stride + ii) };
            }
        }
    }
}

/// Blocked transpose back to row layout: `dst[t * stride + ii] = line[ii * l + t]`.
///
/// # Safety
/// Every `dst[t * stride + ii]` written is in bounds and not accessed concurrently.
#[inline]
unsafe fn scatter(line: &[C64], stride: usize, l: usize, w: usize, dst: *mut C64) {
    debug_assert!(line.len() >= w * l);
    for t0 in (0..l).step_by(TILE) {
        let tb = TILE.min(l - t0);
        for ii in 0..w {
            let src = &line[ii * l + t0..ii * l + t0 + tb];
            for (tt, v) in src.iter().enumerate() {
                // SAFETY: guaranteed by the caller.
                unsafe { *dst.add((t0 + tt) * stride + ii) = *v };
            }
        }
    }
}

/// Geometry of a y or z pass: a set of `outers * nblocks` independent units, each a bundle of
/// `len`-long lines (one per x index of its block).
#[derive(Clone, Copy, Debug)]
struct LinePass {
    /// Transform length (ny or nz).
    len: usize,
    /// Distance between consecutive points of one line in the complex field.
    stride: usize,
    /// Distance between consecutive outer indices (k for y, j for z).
    outer_stride: usize,
    /// Number of outer indices.
    outers: usize,
    /// Number of x indices (nx/2 + 1).
    width: usize,
    /// x indices per unit.
    block: usize,
    /// Blocks per outer index.
    nblocks: usize,
}

impl LinePass {
    fn new(len: usize, stride: usize, outer_stride: usize, outers: usize, width: usize) -> Self {
        let nblocks = TARGET_UNITS.div_ceil(outers).clamp(1, width);
        let block = width.div_ceil(nblocks);
        let nblocks = width.div_ceil(block);
        LinePass {
            len,
            stride,
            outer_stride,
            outers,
            width,
            block,
            nblocks,
        }
    }

    fn units(&self) -> usize {
        self.outers * self.nblocks
    }

    /// Transforms the lines of unit `u`: gather from `src`, FFT, scatter into `dst`.
    ///
    /// # Safety
    /// `src` and `dst` point to complex fields of the pass's geometry (they may be equal); no
    /// other task touches the elements of unit `u` of `dst` (or of `src` when it is written)
    /// concurrently. Units are pairwise disjoint, so distinct units may run concurrently.
    unsafe fn run_unit(
        &self,
        u: usize,
        fft: &dyn Fft<f64>,
        wk: &mut Worker,
        src: SyncPtr<C64>,
        dst: SyncPtr<C64>,
    ) {
        let outer = u / self.nblocks;
        let i0 = (u % self.nblocks) * self.block;
        let w = self.block.min(self.width - i0);
        let base = outer * self.outer_stride + i0;
        let l = self.len;
        let line = &mut wk.line[..w * l];
        // SAFETY: the unit's elements are in bounds and touched by this unit only; the reads of
        // `src` are finished before `dst` (possibly the same memory) is written.
        unsafe {
            gather(src.0.add(base), self.stride, l, w, line);
            let sl = fft.get_inplace_scratch_len();
            fft.process_with_scratch(line, &mut wk.scratch[..sl]);
            scatter(line, self.stride, l, w, dst.0.add(base));
        }
    }
}

/// A complex FFT plan (rustfft).
type Plan = Arc<dyn Fft<f64>>;

/// Plans and geometry (immutable after construction).
struct Engine {
    nx: usize,
    ny: usize,
    /// z-planes of the whole grid.
    nz: usize,
    /// z-planes of the real field this engine transforms (`nz` unless split over processes).
    nk: usize,
    /// y rows of the spectral layout this engine holds (`ny` unless split over processes).
    nyl: usize,
    nxh: usize,
    r2c: Arc<dyn RealToComplex<f64>>,
    c2r: Arc<dyn ComplexToReal<f64>>,
    y_fwd: Arc<dyn Fft<f64>>,
    y_inv: Arc<dyn Fft<f64>>,
    /// z plans, 3D only.
    z_plans: Option<[Plan; 2]>,
    ypass: LinePass,
    zpass: LinePass,
    /// Whether the x and y transforms run fused, one z-plane per unit (3D with enough planes);
    /// otherwise x rows and y line bundles are separate passes.
    fused: bool,
    /// Parallel chunks of a pass (a fixed number for the grid: only scheduling depends on it).
    chunks: usize,
}

/// Panics on the buffer-size errors (internal invariants, never user data) and ignores
/// `InputValues` (non-zero imaginary DC/Nyquist parts, zeroed beforehand anyway).
fn check(r: Result<(), FftError>) {
    match r {
        Ok(()) | Err(FftError::InputValues(..)) => {}
        Err(e) => panic!("spectral: internal FFT buffer size mismatch: {e}"),
    }
}

impl Engine {
    fn complex_len(&self) -> usize {
        self.nxh * self.nyl * self.nz
    }

    fn real_len(&self) -> usize {
        self.nx * self.ny * self.nk
    }

    /// Rows (x lines) per chunk so that there are at most `workers` chunks.
    fn rows_per_chunk(&self, workers: usize) -> usize {
        (self.ny * self.nk).div_ceil(workers).max(1)
    }

    /// z-planes per chunk so that there are at most `workers` chunks.
    fn planes_per_chunk(&self, workers: usize) -> usize {
        self.nk.div_ceil(workers).max(1)
    }

    /// Zeroes the imaginary parts a real row cannot carry, then runs the c2r transform of one
    /// row and normalizes it.
    fn c2r_row(&self, row: &mut [C64], out: &mut [f64], scratch: &mut [C64], scale: f64) {
        row[0].im = 0.0;
        if self.nx.is_multiple_of(2) {
            row[self.nx / 2].im = 0.0;
        }
        let sl = self.c2r.get_scratch_len();
        check(self.c2r.process_with_scratch(row, out, &mut scratch[..sl]));
        for v in out.iter_mut() {
            *v *= scale;
        }
    }

    /// Runs a y or z pass: reads from `src` (or from `data` itself when `None`), writes `data`.
    fn run_pass(
        &self,
        pass: &LinePass,
        fft: &dyn Fft<f64>,
        pool: &Pool<Worker>,
        src: Option<&[C64]>,
        data: &mut [C64],
    ) {
        let dst = SyncPtr(data.as_mut_ptr());
        let srcp = match src {
            Some(s) => {
                assert_eq!(s.len(), data.len(), "spectral: source length mismatch");
                SyncPtr(s.as_ptr() as *mut C64)
            }
            None => dst,
        };
        let units = pass.units();
        let nw = self.chunks;
        (0..nw).into_par_iter().for_each(|w| {
            pool.with(|wk| {
                for u in (w * units / nw)..((w + 1) * units / nw) {
                    // SAFETY: units are disjoint and each is run by exactly one task;
                    // `src` is either `data` (same unit, written only after being read) or
                    // a separate buffer that is only read.
                    unsafe { pass.run_unit(u, fft, wk, srcp, dst) };
                }
            })
        });
    }

    /// Forward x (r2c) and y transforms of one z-plane: `input` is the real plane, `out` the
    /// complex plane.
    fn forward_plane(&self, wk: &mut Worker, input: &[f64], out: &mut [C64]) {
        let (nx, ny, nxh) = (self.nx, self.ny, self.nxh);
        let sl = self.r2c.get_scratch_len();
        let line = &mut wk.line[..nxh * ny];
        for j0 in (0..ny).step_by(TILE) {
            let tb = TILE.min(ny - j0);
            for jj in 0..tb {
                let j = j0 + jj;
                wk.real.copy_from_slice(&input[j * nx..(j + 1) * nx]);
                let row = &mut wk.rows[jj * nxh..(jj + 1) * nxh];
                check(
                    self.r2c
                        .process_with_scratch(&mut wk.real, row, &mut wk.scratch[..sl]),
                );
            }
            for i in 0..nxh {
                let dst = &mut line[i * ny + j0..i * ny + j0 + tb];
                for (jj, d) in dst.iter_mut().enumerate() {
                    *d = wk.rows[jj * nxh + i];
                }
            }
        }
        let sy = self.y_fwd.get_inplace_scratch_len();
        self.y_fwd.process_with_scratch(line, &mut wk.scratch[..sy]);
        // SAFETY: `out` is one complex plane (`ny` rows of `nxh`), exclusively borrowed.
        unsafe { scatter(line, nxh, ny, nxh, out.as_mut_ptr()) };
    }

    /// Inverse y and x (c2r, normalized by `scale`) transforms of one z-plane; `input` (the
    /// complex plane) is only read.
    fn inverse_plane(&self, wk: &mut Worker, input: &[C64], out: &mut [f64], scale: f64) {
        let (nx, ny, nxh) = (self.nx, self.ny, self.nxh);
        assert_eq!(input.len(), nxh * ny);
        let line = &mut wk.line[..nxh * ny];
        // SAFETY: `input` is one complex plane, borrowed.
        unsafe { gather(input.as_ptr(), nxh, ny, nxh, line) };
        let sy = self.y_inv.get_inplace_scratch_len();
        self.y_inv.process_with_scratch(line, &mut wk.scratch[..sy]);
        for j0 in (0..ny).step_by(TILE) {
            let tb = TILE.min(ny - j0);
            for i in 0..nxh {
                let src = &line[i * ny + j0..i * ny + j0 + tb];
                for (jj, v) in src.iter().enumerate() {
                    wk.rows[jj * nxh + i] = *v;
                }
            }
            for jj in 0..tb {
                let j = j0 + jj;
                let row = &mut wk.rows[jj * nxh..(jj + 1) * nxh];
                self.c2r_row(row, &mut out[j * nx..(j + 1) * nx], &mut wk.scratch, scale);
            }
        }
    }

    /// Unnormalized forward x and y transforms of the `nk` planes of `input` into `out`
    /// (`nxh * ny * nk` values).
    fn forward_xy(&self, pool: &Pool<Worker>, input: &[f64], out: &mut [C64]) {
        let (nx, ny, nxh) = (self.nx, self.ny, self.nxh);
        if self.fused {
            let ppc = self.planes_per_chunk(self.chunks);
            input
                .par_chunks(ppc * nx * ny)
                .zip(out.par_chunks_mut(ppc * nxh * ny))
                .for_each(|(inp, o)| {
                    pool.with(|wk| {
                        for (pi, po) in inp.chunks_exact(nx * ny).zip(o.chunks_exact_mut(nxh * ny))
                        {
                            self.forward_plane(wk, pi, po);
                        }
                    })
                });
        } else {
            let rpc = self.rows_per_chunk(self.chunks);
            let sl = self.r2c.get_scratch_len();
            let r2c = &*self.r2c;
            input
                .par_chunks(rpc * nx)
                .zip(out.par_chunks_mut(rpc * nxh))
                .for_each(|(inp, o)| {
                    pool.with(|wk| {
                        for (ri, ro) in inp.chunks_exact(nx).zip(o.chunks_exact_mut(nxh)) {
                            wk.real.copy_from_slice(ri);
                            check(r2c.process_with_scratch(
                                &mut wk.real,
                                ro,
                                &mut wk.scratch[..sl],
                            ));
                        }
                    })
                });
            self.run_pass(&self.ypass, &*self.y_fwd, pool, None, out);
        }
    }

    /// The z transforms (3D only) of the spectral layout `data` (`nxh * nyl * nz` values), in
    /// place or from `src`: forward, or inverse when `inverse`.
    fn z(&self, pool: &Pool<Worker>, inverse: bool, src: Option<&[C64]>, data: &mut [C64]) {
        if let Some(plans) = &self.z_plans {
            let plan = &*plans[usize::from(inverse)];
            self.run_pass(&self.zpass, plan, pool, src, data);
        }
    }

    /// Normalized inverse y and x transforms of the `nk` planes of `src` (or of `work` itself
    /// when `None`) into `out`; `work` is destroyed.
    fn inverse_xy(
        &self,
        pool: &Pool<Worker>,
        mut src: Option<&[C64]>,
        work: &mut [C64],
        out: &mut [f64],
    ) {
        let (nx, ny, nxh) = (self.nx, self.ny, self.nxh);
        let scale = 1.0 / (nx * ny * self.nz) as f64;
        if self.fused {
            assert!(
                src.is_none(),
                "fft: the fused planes read their own work buffer"
            );
            let ppc = self.planes_per_chunk(self.chunks);
            work.par_chunks(ppc * nxh * ny)
                .zip(out.par_chunks_mut(ppc * nx * ny))
                .for_each(|(wi, o)| {
                    pool.with(|wk| {
                        for (pi, po) in wi.chunks_exact(nxh * ny).zip(o.chunks_exact_mut(nx * ny)) {
                            self.inverse_plane(wk, pi, po, scale);
                        }
                    })
                });
            return;
        }
        self.run_pass(&self.ypass, &*self.y_inv, pool, src.take(), work);
        let rpc = self.rows_per_chunk(self.chunks);
        work.par_chunks_mut(rpc * nxh)
            .zip(out.par_chunks_mut(rpc * nx))
            .for_each(|(wi, o)| {
                pool.with(|wk| {
                    for (ri, ro) in wi.chunks_exact_mut(nxh).zip(o.chunks_exact_mut(nx)) {
                        self.c2r_row(ri, ro, &mut wk.scratch, scale);
                    }
                })
            });
    }
}

/// The FFT engine of one [`Grid`]: plans (immutable) and per-worker scratch; split over the
/// processes of a [`Comm`], the transposes between them.
pub struct FftEngine {
    eng: Engine,
    pool: Pool<Worker>,
    split: Option<Split>,
}

/// The transpose between the slab layout (this process's z-planes, every y) and the spectral
/// layout (this process's y rows, every z) of a split engine.
struct Split {
    comm: Arc<Comm>,
    slabs: Slabs,
    transpose: Transpose,
    /// The x/y-transformed planes, `nxh * ny * nk`, before the forward transpose and after the
    /// inverse one.
    planes: Vec<C64>,
    /// The transpose's send or receive buffer, as long.
    packed: Vec<C64>,
}

impl Split {
    fn new(n: [usize; 3], nxh: usize, comm: Arc<Comm>) -> Result<Self, DecompositionError> {
        let slabs = Slabs::new(n, comm.size(), comm.rank())?;
        let transpose = Transpose::new(&slabs, nxh);
        let len = transpose.slab_len();
        Ok(Split {
            comm,
            slabs,
            transpose,
            planes: vec![C64::default(); len],
            packed: vec![C64::default(); len],
        })
    }
}

impl FftEngine {
    /// Plans for this grid (2D when `grid.n[2] == 1`) and allocates the scratch.
    ///
    /// Panics if a node count is 0 or `h` is not positive and finite.
    pub fn new(grid: &Grid) -> Self {
        let [_, ny, nz] = grid.n;
        Self::build(grid, nz, ny, None)
    }

    /// The engine of this process's share of `grid` split over the processes of `comm` into
    /// slabs ([`Slabs`]): it transforms this process's z-planes and holds this process's y
    /// rows of the spectrum (every x wavenumber and z). One process runs the same transposes
    /// with itself (tests use this to check them against [`FftEngine::new`]).
    ///
    /// An error when the grid cannot be split over that many processes.
    pub fn split(grid: &Grid, comm: Arc<Comm>) -> Result<Self, DecompositionError> {
        let nxh = grid.n[0] / 2 + 1;
        let split = Split::new(grid.n, nxh, comm)?;
        let (nk, nyl) = (split.slabs.my_planes().len(), split.slabs.my_rows().len());
        Ok(Self::build(grid, nk, nyl, Some(split)))
    }

    fn build(grid: &Grid, nk: usize, nyl: usize, split: Option<Split>) -> Self {
        let [nx, ny, nz] = grid.n;
        assert!(nx > 0 && ny > 0 && nz > 0, "fft: empty grid {:?}", grid.n);
        assert!(
            grid.h.is_finite() && grid.h > 0.0,
            "fft: bad grid spacing {}",
            grid.h
        );
        let dim = if nz == 1 { 2 } else { 3 };
        let nxh = nx / 2 + 1;

        let mut rp = RealFftPlanner::<f64>::new();
        let r2c = rp.plan_fft_forward(nx);
        let c2r = rp.plan_fft_inverse(nx);
        let mut cp = FftPlanner::<f64>::new();
        let y_fwd = cp.plan_fft_forward(ny);
        let y_inv = cp.plan_fft_inverse(ny);
        let z_plans = (dim == 3).then(|| [cp.plan_fft_forward(nz), cp.plan_fft_inverse(nz)]);

        // The y pass runs over this process's planes, the z pass over its spectral rows.
        let ypass = LinePass::new(ny, nxh, nxh * ny, nk.max(1), nxh);
        let zpass = LinePass::new(nz, nxh * nyl, nxh, nyl.max(1), nxh);

        let mut scratch_len = r2c
            .get_scratch_len()
            .max(c2r.get_scratch_len())
            .max(y_fwd.get_inplace_scratch_len())
            .max(y_inv.get_inplace_scratch_len());
        let fused = dim == 3 && nk >= MIN_FUSED_PLANES;
        let mut line_len = if fused { nxh * ny } else { ypass.block * ny };
        let mut max_units = (ny * nk).max(ypass.units());
        if let Some([zf, zi]) = &z_plans {
            scratch_len = scratch_len
                .max(zf.get_inplace_scratch_len())
                .max(zi.get_inplace_scratch_len());
            line_len = line_len.max(zpass.block * nz);
            max_units = max_units.max(zpass.units());
        }
        let chunks = MIN_WORKERS
            .max(4 * rayon::current_num_threads())
            .min(max_units)
            .max(1);
        let rows_len = if fused { TILE * nxh } else { 0 };
        let pool = Pool::per_thread(move || Worker {
            real: vec![0.0; nx],
            rows: vec![C64::default(); rows_len],
            line: vec![C64::default(); line_len],
            scratch: vec![C64::default(); scratch_len],
        });

        let eng = Engine {
            nx,
            ny,
            nz,
            nk,
            nyl,
            nxh,
            r2c,
            c2r,
            y_fwd,
            y_inv,
            z_plans,
            ypass,
            zpass,
            fused,
            chunks,
        };
        FftEngine { eng, pool, split }
    }

    /// Number of complex coefficients of one real field this engine holds: `(nx/2 + 1) ny nz`,
    /// or its spectral rows' share when split.
    pub fn complex_len(&self) -> usize {
        self.eng.complex_len()
    }

    /// Number of nodes of one real field this engine transforms: `nx ny nz`, or its planes'
    /// share when split.
    pub fn real_len(&self) -> usize {
        self.eng.real_len()
    }

    /// The node counts of the spectral layout this engine holds, `[nx, rows, nz]` (`rows` its
    /// y rows, `ny` unless split), and `nx/2 + 1`.
    pub fn dims(&self) -> ([usize; 3], usize) {
        ([self.eng.nx, self.eng.nyl, self.eng.nz], self.eng.nxh)
    }

    /// The y rows of the spectrum this engine holds (all of them unless split).
    pub fn spectral_rows(&self) -> Range<usize> {
        match &self.split {
            Some(s) => s.slabs.my_rows(),
            None => 0..self.eng.ny,
        }
    }

    /// The z-planes of the real field this engine transforms (all of them unless split).
    pub fn planes(&self) -> Range<usize> {
        match &self.split {
            Some(s) => s.slabs.my_planes(),
            None => 0..self.eng.nz,
        }
    }

    /// The number of nodes of the whole grid (the transforms' normalization).
    pub fn global_len(&self) -> usize {
        self.eng.nx * self.eng.ny * self.eng.nz
    }

    /// The processes the transforms are split over (`None`: one, without transposes).
    pub fn comm(&self) -> Option<&Comm> {
        self.split.as_ref().map(|s| &*s.comm)
    }

    /// Forward real-to-complex transform of one real field (unnormalized) into `out`
    /// (length [`FftEngine::complex_len`]). Panics if a length is wrong.
    pub fn forward(&mut self, input: &[f64], out: &mut [C64]) {
        assert_eq!(input.len(), self.real_len(), "fft: input length");
        assert_eq!(out.len(), self.complex_len(), "fft: output length");
        match &mut self.split {
            None => self.eng.forward_xy(&self.pool, input, out),
            Some(sp) => {
                self.eng.forward_xy(&self.pool, input, &mut sp.planes);
                sp.transpose
                    .forward(&sp.comm, &sp.planes, &mut sp.packed, out);
            }
        }
        self.eng.z(&self.pool, false, None, out);
    }

    /// Inverse complex-to-real transform normalized by `1/(nx ny nz)`. With `src`, the
    /// spectrum is read from it and `work` is the scratch (`src` is kept); without, `work`
    /// holds the spectrum and is destroyed. Panics if a length is wrong.
    pub fn inverse(&mut self, mut src: Option<&[C64]>, work: &mut [C64], out: &mut [f64]) {
        assert_eq!(work.len(), self.complex_len(), "fft: input length");
        assert_eq!(out.len(), self.real_len(), "fft: output length");
        if self.eng.z_plans.is_some() {
            self.eng.z(&self.pool, true, src.take(), work);
        }
        match &mut self.split {
            None => self.eng.inverse_xy(&self.pool, src, work, out),
            Some(sp) => {
                if let Some(s) = src {
                    // 2D is never split (Slabs::new), so the z pass consumed `src`.
                    work.copy_from_slice(s);
                }
                sp.transpose
                    .backward(&sp.comm, work, &mut sp.packed, &mut sp.planes);
                self.eng.inverse_xy(&self.pool, None, &mut sp.planes, out);
            }
        }
    }
}

/// The FFT floor of `grid`: seconds for 3 real-to-complex and 3 complex-to-real transforms of
/// the grid with this engine (the transforms of one velocity solve of a 3D vector field), the
/// median of `reps` repetitions. `tumble bench` divides its step time by it, so a figure
/// can be compared across machines and days.
pub fn floor_seconds(grid: &Grid, reps: usize) -> f64 {
    let mut eng = FftEngine::new(grid);
    let real: Vec<Vec<f64>> = (0..3)
        .map(|c| {
            (0..eng.real_len())
                .map(|i| ((i * 7 + c * 13) % 17) as f64 - 8.0)
                .collect()
        })
        .collect();
    let mut out = vec![vec![0.0; eng.real_len()]; 3];
    let mut spec = vec![vec![C64::default(); eng.complex_len()]; 3];
    let mut times: Vec<f64> = (0..reps.max(1) + 1)
        .map(|_| {
            let t0 = std::time::Instant::now();
            for c in 0..3 {
                eng.forward(&real[c], &mut spec[c]);
            }
            for c in 0..3 {
                eng.inverse(None, &mut spec[c], &mut out[c]);
            }
            t0.elapsed().as_secs_f64()
        })
        .collect();
    // The first repetition warms the caches and the thread pool; it is not counted.
    times.remove(0);
    times.sort_by(f64::total_cmp);
    times[times.len() / 2]
}
