//! The transpose between the slab layout of a field (a process's z-planes, every y) and its
//! row layout (a process's y rows, every z), for fields of rows of any width: real fields
//! (`nx` values a row: the z sweeps of the particles) and half spectra (`nx/2 + 1`: the FFTs).
//!
//! Slab layout: value `i` of row `(j, k)`, `k` one of the process's planes `k0..k0 + nk`, at
//! `i + w (j + ny (k - k0))`. Row layout: `j` one of its rows `j0..j0 + nyl`, at
//! `i + w ((j - j0) + nyl k)`: the whole grid's layout with `ny` replaced by the row count, so a
//! line along z is one process's and code written for the whole grid runs on it unchanged.
//!
//! Forward: each process's block for process `s` (its planes of `s`'s rows) is copied into a
//! send buffer in one parallel pass, then one all-to-all; on the receiving side a process's
//! planes of another's rows are one contiguous range of the row layout, so nothing is copied.
//! Backward: the same in reverse.

use rayon::prelude::*;

use crate::base::grid::SyncPtr;
use crate::parallel::comm::{Comm, Plain, count};
use crate::parallel::slabs::Slabs;

/// The geometry of one transpose (rows of `w` values): the copies and the all-to-all's counts.
#[derive(Debug, Clone)]
pub struct Transpose {
    /// (offset in the send buffer, offset in the slab layout, length): disjoint, one per
    /// process and plane.
    moves: Vec<[usize; 3]>,
    /// Counts and displacements of the blocks in the send buffer (by destination process).
    pcount: Vec<i32>,
    pdispl: Vec<i32>,
    /// Counts and displacements of the blocks in the row layout (by source process).
    rcount: Vec<i32>,
    rdispl: Vec<i32>,
    /// Values of one field in the slab layout (and in the send buffer).
    slab_len: usize,
    /// Values of one field in the row layout.
    rows_len: usize,
}

impl Transpose {
    /// The transpose of fields whose rows hold `w` values, split as `slabs`.
    pub fn new(slabs: &Slabs, w: usize) -> Self {
        let ny = slabs.n[1];
        let nk = slabs.my_planes().len();
        let nyl = slabs.my_rows().len();
        let (mut moves, mut pcount, mut pdispl) = (Vec::new(), Vec::new(), Vec::new());
        let (mut rcount, mut rdispl) = (Vec::new(), Vec::new());
        for s in 0..slabs.ranks {
            let rows = slabs.rows(s);
            let block = w * rows.len();
            pdispl.push(count(w * nk * rows.start));
            pcount.push(count(block * nk));
            for kl in 0..nk {
                moves.push([
                    w * nk * rows.start + block * kl,
                    w * (rows.start + ny * kl),
                    block,
                ]);
            }
            let planes = slabs.planes(s);
            rdispl.push(count(w * nyl * planes.start));
            rcount.push(count(w * nyl * planes.len()));
        }
        Transpose {
            moves,
            pcount,
            pdispl,
            rcount,
            rdispl,
            slab_len: w * ny * nk,
            rows_len: w * nyl * slabs.n[2],
        }
    }

    /// Values of one field in the slab layout (the send buffer's length too).
    pub fn slab_len(&self) -> usize {
        self.slab_len
    }

    /// Values of one field in the row layout.
    pub fn rows_len(&self) -> usize {
        self.rows_len
    }

    /// `slab` (slab layout) into `rows` (row layout); `packed` is scratch of
    /// [`Transpose::slab_len`] values.
    pub fn forward<T: Plain>(&self, comm: &Comm, slab: &[T], packed: &mut [T], rows: &mut [T]) {
        self.check(slab.len(), packed.len(), rows.len());
        let (src, dst) = (
            SyncPtr(slab.as_ptr() as *mut T),
            SyncPtr(packed.as_mut_ptr()),
        );
        self.moves.par_iter().for_each(|&[p, q, len]| {
            // SAFETY: the moves' ranges are disjoint in `packed` and in bounds of both buffers
            // by construction; `slab` is only read, and is not `packed` (distinct borrows).
            unsafe { dst.slice_mut(p, len).copy_from_slice(src.slice_mut(q, len)) };
        });
        comm.all_to_all(
            packed,
            &self.pcount,
            &self.pdispl,
            rows,
            &self.rcount,
            &self.rdispl,
        );
    }

    /// `rows` (row layout) back into `slab` (slab layout); `packed` is scratch of
    /// [`Transpose::slab_len`] values.
    pub fn backward<T: Plain>(&self, comm: &Comm, rows: &[T], packed: &mut [T], slab: &mut [T]) {
        self.check(slab.len(), packed.len(), rows.len());
        comm.all_to_all(
            rows,
            &self.rcount,
            &self.rdispl,
            packed,
            &self.pcount,
            &self.pdispl,
        );
        let (src, dst) = (
            SyncPtr(packed.as_ptr() as *mut T),
            SyncPtr(slab.as_mut_ptr()),
        );
        self.moves.par_iter().for_each(|&[p, q, len]| {
            // SAFETY: as in `forward`, with the roles of the buffers swapped.
            unsafe { dst.slice_mut(q, len).copy_from_slice(src.slice_mut(p, len)) };
        });
    }

    fn check(&self, slab: usize, packed: usize, rows: usize) {
        assert_eq!(slab, self.slab_len, "transpose: slab length");
        assert_eq!(packed, self.slab_len, "transpose: scratch length");
        assert_eq!(rows, self.rows_len, "transpose: rows length");
    }
}
