//! Bodies that cross the periodic box's boundary (issue 45): a body's level set, patch,
//! integrals, contact and pose wrap around the box like the flow does.
//!
//! The key test is translation invariance: the box is periodic and the grid uniform, so the
//! same body and flow shifted by a whole number of cells must evolve identically, whether
//! the body sits in the middle of the box or straddles its boundary (or a corner). The
//! discrete operators (FFT Poisson solve, stencils, particle remeshing) all commute with a
//! circular shift of the grid, so the only differences allowed are round-off: the body's
//! position is a different floating-point number, and the sums over its patch pick up their
//! terms at different positions. A patch wrapped wrongly (a lost half body, a lever arm of a
//! box length, a node written twice) gives differences of order one.

use glam::DVec3;
use tumble::bodies::{Body, Hydro, RigidState};
use tumble::scene::Scene;
use tumble::sim::engine::Simulation;

fn sim(text: &str) -> Simulation {
    let scene = Scene::parse(text, "test", "test").unwrap_or_else(|e| panic!("{e}"));
    Simulation::new(scene).unwrap_or_else(|e| panic!("{e}"))
}

/// Every body's (name, state, hydrodynamic force), sorted by name.
fn bodies(s: &mut Simulation) -> Vec<(String, RigidState, DVec3)> {
    let mut q = s.world.query::<(&Body, &RigidState, &Hydro)>();
    let mut v: Vec<_> = q
        .iter(&s.world)
        .map(|(b, st, h)| (b.name.clone(), *st, h.force))
        .collect();
    v.sort_by(|a, b| a.0.cmp(&b.0));
    v
}

/// The same heavy disk falling from rest in a 2D box of 32² cells (h = 1/32), its centre at
/// `center`; the velocity field after `steps` steps and the disk's (velocity, hydro force,
/// centre).
fn disk_2d(center: [f64; 2], steps: usize) -> (Simulation, Vec<Vec<f64>>, (DVec3, DVec3, DVec3)) {
    let mut s = sim(&format!(
        r#"Scene(
        domain: (extent: [1.0, 1.0], cells: [32, 32]),
        fluid: (viscosity: 0.02, gravity: [0.3, -1.0]),
        numerics: (dt: Fixed(0.004), end_time: 10.0),
        bodies: [(name: "disk", shape: Ellipse(radii: [0.12, 0.08]), density: 2.0,
                  position: [{:.17}, {:.17}], rotation: [0.4])],
    )"#,
        center[0], center[1]
    ));
    for _ in 0..steps {
        s.step().unwrap();
    }
    let b = bodies(&mut s);
    let (_, st, f) = &b[0];
    let u = s.fields().u.clone();
    (s, u, (st.velocity, *f, st.center))
}

#[test]
fn a_body_straddling_the_boundary_moves_as_the_same_body_in_the_middle() {
    // An ellipse (turned, so that its patch is not symmetric), falling obliquely from rest; the
    // middle run's centre is off the nodes by (0.3, 0.7) h. The others are the same set-up
    // moved by (-16, 0) cells (straddling x = 0), (0, -16) (straddling y = 0) and (-16, -16)
    // (straddling a corner). After 40 steps the body has moved about 0.4 cells (its patch
    // is sampled anew every step, in its new position), so each sample, integral and
    // the no-slip and pressure coupling have run on a wrapped patch.
    let h = 1.0 / 32.0;
    let mid = [0.5 + 0.3 * h, 0.5 + 0.7 * h];
    let steps = 40;
    let (_, u0, (v0, f0, c0)) = disk_2d(mid, steps);
    assert!(v0.length() > 1e-3, "the disk should be falling: {v0:?}");
    let mut worst = 0.0f64;
    for shift in [[16usize, 0usize], [0, 16], [16, 16]] {
        let at = [mid[0] - shift[0] as f64 * h, mid[1] - shift[1] as f64 * h];
        let (s, u, (v, f, c)) = disk_2d(at, steps);
        let n = s.grid().n;
        // The flow, shifted back node for node.
        let umax = u0[0]
            .iter()
            .chain(&u0[1])
            .fold(0.0f64, |m, x| m.max(x.abs()));
        let mut du = 0.0f64;
        for j in 0..n[1] {
            for i in 0..n[0] {
                let g = i + n[0] * j;
                let g0 = (i + shift[0]) % n[0] + n[0] * ((j + shift[1]) % n[1]);
                for q in 0..2 {
                    du = du.max((u[q][g] - u0[q][g0]).abs());
                }
            }
        }
        let dv = (v - v0).length() / v0.length();
        let df = (f - f0).length() / f0.length().max(1e-300);
        // The centre: moved by the shift (it stays in the box: x - 16 h wrapped).
        let expect = DVec3::new(c0.x - shift[0] as f64 * h, c0.y - shift[1] as f64 * h, 0.0);
        let ext = 1.0;
        let mut dc = c - expect;
        for a in 0..2 {
            dc[a] -= (dc[a] / ext).round() * ext;
        }
        let err = (du / umax).max(dv).max(df);
        worst = worst.max(err);
        eprintln!(
            "shift {shift:?}: |du|/|u|max = {:.2e}, |dV|/|V| = {dv:.2e}, |dF|/|F| = {df:.2e}, \
             |dc| = {:.2e}",
            du / umax,
            dc.length()
        );
        // Round-off: a few hundred steps' worth of ulps of O(1) quantities, amplified by the
        // no-slip's conjugate gradients (the markers' kernel weights differ in the last bits
        // between the shifted runs; 6e-9 measured). A wrongly wrapped patch shows up at O(1).
        assert!(err < 1e-7, "shift {shift:?}: relative difference {err:.3e}");
        // The centre has moved about 0.4 cells with a velocity that differs by round-off as
        // above: a relative 1e-9 of 0.0125 is 1e-11.
        assert!(
            dc.length() < 1e-10,
            "shift {shift:?}: centre {c:?} vs {expect:?}"
        );
    }
    eprintln!("worst relative difference {worst:.2e}");
}

/// A 3D sphere straddling a corner of the box against the same sphere in the middle: the
/// patch wraps along x, y and z at once (a patch row along x then maps to two grid segments).
#[test]
fn a_sphere_straddling_a_corner_moves_as_the_same_sphere_in_the_middle() {
    let h = 1.0 / 20.0;
    let run = |c: [f64; 3]| {
        let mut s = sim(&format!(
            r#"Scene(
            domain: (extent: [1.0, 1.0, 1.0], cells: [20, 20, 20]),
            fluid: (viscosity: 0.05, gravity: [0.2, 0.1, -1.0]),
            numerics: (dt: Fixed(0.005), end_time: 10.0),
            bodies: [(name: "s", shape: Sphere(radius: 0.15), density: 3.0,
                      position: [{:.17}, {:.17}, {:.17}])],
        )"#,
            c[0], c[1], c[2]
        ));
        for _ in 0..15 {
            s.step().unwrap();
        }
        let b = bodies(&mut s);
        (b[0].1.velocity, b[0].1.angular_velocity, b[0].2)
    };
    let mid = [0.5 + 0.2 * h, 0.5 + 0.6 * h, 0.5 + 0.4 * h];
    let (v0, w0, f0) = run(mid);
    let (v, w, f) = run([mid[0] - 10.0 * h, mid[1] - 10.0 * h, mid[2] - 10.0 * h]);
    let dv = (v - v0).length() / v0.length();
    let df = (f - f0).length() / f0.length().max(1e-300);
    let dw = (w - w0).length() / v0.length() * 0.15;
    eprintln!("corner: |dV|/|V| = {dv:.2e}, |dF|/|F| = {df:.2e}, |dΩ| a/|V| = {dw:.2e}");
    assert!(v0.length() > 1e-3, "{v0:?}");
    assert!(dv.max(df).max(dw) < 1e-9, "{dv:.3e} {df:.3e} {dw:.3e}");
}

#[test]
fn a_disk_settles_through_the_boundary_again_and_again() {
    // A disk settling along y in a periodic box of 32² cells (h = 1/32) at Re = U d/ν of
    // order 10, through the bottom face and in at the top four times. The run goes on, the
    // centre stays in the box, and the crossing leaves no mark on the motion: once the disk
    // is at its terminal velocity, the step-to-step change of its velocity at a crossing is
    // no larger than anywhere else (the velocity wobbles with the disk's position on the
    // grid, a fraction of a per cent at 3 cells per radius; a crossing that lost part of
    // the body or mis-placed its lever arms would jump by O(V)), and the mean velocity over
    // each traversal of the box is the same (the motion is periodic with the box once
    // steady, so successive traversals differ by the tail of the transient only).
    let mut s = sim(r#"Scene(
        domain: (extent: [1.0, 1.0], cells: [32, 32]),
        fluid: (viscosity: 0.02, gravity: [0.0, -1.0]),
        numerics: (dt: Fixed(0.01), end_time: 100.0),
        bodies: [(name: "disk", shape: Disk(radius: 0.1), density: 2.0, position: [0.5, 0.5])],
    )"#);
    let (mut travelled, mut crossings) = (0.0f64, Vec::new());
    let (mut v, mut force) = (Vec::new(), Vec::new());
    let mut last_y = 0.5;
    let mut traversal_start = Vec::new();
    while travelled < 4.6 {
        s.step().unwrap();
        let b = bodies(&mut s);
        let st = b[0].1;
        let dt = 0.01;
        travelled += -st.velocity.y * dt;
        assert!(
            (0.0..1.0).contains(&st.center.y) && (0.0..1.0).contains(&st.center.x),
            "centre {:?} left the box",
            st.center
        );
        if st.center.y > last_y + 0.5 {
            crossings.push(v.len());
        }
        if travelled >= traversal_start.len() as f64 + 0.5 && traversal_start.len() < 5 {
            traversal_start.push(v.len());
        }
        last_y = st.center.y;
        v.push(st.velocity);
        force.push(b[0].2);
        assert!(
            s.steps() < 20_000,
            "too slow: travelled {travelled} in {} steps",
            s.steps()
        );
    }
    assert!(crossings.len() >= 4, "crossings at steps {crossings:?}");
    // Terminal from the second crossing on: the change per step there and elsewhere.
    let from = crossings[1] - 30;
    let step_change = |k: usize| (v[k] - v[k - 1]).length();
    let at_crossing = crossings[1..]
        .iter()
        .flat_map(|&k| [k, k + 1])
        .map(step_change)
        .fold(0.0f64, f64::max);
    let elsewhere = (from..v.len())
        .filter(|k| !crossings.iter().any(|&c| *k == c || *k == c + 1))
        .map(step_change)
        .fold(0.0f64, f64::max);
    let speed = v.last().unwrap().length();
    eprintln!(
        "crossings at steps {crossings:?}; speed {speed:.5}; largest change per step at a \
         crossing {at_crossing:.3e}, elsewhere {elsewhere:.3e}"
    );
    assert!(
        at_crossing <= 1.5 * elsewhere + 1e-6 * speed,
        "the velocity jumps at a crossing: {at_crossing:.3e} against {elsewhere:.3e} elsewhere"
    );
    // Mean velocity over whole traversals (between the points 0.5 + k box lengths down).
    let mean = |a: usize, b: usize| v[a..b].iter().map(|v| v.y).sum::<f64>() / (b - a) as f64;
    let means: Vec<f64> = traversal_start
        .windows(2)
        .map(|w| mean(w[0], w[1]))
        .collect();
    eprintln!("mean velocity per traversal {means:?}");
    let (m2, m3) = (means[means.len() - 2], means[means.len() - 1]);
    assert!(
        ((m3 - m2) / m3).abs() < 2e-3,
        "the mean velocity changed from one traversal to the next: {means:?}"
    );
    // Sideways: the disk falls straight (symmetric about x = 0.5 to round-off).
    // The fluid's force on the disk (`Hydro`), averaged over each whole traversal of the
    // steady, box-periodic motion: the same from one traversal to the next (to the velocity's
    // noise, a fraction of a per cent), so crossing the boundary adds no force; and, the
    // motion being steady, it carries the disk's whole weight ρ_b π a² |g| (buoyancy and
    // drag). (Before the force was taken from the body's motion, the parts the flow and the
    // no-slip report summed to about a quarter of it, half the excess weight.)
    let fmean =
        |a: usize, b: usize| force[a..b].iter().fold(DVec3::ZERO, |s, f| s + *f) / (b - a) as f64;
    let forces: Vec<DVec3> = traversal_start
        .windows(2)
        .map(|w| fmean(w[0], w[1]))
        .collect();
    eprintln!("mean hydrodynamic force per traversal {forces:?}");
    let weight = 2.0 * std::f64::consts::PI * 0.1 * 0.1;
    for f in &forces[1..] {
        assert!(
            (f.y - weight).abs() < 5e-3 * weight && f.x.abs() < 5e-3 * weight,
            "the fluid's force {f:?} does not carry the weight {weight:.5} of a steadily settling disk"
        );
    }
    for w in forces[1..].windows(2) {
        assert!(
            (w[1] - w[0]).length() < 5e-3 * w[1].length(),
            "the mean force changed from one traversal to the next: {forces:?}"
        );
    }
    // Sideways: the set-up is symmetric about x = 0.5, but the no-slip is solved iteratively
    // (to 1e-3 of the step's slip, systems/noslip.rs), which leaves noise of that order in
    // the velocity (the per-step changes above); a crossing that pushed the disk sideways
    // would show at O(V).
    let side = v.iter().fold(0.0f64, |m, v| m.max(v.x.abs()));
    eprintln!("largest sideways velocity {side:.3e}");
    assert!(side < 0.01 * speed, "sideways drift {side:.3e}");
}

#[test]
fn two_spheres_touch_through_the_periodic_boundary() {
    // Two disks moving apart in the box (in vacuum: no flow), towards the boundary at
    // x = 0 and x = 1: they meet through it. The contact must stop and turn them back, as
    // it does for the same two disks meeting in the middle of the box.
    let run = |x: [f64; 2], v: f64| {
        let mut s = sim(&format!(
            r#"Scene(
            domain: (extent: [1.0, 1.0], cells: [64, 64]),
            vacuum: true,
            numerics: (dt: Fixed(0.0005), end_time: 1.0),
            contact: (kappa: 5.0),
            bodies: [
                (name: "a", shape: Disk(radius: 0.1), density: 1.0, position: [{}, 0.5],
                 velocity: [{}, 0.0]),
                (name: "b", shape: Disk(radius: 0.1), density: 1.0, position: [{}, 0.5],
                 velocity: [{}, 0.0]),
            ],
        )"#,
            x[0], -v, x[1], v
        ));
        let mut gap = f64::INFINITY;
        for _ in 0..600 {
            s.step().unwrap();
            let b = bodies(&mut s);
            // The distance between the centres through the nearer image.
            let mut d = (b[1].1.center.x - b[0].1.center.x).abs();
            d = d.min(1.0 - d);
            gap = gap.min(d - 0.2);
        }
        let b = bodies(&mut s);
        (b[0].1.velocity.x, b[1].1.velocity.x, gap)
    };
    // Through the boundary: a at 0.2 going left, b at 0.8 going right (gap 0.2 across x = 0).
    let (va, vb, gap) = run([0.2, 0.8], 1.0);
    // In the middle: the same pair at the same gap (a at 0.7 going left, b at 0.3 going
    // right), at the same offsets from the nodes (0.7 - 0.2 and 0.3 - 0.8 are whole cells).
    let (va0, vb0, gap0) = run([0.7, 0.3], 1.0);
    eprintln!("through: {va} {vb} gap {gap}; middle: {va0} {vb0} gap {gap0}");
    assert!(va > 0.5 && vb < -0.5, "not turned back: {va} {vb}");
    assert!(
        (va - va0).abs() < 1e-6 && (vb - vb0).abs() < 1e-6,
        "{va} {vb} vs {va0} {vb0}"
    );
    assert!((gap - gap0).abs() < 1e-9 && gap > 0.0, "{gap} vs {gap0}");
}

#[test]
fn bodies_overlapping_across_the_boundary_are_rejected() {
    // Centres 0.1 apart through x = 0 (0.05 and 0.95), radii 0.1: they overlap by 0.1 through
    // the boundary, though 0.9 apart inside the box.
    let text = r#"Scene(
        domain: (extent: [1.0, 1.0], cells: [32, 32]),
        fluid: (gravity: [0.0, -1.0]),
        bodies: [
            (name: "a", shape: Disk(radius: 0.1), position: [0.05, 0.5]),
            (name: "b", shape: Disk(radius: 0.1), position: [0.95, 0.5]),
        ],
    )"#;
    let e = Scene::parse(text, "bad.ron", "bad").unwrap_err();
    assert!(e.message.contains("overlap at the start"), "{e}");
    // 0.25 apart through the boundary: fine.
    Scene::parse(&text.replace("0.95", "0.8"), "ok.ron", "ok").unwrap();
}

#[test]
fn bodies_half_a_box_apart_touch_through_both_images() {
    // Two disks half a box apart along x (0.25 in a box of 0.5, gap 0.05, within the contact
    // range of 6 cells) meet through two images at once: b on a's right, and b's image on
    // a's left. The contact on a must be the sum of the two one-sided contacts, measured with
    // the same disks in a box twice as long (the other image out of reach), at the same
    // offsets against the nodes. Counting the nearest image alone gives one of them.
    let force_on_a = |extent: f64, a: f64, b: f64| {
        let n = (extent * 64.0).round() as usize;
        let mut s = sim(&format!(
            r#"Scene(
            domain: (extent: [{extent}, 0.5], cells: [{n}, 32]),
            vacuum: true,
            numerics: (dt: Fixed(0.0005), end_time: 1.0),
            contact: (kappa: 5.0),
            bodies: [
                (name: "a", shape: Disk(radius: 0.1), density: 1.0, position: [{a}, 0.25]),
                (name: "b", shape: Disk(radius: 0.1), density: 1.0, position: [{b}, 0.25]),
            ],
        )"#
        ));
        s.step().unwrap();
        let mut q = s.world.query::<(&Body, &tumble::bodies::ContactState)>();
        q.iter(&s.world)
            .find(|(body, _)| body.name == "a")
            .map(|(_, c)| c.force)
            .unwrap()
    };
    let right = force_on_a(1.0, 0.375, 0.625);
    let left = force_on_a(1.0, 0.375, 0.125);
    let both = force_on_a(0.5, 0.125, 0.375);
    eprintln!("right {right:?}, left {left:?}, both {both:?}");
    assert!(
        right.x < 0.0 && left.x > 0.0,
        "no contact: {right:?} {left:?}"
    );
    let err = (both - (right + left)).length();
    assert!(
        err <= 1e-9 * right.length(),
        "both images {both:?} against {:?}",
        right + left
    );
}
