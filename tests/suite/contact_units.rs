//! The contact strength κ follows the scene's own scales (issue 16 item 4): with `contact.kappa`
//! left out, the same scene written in m and in cm moves the same, to round-off. κ is a
//! length³/time² (the acceleration the force gives is κ A/V e^{-d/ε}/d), so a bare number is
//! 10⁶ times stiffer in one unit system than in the other; the default C L² max(|g|, U²/ε) is
//! made of the scene's lengths, speeds and gravity only.

use tumble::bodies::{Body, RigidState};
use tumble::scene::Scene;
use tumble::sim::engine::Simulation;

/// One run of a body dropped in vacuum on a static floor, every length in the scene multiplied
/// by `scale` (1: m; 100: cm) and time unchanged: the height of the body's centre at every
/// step, divided by `scale` (so in m), and the error that stopped the run early, if any.
/// `contact` is the scene's `contact` entry (empty: the default κ). 2D: a disk of radius
/// 0.05 m; 3D: a ball of radius 0.05 m; both dropped from 0.1 m above the floor (12.8 ε in
/// 2D, 6.4 ε in 3D), to t = 0.6 s: two impacts.
fn drop_heights(dim: usize, scale: f64, contact: &str) -> (Vec<f64>, Option<String>) {
    let l = |x: f64| x * scale;
    let (h, dt) = if dim == 2 {
        (0.5 / 64.0, 0.0005)
    } else {
        (0.5 / 32.0, 0.001)
    };
    // The 2D and 3D scenes differ only in their vectors and in the body's shape.
    let (o, e, g, c, y0) = (l(-0.0625), l(0.5), l(-9.81), l(0.25), l(0.15));
    let (origin, extent, gravity, normal, floor_at, body, at) = if dim == 2 {
        (
            format!("[0.0, {o}]"),
            format!("[{e}, {e}]"),
            format!("[0.0, {g}]"),
            "[0.0, 1.0, 0.0]",
            format!("[{c}, 0.0]"),
            format!("name: \"disk\", shape: Disk(radius: {})", l(0.05)),
            format!("[{c}, {y0}]"),
        )
    } else {
        (
            format!("[0.0, 0.0, {o}]"),
            format!("[{e}, {e}, {e}]"),
            format!("[0.0, 0.0, {g}]"),
            "[0.0, 0.0, 1.0]",
            format!("[{c}, {c}, 0.0]"),
            format!("name: \"ball\", shape: Sphere(radius: {})", l(0.05)),
            format!("[{c}, {c}, {y0}]"),
        )
    };
    let text = format!(
        r#"Scene(
        domain: (origin: {origin}, extent: {extent}, h: {h}),
        fluid: (gravity: {gravity}),
        vacuum: true,
        {contact}
        numerics: (dt: Fixed({dt}), end_time: 0.6),
        bodies: [
            (name: "floor", shape: HalfSpace(normal: {normal}, offset: 0.0),
             kind: Static, position: {floor_at}),
            ({body}, position: {at}),
        ],
    )"#,
        h = l(h),
    );
    let scene = Scene::parse(&text, "drop", "drop").unwrap_or_else(|e| panic!("{e}"));
    let mut sim = Simulation::new(scene).unwrap_or_else(|e| panic!("{e}"));
    sim.set_stop_at(Some(0.6));
    let mut ys = Vec::new();
    while sim.time() < 0.6 - 1e-12 {
        if let Err(e) = sim.step() {
            return (ys, Some(e.to_string()));
        }
        let mut q = sim.world.query::<(&Body, &RigidState)>();
        let (_, s) = q.iter(&sim.world).find(|(b, _)| b.is_dynamic()).unwrap();
        ys.push(s.center[dim - 1] / scale);
    }
    (ys, None)
}

/// The largest difference between two height curves over the steps both ran, m.
fn largest_difference(a: &(Vec<f64>, Option<String>), b: &(Vec<f64>, Option<String>)) -> f64 {
    a.0.iter()
        .zip(&b.0)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

#[test]
fn a_drop_in_m_and_in_cm_moves_the_same_with_the_default_kappa() {
    let (r, drop) = (0.05, 0.1);
    for dim in [2, 3] {
        let si = drop_heights(dim, 1.0, "");
        let cgs = drop_heights(dim, 100.0, "");
        assert!(si.1.is_none() && cgs.1.is_none(), "{:?} {:?}", si.1, cgs.1);
        assert_eq!(si.0.len(), cgs.0.len());
        // The drop is real: the body comes within a few ε of the floor (the default stops a
        // body arriving from the bottom of the domain, here from twice the drop, at about
        // ε), not into it, and comes back up after the first impact.
        let eps = if dim == 2 { 0.5 / 64.0 } else { 0.5 / 32.0 };
        let lowest = si.0.iter().copied().fold(f64::INFINITY, f64::min) - r;
        let first = si.0.iter().position(|&y| y - r == lowest).unwrap();
        let apex = si.0[first..].iter().copied().fold(0.0, f64::max) - r;
        let diff = largest_difference(&si, &cgs);
        println!(
            "{dim}D: lowest gap {:.3} eps, rebound to {:.4} m of {drop} m; largest |y_SI - \
             y_cgs/100| over {} steps: {diff:.3e} m ({:.3e} of the drop)",
            lowest / eps,
            apex,
            si.0.len(),
            diff / drop
        );
        assert!(
            lowest > 0.0 && lowest < 3.0 * eps,
            "{dim}D: the lowest gap {lowest} is not in (0, 3 eps = {})",
            3.0 * eps
        );
        assert!(apex > 0.9 * drop, "{dim}D: rebound to {apex} only");
        // Exactly the same motion in exact arithmetic; in floating point the two runs differ
        // by the rounding of lengths times 100 (not a power of two), amplified by the
        // contact's stiffness: measured 1e-14 m. Any scale left out of the default moves the
        // curves by a power of 100 in κ, i.e. by a sizeable fraction of ε (see the control).
        assert!(
            diff < 1e-9 * drop,
            "{dim}D: the runs in m and in cm differ by {diff} m"
        );
    }
}

#[test]
fn a_bare_kappa_is_not_unit_independent() {
    // The control: the old default, κ = 25 in both unit systems, is 10⁶ times softer in cm
    // than in m.
    let si = drop_heights(2, 1.0, "contact: (kappa: 25.0),");
    let cgs = drop_heights(2, 100.0, "contact: (kappa: 25.0),");
    let diff = largest_difference(&si, &cgs);
    println!(
        "kappa = 25 in both: largest difference {diff:.3e} m over the {} steps both ran; the \
         run in cm: {}",
        si.0.len().min(cgs.0.len()),
        cgs.1.as_deref().unwrap_or("ran to the end")
    );
    // In cm the disk sinks through the floor (and leaves the box); in m it rebounds.
    assert!(
        diff > 0.01,
        "kappa = 25 in m and cm differ by {diff} m only"
    );
}

#[test]
fn the_default_matches_the_papers_values_in_fluid() {
    // The paper's cases in fluid, in its cgs units, without their `contact: (kappa: ..)`.
    let default_of = |file: &str| {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("scenes")
            .join(file);
        let text = std::fs::read_to_string(path).unwrap();
        let text: String = text
            .lines()
            .filter(|l| !l.trim_start().starts_with("contact:"))
            .map(|l| format!("{l}\n"))
            .collect();
        let scene = Scene::parse(&text, file, "t").unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(scene.contact.kappa, None);
        // Body 0 is the walls, body 1 the first dynamic body.
        scene.kappa_default().pair(0, 1)
    };
    // 2D disk of radius 0.125 under g = 980: 2 · 980 · 0.125² (the paper: 30).
    let k = default_of("sedimentation-2d.ron");
    assert!((k - 30.625).abs() < 1e-9, "{k}");
    // Spheres of radius 0.083 under g = 980: 3 · 980 · 0.083² (the paper: 25).
    let k = default_of("dkt.ron");
    assert!((k - 3.0 * 980.0 * 0.083 * 0.083).abs() < 1e-9, "{k}");
}

#[test]
fn without_gravity_or_speed_kappa_must_be_given() {
    let scene = |extra: &str| {
        format!(
            r#"Scene(
            domain: (extent: [1.0, 1.0], h: 0.03125),
            vacuum: true,
            {extra}
            bodies: [
                (name: "floor", shape: HalfSpace(normal: [0.0, 1.0, 0.0], offset: 0.0),
                 kind: Static, position: [0.5, 0.2]),
                (name: "disk", shape: Disk(radius: 0.1), position: [0.5, 0.5]VELOCITY),
            ],
        )"#
        )
    };
    let e = Scene::parse(&scene("").replace("VELOCITY", ""), "s", "s").unwrap_err();
    assert_eq!(e.field.as_deref(), Some("contact.kappa"), "{e}");
    assert!(e.message.contains("gravity is zero"), "{e}");
    // A speed is a scale: C L² U²/ε.
    let s = Scene::parse(
        &scene("").replace("VELOCITY", ", velocity: [0.0, -1.0]"),
        "s",
        "s",
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let k = s.kappa_default().pair(0, 1);
    assert!((k - 2.0 * 0.01 * 1.0 / 0.03125).abs() < 1e-12, "{k}");
    // So is a given κ.
    Scene::parse(
        &scene("contact: (kappa: 1.0),").replace("VELOCITY", ""),
        "s",
        "s",
    )
    .unwrap_or_else(|e| panic!("{e}"));
}
