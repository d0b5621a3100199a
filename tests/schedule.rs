//! The schedule: the default one builds with ambiguity detection as an error, user systems
//! hook into the empty First/Last sets, and an ambiguous pair is rejected.

use bevy_ecs::prelude::*;
use tumble::scene::Scene;
use tumble::sim::engine::Simulation;
use tumble::sim::schedule::{PhysicsSet, step_schedule};

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
    let mut sched = step_schedule();
    sched
        .initialize(&mut s.world)
        .expect("default schedule builds");
    s.step().unwrap();
    assert!(s.time() > 0.0);
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
