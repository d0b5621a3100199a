//! The distributed layer on one process (`tumble::parallel`, the split FFT engine): the same
//! checks `tests/mpi.rs` runs on 2 and 3 processes, the transposes with itself against the
//! engine without them, and the decomposition's limits.

#[path = "../distributed/checks.rs"]
mod checks;

use std::sync::Arc;

use tumble::base::grid::Grid;
use tumble::parallel::{Comm, DecompositionError, Slabs, split};
use tumble::solvers::fft::{C64, FftEngine};

fn solo() -> Arc<Comm> {
    Arc::new(Comm::solo())
}

#[test]
fn one_process_checks() {
    assert!(checks::fft_matches_whole(solo(), [16, 12, 20]) <= 1e-12);
    assert!(checks::fft_matches_whole(solo(), [15, 9, 19]) <= 1e-12);
    assert!(checks::spectral_matches_whole(solo(), [16, 10, 18]) <= 1e-12);
    assert_eq!(
        checks::halo_planes_are_the_neighbours(solo(), [6, 5, 18]),
        0.0
    );
    assert_eq!(checks::sums_are_identical_everywhere(solo()), 0.0);
    for n in [[16, 12, 48], [16, 12, 23], [18, 18, 45], [16, 12, 26]] {
        assert_eq!(checks::multigrid_matches_whole(solo(), n), 0.0, "{n:?}");
    }
    assert_eq!(
        checks::variable_poisson_matches_whole(solo(), [16, 12, 23]),
        0.0
    );
    assert_eq!(
        checks::multigrid_scene_matches_whole_bit_for_bit(solo(), &checks::dense_bodies(), 2),
        0.0
    );
    // One process runs unsplit: the builder's path with a communicator changes nothing.
    assert_eq!(
        checks::simulation_matches_whole(solo(), checks::TAYLOR_GREEN, 2),
        0.0
    );
    assert_eq!(
        checks::simulation_matches_whole(solo(), checks::VORTEX_RING, 2),
        0.0
    );
    assert_eq!(
        checks::simulation_matches_whole(solo(), checks::BODIES, 2),
        0.0
    );
    assert_eq!(
        checks::simulation_matches_whole(solo(), checks::PERIODIC_SPHERE, 2),
        0.0
    );
    assert_eq!(
        checks::simulation_matches_whole(solo(), checks::POOL, 2),
        0.0
    );
    assert_eq!(
        checks::split_runs_are_bit_identical(solo(), checks::VORTEX_RING, 2),
        0.0
    );
}

/// On one process the split engine's transposes are copies: its spectrum and inverse are the
/// unsplit engine's, bit for bit, fused planes (3D, 8 planes or more) or not.
#[test]
fn split_engine_on_one_process_is_the_engine_bit_for_bit() {
    for n in [[16, 12, 20], [9, 8, 3], [12, 10, 1]] {
        let grid = Grid::new(n, 0.25, [0.0; 3]);
        let f = checks::field(&grid, 3);
        let mut a = FftEngine::new(&grid);
        let mut b = FftEngine::split(&grid, solo()).unwrap();
        assert_eq!(a.complex_len(), b.complex_len());
        let (mut sa, mut sb) = (
            vec![C64::default(); a.complex_len()],
            vec![C64::default(); b.complex_len()],
        );
        a.forward(&f, &mut sa);
        b.forward(&f, &mut sb);
        assert!(sa == sb, "{n:?}: spectra differ");
        let (mut ra, mut rb) = (vec![0.0; f.len()], vec![0.0; f.len()]);
        a.inverse(Some(&sa), &mut sa.clone(), &mut ra);
        b.inverse(None, &mut sb, &mut rb);
        assert!(ra == rb, "{n:?}: inverses differ");
    }
}

/// The split hierarchy distributes the levels while every slab starts on an aggregate along z
/// and holds two planes or more, and gathers the rest: on one process every level but the
/// coarsest is distributed (and `one_process_checks` finds its cycle the whole grid's, bit for
/// bit, on every kind of coarsening).
#[test]
fn split_multigrid_distributes_the_levels_it_can() {
    use tumble::parallel::Decomposition;
    use tumble::solvers::multigrid::{Multigrid, distributed_levels};
    for n in [[16, 12, 48], [16, 12, 23], [18, 18, 45]] {
        let grid = Grid::new(n, 0.1, [0.0; 3]);
        let d = Decomposition::new(&grid, solo()).unwrap();
        let mg = Multigrid::split(&grid, &d);
        let whole = Multigrid::new(&grid);
        assert_eq!(mg.level_sizes(), whole.level_sizes(), "{n:?}");
        assert_eq!(
            mg.distributed_levels(),
            whole.level_sizes().len() - 1,
            "{n:?}"
        );
    }
    // Three processes on 23 planes (8, 8, 7): the slabs start on aggregates of 2 (planes 8
    // and 16, then 4 and 8 of the 11 of level 1); level 2 (5 planes) would leave the last
    // process one plane and is gathered. On 26 planes (9, 9, 8) the slabs start inside
    // aggregates: every process holds the whole hierarchy. 45 planes coarsen by 3: on three
    // processes (15 each) level 1's slabs (5 planes) start inside its aggregates of 3, on two
    // (23, 22) already level 0's do.
    for (n, ranks, dist) in [
        ([16, 12, 48], 2, 2),
        ([16, 12, 48], 3, 2),
        ([16, 12, 23], 2, 2),
        ([16, 12, 23], 3, 2),
        ([16, 12, 26], 3, 0),
        ([18, 18, 45], 3, 1),
        ([18, 18, 45], 2, 0),
    ] {
        assert_eq!(distributed_levels(n, ranks), dist, "{n:?} on {ranks}");
    }
}

#[test]
fn slabs_split_evenly_and_refuse_what_cannot_split() {
    // 10 planes over 4 processes: 3, 3, 2, 2, covering 0..10 in order.
    let parts: Vec<_> = (0..4).map(|r| split(10, 4, r)).collect();
    assert_eq!(parts, vec![0..3, 3..6, 6..8, 8..10]);
    let s = Slabs::new([8, 8, 26], 4, 3).unwrap();
    assert_eq!(s.planes(3), 20..26);
    assert_eq!(s.neighbours(), (2, 0));
    assert_eq!(s.my_planes().len(), 6);
    // Each process needs six planes (the remeshing kernel's reach at the step bound) and one
    // spectral row.
    assert!(matches!(
        Slabs::new([8, 8, 26], 5, 0),
        Err(DecompositionError::TooManyRanks { max: 4, .. })
    ));
    assert!(matches!(
        Slabs::new([8, 3, 64], 4, 0),
        Err(DecompositionError::TooManyRanks { max: 3, .. })
    ));
    assert!(matches!(
        Slabs::new([8, 8, 1], 2, 0),
        Err(DecompositionError::TwoD { ranks: 2 })
    ));
    assert!(Slabs::new([8, 8, 1], 1, 0).is_ok());
}
