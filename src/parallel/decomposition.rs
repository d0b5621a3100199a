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

/// The whole grid's field from every process's planes of it (an all-gather), for the few
/// operations that read a field far from a node (the free surface's extensions along a wall's
/// or a body's normal): per process the planes' counts and offsets, made once.
#[derive(Debug, Clone)]
pub struct Gather {
    d: Decomposition,
    counts: Vec<i32>,
    displ: Vec<i32>,
}

impl Gather {
    /// The gather of fields of `plane` values a z-plane over `d`'s slabs.
    pub fn new(d: &Decomposition, plane: usize) -> Self {
        let ranks = d.slabs.ranks;
        let bounds: Vec<usize> = (0..ranks)
            .map(|r| d.slabs.planes(r).start)
            .chain([d.slabs.n[2]])
            .collect();
        Gather::of_planes(d, plane, &bounds)
    }

    /// The gather of fields of `plane` values a plane, rank `r` holding the planes
    /// `bounds[r]..bounds[r + 1]` (a coarse level of a hierarchy, split its own way).
    pub fn of_planes(d: &Decomposition, plane: usize, bounds: &[usize]) -> Self {
        let count = crate::parallel::comm::count;
        Gather {
            d: d.clone(),
            counts: bounds
                .windows(2)
                .map(|b| count(plane * (b[1] - b[0])))
                .collect(),
            displ: bounds[..d.slabs.ranks]
                .iter()
                .map(|&a| count(plane * a))
                .collect(),
        }
    }

    /// `whole` (the whole grid's length) on rank 0 from every process's planes `mine` (the
    /// other processes' `whole` may be empty), on every process together.
    pub fn to_root(&self, mine: &[f64], whole: &mut [f64]) {
        self.d
            .comm
            .gather_varcount(mine, whole, &self.counts, &self.displ);
    }

    /// `whole` (the whole grid's length) from this process's planes `mine`, on every process
    /// together.
    pub fn whole(&self, mine: &[f64], whole: &mut [f64]) {
        self.d
            .comm
            .all_gather_varcount(mine, whole, &self.counts, &self.displ);
    }
}

impl Decomposition {
    /// Makes every process's `reason` (why the run must stop, set by the systems of this
    /// process) the same: the lowest rank's that has one, labelled with its rank, or `None`
    /// when none has. Every process calls it together (each step): a process that stopped
    /// alone would leave the others waiting in the next exchange.
    pub fn agree_failure(&self, reason: &mut Option<String>) {
        let any = self.comm.max_one(if reason.is_some() { 1.0 } else { 0.0 });
        if any == 0.0 {
            return;
        }
        let (p, me) = (self.comm.size(), self.comm.rank());
        // Every process's message length, then the bytes (exact in f64), in one sum each.
        let mine = reason.as_deref().unwrap_or("").as_bytes();
        let mut lens = vec![0.0; p];
        lens[me] = mine.len() as f64;
        self.comm.sum(&mut lens);
        let Some(first) = lens.iter().position(|&l| l > 0.0) else {
            return;
        };
        let mut bytes = vec![0.0; lens[first] as usize];
        if me == first {
            for (b, &c) in bytes.iter_mut().zip(mine) {
                *b = c as f64;
            }
        }
        self.comm.sum(&mut bytes);
        let text: Vec<u8> = bytes.iter().map(|&b| b as u8).collect();
        let text = String::from_utf8_lossy(&text);
        *reason = Some(if p > 1 {
            format!("(process {first} of {p}) {text}")
        } else {
            text.into_owned()
        });
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
