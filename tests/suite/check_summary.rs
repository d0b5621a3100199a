//! `tumble check` summarises a scene in words: bodies counted by kind and shape, not listed.

use std::path::Path;
use std::process::Command;

fn check(scene: &str) -> String {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = Command::new(env!("CARGO_BIN_EXE_tumble"))
        .arg("check")
        .arg(root.join("scenes").join(scene))
        .output()
        .expect("tumble runs");
    assert!(out.status.success(), "check {scene} failed");
    String::from_utf8(out.stdout).unwrap()
}

#[test]
fn tank_summary_counts_bodies_by_kind_and_shape() {
    let s = check("tank-200.ron");
    // scenes/tank-200.ron: a static box complement and 200 spheres of density 1.5, 64^3 cells.
    assert!(s.contains("200 dynamic Sphere, density 1.5"), "{s}");
    assert!(s.contains("1 static Complement"), "{s}");
    assert!(s.contains("262,144 cells"), "{s}");
    assert!(s.contains("adaptive"), "{s}");
    assert!(s.lines().count() < 25, "one line per body?\n{s}");
    assert!(
        !s.contains("Adaptive {"),
        "internal structures printed:\n{s}"
    );
}

#[test]
fn vacuum_scene_says_so() {
    let s = check("tank-200-vacuum.ron");
    assert!(s.contains("vacuum: no flow"), "{s}");
    let s = check("lamb-oseen.ron");
    assert!(s.contains("fluid: density"), "{s}");
    assert!(s.contains("bodies: none"), "{s}");
}
