//! Spectral operators on the periodic grid, built on the FFT engine ([`crate::solvers::fft`]):
//! velocity from vorticity (Poisson, Biot-Savart in Fourier space), implicit diffusion with the
//! spectral Laplacian's symbol, the divergence cleaning of a 3D vorticity, and the inverse of
//! the second-order difference Laplacian (the variable-density pressure solve's preconditioner);
//! and the centred-difference curl that turns a velocity increment into vorticity
//! ([`curl_add`]: the penalization's and the pressure projection's). Complex fields use the
//! layout described in [`crate::solvers::fft`].

use std::ops::Range;
use std::sync::Arc;

use crate::base::grid::Grid;
use crate::parallel::{Comm, Decomposition, DecompositionError, Halo, PlaneSums};
use crate::solvers::fft::{C64, FftEngine, wavenumber};
use rayon::prelude::*;

/// max over nodes of |ω| (the Euclidean norm of the components at a node); a maximum, so it
/// does not depend on the thread count.
pub fn max_norm(omega: &[Vec<f64>]) -> f64 {
    let n = omega[0].len();
    (0..n)
        .into_par_iter()
        .with_min_len(4096)
        .map(|i| omega.iter().map(|c| c[i] * c[i]).sum::<f64>())
        .reduce(|| 0.0, f64::max)
        .sqrt()
}

/// Wavenumber tables.
struct Tables {
    /// Spectral wavenumbers per axis (x: `0..=nx/2`; y, z: signed); z is `[0]` in 2D.
    k: [Vec<f64>; 3],
    /// The same with the Nyquist wavenumber set to 0 (for odd derivatives).
    kd: [Vec<f64>; 3],
    /// Symbol of minus the second-order difference along each axis: `(2 - 2 cos(k h)) / h^2`.
    lap: [Vec<f64>; 3],
    /// Symbol of minus the second derivative along each axis, `k^2` (Nyquist included).
    k2: [Vec<f64>; 3],
    /// `k sin(k h) / h` along each axis: the centred first difference's symbol times the
    /// spectral one (the numerator of [`Spectral::forcing_velocity`]'s transfer function).
    ks: [Vec<f64>; 3],
}

impl Tables {
    /// The tables of the spectrum's y rows `rows` (all of them unless the engine is split).
    fn new(grid: &Grid, nxh: usize, rows: Range<usize>) -> Self {
        let h = grid.h;
        let dim = if grid.n[2] == 1 { 2 } else { 3 };
        let ranges = [0..nxh, rows, 0..if dim == 3 { grid.n[2] } else { 1 }];
        let mk = |a: usize, zero_nyq: bool| -> Vec<f64> {
            let n = grid.n[a];
            let len = n as f64 * h;
            ranges[a]
                .clone()
                .map(|m| {
                    if (a == 2 && dim == 2) || (zero_nyq && 2 * m == n) {
                        0.0
                    } else {
                        wavenumber(m, n, len)
                    }
                })
                .collect()
        };
        let k = [mk(0, false), mk(1, false), mk(2, false)];
        let kd = [mk(0, true), mk(1, true), mk(2, true)];
        let lap = std::array::from_fn(|a| {
            k[a].iter()
                .map(|&ka| (2.0 - 2.0 * (ka * h).cos()) / (h * h))
                .collect()
        });
        let k2 = std::array::from_fn(|a| k[a].iter().map(|&ka| ka * ka).collect());
        let ks = std::array::from_fn(|a| k[a].iter().map(|&ka| ka * (ka * h).sin() / h).collect());
        Tables { k, kd, lap, k2, ks }
    }
}

/// Periodic spectral Poisson / diffusion solver for one [`Grid`]; a resource.
///
/// Owns its plans, scratch pools and the cached vorticity spectrum (see [`Spectral::diffuse`] and
/// [`Spectral::velocity`]). Complex fields use the layout described in the module docs.
#[derive(bevy_ecs::prelude::Resource)]
pub struct Spectral {
    fft: FftEngine,
    tab: Tables,
    /// 2 or 3.
    dim: usize,
    /// Cached vorticity spectrum, one buffer per component.
    omega_hat: Vec<Vec<C64>>,
    /// Complex work buffer for non-destructive inverse transforms and velocity spectra.
    work: Vec<C64>,
    /// Version `omega_hat` corresponds to.
    cached: Option<u64>,
    /// The Nyquist wavenumber of one axis, π/h.
    k_nyquist: f64,
    /// Per row of the spectrum: the kinetic energy the last damped diffusion removed (summed
    /// in row order afterwards, so the total does not depend on the thread count).
    removed_rows: Vec<f64>,
    /// Per y row of the whole spectrum, the removed energy of its modes (summed over z in
    /// order), added in row order: the same on any number of processes ([`PlaneSums`]).
    removed_by_y: PlaneSums,
    /// Spectrum of the last forcing response, one buffer per velocity component (empty until
    /// [`Spectral::reserve_forcing`]).
    force_hat: Vec<Vec<C64>>,
    /// The vorticity spectrum of a combination of forcings, Σ α_i ∇×(m R f_i)
    /// ([`Spectral::forcing_accumulate`]), one buffer per vorticity component.
    force_sum_hat: Vec<Vec<C64>>,
}

/// The damping of the top of the spectrum that [`Spectral::diffuse`] applies with the
/// diffusion: every mode is multiplied by exp(-`strength` (|k|/k_N)^(2`order`)), with k_N = π/h
/// the Nyquist wavenumber of one axis. `strength` is the rate at |k| = k_N times the step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TopDamping {
    /// Rate at |k| = k_N times the time step (dimensionless); 0 switches the damping off.
    pub strength: f64,
    /// Half the power of |k|/k_N (the damping grows like |k|^(2 order)).
    pub order: i32,
}

impl TopDamping {
    /// No damping.
    pub const NONE: TopDamping = TopDamping {
        strength: 0.0,
        order: 1,
    };
}

impl Spectral {
    /// Plans for this grid (2D when `grid.n[2] == 1`) and allocates everything needed later.
    ///
    /// Panics if a node count is 0 or `h` is not positive and finite.
    pub fn new(grid: &Grid) -> Self {
        Self::with_engine(grid, FftEngine::new(grid))
    }

    /// The solver of this process's share of `grid` split over the processes of `comm`
    /// ([`FftEngine::split`]): real fields are this process's z-planes, the spectrum its y rows.
    /// Every operator works on the share and gives the whole grid's result there; the energies
    /// it returns are the whole grid's, the same on every process.
    pub fn split(grid: &Grid, comm: Arc<Comm>) -> Result<Self, DecompositionError> {
        Ok(Self::with_engine(grid, FftEngine::split(grid, comm)?))
    }

    /// The solver of a world's grid: [`Spectral::new`] on one process, [`Spectral::split`] of
    /// the whole grid when the run is split (`grid` is then this process's slab).
    pub fn of_grid(grid: &Grid, split: Option<&Decomposition>) -> Self {
        match split {
            Some(d) => Self::split(&grid.whole(), d.comm.clone())
                .expect("spectral: the decomposition was checked when it was made"),
            None => Self::new(grid),
        }
    }

    fn with_engine(grid: &Grid, fft: FftEngine) -> Self {
        let dim = if grid.n[2] == 1 { 2 } else { 3 };
        let (_, nxh) = fft.dims();
        let clen = fft.complex_len();
        let ncomp = if dim == 2 { 1 } else { 3 };
        Spectral {
            tab: Tables::new(grid, nxh, fft.spectral_rows()),
            fft,
            dim,
            omega_hat: (0..ncomp).map(|_| vec![C64::default(); clen]).collect(),
            work: vec![C64::default(); clen],
            cached: None,
            k_nyquist: std::f64::consts::PI / grid.h,
            removed_rows: vec![0.0; clen / nxh],
            removed_by_y: PlaneSums::new(grid.n[1], 1),
            force_hat: Vec::new(),
            force_sum_hat: Vec::new(),
        }
    }

    /// Allocates the buffers of [`Spectral::forcing_velocity`] (once, before the first step).
    pub fn reserve_forcing(&mut self) {
        if self.force_hat.len() != self.dim {
            let clen = self.fft.complex_len();
            self.force_hat = (0..self.dim).map(|_| vec![C64::default(); clen]).collect();
            let ncomp = self.omega_hat.len();
            self.force_sum_hat = (0..ncomp).map(|_| vec![C64::default(); clen]).collect();
        }
    }

    /// Starts a new combination of forcings (see [`Spectral::forcing_accumulate`]) at zero.
    pub fn forcing_reset(&mut self) {
        for c in self.force_sum_hat.iter_mut() {
            c.par_iter_mut().for_each(|v| *v = C64::default());
        }
    }

    /// Adds `alpha` times the vorticity of the last [`Spectral::forcing_velocity`]'s force to
    /// the combination that [`Spectral::forcing_vorticity_add`] adds to ω: a solver that
    /// combines the responses of its iterations applies the sum once, without transforming
    /// the summed force again.
    pub fn forcing_accumulate(&mut self, alpha: f64) {
        for (acc, wh) in self.force_sum_hat.iter_mut().zip(self.force_hat.iter()) {
            acc.par_iter_mut()
                .zip(wh.par_iter())
                .for_each(|(a, w)| *a += *w * alpha);
        }
    }

    /// The velocity a force field makes within an implicit diffusion step: u = BS(∇×(m R f)),
    /// with R = (1 + νΔt|k|²)⁻¹ the diffusion's resolvent, m(k) = k·k̃ / |k|² (k̃ = sin(k h)/h)
    /// the transfer function of the centred curl through which the penalization's forcing
    /// enters the vorticity (eq. 27), against the spectral curl, and ∇× and BS (the velocity
    /// from the vorticity, [`Spectral::velocity`]) spectral: û = (|k|² f̂ - k (k·f̂)) m R / |k|²
    /// (k with the Nyquist wavenumber zeroed in the numerators, as in `velocity`). Each factor
    /// is symmetric positive and they commute, so f ↦ u is symmetric positive semi-definite
    /// (conjugate gradients apply: `systems/noslip.rs`). The mean (k = 0) is dropped: in the
    /// periodic box the mean flow is the background's. `f` and `u` have `dim` components; the
    /// vorticity's spectrum is kept for [`Spectral::forcing_vorticity_add`].
    ///
    /// Panics if [`Spectral::reserve_forcing`] was not called or a shape is wrong.
    pub fn forcing_velocity(&mut self, f: &[Vec<f64>], nu_dt: f64, u: &mut [Vec<f64>]) {
        assert_eq!(
            self.force_hat.len(),
            self.dim,
            "spectral: reserve_forcing first"
        );
        self.check_field(f, self.dim, "forcing");
        self.check_field(u, self.dim, "velocity");
        for (fc, fh) in f.iter().zip(self.force_hat.iter_mut()) {
            self.fft.forward(fc, fh);
        }
        let ([_, ny, _], nxh) = self.fft.dims();
        let [lx, ly, lz] = &self.tab.k2;
        let [sx, sy, sz] = &self.tab.ks;
        let [dx, dy, dz] = &self.tab.kd;
        // m R, 0 at k = 0.
        let scale = |i: usize, j: usize, k: usize| {
            let k2 = lx[i] + ly[j] + lz[k];
            if k2 == 0.0 {
                0.0
            } else {
                (sx[i] + sy[j] + sz[k]) / (k2 * (1.0 + nu_dt * k2))
            }
        };
        let i_ = |v: C64| C64::new(-v.im, v.re);
        // In place: the force's spectrum becomes the vorticity's, ω̂ = i k × (m R f̂).
        let (first, rest) = self.force_hat.split_at_mut(1);
        let (second, third) = rest.split_at_mut(1);
        if self.dim == 3 {
            first[0]
                .par_chunks_mut(nxh)
                .zip(second[0].par_chunks_mut(nxh))
                .zip(third[0].par_chunks_mut(nxh))
                .enumerate()
                .for_each(|(r, ((a, b), c))| {
                    let (j, k) = (r % ny, r / ny);
                    for i in 0..nxh {
                        let s = scale(i, j, k);
                        let (p, q, t) = (dx[i], dy[j], dz[k]);
                        let (x, y, z) = (a[i] * s, b[i] * s, c[i] * s);
                        a[i] = i_(z * q - y * t);
                        b[i] = i_(x * t - z * p);
                        c[i] = i_(y * p - x * q);
                    }
                });
        } else {
            first[0]
                .par_chunks_mut(nxh)
                .zip(second[0].par_chunks_mut(nxh))
                .enumerate()
                .for_each(|(r, (a, b))| {
                    let j = r % ny;
                    for i in 0..nxh {
                        let s = scale(i, j, 0);
                        a[i] = i_((b[i] * dx[i] - a[i] * dy[j]) * s);
                        b[i] = C64::default();
                    }
                });
        }
        // u = BS(ω).
        let ncomp = self.omega_hat.len();
        for (c, uc) in u.iter_mut().enumerate() {
            velocity_hat(
                &self.tab,
                self.fft.dims(),
                &self.force_hat[..ncomp],
                c,
                &mut self.work,
            );
            self.fft.inverse(None, &mut self.work, uc);
        }
    }

    /// ω += Σ α_i ∇×(m R f_i) for the forces f_i accumulated since [`Spectral::forcing_reset`]
    /// ([`Spectral::forcing_accumulate`]; spectral curl), whose velocity is Σ α_i u_i of the
    /// u_i [`Spectral::forcing_velocity`] returned: the velocity of the new vorticity is the
    /// old one's plus that sum exactly. `scratch` is one real field. Forgets the cached
    /// vorticity spectrum.
    pub fn forcing_vorticity_add(&mut self, omega: &mut [Vec<f64>], scratch: &mut [f64]) {
        assert_eq!(
            self.force_hat.len(),
            self.dim,
            "spectral: reserve_forcing first"
        );
        self.check_field(omega, self.omega_hat.len(), "omega");
        for (oc, wh) in omega.iter_mut().zip(self.force_sum_hat.iter()) {
            self.fft.inverse(Some(wh), &mut self.work, scratch);
            oc.par_iter_mut()
                .zip(scratch.par_iter())
                .for_each(|(o, s)| *o += s);
        }
        self.cached = None;
    }

    /// Number of complex coefficients of one real field: `(nx/2 + 1) * ny * nz`, or this
    /// process's share when split.
    pub fn complex_len(&self) -> usize {
        self.fft.complex_len()
    }

    /// Number of nodes of one real field: `nx * ny * nz`, or this process's planes' share when
    /// split.
    pub fn real_len(&self) -> usize {
        self.fft.real_len()
    }

    /// The version the cached vorticity spectrum corresponds to, if any.
    pub fn cached_version(&self) -> Option<u64> {
        self.cached
    }

    /// The cached vorticity spectrum (one buffer per component; see [`Spectral::diffuse`]).
    pub fn omega_hat(&self) -> &[Vec<C64>] {
        &self.omega_hat
    }

    /// Forgets the cached vorticity spectrum (the next [`Spectral::velocity`] transforms afresh).
    pub fn invalidate(&mut self) {
        self.cached = None;
    }

    /// Forward real-to-complex 2D/3D transform of one real field (unnormalized) into `out`
    /// (length [`Spectral::complex_len`]).
    ///
    /// Panics if a length is wrong.
    pub fn forward(&mut self, input: &[f64], out: &mut [C64]) {
        assert_eq!(input.len(), self.real_len(), "spectral: input length");
        assert_eq!(out.len(), self.complex_len(), "spectral: output length");
        self.fft.forward(input, out);
    }

    /// Inverse complex-to-real transform, normalized by `1/(nx ny nz)` so that
    /// `inverse(forward(f)) == f` to round-off. `input` is used as scratch (destroyed). The
    /// imaginary parts the real field cannot carry (x index 0 and, for even `nx`, `nx/2`, after
    /// the y/z transforms) are dropped.
    ///
    /// Panics if a length is wrong.
    pub fn inverse(&mut self, input: &mut [C64], out: &mut [f64]) {
        assert_eq!(input.len(), self.complex_len(), "spectral: input length");
        assert_eq!(out.len(), self.real_len(), "spectral: output length");
        self.fft.inverse(None, input, out);
    }

    /// Solves `-Lap_h x = rhs` for the zero-mean `x`, with `Lap_h` the classical 5/7-point
    /// Laplacian (the constant-coefficient operator; the preconditioner of the
    /// variable-density pressure solve). The mean of `rhs` is ignored. Uses the solver's own
    /// complex work buffer; the cached vorticity spectrum is untouched.
    ///
    /// Panics if a length is wrong.
    pub fn solve_laplacian(&mut self, rhs: &[f64], x: &mut [f64]) {
        assert_eq!(rhs.len(), self.real_len(), "spectral: rhs length");
        assert_eq!(x.len(), self.real_len(), "spectral: solution length");
        self.fft.forward(rhs, &mut self.work);
        let ([_, ny, _], nxh) = self.fft.dims();
        let [lx, ly, lz] = &self.tab.lap;
        self.work
            .par_chunks_mut(nxh)
            .enumerate()
            .for_each(|(r, row)| {
                let (j, k) = (r % ny, r / ny);
                let lyz = ly[j] + lz[k];
                for (i, z) in row.iter_mut().enumerate() {
                    let l = lx[i] + lyz;
                    *z = if l > 0.0 { *z / l } else { C64::default() };
                }
            });
        self.fft.inverse(None, &mut self.work, x);
    }

    /// Checks the component count and lengths of a vector field.
    fn check_field(&self, f: &[Vec<f64>], comps: usize, what: &str) {
        assert_eq!(
            f.len(),
            comps,
            "spectral: {what} must have {comps} components"
        );
        for c in f {
            assert_eq!(
                c.len(),
                self.real_len(),
                "spectral: {what} component length"
            );
        }
    }

    /// Forward-transforms every component of `omega` into the cache.
    fn load_omega(&mut self, omega: &[Vec<f64>]) {
        for (w, wh) in omega.iter().zip(self.omega_hat.iter_mut()) {
            self.fft.forward(w, wh);
        }
    }

    /// Inverse-transforms the cache back into `omega` (the cache is kept).
    fn store_omega(&mut self, omega: &mut [Vec<f64>]) {
        for (w, wh) in omega.iter_mut().zip(self.omega_hat.iter()) {
            self.fft.inverse(Some(wh), &mut self.work, w);
        }
    }

    /// Multiplies the cached spectrum by `1/(1 + nu_dt |k|^2)` and by the top damping's
    /// factor (each skipped when zero) and, in 3D, removes its divergence. Returns the kinetic
    /// energy per unit volume the damping removed (0 without damping).
    fn filter_omega(&mut self, nu_dt: f64, damp: TopDamping) -> f64 {
        let ([nx, ny, _], nxh) = self.fft.dims();
        let [lx, ly, lz] = &self.tab.k2;
        let [kx, ky, kz] = &self.tab.kd;
        let diffuse = nu_dt != 0.0;
        let damped = damp.strength != 0.0;
        if !diffuse && !damped && self.omega_hat.len() == 1 {
            return 0.0;
        }
        let kn2 = self.k_nyquist * self.k_nyquist;
        // The factor of a mode of |k|^2 = l: the implicit diffusion and the damping.
        let factor = |l: f64| -> (f64, f64) {
            let fd = if diffuse {
                1.0 / (1.0 + nu_dt * l)
            } else {
                1.0
            };
            let fs = if damped {
                (-damp.strength * (l / kn2).powi(damp.order)).exp()
            } else {
                1.0
            };
            (fd, fs)
        };
        // The energy the damping factor fs takes from a divergence-free mode of vorticity
        // |w|^2, |k|^2 = l and |k_d|^2 = kd2 (the first-derivative wavenumbers, Nyquist
        // components 0): the velocity solve makes |u_hat|^2 = |k_d x w|^2 / l^2 =
        // kd2 |w|^2 / l^2, of which 1 - fs^2 goes.
        let mode_energy = |w2: f64, kd2: f64, l: f64, fs: f64| kd2 * w2 / (l * l) * (1.0 - fs * fs);
        // Modes of the half spectrum stand for themselves and their conjugates, except the
        // x index 0 and (even nx) nx/2.
        let weight = |i: usize| if i == 0 || 2 * i == nx { 1.0 } else { 2.0 };
        // Energy per unit volume of a velocity mode: 1/2 |u_hat|^2 / N^2.
        let n_total = self.fft.global_len() as f64;
        let e_norm = 0.5 / (n_total * n_total);
        let removed = &mut self.removed_rows;
        match &mut self.omega_hat[..] {
            [w] => {
                w.par_chunks_mut(nxh)
                    .zip(removed.par_iter_mut())
                    .enumerate()
                    .for_each(|(r, (row, out))| {
                        let lyz = ly[r % ny] + lz[r / ny];
                        let kyz2 = ky[r % ny] * ky[r % ny];
                        let mut sum = 0.0;
                        for (i, (v, &lxi)) in row.iter_mut().zip(lx).enumerate() {
                            let l = lxi + lyz;
                            let (fd, fs) = factor(l);
                            *v *= fd;
                            if damped {
                                if l > 0.0 {
                                    let kd2 = kx[i] * kx[i] + kyz2;
                                    sum += weight(i) * mode_energy(v.norm_sqr(), kd2, l, fs);
                                }
                                *v *= fs;
                            }
                        }
                        *out = sum;
                    });
            }
            [a, b, c] => {
                a.par_chunks_mut(nxh)
                    .zip(b.par_chunks_mut(nxh))
                    .zip(c.par_chunks_mut(nxh))
                    .zip(removed.par_iter_mut())
                    .enumerate()
                    .for_each(|(r, (((ra, rb), rc), out))| {
                        let (j, k) = (r % ny, r / ny);
                        let lyz = ly[j] + lz[k];
                        let (kyj, kzk) = (ky[j], kz[k]);
                        let mut sum = 0.0;
                        for i in 0..nxh {
                            let mut w = [ra[i], rb[i], rc[i]];
                            let l = lx[i] + lyz;
                            let (fd, fs) = factor(l);
                            if diffuse {
                                w = w.map(|v| v * fd);
                            }
                            let kv = [kx[i], kyj, kzk];
                            let k2 = kv[0] * kv[0] + kv[1] * kv[1] + kv[2] * kv[2];
                            if k2 > 0.0 {
                                let d = (w[0] * kv[0] + w[1] * kv[1] + w[2] * kv[2]) / k2;
                                for a in 0..3 {
                                    w[a] -= d * kv[a];
                                }
                            }
                            if damped {
                                if l > 0.0 {
                                    let w2 = w[0].norm_sqr() + w[1].norm_sqr() + w[2].norm_sqr();
                                    sum += weight(i) * mode_energy(w2, k2, l, fs);
                                }
                                w = w.map(|v| v * fs);
                            }
                            ra[i] = w[0];
                            rb[i] = w[1];
                            rc[i] = w[2];
                        }
                        *out = sum;
                    });
            }
            _ => unreachable!("omega_hat has 1 or 3 components"),
        }
        if damped {
            e_norm * self.removed_total()
        } else {
            0.0
        }
    }

    /// Diffusion and (3D) divergence cleaning of the vorticity, in place.
    ///
    /// `omega` has 1 component (2D, scalar) or 3 (3D), each `grid.len()` long. Every component
    /// is forward-transformed and multiplied by `1/(1 + nu_dt |k|^2)`, with the spectral
    /// wavenumbers (Nyquist included): implicit Euler, `(I - nu dt Lap) omega_new = omega`, with
    /// the periodic grid's spectral Laplacian, the operator the velocity solve inverts, and by
    /// the factor of `damp` (see [`TopDamping`]). In 3D
    /// the divergence is then removed,
    /// `w_hat -= k (k . w_hat) / |k|^2`, with spectral `k` whose Nyquist components are 0
    /// (modes whose such `k` vanishes, among them `k = 0`, are untouched). The result is
    /// transformed back into `omega` and its spectrum stays cached as version `version`.
    /// Returns the kinetic energy per unit volume the damping removed, ½⟨|u|²⟩ of the velocity
    /// the diffused vorticity would have had without it minus that of the result (0 when
    /// `damp.strength` is 0).
    ///
    /// Panics if `omega` has the wrong shape.
    pub fn diffuse(
        &mut self,
        omega: &mut [Vec<f64>],
        nu_dt: f64,
        damp: TopDamping,
        version: u64,
    ) -> f64 {
        self.check_field(omega, self.omega_hat.len(), "omega");
        self.load_omega(omega);
        let removed = self.filter_omega(nu_dt, damp);
        self.store_omega(omega);
        self.cached = Some(version);
        removed
    }

    /// Implicit diffusion and top damping of each component of `f` on its own, in place:
    /// every mode multiplied by `1/(1 + nu_dt |k|^2)` and by the factor of `damp`, no
    /// divergence removed (the momentum form's velocity, whose projection is the variable-density
    /// one). Returns the kinetic energy per unit volume (½⟨|f|²⟩, unit density) the damping
    /// removed. The cached vorticity spectrum is dropped.
    ///
    /// Panics if a component's length is wrong.
    pub fn diffuse_components(&mut self, f: &mut [Vec<f64>], nu_dt: f64, damp: TopDamping) -> f64 {
        self.cached = None;
        let diffuse = nu_dt != 0.0;
        let damped = damp.strength != 0.0;
        if !diffuse && !damped {
            return 0.0;
        }
        let ([nx, ny, _], nxh) = self.fft.dims();
        let kn2 = self.k_nyquist * self.k_nyquist;
        let weight = |i: usize| if i == 0 || 2 * i == nx { 1.0 } else { 2.0 };
        let n_total = self.fft.global_len() as f64;
        let e_norm = 0.5 / (n_total * n_total);
        let mut removed = 0.0;
        for c in f.iter_mut() {
            assert_eq!(c.len(), self.real_len(), "spectral: component length");
            self.fft.forward(c, &mut self.work);
            let [lx, ly, lz] = &self.tab.k2;
            self.work
                .par_chunks_mut(nxh)
                .zip(self.removed_rows.par_iter_mut())
                .enumerate()
                .for_each(|(r, (row, out))| {
                    let lyz = ly[r % ny] + lz[r / ny];
                    let mut sum = 0.0;
                    for (i, (v, &lxi)) in row.iter_mut().zip(lx).enumerate() {
                        let l = lxi + lyz;
                        if diffuse {
                            *v *= 1.0 / (1.0 + nu_dt * l);
                        }
                        if damped {
                            let fs = (-damp.strength * (l / kn2).powi(damp.order)).exp();
                            sum += weight(i) * v.norm_sqr() * (1.0 - fs * fs);
                            *v *= fs;
                        }
                    }
                    *out = sum;
                });
            if damped {
                removed += e_norm * self.removed_total();
            }
            self.fft.inverse(None, &mut self.work, c);
        }
        removed
    }

    /// The sum of `removed_rows` over the whole spectrum: per y row over z in order, then the
    /// rows in order (every process holds whole y rows of the spectrum).
    fn removed_total(&mut self) -> f64 {
        let rows = self.fft.spectral_rows();
        let nyl = rows.len();
        let ny = self.removed_by_y.len();
        self.removed_by_y.clear(ny);
        for jl in 0..nyl {
            let mut s = 0.0;
            for v in self.removed_rows.iter().skip(jl).step_by(nyl) {
                s += v;
            }
            self.removed_by_y.plane_mut(rows.start + jl)[0] = s;
        }
        self.removed_by_y.total_one(self.fft.comm(), ny)
    }

    /// Velocity from vorticity: `Lap psi = -omega`, `u = curl psi`, spectrally exact.
    ///
    /// If the cached vorticity spectrum was made for `version` it is used as is (no forward
    /// transform, `omega` is not read). Otherwise `omega` is forward-transformed, in 3D
    /// divergence-cleaned (as in [`Spectral::diffuse`], without diffusion) and the cleaned
    /// vorticity written back into `omega` (in 2D `omega` is left untouched); the spectrum is then
    /// cached for `version`.
    ///
    /// 2D: `u_hat = i ky w_hat / k^2`, `v_hat = -i kx w_hat / k^2`; 3D: `u_hat = i k x w_hat / |k|^2`,
    /// with spectral `k = 2 pi m / L` per axis (`L = n h`), the Nyquist component set to 0 in the
    /// numerator (first derivatives) but kept in `|k|^2`. The `k = 0` mode of `u` is
    /// `background` (a uniform velocity). `u` has `grid.dim` components, each `grid.len()` long.
    ///
    /// Panics if `omega` or `u` has the wrong shape.
    pub fn velocity(
        &mut self,
        omega: &mut [Vec<f64>],
        version: u64,
        background: [f64; 3],
        u: &mut [Vec<f64>],
    ) {
        self.check_field(omega, self.omega_hat.len(), "omega");
        self.check_field(u, self.dim, "u");
        if self.cached != Some(version) {
            self.load_omega(omega);
            if self.dim == 3 {
                self.filter_omega(0.0, TopDamping::NONE);
                self.store_omega(omega);
            }
            self.cached = Some(version);
        }
        let n_total = self.fft.global_len() as f64;
        // The mean (k = 0) sits first in the spectrum of the process that holds y row 0.
        let holds_mean = self.fft.spectral_rows().start == 0;
        for (c, uc) in u.iter_mut().enumerate() {
            self.velocity_hat(c);
            if holds_mean {
                self.work[0] = C64::new(background[c] * n_total, 0.0);
            }
            self.fft.inverse(None, &mut self.work, uc);
        }
    }

    /// Writes the spectrum of velocity component `c` (without its mean) into `self.work`.
    fn velocity_hat(&mut self, c: usize) {
        velocity_hat(
            &self.tab,
            self.fft.dims(),
            &self.omega_hat,
            c,
            &mut self.work,
        );
    }
}

/// The spectrum of velocity component `c` (without its mean) of the vorticity spectrum `wh`
/// (1 component in 2D, 3 in 3D), û = i k × ω̂ / |k|², into `work`.
fn velocity_hat(
    tab: &Tables,
    ([_, ny, _], nxh): ([usize; 3], usize),
    wh: &[Vec<C64>],
    c: usize,
    work: &mut [C64],
) {
    let [kx, ky, kz] = &tab.k;
    let [dx, dy, dz] = &tab.kd;
    // i * z / k2
    let i_over = |z: C64, k2: f64| {
        if k2 > 0.0 {
            C64::new(-z.im, z.re) / k2
        } else {
            C64::default()
        }
    };
    work.par_chunks_mut(nxh).enumerate().for_each(|(r, row)| {
        let (j, k) = (r % ny, r / ny);
        let k2yz = ky[j] * ky[j] + kz[k] * kz[k];
        let off = r * nxh;
        match wh.len() {
            1 => {
                let w = &wh[0][off..off + nxh];
                for i in 0..nxh {
                    let k2 = kx[i] * kx[i] + k2yz;
                    let num = if c == 0 { w[i] * dy[j] } else { -w[i] * dx[i] };
                    row[i] = i_over(num, k2);
                }
            }
            _ => {
                let (a, b, d) = (
                    &wh[0][off..off + nxh],
                    &wh[1][off..off + nxh],
                    &wh[2][off..off + nxh],
                );
                let (kyj, kzk) = (dy[j], dz[k]);
                for i in 0..nxh {
                    let k2 = kx[i] * kx[i] + k2yz;
                    let kxi = dx[i];
                    let cross = match c {
                        0 => d[i] * kyj - b[i] * kzk,
                        1 => a[i] * kzk - d[i] * kxi,
                        _ => b[i] * kxi - a[i] * kyj,
                    };
                    row[i] = i_over(cross, k2);
                }
            }
        }
    });
}

/// The halo [`curl_add`] reads on a slab (one plane a side of three components), shared by the
/// systems that add a curl; empty on one process.
#[derive(bevy_ecs::prelude::Resource, Debug, Clone, Default)]
pub struct CurlHalo(pub Option<Halo>);

impl CurlHalo {
    /// The halo of `grid`'s slab when split.
    pub fn of_grid(grid: &Grid, split: Option<&Decomposition>) -> Self {
        CurlHalo(split.map(|d| Halo::new(grid, d, 1, 3)))
    }

    /// The halo, if split.
    pub fn get(&mut self) -> Option<&mut Halo> {
        self.0.as_mut()
    }
}

/// ω += ∇×a by centred differences (periodic): the vorticity of a velocity increment `a`
/// (the penalization's, `systems/penalization.rs`, or the pressure projection's,
/// `systems/pressure.rs`). On a slab, `halo` (one plane a side, three components) is filled with
/// the neighbours' planes of `a` first.
pub fn curl_add(grid: &Grid, a: &[Vec<f64>], omega: &mut [Vec<f64>], halo: Option<&mut Halo>) {
    let [nx, ny, _] = grid.n;
    let inv2h = 0.5 / grid.h;
    let plane = nx * ny;
    let nb = crate::base::grid::periodic_neighbours;
    if grid.dim == 2 {
        omega[0]
            .par_chunks_mut(nx)
            .enumerate()
            .for_each(|(j, row)| {
                let (jm, jp) = nb(j, ny);
                for i in 0..nx {
                    let (im, ip) = nb(i, nx);
                    let dvy_dx = (a[1][ip + nx * j] - a[1][im + nx * j]) * inv2h;
                    let dux_dy = (a[0][i + nx * jp] - a[0][i + nx * jm]) * inv2h;
                    row[i] += dvy_dx - dux_dy;
                }
            });
        return;
    }
    let halo = halo.map(|h| {
        h.fill(a);
        &*h
    });
    let (o0, rest) = omega.split_at_mut(1);
    let (o1, o2) = rest.split_at_mut(1);
    o0[0]
        .par_chunks_mut(plane)
        .zip(o1[0].par_chunks_mut(plane))
        .zip(o2[0].par_chunks_mut(plane))
        .enumerate()
        .for_each(|(k, ((w0, w1), w2))| {
            let k = k as isize;
            let at = |c: usize, k: isize| crate::parallel::halo::plane(grid, &a[c], halo, c, k);
            let [a0, a1, a2] = [0, 1, 2].map(|c| at(c, k));
            let below = [0, 1, 2].map(|c| at(c, k - 1));
            let above = [0, 1, 2].map(|c| at(c, k + 1));
            for j in 0..ny {
                let (jm, jp) = nb(j, ny);
                for i in 0..nx {
                    let (im, ip) = nb(i, nx);
                    let l = i + nx * j;
                    let dx = |f: &[f64]| (f[ip + nx * j] - f[im + nx * j]) * inv2h;
                    let dy = |f: &[f64]| (f[i + nx * jp] - f[i + nx * jm]) * inv2h;
                    let dz = |c: usize| (above[c][l] - below[c][l]) * inv2h;
                    w0[l] += dy(a2) - dz(1);
                    w1[l] += dz(0) - dx(a2);
                    w2[l] += dx(a1) - dy(a0);
                }
            }
        });
}
