//! Integrals over a body's patch on the grid: volume, centroid, momentum, angular momentum and
//! inertia of a weight χ (the rigid velocity of paper eq. 7, the mass properties of a body in
//! vacuum, the excess momentum of the pressure projection), several weights in one pass, with
//! the per-row partial sums preallocated in [`BodySums`]. Sums are taken per patch row and added
//! in order, per z-plane of the patch first and then plane after plane
//! ([`crate::parallel::PlaneSums`]), so they depend neither on the number of threads nor on the
//! number of processes: split, each process sums the rows of its slab's planes and every
//! process gets the same moments, those of one process, bit for bit.

use crate::base::grid::Grid;
use crate::bodies::{Body, GridPatch, RigidState, kinematic_velocity};
use crate::parallel::{Comm, Decomposition, PlaneSums};
use bevy_ecs::prelude::*;
use glam::{DMat3, DVec3};
use rayon::prelude::*;
use std::sync::Arc;

/// Per-row partial sums (preallocated, so a step allocates nothing), and the processes whose
/// sums make a whole body's when the grid is split.
#[derive(Resource, Debug, Clone)]
pub struct BodySums {
    rows: Vec<[f64; 16]>,
    planes: PlaneSums,
    comm: Option<Arc<Comm>>,
}

impl BodySums {
    /// The row buffer (for other systems that sum over patches).
    pub fn rows_mut(&mut self) -> &mut [[f64; 16]] {
        &mut self.rows
    }

    /// Room for the largest patch of the grid of `world` (ny nz rows), [`MAX_WEIGHTS`] weights
    /// a row; when split (its [`Decomposition`]) the patch sums are added over the processes,
    /// and since on a slab a moving body's patch may span its whole box along z
    /// ([`GridPatch::holds`]), the rows have room for a moving body's longest box too
    /// ([`crate::bodies::box_span`]).
    pub fn of_world(world: &World) -> Self {
        let grid = world.resource::<Grid>();
        let split = world.get_resource::<Decomposition>();
        let mut planes = grid.n[2];
        if grid.is_slab()
            && let Some(mut q) = world.try_query::<(&Body, &crate::bodies::BodyShape)>()
        {
            for (body, shape) in q.iter(world) {
                if let (false, Some(n)) = (
                    body.is_static(),
                    crate::bodies::box_span(&shape.level_set, grid.h),
                ) {
                    planes = planes.max(n.min(grid.nz_whole));
                }
            }
        }
        BodySums {
            rows: vec![[0.0; 16]; MAX_WEIGHTS * grid.n[1] * planes],
            planes: PlaneSums::new(grid.nz_whole, MAX_WEIGHTS * 16),
            comm: split.map(|d| d.comm.clone()),
        }
    }

    /// The sum over `patch` (the whole body's, on every process) of the rows' values in the
    /// row buffer, `per` entries a patch row of this process (`out.len()` of them): the rows of
    /// each plane in order, then the planes of the whole box in order ([`PlaneSums`]). Every
    /// process must call it, for the same bodies in the same order.
    pub fn patch_total(&mut self, grid: &Grid, patch: &GridPatch, out: &mut [[f64; 16]]) {
        let per = out.len();
        let (dy, dz) = (patch.dims[1], patch.dims[2]);
        let whole_dz = patch.whole.1[2];
        // The box's plane of this process's patch plane 0.
        let c0 = (patch.lo[2] - patch.whole.0[2]) as usize;
        self.planes.clear(whole_dz);
        if !patch.is_empty() {
            for c in (0..dz).filter(|&c| patch.holds(grid, c)) {
                let p = self.planes.plane_mut(c0 + c);
                for b in 0..dy {
                    let r = b + dy * c;
                    for (q, row) in self.rows[r * per..(r + 1) * per].iter().enumerate() {
                        for (t, v) in p[q * 16..(q + 1) * 16].iter_mut().zip(row) {
                            *t += v;
                        }
                    }
                }
            }
        }
        let mut flat = [0.0; MAX_WEIGHTS * 16];
        self.planes
            .total(self.comm.as_deref(), whole_dz, &mut flat[..per * 16]);
        for (q, o) in out.iter_mut().enumerate() {
            o.copy_from_slice(&flat[q * 16..(q + 1) * 16]);
        }
    }
}

/// The weight w = λΔtχ/(1 + λΔtχ) with which the implicit penalization (`ldt` = λΔt) moves
/// a node of characteristic function `chi` to the rigid velocity: the region a body's rigid
/// velocity is averaged over.
#[inline]
pub fn penalized_weight(ldt: f64, chi: f64) -> f64 {
    ldt * chi / (1.0 + ldt * chi)
}

/// The rigid region of a body that moves by Newton-Euler (`systems/noslip.rs`): the nodes
/// inside its surface, φ > 0, each wholly (weight 1). Its penalization, its rigid velocity's
/// mean and its no-slip use this one weight, whatever the smoothing band.
#[inline]
pub fn rigid_region(phi: f64) -> f64 {
    if phi > 0.0 { 1.0 } else { 0.0 }
}

/// J⁻¹: in 2D about z only (the x and y rows are zero); zero where J is singular (an empty
/// body).
pub fn inertia_inverse(dim: usize, j: DMat3) -> DMat3 {
    if dim == 2 {
        let jz = j.z_axis.z;
        DMat3::from_diagonal(DVec3::new(0.0, 0.0, if jz > 0.0 { 1.0 / jz } else { 0.0 }))
    } else if j.determinant().abs() > 0.0 {
        j.inverse()
    } else {
        DMat3::ZERO
    }
}

/// J⁻¹ l ([`inertia_inverse`]; in 2D by one division).
pub fn solve_inertia(dim: usize, j: DMat3, l: DVec3) -> DVec3 {
    if dim == 2 {
        let jz = j.z_axis.z;
        DVec3::new(0.0, 0.0, if jz > 0.0 { l.z / jz } else { 0.0 })
    } else {
        inertia_inverse(dim, j) * l
    }
}

/// The integrals of one weight over a patch: (volume, centroid, ∫χu, ∫χ r×u, J), with r
/// measured from the centroid.
pub type Moments = (f64, DVec3, DVec3, DVec3, DMat3);

/// The most weights [`integrate_n`] takes in one pass.
pub const MAX_WEIGHTS: usize = 5;

/// Integrals of a weight χ over a body's patch: (volume, centroid, ∫χu, ∫χ r×u, J), with r
/// measured from the centroid; all zero when ∫χ is.
pub fn integrate(
    grid: &Grid,
    patch: &GridPatch,
    center: DVec3,
    u: &[Vec<f64>],
    sums: &mut BodySums,
    weight: impl Fn(f64, f64, usize) -> f64 + Sync,
) -> Moments {
    integrate_n::<1>(grid, patch, center, u, sums, |c, p, g| [weight(c, p, g)])[0]
}

/// The integrals of `N` weights (at most [`MAX_WEIGHTS`]) in one pass over the patch, each
/// as [`integrate`] would give it alone (the same sums in the same order, bit for bit).
pub fn integrate_n<const N: usize>(
    grid: &Grid,
    patch: &GridPatch,
    center: DVec3,
    u: &[Vec<f64>],
    sums: &mut BodySums,
    weight: impl Fn(f64, f64, usize) -> [f64; N] + Sync,
) -> [Moments; N] {
    const ZERO: [f64; 16] = [0.0; 16];
    let [dx, dy, _] = patch.dims;
    let empty = (0.0, center, DVec3::ZERO, DVec3::ZERO, DMat3::ZERO);
    assert!(
        N <= MAX_WEIGHTS,
        "integrate_n: at most {MAX_WEIGHTS} weights"
    );
    let dv = grid.cell_volume();
    let dim = grid.dim;
    let rows = if patch.is_empty() {
        0
    } else {
        patch.len() / dx
    };
    sums.rows[..N * rows]
        .par_chunks_mut(N)
        .enumerate()
        .for_each(|(r, acc)| {
            let (b, c) = (r % dy, r / dy);
            let mut s = [ZERO; N];
            // (A plane of the patch held by another process adds zero here.)
            if !patch.holds(grid, c) {
                acc.copy_from_slice(&s);
                return;
            }
            let nodes = patch.row(grid, b, c);
            for a in 0..dx {
                // The wrapped node for the fields, its image next to the body (unwrapped
                // position) for the moments.
                let g = nodes.index(a);
                let w = weight(patch.chi[r * dx + a], patch.phi[r * dx + a], g);
                if w.iter().all(|&chi| chi == 0.0) {
                    continue;
                }
                let p = patch.pos(grid, a, b, c);
                let rv = DVec3::new(p[0], p[1], p[2]) - center;
                let uv = DVec3::new(u[0][g], u[1][g], if dim == 3 { u[2][g] } else { 0.0 });
                let m = rv.cross(uv);
                for (s, &chi) in s.iter_mut().zip(&w) {
                    if chi == 0.0 {
                        continue;
                    }
                    s[0] += chi;
                    s[1] += chi * uv.x;
                    s[2] += chi * uv.y;
                    s[3] += chi * uv.z;
                    s[4] += chi * m.x;
                    s[5] += chi * m.y;
                    s[6] += chi * m.z;
                    s[7] += chi * rv.x * rv.x;
                    s[8] += chi * rv.y * rv.y;
                    s[9] += chi * rv.z * rv.z;
                    s[10] += chi * rv.x * rv.y;
                    s[11] += chi * rv.x * rv.z;
                    s[12] += chi * rv.y * rv.z;
                    s[13] += chi * rv.x;
                    s[14] += chi * rv.y;
                    s[15] += chi * rv.z;
                }
            }
            acc.copy_from_slice(&s);
        });
    let mut t = [ZERO; N];
    sums.patch_total(grid, patch, &mut t);
    std::array::from_fn(|q| moments(center, dv, t[q]).unwrap_or(empty))
}

/// The moments from the weight's sums `t` (before the cell volume `dv`); `None` when ∫χ is 0.
fn moments(center: DVec3, dv: f64, mut t: [f64; 16]) -> Option<Moments> {
    for v in &mut t {
        *v *= dv;
    }
    let vol = t[0];
    // (A weight may be negative: the mass of a body lighter than the fluid beyond the
    // fluid's.)
    if vol == 0.0 {
        return None;
    }
    // Shift the moments from the centre c to the centroid x_G = c + d.
    let d = DVec3::new(t[13], t[14], t[15]) / vol;
    let mom = DVec3::new(t[1], t[2], t[3]);
    let ang = DVec3::new(t[4], t[5], t[6]) - d.cross(mom);
    let (xx, yy, zz) = (
        t[7] - vol * d.x * d.x,
        t[8] - vol * d.y * d.y,
        t[9] - vol * d.z * d.z,
    );
    let (xy, xz, yz) = (
        t[10] - vol * d.x * d.y,
        t[11] - vol * d.x * d.z,
        t[12] - vol * d.y * d.z,
    );
    let j = DMat3::from_cols(
        DVec3::new(yy + zz, -xy, -xz),
        DVec3::new(-xy, xx + zz, -yz),
        DVec3::new(-xz, -yz, xx + yy),
    );
    Some((vol, center + d, mom, ang, j))
}

/// Volume, centroid and inertia of a moving body from χ (the body the density field
/// carries) into `state`; a kinematic body also takes its prescribed velocities. Returns
/// whether the body's velocity is still to be found (a dynamic body with a non-empty χ).
pub fn mass_properties(
    grid: &Grid,
    patch: &GridPatch,
    u: &[Vec<f64>],
    sums: &mut BodySums,
    body: &Body,
    t: f64,
    state: &mut RigidState,
) -> bool {
    let (vol, centroid, _, _, j) = integrate(grid, patch, state.center, u, sums, |c, _, _| c);
    state.volume = vol;
    state.centroid = centroid;
    state.inertia = j;
    if let Some((v, w)) = kinematic_velocity(&body.kind, t) {
        state.velocity = v;
        state.angular_velocity = w;
        return false;
    }
    vol > 0.0
}
