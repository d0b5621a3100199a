//! Body generators (`generators: [...]`): expanded at load time into ordinary bodies,
//! deterministic for a seed, non-overlapping, inside their region, in the documented shares,
//! and with errors that name the generator's line.

use std::collections::BTreeMap;
use tumble::bodies::shapes::Shape;
use tumble::scene::generate::{Draw, Range, Values, shares};
use tumble::scene::{BodySpec, Scene, SceneError, ValidScene};

/// A 3D scene in the unit box with one generator (`GEN` replaced by its text); the generator
/// starts on line 4.
fn scene3(generator: &str) -> String {
    format!(
        "Scene(\n    domain: (extent: [1.0, 1.0, 1.0], cells: [32, 32, 32]), contact: (kappa: 1.0),\n    generators: [\n        {generator},\n    ],\n)"
    )
}

fn load(text: &str) -> ValidScene {
    Scene::parse(text, "gen.ron", "gen").unwrap_or_else(|e| panic!("{e}"))
}

fn err(text: &str) -> SceneError {
    Scene::parse(text, "gen.ron", "gen").expect_err("must be rejected")
}

/// Radius about the centre of the sphere around the shape, from the shape's own sizes.
fn bounding_radius(s: &Shape) -> f64 {
    match s {
        Shape::Sphere { radius } | Shape::Disk { radius } => *radius,
        Shape::Box { half_extents } => half_extents.iter().map(|x| x * x).sum::<f64>().sqrt(),
        Shape::Rectangle { half_extents } => half_extents.iter().map(|x| x * x).sum::<f64>().sqrt(),
        Shape::Capsule {
            radius,
            half_height,
        } => radius + half_height,
        Shape::Cylinder {
            radius,
            half_height,
        } => (radius * radius + half_height * half_height).sqrt(),
        other => panic!("no radius for {other:?}"),
    }
}

const MIXED: &str = "(name: \"g\", layout: Random(region: (min: [0.1, 0.1, 0.1], max: [0.9, 0.9, 0.9]), count: 100, gap: 0.01), seed: SEED, shapes: [Sphere(radius: 0.04), Box(half_extents: [0.03, 0.03, 0.03]), Capsule(radius: 0.02, half_height: 0.02)], scale: (min: 0.8, max: 1.2), densities: [0.5, 2.0], rotation: Random)";

fn mixed(seed: u64) -> ValidScene {
    load(&scene3(&MIXED.replace("SEED", &seed.to_string())))
}

#[test]
fn same_seed_same_bodies_other_seed_other_bodies() {
    let a = mixed(7);
    let b = mixed(7);
    assert_eq!(a.bodies, b.bodies);
    assert_eq!(a.bodies.len(), 100);
    let c = mixed(8);
    assert_eq!(c.bodies.len(), 100);
    let moved = a
        .bodies
        .iter()
        .zip(&c.bodies)
        .filter(|(x, y)| x.position != y.position)
        .count();
    assert!(moved > 90, "only {moved} of 100 bodies moved with the seed");
    // Expanded into ordinary bodies: the loaded scene has no generator left.
    assert!(a.generators.is_empty());
    // Names are <name><index>.
    let names: Vec<&str> = a.bodies.iter().map(|b| b.name.as_str()).collect();
    assert_eq!(names[0], "g0");
    assert_eq!(names[99], "g99");
}

#[test]
fn random_packing_is_inside_the_region_without_overlaps() {
    let s = mixed(7);
    let (lo, hi, gap) = ([0.1; 3], [0.9; 3], 0.01);
    let balls: Vec<([f64; 3], f64)> = s
        .bodies
        .iter()
        .map(|b| {
            (
                [b.position[0], b.position[1], b.position[2]],
                bounding_radius(&b.shape),
            )
        })
        .collect();
    for (c, r) in &balls {
        for a in 0..3 {
            assert!(
                c[a] - r >= lo[a] - 1e-12 && c[a] + r <= hi[a] + 1e-12,
                "{c:?} r {r}"
            );
        }
    }
    for i in 0..balls.len() {
        for j in i + 1..balls.len() {
            let (ci, ri) = balls[i];
            let (cj, rj) = balls[j];
            let d = (0..3).map(|a| (ci[a] - cj[a]).powi(2)).sum::<f64>().sqrt();
            assert!(
                d >= ri + rj + gap,
                "bodies {i} and {j}: {d} < {ri} + {rj} + {gap}"
            );
        }
    }
}

#[test]
fn shapes_and_densities_come_in_equal_shares() {
    let s = mixed(7);
    let mut shapes: BTreeMap<&str, usize> = BTreeMap::new();
    let mut dens: BTreeMap<u64, usize> = BTreeMap::new();
    for b in &s.bodies {
        *shapes.entry(b.shape.name()).or_default() += 1;
        *dens.entry(b.density.unwrap().to_bits()).or_default() += 1;
    }
    // 100 over 3 shapes: the first listed gets the extra one; 100 over 2 densities: 50 each.
    assert_eq!(shapes["Sphere"], 34);
    assert_eq!(shapes["Box"], 33);
    assert_eq!(shapes["Capsule"], 33);
    assert_eq!(dens[&0.5f64.to_bits()], 50);
    assert_eq!(dens[&2.0f64.to_bits()], 50);
    // Shapes and densities are not paired up: both densities occur with spheres.
    let sphere_dens: std::collections::BTreeSet<u64> = s
        .bodies
        .iter()
        .filter(|b| b.shape.name() == "Sphere")
        .map(|b| b.density.unwrap().to_bits())
        .collect();
    assert_eq!(sphere_dens.len(), 2);
    // Sizes within the scale range, and not all alike.
    let radii: Vec<f64> = s
        .bodies
        .iter()
        .filter_map(|b| match b.shape {
            Shape::Sphere { radius } => Some(radius),
            _ => None,
        })
        .collect();
    assert!(
        radii.iter().all(|r| (0.032..=0.048).contains(r)),
        "{radii:?}"
    );
    let spread =
        radii.iter().cloned().fold(0.0, f64::max) - radii.iter().cloned().fold(1.0, f64::min);
    assert!(spread > 0.008, "sizes barely vary: {spread}");
}

#[test]
fn random_rotations_are_uniform() {
    // Uniform rotations have a zero mean rotation matrix; 1000 tiny spheres in a big region.
    let g = "(layout: Random(region: (min: [0.0, 0.0, 0.0], max: [1.0, 1.0, 1.0]), count: 1000), seed: 3, shapes: [Sphere(radius: 0.01)], rotation: Random)";
    let s = load(&scene3(g));
    let mut mean = [[0.0; 3]; 3];
    for b in &s.bodies {
        let r = glam::DVec3::new(b.rotation[0], b.rotation[1], b.rotation[2]);
        assert!(r.length() <= std::f64::consts::PI + 1e-12);
        let m = glam::DMat3::from_quat(glam::DQuat::from_scaled_axis(r));
        for (i, row) in mean.iter_mut().enumerate() {
            for (j, x) in row.iter_mut().enumerate() {
                *x += m.col(j)[i] / 1000.0;
            }
        }
    }
    // Each entry's standard deviation is 1/sqrt(3 * 1000) = 0.018.
    for row in mean {
        for x in row {
            assert!(x.abs() < 0.08, "{mean:?}");
        }
    }
    // Default names: gen<index>_<k>.
    assert_eq!(s.bodies[0].name, "gen0_0");
}

#[test]
fn lattice_gives_exact_positions() {
    let g = "(name: \"p\", layout: Lattice(start: [0.2, 0.25, 0.3], spacing: [0.2, 0.25, 0.1], counts: [3, 2, 2]), shapes: [Sphere(radius: 0.05)], densities: 2.0)";
    let s = load(&scene3(g));
    assert_eq!(s.bodies.len(), 12);
    let mut k = 0;
    for l in 0..2 {
        for j in 0..2 {
            for i in 0..3 {
                let b = &s.bodies[k];
                assert_eq!(b.name, format!("p{k}"));
                let want = [
                    0.2 + i as f64 * 0.2,
                    0.25 + j as f64 * 0.25,
                    0.3 + l as f64 * 0.1,
                ];
                for (x, w) in b.position.iter().zip(want) {
                    assert!((x - w).abs() < 1e-12, "{k}: {:?}", b.position);
                }
                assert_eq!(b.density, Some(2.0));
                assert!(b.rotation.is_empty());
                k += 1;
            }
        }
    }
}

#[test]
fn two_dimensional_generator_with_range_densities_and_angles() {
    let text = "Scene(\n    domain: (extent: [1.0, 1.0], cells: [64, 64]), contact: (kappa: 1.0),\n    bodies: [(name: \"d\", shape: Disk(radius: 0.2), position: [0.5, 0.5])],\n    generators: [(layout: Random(region: (min: [0.0, 0.0], max: [1.0, 1.0]), count: 20), shapes: [Rectangle(half_extents: [0.03, 0.01])], densities: (min: 1.0, max: 3.0), rotation: Random)],\n)";
    let s = load(text);
    assert_eq!(s.bodies.len(), 21);
    let listed = [0.5, 0.5];
    for b in &s.bodies[1..] {
        let d = b.density.unwrap();
        assert!((1.0..=3.0).contains(&d));
        assert_eq!(b.rotation.len(), 1);
        assert!((0.0..std::f64::consts::TAU).contains(&b.rotation[0]));
        // Kept off the listed disk: the bounding circles do not meet.
        let r = bounding_radius(&b.shape);
        let dist =
            ((b.position[0] - listed[0]).powi(2) + (b.position[1] - listed[1]).powi(2)).sqrt();
        assert!(dist >= 0.2 + r, "{:?}", b.position);
    }
}

#[test]
fn a_region_too_small_is_an_error_at_the_generator() {
    // 200 spheres of radius 0.05 cannot fit a box of side 0.3 (at most 27 on a lattice).
    let g = "(layout: Random(region: (min: [0.1, 0.1, 0.1], max: [0.4, 0.4, 0.4]), count: 200), shapes: [Sphere(radius: 0.05)])";
    let e = err(&scene3(g));
    assert_eq!(e.line, Some(4), "{e}");
    assert!(e.message.contains("placed only"), "{e}");
    assert!(e.message.contains("of 200"), "{e}");
    assert!(e.message.contains("bigger region"), "{e}");
}

#[test]
fn bad_generators_are_errors_naming_the_line() {
    let good = "(layout: Random(region: (min: [0.1, 0.1, 0.1], max: [0.9, 0.9, 0.9]), count: 10), shapes: [Sphere(radius: 0.05)])";
    assert_eq!(load(&scene3(good)).bodies.len(), 10);
    let cases = [
        (good.replace("count: 10", "count: 0"), "at least 1"),
        (
            good.replace("[Sphere(radius: 0.05)]", "[]"),
            "at least one shape",
        ),
        (
            good.replace("max: [0.9, 0.9, 0.9]", "max: [0.9, 1.5, 0.9]"),
            "not inside the domain",
        ),
        (
            good.replace("count: 10)", "count: 10), scale: (min: 1.2, max: 0.8)"),
            "above max",
        ),
        (
            good.replace("count: 10)", "count: 10), densities: [1.0, -2.0]"),
            "positive",
        ),
        (
            good.replace("Sphere(radius: 0.05)", "Disk(radius: 0.05)"),
            "2D shape",
        ),
        (
            good.replace(
                "Sphere(radius: 0.05)",
                "HalfSpace(normal: [0.0, 0.0, 1.0], offset: 0.1)",
            ),
            "unbounded",
        ),
    ];
    for (text, words) in cases {
        let e = err(&scene3(&text));
        assert_eq!(e.line, Some(4), "{text}: {e}");
        assert!(e.message.contains(words), "{text}: {e}");
        assert!(
            e.field
                .as_deref()
                .unwrap_or("")
                .starts_with("generators[0]"),
            "{e}"
        );
    }
}

#[test]
fn a_generated_body_in_a_wall_is_an_error_at_the_generator() {
    // A lattice whose last column sits in a floor (the half-space z <= 0.2).
    let text = "Scene(\n    domain: (extent: [1.0, 1.0, 1.0], cells: [32, 32, 32]), contact: (kappa: 1.0),\n    bodies: [(name: \"floor\", shape: HalfSpace(normal: [0.0, 0.0, 1.0], offset: 0.2), kind: Static, position: [0.0, 0.0, 0.0])],\n    generators: [\n        (layout: Lattice(start: [0.5, 0.5, 0.5], spacing: [0.1, 0.1, -0.1], counts: [1, 1, 4]), shapes: [Sphere(radius: 0.05)]),\n    ],\n)";
    let e = err(text);
    // Negative spacing is rejected first; with a positive one going down from 0.2 instead:
    assert_eq!(e.line, Some(5), "{e}");
    let text = text.replace(
        "start: [0.5, 0.5, 0.5], spacing: [0.1, 0.1, -0.1]",
        "start: [0.5, 0.5, 0.2], spacing: [0.1, 0.1, 0.1]",
    );
    let e = err(&text);
    assert_eq!(e.line, Some(5), "{e}");
    assert!(e.message.contains("overlap"), "{e}");
    assert!(e.message.contains("floor"), "{e}");
    assert!(e.message.contains("generators[0]"), "{e}");
    // The random packing keeps clear of the wall by itself.
    let text = "Scene(\n    domain: (extent: [1.0, 1.0, 1.0], cells: [32, 32, 32]), contact: (kappa: 1.0),\n    bodies: [(name: \"floor\", shape: HalfSpace(normal: [0.0, 0.0, 1.0], offset: 0.2), kind: Static, position: [0.0, 0.0, 0.0])],\n    generators: [(layout: Random(region: (min: [0.0, 0.0, 0.0], max: [1.0, 1.0, 1.0]), count: 50, gap: 0.01), shapes: [Sphere(radius: 0.05)])],\n)";
    let s = load(text);
    for b in &s.bodies[1..] {
        assert!(
            b.position[2] >= 0.2 + 0.05 + 0.01 - 1e-12,
            "{:?}",
            b.position
        );
    }
}

#[test]
fn generated_names_must_not_clash() {
    let text = "Scene(\n    domain: (extent: [1.0, 1.0, 1.0], cells: [32, 32, 32]), contact: (kappa: 1.0),\n    bodies: [(name: \"g1\", shape: Sphere(radius: 0.05), position: [0.1, 0.1, 0.1])],\n    generators: [(name: \"g\", layout: Lattice(start: [0.5, 0.5, 0.5], spacing: [0.2, 0.2, 0.2], counts: [2, 1, 1]), shapes: [Sphere(radius: 0.05)])],\n)";
    let e = err(text);
    assert_eq!(e.line, Some(4), "{e}");
    assert!(e.message.contains("`g1`"), "{e}");
}

#[test]
fn bundled_grains_scene_checks_with_counts_by_shape_and_density() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_tumble"))
        .arg("check")
        .arg(root.join("scenes/grains.ron"))
        .output()
        .expect("tumble runs");
    let s = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{s}");
    // scenes/grains.ron: a box, 4 static posts, 60 grains in three shapes (20 each) and two
    // densities (30 each).
    assert!(s.contains("bodies: 65"), "{s}");
    assert!(s.contains("Sphere 20"), "{s}");
    assert!(s.contains("Box 20"), "{s}");
    assert!(s.contains("Capsule 20"), "{s}");
    assert!(s.contains("1.5 x 30"), "{s}");
    assert!(s.contains("2.5 x 30"), "{s}");
    let scene = Scene::load(&root.join("scenes/grains.ron")).unwrap();
    let grains: Vec<&BodySpec> = scene
        .bodies
        .iter()
        .filter(|b| b.name.starts_with("grain"))
        .collect();
    assert_eq!(grains.len(), 60);
}

#[test]
fn check_memory_estimate_is_near_the_measured_peak() {
    // The estimate `tumble check` prints against `tumble bench`'s measured peak (VmHWM) on the
    // grains scene: loosely, within a factor 1.5 either way. Time is not tested (it varies
    // with the machine's load).
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let scene = Scene::load(&root.join("scenes/grains.ron")).unwrap();
    let est = tumble::io::estimate::estimate(&scene);
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_tumble"))
        .args(["bench", "--steps", "1", "--warmup", "1"])
        .arg(root.join("scenes/grains.ron"))
        .output()
        .expect("tumble runs");
    assert!(out.status.success());
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON line");
    let Some(peak) = v["peak_memory_bytes"].as_f64() else {
        eprintln!("no peak memory on this platform");
        return;
    };
    let ratio = est.bytes / peak;
    assert!(
        (1.0 / 1.5..1.5).contains(&ratio),
        "estimate {} against peak {peak}",
        est.bytes
    );
    assert!(est.seconds_per_step > 0.0 && est.patch_nodes > est.nodes);
}

#[test]
fn values_parse_as_one_list_or_range() {
    let p = |t: &str| ron::from_str::<Values>(t).unwrap();
    assert_eq!(p("1.5"), Values::One(1.5));
    assert_eq!(p("[0.5, 2.0]"), Values::List(vec![0.5, 2.0]));
    assert_eq!(
        p("(min: 0.5, max: 2.0)"),
        Values::Range(Range { min: 0.5, max: 2.0 })
    );
}

#[test]
fn shares_are_equal_and_shuffled() {
    let mut d = Draw::new(3);
    let v = shares(10, 3, &mut d);
    let n = |k| v.iter().filter(|&&x| x == k).count();
    assert_eq!((n(0), n(1), n(2)), (4, 3, 3));
}
