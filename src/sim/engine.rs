//! The simulation: a `bevy_ecs` world holding the resources, and the two schedules.

use crate::base::fields::{Failure, Fields, Params, Sample, SimTime, Timings};
use crate::base::grid::Grid;
use crate::parallel::{Comm, Decomposition};
use crate::scene::ValidScene;
use crate::schedule::{Mode, Plugin, PluginList, PluginSections, Scheduler, StateRecord};
use crate::sim::init::add_initial;
use crate::systems::diagnostics::{BodyItem, BodyMotion, Diagnostics};
use bevy_ecs::prelude::*;
use std::sync::Arc;

/// A running simulation.
pub struct Simulation {
    /// The ECS world: resources (grid, fields, solvers) and, later, body entities.
    pub world: World,
    /// The step schedule: add your own systems to it (see [`crate::schedule`]), or better,
    /// a plugin through [`Simulation::builder`].
    pub schedule: Schedule,
    scheduler: Scheduler,
    scene: ValidScene,
}

/// A simulation being set up: the scene and the plugins beyond the built-in ones.
pub struct SimulationBuilder {
    scene: ValidScene,
    plugins: PluginList,
    comm: Option<Arc<Comm>>,
}

impl SimulationBuilder {
    /// Add a plugin; it is built after the built-in ones (and the plugins added before it),
    /// so within a set its systems run after theirs.
    pub fn add_plugin(mut self, plugin: impl Plugin) -> Self {
        self.plugins = self.plugins.with(plugin);
        self
    }

    /// Add every plugin of `plugins`, in order.
    pub fn add_plugins(mut self, plugins: &PluginList) -> Self {
        self.plugins.0.extend(plugins.0.iter().cloned());
        self
    }

    /// Run on the processes of `comm`, each holding a slab of the grid ([`Decomposition`]);
    /// every process builds the simulation with the same scene and steps it in step with the
    /// others. One process runs as without it.
    pub fn on_processes(mut self, comm: Arc<Comm>) -> Self {
        self.comm = Some(comm);
        self
    }

    /// Check the scene's plugin sections against the plugins, then set up the world (see
    /// [`Simulation::new`]).
    pub fn build(self) -> anyhow::Result<Simulation> {
        let builtin = crate::systems::builtin();
        let plugins = with_builtin(&builtin, &self.plugins);
        let sections = self.scene.plugin_sections();
        sections.check(plugins.iter().copied())?;
        let split = match self.comm {
            Some(c) if c.size() > 1 => Some(split_scene(&self.scene, c)?),
            _ => None,
        };
        Simulation::with_plugins(self.scene, sections, &plugins, split)
    }
}

/// Why `scene` cannot run on several processes, if it cannot (so far: a free surface, or
/// bodies under another coupling than the default `Pressure`); the grid's split is checked
/// apart ([`Decomposition::new`]).
pub fn unsplittable(scene: &ValidScene) -> Option<String> {
    let coupling = scene.resolved().params.numerics.body_coupling;
    if !scene.bodies.is_empty() && coupling != crate::base::params::BodyCoupling::Pressure {
        return Some(format!(
            "this scene couples its bodies by `{coupling:?}`: on several processes tumble runs \
             bodies under the default `Pressure` coupling only (run it on one process, without \
             mpirun, or with -np 1)"
        ));
    }
    None
}

/// The decomposition of `scene`'s grid over the processes of `comm`, or why it cannot run
/// split ([`unsplittable`], or a grid that does not split that many ways).
pub fn split_scene(scene: &ValidScene, comm: Arc<Comm>) -> anyhow::Result<Decomposition> {
    let ranks = comm.size();
    if let Some(why) = unsplittable(scene) {
        anyhow::bail!("{why}");
    }
    Decomposition::new(&scene.grid(), comm)
        .map_err(|e| anyhow::anyhow!("cannot split the grid over {ranks} processes: {e}"))
}

/// The built-in plugins, then `extra`, in the order they are built.
fn with_builtin<'a>(builtin: &'a [Box<dyn Plugin>], extra: &'a PluginList) -> Vec<&'a dyn Plugin> {
    builtin
        .iter()
        .map(|p| p.as_ref())
        .chain(extra.0.iter().map(|p| p.as_ref()))
        .collect()
}

/// Check `scene`'s plugin sections against the built-in plugins and `plugins`, as
/// [`SimulationBuilder::build`] does, without setting anything up (for `tumble check`, and
/// so that a run refuses a bad section before it makes its directory).
pub fn check_plugin_sections(scene: &ValidScene, plugins: &PluginList) -> anyhow::Result<()> {
    let builtin = crate::systems::builtin();
    scene
        .plugin_sections()
        .check(with_builtin(&builtin, plugins))
}

impl Simulation {
    /// Set up the world for a validated scene (the only kind there is, see [`ValidScene`]):
    /// fields from the initial conditions, velocity from the Poisson solve, first time step. Fails if the schedule cannot be built or the
    /// initial state is not finite.
    pub fn new(scene: ValidScene) -> anyhow::Result<Self> {
        Simulation::builder(scene).build()
    }

    /// A simulation of `scene` with more plugins than the built-in ones.
    pub fn builder(scene: ValidScene) -> SimulationBuilder {
        SimulationBuilder {
            scene,
            plugins: PluginList::default(),
            comm: None,
        }
    }

    fn with_plugins(
        scene: ValidScene,
        sections: PluginSections,
        plugins: &[&dyn Plugin],
        split: Option<Decomposition>,
    ) -> anyhow::Result<Self> {
        let whole = scene.grid();
        let grid = match &split {
            Some(d) => d.local_grid(&whole),
            None => whole,
        };
        let mut world = World::new();
        let mut fields = Fields::new(&grid);
        for init in &scene.initial {
            add_initial(&grid, init, fields.omega_mut());
        }
        world.insert_resource(scene.resolved().params.clone());
        world.insert_resource(fields);
        world.insert_resource(SimTime {
            stop_at: Some(scene.numerics.end_time),
            ..Default::default()
        });
        world.insert_resource(Timings::default());
        world.insert_resource(Failure::default());
        let n_bodies = crate::sim::build::spawn_bodies(&mut world, &scene, &grid)?;
        if n_bodies > 0 {
            world.insert_resource(crate::bodies::BodyFields::new(
                &grid,
                scene.fluid.density,
                n_bodies,
            ));
            world.insert_resource(scene.resolved().contact.clone());
        }
        crate::sim::build::spawn_free_surface(&mut world, &scene, &grid)?;
        world.insert_resource(grid);
        if let Some(d) = split {
            world.insert_resource(d);
        }
        let mode = Mode {
            vacuum: scene.vacuum,
            bodies: n_bodies,
        };
        world.insert_resource(sections);
        let mut scheduler = Scheduler::default();
        scheduler.build(&mut world, mode, plugins.iter().copied())?;
        world.remove_resource::<PluginSections>();
        let mut startup = std::mem::take(&mut scheduler.startup);
        startup
            .initialize(&mut world)
            .map_err(|e| anyhow::anyhow!("the startup schedule cannot be built: {e:?}"))?;
        startup.run(&mut world);
        scheduler.collect_timings(&mut world.resource_mut::<Timings>());
        let mut schedule = std::mem::take(&mut scheduler.step);
        schedule
            .initialize(&mut world)
            .map_err(|e| anyhow::anyhow!("the step schedule cannot be built: {e:?}"))?;
        let sim = Simulation {
            world,
            schedule,
            scheduler,
            scene,
        };
        if let Some(f) = sim.failure() {
            anyhow::bail!("{f}");
        }
        Ok(sim)
    }

    /// The checkpoint records of the plugins' state (see
    /// [`crate::schedule::PluginContext::checkpoint_resource`]).
    pub fn save_state(&self) -> Result<Vec<StateRecord>, String> {
        self.scheduler.save_state(&self.world)
    }

    /// Restore the plugins' state from checkpoint records.
    pub fn restore_state(&mut self, records: &[StateRecord]) -> Result<(), String> {
        self.scheduler.restore_state(&mut self.world, records)
    }

    /// Advance one step. On blow-up the error says what, where and when.
    pub fn step(&mut self) -> anyhow::Result<()> {
        self.schedule.run(&mut self.world);
        let mut timings = self.world.resource_mut::<Timings>();
        self.scheduler.collect_timings(&mut timings);
        match self.failure() {
            Some(f) => Err(anyhow::anyhow!(f)),
            None => Ok(()),
        }
    }

    /// Step until `t_end` (landing on it exactly), calling `each` after every step.
    ///
    /// Landing on `t_end` evens out the steps before it (the time left split evenly over the
    /// fewest steps the policy allows) with an `Adaptive` step: calling this at intermediate
    /// times changes the steps that follow. To sample a `Fixed` run at times without changing it, set the end time with
    /// [`Simulation::set_stop_at`] once and step while [`Simulation::time`] is before each
    /// sample time, as `tumble run` does for its snapshots.
    pub fn run_until(
        &mut self,
        t_end: f64,
        mut each: impl FnMut(&Simulation),
    ) -> anyhow::Result<()> {
        self.set_stop_at(Some(t_end));
        while self.time() < t_end * (1.0 - 1e-12) {
            self.step()?;
            each(self);
        }
        Ok(())
    }

    /// Make the clock land exactly on `t` (the end time, or with an Adaptive step an output
    /// time; see [`crate::base::params::TimeStep`]): the time left is split evenly over the
    /// fewest steps the policy allows. `None` lands nowhere. The next step is recomputed now.
    pub fn set_stop_at(&mut self, t: Option<f64>) {
        let (h, dim) = (self.grid().h, self.grid().dim);
        let params = self.world.resource::<Params>().clone();
        let mut q = self.world.query::<BodyItem>();
        let motion = BodyMotion::of(dim, &params, q.iter(&self.world));
        let diag = self.world.resource::<Diagnostics>();
        let (sample, fallback) = (diag.sample, diag.dt_fallback);
        let now = self.time();
        let dt =
            crate::systems::diagnostics::next_dt(&params, &sample, h, fallback, motion, now, t);
        let mut time = self.world.resource_mut::<SimTime>();
        time.stop_at = t;
        time.dt = dt;
    }

    /// The names of the systems run at every step, in the order they were added.
    pub fn step_systems(&self) -> &[&'static str] {
        self.scheduler.step_systems()
    }

    /// Why the run must stop, if it must.
    pub fn failure(&self) -> Option<String> {
        self.world.resource::<Failure>().reason.clone()
    }

    /// The scene being run.
    pub fn scene(&self) -> &ValidScene {
        &self.scene
    }

    /// Current time.
    pub fn time(&self) -> f64 {
        self.world.resource::<SimTime>().t
    }

    /// Steps taken.
    pub fn steps(&self) -> u64 {
        self.world.resource::<SimTime>().step
    }

    /// The grid.
    pub fn grid(&self) -> &Grid {
        self.world.resource::<Grid>()
    }

    /// The fields.
    pub fn fields(&self) -> &Fields {
        self.world.resource::<Fields>()
    }

    /// Global quantities after the last step.
    pub fn sample(&self) -> Sample {
        self.world.resource::<Diagnostics>().sample
    }

    /// Per-system wall-clock time of the last step (after [`Simulation::new`], of the startup
    /// systems): only the systems that ran in it are listed.
    pub fn timings(&self) -> &Timings {
        self.world.resource::<Timings>()
    }
}
