//! Scene parsing: a good scene loads; a bad one is rejected with the line and the field path;
//! the field locator follows keys and list entries.

use tumble::scene::Scene;
use tumble::scene::error::{Seg, locate, offset_of, path_at};

const GOOD: &str = r#"Scene(
    domain: (extent: [2.0, 2.0], origin: [-1.0, -1.0], cells: [32, 32]),
    fluid: (
        viscosity: 0.001,
    ),
    initial: [LambOseen(center: [0.0, 0.0], circulation: 1.0, core_radius: 0.1)],
)"#;

#[test]
fn good_scene_loads() {
    let s = Scene::parse(GOOD, "good.ron", "good").unwrap();
    assert_eq!(s.name, "good");
    assert_eq!(s.grid().n, [32, 32, 1]);
    assert_eq!(s.grid().h, 2.0 / 32.0);
}

#[test]
fn negative_viscosity_names_line_and_field() {
    let text = GOOD.replace("0.001", "-1.0");
    let e = Scene::parse(&text, "bad.ron", "bad").unwrap_err();
    assert_eq!(e.line, Some(4));
    assert_eq!(e.field.as_deref(), Some("fluid.viscosity"));
}

#[test]
fn unknown_field_names_line() {
    let text = GOOD.replace("viscosity:", "viscosty:");
    let e = Scene::parse(&text, "bad.ron", "bad").unwrap_err();
    assert_eq!(e.line, Some(4));
    assert!(e.message.contains("viscosty"), "{}", e.message);
}

const TEXT: &str = r#"Scene(
    // a comment with shape: in it
    initial: [
        LambOseen(center: [0.0, 0.0], circulation: 1.0, core_radius: 0.1),
        LambOseen(center: [0.5, 0.0], circulation: "x",
            core_radius: 0.1),
    ],
    numerics: (end_time: "0.01"),
)"#;

#[test]
fn list_entries_are_located_by_index() {
    use Seg::*;
    let p = [Key("initial"), Index(1), Key("core_radius")];
    assert_eq!(locate(TEXT, &p), Some(6));
    let p = [Key("initial"), Index(0), Key("core_radius")];
    assert_eq!(locate(TEXT, &p), Some(4));
    let p = [Key("initial"), Index(1)];
    assert_eq!(locate(TEXT, &p), Some(5));
    // A key not written falls back to its entry.
    let p = [Key("initial"), Index(1), Key("nothing")];
    assert_eq!(locate(TEXT, &p), Some(5));
}

#[test]
fn position_names_the_field() {
    let at = TEXT.find("\"x\"").unwrap();
    assert_eq!(path_at(TEXT, at).as_deref(), Some("initial[1].circulation"));
    let at = TEXT.find("\"0.01\"").unwrap();
    assert_eq!(path_at(TEXT, at).as_deref(), Some("numerics.end_time"));
}

#[test]
fn offsets_count_characters() {
    let text = "a\nκb: 1";
    assert_eq!(&text[offset_of(text, 2, 2)..], "b: 1");
}

/// A 3D box of side 1 on 16³ cells with `bodies` (the entries' text).
fn box_with(bodies: &str) -> String {
    format!(
        "Scene(\n    domain: (extent: [1.0, 1.0, 1.0], cells: [16, 16, 16]),\n    \
         contact: (kappa: 1.0),\n    bodies: [\n{bodies}\n    ],\n)"
    )
}

#[test]
fn duplicate_body_names_name_the_second_line_and_field() {
    let text = box_with(
        "        (name: \"a\", shape: Sphere(radius: 0.1), position: [0.2, 0.5, 0.5]),\n        \
         (name: \"b\", shape: Sphere(radius: 0.1), position: [0.5, 0.5, 0.5]),\n        \
         (name: \"a\", shape: Sphere(radius: 0.1), position: [0.8, 0.5, 0.5]),",
    );
    let e = Scene::parse(&text, "dup.ron", "dup").unwrap_err();
    assert_eq!(e.line, Some(7), "{e}");
    assert_eq!(e.field.as_deref(), Some("bodies[2].name"), "{e}");
    assert!(
        e.message.contains("`a` is already the name of bodies[0]"),
        "{e}"
    );
    // Different names load.
    Scene::parse(&text.replacen("\"a\"", "\"c\"", 1), "dup.ron", "dup").unwrap();
}

#[test]
fn a_body_longer_than_the_periodic_box_is_refused() {
    let text = box_with(
        "        (name: \"small\", shape: Sphere(radius: 0.1), position: [0.5, 0.5, 0.2]),\n        \
         (name: \"ball\", shape: Sphere(radius: 0.6), position: [0.5, 0.5, 0.5]),",
    );
    let e = Scene::parse(&text, "big.ron", "big").unwrap_err();
    assert_eq!(e.line, Some(6), "{e}");
    assert_eq!(e.field.as_deref(), Some("bodies[1].shape"), "{e}");
    assert!(
        e.message.contains("1.2000 long along x") && e.message.contains("periodic image"),
        "{e}"
    );
}

#[test]
fn a_body_touching_its_own_periodic_image_is_refused() {
    // 0.9 long in a box of 1 on h = 1/16: 0.1 to its image, less than 2 (1 + 1) h = 0.25.
    let near = box_with(
        "        (name: \"ball\", shape: Sphere(radius: 0.45), position: [0.5, 0.5, 0.5]),",
    );
    let e = Scene::parse(&near, "near.ron", "near").unwrap_err();
    assert_eq!(e.line, Some(5), "{e}");
    assert_eq!(e.field.as_deref(), Some("bodies[0].shape"), "{e}");
    assert!(
        e.message
            .contains("overlaps its own periodic image along x")
            && e.message.contains("leaving 0.1000"),
        "{e}"
    );
    // A square plate 0.7 wide fits unrotated (0.3 to its image); turned by 45° about z it is
    // 0.7 √2 = 0.99 long along x and y (0.01 to its image).
    let plank = "        (name: \"plate\", shape: Box(half_extents: [0.35, 0.35, 0.025]), \
                 position: [0.5, 0.5, 0.5]ROT),";
    Scene::parse(&box_with(&plank.replace("ROT", "")), "p.ron", "p").unwrap();
    let turned = box_with(&plank.replace("ROT", ", rotation: [0.0, 0.0, 0.7853981633974483]"));
    let e = Scene::parse(&turned, "p.ron", "p").unwrap_err();
    assert_eq!(e.field.as_deref(), Some("bodies[0].shape"), "{e}");
    assert!(e.message.contains("as rotated"), "{e}");
    // A static wall may span the box (a floor continuing into its image).
    let floor = box_with(
        "        (name: \"floor\", shape: Box(half_extents: [0.6, 0.6, 0.1]), kind: Static, \
         position: [0.5, 0.5, 0.05]),",
    );
    Scene::parse(&floor, "floor.ron", "floor").unwrap();
}

#[test]
fn an_end_time_beyond_the_step_count_is_refused_with_the_numbers() {
    let text = "Scene(\n    domain: (extent: [1.0, 1.0], cells: [32, 32]),\n    \
                numerics: (dt: Fixed(0.001), end_time: 1e300),\n)";
    let e = Scene::parse(text, "end.ron", "end").unwrap_err();
    assert_eq!(e.line, Some(3), "{e}");
    assert_eq!(e.field.as_deref(), Some("numerics.end_time"), "{e}");
    assert!(
        e.message.contains("1.000e303 steps") && e.message.contains("2^53"),
        "{e}"
    );
    // An adaptive step bounded by dt_max: at least end_time / dt_max steps.
    let adaptive = text.replace("Fixed(0.001)", "Adaptive(dt_max: 0.01)");
    let e = Scene::parse(&adaptive, "end.ron", "end").unwrap_err();
    assert!(e.message.contains("at least 1.000e302 steps"), "{e}");
    // A long but countable run loads.
    Scene::parse(&text.replace("1e300", "1e6"), "end.ron", "end").unwrap();
}

#[test]
fn checkpoint_wall_must_be_positive() {
    let text = GOOD.replace("fluid: (", "output: (checkpoint_wall: 0.0),\n    fluid: (");
    let e = Scene::parse(&text, "w.ron", "w").unwrap_err();
    assert_eq!(e.field.as_deref(), Some("output.checkpoint_wall"), "{e}");
    assert_eq!(e.line, Some(3), "{e}");
    let off = GOOD.replace("fluid: (", "output: (checkpoint_wall: None),\n    fluid: (");
    assert_eq!(
        Scene::parse(&off, "w.ron", "w")
            .unwrap()
            .output
            .checkpoint_wall,
        None
    );
    assert_eq!(
        Scene::parse(GOOD, "w.ron", "w")
            .unwrap()
            .output
            .checkpoint_wall,
        Some(900.0)
    );
}
