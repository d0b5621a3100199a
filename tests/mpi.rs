//! The distributed layer on several processes: `cargo test --release --features mpi --test mpi`.
//!
//! Started by `cargo test`, this binary starts itself under `mpirun`, on 2 processes and on 3
//! (slabs of unequal thickness), and passes if every process of both runs does. Under `mpirun`
//! it runs the checks of `tests/distributed/checks.rs` (the suite runs the same checks on one
//! process), each against the whole computation done on every process. Then `tumble run` itself
//! (`tests/distributed/run.rs`): a scene run by `mpirun -np 2` and `-np 3` gives the
//! one-process run's `series.csv` and snapshots.

#[path = "distributed/checks.rs"]
mod checks;
#[path = "distributed/run.rs"]
mod run;

use std::sync::Arc;

use tumble::parallel::comm::Mpi;

/// One check: its name and the largest error it measured with the tolerance it is held to.
type Check = (&'static str, fn(Arc<tumble::parallel::Comm>) -> f64, f64);

const CHECKS: &[Check] = &[
    (
        "fft_matches_whole_even",
        |c| checks::fft_matches_whole(c, [16, 12, 20]),
        1e-12,
    ),
    (
        "fft_matches_whole_odd",
        |c| checks::fft_matches_whole(c, [15, 9, 19]),
        1e-12,
    ),
    (
        "spectral_matches_whole",
        |c| checks::spectral_matches_whole(c, [16, 10, 18]),
        1e-12,
    ),
    (
        "taylor_green_matches_whole",
        |c| checks::simulation_matches_whole(c, checks::TAYLOR_GREEN, 12),
        1e-12,
    ),
    (
        "vortex_ring_matches_whole",
        |c| checks::simulation_matches_whole(c, checks::VORTEX_RING, 12),
        1e-12,
    ),
    (
        "split_runs_are_bit_identical",
        |c| checks::split_runs_are_bit_identical(c, checks::VORTEX_RING, 6),
        0.0,
    ),
    (
        "halo_planes_are_the_neighbours",
        |c| checks::halo_planes_are_the_neighbours(c, [6, 5, 18]),
        0.0,
    ),
    (
        "sums_are_identical_everywhere",
        checks::sums_are_identical_everywhere,
        0.0,
    ),
];

fn under_mpirun() -> bool {
    std::env::var_os("OMPI_COMM_WORLD_SIZE").is_some() || std::env::var_os("PMI_SIZE").is_some()
}

fn main() {
    if under_mpirun() {
        std::process::exit(ranks_main());
    }
    let exe = std::env::current_exe().expect("test binary path");
    let (mut passed, mut failed) = (0, 0);
    for np in [2, 3] {
        let mut cmd = run::mpirun(np);
        cmd.arg(&exe);
        let status = cmd.status().unwrap_or_else(|e| {
            panic!("cannot start mpirun ({e}): install Open MPI (openmpi-bin, libopenmpi-dev)")
        });
        if status.success() {
            passed += CHECKS.len();
        } else {
            println!("mpirun -np {np}: failed ({status})");
            failed += CHECKS.len();
        }
    }
    for (name, test) in [
        (
            "tumble run under mpirun matches one process",
            run::run_matches_one_process as fn() -> Result<(), String>,
        ),
        (
            "a killed process, then --restart, is bit-identical",
            run::killed_and_restarted_is_bit_identical,
        ),
    ] {
        match test() {
            Ok(()) => {
                println!("{name}: ok");
                passed += 1;
            }
            Err(e) => {
                println!("{name}: FAILED: {e}");
                failed += 1;
            }
        }
    }
    println!(
        "test result: {}. {passed} passed; {failed} failed",
        if failed == 0 { "ok" } else { "FAILED" }
    );
    if failed > 0 {
        std::process::exit(1);
    }
}

/// Runs every check on this process; rank 0 reports. The exit code is non-zero on every
/// process if any check failed anywhere (each check's figure is already reduced).
fn ranks_main() -> i32 {
    let mpi = Mpi::init()
        .expect("MPI initializes")
        .expect("MPI not yet initialized");
    let comm = Arc::new(mpi.world());
    let mut failed = 0;
    for (name, check, tol) in CHECKS {
        let err = check(comm.clone());
        let ok = err <= *tol;
        if comm.is_root() {
            println!(
                "{} processes: {name}: {err:.3e} (tolerance {tol:.0e}) {}",
                comm.size(),
                if ok { "ok" } else { "FAILED" }
            );
        }
        failed += usize::from(!ok);
    }
    i32::from(failed > 0)
}
