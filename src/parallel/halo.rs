//! Ghost planes of a slab's fields: the `w` z-planes below its first plane and above its last,
//! the neighbours' (periodic), for the stencils that reach across a slab's faces (centred
//! differences, the pressure operator, a marker's kernel).
//!
//! A stencil reads plane `k` of a field for `k` in `-w..nz + w` through [`Halo::plane`]: the
//! slab's own planes from the field, the others from the ghosts. On one whole grid (no halo) the
//! same call wraps round the periodic axis, so a stencil written with it is one code for both.

use crate::base::grid::Grid;
use crate::parallel::Decomposition;

/// The ghost planes of up to `components` fields, filled by [`Halo::fill`].
#[derive(Debug, Clone)]
pub struct Halo {
    d: Decomposition,
    /// Planes a side.
    w: usize,
    /// Nodes a plane.
    plane: usize,
    /// Per component: `w` planes below the slab, then `w` above it.
    ghosts: Vec<Vec<f64>>,
}

impl Halo {
    /// `w` ghost planes a side for `components` fields of the slab `grid`.
    pub fn new(grid: &Grid, d: &Decomposition, w: usize, components: usize) -> Self {
        assert!(
            w <= grid.n[2],
            "halo: {w} planes a side of a slab of {}",
            grid.n[2]
        );
        Halo {
            d: d.clone(),
            w,
            plane: grid.plane(),
            ghosts: vec![vec![0.0; 2 * w * grid.plane()]; components],
        }
    }

    /// Exchanges the neighbours' planes of `fields` (at most `components` of them) into the
    /// ghosts; every process calls it together.
    pub fn fill<F: AsRef<[f64]>>(&mut self, fields: &[F]) {
        for (c, f) in fields.iter().enumerate().take(self.ghosts.len()) {
            self.fill_one(c, f.as_ref());
        }
    }

    /// Exchanges the neighbours' planes of `field` into component `c`'s ghosts.
    pub fn fill_one(&mut self, c: usize, field: &[f64]) {
        let wp = self.w * self.plane;
        let (below, above) = self.ghosts[c].split_at_mut(wp);
        let (first, last) = (&field[..wp], &field[field.len() - wp..]);
        self.d
            .comm
            .exchange(&self.d.slabs, first, last, below, above);
    }

    /// Planes a side.
    pub fn width(&self) -> usize {
        self.w
    }

    /// The ghosts of every component: per component, `w` planes below, then `w` above.
    pub fn all(&self) -> &[Vec<f64>] {
        &self.ghosts
    }
}

/// Plane `k` (`-w..nz + w` on a slab with a halo of `w` planes, any `k` on a whole grid, which
/// wraps) of `field`, component `c` of the fields `halo` was filled with.
#[inline]
pub fn plane<'a>(
    grid: &Grid,
    field: &'a [f64],
    halo: Option<&'a Halo>,
    c: usize,
    k: isize,
) -> &'a [f64] {
    let (p, nz) = (grid.plane(), grid.n[2] as isize);
    let at = |f: &'a [f64], k: usize| &f[k * p..(k + 1) * p];
    match halo {
        Some(h) if k < 0 => at(&h.ghosts[c], (h.w as isize + k) as usize),
        Some(h) if k >= nz => at(&h.ghosts[c], h.w + (k - nz) as usize),
        _ => at(field, k.rem_euclid(nz) as usize),
    }
}

/// Row `row` (`j + ny k` of the slab) of `field` moved by `dk` planes along z (within the halo's
/// width on a slab): the row [`plane`] gives.
#[inline]
pub fn z_line<'a>(
    grid: &Grid,
    field: &'a [f64],
    halo: Option<&'a Halo>,
    c: usize,
    row: usize,
    dk: isize,
) -> &'a [f64] {
    let (nx, ny) = (grid.n[0], grid.n[1]);
    let (j, k) = (row % ny, row / ny);
    let p = plane(grid, field, halo, c, k as isize + dk);
    &p[j * nx..(j + 1) * nx]
}
