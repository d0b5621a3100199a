//! The spectral solver allocates nothing after `Spectral::new` (a step allocates nothing).
//! Its own binary: the counting allocator below wraps the whole process, so it stays out of
//! the suite's other tests (and they out of its count).

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::sync::atomic::{AtomicUsize, Ordering};

use tumble::base::grid::Grid;

// The suite's shared helpers (`Rng`); this binary uses only part of them.
#[allow(dead_code)]
#[path = "suite/common.rs"]
mod common;
use common::Rng;
use tumble::solvers::fft::C64;
use tumble::solvers::operators::{Spectral, TopDamping};

// ---------------------------------------------------------------------------------------------
// Allocation counting: only threads marked through `MARK` (the workers of a dedicated rayon pool
// and the test thread while it measures) count, so concurrently running tests do not interfere.

struct Counting;

thread_local! {
    static MARK: Cell<bool> = const { Cell::new(false) };
}
static ALLOCS: AtomicUsize = AtomicUsize::new(0);

fn count() {
    if MARK.with(|m| m.get()) {
        ALLOCS.fetch_add(1, Ordering::Relaxed);
    }
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count();
        unsafe { System.alloc(layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        count();
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count();
        unsafe { System.realloc(ptr, layout, new_size) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn no_allocation_after_new() {
    for n in [[16, 12, 10], [20, 14, 1]] {
        let grid = Grid::new(n, 0.1, [0.0; 3]);
        // One worker thread: the work is the same as with more (fixed chunks), while rayon's own
        // work-stealing bookkeeping (which may allocate the first time a thread steals) stays
        // out of the count.
        // A worker stops counting before it exits: the pool of the previous grid is dropped
        // without waiting for its thread, whose thread-local destructors (crossbeam's epoch
        // handle pushes a bag) then allocate, under load during this grid's count.
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .start_handler(|_| MARK.with(|m| m.set(true)))
            .exit_handler(|_| MARK.with(|m| m.set(false)))
            .build()
            .unwrap();
        let ncomp = grid.omega_components();
        let mut rng = Rng(5);
        let mut omega: Vec<Vec<f64>> = (0..ncomp).map(|_| rng.field(grid.len())).collect();
        let mut u = vec![vec![0.0; grid.len()]; grid.dim];
        let a0 = ALLOCS.load(Ordering::Relaxed);
        let mut sp = pool.install(|| Spectral::new(&grid));
        // The counter works: `new` allocates on a marked worker thread.
        assert!(
            ALLOCS.load(Ordering::Relaxed) > a0,
            "allocation counter is not counting"
        );
        let mut hat = vec![C64::default(); sp.complex_len()];
        let mut back = vec![0.0; grid.len()];
        let mut step = |sp: &mut Spectral, v: u64| {
            sp.forward(&omega[0], &mut hat);
            sp.inverse(&mut hat, &mut back);
            sp.diffuse(&mut omega, 0.01, TopDamping::NONE, v);
            sp.velocity(&mut omega, v, [0.0; 3], &mut u);
            sp.velocity(&mut omega, v + 100, [0.0; 3], &mut u);
        };
        // Warm up (lets rayon's own queues reach their working size).
        pool.install(|| step(&mut sp, 0));
        let before = ALLOCS.load(Ordering::Relaxed);
        pool.install(|| {
            MARK.with(|m| m.set(true));
            for v in 1..4 {
                step(&mut sp, v);
            }
        });
        let after = ALLOCS.load(Ordering::Relaxed);
        assert_eq!(after - before, 0, "{n:?}: allocations after Spectral::new");
    }
}
