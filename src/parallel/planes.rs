//! Sums over the grid that come out the same, bit for bit, on any number of processes.
//!
//! A sum over the grid is taken in two levels: each z-plane's partial sum first (its rows in
//! order), then the planes' partials added in plane order. Every plane is whole on one process,
//! so each process fills the partials of its own planes and zeros elsewhere, the processes'
//! arrays are added (each entry is non-zero on one process only: x + 0 = x, exact in any
//! order), and every process adds the planes in order: the very sum one process takes. With
//! the fields themselves the same bit for bit on any process count (the transforms, the
//! transport and the stencils compute each node from the same values), a run then does not
//! depend on how many processes it is split over.

use crate::parallel::Comm;

/// Per-plane partial sums of `width` values each, for the planes of the whole grid (or of a
/// body's box along z), preallocated.
#[derive(Debug, Clone, Default)]
pub struct PlaneSums {
    width: usize,
    buf: Vec<f64>,
    /// The reduction's send buffer (several processes).
    scratch: Vec<f64>,
}

impl PlaneSums {
    /// Room for `planes` planes of `width` values.
    pub fn new(planes: usize, width: usize) -> Self {
        PlaneSums {
            width,
            buf: vec![0.0; planes * width],
            scratch: vec![0.0; planes * width],
        }
    }

    /// Planes of room.
    pub fn len(&self) -> usize {
        self.buf.len() / self.width.max(1)
    }

    /// Whether there is no room.
    pub fn is_empty(&self) -> bool {
        self.buf.is_empty()
    }

    /// Zeroes the first `planes` planes' partials (before a process fills its own).
    pub fn clear(&mut self, planes: usize) {
        self.buf[..planes * self.width].fill(0.0);
    }

    /// The partials of plane `k`.
    pub fn plane_mut(&mut self, k: usize) -> &mut [f64] {
        &mut self.buf[k * self.width..(k + 1) * self.width]
    }

    /// Adds the first `planes` planes' partials over the processes of `comm` (each plane's are
    /// one process's: exact), then the planes in order, into `out` (the first `out.len()`
    /// values of each plane's, at most `width`).
    pub fn total(&mut self, comm: Option<&Comm>, planes: usize, out: &mut [f64]) {
        let w = self.width;
        let all = &mut self.buf[..planes * w];
        if let Some(c) = comm {
            c.sum_disjoint(all, &mut self.scratch);
        }
        out.fill(0.0);
        for p in all.chunks_exact(w) {
            for (o, v) in out.iter_mut().zip(p) {
                *o += v;
            }
        }
    }

    /// [`PlaneSums::total`] of one value a plane.
    pub fn total_one(&mut self, comm: Option<&Comm>, planes: usize) -> f64 {
        let mut out = [0.0];
        self.total(comm, planes, &mut out);
        out[0]
    }
}

/// Sums over a slab's x-rows (one partial per row, `j + ny k`) taken as [`PlaneSums`] does:
/// the rows of each plane in order, then the planes, the same on any number of processes.
#[derive(Debug, Clone)]
pub struct RowSums {
    ny: usize,
    k0: usize,
    nz_whole: usize,
    planes: PlaneSums,
    comm: Option<std::sync::Arc<Comm>>,
}

impl RowSums {
    /// For the rows of `grid` (a slab of `split`'s, or the whole grid).
    pub fn new(
        grid: &crate::base::grid::Grid,
        split: Option<&crate::parallel::Decomposition>,
    ) -> Self {
        RowSums {
            ny: grid.n[1],
            k0: grid.k0,
            nz_whole: grid.nz_whole,
            planes: PlaneSums::new(grid.nz_whole, 1),
            comm: split.map(|d| d.comm.clone()),
        }
    }

    /// The sum of the rows' partials `partial` (this process's rows) over the whole grid.
    pub fn total(&mut self, partial: &[f64]) -> f64 {
        self.planes.clear(self.nz_whole);
        for (k, rows) in partial.chunks(self.ny).enumerate() {
            let mut s = 0.0;
            for v in rows {
                s += v;
            }
            self.planes.plane_mut(self.k0 + k)[0] = s;
        }
        self.planes.total_one(self.comm.as_deref(), self.nz_whole)
    }

    /// The node count of the whole grid, for rows of `nx` nodes.
    pub fn whole_len(&self, nx: usize) -> usize {
        nx * self.ny * self.nz_whole
    }
}
