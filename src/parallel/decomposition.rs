//! The world's view of the split: a resource present when a run is spread over several
//! processes, absent on one (every system then runs as it always has).

use std::sync::Arc;

use bevy_ecs::prelude::Resource;

use crate::base::grid::Grid;
use crate::parallel::comm::Comm;
use crate::parallel::slabs::{DecompositionError, Slabs};

/// The processes a run is split over and this process's slab: a resource of a run on several
/// processes. The world's [`Grid`] is then this process's slab ([`Grid::slab`]).
#[derive(Resource, Debug, Clone)]
pub struct Decomposition {
    /// The processes.
    pub comm: Arc<Comm>,
    /// The split of the whole grid.
    pub slabs: Slabs,
}

impl Decomposition {
    /// The split of `whole` over the processes of `comm`; an error when it cannot be split that
    /// many ways.
    pub fn new(whole: &Grid, comm: Arc<Comm>) -> Result<Self, DecompositionError> {
        let slabs = Slabs::new(whole.n, comm.size(), comm.rank())?;
        Ok(Decomposition { comm, slabs })
    }

    /// This process's slab of `whole`.
    pub fn local_grid(&self, whole: &Grid) -> Grid {
        whole.slab(self.slabs.my_planes())
    }
}

/// The sum over the processes of `x` when split (`x` itself on one).
pub fn global_sum(d: Option<&Decomposition>, x: f64) -> f64 {
    d.map_or(x, |d| d.comm.sum_one(x))
}

/// The maximum over the processes of `x` when split (`x` itself on one).
pub fn global_max(d: Option<&Decomposition>, x: f64) -> f64 {
    d.map_or(x, |d| d.comm.max_one(x))
}
