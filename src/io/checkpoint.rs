//! Checkpoint and restart: everything the next step needs, in one binary file.
//!
//! A checkpoint is written between two steps. Restoring it into a fresh [`Simulation`] of the
//! same scene and stepping on gives results identical bit for bit to the run that was never
//! stopped, so it holds every piece of state a step reads before recomputing it:
//!
//! * the fields: ω, u, the previous velocity u_prev (single precision, as the run keeps it)
//!   and the step between them (the mid-step extrapolation in transport and ∂u/∂t in the
//!   baroclinic term read them). The spectral solver's cached ω̂ is not kept: every step makes
//!   a new vorticity version (transport) before the Poisson solve, so the cache is never
//!   carried from one step to the next; it is invalidated on restore all the same;
//! * the clock ([`SimTime`]: t, the next dt, the step count, the stop time);
//! * every body's [`RigidState`] (pose, velocities, and the volume, χ-centroid and inertia of
//!   the last step, which the contact system reads before they are recomputed), [`Hydro`],
//!   [`ContactState`] (with its own κ), [`FreeMotion`] (the angular momentum a body in vacuum
//!   carries) and [`PreviousVelocity`], matched by [`Body::id`]. Level-set patches, density
//!   and χ are recomputed from the poses at the start of every step; kinematic prescriptions
//!   are functions of t;
//! * the scene as RON text (and the directory its mesh paths are relative to), and where the
//!   run's outputs stood ([`RunProgress`]: CSV lengths, snapshot count, `.pvd` entries, the
//!   next output time), so a restarted run continues its files without duplicate rows. HDF5
//!   outputs need nothing more here: a restart reads the times of the `.h5` snapshots kept
//!   (for `fields.xmf`) and `series.h5`, written at every checkpoint, back from the run
//!   directory (see [`crate::io::snapshots::Snapshots::resume`]);
//! * the state the systems keep, registered by their plugins
//!   ([`crate::schedule::PluginContext::checkpoint_resource`] and `checkpoint_part`): the
//!   diagnostics' last sample, the transport's split order, the pressure coupling's state, the
//!   free surface, the no-slip's last force, a user plugin's resources. One record per
//!   resource, its name, layout version and serde bytes, so this file knows no system: a
//!   record missing, left over or of another version is refused by name.
//!
//! Format: the magic `TUMBLECK` and the format version (u32, little-endian), which say what
//! the file is before anything else is read; then, serde in the postcard encoding, the header
//! (the tumble version) and the state; then a trailer: the byte length before it (u64,
//! little-endian), the CRC-32 of those bytes and `KEND`. Floats are written as their bits, so
//! values come back exactly. A foreign file, a checkpoint of another format (the hand-written
//! layout of format 2 and before) or of another tumble version, a truncated or corrupt file
//! (trailer or checksum) is refused with a [`CheckpointError`] naming the file and what it is.
//!
//! A run writes `checkpoint_NNNNNN.bin` (named by step, [`file_name`]) with
//! [`atomic_write_with`] (temporary `.checkpoint_NNNNNN.bin.tmp-*` in the same directory,
//! fsync, rename), so a killed run leaves whole checkpoints only; once one is complete the
//! oldest beyond `output.checkpoints_kept` are deleted ([`prune`], only files of that name).
//! `--restart DIR` takes the latest ([`resolve`]).

use crate::base::fields::{Failure, Fields, SimTime};
use crate::bodies::{Body, ContactState, FreeMotion, Hydro, PreviousVelocity, RigidState};
use crate::io::output::atomic_write_with;
use crate::scene::{Scene, ValidScene};
use crate::schedule::StateRecord;
use crate::sim::engine::Simulation;
use crate::solvers::Spectral;
use serde::{Deserialize, Serialize};
use std::borrow::Cow;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};

/// The single checkpoint file of runs written by earlier tumble versions, which `--restart DIR`
/// still finds (this version writes [`file_name`]).
pub const FILE_NAME: &str = "checkpoint.bin";
/// Name prefix of the numbered checkpoints a run keeps (`checkpoint_NNNNNN.bin`, the step).
const PREFIX: &str = "checkpoint_";
/// First bytes of every checkpoint.
pub const MAGIC: [u8; 8] = *b"TUMBLECK";
/// Last bytes of every complete checkpoint.
const END_MAGIC: [u8; 4] = *b"KEND";
/// The trailer: byte length (u64), CRC-32 (u32), [`END_MAGIC`].
const TRAILER: usize = 16;
/// Version of the layout; a checkpoint of another format version is refused. Formats 1 and 2
/// were hand-written; format 3 is serde (postcard) throughout; format 4 adds the bodies' last
/// accelerations to [`PreviousVelocity`] (the virtual mass's extrapolation). It changes with
/// the serialized layout of anything saved here: [`RunProgress`], [`SimTime`] and the body
/// components.
pub const FORMAT_VERSION: u32 = 4;
/// The tumble version that writes (and alone restarts) these checkpoints.
pub const CRATE_VERSION: &str = env!("CARGO_PKG_VERSION");

/// A checkpoint that cannot be used, and why; `tumble run --restart` exits with status 2.
#[derive(Debug, Clone, thiserror::Error)]
#[error("cannot restart from {}: {message}", file.display())]
pub struct CheckpointError {
    /// The checkpoint file.
    pub file: PathBuf,
    /// What is wrong.
    pub message: String,
}

/// A run stopped by SIGINT or SIGTERM after writing its checkpoint; `tumble run` exits with
/// status 130.
#[derive(Debug, Clone, thiserror::Error)]
#[error(
    "interrupted at step {step}, t = {t}; restart with tumble run --restart {}",
    checkpoint.display()
)]
pub struct Interrupted {
    /// Steps taken.
    pub step: u64,
    /// Simulated time reached.
    pub t: f64,
    /// The checkpoint written.
    pub checkpoint: PathBuf,
}

static INTERRUPT: AtomicBool = AtomicBool::new(false);

/// Make SIGINT (Ctrl-C) and SIGTERM ask the run to stop after its current step (see
/// [`interrupt_requested`]); a second signal exits at once with status 130.
pub fn install_interrupt_handler() -> anyhow::Result<()> {
    ctrlc::set_handler(|| {
        if INTERRUPT.swap(true, Ordering::SeqCst) {
            std::process::exit(130);
        }
        eprintln!(
            "\ninterrupt: stopping after this step and writing a checkpoint (again to stop at once)"
        );
    })
    .map_err(|e| anyhow::anyhow!("cannot install the interrupt handler: {e}"))
}

/// Whether a stop was requested (by a signal or [`request_interrupt`]).
pub fn interrupt_requested() -> bool {
    INTERRUPT.load(Ordering::SeqCst)
}

/// Ask the running loop to stop after its current step, as SIGINT does.
pub fn request_interrupt() {
    INTERRUPT.store(true, Ordering::SeqCst);
}

/// Forget a stop request.
pub fn clear_interrupt() {
    INTERRUPT.store(false, Ordering::SeqCst);
}

/// Whether `name` is a temporary file of an atomic write (`.NAME.tmp-PID-SEQ`): never a
/// result, left behind only by a killed run.
pub fn is_temp_file(name: &str) -> bool {
    name.starts_with('.') && name.contains(".tmp-")
}

/// Remove the temporary files a killed run left in `dir`; returns how many.
pub fn remove_temp_files(dir: &Path) -> io::Result<usize> {
    let mut n = 0;
    for e in std::fs::read_dir(dir)? {
        let e = e?;
        if e.file_name().to_str().is_some_and(is_temp_file) && e.file_type()?.is_file() {
            std::fs::remove_file(e.path())?;
            n += 1;
        }
    }
    Ok(n)
}

/// The file name of the checkpoint at `step`: `checkpoint_NNNNNN.bin` (at least 6 digits).
pub fn file_name(step: u64) -> String {
    format!("{PREFIX}{step:06}.bin")
}

/// The file of process `rank` of the checkpoint at `step` of a run split over `ranks`
/// processes: rank 0's is [`file_name`] (it carries the scene and the run's progress, and is
/// what `--restart DIR` finds), the others' `checkpoint_NNNNNN.rank{R}of{N}.bin`, each holding
/// that process's slab of the fields and its systems' state.
pub fn piece_file_name(step: u64, rank: usize, ranks: usize) -> String {
    if rank == 0 {
        file_name(step)
    } else {
        format!("{PREFIX}{step:06}.rank{rank}of{ranks}.bin")
    }
}

/// The step of a checkpoint file name tumble writes ([`file_name`]), `None` for any other.
pub fn step_of(name: &str) -> Option<u64> {
    let digits = name.strip_prefix(PREFIX)?.strip_suffix(".bin")?;
    if digits.len() < 6 || !digits.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    let step: u64 = digits.parse().ok()?;
    (file_name(step) == name).then_some(step)
}

/// The numbered checkpoints in `dir` (files named as [`file_name`] makes them), by step,
/// oldest first.
pub fn list(dir: &Path) -> io::Result<Vec<(u64, PathBuf)>> {
    let mut v = Vec::new();
    for e in std::fs::read_dir(dir)? {
        let e = e?;
        if let Some(step) = e.file_name().to_str().and_then(step_of)
            && e.file_type()?.is_file()
        {
            v.push((step, e.path()));
        }
    }
    v.sort();
    Ok(v)
}

/// Delete the numbered checkpoints in `dir` but the `keep` latest (by step); returns those
/// deleted. Only files named as [`file_name`] makes them are touched.
pub fn prune(dir: &Path, keep: usize) -> io::Result<Vec<PathBuf>> {
    let all = list(dir)?;
    let n = all.len().saturating_sub(keep);
    let mut gone = Vec::with_capacity(n);
    for (_, p) in all.into_iter().take(n) {
        std::fs::remove_file(&p)?;
        gone.push(p);
    }
    Ok(gone)
}

/// Delete the numbered checkpoints in `dir` of steps after `step` (written by a run that a
/// restart from `step` replaces); returns those deleted.
pub fn remove_after(dir: &Path, step: u64) -> io::Result<Vec<PathBuf>> {
    let mut gone = Vec::new();
    for (s, p) in list(dir)? {
        if s > step {
            std::fs::remove_file(&p)?;
            gone.push(p);
        }
    }
    Ok(gone)
}

/// The checkpoint `--restart PATH` means: PATH itself if it is a file; if it is a directory,
/// its latest complete checkpoint (the numbered one of the highest step that reads back
/// whole, else a `checkpoint.bin` of older tumble versions).
pub fn resolve(path: &Path) -> Result<PathBuf, CheckpointError> {
    let err = |message: String| CheckpointError {
        file: path.to_path_buf(),
        message,
    };
    if !path.is_dir() {
        return Ok(path.to_path_buf());
    }
    let all = list(path).map_err(|e| err(format!("cannot list the directory: {e}")))?;
    let mut refused = Vec::new();
    for (_, p) in all.into_iter().rev() {
        match Checkpoint::load(&p) {
            Ok(_) => return Ok(p),
            Err(e) => refused.push(e.to_string()),
        }
    }
    let legacy = path.join(FILE_NAME);
    if legacy.is_file() {
        return Ok(legacy);
    }
    Err(err(if refused.is_empty() {
        "the directory holds no checkpoint (checkpoint_NNNNNN.bin): the run wrote none (a run \
         writes one every output.checkpoint_wall seconds of wall time, 15 minutes by default, \
         every output.checkpoint_every of simulated time, and when stopped with Ctrl-C)"
            .to_string()
    } else {
        format!(
            "no checkpoint in the directory is usable: {}",
            refused.join("; ")
        )
    }))
}

/// Where a run's outputs stood when its checkpoint was written.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct RunProgress {
    /// The next snapshot time, if snapshots are periodic.
    pub next_out: Option<f64>,
    /// Snapshots written (the next one is `fields_{snapshots:06}.vti` / `.h5`).
    pub snapshots: u64,
    /// The `.pvd` entries: (time, file name); none without VTK output.
    pub pvd: Vec<(f64, String)>,
    /// Bytes of `series.csv`.
    pub series_len: u64,
    /// Bytes of `bodies.csv`, if written.
    pub bodies_len: Option<u64>,
    /// Bytes of `contacts.csv`, if written.
    pub contacts_len: Option<u64>,
}

/// The saved state of one body.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BodyState {
    /// [`Body::id`].
    pub id: usize,
    /// [`Body::name`].
    pub name: String,
    /// Pose, velocities, volume, centroid, inertia.
    pub rigid: RigidState,
    /// Hydrodynamic force and torque of the last step.
    pub hydro: Hydro,
    /// The body's own κ (`None`: each pair's default) and the contact force, torque and
    /// potential of the last step.
    pub contact: ContactState,
    /// Angular momentum carried in vacuum.
    pub free: FreeMotion,
    /// The previous step's ū (the body's acceleration in the baroclinic term).
    pub prev: PreviousVelocity,
}

/// A checkpoint read back (see the module docs for what it holds).
#[derive(Debug, Clone)]
pub struct Checkpoint {
    /// The file it was read from.
    pub file: PathBuf,
    /// The scene as run, RON.
    pub scene_ron: String,
    /// The directory the scene's relative mesh paths are resolved against.
    pub base_dir: PathBuf,
    /// Where the outputs stood.
    pub progress: RunProgress,
    /// The clock.
    pub time: SimTime,
    /// Grid node counts.
    pub n: [usize; 3],
    /// Vorticity components.
    pub omega: Vec<Vec<f64>>,
    /// Velocity components.
    pub u: Vec<Vec<f64>>,
    /// Previous velocity components (single precision, as the run keeps them).
    pub u_prev: Vec<Vec<f32>>,
    /// The step between `u_prev` and `u`.
    pub dt_prev: f64,
    /// Bodies, by id.
    pub bodies: Vec<BodyState>,
    /// The state records of the systems (see the module docs).
    pub state: Vec<StateRecord>,
}

/// What follows the magic and the format version.
#[derive(Serialize, Deserialize)]
struct Header {
    /// The tumble version that wrote the file.
    tumble: String,
}

/// The fields a step reads before recomputing them (borrowed from the simulation when
/// written).
#[derive(Serialize, Deserialize)]
struct SavedFields<'a> {
    n: [usize; 3],
    omega: Cow<'a, [Vec<f64>]>,
    u: Cow<'a, [Vec<f64>]>,
    u_prev: Cow<'a, [Vec<f32>]>,
    dt_prev: f64,
}

/// Everything after the header, as serde writes and reads it.
#[derive(Serialize, Deserialize)]
struct Saved<'a> {
    scene_ron: String,
    base_dir: String,
    progress: Cow<'a, RunProgress>,
    time: SimTime,
    fields: SavedFields<'a>,
    bodies: Vec<BodyState>,
    state: Vec<StateRecord>,
}

impl<'a> Saved<'a> {
    /// The state of `sim` (between two steps) and the run's `progress`.
    fn of(sim: &'a mut Simulation, progress: &'a RunProgress) -> io::Result<Saved<'a>> {
        let bodies = body_states(sim);
        let state = sim.save_state().map_err(io::Error::other)?;
        let sim: &'a Simulation = sim;
        let scene = sim.scene();
        let base_dir = std::path::absolute(&scene.base_dir).unwrap_or(scene.base_dir.clone());
        let f = sim.world.resource::<Fields>();
        Ok(Saved {
            scene_ron: scene.to_ron(),
            base_dir: base_dir.to_string_lossy().into_owned(),
            progress: Cow::Borrowed(progress),
            time: sim.world.resource::<SimTime>().clone(),
            fields: SavedFields {
                n: sim.grid().n,
                omega: Cow::Borrowed(f.omega()),
                u: Cow::Borrowed(&f.u),
                u_prev: Cow::Borrowed(&f.u_prev),
                dt_prev: f.dt_prev,
            },
            bodies,
            state,
        })
    }
}

/// A writer that counts and checksums the bytes passed to the one under it, and keeps that
/// writer's first error (postcard reports a failed write without its cause, e.g. a full
/// disk).
struct Checksummed<W: Write> {
    w: W,
    crc: crc32fast::Hasher,
    len: u64,
    error: Option<io::Error>,
}

impl<W: Write> Write for Checksummed<W> {
    fn write(&mut self, b: &[u8]) -> io::Result<usize> {
        if let Err(e) = self.w.write_all(b) {
            let again = io::Error::new(e.kind(), e.to_string());
            self.error.get_or_insert(e);
            return Err(again);
        }
        self.crc.update(b);
        self.len += b.len() as u64;
        Ok(b.len())
    }
    fn flush(&mut self) -> io::Result<()> {
        self.w.flush()
    }
}

impl<W: Write> Checksummed<W> {
    /// Magic, format version, then header and `saved` in postcard.
    fn data(&mut self, saved: &Saved) -> io::Result<()> {
        self.write_all(&MAGIC)?;
        self.write_all(&FORMAT_VERSION.to_le_bytes())?;
        let header = Header {
            tumble: CRATE_VERSION.to_string(),
        };
        let encode = |e| io::Error::other(format!("cannot encode the checkpoint: {e}"));
        let mut buf = BufWriter::with_capacity(1 << 16, &mut *self);
        postcard::to_io(&header, &mut buf).map_err(encode)?;
        postcard::to_io(saved, &mut buf).map_err(encode)?;
        buf.flush()
    }

    /// The byte length and checksum of everything written, and the end marker.
    fn trailer(mut self) -> io::Result<()> {
        let crc = self.crc.clone().finalize();
        self.w.write_all(&self.len.to_le_bytes())?;
        self.w.write_all(&crc.to_le_bytes())?;
        self.w.write_all(&END_MAGIC)?;
        self.w.flush()
    }
}

/// The saved state of every body of `sim`, sorted by id.
pub fn body_states(sim: &mut Simulation) -> Vec<BodyState> {
    let mut q = sim.world.query::<(
        &Body,
        &RigidState,
        &Hydro,
        &ContactState,
        &FreeMotion,
        &PreviousVelocity,
    )>();
    let mut out: Vec<BodyState> = q
        .iter(&sim.world)
        .map(|(b, r, h, c, f, p)| BodyState {
            id: b.id,
            name: b.name.clone(),
            rigid: *r,
            hydro: *h,
            contact: *c,
            free: *f,
            prev: *p,
        })
        .collect();
    out.sort_by_key(|b| b.id);
    out
}

/// Write a checkpoint of `sim` (between two steps) and the run's `progress` to `w`.
pub fn write_to(w: impl Write, sim: &mut Simulation, progress: &RunProgress) -> io::Result<()> {
    let saved = Saved::of(sim, progress)?;
    let mut out = Checksummed {
        w,
        crc: crc32fast::Hasher::new(),
        len: 0,
        error: None,
    };
    if let Err(e) = out.data(&saved) {
        return Err(out.error.take().unwrap_or(e));
    }
    out.trailer()
}

/// A checkpoint of `sim` as bytes.
pub fn to_bytes(sim: &mut Simulation, progress: &RunProgress) -> Vec<u8> {
    let mut v = Vec::new();
    write_to(&mut v, sim, progress).expect("writing to memory cannot fail");
    v
}

/// Write a checkpoint of `sim` to `path` atomically (temporary file, fsync, rename).
pub fn save(path: &Path, sim: &mut Simulation, progress: &RunProgress) -> io::Result<()> {
    atomic_write_with(path, |w| write_to(w, sim, progress))
}

impl Checkpoint {
    /// Read and check a checkpoint file.
    pub fn load(path: &Path) -> Result<Checkpoint, CheckpointError> {
        let bytes = std::fs::read(path).map_err(|e| CheckpointError {
            file: path.to_path_buf(),
            message: format!("cannot read the file: {e}"),
        })?;
        Checkpoint::from_bytes(&bytes, path)
    }

    /// Check and decode checkpoint bytes; `file` names them in errors.
    pub fn from_bytes(bytes: &[u8], file: &Path) -> Result<Checkpoint, CheckpointError> {
        decode(bytes, file).map_err(|message| CheckpointError {
            file: file.to_path_buf(),
            message,
        })
    }

    /// The error `message` about this checkpoint.
    pub fn error(&self, message: impl Into<String>) -> CheckpointError {
        CheckpointError {
            file: self.file.clone(),
            message: message.into(),
        }
    }

    /// The scene the checkpoint was written with (its mesh paths resolved as in the run).
    pub fn scene(&self) -> Result<ValidScene, CheckpointError> {
        Scene::parse_in(
            &self.scene_ron,
            &self.file.display().to_string(),
            "",
            &self.base_dir,
        )
        .map_err(|e| self.error(format!("its scene does not load: {e}")))
    }

    /// A simulation of `scene` (the checkpoint's, possibly with another end time or
    /// checkpoint interval) in the checkpoint's state.
    pub fn simulation(&self, scene: ValidScene) -> anyhow::Result<Simulation> {
        let mut sim = Simulation::new(scene)?;
        self.restore(&mut sim)?;
        Ok(sim)
    }

    /// Overwrite the state of `sim`, built from the checkpoint's scene, with the checkpoint's.
    pub fn restore(&self, sim: &mut Simulation) -> Result<(), CheckpointError> {
        self.check_fits(sim)?;
        self.restore_fields(sim);
        *sim.world.resource_mut::<SimTime>() = self.time.clone();
        sim.world.resource_mut::<Failure>().reason = None;
        self.restore_bodies(sim);
        sim.restore_state(&self.state).map_err(|m| self.error(m))
    }

    /// Whether the fields fit the grid of `sim` and the bodies are its bodies.
    fn check_fits(&self, sim: &mut Simulation) -> Result<(), CheckpointError> {
        let grid = sim.grid();
        if grid.n != self.n {
            return Err(self.error(format!(
                "its grid has {:?} nodes, the scene's has {:?}",
                self.n, grid.n
            )));
        }
        fn fits<T>(f: &[Vec<T>], nc: usize, len: usize) -> bool {
            f.len() == nc && f.iter().all(|c| c.len() == len)
        }
        if !fits(&self.omega, grid.omega_components(), grid.len())
            || !fits(&self.u, grid.dim, grid.len())
            || !fits(&self.u_prev, grid.dim, grid.len())
        {
            return Err(self.error("its fields do not fit the scene's grid"));
        }
        let ids: Vec<(usize, String)> = body_states(sim)
            .into_iter()
            .map(|b| (b.id, b.name))
            .collect();
        let saved: Vec<(usize, String)> =
            self.bodies.iter().map(|b| (b.id, b.name.clone())).collect();
        if ids != saved {
            return Err(self.error(format!("its bodies {saved:?} are not the scene's {ids:?}")));
        }
        Ok(())
    }

    /// ω, u, u_prev and the step between them; the spectral solver's cached ω̂ is dropped.
    fn restore_fields(&self, sim: &mut Simulation) {
        let mut f = sim.world.resource_mut::<Fields>();
        for (dst, src) in f.omega_mut().iter_mut().zip(&self.omega) {
            dst.copy_from_slice(src);
        }
        for (dst, src) in f.u.iter_mut().zip(&self.u) {
            dst.copy_from_slice(src);
        }
        for (dst, src) in f.u_prev.iter_mut().zip(&self.u_prev) {
            dst.copy_from_slice(src);
        }
        f.dt_prev = self.dt_prev;
        sim.world.resource_mut::<Spectral>().invalidate();
    }

    /// Every body's components, matched by id (checked by [`Checkpoint::check_fits`]).
    fn restore_bodies(&self, sim: &mut Simulation) {
        let mut q = sim.world.query::<(
            &Body,
            &mut RigidState,
            &mut Hydro,
            &mut ContactState,
            &mut FreeMotion,
            &mut PreviousVelocity,
        )>();
        for (b, mut r, mut h, mut c, mut f, mut p) in q.iter_mut(&mut sim.world) {
            let s = &self.bodies[self
                .bodies
                .binary_search_by_key(&b.id, |s| s.id)
                .expect("ids checked before")];
            *r = s.rigid;
            *h = s.hydro;
            *c = s.contact;
            *f = s.free;
            *p = s.prev;
        }
    }

    /// The checkpoint read from `file` as `saved`.
    fn from_saved(file: &Path, saved: Saved) -> Result<Checkpoint, String> {
        if !saved.bodies.windows(2).all(|w| w[0].id < w[1].id) {
            return Err("corrupt data (bodies out of order)".into());
        }
        let f = saved.fields;
        Ok(Checkpoint {
            file: file.to_path_buf(),
            scene_ron: saved.scene_ron,
            base_dir: PathBuf::from(saved.base_dir),
            progress: saved.progress.into_owned(),
            time: saved.time,
            n: f.n,
            omega: f.omega.into_owned(),
            u: f.u.into_owned(),
            u_prev: f.u_prev.into_owned(),
            dt_prev: f.dt_prev,
            bodies: saved.bodies,
            state: saved.state,
        })
    }
}

/// Check and decode the bytes of a checkpoint read from `file`: what the file is, who wrote
/// it, whether it is whole, then its state.
fn decode(b: &[u8], file: &Path) -> Result<Checkpoint, String> {
    let after_format = identify(b)?;
    let after_header = check_header(after_format)?;
    let data = check_trailer(b, b.len() - after_header.len())?;
    let (saved, rest) =
        postcard::take_from_bytes::<Saved>(data).map_err(|e| format!("corrupt data ({e})"))?;
    if !rest.is_empty() {
        return Err(format!(
            "corrupt data ({} unexpected bytes at the end)",
            rest.len()
        ));
    }
    Checkpoint::from_saved(file, saved)
}

/// What this tumble reads, for the messages that refuse a file.
fn what_is_read() -> String {
    format!(
        "this tumble {CRATE_VERSION} reads checkpoints of format {FORMAT_VERSION} (serde, \
         postcard), written by tumble {CRATE_VERSION}"
    )
}

/// The bytes after the magic and the format version if they say the file is a checkpoint of
/// [`FORMAT_VERSION`]; else what the file is.
fn identify(b: &[u8]) -> Result<&[u8], String> {
    let truncated = || {
        format!(
            "the file is truncated ({} bytes, not even a header): it was cut short; use an \
             older checkpoint or rerun the scene",
            b.len()
        )
    };
    let Some(rest) = b.strip_prefix(&MAGIC) else {
        if b.is_empty() {
            return Err(format!(
                "the file is empty, not a tumble checkpoint; {}",
                what_is_read()
            ));
        }
        if !MAGIC.starts_with(b) {
            let start = &b[..b.len().min(MAGIC.len())];
            return Err(format!(
                "not a tumble checkpoint (it starts with \"{}\", a checkpoint with the \
                 TUMBLECK header); {}",
                start.escape_ascii(),
                what_is_read()
            ));
        }
        return Err(truncated());
    };
    let Some((format, rest)) = rest.split_first_chunk::<4>() else {
        return Err(truncated());
    };
    match u32::from_le_bytes(*format) {
        FORMAT_VERSION => Ok(rest),
        old @ 3..FORMAT_VERSION => Err(format!(
            "it is a checkpoint in format {old}, the layout of an earlier build; {}: restart \
             it with the tumble that wrote it, or rerun the scene",
            what_is_read()
        )),
        old @ 1..3 => Err(format!(
            "it is a checkpoint in format {old}, the hand-written layout of earlier builds \
             ({}); {}: restart it with the tumble that wrote it, or rerun the scene",
            old_writer(rest).map_or("its writer unknown".into(), |v| format!("by tumble {v}")),
            what_is_read()
        )),
        other => Err(format!(
            "it is a checkpoint in format {other}, which this tumble does not know; {}: \
             restart it with the tumble that wrote it, or rerun the scene",
            what_is_read()
        )),
    }
}

/// The tumble version that wrote a checkpoint of format 1 or 2, from its header (a u64 byte
/// length and the text), if it reads as one.
fn old_writer(rest: &[u8]) -> Option<String> {
    let (len, rest) = rest.split_first_chunk::<8>()?;
    let text = rest.get(
        ..usize::try_from(u64::from_le_bytes(*len))
            .ok()
            .filter(|&n| n <= 64)?,
    )?;
    String::from_utf8(text.to_vec()).ok()
}

/// The bytes after the header if the tumble version that wrote them is this one.
fn check_header(b: &[u8]) -> Result<&[u8], String> {
    let (header, rest) = postcard::take_from_bytes::<Header>(b).map_err(|e| match e {
        postcard::Error::DeserializeUnexpectedEnd => {
            "the file is truncated (it ends inside its header): it was cut short; use an older \
             checkpoint or rerun the scene"
                .to_string()
        }
        e => format!("corrupt header ({e})"),
    })?;
    if header.tumble != CRATE_VERSION {
        return Err(format!(
            "it was written by tumble {0}, and this is tumble {CRATE_VERSION}: a checkpoint \
             restarts only with the version that wrote it (use tumble {0}, or rerun the scene)",
            header.tumble
        ));
    }
    Ok(rest)
}

/// The bytes from `start` to the trailer, if the trailer is there and their length and
/// checksum are the ones it gives for everything before it.
fn check_trailer(b: &[u8], start: usize) -> Result<&[u8], String> {
    let n = b.len();
    if n < start + TRAILER || b[n - 4..] != END_MAGIC {
        return Err(format!(
            "the file is truncated or incomplete ({n} bytes, no end marker): it was cut short, \
             e.g. copied while being written; use an older checkpoint or rerun the scene"
        ));
    }
    let (data, trailer) = b.split_at(n - TRAILER);
    let len = u64::from_le_bytes(trailer[..8].try_into().expect("8 bytes"));
    if len != data.len() as u64 {
        return Err(format!(
            "the file is truncated or corrupt (its trailer gives {len} bytes of data, it holds \
             {})",
            data.len()
        ));
    }
    let crc = u32::from_le_bytes(trailer[8..12].try_into().expect("4 bytes"));
    if crc32fast::hash(data) != crc {
        return Err(
            "the file is corrupt (checksum mismatch): it changed after it was written; use an \
             older checkpoint or rerun the scene"
                .into(),
        );
    }
    Ok(&data[start..])
}

/// The scene text that decides whether two scenes are the same run: everything but the end
/// time and the checkpoint intervals (a restart may change them) and the output directory (a
/// restart writes into the checkpoint's).
fn run_identity(scene: &Scene) -> String {
    let mut s = scene.clone();
    s.numerics.end_time = 0.0;
    s.output.checkpoint_every = None;
    s.output.checkpoint_wall = None;
    s.output.dir = None;
    s.to_ron()
}

/// Whether `a` and `b` are the same run (see [`run_identity`]).
pub fn same_run(a: &Scene, b: &Scene) -> bool {
    run_identity(a) == run_identity(b)
}
