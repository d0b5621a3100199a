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
