//! The schedule: the default one builds with ambiguity detection as an error, user systems
//! hook into the empty First/Last sets, an ambiguous pair is rejected (added by hand or
//! through a plugin), every plugin system is timed under its name, and the built-in systems
//! run in the one order stated below.

use bevy_ecs::prelude::*;
use tumble::scene::Scene;
use tumble::schedule::{PhysicsSet, Plugin, PluginContext, step_schedule};
use tumble::sim::engine::Simulation;

const SCENE: &str = r#"Scene(
    domain: (extent: [1.0, 1.0], cells: [16, 16]),
    numerics: (end_time: 0.1, dt: Fixed(0.01)),
    initial: [LambOseen(center: [0.5, 0.5], circulation: 1.0, core_radius: 0.1)],
)"#;

fn sim() -> Simulation {
    Simulation::new(Scene::parse(SCENE, "test", "test").unwrap()).unwrap()
}

#[derive(Resource, Default)]
struct Trace(Vec<&'static str>);

#[test]
fn default_schedule_builds_without_ambiguity() {
    let mut s = sim();
    s.schedule
        .initialize(&mut s.world)
        .expect("default schedule builds");
    s.step().unwrap();
    assert!(s.time() > 0.0);
}

#[test]
fn plugin_systems_are_timed_by_name() {
    let mut s = sim();
    s.step().unwrap();
    let names: Vec<&str> = s.timings().last.iter().map(|e| e.0).collect();
    // A fluid run without bodies: the fluid systems, in schedule order, each once.
    assert_eq!(names, ["transport", "diffusion", "poisson", "diagnostics"]);
    assert!(s.timings().last.iter().all(|e| e.1 >= 0.0));
}

/// A plugin writing `Trace` from the First set.
struct Tracer;

impl Plugin for Tracer {
    fn name(&self) -> &'static str {
        "tracer"
    }
    fn build(&self, ctx: &mut PluginContext) -> anyhow::Result<()> {
        ctx.insert_resource(Trace::default());
        ctx.add_system(PhysicsSet::First, "trace_a", |mut t: ResMut<Trace>| {
            t.0.push("a")
        })?;
        // Same set, same resource: chained after trace_a by the plugin registration.
        ctx.add_system(PhysicsSet::First, "trace_b", |mut t: ResMut<Trace>| {
            t.0.push("b")
        })
    }
}

#[test]
fn plugin_systems_in_one_set_are_ordered() {
    let scene = Scene::parse(SCENE, "test", "test").unwrap();
    let mut s = Simulation::builder(scene)
        .add_plugin(Tracer)
        .build()
        .unwrap();
    s.step().unwrap();
    assert_eq!(s.world.resource::<Trace>().0, vec!["a", "b"]);
}

#[test]
fn ambiguous_plugin_system_is_rejected() {
    let mut s = {
        let scene = Scene::parse(SCENE, "test", "test").unwrap();
        Simulation::builder(scene)
            .add_plugin(Tracer)
            .build()
            .unwrap()
    };
    // A hand-added system writing the same resource in the same set, unordered: an error.
    s.schedule
        .add_systems((|mut t: ResMut<Trace>| t.0.push("c")).in_set(PhysicsSet::First));
    assert!(s.schedule.initialize(&mut s.world).is_err());
}

#[test]
fn a_system_name_is_registered_once() {
    struct Twice;
    impl Plugin for Twice {
        fn name(&self) -> &'static str {
            "twice"
        }
        fn build(&self, ctx: &mut PluginContext) -> anyhow::Result<()> {
            ctx.add_system(PhysicsSet::Last, "poisson", || {})
        }
    }
    let scene = Scene::parse(SCENE, "test", "test").unwrap();
    let err = Simulation::builder(scene)
        .add_plugin(Twice)
        .build()
        .err()
        .expect("a second `poisson` is refused");
    assert!(format!("{err:#}").contains("twice"), "{err:#}");
}

#[test]
fn user_systems_run_first_and_last() {
    let mut s = sim();
    s.world.insert_resource(Trace::default());
    s.schedule.add_systems(
        (|mut t: ResMut<Trace>, time: Res<tumble::base::fields::SimTime>| {
            t.0.push(if time.step == 0 { "first@0" } else { "first" })
        })
        .in_set(PhysicsSet::First),
    );
    s.schedule.add_systems(
        (|mut t: ResMut<Trace>, time: Res<tumble::base::fields::SimTime>| {
            // Diagnostics has advanced the clock before Last runs.
            assert!(time.step >= 1);
            t.0.push("last")
        })
        .in_set(PhysicsSet::Last),
    );
    s.step().unwrap();
    s.step().unwrap();
    assert_eq!(
        s.world.resource::<Trace>().0,
        vec!["first@0", "last", "first", "last"]
    );
}

#[test]
fn ambiguous_user_systems_are_rejected() {
    let mut s = sim();
    let mut sched = step_schedule();
    s.world.insert_resource(Trace::default());
    // Two systems writing the same resource in the same set, unordered: an error.
    sched.add_systems((|mut t: ResMut<Trace>| t.0.push("a")).in_set(PhysicsSet::First));
    sched.add_systems((|mut t: ResMut<Trace>| t.0.push("b")).in_set(PhysicsSet::First));
    assert!(sched.initialize(&mut s.world).is_err());
}

#[test]
fn sets_are_listed_in_order() {
    assert_eq!(PhysicsSet::ALL.first(), Some(&PhysicsSet::First));
    assert_eq!(PhysicsSet::ALL.last(), Some(&PhysicsSet::Last));
    let t = PhysicsSet::ALL
        .iter()
        .position(|s| *s == PhysicsSet::Transport);
    let d = PhysicsSet::ALL
        .iter()
        .position(|s| *s == PhysicsSet::Diffusion);
    let p = PhysicsSet::ALL
        .iter()
        .position(|s| *s == PhysicsSet::Poisson);
    assert!(t < d && d < p);
}

/// The order of the built-in systems in a step, stated once (by `PhysicsSet::ALL`): every run
/// runs these, in this order, less those its mode does not need (`pressure` and `baroclinic`
/// are the two kinds of body coupling; `free_motion` replaces the flow in vacuum).
const STEP_ORDER: &[&str] = &[
    "level_sets",
    "phase_density",
    "density",
    "rigid_velocity",
    "collision",
    "contact_impulse",
    "penalization",
    "pressure",
    "baroclinic",
    "transport",
    "diffusion",
    "poisson",
    "vorticity",
    "noslip",
    "free_surface",
    "free_motion",
    "rigid_update",
    "diagnostics",
];

/// The order of the built-in startup systems (the same sets, in the same order).
const STARTUP_ORDER: &[&str] = &[
    "level_sets_init",
    "free_surface_init",
    "density_init",
    "poisson",
    "diagnostics_init",
];

/// Bodies under a free surface: every built-in system but the other coupling's and vacuum's.
const BODIES_UNDER_WATER: &str = r#"Scene(
    domain: (extent: [1.0, 1.0], cells: [32, 32]),
    fluid: (gravity: [0.0, -1.0]),
    free_surface: Some((gas_density: 0.1, liquid: [Below(height: 0.6)])),
    numerics: (end_time: 0.1, dt: Fixed(0.001)COUPLING),
    bodies: [
        (name: "floor", shape: HalfSpace(normal: [0.0, 1.0, 0.0], offset: 0.0), kind: Static,
         position: [0.5, 0.1]),
        (name: "disk", shape: Disk(radius: 0.1), density: 2.0, position: [0.5, 0.4]),
    ],
)"#;

/// The systems that ran in the last schedule run, in the order they ran.
fn ran(s: &Simulation) -> Vec<&'static str> {
    s.timings().last.iter().map(|e| e.0).collect()
}

/// Whether `names` appear in `order` in the same order.
fn in_order(names: &[&str], order: &[&str]) -> bool {
    let mut rest = order.iter();
    names.iter().all(|n| rest.any(|o| o == n))
}

#[test]
fn built_in_systems_run_in_the_stated_order() {
    let text = BODIES_UNDER_WATER.replace("COUPLING", "");
    let mut s = Simulation::new(Scene::parse(&text, "test", "test").unwrap()).unwrap();
    assert_eq!(ran(&s), STARTUP_ORDER, "startup");
    s.step().unwrap();
    let expected: Vec<&str> = STEP_ORDER
        .iter()
        .copied()
        .filter(|n| !["baroclinic", "poisson", "free_motion", "noslip"].contains(n))
        .collect();
    // A free surface is carried in momentum form: the velocity is carried, and the Poisson
    // set only takes its vorticity.
    assert_eq!(ran(&s), expected, "a step with bodies under a free surface");
}

#[test]
fn every_kind_of_run_keeps_the_stated_order() {
    let vacuum = r#"Scene(
    domain: (extent: [1.0, 1.0], cells: [32, 32]),
    fluid: (gravity: [0.0, -10.0]),
    vacuum: true,
    numerics: (dt: Fixed(0.001), end_time: 0.1),
    bodies: [
        (name: "floor", shape: HalfSpace(normal: [0.0, 1.0, 0.0], offset: 0.0), kind: Static,
         position: [0.5, 0.05]),
        (name: "disk", shape: Disk(radius: 0.1), position: [0.5, 0.3]),
    ],
)"#;
    // (A free surface needs the pressure coupling.)
    let baroclinic = BODIES_UNDER_WATER
        .replace("COUPLING", ", body_coupling: Baroclinic")
        .replace(
            "free_surface: Some((gas_density: 0.1, liquid: [Below(height: 0.6)])),",
            "",
        );
    for (what, text, runs) in [
        ("vacuum", vacuum, &["free_motion", "rigid_update"][..]),
        (
            "baroclinic",
            baroclinic.as_str(),
            &["density", "baroclinic"][..],
        ),
        ("fluid", SCENE, &["transport", "poisson"][..]),
    ] {
        let mut s = Simulation::new(Scene::parse(text, "test", "test").unwrap()).unwrap();
        let startup = ran(&s);
        assert!(
            in_order(&startup, STARTUP_ORDER),
            "{what} startup: {startup:?}"
        );
        s.step().unwrap();
        let step = ran(&s);
        assert!(in_order(&step, STEP_ORDER), "{what}: {step:?}");
        for name in runs {
            assert!(step.contains(name), "{what}: {name} is not in {step:?}");
        }
    }
}
