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
