//! Lagrangian markers on a body's surface, fixed in the body frame, and the regularised delta
//! that couples them to the grid (Uhlmann, J. Comput. Phys. 209, 2005; Roma, Peskin & Berger,
//! J. Comput. Phys. 153, 1999).
//!
//! The no-slip of a Newton-Euler body (`systems/noslip.rs`) is held at these points: the wall
//! is then where the surface is, whatever the body's position against the grid (on the
//! staircase of nodes inside the surface a settling sphere at 3.2 cells per radius moved at
//! 0.974 to 1.007 of Hasimoto's velocity depending on its offset against the grid), and the
//! markers, being material, carry the last step's force with the body into the next step
//! however fast it moves. They lie on the level φ = r h inside the surface (φ > 0 inside),
//! r = [`RETRACTION`] + [`RETRACTION_CURVATURE`] H h, [`SPACING`] grid spacings apart; a
//! marker's force is spread to the grid, and the velocity read at it, with Roma's three-point
//! kernel, whose weights sum to one and whose first moment vanishes.
//!
//! Why the retraction: the kernel spreads the force over three cells, so a wall held at the
//! surface itself acts as if the body were larger (Breugem, J. Comput. Phys. 231, 2012,
//! retracts his markers by 0.3 h for the same reason). The retraction that gives a settling
//! sphere (3D) or disk (2D) in a periodic box Hasimoto's and Sangani & Acrivos's velocities
//! falls from about 0.56 h at 3.2 cells per radius to 0.45-0.47 h at 9.6, the same function
//! of h/R in 2D and 3D: r = 0.40 + 0.50 H h, H the mean of the principal curvatures (1/R on
//! both), fits both (docs/numerics.md, "The no-slip at surface markers"); with it the sphere
//! moves at 0.989-1.005 of Hasimoto's from 3.2 to 6.4 cells per radius and the disk at
//! 0.990-1.000 from 3.2 to 9.6 (calibrated with markers h apart). They are 1.5 h apart: the
//! conjugate gradients of the no-slip converge much faster than with markers h apart
//! (neighbouring markers' forces nearly cancel in the response; 0.7 h apart the solve stalled
//! at 1-3% of the slip), and the settling speeds moved by less than 0.2%.

use crate::base::grid::Grid;
use crate::bodies::levelset::LocalLevelSet;
use bevy_ecs::prelude::Component;
use glam::DVec3;

/// Roma's three-point kernel φ(r), r in grid spacings; zero beyond |r| = 1.5.
#[inline]
pub fn roma(r: f64) -> f64 {
    let a = r.abs();
    if a <= 0.5 {
        (1.0 + (1.0 - 3.0 * a * a).sqrt()) / 3.0
    } else if a <= 1.5 {
        let b = 1.0 - a;
        (5.0 - 3.0 * a - (1.0 - 3.0 * b * b).max(0.0).sqrt()) / 6.0
    } else {
        0.0
    }
}

/// The three nodes along one axis that a point at `x` (in grid spacings from the origin)
/// touches, from the first, and their weights.
#[inline]
pub fn roma_weights(x: f64) -> (i64, [f64; 3]) {
    let c = x.round();
    let first = c as i64 - 1;
    let mut w = [0.0; 3];
    for (k, wk) in w.iter_mut().enumerate() {
        *wk = roma(x - (first + k as i64) as f64);
    }
    // The weights sum to one exactly in exact arithmetic; remove the rounding.
    let s: f64 = w.iter().sum();
    for wk in w.iter_mut() {
        *wk /= s;
    }
    (first, w)
}

/// Body-frame markers on the level φ = `retraction` · `h` of `level_set`, about `spacing`
/// apart: candidates on a lattice of spacing h/4 within a quarter-spacing of that level are
/// moved onto it (two Newton steps along ∇φ), then taken in lattice order, each kept if no
/// marker kept before lies closer than `spacing` (a deterministic Poisson-disk thinning). An
/// unbounded shape has none.
pub fn surface_markers(
    level_set: &LocalLevelSet,
    h: f64,
    dim: usize,
    retraction: impl Fn(f64) -> f64,
    spacing: f64,
) -> Vec<DVec3> {
    let Some((lo, hi)) = level_set.bounds() else {
        return Vec::new();
    };
    let s = 0.25 * h;
    let n = |a: usize| {
        if a < dim {
            ((hi[a] - lo[a]) / s).ceil() as usize + 1
        } else {
            1
        }
    };
    let (nx, ny, nz) = (n(0), n(1), n(2));
    let mut kept: Vec<DVec3> = Vec::new();
    // Kept markers by cell of side `spacing` (a marker's neighbours are in the 3^d cells
    // around it).
    let mut cells: std::collections::HashMap<[i64; 3], Vec<usize>> =
        std::collections::HashMap::new();
    let cell = |p: DVec3| {
        [
            (p.x / spacing).floor() as i64,
            (p.y / spacing).floor() as i64,
            if dim == 3 {
                (p.z / spacing).floor() as i64
            } else {
                0
            },
        ]
    };
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let mut p = DVec3::new(
                    lo.x + i as f64 * s,
                    lo.y + j as f64 * s,
                    if dim == 3 { lo.z + k as f64 * s } else { 0.0 },
                );
                let phi = level_set.phi(p);
                if !(-0.5 * s..=1.5 * h).contains(&phi) {
                    continue;
                }
                // The surface's mean curvature (the mean of the principal curvatures) at the
                // nearest surface point, and the retraction there.
                let target = retraction(mean_curvature(level_set, p, h, dim) * h) * h;
                if (phi - target).abs() > 0.5 * s {
                    continue;
                }
                for _ in 0..2 {
                    let (v, g) = level_set.phi_grad(p, 1e-3 * h, dim);
                    let g2 = g.length_squared();
                    if g2 <= 0.0 {
                        break;
                    }
                    p += (target - v) / g2 * g;
                }
                if (level_set.phi(p) - target).abs() > 0.05 * h {
                    continue;
                }
                let c = cell(p);
                let mut near = false;
                'search: for dz in if dim == 3 { -1..=1 } else { 0..=0 } {
                    for dy in -1..=1 {
                        for dx in -1..=1 {
                            if let Some(list) = cells.get(&[c[0] + dx, c[1] + dy, c[2] + dz]) {
                                for &m in list {
                                    if (kept[m] - p).length() < spacing {
                                        near = true;
                                        break 'search;
                                    }
                                }
                            }
                        }
                    }
                }
                if !near {
                    cells.entry(c).or_default().push(kept.len());
                    kept.push(p);
                }
            }
        }
    }
    kept
}

/// The markers' retraction into the body, in grid spacings, on a flat wall (see the module
/// doc).
pub const RETRACTION: f64 = 0.40;

/// The retraction's growth with the surface's mean curvature H (the mean of the principal
/// curvatures): r = [`RETRACTION`] + [`RETRACTION_CURVATURE`] H h, H h clamped to ±0.5.
pub const RETRACTION_CURVATURE: f64 = 0.50;

/// H at the surface point nearest `p` (two Newton steps to φ = 0), from the Laplacian of φ
/// with a step of h: for a signed distance, -Δφ / (d - 1) on the surface (1/R on a sphere and
/// on a circle).
fn mean_curvature(level_set: &LocalLevelSet, mut p: DVec3, h: f64, dim: usize) -> f64 {
    for _ in 0..2 {
        let (v, g) = level_set.phi_grad(p, 1e-3 * h, dim);
        let g2 = g.length_squared();
        if g2 <= 0.0 {
            break;
        }
        p -= v / g2 * g;
    }
    let c = level_set.phi(p);
    let mut lap = 0.0;
    for a in 0..dim {
        let mut e = DVec3::ZERO;
        e[a] = h;
        lap += (level_set.phi(p + e) - 2.0 * c + level_set.phi(p - e)) / (h * h);
    }
    -lap / (dim as f64 - 1.0)
}

/// The markers' spacing, in grid spacings.
pub const SPACING: f64 = 1.5;

/// A Newton-Euler body's markers, in its frame (relative to `RigidState::center`, before
/// the rotation `RigidState::orientation`), made once when the body is made.
#[derive(Component, Debug, Clone, Default)]
pub struct Markers {
    /// The points, body frame.
    pub points: Vec<DVec3>,
}

impl Markers {
    /// The markers of a body whose reference level set is `level_set` on a grid of spacing
    /// `h` ([`RETRACTION`], [`SPACING`]).
    pub fn new(level_set: &LocalLevelSet, h: f64, dim: usize) -> Self {
        let r = |hh: f64| RETRACTION + RETRACTION_CURVATURE * hh.clamp(-0.5, 0.5);
        Markers {
            points: surface_markers(level_set, h, dim, r, SPACING * h),
        }
    }
}

/// A marker's stencil on the grid: the first node of the kernel's three along each axis
/// (unwrapped: the grid is periodic) and the weights.
#[derive(Debug, Clone, Copy, Default)]
pub struct Stencil {
    first: [i64; 3],
    w: [[f64; 3]; 3],
}

impl Stencil {
    /// The stencil of a point at `pos` on `grid`.
    #[inline]
    pub fn at(grid: &Grid, pos: DVec3) -> Self {
        let mut st = Stencil {
            first: [-1; 3],
            w: [[0.0, 1.0, 0.0]; 3],
        };
        for a in 0..grid.dim {
            let (f, w) = roma_weights((pos[a] - grid.origin[a]) / grid.h);
            st.first[a] = f;
            st.w[a] = w;
        }
        st
    }

    /// Visits the stencil's nodes (wrapped into the periodic grid) with their weights; on a
    /// slab, only the nodes of its planes (the other processes visit the rest).
    #[inline]
    pub fn visit(&self, grid: &Grid, mut f: impl FnMut(usize, f64)) {
        let wrap = |i: i64, n: usize| i.rem_euclid(n as i64) as usize;
        let kz = if grid.dim == 3 { 3 } else { 1 };
        for c in 0..kz {
            let (k, wz) = if grid.dim == 3 {
                (wrap(self.first[2] + c as i64, grid.nz_whole), self.w[2][c])
            } else {
                (0, 1.0)
            };
            if k < grid.k0 || k >= grid.k0 + grid.n[2] {
                continue;
            }
            let k = k - grid.k0;
            for b in 0..3 {
                let j = wrap(self.first[1] + b as i64, grid.n[1]);
                let wyz = self.w[1][b] * wz;
                for a in 0..3 {
                    let i = wrap(self.first[0] + a as i64, grid.n[0]);
                    f(grid.idx(i, j, k), self.w[0][a] * wyz);
                }
            }
        }
    }

    /// The value of a vector field (`dim` components) at the point, the kernel's planes along z
    /// added in order ([`Stencil::interpolate_planes`]).
    #[inline]
    pub fn interpolate(&self, grid: &Grid, field: &[Vec<f64>]) -> DVec3 {
        let [a, b, c] = self.interpolate_planes(grid, field);
        a + b + c
    }

    /// The kernel's sum over each of its planes along z (one in 2D, the others zero); on a
    /// slab, zero for the planes it does not hold. Added over the processes (each plane's is
    /// one process's: exact) and then in order, it is [`Stencil::interpolate`] on one process,
    /// bit for bit.
    #[inline]
    pub fn interpolate_planes(&self, grid: &Grid, field: &[Vec<f64>]) -> [DVec3; 3] {
        let mut v = [DVec3::ZERO; 3];
        let plane = grid.plane();
        self.visit(grid, |g, w| {
            let c = self.plane_of(grid, g / plane);
            for (q, f) in field.iter().enumerate() {
                v[c][q] += w * f[g];
            }
        });
        v
    }

    /// The kernel's plane (0..3) of the slab's plane `k`.
    #[inline]
    fn plane_of(&self, grid: &Grid, k: usize) -> usize {
        if grid.dim == 2 {
            return 0;
        }
        let kw = (k + grid.k0) as i64;
        (kw - self.first[2]).rem_euclid(grid.nz_whole as i64) as usize
    }
}
