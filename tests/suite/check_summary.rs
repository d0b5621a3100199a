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

#[test]
fn check_gives_the_steps_wall_time_disk_and_default_checkpoints() {
    // scenes/lamb-oseen.ron: adaptive with dt_max 0.02 to t = 2.5, 128² cells, 6 snapshots.
    let s = check("lamb-oseen.ron");
    assert!(
        s.contains("run: at least 125 steps (dt at most 0.02: numerics.dt.dt_max)"),
        "{s}"
    );
    assert!(s.contains("of wall time on 2 threads"), "{s}");
    assert!(s.contains("disk: about "), "{s}");
    assert!(s.contains("6 snapshots of 262 kB"), "{s}");
    assert!(s.contains("free on the disk of"), "{s}");
    assert!(
        s.contains("checkpoints: every 15 min of wall time (output.checkpoint_wall: 900 s)"),
        "{s}"
    );
}

#[test]
fn check_refuses_an_end_time_it_cannot_count_to() {
    let dir = std::env::temp_dir().join(format!("tumble-check-end-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("end.ron");
    std::fs::write(
        &scene,
        "Scene(\n    domain: (extent: [1.0, 1.0], cells: [32, 32]),\n    \
         numerics: (dt: Fixed(0.001), end_time: 1e300),\n)",
    )
    .unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_tumble"))
        .arg("check")
        .arg(&scene)
        .output()
        .unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("line 3, field `numerics.end_time`") && err.contains("1.000e303 steps"),
        "{err}"
    );
}
