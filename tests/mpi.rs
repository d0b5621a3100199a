//! The distributed layer on several processes: `cargo test --release --features mpi --test mpi`.
//!
//! Started by `cargo test`, this binary starts itself under `mpirun`, on 2 processes and on 3
//! (slabs of unequal thickness), and passes if every process of both runs does. Under `mpirun`
//! it runs the checks of `tests/distributed/checks.rs` (the suite runs the same checks on one
//! process), each against the whole computation done on every process. Then `tumble run` itself
//! (`tests/distributed/run.rs`): a scene run by `mpirun -np 2` and `-np 3` gives the
//! one-process run's `series.csv` and snapshots, and with the `hdf5` feature
//! its HDF5 snapshots, body surfaces and `series.h5`.

#[path = "distributed/checks.rs"]
mod checks;
#[path = "distributed/run.rs"]
mod run;

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

use tumble::parallel::comm::Mpi;

/// Rust allocations made by any thread while `COUNTING` is set (MPI's own, in C, are not
/// Rust's and are not counted).
struct Counting;
static COUNTING: AtomicBool = AtomicBool::new(false);
static ALLOCS: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if COUNTING.load(Ordering::Relaxed) {
            ALLOCS.fetch_add(1, Ordering::Relaxed);
        }
        unsafe { System.alloc(layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if COUNTING.load(Ordering::Relaxed) {
            ALLOCS.fetch_add(1, Ordering::Relaxed);
        }
        unsafe { System.realloc(ptr, layout, new_size) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// The split spectral solver allocates nothing after its first use: diffusion, velocity,
/// the Laplacian's inverse and the forcing velocity, with their transposes and reductions;
/// returns the allocations counted on every process.
fn split_spectral_allocates_nothing(comm: Arc<tumble::parallel::Comm>) -> f64 {
    use tumble::base::grid::Grid;
    use tumble::solvers::operators::{Spectral, TopDamping};
    let grid = Grid::new([16, 10, 18], 0.1, [0.0; 3]);
    // The counter counts: making the solver allocates.
    COUNTING.store(true, Ordering::Relaxed);
    let mut sp = Spectral::split(&grid, comm.clone()).expect("grid splits");
    COUNTING.store(false, Ordering::Relaxed);
    if ALLOCS.swap(0, Ordering::Relaxed) == 0 {
        return f64::INFINITY;
    }
    sp.reserve_forcing();
    let n = sp.real_len();
    let mut w: Vec<Vec<f64>> = (0..3)
        .map(|c| (0..n).map(|i| ((i * 7 + c) % 13) as f64 - 6.0).collect())
        .collect();
    let mut u = vec![vec![0.0; n]; 3];
    let mut x = vec![0.0; n];
    let damp = TopDamping {
        strength: 0.3,
        order: 2,
    };
    let mut once = |version: u64| {
        sp.diffuse(&mut w, 1e-3, damp, version);
        sp.velocity(&mut w, version, [0.0; 3], &mut u);
        sp.solve_laplacian(&w[0], &mut x);
        sp.forcing_velocity(&w, 1e-3, &mut u);
    };
    // Inside a one-thread pool: called from outside, every parallel loop would hand rayon's
    // injector a job, and its queue allocates a block every 63 (crossbeam's `Injector`), which
    // is rayon's bookkeeping, not the solver's.
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("a one-thread pool");
    pool.install(|| once(1));
    comm.barrier();
    pool.install(|| {
        COUNTING.store(true, Ordering::Relaxed);
        once(2);
        COUNTING.store(false, Ordering::Relaxed);
    });
    comm.sum_one(ALLOCS.swap(0, Ordering::Relaxed) as f64)
}

/// A split step of a scene with bodies (level sets, contact, penalization, the pressure solve
/// with its halos and plane sums and, at a density ratio of 5 or more, the split multigrid
/// hierarchy, transport, the no-slip's markers) allocates nothing once the run is under way;
/// returns the allocations counted on every process over two steps.
fn split_step_allocates_nothing(comm: Arc<tumble::parallel::Comm>, scene: &str) -> f64 {
    use tumble::scene::Scene;
    use tumble::sim::engine::Simulation;
    let scene = Scene::parse(scene, "check.ron", "check").expect("scene parses");
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("a one-thread pool");
    let mut sim = pool.install(|| {
        Simulation::builder(scene)
            .on_processes(comm.clone())
            .build()
            .expect("split simulation builds")
    });
    pool.install(|| {
        for _ in 0..3 {
            sim.step().expect("step");
        }
    });
    comm.barrier();
    pool.install(|| {
        COUNTING.store(true, Ordering::Relaxed);
        for _ in 0..2 {
            sim.step().expect("step");
        }
        COUNTING.store(false, Ordering::Relaxed);
    });
    comm.sum_one(ALLOCS.swap(0, Ordering::Relaxed) as f64)
}

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
        0.0,
    ),
    (
        "taylor_green_matches_whole",
        |c| checks::simulation_matches_whole(c, checks::TAYLOR_GREEN, 12),
        0.0,
    ),
    (
        "vortex_ring_matches_whole",
        |c| checks::simulation_matches_whole(c, checks::VORTEX_RING, 12),
        0.0,
    ),
    (
        "bodies_match_whole",
        |c| checks::simulation_matches_whole(c, checks::BODIES, 12),
        0.0,
    ),
    (
        "periodic_sphere_matches_whole",
        |c| checks::simulation_matches_whole(c, checks::PERIODIC_SPHERE, 12),
        0.0,
    ),
    (
        "pool_matches_whole",
        |c| checks::simulation_matches_whole(c, checks::POOL, 8),
        0.0,
    ),
    (
        "split_pool_step_allocates_nothing",
        |c| split_step_allocates_nothing(c, checks::POOL),
        0.0,
    ),
    (
        "split_body_step_allocates_nothing",
        |c| split_step_allocates_nothing(c, checks::BODIES),
        0.0,
    ),
    (
        "split_multigrid_step_allocates_nothing",
        |c| split_step_allocates_nothing(c, &checks::dense_bodies()),
        0.0,
    ),
    (
        "multigrid_matches_whole_red_black",
        |c| checks::multigrid_matches_whole(c, [16, 12, 48]),
        0.0,
    ),
    (
        "multigrid_matches_whole_odd",
        |c| checks::multigrid_matches_whole(c, [16, 12, 23]),
        0.0,
    ),
    (
        "multigrid_matches_whole_by_three",
        |c| checks::multigrid_matches_whole(c, [18, 18, 45]),
        0.0,
    ),
    (
        "multigrid_matches_whole_unaligned",
        |c| checks::multigrid_matches_whole(c, [16, 12, 26]),
        0.0,
    ),
    (
        "variable_poisson_matches_whole",
        |c| checks::variable_poisson_matches_whole(c, [16, 12, 48]),
        0.0,
    ),
    (
        "variable_poisson_matches_whole_odd",
        |c| checks::variable_poisson_matches_whole(c, [16, 12, 23]),
        0.0,
    ),
    (
        "dense_bodies_match_whole_bit_for_bit",
        |c| checks::multigrid_scene_matches_whole_bit_for_bit(c, &checks::dense_bodies(), 12),
        0.0,
    ),
    (
        "split_runs_are_bit_identical",
        |c| checks::split_runs_are_bit_identical(c, checks::VORTEX_RING, 6),
        0.0,
    ),
    (
        "split_spectral_allocates_nothing",
        split_spectral_allocates_nothing,
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
            "bodies under mpirun match one process bit for bit, and restart",
            run::bodies_match_one_process_bit_for_bit,
        ),
        (
            "tumble validate under mpirun gives the one-process report",
            run::validate_matches_one_process,
        ),
        (
            "a killed process, then --restart, is bit-identical",
            run::killed_and_restarted_is_bit_identical,
        ),
        (
            "a free surface under mpirun matches one process bit for bit, and restarts",
            run::free_surface_matches_one_process_bit_for_bit,
        ),
        (
            "a scene that cannot split is refused and writes nothing",
            run::unsplittable_scene_is_refused_and_writes_nothing,
        ),
        (
            "other commands refuse several processes",
            run::other_commands_refuse_several_processes,
        ),
        #[cfg(feature = "hdf5")]
        (
            "HDF5 snapshots under mpirun read as one process's",
            run::hdf5_matches_one_process,
        ),
        #[cfg(feature = "hdf5")]
        (
            "HDF5 body surfaces under mpirun are one process's, and restart",
            run::hdf5_bodies_match_one_process,
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
