//! The same scene gives bit-identical results with 1 and 2 threads.

use crate::common::on_threads;
use tumble::scene::Scene;
use tumble::sim::engine::Simulation;

fn run(threads: usize, text: &str) -> (Vec<Vec<f64>>, Vec<Vec<f64>>, f64) {
    on_threads(threads, || {
        let scene = Scene::parse(text, "det", "det").unwrap();
        let mut sim = Simulation::new(scene).unwrap();
        for _ in 0..5 {
            sim.step().unwrap();
        }
        (
            sim.fields().omega().to_vec(),
            sim.fields().u.clone(),
            sim.sample().energy,
        )
    })
}

#[test]
fn three_d_results_do_not_depend_on_threads() {
    let text = r#"Scene(
        domain: (extent: [1.0, 1.0, 2.0], cells: [16, 16, 32]),
        fluid: (viscosity: 0.001),
        initial: [VortexRing(center: [0.5, 0.5, 0.6], axis: [0.1, 0.0, 1.0], radius: 0.25,
                             core_radius: 0.08, circulation: 1.0)],
    )"#;
    let a = run(1, text);
    let b = run(2, text);
    assert!(a.0 == b.0, "vorticity differs between 1 and 2 threads");
    assert!(a.1 == b.1, "velocity differs between 1 and 2 threads");
    assert_eq!(a.2.to_bits(), b.2.to_bits());
}

#[test]
fn two_d_results_do_not_depend_on_threads() {
    let text = r#"Scene(
        domain: (extent: [1.0, 1.0], cells: [32, 32]),
        initial: [LambOseen(center: [0.4, 0.5], circulation: 1.0, core_radius: 0.1),
                  LambOseen(center: [0.6, 0.5], circulation: 0.5, core_radius: 0.08)],
    )"#;
    let a = run(1, text);
    let b = run(2, text);
    assert!(a.0 == b.0 && a.1 == b.1);
}

/// Every body's pose and velocities, by scene index, as bits: (centre, orientation, velocity,
/// angular velocity, centroid, volume).
fn body_bits(sim: &mut Simulation) -> Vec<(usize, Vec<u64>)> {
    use tumble::bodies::{Body, RigidState};
    let mut q = sim.world.query::<(&Body, &RigidState)>();
    let mut v: Vec<(usize, Vec<u64>)> = q
        .iter(&sim.world)
        .map(|(b, s)| {
            let mut bits = Vec::new();
            for x in [s.center, s.velocity, s.angular_velocity, s.centroid] {
                bits.extend(x.to_array().map(f64::to_bits));
            }
            bits.extend(s.orientation.to_array().map(f64::to_bits));
            bits.push(s.volume.to_bits());
            (b.id, bits)
        })
        .collect();
    v.sort_by_key(|e| e.0);
    v
}

fn field_bits(f: &[Vec<f64>]) -> Vec<u64> {
    f.iter().flatten().map(|x| x.to_bits()).collect()
}

/// What a run with bodies leaves after `steps` steps on `threads` threads: every body's bits,
/// the vorticity and velocity bits, and how many steps had a contact.
struct BodyRun {
    bodies: Vec<(usize, Vec<u64>)>,
    omega: Vec<u64>,
    u: Vec<u64>,
    steps_in_contact: usize,
}

fn run_with_bodies(threads: usize, text: &str, steps: usize) -> BodyRun {
    on_threads(threads, || {
        let scene = Scene::parse(text, "det", "det").unwrap();
        let mut sim = Simulation::new(scene).unwrap();
        let mut steps_in_contact = 0;
        for _ in 0..steps {
            sim.step().unwrap();
            let contacts = sim
                .world
                .get_resource::<tumble::systems::collision::Contacts>()
                .map_or(0, |c| c.records.len());
            if contacts > 0 {
                steps_in_contact += 1;
            }
        }
        BodyRun {
            bodies: body_bits(&mut sim),
            omega: field_bits(sim.fields().omega()),
            u: field_bits(&sim.fields().u),
            steps_in_contact,
        }
    })
}

fn assert_same(a: &BodyRun, b: &BodyRun, steps: usize) {
    assert_eq!(
        a.steps_in_contact, steps,
        "the bodies must be in contact at every step (else contact is not tested)"
    );
    assert_eq!(a.bodies.len(), b.bodies.len());
    for (x, y) in a.bodies.iter().zip(&b.bodies) {
        assert!(x == y, "body {} differs between 1 and 2 threads", x.0);
    }
    assert!(
        a.omega == b.omega,
        "vorticity differs between 1 and 2 threads"
    );
    assert!(a.u == b.u, "velocity differs between 1 and 2 threads");
}

/// Four spheres and an ellipsoid in a closed box of fluid, touching each other and the floor
/// from the first step (gaps under eps = h), falling and pushing on each other.
const CONTACT_IN_FLUID: &str = r#"Scene(
    domain: (extent: [1.0, 1.0, 1.0], cells: [24, 24, 24]),
    fluid: (density: 1.0, viscosity: 0.01, gravity: [0.0, 0.0, -20.0]),
    numerics: (dt: Adaptive(c: 0.5, dt_max: 0.005), end_time: 1.0),
    contact: (kappa: 1.0),
    bodies: [
        (name: "box", shape: Complement(Box(half_extents: [0.42, 0.42, 0.42])), kind: Static,
         position: [0.5, 0.5, 0.5]),
        (name: "a", shape: Sphere(radius: 0.1), density: 1.5, position: [0.5, 0.5, 0.2]),
        (name: "b", shape: Sphere(radius: 0.1), density: 1.5, position: [0.52, 0.49, 0.42]),
        (name: "c", shape: Sphere(radius: 0.1), density: 2.0, position: [0.71, 0.5, 0.2]),
        (name: "d", shape: Sphere(radius: 0.1), density: 1.2, position: [0.5, 0.71, 0.21]),
        (name: "e", shape: Ellipsoid(radii: [0.12, 0.08, 0.06]), density: 1.5,
         position: [0.3, 0.3, 0.15]),
    ],
)"#;

#[test]
fn bodies_in_contact_in_fluid_do_not_depend_on_threads() {
    let steps = 12;
    let a = run_with_bodies(1, CONTACT_IN_FLUID, steps);
    let b = run_with_bodies(2, CONTACT_IN_FLUID, steps);
    assert_same(&a, &b, steps);
}

#[test]
fn bodies_in_contact_in_vacuum_do_not_depend_on_threads() {
    // The same bodies without fluid (collision and body integration only).
    let text = CONTACT_IN_FLUID.replace(
        "contact: (kappa: 1.0),",
        "contact: (kappa: 1.0),\n    vacuum: true,",
    );
    let steps = 40;
    let a = run_with_bodies(1, &text, steps);
    let b = run_with_bodies(2, &text, steps);
    assert_same(&a, &b, steps);
}

/// Spheres in an open periodic box touching each other through its boundary (corner and
/// faces) from the first step, their patches wrapped along x, y and z: the wrapped patch rows
/// (two grid segments each) and the image pairs of the contact are thread-count independent.
#[test]
fn bodies_across_the_periodic_boundary_do_not_depend_on_threads() {
    let text = r#"Scene(
        domain: (extent: [1.0, 1.0, 1.0], cells: [20, 20, 20]),
        fluid: (density: 1.0, viscosity: 0.01, gravity: [0.0, 0.0, -20.0]),
        numerics: (dt: Adaptive(c: 0.5, dt_max: 0.005), end_time: 1.0),
        contact: (kappa: 1.0),
        bodies: [
            (name: "a", shape: Sphere(radius: 0.1), density: 1.5, position: [0.02, 0.03, 0.05]),
            (name: "b", shape: Sphere(radius: 0.1), density: 2.0, position: [0.81, 0.02, 0.04]),
            (name: "c", shape: Sphere(radius: 0.1), density: 1.2, position: [0.03, 0.5, 0.83]),
        ],
    )"#;
    let steps = 6;
    let a = run_with_bodies(1, text, steps);
    let b = run_with_bodies(2, text, steps);
    assert_same(&a, &b, steps);
}
