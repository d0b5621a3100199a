//! # free_surface: the liquid's level set, carried by the flow (paper section 5)
//!
//! The air/water interface is the zero level of φ_w (> 0 in the liquid), which moves with the
//! flow (not rigidly):
//!
//!   ∂φ_w/∂t + u·∇φ_w = 0,
//!
//! and sets the density of the fluid phases, ρ_P = ρ_gas + (ρ_liquid - ρ_gas) H_ε(φ_w), with the
//! bodies' smoothed Heaviside (half-width ε = `interface_cells` h). The density system adds the
//! bodies (eq. 19): ρ = (1 - Σχ_i) ρ_P + Σ ρ_i χ_i, and the variable-density projection
//! (`pressure`) makes the baroclinic vorticity of gravity and inertia on the interface.
//!
//! * Transport: φ_w rides the particles of the momentum form (`transport`), which carry it
//!   with the mass and the momentum and remesh all three with the same weights, pushed by the
//!   velocity of this step's projection: the interface and the flow advance as a symplectic
//!   Euler pair, so an interface oscillation neither grows nor decays from the time stepping.
//!   This system does not move it again.
//! * Redistancing: φ_w is kept a signed distance within the band (|φ_w| ≤ `band`, clipped
//!   beyond) by pseudo-time iterations of ∂φ/∂τ + sgn(φ⁰)(|∇φ| - 1) = 0 (Sussman, Smereka &
//!   Osher 1994) with Godunov's upwind |∇φ|, and the subcell fix of Russo & Smereka
//!   (J. Comput. Phys. 163 (2000)) at the nodes next to the interface: there φ is relaxed to
//!   D = φ⁰/|∇φ⁰|, the distance the linear interpolation of φ⁰ gives, so the zero level does not
//!   move. Two iterations per step; many at the start. In the step, the gas side of the
//!   smoothed band (-ε < φ⁰ < 0) keeps its φ_w: there the density H_ε(φ_w) is that of a light
//!   fringe that carries the gas's velocity, often several times the liquid's next to it, and
//!   a redistancing that restores the band's width where the flow has squeezed it makes those
//!   nodes heavier under that velocity, turning the gas's momentum into the liquid's. A
//!   collapsing water column (`column-collapse`, h = a/32) gained energy from t ≈ 1.7 and blew
//!   up at 1:1000 (t = 2.05), and at 1:100 its energy rose from 2.86 to 4.13 by t = 2.3; with
//!   the gas side held, the energy of both only falls and both run to t = 2.3. Holding the
//!   whole band did the same for the column but moved a standing wave's frequency by 0.8%
//!   (1:10, h = 1/64); holding the gas side changes it by less than 0.1%.
//! * Walls: inside a static body and in the band the penalization holds at rest with it
//!   (φ_s > -ε, where χ_s > 0), φ_w is not the flow's but the fluid's continued along the
//!   wall's normal from one cell beyond that band, φ_w(x) = φ_w(x + (φ_s(x) + ε + h) n) with
//!   φ_s the walls' signed distance and n its outward normal (a 90° contact angle), set after
//!   the transport and the redistancing. Carried by the flow, the band's φ_w stood still with
//!   the fluid there (no slip), so the contact line could not move: a collapsing water column
//!   ran over a film of gas along the floor, which it rolled up under its front (issue 34;
//!   the front at t = 1 was 11% ahead of Martin & Moyce's measurement and the region φ_w > 0
//!   lost 0.5% of the liquid by t = 0.05; with the band continued, 6% and 0.0%). Sliding the
//!   contact line over the band is the slip a no-slip wall needs for it to move. Otherwise the periodic box's seam runs
//!   through the walls as a second interface, liquid over gas across the wrap, held only by
//!   the penalization: under a rising body that interface climbed out of the floor as a gas
//!   finger and the run blew up (the `floating` case at t = 4.5).
//! * Moving bodies: inside a moving body φ_w is likewise the fluid's, continued linearly along
//!   the body's outward normal n from the point x_s = x + (φ_b + h) n just outside it,
//!   φ_e(x) = φ_w(x_s) - (φ_b + h) (φ_w(x_s + h n) - φ_w(x_s)) / h,
//!   exact for a flat surface cut by the body: written into φ_w after the transport (then
//!   redistanced with the rest), and used again for the phases' density inside the body at
//!   the start of the next step, at its new pose. A body then displaces the fluid around it,
//!   which sets its buoyancy (through ρ - ρ_P). Carried rigidly instead, φ_w kept inside a
//!   body the phase of wherever it had entered: a body dropped from the gas into the liquid
//!   held gas and displaced nothing (in `scenes/tank.ron`
//!   bodies of density 0.8 sank), and in the `floating` case the box of density 0.25 drew
//!   0.0142 against Archimedes' 0.0242 (0.0240 now), the one of 0.5 0.0440 against 0.0495
//!   (0.0485). (Masking these nodes out of the redistancing made the `floating` case blow up
//!   at t = 7 in vorticity form.)
//! * Volume: neither transport keeps the volume of a level set exactly, so after each step the
//!   level set is shifted, φ_w += (V₀ - V)/A, with V = ∫(1 - χ)H_ε(φ_w) and
//!   A = ∫(1 - χ)δ_ε(φ_w) over the fluid (χ = χ_s + Σχ_i, the walls and the moving bodies at
//!   their current pose; two Newton steps), which holds the liquid outside the bodies at its
//!   initial volume V₀: a body that surfaces leaves the liquid as it was. Kept with the liquid
//!   continued inside the moving bodies, V counted the submerged part of every body as liquid,
//!   so a light disk rising through the surface of `floating` (h = 1/64, 1:100) added 0.012 of
//!   liquid (0.7% of the pool) and raised the tank's energy by 1e-2; the 64³ `pool-drop` lost
//!   up to 0.86% of its liquid outside the spheres (0.06% now).
//!
//! Sums are taken row by row in a fixed order: the results do not depend on the thread count.
//! The extensions into the walls and the bodies read φ_w as it was before them, so they do not
//! depend on the order of the nodes either.
//!
//! On several processes each holds its planes of φ_w; the redistancing reads one ghost plane a
//! side. The extensions read φ_w at points up to a body's depth away along a normal, so they
//! read as many ghost planes as the deepest wall or body reaches (measured at startup), or the
//! whole grid's φ_w, gathered from every process, where that reach passes the thinnest slab. A
//! moving body's level set beyond the slab's part of its patch is evaluated from its shape, as
//! its sampling does. The results are the one-process results bit for bit.

use crate::base::fields::Params;
use crate::base::grid::{Grid, RowNeighbours, for_row, line_at};
use crate::base::kernels::heaviside;
use crate::bodies::free_surface::{FreeSurface, LiquidLevelSet};
use crate::bodies::{Body, BodyFields, BodyShape, GridPatch, RigidState};
use crate::parallel::halo::{plane, z_line};
use crate::parallel::{Decomposition, Gather, Halo, RowSums};
use bevy_ecs::prelude::*;
use glam::DVec3;
use rayon::prelude::*;

/// The bodies as the free surface reads them: a moving body's level set beyond its slab's
/// part of the patch is evaluated from its shape and pose.
type Bodies<'w, 's> = Query<
    'w,
    's,
    (
        &'static Body,
        &'static GridPatch,
        &'static RigidState,
        &'static BodyShape,
    ),
>;

/// Pseudo-time iterations of the redistancing per step.
pub const STEP_ITERATIONS: usize = 2;

/// A node inside a wall or in the band it holds at rest, and the point (in grid units from the
/// origin) whose φ_w it takes.
#[derive(Debug, Clone, Copy)]
struct WallNode {
    node: usize,
    from: [f64; 3],
}

/// The free surface's scratch: the level set before redistancing and a second buffer for the
/// Jacobi iterations, per-row partial sums, and the walls (set at startup from the static
/// bodies): the nodes inside them with the point each copies, and 1 - χ_s per node (empty
/// without walls).
#[derive(Resource)]
pub struct FreeSurfaceScratch {
    phi0: Vec<f64>,
    next: Vec<f64>,
    /// Per row: the volume's partial sums, then the area's.
    partial: Vec<f64>,
    sums: RowSums,
    wall: Vec<WallNode>,
    in_wall: Vec<bool>,
    open: Vec<f32>,
    /// 1 - χ_s - Σχ_i per node with the moving bodies at their current pose (empty without
    /// any body): the weight of the liquid volume that is kept.
    outside: Vec<f32>,
    /// On several processes: the ghost planes the stencils and the extensions read.
    split: Option<SplitLevelSet>,
}

/// The free surface on a slab: the redistancing reads one ghost plane a side; the extensions
/// into the walls and the bodies read φ_w at points along a normal, up to the deepest wall's or
/// body's reach away, through [`Far`].
struct SplitLevelSet {
    d: Decomposition,
    /// One ghost plane a side of φ⁰ (or the walls' level set at startup) and φ.
    halo: Halo,
    /// What the extensions read beyond the slab (set at startup).
    far: Far,
}

/// φ_w beyond a slab for the extensions.
enum Far {
    /// Before the startup has measured the reach.
    Unset,
    /// Ghost planes a side as many as the deepest reach of the walls' and the bodies'
    /// extensions, measured at startup (a wall's points are fixed; a rigid body's depth is its
    /// own).
    Planes(Halo),
    /// The whole grid's φ_w, gathered from every process: where that reach is wider than the
    /// thinnest slab.
    Whole(Gather, Vec<f64>),
}

/// φ_w as the extensions read it: this process's planes `phi`, and beyond them (several
/// processes) the ghost planes or the whole grid's copy that [`FreeSurfaceScratch::view`]
/// filled.
#[derive(Clone, Copy)]
struct View<'a> {
    grid: &'a Grid,
    phi: &'a [f64],
    far: FarView<'a>,
}

#[derive(Clone, Copy)]
enum FarView<'a> {
    /// The whole grid's φ_w: `phi` itself on one process, else the gathered copy.
    Whole(&'a [f64]),
    Planes(&'a Halo),
}

impl View<'_> {
    /// φ_w at node (i, j) (wrapped) of the whole grid's plane `k` (unwrapped).
    #[inline]
    fn at(&self, i: usize, j: usize, k: isize) -> f64 {
        let g = self.grid;
        let nzw = g.nz_whole as isize;
        match self.far {
            FarView::Whole(w) => w[g.idx(i, j, k.rem_euclid(nzw) as usize)],
            FarView::Planes(h) => {
                let (w, nz) = (h.width() as isize, g.n[2] as isize);
                let mut kl = k - g.k0 as isize;
                if kl < -w || kl >= nz + w {
                    kl = (kl + w).rem_euclid(nzw) - w;
                }
                debug_assert!(
                    kl >= -w && kl < nz + w,
                    "free surface: plane {k} beyond the reach"
                );
                plane(g, self.phi, Some(h), 0, kl)[g.idx(i, j, 0)]
            }
        }
    }
}

impl FreeSurfaceScratch {
    /// Per node, whether it lies inside a static wall (empty without walls).
    pub fn in_wall(&self) -> &[bool] {
        &self.in_wall
    }

    /// Scratch for `grid`, a slab of `split`'s when the run is split.
    pub fn new(grid: &Grid, split: Option<&Decomposition>) -> Self {
        FreeSurfaceScratch {
            phi0: vec![0.0; grid.len()],
            next: vec![0.0; grid.len()],
            partial: vec![0.0; 2 * (grid.len() / grid.n[0])],
            sums: RowSums::new(grid, split),
            wall: Vec::new(),
            in_wall: Vec::new(),
            open: Vec::new(),
            outside: Vec::new(),
            split: split.map(|d| SplitLevelSet {
                d: d.clone(),
                halo: Halo::new(grid, d, 1, 2),
                far: Far::Unset,
            }),
        }
    }

    /// The view of `phi` (this process's planes) the extensions read: on several processes
    /// with its planes beyond the slab filled (every process calls it together).
    fn view<'a>(split: &'a mut Option<SplitLevelSet>, grid: &'a Grid, phi: &'a [f64]) -> View<'a> {
        let far = match split.as_mut().map(|s| &mut s.far) {
            None => FarView::Whole(phi),
            Some(Far::Planes(h)) => {
                h.fill_one(0, phi);
                FarView::Planes(h)
            }
            Some(Far::Whole(g, whole)) => {
                g.whole(phi, whole);
                FarView::Whole(whole)
            }
            Some(Far::Unset) => unreachable!("free surface: the reach is set at startup"),
        };
        View { grid, phi, far }
    }

    /// On several processes, the ghost planes of the extensions: as many as the deepest point
    /// a wall's node or a moving body's copies from (a body's depth and two cells, one more for
    /// a pose whose nodes sample the body deeper than the startup's), or the whole grid's
    /// φ_w where that is more than the thinnest slab holds.
    fn set_reach<'a>(&mut self, grid: &Grid, bodies: impl Iterator<Item = MovingBody<'a>>) {
        let Some(s) = self.split.as_mut() else {
            return;
        };
        let h = grid.h;
        let mut reach = 1.0f64;
        for w in &self.wall {
            let k = (w.node / grid.plane() + grid.k0) as f64;
            reach = reach.max((w.from[2] - k).abs().floor() + 2.0);
        }
        for b in bodies {
            let depth = b.patch.phi.iter().fold(0.0f64, |m, &p| m.max(p));
            reach = reach.max((depth / h).ceil() + 4.0);
        }
        let reach = s.d.comm.max_one(reach) as usize;
        let slabs = &s.d.slabs;
        let thinnest = (0..slabs.ranks)
            .map(|r| slabs.planes(r).len())
            .min()
            .unwrap_or(0);
        s.far = if reach <= thinnest {
            Far::Planes(Halo::new(grid, &s.d, reach, 1))
        } else {
            Far::Whole(
                Gather::new(&s.d, grid.plane()),
                vec![0.0; grid.whole().len()],
            )
        };
    }

    /// The weight of the kept liquid volume, 1 - χ_s - Σχ_i (at least 0), with the moving
    /// bodies' χ_i from their patches at their current pose (empty without any body); the
    /// static ones among `bodies` are already in the walls' part.
    fn fill_outside<'a>(
        &mut self,
        grid: &Grid,
        bodies: impl Iterator<Item = (&'a Body, &'a GridPatch)>,
    ) {
        self.outside.clear();
        let mut moving = bodies
            .filter(|(b, p)| !b.is_static() && !p.is_empty())
            .map(|(_, p)| p)
            .peekable();
        if self.open.is_empty() && moving.peek().is_none() {
            return;
        }
        if self.open.is_empty() {
            self.outside.resize(grid.len(), 1.0);
        } else {
            self.outside.extend_from_slice(&self.open);
        }
        for patch in moving {
            let [dx, dy, dz] = patch.dims;
            for c in 0..dz {
                if !patch.holds(grid, c) {
                    continue;
                }
                for b in 0..dy {
                    for a in 0..dx {
                        let g = patch.grid_index(grid, a, b, c);
                        let x = self.outside[g] as f64 - patch.chi[a + dx * (b + dy * c)];
                        self.outside[g] = x.max(0.0) as f32;
                    }
                }
            }
        }
    }

    /// The walls from the static bodies' union level set `phi_s` (> 0 inside, `None` without
    /// static bodies; on every process or none) and smoothed half-width `eps`.
    fn set_walls(&mut self, grid: &Grid, phi_s: Option<&[f64]>, eps: f64) {
        self.wall.clear();
        self.in_wall.clear();
        self.open.clear();
        let Some(phi_s) = phi_s else {
            return;
        };
        // The walls' level set one plane beyond the slab, for the normals.
        let halo = self.split.as_mut().map(|s| {
            s.halo.fill_one(0, phi_s);
            &s.halo
        });
        let [nx, ny, nz] = grid.n;
        let h = grid.h;
        self.open = phi_s
            .iter()
            .map(|&p| (1.0 - heaviside(p, eps)) as f32)
            .collect();
        self.in_wall = phi_s.iter().map(|&p| p > 0.0).collect();
        let wrap = crate::base::grid::periodic_offset;
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    let c = grid.idx(i, j, k);
                    let p = phi_s[c];
                    if p <= -eps {
                        continue;
                    }
                    // The outward normal -∇φ_s by centred differences (a neighbour beyond
                    // every static patch counts as one cell further out).
                    let mut g = [0.0; 3];
                    let mut down = [0.0; 3];
                    for a in 0..grid.dim {
                        // φ_s one node away along a (along z from the halo on a slab).
                        let at = |d: isize| match a {
                            0 => phi_s[grid.idx(wrap(i, d, nx), j, k)],
                            1 => phi_s[grid.idx(i, wrap(j, d, ny), k)],
                            _ => plane(grid, phi_s, halo, 0, k as isize + d)[grid.idx(i, j, 0)],
                        };
                        let (pm, pq) = (at(-1).max(p - h), at(1).max(p - h));
                        g[a] = -(pq - pm) / (2.0 * h);
                        // The steeper one-sided descent, for a ridge (the middle of a wall
                        // across the periodic seam, where the centred difference vanishes).
                        down[a] = if pq <= pm {
                            (p - pq) / h
                        } else {
                            -(p - pm) / h
                        };
                    }
                    let mut norm = (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]).sqrt();
                    if norm < 0.5 {
                        g = down;
                        norm = (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]).sqrt();
                    }
                    // No direction out of the wall here: the node keeps the flow's φ_w.
                    if norm < 0.5 {
                        continue;
                    }
                    let reach = (p + eps + h) / (h * norm);
                    // In the whole grid's nodes (the slab's planes are k0 on).
                    let from = [
                        i as f64 + g[0] * reach,
                        j as f64 + g[1] * reach,
                        (k + grid.k0) as f64 + g[2] * reach,
                    ];
                    self.wall.push(WallNode { node: c, from });
                }
            }
        }
    }
}

/// φ_w at the point `x` in grid units from the whole grid's origin (multilinear, periodic).
fn interpolate(view: &View, x: [f64; 3]) -> f64 {
    let grid = view.grid;
    let mut idx = [[0isize; 2]; 3];
    let mut w = [[1.0, 0.0]; 3];
    for a in 0..grid.dim {
        let f = x[a].floor();
        let t = x[a] - f;
        if a < 2 {
            let n = grid.n[a] as isize;
            let i0 = (f as isize).rem_euclid(n);
            idx[a] = [i0, (i0 + 1) % n];
        } else {
            // Along z the planes of the whole grid, unwrapped (the view wraps them).
            idx[a] = [f as isize, f as isize + 1];
        }
        w[a] = [1.0 - t, t];
    }
    let mut v = 0.0;
    for c in 0..2 {
        for b in 0..2 {
            for a in 0..2 {
                let wt = w[0][a] * w[1][b] * w[2][c];
                if wt != 0.0 {
                    v += wt * view.at(idx[0][a] as usize, idx[1][b] as usize, idx[2][c]);
                }
            }
        }
    }
    v
}

/// A moving body as the extension reads it: its patch, and its shape and pose for its level
/// set at the nodes of its whole box beyond the slab's part of the patch.
#[derive(Clone, Copy)]
struct MovingBody<'a> {
    patch: &'a GridPatch,
    state: &'a RigidState,
    shape: &'a BodyShape,
}

impl MovingBody<'_> {
    /// φ_b at the patch's node `q` (its own axes; along z any plane of the whole box, which
    /// wraps when it spans the grid): the patch's value where it holds the node, else the
    /// shape's at the node, the value the body's own process sampled there (the same
    /// arithmetic); `None` beyond the whole box.
    fn phi(&self, grid: &Grid, q: [isize; 3]) -> Option<f64> {
        let p = self.patch;
        let dims = p.dims;
        if (0..grid.dim).all(|a| q[a] >= 0 && q[a] < dims[a] as isize) {
            let q = q.map(|v| v as usize);
            return Some(p.phi[q[0] + dims[0] * (q[1] + dims[1] * q[2])]);
        }
        // Only z (on a slab) reaches past the patch inside the whole box.
        let (wlo, wdims) = p.whole;
        if !grid.is_slab() || (0..2).any(|a| q[a] < 0 || q[a] >= dims[a] as isize) {
            return None;
        }
        let mut cw = p.lo[2] + q[2] - wlo[2];
        if wdims[2] == grid.nz_whole {
            cw = cw.rem_euclid(wdims[2] as isize);
        } else if cw < 0 || cw >= wdims[2] as isize {
            return None;
        }
        let lo = [p.lo[0], p.lo[1], wlo[2] + cw];
        let x = crate::bodies::patch_pos(grid, lo, q[0] as usize, q[1] as usize, 0);
        let x = DVec3::new(x[0], x[1], x[2]);
        let inv = self.state.orientation.inverse();
        Some(self.shape.level_set.phi(inv * (x - self.state.center)))
    }
}

/// The outward unit normal -∇φ_b/|∇φ_b| of a body at its patch node `q` (inside, φ_b = `p`),
/// by centred differences (a neighbour beyond the body's box that does not span the grid
/// counts as one cell further out); at a ridge, where the centred difference vanishes (the
/// middle of a wall across the periodic seam), the steeper one-sided descent. `None` where
/// neither gives a direction.
fn outward_normal(grid: &Grid, body: MovingBody, q: [usize; 3], p: f64) -> Option<[f64; 3]> {
    let h = grid.h;
    let dims = body.patch.dims;
    let at = |ax: usize, d: isize| -> f64 {
        let mut idx = q.map(|v| v as isize);
        let n = dims[ax] as isize;
        idx[ax] += d;
        // A patch spanning the grid wraps (along z on a slab, `MovingBody::phi` wraps the
        // whole box).
        let spans = dims[ax] == grid.n[ax] && (ax < 2 || !grid.is_slab());
        if spans {
            idx[ax] = idx[ax].rem_euclid(n);
        }
        body.phi(grid, idx).unwrap_or(p - h).max(p - h)
    };
    let mut g = [0.0; 3];
    let mut down = [0.0; 3];
    for a in 0..grid.dim {
        let (pm, pq) = (at(a, -1), at(a, 1));
        g[a] = -(pq - pm) / (2.0 * h);
        down[a] = if pq <= pm {
            (p - pq) / h
        } else {
            -(p - pm) / h
        };
    }
    let norm = |g: &[f64; 3]| (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]).sqrt();
    let mut n = norm(&g);
    if n < 0.5 {
        g = down;
        n = norm(&g);
    }
    (n >= 0.5).then(|| [g[0] / n, g[1] / n, g[2] / n])
}

/// The fluid's φ_w continued into one body: for each node of its patch inside it (φ_b > 0), the
/// value of the linear extrapolation along the outward normal n from the point
/// x_s = x + (φ_b + h) n just outside, φ_w(x_s) - (φ_b + h) (φ_w(x_s + h n) - φ_w(x_s)) / h,
/// clipped to ±`band`, is written into `next` (the slab's nodes), read from `view` (left
/// unchanged).
fn extension_values(grid: &Grid, body: MovingBody, view: &View, next: &mut [f64], band: f64) {
    let patch = body.patch;
    let [dx, dy, _] = patch.dims;
    if patch.is_empty() {
        return;
    }
    let h = grid.h;
    let out = crate::base::grid::SyncPtr(next.as_mut_ptr());
    (0..patch.len() / dx).into_par_iter().for_each(|r| {
        let (b, c) = (r % dy, r / dy);
        if !patch.holds(grid, c) {
            return;
        }
        for a in 0..dx {
            let p = patch.phi[r * dx + a];
            if p <= 0.0 {
                continue;
            }
            let g = patch.grid_index(grid, a, b, c);
            let Some(n) = outward_normal(grid, body, [a, b, c], p) else {
                // No direction out of the body here: the node's own value.
                // SAFETY: distinct patch nodes map to distinct grid nodes.
                unsafe { out.write(g, view.phi[g]) };
                continue;
            };
            let s = (p + h) / h;
            // The node's index unwrapped (`interpolate` wraps it into the periodic box).
            let i = [
                (patch.lo[0] + a as isize) as f64,
                (patch.lo[1] + b as isize) as f64,
                (patch.lo[2] + c as isize) as f64,
            ];
            let xs = [i[0] + s * n[0], i[1] + s * n[1], i[2] + s * n[2]];
            let x1 = [xs[0] + n[0], xs[1] + n[1], xs[2] + n[2]];
            let (f0, f1) = (interpolate(view, xs), interpolate(view, x1));
            // SAFETY: distinct patch nodes map to distinct grid nodes.
            unsafe { out.write(g, (f0 - s * (f1 - f0)).clamp(-band, band)) };
        }
    });
}

/// `out[n] = value(n)` at every grid node `n` of the slab inside a body (its patch's φ > 0).
fn write_inside(
    grid: &Grid,
    patch: &GridPatch,
    out: &mut [f64],
    value: impl Fn(usize) -> f64 + Sync,
) {
    let [dx, dy, _] = patch.dims;
    if patch.is_empty() {
        return;
    }
    let out = crate::base::grid::SyncPtr(out.as_mut_ptr());
    (0..patch.len() / dx).into_par_iter().for_each(|r| {
        let (b, c) = (r % dy, r / dy);
        if !patch.holds(grid, c) {
            return;
        }
        for a in 0..dx {
            if patch.phi[r * dx + a] > 0.0 {
                let n = patch.grid_index(grid, a, b, c);
                // SAFETY: distinct patch nodes map to distinct grid nodes.
                unsafe { out.write(n, value(n)) };
            }
        }
    });
}

/// φ_w inside the walls: at each wall node, the value of φ_w before this call (`frozen`) at its
/// point outside, so that the result does not depend on the order of the nodes.
fn extend_into_walls(phi: &mut [f64], frozen: &View, wall: &[WallNode]) {
    let out = crate::base::grid::SyncPtr(phi.as_mut_ptr());
    wall.par_iter().for_each(|w| {
        // SAFETY: every wall node appears once.
        unsafe { out.write(w.node, interpolate(frozen, w.from)) };
    });
}

/// The moving bodies of the query whose box holds grid nodes: the same on every process, also
/// where a body does not reach a process's slab (which then gathers with the others).
fn moving<'a>(
    bodies: impl Iterator<Item = (&'a Body, &'a GridPatch, &'a RigidState, &'a BodyShape)>,
) -> impl Iterator<Item = MovingBody<'a>> {
    bodies
        .filter(|(b, p, ..)| !b.is_static() && p.on_grid())
        .map(|(_, patch, state, shape)| MovingBody {
            patch,
            state,
            shape,
        })
}

/// The density of the fluid phases from φ_w (before the `density` system adds the bodies).
pub fn phase_density(
    params: Res<Params>,
    grid: Res<Grid>,
    surfaces: Query<&FreeSurface>,
    ls: Res<LiquidLevelSet>,
    mut bf: ResMut<BodyFields>,
    mut scratch: ResMut<FreeSurfaceScratch>,
    bodies: Bodies,
) {
    let Some(fs) = surfaces.iter().next() else {
        return;
    };
    let eps = params.numerics.interface_cells * grid.h;
    write_phase_density(fs, &ls.phi, eps, &mut bf.rho_phase);
    // Inside a moving body, the phase it displaces at its pose now: φ_w continued from outside
    // (see the module doc).
    if moving(bodies.iter()).next().is_none() {
        return;
    }
    let (g, d) = (fs.gas_density, fs.liquid_density - fs.gas_density);
    let scratch = &mut *scratch;
    let view = FreeSurfaceScratch::view(&mut scratch.split, &grid, &ls.phi);
    for body in moving(bodies.iter()) {
        extension_values(&grid, body, &view, &mut scratch.next, ls.band);
        let next = &scratch.next;
        write_inside(&grid, body.patch, &mut bf.rho_phase, |n| {
            g + d * heaviside(next[n], eps)
        });
    }
}

/// ρ_P = ρ_gas + (ρ_liquid - ρ_gas) H_ε(φ_w) at every node.
pub fn write_phase_density(fs: &FreeSurface, phi: &[f64], eps: f64, rho_phase: &mut [f64]) {
    let (g, d) = (fs.gas_density, fs.liquid_density - fs.gas_density);
    rho_phase
        .par_chunks_mut(4096)
        .zip(phi.par_chunks(4096))
        .for_each(|(r, p)| {
            for (r, &p) in r.iter_mut().zip(p) {
                *r = g + d * heaviside(p, eps);
            }
        });
}

/// φ_w continued into the walls (from its values now, through a copy of them).
fn walls_step(grid: &Grid, ls: &mut LiquidLevelSet, scratch: &mut FreeSurfaceScratch) {
    // Without walls (on every process alike: `open` is empty).
    if scratch.open.is_empty() {
        return;
    }
    scratch.phi0.copy_from_slice(&ls.phi);
    let frozen = FreeSurfaceScratch::view(&mut scratch.split, grid, &scratch.phi0);
    extend_into_walls(&mut ls.phi, &frozen, &scratch.wall);
}

/// The free surface's step: φ_w (carried with the mass and momentum by the transport) continued
/// into the walls and the moving bodies, redistanced and its volume restored.
pub fn free_surface(
    params: Res<Params>,
    grid: Res<Grid>,
    mut ls: ResMut<LiquidLevelSet>,
    mut scratch: ResMut<FreeSurfaceScratch>,
    bodies: Bodies,
) {
    let ls = &mut *ls;
    let scratch = &mut *scratch;
    walls_step(&grid, ls, scratch);
    // Inside the moving bodies: the fluid's φ_w continued (see the module doc), every body's
    // from the same φ_w.
    if moving(bodies.iter()).next().is_some() {
        let view = FreeSurfaceScratch::view(&mut scratch.split, &grid, &ls.phi);
        for body in moving(bodies.iter()) {
            extension_values(&grid, body, &view, &mut scratch.next, ls.band);
        }
        let next = &scratch.next;
        for body in moving(bodies.iter()) {
            write_inside(&grid, body.patch, &mut ls.phi, |n| next[n]);
        }
    }
    let eps = params.numerics.interface_cells * grid.h;
    redistance(&grid, ls, scratch, STEP_ITERATIONS, Some(eps));
    scratch.fill_outside(&grid, bodies.iter().map(|(b, p, ..)| (b, p)));
    restore_volume(&grid, ls, scratch, eps);
}

/// `iterations` pseudo-time steps of the redistancing equation with the Russo-Smereka subcell
/// fix, then φ clipped to ±band. With `hold_gas`, the smoothed band's half-width ε, the gas
/// side of the band (-ε < φ⁰ < 0) keeps its values (see the module doc).
pub fn redistance(
    grid: &Grid,
    ls: &mut LiquidLevelSet,
    scratch: &mut FreeSurfaceScratch,
    iterations: usize,
    hold_gas: Option<f64>,
) {
    let dim = grid.dim;
    let h = grid.h;
    let nx = grid.n[0];
    // Pseudo-time step: h/2 in 2D, h/3 in 3D (first-order Godunov is stable below h/√d).
    let dtau = if dim == 2 { 0.5 * h } else { h / 3.0 };
    let hold = -hold_gas.unwrap_or(0.0);
    let band = ls.band;
    scratch.phi0.copy_from_slice(&ls.phi);
    if let Some(s) = scratch.split.as_mut() {
        s.halo.fill_one(0, &scratch.phi0);
    }
    let phi0 = &scratch.phi0;
    let in_wall = &scratch.in_wall;
    let three = dim == 3;
    for _ in 0..iterations {
        let halo = scratch.split.as_mut().map(|s| {
            s.halo.fill_one(1, &ls.phi);
            &s.halo
        });
        let phi = &ls.phi;
        scratch
            .next
            .par_chunks_mut(nx)
            .enumerate()
            .for_each(|(row, out)| {
                let rn = RowNeighbours::new(grid, row);
                // This row and its neighbour rows in y and z, of φ⁰ and of φ.
                let (c0, ym, yp) = (
                    line_at(phi0, rn.c0, nx),
                    line_at(phi0, rn.below[0], nx),
                    line_at(phi0, rn.above[0], nx),
                );
                let (zm, zp) = if three {
                    (
                        z_line(grid, phi0, halo, 0, row, -1),
                        z_line(grid, phi0, halo, 0, row, 1),
                    )
                } else {
                    (c0, c0)
                };
                let (f, fym, fyp) = (
                    line_at(phi, rn.c0, nx),
                    line_at(phi, rn.below[0], nx),
                    line_at(phi, rn.above[0], nx),
                );
                let (fzm, fzp) = if three {
                    (
                        z_line(grid, phi, halo, 1, row, -1),
                        z_line(grid, phi, halo, 1, row, 1),
                    )
                } else {
                    (f, f)
                };
                let wall = in_wall.get(rn.c0..rn.c0 + nx);
                for_row(nx, |i, im, ip| {
                    let s0 = c0[i];
                    // (minus, plus) neighbours per axis, of φ⁰ and of φ.
                    let n0 = [(c0[im], c0[ip]), (ym[i], yp[i]), (zm[i], zp[i])];
                    let nf = [(f[im], f[ip]), (fym[i], fyp[i]), (fzm[i], fzp[i])];
                    // Next to the interface: relax to the subcell distance D = φ⁰ h / Δφ⁰.
                    let near = n0[..dim].iter().any(|&(m, p)| s0 * m < 0.0 || s0 * p < 0.0);
                    let v = f[i];
                    // Wall nodes hold the fluid's φ_w continued (`extend_into_walls`).
                    if wall.is_some_and(|w| w[i]) {
                        out[i] = v;
                        return;
                    }
                    if s0 == 0.0 {
                        out[i] = 0.0;
                        return;
                    }
                    // The light fringe of the band keeps its density.
                    if s0 < 0.0 && s0 > hold {
                        out[i] = v;
                        return;
                    }
                    let o = if near {
                        let mut g2 = 0.0;
                        for &(m, p) in &n0[..dim] {
                            let d = (0.5 * (p - m).abs())
                                .max((p - s0).abs())
                                .max((s0 - m).abs())
                                .max(1e-12 * h);
                            g2 += d * d;
                        }
                        let dist = h * s0 / g2.sqrt();
                        v - dtau / h * (s0.signum() * v.abs() - dist)
                    } else {
                        let mut g2 = 0.0;
                        for &(m, p) in &nf[..dim] {
                            let a = (v - m) / h;
                            let b = (p - v) / h;
                            let t = if s0 > 0.0 {
                                a.max(0.0).powi(2).max(b.min(0.0).powi(2))
                            } else {
                                a.min(0.0).powi(2).max(b.max(0.0).powi(2))
                            };
                            g2 += t;
                        }
                        v - dtau * s0.signum() * (g2.sqrt() - 1.0)
                    };
                    out[i] = o.clamp(-band, band);
                });
            });
        std::mem::swap(&mut ls.phi, &mut scratch.next);
    }
}

/// ∫(1 - χ)H_ε(φ) dV and ∫(1 - χ)δ_ε(φ) dV outside the walls and bodies (`open` = 1 - χ per
/// node, empty for none) over the whole grid: per row into `partial` (the volume's rows, then
/// the area's), added by `sums` (in the same order on any number of processes).
pub fn volume_and_area(
    grid: &Grid,
    phi: &[f64],
    open: &[f32],
    partial: &mut [f64],
    sums: &mut RowSums,
    eps: f64,
) -> (f64, f64) {
    let nx = grid.n[0];
    let rows = phi.len() / nx;
    let (pv, pa) = partial.split_at_mut(rows);
    pv.par_iter_mut()
        .zip(pa.par_iter_mut())
        .zip(phi.par_chunks(nx))
        .enumerate()
        .for_each(|(r, ((sv, sa), row))| {
            let (mut v, mut a) = (0.0, 0.0);
            let open = open.get(r * nx..(r + 1) * nx);
            for (i, &p) in row.iter().enumerate() {
                let w = open.map_or(1.0, |o| o[i] as f64);
                v += w * heaviside(p, eps);
                a += w * delta(p, eps);
            }
            (*sv, *sa) = (v, a);
        });
    let dv = grid.cell_volume();
    let (v, a) = (sums.total(pv), sums.total(pa));
    (v * dv, a * dv)
}

/// The smoothed delta function δ_ε = dH_ε/dφ.
#[inline]
pub fn delta(phi: f64, eps: f64) -> f64 {
    if phi.abs() >= eps {
        0.0
    } else {
        0.5 / eps * (1.0 + (std::f64::consts::PI * phi / eps).cos())
    }
}

/// The liquid's volume and area now, into `ls`.
fn measure(grid: &Grid, ls: &mut LiquidLevelSet, scratch: &mut FreeSurfaceScratch, eps: f64) {
    let s = scratch;
    let (v, a) = volume_and_area(grid, &ls.phi, &s.outside, &mut s.partial, &mut s.sums, eps);
    ls.volume = v;
    ls.area = a;
}

/// Shift φ so that ∫H_ε(φ) dV returns to the target volume (two Newton steps); records the
/// volume and area.
pub fn restore_volume(
    grid: &Grid,
    ls: &mut LiquidLevelSet,
    scratch: &mut FreeSurfaceScratch,
    eps: f64,
) {
    for _ in 0..2 {
        measure(grid, ls, scratch, eps);
        let (v, a) = (ls.volume, ls.area);
        if a <= 0.0 {
            return;
        }
        let shift = (ls.target_volume - v) / a;
        let band = ls.band;
        ls.phi.par_chunks_mut(4096).for_each(|c| {
            c.iter_mut()
                .for_each(|p| *p = (*p + shift).clamp(-band, band))
        });
    }
    measure(grid, ls, scratch, eps);
}

/// Before the first step: redistance the initial level set through the whole band, take its
/// volume as the one to keep, and set the phases' density.
pub fn free_surface_init(
    params: Res<Params>,
    grid: Res<Grid>,
    surfaces: Query<&FreeSurface>,
    mut ls: ResMut<LiquidLevelSet>,
    mut scratch: ResMut<FreeSurfaceScratch>,
    mut bf: ResMut<BodyFields>,
    bodies: Bodies,
) {
    let ls = &mut *ls;
    let scratch = &mut *scratch;
    let eps = params.numerics.interface_cells * grid.h;
    // The walls: the static bodies' union level set (sampled by `level_sets_init`); every
    // process has the same static bodies, so all or none make one.
    let mut phi_s: Option<Vec<f64>> = None;
    for (body, patch, ..) in &bodies {
        if !body.is_static() || !patch.on_grid() {
            continue;
        }
        let phi_s = phi_s.get_or_insert_with(|| vec![f64::NEG_INFINITY; grid.len()]);
        let [dx, dy, dz] = patch.dims;
        for c in 0..dz {
            if !patch.holds(&grid, c) {
                continue;
            }
            for b in 0..dy {
                for a in 0..dx {
                    let g = patch.grid_index(&grid, a, b, c);
                    let v = patch.phi[a + dx * (b + dy * c)];
                    phi_s[g] = phi_s[g].max(v);
                }
            }
        }
    }
    scratch.set_walls(&grid, phi_s.as_deref(), eps);
    scratch.set_reach(&grid, moving(bodies.iter()));
    scratch.fill_outside(&grid, bodies.iter().map(|(b, p, ..)| (b, p)));
    walls_step(&grid, ls, scratch);
    // A restart holds a redistanced level set and its target: leave both.
    if ls.target_volume == 0.0 {
        let dtau = if grid.dim == 2 { 0.5 } else { 1.0 / 3.0 };
        let its = (3.0 * ls.band / grid.h / dtau).ceil() as usize;
        redistance(&grid, ls, scratch, its, None);
        walls_step(&grid, ls, scratch);
        measure(&grid, ls, scratch, eps);
        ls.target_volume = ls.volume;
    }
    if let Some(fs) = surfaces.iter().next() {
        write_phase_density(fs, &ls.phi, eps, &mut bf.rho_phase);
    }
}

/// The free surface (a scene with `free_surface`).
#[derive(Debug, Clone, Copy, Default)]
pub struct FreeSurfacePlugin;

impl crate::schedule::Plugin for FreeSurfacePlugin {
    fn name(&self) -> &'static str {
        "free_surface"
    }

    fn build(&self, ctx: &mut crate::schedule::PluginContext) -> anyhow::Result<()> {
        use crate::schedule::PhysicsSet;
        if !ctx.world.contains_resource::<LiquidLevelSet>() {
            return Ok(());
        }
        let grid = ctx.world.resource::<Grid>().clone();
        let split = ctx.world.get_resource::<Decomposition>().cloned();
        ctx.insert_resource(FreeSurfaceScratch::new(&grid, split.as_ref()));
        ctx.checkpoint_resource::<LiquidLevelSet>("free_surface", 1)?;
        ctx.add_startup_system_in(
            PhysicsSet::PhaseDensity,
            "free_surface_init",
            free_surface_init,
        )?;
        ctx.add_system(PhysicsSet::PhaseDensity, "phase_density", phase_density)?;
        ctx.add_system(PhysicsSet::FreeSurface, "free_surface", free_surface)?;
        Ok(())
    }
}
