//! Everything that touches files: VTK and HDF5/XDMF snapshots, checkpoints, the run log and
//! the plots.

pub mod checkpoint;
pub mod disk;
pub mod estimate;
#[cfg(feature = "hdf5")]
pub mod hdf5_out;
pub mod isosurface;
pub mod output;
pub mod plot;
pub mod runlog;
pub mod slices;
pub mod snapshots;
pub mod summary;
pub mod surfaces;
pub mod xdmf;
