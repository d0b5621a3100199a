//! # level_sets: each body's φ on the grid from its rigid motion (paper section 3.1, eqs. 24-25)
//!
//! A body's level set is never advected: φ_i(x, t) = φ_i⁰(X(0; x, t)), where the backward
//! characteristic of the rigid motion is X = Rᵀ (x - c) in the body frame (R the accumulated
//! rotation, c the centre). φ_i⁰ is the reference signed distance held on the body's local grid
//! and read by trilinear interpolation, so φ_i stays a signed distance for all time and errors
//! do not accumulate. Only the nodes of the box the body (plus a band) can reach are sampled;
//! χ_i = H_ε(φ_i) is the smoothed Heaviside of half-width ε = `interface_cells` h.
//!
//! The box is periodic, for the moving bodies as for the flow: a dynamic or kinematic body's
//! box of nodes is not clipped at the grid's ends but continues past them, its nodes mapping
//! to the grid modulo n (`GridPatch`), so a body straddling the boundary is sampled whole,
//! each node at its image next to the body (φ is evaluated at the unwrapped position, and every
//! consumer takes lever arms from it). `rigid_update` keeps the centre inside the box. A
//! static body (a wall) keeps the clipped box it always had (walls that fill the box's edge
//! would otherwise put their band on the far side); one whose solid reaches past the box's
//! last nodes stops the run.

use crate::base::fields::{Failure, Params, SimTime};
use crate::base::grid::Grid;
use crate::bodies::{Body, BodyShape, GridPatch, RigidState, heaviside, patch_pos};
use bevy_ecs::prelude::*;
use glam::DVec3;
use rayon::prelude::*;

/// The level-set system.
pub fn level_sets(
    grid: Res<Grid>,
    params: Res<Params>,
    time: Res<SimTime>,
    mut bodies: Query<(&Body, &RigidState, &BodyShape, &mut GridPatch)>,
    mut failure: ResMut<Failure>,
) {
    let eps = params.numerics.interface_cells * grid.h;
    for (body, state, shape, mut patch) in &mut bodies {
        if body.is_static() && patch.sampled {
            continue;
        }
        // A moving body's centre is kept in the box by `rigid_update` (wrapped by a box
        // length when it leaves it); only a non-finite one is left outside.
        if !state.center.is_finite() && failure.reason.is_none() {
            failure.reason = Some(format!(
                "body `{}` left the domain at step {} (t = {:.6}): centre {:?}",
                body.name,
                time.step,
                time.t,
                &state.center.to_array()[..grid.dim]
            ));
        }
        let offset = wall_offset(&params, body, grid.h);
        let sampled = sample(&grid, body, state, shape, &mut patch, eps, offset);
        if let Err(SampleError(axis)) = sampled
            && failure.reason.is_none()
        {
            failure.reason = Some(format!(
                "static body `{}` reaches outside the periodic box along {} at step {} \
                 (t = {:.6}): centre {:?}; a static body's level set is clipped at the box's \
                 last nodes, not wrapped around (moving bodies are); move it inside or \
                 enlarge the domain",
                body.name,
                ["x", "y", "z"][axis],
                time.step,
                time.t,
                &state.center.to_array()[..grid.dim],
            ));
        }
    }
}

/// Sample every body's level set before the first step, so that the state at t = 0 (its
/// snapshot) holds the bodies. Nothing is checked here (the first step's [`level_sets`]
/// checks, and reports, where the bodies are) and static bodies are left to be sampled again
/// by it, as they were before this system existed: the step's results are unchanged.
pub fn level_sets_init(
    grid: Res<Grid>,
    params: Res<Params>,
    mut bodies: Query<(&Body, &RigidState, &BodyShape, &mut GridPatch)>,
) {
    let eps = params.numerics.interface_cells * grid.h;
    for (body, state, shape, mut patch) in &mut bodies {
        let offset = wall_offset(&params, body, grid.h);
        // Errors are reported by the first step's `level_sets`.
        let _ = sample(&grid, body, state, shape, &mut patch, eps, offset);
        patch.sampled = false;
    }
}

/// How far into a body (length) its mask χ = H_ε(φ - δ) is moved: δ =
/// `numerics.penalization_offset` h for a static or kinematic body, whose rigid region then
/// ends at its surface for every system that reads χ (the penalization, the free surface's
/// projection and gravity, the kernels' choice); 0 for a dynamic body, whose χ is also its
/// density and mass (`systems/penalization.rs`).
pub fn wall_offset(params: &Params, body: &Body, h: f64) -> f64 {
    if body.is_dynamic() {
        0.0
    } else {
        params.numerics.penalization_offset * h
    }
}

/// How far beyond a body (length) its patch reaches: χ = H_ε(φ) is non-zero for φ > -ε, and the
/// centred differences of ρ in the baroclinic term read one node further, where the node's
/// owner must be known; one more cell is margin. The reference level set keeps a wider band
/// (`bodies::band`, for the contact range), which the flow-grid systems do not need: with
/// 200 spheres of 3.2 cells the patches shrink about five-fold.
pub fn patch_reach(grid: &Grid, eps: f64) -> f64 {
    eps + 2.0 * grid.h
}

/// The world-space box of a body's shape bounds `(blo, bhi)` (body frame, grown by the
/// reference band) shrunk by `shrink`, in its current pose.
fn world_box(
    grid: &Grid,
    state: &RigidState,
    (blo, bhi): (DVec3, DVec3),
    shrink: f64,
) -> (DVec3, DVec3) {
    let (mut blo, mut bhi) = (blo + DVec3::splat(shrink), bhi - DVec3::splat(shrink));
    if grid.dim == 2 {
        (blo.z, bhi.z) = (0.0, 0.0);
    }
    let mut wlo = DVec3::splat(f64::INFINITY);
    let mut whi = DVec3::splat(f64::NEG_INFINITY);
    for corner in 0..8 {
        let p = DVec3::new(
            if corner & 1 == 0 { blo.x } else { bhi.x },
            if corner & 2 == 0 { blo.y } else { bhi.y },
            if corner & 4 == 0 { blo.z } else { bhi.z },
        );
        let w = state.center + state.orientation * p;
        wlo = wlo.min(w);
        whi = whi.max(w);
    }
    (wlo, whi)
}

/// Sides of a patch box cut off by the grid: `[axis][0]` below node 0, `[axis][1]` above
/// node n - 1.
pub type Clipped = [[bool; 2]; 3];

/// The box of grid nodes a body can affect in its current pose: its shape's bounds grown by
/// `reach` (length), and which sides were clipped. With `wrap` (a moving body) the box is not
/// clipped: its first node may lie outside the grid, its nodes map to the grid modulo `n`
/// (the box is periodic), and a box longer than `n` nodes along an axis is cut to `n`, the
/// extra nodes taken evenly off both ends (the scene checks keep a moving body shorter than
/// the box by its smoothed edges, so only band nodes go). Without it (a static body: walls
/// keep the clipped band they always had) the box is clipped to the grid's nodes.
pub fn patch_box(
    grid: &Grid,
    state: &RigidState,
    shape: &BodyShape,
    reach: f64,
    wrap: bool,
) -> ([isize; 3], [usize; 3], Clipped) {
    let mut clipped = [[false; 2]; 3];
    let mut lo = [0isize; 3];
    let mut dims = [1usize; 3];
    match shape.level_set.bounds() {
        None => {
            dims = grid.n;
        }
        Some(bounds) => {
            // `bounds` are the shape's grown by the reference band; grow by `reach` instead.
            let shrink = (shape.level_set.band() - reach).max(0.0);
            let (wlo, whi) = world_box(grid, state, bounds, shrink);
            for a in 0..grid.dim {
                let n = grid.n[a];
                let f0 = ((wlo[a] - grid.origin[a]) / grid.h).ceil();
                let i1 = ((whi[a] - grid.origin[a]) / grid.h).floor();
                if wrap && f0.is_finite() && i1.is_finite() {
                    let (f0, i1) = (f0 as isize, i1 as isize);
                    let len = (i1 - f0 + 1).max(0) as usize;
                    let cut = len.saturating_sub(n);
                    lo[a] = f0 + (cut / 2) as isize;
                    dims[a] = len - cut;
                    continue;
                }
                clipped[a] = [f0 < 0.0, i1 > (n - 1) as f64];
                let i0 = f0.max(0.0) as usize;
                let i1 = if i1 < 0.0 {
                    0
                } else {
                    (i1 as usize).min(n - 1)
                };
                lo[a] = i0.min(n - 1) as isize;
                dims[a] = if i1 >= i0 { i1 - i0 + 1 } else { 0 };
            }
        }
    }
    (lo, dims, clipped)
}

/// Sample φ and χ of one body on its patch. Returns the first axis along which the solid
/// itself (φ > 0) reaches a clipped side of the patch: a part of the body then lies beyond
/// the box's last nodes and would be lost (the patch is clipped, not wrapped). The band
/// around a body (interface half-width and margin, a few cells) may be clipped: in the
/// bundled scenes that happens where a body touches a wall that fills the box's edge.
pub fn sample(
    grid: &Grid,
    body: &Body,
    state: &RigidState,
    shape: &BodyShape,
    patch: &mut GridPatch,
    eps: f64,
    offset: f64,
) -> Result<(), SampleError> {
    let wrap = !body.is_static();
    let whole = grid.whole();
    let (lo, dims, clipped) = patch_box(&whole, state, shape, patch_reach(grid, eps), wrap);
    patch.whole = (lo, dims);
    let outside = solid_on_clipped_side(&whole, state, shape, (lo, dims), &clipped);
    let (lo, dims) = slab_part(grid, lo, dims);
    patch.lo = lo;
    patch.dims = dims;
    let len = dims[0] * dims[1] * dims[2];
    // Within the capacity reserved at spawn: no allocation in a step.
    patch.phi.resize(len, 0.0);
    patch.chi.resize(len, 0.0);
    let inv = state.orientation.inverse();
    let c = state.center;
    let ls = &shape.level_set;
    let row = dims[0].max(1);
    let GridPatch { phi, chi, .. } = patch;
    phi.par_chunks_mut(row)
        .zip(chi.par_chunks_mut(row))
        .enumerate()
        .for_each(|(r, (phi, chi))| {
            let (b, cc) = (r % dims[1], r / dims[1]);
            for a in 0..dims[0] {
                let p = patch_pos(grid, lo, a, b, cc);
                let x = DVec3::new(p[0], p[1], p[2]);
                let v = ls.phi(inv * (x - c));
                phi[a] = v;
                chi[a] = heaviside(v - offset, eps);
            }
        });
    patch.sampled = true;
    match outside {
        Some(axis) => Err(SampleError(axis)),
        None => Ok(()),
    }
}

/// The solid of a static body reaches the box's boundary along this axis, on a side where its
/// patch is clipped: a part of the body would be lost.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SampleError(pub usize);

/// The part of a box of the whole grid (first node `lo`, unwrapped, `dims` nodes) that lies in
/// `grid`'s slab: its first node (at the image next to the box) and node counts, all of the
/// box unless `grid` is a slab. A box that wraps round the periodic z axis may hold both ends of
/// the slab but not its middle (a box nearly as long as the whole grid): then its part is the
/// whole box, whose planes between the two ends are other processes' ([`GridPatch::holds`]).
pub fn slab_part(grid: &Grid, lo: [isize; 3], dims: [usize; 3]) -> ([isize; 3], [usize; 3]) {
    if !grid.is_slab() || dims[2] == 0 {
        return (lo, dims);
    }
    let (nzw, nz, d) = (grid.nz_whole as isize, grid.n[2] as isize, dims[2] as isize);
    // The box's offset of the slab's first plane (at its image at or after the box's start);
    // the slab's planes are the offsets s..s + nz, wrapping past nzw.
    let s = (grid.k0 as isize - lo[2]).rem_euclid(nzw);
    let first = (s < d).then(|| (s, (s + nz).min(d)));
    let wrapped = (s + nz > nzw).then(|| (0, (s + nz - nzw).min(d)));
    let (c0, c1) = match (first, wrapped) {
        (Some(_), Some(b)) if b.1 > 0 => return (lo, dims),
        (Some(a), _) => a,
        (None, Some(b)) => b,
        (None, None) => (0, 0),
    };
    let mut lo = lo;
    let mut dims = dims;
    lo[2] += c0;
    dims[2] = (c1 - c0).max(0) as usize;
    (lo, dims)
}

/// The first axis along which the solid (φ > 0) reaches the periodic box's boundary on a
/// clipped side of the patch: below, node 0 lies on the boundary (`origin`); above, the
/// boundary is the node one past the last (`origin + n h`, the image of node 0), where φ is
/// evaluated directly. A body that reaches into the last cell but not to the boundary is
/// inside the box (only its band wraps around, see [`sample`]).
fn solid_on_clipped_side(
    grid: &Grid,
    state: &RigidState,
    shape: &BodyShape,
    (lo, dims): ([isize; 3], [usize; 3]),
    clipped: &Clipped,
) -> Option<usize> {
    let inv = state.orientation.inverse();
    (0..grid.dim).find(|&a| {
        (0..2).any(|side| {
            if !clipped[a][side] || dims[a] == 0 {
                return false;
            }
            let (b, c) = ((a + 1) % 3, (a + 2) % 3);
            (0..dims[b]).any(|ib| {
                (0..dims[c]).any(|ic| {
                    let mut ijk = [0; 3];
                    ijk[b] = ib;
                    ijk[c] = ic;
                    // On the side below the patch's first node is node 0 (the patch
                    // starts there: `patch_pos` of it, bit for bit); above, the boundary.
                    let p = if side == 0 {
                        patch_pos(grid, lo, ijk[0], ijk[1], ijk[2])
                    } else {
                        let mut x = [0.0; 3];
                        for d in 0..3 {
                            x[d] = grid.origin[d] + (lo[d] + ijk[d] as isize) as f64 * grid.h;
                        }
                        x[a] = grid.origin[a] + grid.n[a] as f64 * grid.h;
                        if grid.dim == 2 {
                            x[2] = 0.0;
                        }
                        x
                    };
                    let w = DVec3::new(p[0], p[1], p[2]);
                    shape.level_set.phi(inv * (w - state.center)) > 0.0
                })
            })
        })
    })
}

/// Samples each body's level set on the grid (every run with bodies).
#[derive(Debug, Clone, Copy, Default)]
pub struct LevelSetsPlugin;

impl crate::schedule::Plugin for LevelSetsPlugin {
    fn name(&self) -> &'static str {
        "level_sets"
    }

    fn build(&self, ctx: &mut crate::schedule::PluginContext) -> anyhow::Result<()> {
        use crate::schedule::PhysicsSet;
        if ctx.mode().has_bodies() {
            ctx.add_system(PhysicsSet::LevelSets, "level_sets", level_sets)?;
            ctx.add_startup_system_in(PhysicsSet::LevelSets, "level_sets_init", level_sets_init)?;
        }
        Ok(())
    }
}
