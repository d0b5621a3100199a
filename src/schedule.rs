//! All scheduling in one place, and the plugin interface through which every physics system
//! enters it.
//!
//! One step of the method is one run of the [`Step`] schedule: the named [`PhysicsSet`]s,
//! chained once in the order of the paper's splitting (DESIGN.md, "One time step"). `First`
//! and `Last` are empty: they are where users hook their own systems. The executor is
//! single-threaded (the systems parallelise inside with rayon) and ambiguous ordering is an
//! error: two systems that touch the same data must be ordered.
//!
//! A physics system is a [`Plugin`]: one file in `systems/` (or anywhere, see
//! `examples/passive_scalar.rs`) whose [`Plugin::build`] inserts its resources, reading typed
//! settings from [`Params`] and the world, adds its systems to a named set with
//! [`PluginContext::add_system`], and registers the resources it keeps across a restart with
//! [`PluginContext::checkpoint_resource`] (or [`PluginContext::checkpoint_part`]). The built-in plugins are listed once, in
//! `systems::builtin`; adding a system is that file plus one line there (or one
//! `add_plugin` call on the simulation builder). Every system added through a plugin is timed
//! under its name into [`Timings`]: no system carries timing code.
//!
//! The order of a step is stated once, in [`PhysicsSet::ALL`]: each built-in set holds the
//! systems of one plugin (collision's two run in the order it adds them), so the order of the
//! plugin list does not matter. Within a set that several plugins use (`First` and `Last`),
//! systems are chained in the order they were added: the built-in plugins first, then the
//! plugins of the builder in the order they were added. The startup schedule runs through the
//! same sets in the same order ([`PluginContext::add_startup_system_in`]). What a run does is
//! decided by [`Mode`] (vacuum or fluid, with or without bodies), which each plugin reads in
//! `build`.

use crate::base::fields::{Params, Timings};
use bevy_ecs::prelude::*;
use bevy_ecs::schedule::{LogLevel, ScheduleBuildSettings, ScheduleLabel, SingleThreadedExecutor};
use bevy_ecs::system::{Adapt, IntoAdapterSystem, RunSystemError, SystemIn};
use serde::Serialize;
use serde::de::DeserializeOwned;
use std::collections::HashMap;
use std::sync::{Arc, Mutex};
use std::time::Instant;

/// The named stages of a step, in order (see [`PhysicsSet::ALL`]); each built-in system has
/// its own set, or shares one with the systems of its own plugin only.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PhysicsSet {
    /// Empty: user systems that run before everything else.
    First,
    /// Sample body level sets on the grid (section 3.1).
    LevelSets,
    /// The density of the fluid phases, ρ_P (the free surface's, section 5), which the
    /// density of the bodies is added to.
    PhaseDensity,
    /// Characteristic functions and density (eq. 19).
    Density,
    /// Rigid velocity of each body from the flow (eq. 7).
    RigidVelocity,
    /// Contact forces between bodies (eqs. 20-22), added to the rigid velocities as impulses
    /// (section 3.2).
    Collision,
    /// Implicit penalization (eqs. 13, 27).
    Penalization,
    /// The variable-density pressure projection (eqs. 14, 16), which adds the penalization's
    /// curl (`body_coupling: Pressure`, the default).
    Pressure,
    /// Baroclinic vorticity generation (eq. 28; `body_coupling: Baroclinic` or `Momentum`).
    Baroclinic,
    /// Particle push, stretching and remeshing (eqs. 29-30).
    Transport,
    /// The no-slip's forcing of the last step carried into this one, before the diffusion
    /// (`systems/noslip.rs`).
    CarriedForcing,
    /// Implicit diffusion.
    Diffusion,
    /// Velocity from vorticity (eq. 15).
    Poisson,
    /// The no-slip of the Newton-Euler bodies restored after the diffusion, with their recoil
    /// (`systems/noslip.rs`).
    NoSlip,
    /// The free surface carried by the new velocity, redistanced, its volume restored
    /// (section 5).
    FreeSurface,
    /// In vacuum, the bodies' velocities from gravity and contact (before they move with
    /// them: symplectic Euler).
    FreeMotion,
    /// Move the bodies.
    RigidUpdate,
    /// Clock, time step, global quantities, blow-up guard.
    Diagnostics,
    /// Empty: user systems that run after everything else.
    Last,
}

impl PhysicsSet {
    /// Every set, in schedule order.
    pub const ALL: [PhysicsSet; 19] = [
        PhysicsSet::First,
        PhysicsSet::LevelSets,
        PhysicsSet::PhaseDensity,
        PhysicsSet::Density,
        PhysicsSet::RigidVelocity,
        PhysicsSet::Collision,
        PhysicsSet::Penalization,
        PhysicsSet::Pressure,
        PhysicsSet::Baroclinic,
        PhysicsSet::Transport,
        PhysicsSet::CarriedForcing,
        PhysicsSet::Diffusion,
        PhysicsSet::Poisson,
        PhysicsSet::NoSlip,
        PhysicsSet::FreeSurface,
        PhysicsSet::FreeMotion,
        PhysicsSet::RigidUpdate,
        PhysicsSet::Diagnostics,
        PhysicsSet::Last,
    ];
}

/// Label of the schedule that advances the simulation by one step.
#[derive(ScheduleLabel, Debug, Clone, PartialEq, Eq, Hash)]
pub struct Step;

/// Label of the schedule run once before the first step (velocity and first dt).
#[derive(ScheduleLabel, Debug, Clone, PartialEq, Eq, Hash)]
pub struct Startup;

/// The set of one named system (so later systems of the same set can be ordered after it).
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
struct Named(&'static str);

fn configured(label: impl ScheduleLabel) -> Schedule {
    let mut s = Schedule::new(label);
    s.set_executor(SingleThreadedExecutor::new());
    s.set_build_settings(ScheduleBuildSettings {
        ambiguity_detection: LogLevel::Error,
        ..Default::default()
    });
    s
}

/// An empty schedule labelled `label` whose sets are chained once, in the order of
/// [`PhysicsSet::ALL`], single-threaded, ambiguity an error.
fn chained(label: impl ScheduleLabel) -> Schedule {
    let mut s = configured(label);
    for pair in PhysicsSet::ALL.windows(2) {
        s.configure_sets(pair[0].before(pair[1]));
    }
    s
}

/// An empty step schedule: the sets chained once, in the order of [`PhysicsSet::ALL`],
/// single-threaded, ambiguity an error.
pub fn step_schedule() -> Schedule {
    chained(Step)
}

/// An empty startup schedule: the same sets in the same order as a step's.
pub fn startup_schedule() -> Schedule {
    chained(Startup)
}

/// What kind of run the world holds; plugins decide from it which systems to add.
#[derive(Resource, Debug, Clone, Copy, PartialEq, Eq)]
pub struct Mode {
    /// No fluid: the bodies move under gravity and contact alone.
    pub vacuum: bool,
    /// Number of bodies.
    pub bodies: usize,
}

impl Mode {
    /// Whether the flow solver runs.
    pub fn fluid(&self) -> bool {
        !self.vacuum
    }
    /// Whether there are bodies.
    pub fn has_bodies(&self) -> bool {
        self.bodies > 0
    }
}

/// A physics system: its resources, its systems and their place in the schedule, its scene
/// settings, its output fields and the state it keeps across a checkpoint.
pub trait Plugin: Send + Sync + 'static {
    /// A short name (used in errors, and the key of its scene section).
    fn name(&self) -> &'static str;
    /// The scene section this plugin reads, `plugins: {"<name>": (..)}`, if it has settings:
    /// [`Section::of`] its settings struct. The section is checked against it when a
    /// simulation is set up and by `tumble check`, before anything is built; a scene whose
    /// section no plugin reads is refused. Default: none.
    fn section(&self) -> Option<Section> {
        None
    }
    /// Insert the resources and add the systems (see [`PluginContext`]). Only what the
    /// [`Mode`] needs should be added: a pure-fluid run does no body work at all.
    fn build(&self, ctx: &mut PluginContext) -> anyhow::Result<()>;
}

/// The plugins of a simulation beyond the built-in ones, shared by every simulation a run
/// sets up (a restart sets up its own): what a user's binary hands to
/// `tumble::cli::main_with` or puts in `RunOptions::plugins`.
#[derive(Clone, Default)]
pub struct PluginList(pub Vec<Arc<dyn Plugin>>);

impl PluginList {
    /// A list of one plugin more.
    pub fn with(mut self, plugin: impl Plugin) -> Self {
        self.0.push(Arc::new(plugin));
        self
    }
}

impl std::fmt::Debug for PluginList {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_list()
            .entries(self.0.iter().map(|p| p.name()))
            .finish()
    }
}

/// How a plugin's scene section is read: its settings type, as a parser that checks a section's
/// RON text (see [`Plugin::section`]).
#[derive(Clone, Copy)]
pub struct Section {
    check: fn(&str) -> Result<(), ron::error::SpannedError>,
}

impl Section {
    /// The section of settings `T` (a `Deserialize` struct; give it
    /// `#[serde(deny_unknown_fields)]` so a misspelt setting is an error).
    pub fn of<T: DeserializeOwned>() -> Section {
        Section {
            check: |text| parse_section::<T>(text).map(|_| ()),
        }
    }
}

fn parse_section<T: DeserializeOwned>(text: &str) -> Result<T, ron::error::SpannedError> {
    ron::Options::default()
        .with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME)
        .from_str(text)
}

/// The plugins' sections of the scene a simulation is set up from (a resource while the
/// plugins are built): the scene file, and each section's key, RON text and 1-based line and
/// column of its first character in the file (`None` for a scene built or edited in code).
#[derive(Resource, Debug, Clone, Default)]
pub struct PluginSections {
    /// The scene file, as named in errors.
    pub file: String,
    /// The sections, in the scene's order of keys.
    pub sections: Vec<SceneSection>,
}

/// One plugin section of a scene.
#[derive(Debug, Clone)]
pub struct SceneSection {
    /// Its key: the name of the plugin that reads it.
    pub key: String,
    /// Its RON text.
    pub text: String,
    /// The 1-based line and column of its first character in the scene file, when known.
    pub at: Option<(usize, usize)>,
}

impl PluginSections {
    /// Check every section against the plugin of its key: a key no plugin of `plugins` has,
    /// or a plugin without settings, or a section that does not parse as the plugin's
    /// settings is an error naming the file, the line and the column.
    pub fn check<'a>(
        &self,
        plugins: impl IntoIterator<Item = &'a dyn Plugin>,
    ) -> anyhow::Result<()> {
        let plugins: Vec<&dyn Plugin> = plugins.into_iter().collect();
        for SceneSection { key, text, at } in &self.sections {
            let Some(p) = plugins.iter().find(|p| p.name() == key) else {
                let names: Vec<_> = plugins.iter().map(|p| p.name()).collect();
                anyhow::bail!(
                    "{}: `plugins` has a section \"{key}\" but no plugin of this simulation is \
                     named so (its plugins: {})",
                    self.locate(*at),
                    names.join(", ")
                );
            };
            let Some(section) = p.section() else {
                anyhow::bail!(
                    "{}: plugin `{key}` has no settings, but the scene gives it a section",
                    self.locate(*at)
                );
            };
            (section.check)(text).map_err(|e| self.parse_error(key, *at, &e))?;
        }
        Ok(())
    }

    /// The settings of plugin `key`: its section parsed as `T`, or `T::default()` without one.
    pub fn settings<T: DeserializeOwned + Default>(&self, key: &str) -> anyhow::Result<T> {
        match self.sections.iter().find(|s| s.key == key) {
            Some(s) => parse_section::<T>(&s.text).map_err(|e| self.parse_error(key, s.at, &e)),
            None => Ok(T::default()),
        }
    }

    fn parse_error(
        &self,
        key: &str,
        at: Option<(usize, usize)>,
        e: &ron::error::SpannedError,
    ) -> anyhow::Error {
        let (line, col) = (e.span.start.line, e.span.start.col);
        let pos = at.map(|(l0, c0)| {
            if line <= 1 {
                (l0, c0 + col.saturating_sub(1))
            } else {
                (l0 + line - 1, col)
            }
        });
        let column = pos.map_or(col, |p| p.1);
        anyhow::anyhow!(
            "{}, field `plugins.{key}`: {} (column {column})",
            self.locate(pos),
            e.code
        )
    }

    fn locate(&self, at: Option<(usize, usize)>) -> String {
        match at {
            Some((l, _)) => format!("scene error in {}, line {l}", self.file),
            None => format!("scene error in {}", self.file),
        }
    }
}

/// A field a plugin writes into the snapshots (VTK `fields_NNNNNN.vti` and HDF5), after the
/// built-in ones, whenever the scene's `output.fields` asks for any field: its name in the
/// files and how to read its components (1 for a scalar, `dim` or 3 for a vector; each one
/// value per grid node, in the grid's flat order) from the world.
#[derive(Clone, Copy)]
pub struct OutputField {
    /// The field's name in the files (unique among the snapshot's fields).
    pub name: &'static str,
    /// Its components, read from the world.
    pub read: for<'w> fn(&'w World) -> Vec<&'w [f64]>,
}

/// The fields the plugins write (a resource, see [`PluginContext::output_field`]).
#[derive(Resource, Clone, Default)]
pub struct OutputFields(pub Vec<OutputField>);

/// Wall-clock times of the systems run since the last [`Scheduler::collect_timings`].
type TimingSink = Arc<Mutex<Vec<(&'static str, f64)>>>;

/// Runs the wrapped system and records its wall-clock time under `name`.
#[derive(Clone)]
struct Timed {
    name: &'static str,
    sink: TimingSink,
}

impl<S: System<In = (), Out = ()>> Adapt<S> for Timed {
    type In = ();
    type Out = ();

    fn adapt(
        &mut self,
        input: (),
        run_system: impl FnOnce(SystemIn<'_, S>) -> Result<(), RunSystemError>,
    ) -> Result<(), RunSystemError> {
        let start = Instant::now();
        let r = run_system(input);
        let secs = start.elapsed().as_secs_f64();
        self.sink
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .push((self.name, secs));
        r
    }
}

/// The state a plugin keeps across a checkpoint: one serde-encoded record per resource.
struct StateEntry {
    name: &'static str,
    version: u32,
    save: fn(&World) -> Result<Vec<u8>, String>,
    restore: fn(&mut World, &[u8]) -> Result<(), String>,
}

/// One saved record: name, version and the encoded bytes.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct StateRecord {
    /// The record's name (unique in a simulation).
    pub name: String,
    /// Its layout version.
    pub version: u32,
    /// Its serde (postcard) encoding.
    pub bytes: Vec<u8>,
}

/// The schedules being built and everything registered with them.
pub struct Scheduler {
    /// The step schedule.
    pub step: Schedule,
    /// The startup schedule.
    pub startup: Schedule,
    sink: TimingSink,
    last_in_set: HashMap<PhysicsSet, &'static str>,
    last_in_startup_set: HashMap<PhysicsSet, &'static str>,
    names: Vec<&'static str>,
    /// The set of each of `names` (its place in [`PhysicsSet::ALL`]).
    name_sets: Vec<usize>,
    state: Vec<StateEntry>,
}

impl Default for Scheduler {
    fn default() -> Self {
        Scheduler {
            step: step_schedule(),
            startup: startup_schedule(),
            sink: TimingSink::default(),
            last_in_set: HashMap::new(),
            last_in_startup_set: HashMap::new(),
            names: Vec::new(),
            name_sets: Vec::new(),
            state: Vec::new(),
        }
    }
}

impl Scheduler {
    /// Build `plugins` in order into `world` for `mode`.
    pub fn build<'a>(
        &mut self,
        world: &mut World,
        mode: Mode,
        plugins: impl IntoIterator<Item = &'a dyn Plugin>,
    ) -> anyhow::Result<()> {
        world.insert_resource(mode);
        for p in plugins {
            let mut ctx = PluginContext {
                world: &mut *world,
                scheduler: &mut *self,
                plugin: p.name(),
            };
            p.build(&mut ctx)
                .map_err(|e| anyhow::anyhow!("plugin `{}`: {e:#}", p.name()))?;
        }
        Ok(())
    }

    /// Replace `timings` with the times recorded since the last call (one schedule run: a
    /// system not run in it is not listed, so a startup system is not counted at every step).
    pub fn collect_timings(&self, timings: &mut Timings) {
        let mut sink = self.sink.lock().unwrap_or_else(|e| e.into_inner());
        timings.last.clear();
        for &(name, secs) in sink.iter() {
            match timings.last.iter_mut().find(|e| e.0 == name) {
                Some(e) => e.1 += secs,
                None => timings.last.push((name, secs)),
            }
        }
        sink.clear();
    }

    /// The names of the systems of the step schedule, in the order they run (the
    /// startup systems are not among them unless they also run at every step).
    pub fn step_systems(&self) -> &[&'static str] {
        &self.names
    }

    /// The checkpoint records of every registered resource, in registration order.
    pub fn save_state(&self, world: &World) -> Result<Vec<StateRecord>, String> {
        self.state
            .iter()
            .map(|e| {
                Ok(StateRecord {
                    name: e.name.to_string(),
                    version: e.version,
                    bytes: (e.save)(world).map_err(|m| format!("state `{}`: {m}", e.name))?,
                })
            })
            .collect()
    }

    /// Restore every registered resource from `records`; each must be there, once, with the
    /// version it was registered with, and no record may be left over.
    pub fn restore_state(&self, world: &mut World, records: &[StateRecord]) -> Result<(), String> {
        for r in records {
            if !self.state.iter().any(|e| e.name == r.name) {
                return Err(format!(
                    "it holds the state `{}`, which no system of this simulation keeps",
                    r.name
                ));
            }
        }
        for e in &self.state {
            let mut found = records.iter().filter(|r| r.name == e.name);
            let Some(r) = found.next() else {
                return Err(format!("it holds no state `{}`", e.name));
            };
            if found.next().is_some() {
                return Err(format!("it holds the state `{}` twice", e.name));
            }
            if r.version != e.version {
                return Err(format!(
                    "its state `{}` is version {}, this tumble reads version {}",
                    e.name, r.version, e.version
                ));
            }
            (e.restore)(world, &r.bytes).map_err(|m| format!("state `{}`: {m}", e.name))?;
        }
        Ok(())
    }
}

/// What a plugin's [`Plugin::build`] works with.
pub struct PluginContext<'a> {
    /// The world: read [`Params`], the grid and other typed resources, insert your own.
    pub world: &'a mut World,
    scheduler: &'a mut Scheduler,
    plugin: &'static str,
}

impl PluginContext<'_> {
    /// The kind of run.
    pub fn mode(&self) -> Mode {
        *self.world.resource::<Mode>()
    }

    /// The typed parameters.
    pub fn params(&self) -> &Params {
        self.world.resource::<Params>()
    }

    /// This plugin's settings from the scene's `plugins` section under its name (already
    /// checked against its [`Plugin::section`]), or `T::default()` when the scene has none.
    pub fn settings<T: DeserializeOwned + Default>(&self) -> anyhow::Result<T> {
        match self.world.get_resource::<PluginSections>() {
            Some(s) => s.settings(self.plugin),
            None => Ok(T::default()),
        }
    }

    /// Write a field into the snapshots (see [`OutputField`]); its name must not be taken.
    pub fn output_field(&mut self, field: OutputField) -> anyhow::Result<()> {
        const BUILT_IN: [&str; 7] = [
            "omega",
            "velocity",
            "density",
            "chi",
            "phi",
            "free_surface",
            "TIME",
        ];
        let mut fields = self.world.get_resource_or_init::<OutputFields>();
        if BUILT_IN.contains(&field.name) || fields.0.iter().any(|f| f.name == field.name) {
            anyhow::bail!(
                "plugin `{}`: the output field `{}` is already written",
                self.plugin,
                field.name
            );
        }
        fields.0.push(field);
        Ok(())
    }

    /// Insert a resource (replacing one of the same type).
    pub fn insert_resource<R: Resource>(&mut self, r: R) {
        self.world.insert_resource(r);
    }

    /// Insert a resource unless one of its type is there (for resources shared by plugins).
    pub fn share_resource<R: Resource>(&mut self, make: impl FnOnce(&World) -> R) {
        if !self.world.contains_resource::<R>() {
            let r = make(self.world);
            self.world.insert_resource(r);
        }
    }

    /// Records `name` among the step's systems in the order they run: after every system of
    /// its set and of the sets before it.
    fn check_name(&mut self, set: PhysicsSet, name: &'static str) -> anyhow::Result<()> {
        if self.scheduler.names.contains(&name) {
            anyhow::bail!("a system named `{name}` is already registered");
        }
        let k = PhysicsSet::ALL
            .iter()
            .position(|s| *s == set)
            .unwrap_or(PhysicsSet::ALL.len());
        let at = self.scheduler.name_sets.partition_point(|&s| s <= k);
        self.scheduler.names.insert(at, name);
        self.scheduler.name_sets.insert(at, k);
        Ok(())
    }

    /// Add `system` to `set` of the step schedule, timed under `name`, after the systems
    /// added to `set` before it.
    pub fn add_system<M>(
        &mut self,
        set: PhysicsSet,
        name: &'static str,
        system: impl IntoSystem<(), (), M> + Send + Sync + 'static,
    ) -> anyhow::Result<()> {
        self.check_name(set, name)?;
        let timed = IntoAdapterSystem::new(
            Timed {
                name,
                sink: self.scheduler.sink.clone(),
            },
            system,
        );
        let prev = self.scheduler.last_in_set.insert(set, name);
        let s = &mut self.scheduler.step;
        match prev {
            Some(p) => s.add_systems(timed.in_set(set).in_set(Named(name)).after(Named(p))),
            None => s.add_systems(timed.in_set(set).in_set(Named(name))),
        };
        Ok(())
    }

    /// Add `system` to `set` of the startup schedule (run once before the first step), timed
    /// under `name`, after the startup systems added to `set` before it.
    pub fn add_startup_system_in<M>(
        &mut self,
        set: PhysicsSet,
        name: &'static str,
        system: impl IntoSystem<(), (), M> + Send + Sync + 'static,
    ) -> anyhow::Result<()> {
        let timed = IntoAdapterSystem::new(
            Timed {
                name,
                sink: self.scheduler.sink.clone(),
            },
            system,
        );
        let prev = self.scheduler.last_in_startup_set.insert(set, name);
        let s = &mut self.scheduler.startup;
        match prev {
            Some(p) => s.add_systems(timed.in_set(set).in_set(Named(name)).after(Named(p))),
            None => s.add_systems(timed.in_set(set).in_set(Named(name))),
        };
        Ok(())
    }

    /// Add `system` to the `Last` set of the startup schedule: after every built-in startup
    /// system and the ones added there before it (see [`Self::add_startup_system_in`]).
    pub fn add_startup_system<M>(
        &mut self,
        name: &'static str,
        system: impl IntoSystem<(), (), M> + Send + Sync + 'static,
    ) -> anyhow::Result<()> {
        self.add_startup_system_in(PhysicsSet::Last, name, system)
    }

    /// Keep resource `R` across a checkpoint: it is saved as a record named `name` with
    /// layout `version` (serde, postcard encoding) and restored from it. Change `version`
    /// whenever `R`'s serialized layout changes: an old record is then refused by name.
    pub fn checkpoint_resource<R>(&mut self, name: &'static str, version: u32) -> anyhow::Result<()>
    where
        R: Resource + Serialize + DeserializeOwned,
    {
        self.keep_state(StateEntry {
            name,
            version,
            save: |world| encode(resource::<R>(world)?),
            restore: |world, bytes| {
                world.insert_resource(decode::<R>(bytes)?);
                Ok(())
            },
        })
    }

    /// Keep [`CheckpointPart::Part`] of resource `R` across a checkpoint, as
    /// [`PluginContext::checkpoint_resource`] keeps a whole resource: for a resource that also
    /// holds scratch or settings the plugin makes again. The part is put back into the
    /// resource the plugin inserted.
    pub fn checkpoint_part<R: CheckpointPart>(
        &mut self,
        name: &'static str,
        version: u32,
    ) -> anyhow::Result<()> {
        self.keep_state(StateEntry {
            name,
            version,
            save: |world| encode(&resource::<R>(world)?.save_part()),
            restore: |world, bytes| {
                let part = decode::<R::Part>(bytes)?;
                world
                    .get_resource_mut::<R>()
                    .ok_or_else(|| MISSING.to_string())?
                    .restore_part(part);
                Ok(())
            },
        })
    }

    fn keep_state(&mut self, entry: StateEntry) -> anyhow::Result<()> {
        if self.scheduler.state.iter().any(|e| e.name == entry.name) {
            anyhow::bail!(
                "plugin `{}`: the checkpoint state `{}` is already registered",
                self.plugin,
                entry.name
            );
        }
        self.scheduler.state.push(entry);
        Ok(())
    }
}

/// A resource of which a checkpoint keeps a part, the rest being scratch or settings its
/// plugin makes again (see [`PluginContext::checkpoint_part`]).
pub trait CheckpointPart: Resource<Mutability = bevy_ecs::component::Mutable> {
    /// What a checkpoint keeps.
    type Part: Serialize + DeserializeOwned;
    /// The part to save.
    fn save_part(&self) -> Self::Part;
    /// Put a saved part back.
    fn restore_part(&mut self, part: Self::Part);
}

const MISSING: &str = "the resource is missing";

/// The resource a checkpoint record is saved from.
fn resource<R: Resource>(world: &World) -> Result<&R, String> {
    world.get_resource::<R>().ok_or_else(|| MISSING.to_string())
}

/// A checkpoint record's bytes (postcard).
fn encode<T: Serialize + ?Sized>(value: &T) -> Result<Vec<u8>, String> {
    postcard::to_stdvec(value).map_err(|e| e.to_string())
}

/// A checkpoint record read back.
fn decode<T: DeserializeOwned>(bytes: &[u8]) -> Result<T, String> {
    postcard::from_bytes(bytes).map_err(|e| format!("corrupt data ({e})"))
}
