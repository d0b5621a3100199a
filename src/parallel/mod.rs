//! The distributed layer: everything tumble knows about running on several processes, under the
//! solvers and above the grid.
//!
//! The grid is split into slabs of whole z-planes ([`Slabs`]): z is the slowest axis of every
//! field, so a rank's nodes are one contiguous range of each field. The spectral solvers see the
//! transposed split as well: after the x and y transforms of its planes a rank owns a range of
//! y rows with every z ([`Slabs::rows`]), reached by one all-to-all ([`Comm::all_to_all`]), the
//! scheme of FFTW-MPI, P3DFFT and 2DECOMP&FFT with a one-dimensional process grid. Halo planes
//! ([`Comm::exchange`]) and global reductions ([`Comm::sum`], [`Comm::max`]) complete what the
//! stencils and the Krylov solvers need.
//!
//! [`Comm`] is MPI (the `mpi` feature, over the system's Open MPI) or a single process. A
//! single process runs the same code: its all-to-all is a copy, its exchange with itself a copy
//! and its reductions the identity. Nothing above the solvers calls MPI; `systems/` sees only
//! local extents.
//!
//! Reductions are computed the same way on every rank, in rank order, from all the ranks'
//! contributions (an all-gather, not `MPI_Allreduce`, whose result may differ in its last bits
//! between ranks and between runs): every rank then holds bit-identical sums, which is what keeps
//! the rigid bodies, integrated redundantly on every rank, identical everywhere, and a run with a
//! fixed rank count bit-identical to itself.

pub mod comm;
pub mod decomposition;
pub mod halo;
pub mod planes;
pub mod slabs;
pub mod transpose;

pub use comm::{Comm, Plain};
pub use decomposition::{Decomposition, Gather, global_max, global_sum};
pub use halo::Halo;
pub use planes::{PlaneSums, RowSums};
pub use slabs::{DecompositionError, Slabs, split};
pub use transpose::Transpose;
