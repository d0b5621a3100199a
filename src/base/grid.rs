//! The uniform periodic grid every field lives on.
//!
//! Nodes sit at `x = origin + (i, j, k) h` for `i` in `0..n[0]` (and so on), so the box
//! `[origin, origin + extent)` holds exactly `n` nodes per axis and is periodic. In 2D
//! `n[2] == 1` and the z axis is ignored everywhere (no work is spent on it).

use bevy_ecs::prelude::Resource;

/// The computational grid: a resource.
///
/// On several processes each holds a slab of whole z-planes ([`Grid::slab`]): `n` counts the
/// slab's nodes, whose fields are stored and looped over as a grid of their own, while positions
/// and the box ([`Grid::pos`], [`Grid::extent`]) stay the whole grid's.
#[derive(Resource, Clone, Debug, PartialEq)]
pub struct Grid {
    /// 2 or 3.
    pub dim: usize,
    /// Node counts per axis (of this process's slab, when split); `n[2] == 1` in 2D.
    pub n: [usize; 3],
    /// Grid spacing (the same on every axis), length units.
    pub h: f64,
    /// Position of node (0, 0, 0) of the whole grid.
    pub origin: [f64; 3],
    /// The whole grid's first z-plane that this grid's plane 0 is (0 unless a slab).
    pub k0: usize,
    /// The whole grid's z-plane count (`n[2]` unless a slab).
    pub nz_whole: usize,
}

impl Grid {
    /// A grid of `n` nodes with spacing `h`; `n[2] == 1` makes it 2D.
    pub fn new(n: [usize; 3], h: f64, origin: [f64; 3]) -> Self {
        let dim = if n[2] == 1 { 2 } else { 3 };
        Grid {
            dim,
            n,
            h,
            origin,
            k0: 0,
            nz_whole: n[2],
        }
    }

    /// The slab of z-planes `planes` of this (whole, 3D) grid.
    pub fn slab(&self, planes: std::ops::Range<usize>) -> Self {
        assert!(
            self.dim == 3 && self.k0 == 0 && self.nz_whole == self.n[2],
            "grid: a slab of a slab or of a 2D grid"
        );
        assert!(
            !planes.is_empty() && planes.end <= self.n[2],
            "grid: planes {planes:?}"
        );
        Grid {
            dim: 3,
            n: [self.n[0], self.n[1], planes.len()],
            h: self.h,
            origin: self.origin,
            k0: planes.start,
            nz_whole: self.nz_whole,
        }
    }

    /// The whole grid this one is a slab of (itself unless a slab).
    pub fn whole(&self) -> Self {
        Grid::new([self.n[0], self.n[1], self.nz_whole], self.h, self.origin)
    }

    /// Whether this is a slab of a larger grid.
    pub fn is_slab(&self) -> bool {
        self.n[2] != self.nz_whole
    }

    /// Total number of nodes.
    #[inline]
    pub fn len(&self) -> usize {
        self.n[0] * self.n[1] * self.n[2]
    }

    /// Always false for a valid grid (kept for clippy's `len_without_is_empty`).
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Flat index of node (i, j, k); x is the fastest axis.
    #[inline(always)]
    pub fn idx(&self, i: usize, j: usize, k: usize) -> usize {
        i + self.n[0] * (j + self.n[1] * k)
    }

    /// Physical position of node (i, j, k).
    #[inline(always)]
    pub fn pos(&self, i: usize, j: usize, k: usize) -> [f64; 3] {
        [
            self.origin[0] + i as f64 * self.h,
            self.origin[1] + j as f64 * self.h,
            if self.dim == 3 {
                self.origin[2] + (k + self.k0) as f64 * self.h
            } else {
                0.0
            },
        ]
    }

    /// Index along `axis` of the node nearest to coordinate `x`, wrapped periodically into
    /// `0..n[axis]` (a non-finite `x` gives 0). Of a whole grid only.
    pub fn nearest(&self, axis: usize, x: f64) -> usize {
        debug_assert!(!self.is_slab(), "grid: nearest node of a slab");
        let n = self.n[axis] as i64;
        (((x - self.origin[axis]) / self.h).round() as i64).rem_euclid(n) as usize
    }

    /// Box size per axis (`n h` of the whole grid); 0 for z in 2D.
    pub fn extent(&self) -> [f64; 3] {
        [
            self.n[0] as f64 * self.h,
            self.n[1] as f64 * self.h,
            if self.dim == 3 {
                self.nz_whole as f64 * self.h
            } else {
                0.0
            },
        ]
    }

    /// The whole box lengths to add to point `x` to bring it into the periodic box
    /// `[origin, origin + extent)` (zero along z in 2D, and along any axis where `x` is
    /// already inside or not finite).
    pub fn wrap_shift(&self, x: [f64; 3]) -> [f64; 3] {
        let ext = self.extent();
        let mut shift = [0.0; 3];
        for a in 0..self.dim {
            let s = ((x[a] - self.origin[a]) / ext[a]).floor();
            if s.is_finite() && s != 0.0 {
                shift[a] = -s * ext[a];
                // Round-off may leave the point a hair outside: fix it up.
                let y = x[a] + shift[a];
                if y >= self.origin[a] + ext[a] {
                    shift[a] -= ext[a];
                } else if y < self.origin[a] {
                    shift[a] += ext[a];
                }
            }
        }
        shift
    }

    /// The whole box lengths to add to a separation `d` between two points to make it the
    /// separation from the first to the second's periodic image nearest it (zero along z in
    /// 2D).
    pub fn image_shift(&self, d: [f64; 3]) -> [f64; 3] {
        let ext = self.extent();
        let mut shift = [0.0; 3];
        for a in 0..self.dim {
            shift[a] = -(d[a] / ext[a]).round() * ext[a];
        }
        shift
    }

    /// Volume (3D) or area (2D) of one cell.
    pub fn cell_volume(&self) -> f64 {
        self.h.powi(self.dim as i32)
    }

    /// Number of vorticity components: 1 in 2D (scalar), 3 in 3D.
    pub fn omega_components(&self) -> usize {
        if self.dim == 2 { 1 } else { 3 }
    }

    /// Size of one z-plane (`nx ny`).
    #[inline]
    pub fn plane(&self) -> usize {
        self.n[0] * self.n[1]
    }
}

/// A raw pointer that may be shared between rayon tasks that write disjoint indices.
///
/// Every use states why the indices written by different tasks cannot overlap.
#[derive(Clone, Copy)]
pub struct SyncPtr<T>(pub *mut T);
unsafe impl<T: Send> Send for SyncPtr<T> {}
unsafe impl<T: Send> Sync for SyncPtr<T> {}

impl<T> SyncPtr<T> {
    /// # Safety
    /// `i` is in bounds and no other task reads or writes index `i` concurrently.
    #[inline(always)]
    pub unsafe fn write(self, i: usize, v: T) {
        unsafe { *self.0.add(i) = v }
    }
    /// # Safety
    /// `i` is in bounds and no other task writes index `i` concurrently.
    #[inline(always)]
    pub unsafe fn read(self, i: usize) -> T
    where
        T: Copy,
    {
        unsafe { *self.0.add(i) }
    }
    /// The `len` elements from `start`, as a slice.
    ///
    /// # Safety
    /// `start..start + len` is in bounds and no other task reads or writes it while the slice
    /// lives.
    #[inline(always)]
    pub unsafe fn slice_mut<'a>(self, start: usize, len: usize) -> &'a mut [T] {
        unsafe { std::slice::from_raw_parts_mut(self.0.add(start), len) }
    }
}

/// Shared pointers to the (up to three) components of a vector field, for rayon tasks that
/// write disjoint nodes; missing components are null and must not be used.
pub fn component_ptrs(field: &mut [Vec<f64>]) -> [SyncPtr<f64>; 3] {
    std::array::from_fn(|c| match field.get_mut(c) {
        Some(v) => SyncPtr(v.as_mut_ptr()),
        None => SyncPtr(std::ptr::null_mut()),
    })
}

/// The periodic neighbour `i + d` of index `i` on an axis of `n` nodes (any offset `d`).
#[inline(always)]
pub fn periodic_offset(i: usize, d: isize, n: usize) -> usize {
    (i as isize + d).rem_euclid(n as isize) as usize
}

/// The periodic neighbours of the nodes of one row along x: the row's first node and the first
/// nodes of the rows below and above it in y and z, so a node's neighbours cost two additions
/// instead of a division and three wraps.
#[derive(Clone, Copy)]
pub struct RowNeighbours {
    /// The row's first node.
    pub c0: usize,
    /// The first nodes of the rows below it in y and in z (itself in z in 2D).
    pub below: [usize; 2],
    /// The first nodes of the rows above it in y and in z (itself in z in 2D).
    pub above: [usize; 2],
}

impl RowNeighbours {
    /// The row `row = j + ny k` of `grid`.
    #[inline]
    pub fn new(grid: &Grid, row: usize) -> Self {
        let [nx, ny, nz] = grid.n;
        let (j, k) = (row % ny, row / ny);
        let nb = periodic_neighbours;
        let (jm, jp) = nb(j, ny);
        let (km, kp) = if grid.dim == 3 { nb(k, nz) } else { (k, k) };
        let start = |j: usize, k: usize| nx * (j + ny * k);
        RowNeighbours {
            c0: nx * row,
            below: [start(jm, k), start(j, km)],
            above: [start(jp, k), start(j, kp)],
        }
    }
}

/// Calls `node(i, im, ip)` for every node `i` of a periodic row of `nx` nodes with its
/// neighbours `im`, `ip` along the row: the interior in one branch-free loop (which the
/// compiler can vectorise), then the two end nodes with the wrap. Each node once.
#[inline(always)]
pub fn for_row(nx: usize, mut node: impl FnMut(usize, usize, usize)) {
    if nx == 1 {
        node(0, 0, 0);
        return;
    }
    for i in 1..nx - 1 {
        node(i, i - 1, i + 1);
    }
    node(0, nx - 1, 1 % nx);
    node(nx - 1, nx - 2, 0);
}

/// The periodic neighbours (i - 1, i + 1) of index `i` on an axis of `n` nodes.
#[inline]
pub fn periodic_neighbours(i: usize, n: usize) -> (usize, usize) {
    (
        if i == 0 { n - 1 } else { i - 1 },
        if i + 1 == n { 0 } else { i + 1 },
    )
}

/// The `nx` values of `f` from `at` (one row).
#[inline(always)]
pub fn line_at(f: &[f64], at: usize, nx: usize) -> &[f64] {
    &f[at..at + nx]
}
