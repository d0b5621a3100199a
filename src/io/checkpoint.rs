//! Checkpoint and restart: everything the next step needs, in one binary file.
//!
//! A checkpoint is written between two steps. Restoring it into a fresh [`Simulation`] of the
//! same scene and stepping on gives results identical bit for bit to the run that was never
//! stopped, so it holds every piece of state a step reads before recomputing it:
//!
//! * the fields: ω, u, the previous velocity u_prev and the step between them (the mid-step
//!   extrapolation in transport and ∂u/∂t in the baroclinic term read them). The spectral
//!   solver's cached ω̂ is not kept: every step makes a new vorticity version (transport)
//!   before the Poisson solve, so the cache is never carried from one step to the next; it is
//!   invalidated on restore all the same;
//! * the clock ([`SimTime`]: t, the next dt, the step count, the stop time);
//! * the diagnostics: the last sample (the next adaptive dt is chosen from it), the initial
//!   max|ω| (the blow-up guard's reference) and the fallback step (it depends on the end time
//!   the run started with, which a restart may change);
//! * the transport's split order, which alternates every step and is stored, not derived;
//! * every body's [`RigidState`] (pose, velocities, and the volume, χ-centroid and inertia of
//!   the last step, which the contact system reads before they are recomputed), [`Hydro`],
//!   [`ContactState`] (its own κ written as an f64, NaN for `None`: the body takes each pair's
//!   scaled default) and [`FreeMotion`] (the angular momentum a body in vacuum carries),
//!   matched by [`Body::id`]. Level-set patches, density and χ are recomputed from the poses at
//!   the start of every step; kinematic prescriptions are functions of t;
//! * the scene as RON text (and the directory its mesh paths are relative to), and where the
//!   run's outputs stood ([`RunProgress`]: CSV lengths, snapshot count, `.pvd` entries, the
//!   next output time), so a restarted run continues its files without duplicate rows. HDF5
//!   outputs need nothing more here: a restart reads the times of the `.h5` snapshots kept
//!   (for `fields.xmf`) and `series.h5`, written at every checkpoint, back from the run
//!   directory (see [`crate::io::snapshots::Snapshots::resume`]).
//!
//! * the state the plugins registered ([`crate::schedule::PluginContext::checkpoint_resource`]):
//!   one record per resource, its name, layout version and serde (postcard) bytes, so a new
//!   system's state needs no encoder here. A record missing, left over or of another
//!   version is refused by name.
//!
//! Format (little-endian): the magic `TUMBLECK`, the format version (u32), the tumble version
//! (string), the CRC-32 of the scene text, the payload (f64 as raw bits, so values come back
//! exactly), then a trailer: the byte length before it (u64), the CRC-32 of those bytes and
//! `KEND`. A checkpoint from another format or tumble version, a truncated or corrupt file
//! (trailer or checksum) is refused with a [`CheckpointError`] naming the file.
//!
//! A run writes `checkpoint_NNNNNN.bin` (named by step, [`file_name`]) with
//! [`atomic_write_with`] (temporary `.checkpoint_NNNNNN.bin.tmp-*` in the same directory,
//! fsync, rename), so a killed run leaves whole checkpoints only; once one is complete the
//! oldest beyond `output.checkpoints_kept` are deleted ([`prune`], only files of that name).
//! `--restart DIR` takes the latest ([`resolve`]).

use crate::base::fields::{Failure, Fields, Sample, SimTime};
use crate::bodies::{Body, ContactState, FreeMotion, Hydro, PreviousVelocity, RigidState};
use crate::io::output::atomic_write_with;
use crate::scene::{Scene, ValidScene};
use crate::schedule::StateRecord;
use crate::sim::engine::Simulation;
use crate::solvers::Spectral;
use crate::systems::diagnostics::Diagnostics;
use crate::systems::transport::TransportScratch;
use glam::{DMat3, DQuat, DVec3};
use std::io::{self, Write};
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
/// Version of the layout; a checkpoint of another format version is refused.
pub const FORMAT_VERSION: u32 = 2;
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
        "the directory holds no checkpoint (checkpoint_NNNNNN.bin); was the run written with \
         output.checkpoint_every or --checkpoint-every, or stopped with Ctrl-C?"
            .to_string()
    } else {
        format!(
            "no checkpoint in the directory is usable: {}",
            refused.join("; ")
        )
    }))
}

/// Where a run's outputs stood when its checkpoint was written.
#[derive(Debug, Clone, PartialEq, Default)]
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
#[derive(Debug, Clone, PartialEq)]
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
    /// The last diagnostics sample.
    pub sample: Sample,
    /// Initial max|ω| (the blow-up guard's reference).
    pub omega0: f64,
    /// The fallback step of the adaptive time step.
    pub dt_fallback: f64,
    /// Whether the next transport step sweeps the axes in reverse.
    pub reverse: bool,
    /// Grid node counts.
    pub n: [usize; 3],
    /// Vorticity components.
    pub omega: Vec<Vec<f64>>,
    /// Velocity components.
    pub u: Vec<Vec<f64>>,
    /// Previous velocity components (kept in single precision by the run, widened here).
    pub u_prev: Vec<Vec<f64>>,
    /// The step between `u_prev` and `u`.
    pub dt_prev: f64,
    /// Bodies, by id.
    pub bodies: Vec<BodyState>,
    /// The plugins' state records.
    pub state: Vec<StateRecord>,
}

/// Little-endian writer that counts and checksums what it writes.
struct Enc<W: Write> {
    w: W,
    crc: crc32fast::Hasher,
    len: u64,
    buf: Vec<u8>,
}

impl<W: Write> Enc<W> {
    fn bytes(&mut self, b: &[u8]) -> io::Result<()> {
        self.crc.update(b);
        self.len += b.len() as u64;
        self.w.write_all(b)
    }
    fn u8(&mut self, v: u8) -> io::Result<()> {
        self.bytes(&[v])
    }
    fn u32(&mut self, v: u32) -> io::Result<()> {
        self.bytes(&v.to_le_bytes())
    }
    fn u64(&mut self, v: u64) -> io::Result<()> {
        self.bytes(&v.to_le_bytes())
    }
    fn f64(&mut self, v: f64) -> io::Result<()> {
        self.bytes(&v.to_bits().to_le_bytes())
    }
    fn opt_f64(&mut self, v: Option<f64>) -> io::Result<()> {
        match v {
            Some(x) => {
                self.u8(1)?;
                self.f64(x)
            }
            None => self.u8(0),
        }
    }
    fn opt_u64(&mut self, v: Option<u64>) -> io::Result<()> {
        match v {
            Some(x) => {
                self.u8(1)?;
                self.u64(x)
            }
            None => self.u8(0),
        }
    }
    fn str(&mut self, s: &str) -> io::Result<()> {
        self.u64(s.len() as u64)?;
        self.bytes(s.as_bytes())
    }
    fn vec3(&mut self, v: DVec3) -> io::Result<()> {
        self.f64(v.x)?;
        self.f64(v.y)?;
        self.f64(v.z)
    }
    fn f64s<T: Copy + Into<f64>>(&mut self, v: &[T]) -> io::Result<()> {
        self.u64(v.len() as u64)?;
        let mut buf = std::mem::take(&mut self.buf);
        for chunk in v.chunks(8192) {
            buf.clear();
            for &x in chunk {
                buf.extend_from_slice(&x.into().to_bits().to_le_bytes());
            }
            self.bytes(&buf)?;
        }
        self.buf = buf;
        Ok(())
    }
    /// A field's components as doubles (single precision ones are widened, exactly).
    fn fields<T: Copy + Into<f64>>(&mut self, f: &[Vec<T>]) -> io::Result<()> {
        self.u32(f.len() as u32)?;
        for c in f {
            self.f64s(c)?;
        }
        Ok(())
    }
}

/// Reader of what [`Enc`] writes; every error is a message for a [`CheckpointError`].
struct Dec<'a> {
    b: &'a [u8],
    pos: usize,
}

impl<'a> Dec<'a> {
    fn take(&mut self, n: usize) -> Result<&'a [u8], String> {
        if self.b.len() - self.pos < n {
            return Err("the file is truncated (it ends inside its data)".into());
        }
        let s = &self.b[self.pos..self.pos + n];
        self.pos += n;
        Ok(s)
    }
    fn u8(&mut self) -> Result<u8, String> {
        Ok(self.take(1)?[0])
    }
    fn u32(&mut self) -> Result<u32, String> {
        Ok(u32::from_le_bytes(self.take(4)?.try_into().unwrap()))
    }
    fn u64(&mut self) -> Result<u64, String> {
        Ok(u64::from_le_bytes(self.take(8)?.try_into().unwrap()))
    }
    fn f64(&mut self) -> Result<f64, String> {
        Ok(f64::from_bits(self.u64()?))
    }
    fn flag(&mut self) -> Result<bool, String> {
        match self.u8()? {
            0 => Ok(false),
            1 => Ok(true),
            v => Err(format!("corrupt data (flag {v} at byte {})", self.pos - 1)),
        }
    }
    fn opt_f64(&mut self) -> Result<Option<f64>, String> {
        Ok(if self.flag()? {
            Some(self.f64()?)
        } else {
            None
        })
    }
    fn opt_u64(&mut self) -> Result<Option<u64>, String> {
        Ok(if self.flag()? {
            Some(self.u64()?)
        } else {
            None
        })
    }
    fn len(&mut self, elem: usize) -> Result<usize, String> {
        let n = self.u64()?;
        if n > ((self.b.len() - self.pos) / elem) as u64 {
            return Err(format!(
                "corrupt data (a length of {n} at byte {} runs past the end)",
                self.pos - 8
            ));
        }
        Ok(n as usize)
    }
    fn str(&mut self) -> Result<String, String> {
        let n = self.len(1)?;
        String::from_utf8(self.take(n)?.to_vec())
            .map_err(|_| format!("corrupt data (text that is not UTF-8 at byte {})", self.pos))
    }
    fn vec3(&mut self) -> Result<DVec3, String> {
        Ok(DVec3::new(self.f64()?, self.f64()?, self.f64()?))
    }
    fn f64s(&mut self) -> Result<Vec<f64>, String> {
        let n = self.len(8)?;
        Ok(self
            .take(8 * n)?
            .chunks_exact(8)
            .map(|c| f64::from_bits(u64::from_le_bytes(c.try_into().unwrap())))
            .collect())
    }
    fn fields(&mut self) -> Result<Vec<Vec<f64>>, String> {
        let nc = self.u32()?;
        if nc > 3 {
            return Err(format!("corrupt data ({nc} field components)"));
        }
        (0..nc).map(|_| self.f64s()).collect()
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
    let bodies = body_states(sim);
    let scene_ron = sim.scene().to_ron();
    let base_dir =
        std::path::absolute(&sim.scene().base_dir).unwrap_or_else(|_| sim.scene().base_dir.clone());
    let mut e = Enc {
        w,
        crc: crc32fast::Hasher::new(),
        len: 0,
        buf: Vec::with_capacity(8 * 8192),
    };
    e.bytes(&MAGIC)?;
    e.u32(FORMAT_VERSION)?;
    e.str(CRATE_VERSION)?;
    e.u32(crc32fast::hash(scene_ron.as_bytes()))?;
    e.str(&scene_ron)?;
    e.str(&base_dir.to_string_lossy())?;
    // Outputs.
    e.opt_f64(progress.next_out)?;
    e.u64(progress.snapshots)?;
    e.u64(progress.pvd.len() as u64)?;
    for (t, f) in &progress.pvd {
        e.f64(*t)?;
        e.str(f)?;
    }
    e.u64(progress.series_len)?;
    e.opt_u64(progress.bodies_len)?;
    e.opt_u64(progress.contacts_len)?;
    // Clock, diagnostics, transport.
    let time = sim.world.resource::<SimTime>().clone();
    e.f64(time.t)?;
    e.f64(time.dt)?;
    e.u64(time.step)?;
    e.opt_f64(time.stop_at)?;
    let diag = sim.world.resource::<Diagnostics>();
    let s = diag.sample;
    for v in [
        s.t,
        s.dt,
        s.energy,
        s.enstrophy,
        s.circulation,
        s.max_omega,
        s.max_u,
        diag.omega0,
        diag.dt_fallback,
    ] {
        e.f64(v)?;
    }
    e.u8(sim.world.resource::<TransportScratch>().reverse() as u8)?;
    // Fields.
    let n = sim.grid().n;
    for a in n {
        e.u64(a as u64)?;
    }
    let f = sim.world.resource::<Fields>();
    e.fields(f.omega())?;
    e.fields(&f.u)?;
    e.fields(&f.u_prev)?;
    e.f64(f.dt_prev)?;
    // Bodies.
    e.u64(bodies.len() as u64)?;
    for b in &bodies {
        e.u64(b.id as u64)?;
        e.str(&b.name)?;
        let r = &b.rigid;
        e.vec3(r.center)?;
        for v in r.orientation.to_array() {
            e.f64(v)?;
        }
        e.vec3(r.velocity)?;
        e.vec3(r.angular_velocity)?;
        e.f64(r.volume)?;
        e.vec3(r.centroid)?;
        for v in r.inertia.to_cols_array() {
            e.f64(v)?;
        }
        e.vec3(b.hydro.force)?;
        e.vec3(b.hydro.torque)?;
        e.f64(b.contact.kappa.unwrap_or(f64::NAN))?;
        e.vec3(b.contact.force)?;
        e.vec3(b.contact.torque)?;
        e.f64(b.contact.potential)?;
        match b.free.angular_momentum {
            Some(l) => {
                e.u8(1)?;
                e.vec3(l)?;
            }
            None => e.u8(0)?,
        }
        e.vec3(b.prev.velocity)?;
        e.vec3(b.prev.angular_velocity)?;
    }
    // Plugin state records.
    let records = sim.save_state().map_err(io::Error::other)?;
    e.u64(records.len() as u64)?;
    for r in &records {
        e.str(&r.name)?;
        e.u32(r.version)?;
        e.u64(r.bytes.len() as u64)?;
        e.bytes(&r.bytes)?;
    }
    // Trailer.
    let len = e.len;
    let crc = e.crc.clone().finalize();
    e.w.write_all(&len.to_le_bytes())?;
    e.w.write_all(&crc.to_le_bytes())?;
    e.w.write_all(&END_MAGIC)?;
    e.w.flush()
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
        let grid = sim.grid().clone();
        if grid.n != self.n {
            return Err(self.error(format!(
                "its grid has {:?} nodes, the scene's has {:?}",
                self.n, grid.n
            )));
        }
        let shape_ok =
            |f: &[Vec<f64>], nc: usize| f.len() == nc && f.iter().all(|c| c.len() == grid.len());
        if !shape_ok(&self.omega, grid.omega_components())
            || !shape_ok(&self.u, grid.dim)
            || !shape_ok(&self.u_prev, grid.dim)
        {
            return Err(self.error("its fields do not fit the scene's grid"));
        }
        let states = body_states(sim);
        let ids: Vec<(usize, &str)> = states.iter().map(|b| (b.id, b.name.as_str())).collect();
        let saved: Vec<(usize, &str)> = self
            .bodies
            .iter()
            .map(|b| (b.id, b.name.as_str()))
            .collect();
        if ids != saved {
            return Err(self.error(format!("its bodies {saved:?} are not the scene's {ids:?}")));
        }
        {
            let mut f = sim.world.resource_mut::<Fields>();
            for (dst, src) in f.omega_mut().iter_mut().zip(&self.omega) {
                dst.copy_from_slice(src);
            }
            for (dst, src) in f.u.iter_mut().zip(&self.u) {
                dst.copy_from_slice(src);
            }
            for (dst, src) in f.u_prev.iter_mut().zip(&self.u_prev) {
                // Saved from single precision, so exact.
                for (d, &s) in dst.iter_mut().zip(src) {
                    *d = s as f32;
                }
            }
            f.dt_prev = self.dt_prev;
        }
        sim.world.resource_mut::<Spectral>().invalidate();
        *sim.world.resource_mut::<SimTime>() = self.time.clone();
        {
            let mut d = sim.world.resource_mut::<Diagnostics>();
            d.sample = self.sample;
            d.omega0 = self.omega0;
            d.dt_fallback = self.dt_fallback;
        }
        sim.world.resource_mut::<Failure>().reason = None;
        sim.world
            .resource_mut::<TransportScratch>()
            .set_reverse(self.reverse);
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
                .expect("ids checked above")];
            *r = s.rigid;
            *h = s.hydro;
            *c = s.contact;
            *f = s.free;
            *p = s.prev;
        }
        sim.restore_state(&self.state).map_err(|m| self.error(m))?;
        Ok(())
    }
}

fn decode(b: &[u8], file: &Path) -> Result<Checkpoint, String> {
    if b.len() < MAGIC.len() || b[..MAGIC.len()] != MAGIC {
        return Err("not a tumble checkpoint (it does not start with the TUMBLECK header)".into());
    }
    let mut d = Dec {
        b,
        pos: MAGIC.len(),
    };
    let format = d.u32()?;
    if format != FORMAT_VERSION {
        return Err(format!(
            "it is in checkpoint format {format}, and this tumble {CRATE_VERSION} reads format \
             {FORMAT_VERSION} only; rerun the scene"
        ));
    }
    let vlen = d.u64()?;
    if vlen > 64 {
        return Err(format!("corrupt header (a version string of {vlen} bytes)"));
    }
    let version = String::from_utf8_lossy(d.take(vlen as usize)?).into_owned();
    if version != CRATE_VERSION {
        return Err(format!(
            "it was written by tumble {version}, and this is tumble {CRATE_VERSION}: a \
             checkpoint restarts only with the version that wrote it (use tumble {version}, \
             or rerun the scene)"
        ));
    }
    // Trailer: length and checksum of everything before it, then the end marker.
    let n = b.len();
    if n < d.pos + 16 || b[n - 4..] != END_MAGIC {
        return Err(format!(
            "the file is truncated or incomplete ({n} bytes, no end marker): it was cut short, \
             e.g. copied while being written; use an older checkpoint or rerun the scene"
        ));
    }
    let body_len = u64::from_le_bytes(b[n - 16..n - 8].try_into().unwrap());
    if body_len != (n - 16) as u64 {
        return Err(format!(
            "the file is truncated or corrupt (its trailer gives {body_len} bytes of data, it \
             holds {})",
            n - 16
        ));
    }
    let crc = u32::from_le_bytes(b[n - 8..n - 4].try_into().unwrap());
    if crc32fast::hash(&b[..n - 16]) != crc {
        return Err(
            "the file is corrupt (checksum mismatch): it changed after it was written; use an \
             older checkpoint or rerun the scene"
                .into(),
        );
    }
    let b = &b[..n - 16];
    d.b = b;
    let scene_hash = d.u32()?;
    let scene_ron = d.str()?;
    if crc32fast::hash(scene_ron.as_bytes()) != scene_hash {
        return Err("corrupt data (the scene text does not match its hash)".into());
    }
    let base_dir = PathBuf::from(d.str()?);
    let next_out = d.opt_f64()?;
    let snapshots = d.u64()?;
    let npvd = d.len(9)?;
    let mut pvd = Vec::with_capacity(npvd);
    for _ in 0..npvd {
        let t = d.f64()?;
        pvd.push((t, d.str()?));
    }
    let progress = RunProgress {
        next_out,
        snapshots,
        pvd,
        series_len: d.u64()?,
        bodies_len: d.opt_u64()?,
        contacts_len: d.opt_u64()?,
    };
    let time = SimTime {
        t: d.f64()?,
        dt: d.f64()?,
        step: d.u64()?,
        stop_at: d.opt_f64()?,
    };
    let mut v = [0.0; 9];
    for x in &mut v {
        *x = d.f64()?;
    }
    let sample = Sample {
        t: v[0],
        dt: v[1],
        energy: v[2],
        enstrophy: v[3],
        circulation: v[4],
        max_omega: v[5],
        max_u: v[6],
    };
    let reverse = d.flag()?;
    let mut grid_n = [0usize; 3];
    for a in &mut grid_n {
        *a = d.u64()? as usize;
    }
    let omega = d.fields()?;
    let u = d.fields()?;
    let u_prev = d.fields()?;
    let dt_prev = d.f64()?;
    let nb = d.len(1)?;
    let mut bodies = Vec::with_capacity(nb);
    for _ in 0..nb {
        let id = d.u64()? as usize;
        let name = d.str()?;
        let center = d.vec3()?;
        let mut q = [0.0; 4];
        for x in &mut q {
            *x = d.f64()?;
        }
        let velocity = d.vec3()?;
        let angular_velocity = d.vec3()?;
        let volume = d.f64()?;
        let centroid = d.vec3()?;
        let mut m = [0.0; 9];
        for x in &mut m {
            *x = d.f64()?;
        }
        let hydro = Hydro {
            force: d.vec3()?,
            torque: d.vec3()?,
        };
        let kappa = d.f64()?;
        let contact = ContactState {
            kappa: (!kappa.is_nan()).then_some(kappa),
            force: d.vec3()?,
            torque: d.vec3()?,
            potential: d.f64()?,
        };
        let free = FreeMotion {
            angular_momentum: if d.flag()? { Some(d.vec3()?) } else { None },
        };
        let prev = PreviousVelocity {
            velocity: d.vec3()?,
            angular_velocity: d.vec3()?,
        };
        bodies.push(BodyState {
            id,
            name,
            rigid: RigidState {
                center,
                orientation: DQuat::from_array(q),
                velocity,
                angular_velocity,
                volume,
                centroid,
                inertia: DMat3::from_cols_array(&m),
            },
            hydro,
            contact,
            free,
            prev,
        });
    }
    let nrec = d.len(16)?;
    let mut state = Vec::with_capacity(nrec);
    for _ in 0..nrec {
        let name = d.str()?;
        let version = d.u32()?;
        let n = d.len(1)?;
        state.push(StateRecord {
            name,
            version,
            bytes: d.take(n)?.to_vec(),
        });
    }
    if d.pos != b.len() {
        return Err(format!(
            "corrupt data ({} unexpected bytes at the end)",
            b.len() - d.pos
        ));
    }
    if !bodies.windows(2).all(|w| w[0].id < w[1].id) {
        return Err("corrupt data (bodies out of order)".into());
    }
    Ok(Checkpoint {
        file: file.to_path_buf(),
        scene_ron,
        base_dir,
        progress,
        time,
        sample,
        omega0: v[7],
        dt_fallback: v[8],
        reverse,
        n: grid_n,
        omega,
        u,
        u_prev,
        dt_prev,
        bodies,
        state,
    })
}

/// The scene text that decides whether two scenes are the same run: everything but the end
/// time and the checkpoint interval (a restart may change them) and the output directory (a
/// restart writes into the checkpoint's).
fn run_identity(scene: &Scene) -> String {
    let mut s = scene.clone();
    s.numerics.end_time = 0.0;
    s.output.checkpoint_every = None;
    s.output.dir = None;
    s.to_ron()
}

/// Whether `a` and `b` are the same run (see [`run_identity`]).
pub fn same_run(a: &Scene, b: &Scene) -> bool {
    run_identity(a) == run_identity(b)
}
