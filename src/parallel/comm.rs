//! The communicator: MPI over the system's Open MPI (the `mpi` feature), or one process.
//!
//! Only this file names MPI. Every operation is collective over the communicator's ranks
//! except [`Comm::exchange`], which pairs each rank with two partners. Calls come from one thread
//! at a time (the schedule runs one system at a time; MPI is initialized with
//! `MPI_THREAD_SERIALIZED`), never from inside a rayon loop.

use std::sync::Mutex;

use crate::parallel::slabs::Slabs;
use rustfft::num_complex::Complex;

/// Double precision complex number, as the FFTs store it.
pub type C64 = Complex<f64>;

/// A value the processes exchange as it is in memory: `f64` and [`C64`].
#[cfg(feature = "mpi")]
pub trait Plain: Copy + Send + Sync + mpi::datatype::Equivalence {}
/// A value the processes exchange as it is in memory: `f64` and [`C64`].
#[cfg(not(feature = "mpi"))]
pub trait Plain: Copy + Send + Sync {}
impl Plain for f64 {}
impl Plain for C64 {}

/// A group of processes that run one simulation together.
pub struct Comm {
    inner: Inner,
    /// Nanoseconds spent in all-to-alls and exchanges with other processes (for `tumble bench`).
    waited: std::sync::atomic::AtomicU64,
    /// Scratch of the reductions (one value per rank and entry); grows to the longest reduction
    /// once, then is reused.
    gathered: Mutex<Vec<f64>>,
}

enum Inner {
    /// One process: every collective is a local copy or nothing.
    Solo,
    #[cfg(feature = "mpi")]
    Mpi(mpi::topology::SimpleCommunicator),
}

// SAFETY: an MPI communicator is a handle that MPI lets any thread use when the library was
// initialized with MPI_THREAD_SERIALIZED or above ([`Mpi::init`] checks it) and the calls are
// not concurrent: every method takes `&self` but is only called from the schedule's systems and
// the driver, which run one at a time, never from parallel loops (the module docs).
#[cfg(feature = "mpi")]
unsafe impl Send for Comm {}
#[cfg(feature = "mpi")]
unsafe impl Sync for Comm {}

impl std::fmt::Debug for Comm {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Comm(rank {} of {})", self.rank(), self.size())
    }
}

impl Default for Comm {
    fn default() -> Self {
        Comm::solo()
    }
}

impl Comm {
    /// One process on its own.
    pub fn solo() -> Self {
        Comm {
            inner: Inner::Solo,
            gathered: Mutex::new(Vec::new()),
            waited: Default::default(),
        }
    }

    /// The processes of an MPI communicator (a duplicate of `comm`, so tumble's messages never
    /// meet the caller's; it is freed when the `Comm` is dropped, which must be before MPI is
    /// finalized).
    #[cfg(feature = "mpi")]
    pub fn from_mpi(comm: &impl mpi::topology::Communicator) -> Self {
        Comm {
            inner: Inner::Mpi(comm.duplicate()),
            gathered: Mutex::new(Vec::new()),
            waited: Default::default(),
        }
    }

    /// This process's rank, `0..size`.
    pub fn rank(&self) -> usize {
        match &self.inner {
            Inner::Solo => 0,
            #[cfg(feature = "mpi")]
            Inner::Mpi(c) => {
                use mpi::topology::Communicator;
                c.rank() as usize
            }
        }
    }

    /// The number of processes.
    pub fn size(&self) -> usize {
        match &self.inner {
            Inner::Solo => 1,
            #[cfg(feature = "mpi")]
            Inner::Mpi(c) => {
                use mpi::topology::Communicator;
                c.size() as usize
            }
        }
    }

    /// Seconds this process has spent in all-to-alls and exchanges with other processes (the
    /// transposes and halos; 0 on one process).
    pub fn seconds_communicating(&self) -> f64 {
        self.waited.load(std::sync::atomic::Ordering::Relaxed) as f64 * 1e-9
    }

    #[cfg(feature = "mpi")]
    fn count_time(&self, t0: std::time::Instant) {
        let ns = t0.elapsed().as_nanos() as u64;
        self.waited
            .fetch_add(ns, std::sync::atomic::Ordering::Relaxed);
    }

    /// Whether this is rank 0 (the one that writes files meant to exist once).
    pub fn is_root(&self) -> bool {
        self.rank() == 0
    }

    /// Waits until every rank has called it.
    pub fn barrier(&self) {
        match &self.inner {
            Inner::Solo => {}
            #[cfg(feature = "mpi")]
            Inner::Mpi(c) => {
                use mpi::collective::CommunicatorCollectives;
                c.barrier()
            }
        }
    }

    /// Replaces every entry of `v` by its sum over the ranks, added in rank order, so every rank
    /// gets the same bits (module docs of [`crate::parallel`]).
    pub fn sum(&self, v: &mut [f64]) {
        self.reduce(v, |a, b| a + b);
    }

    /// Replaces every entry of `v` by its sum over the ranks when each entry is non-zero on at
    /// most one rank (the partial sums of planes each rank holds whole): every order of that
    /// sum is exact, so one `MPI_Allreduce` gives every rank the same bits, receiving `v.len()`
    /// values (not `v.len()` per rank as [`Comm::sum`] does). `scratch` is as long as `v`.
    pub fn sum_disjoint(&self, v: &mut [f64], scratch: &mut [f64]) {
        match &self.inner {
            Inner::Solo => {
                let _ = (v, scratch);
            }
            #[cfg(feature = "mpi")]
            Inner::Mpi(c) => {
                use mpi::collective::{CommunicatorCollectives, SystemOperation};
                let scratch = &mut scratch[..v.len()];
                scratch.copy_from_slice(v);
                let t0 = std::time::Instant::now();
                c.all_reduce_into(&*scratch, v, SystemOperation::sum());
                self.count_time(t0);
            }
        }
    }

    /// Replaces every entry of `v` by its maximum over the ranks.
    pub fn max(&self, v: &mut [f64]) {
        self.reduce(v, f64::max);
    }

    /// The sum over the ranks of one value.
    pub fn sum_one(&self, x: f64) -> f64 {
        let mut v = [x];
        self.sum(&mut v);
        v[0]
    }

    /// The maximum over the ranks of one value.
    pub fn max_one(&self, x: f64) -> f64 {
        let mut v = [x];
        self.max(&mut v);
        v[0]
    }

    fn reduce(&self, v: &mut [f64], op: impl Fn(f64, f64) -> f64) {
        let (p, len) = (self.size(), v.len());
        let mut all = self.gathered.lock().unwrap_or_else(|e| e.into_inner());
        if all.len() < p * len {
            all.resize(p * len, 0.0);
        }
        let all = &mut all[..p * len];
        match &self.inner {
            Inner::Solo => all.copy_from_slice(v),
            #[cfg(feature = "mpi")]
            Inner::Mpi(c) => {
                use mpi::collective::CommunicatorCollectives;
                c.all_gather_into(&*v, all);
            }
        }
        for (e, x) in v.iter_mut().enumerate() {
            let mut acc = all[e];
            for r in 1..p {
                acc = op(acc, all[r * len + e]);
            }
            *x = acc;
        }
    }

    /// All-to-all with counts: rank `r`'s block for rank `s` is `send[sdispl[s]..][..scount[s]]`
    /// and lands on `s` at `recv[rdispl[r]..][..rcount[r]]`. Counts and displacements are in
    /// values, MPI's 32-bit integers ([`count`] makes them). One process copies its one block.
    pub fn all_to_all<T: Plain>(
        &self,
        send: &[T],
        scount: &[i32],
        sdispl: &[i32],
        recv: &mut [T],
        rcount: &[i32],
        rdispl: &[i32],
    ) {
        match &self.inner {
            Inner::Solo => {
                let n = scount[0] as usize;
                assert_eq!(
                    scount[0], rcount[0],
                    "all_to_all: one process sends what it receives"
                );
                let (s, r) = (sdispl[0] as usize, rdispl[0] as usize);
                recv[r..r + n].copy_from_slice(&send[s..s + n]);
            }
            #[cfg(feature = "mpi")]
            Inner::Mpi(c) => {
                use mpi::collective::CommunicatorCollectives;
                use mpi::datatype::{Partition, PartitionMut};
                let s = Partition::new(send, scount, sdispl);
                let mut r = PartitionMut::new(recv, rcount, rdispl);
                let t0 = std::time::Instant::now();
                c.all_to_all_varcount_into(&s, &mut r);
                self.count_time(t0);
            }
        }
    }

    /// All-gather with counts: every rank's `send` (`counts[r]` values on rank `r`) lands on
    /// every rank at `recv[displs[r]..][..counts[r]]`, in rank order (MPI's all-gather-v; a
    /// copy of the data, so every rank holds the same bits). One process copies `send`.
    pub fn all_gather_varcount(
        &self,
        send: &[f64],
        recv: &mut [f64],
        counts: &[i32],
        displs: &[i32],
    ) {
        assert_eq!(
            send.len(),
            counts[self.rank()] as usize,
            "all_gather_varcount: this rank sends its count"
        );
        match &self.inner {
            Inner::Solo => {
                let d = displs[0] as usize;
                recv[d..d + send.len()].copy_from_slice(send);
            }
            #[cfg(feature = "mpi")]
            Inner::Mpi(c) => {
                use mpi::collective::CommunicatorCollectives;
                use mpi::datatype::PartitionMut;
                let mut r = PartitionMut::new(recv, counts, displs);
                let t0 = std::time::Instant::now();
                c.all_gather_varcount_into(send, &mut r);
                self.count_time(t0);
            }
        }
    }

    /// Gather with counts to rank 0: every rank's `send` (`counts[r]` values on rank `r`) lands
    /// at `recv[displs[r]..][..counts[r]]` on rank 0, whose `recv` is as long as all of them;
    /// the other ranks' `recv` is not touched (may be empty). One process copies `send`.
    pub fn gather_varcount(&self, send: &[f64], recv: &mut [f64], counts: &[i32], displs: &[i32]) {
        match &self.inner {
            Inner::Solo => {
                let d = displs[0] as usize;
                recv[d..d + send.len()].copy_from_slice(send);
                let _ = counts;
            }
            #[cfg(feature = "mpi")]
            Inner::Mpi(c) => {
                use mpi::collective::Root;
                use mpi::datatype::PartitionMut;
                use mpi::topology::Communicator;
                let root = c.process_at_rank(0);
                let t0 = std::time::Instant::now();
                if self.rank() == 0 {
                    let mut r = PartitionMut::new(recv, counts, displs);
                    root.gather_varcount_into_root(send, &mut r);
                } else {
                    root.gather_varcount_into(send);
                }
                self.count_time(t0);
            }
        }
    }

    /// Sends `to_below` to the rank below and `to_above` to the rank above (periodic) and
    /// receives the rank above's `to_below` into `from_above` and the rank below's `to_above`
    /// into `from_below`: a halo exchange along the split axis. With one process the data goes
    /// round to itself.
    pub fn exchange(
        &self,
        slabs: &Slabs,
        to_below: &[f64],
        to_above: &[f64],
        from_below: &mut [f64],
        from_above: &mut [f64],
    ) {
        match &self.inner {
            Inner::Solo => {
                assert_eq!(
                    slabs.neighbours(),
                    (0, 0),
                    "exchange: one process is its neighbour"
                );
                from_above.copy_from_slice(to_below);
                from_below.copy_from_slice(to_above);
            }
            #[cfg(feature = "mpi")]
            Inner::Mpi(c) => {
                use mpi::point_to_point::send_receive_into;
                use mpi::topology::Communicator;
                let (below, above) = slabs.neighbours();
                let (pb, pa) = (
                    c.process_at_rank(below as i32),
                    c.process_at_rank(above as i32),
                );
                let t0 = std::time::Instant::now();
                send_receive_into(to_below, &pb, from_above, &pa);
                send_receive_into(to_above, &pa, from_below, &pb);
                self.count_time(t0);
            }
        }
    }
}

/// An MPI count or displacement: the buffers of one process stay below 2³¹ values of their
/// type (a clear panic past it, when the layout is made).
pub fn count(x: usize) -> i32 {
    i32::try_from(x).unwrap_or_else(|_| {
        panic!("comm: a message of {x} values is past MPI's 32-bit counts; use more processes")
    })
}

/// The MPI environment of a process started by `mpirun`: initialized once, finalized when the
/// value is dropped (at the end of `main`).
#[cfg(feature = "mpi")]
pub struct Mpi {
    universe: mpi::environment::Universe,
}

#[cfg(feature = "mpi")]
impl Mpi {
    /// Initializes MPI for serialized calls from any thread; `None` if it was already
    /// initialized, an error if the library cannot serialize calls from several threads.
    pub fn init() -> anyhow::Result<Option<Mpi>> {
        use mpi::Threading;
        let Some((universe, level)) = mpi::initialize_with_threading(Threading::Serialized) else {
            return Ok(None);
        };
        if level < Threading::Serialized {
            anyhow::bail!(
                "the MPI library offers thread level {level:?}; tumble needs Serialized (calls \
                 from one thread at a time, not always the main one)"
            );
        }
        Ok(Some(Mpi { universe }))
    }

    /// The communicator of every process of the run (`MPI_COMM_WORLD` itself, which outlives
    /// every [`Comm`] made of it: nothing is freed after MPI is finalized).
    pub fn world(&self) -> Comm {
        Comm {
            inner: Inner::Mpi(self.universe.world()),
            gathered: Mutex::new(Vec::new()),
            waited: Default::default(),
        }
    }
}

/// The processes `mpirun` started this one among, when there are several: MPI (kept
/// initialized while this lives) and their communicator.
pub struct Processes {
    /// Every process of the run.
    pub comm: std::sync::Arc<Comm>,
    #[cfg(feature = "mpi")]
    _mpi: Mpi,
}

/// The number of processes the launcher says this one is among (Open MPI's or a PMI
/// launcher's variables), if any.
pub fn launcher_size() -> Option<usize> {
    ["OMPI_COMM_WORLD_SIZE", "PMI_SIZE"]
        .iter()
        .find_map(|v| std::env::var(v).ok()?.parse().ok())
}

/// The processes of this run: `None` on one (not started by `mpirun`, or `-np 1`); an error if
/// `mpirun` started several and this build has no MPI, or MPI cannot start.
pub fn launched() -> anyhow::Result<Option<Processes>> {
    let Some(n) = launcher_size().filter(|&n| n > 1) else {
        return Ok(None);
    };
    #[cfg(feature = "mpi")]
    {
        let _ = n;
        let mpi = Mpi::init()?.ok_or_else(|| anyhow::anyhow!("MPI was already initialized"))?;
        let comm = std::sync::Arc::new(mpi.world());
        Ok(Some(Processes { comm, _mpi: mpi }))
    }
    #[cfg(not(feature = "mpi"))]
    anyhow::bail!(
        "started by mpirun on {n} processes, but this tumble was built without MPI: build it \
         with `cargo build --release --features mpi` (needs libopenmpi-dev, openmpi-bin and \
         libclang-dev)"
    )
}
