//! The command line as a user meets it.

use std::path::PathBuf;
use std::process::Command;

fn tumble() -> Command {
    Command::new(env!("CARGO_BIN_EXE_tumble"))
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("tumble-cli-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

const SCENE: &str = r#"Scene(
    name: "tiny",
    domain: (extent: [1.0, 1.0], cells: [32, 32]),
    fluid: (viscosity: 0.001),
    numerics: (end_time: 0.2),
    initial: [LambOseen(center: [0.5, 0.5], circulation: 1.0, core_radius: 0.1)],
    output: (every: 0.1),
)"#;

#[test]
fn run_writes_outputs_and_refuses_to_overwrite() {
    let d = tmp("run");
    let scene = d.join("tiny.ron");
    std::fs::write(&scene, SCENE).unwrap();
    let out = d.join("out");
    let st = tumble()
        .args([
            "run",
            scene.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(
        st.status.success(),
        "{}",
        String::from_utf8_lossy(&st.stderr)
    );
    for f in [
        "scene.ron",
        "series.csv",
        "fields.pvd",
        "log.txt",
        "timings.csv",
    ] {
        assert!(out.join(f).exists(), "{f} missing");
    }
    // Snapshots at t = 0, 0.1, 0.2, each readable, with the time it claims.
    let pvd = std::fs::read_to_string(out.join("fields.pvd")).unwrap();
    assert_eq!(pvd.matches("<DataSet").count(), 3, "{pvd}");
    let last = crate::vti::read_vti(&out.join("fields_000002.vti")).unwrap();
    assert!((last.time.unwrap() - 0.2).abs() < 1e-12);
    assert_eq!(last.whole_extent, [0, 31, 0, 31, 0, 0]);
    // The series ends at the end time.
    let series = std::fs::read_to_string(out.join("series.csv")).unwrap();
    let last_t: f64 = series
        .lines()
        .last()
        .unwrap()
        .split(',')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!((last_t - 0.2).abs() < 1e-12);
    // A second run into the same directory is refused without --force...
    let st = tumble()
        .args([
            "run",
            scene.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(!st.status.success());
    assert!(String::from_utf8_lossy(&st.stderr).contains("--force"));
    // ...and allowed with it, since tumble made the directory (it holds the marker): the old
    // directory is replaced as a whole, so a snapshot of the first run does not survive.
    assert!(out.join(".tumble-run").is_file());
    let st = tumble()
        .args([
            "run",
            scene.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--force",
            "--until",
            "0.05",
        ])
        .output()
        .unwrap();
    assert!(
        st.status.success(),
        "{}",
        String::from_utf8_lossy(&st.stderr)
    );
    assert!(out.join(".tumble-run").is_file());
    assert!(!out.join("fields_000002.vti").exists());
    let pvd = std::fs::read_to_string(out.join("fields.pvd")).unwrap();
    assert_eq!(pvd.matches("<DataSet").count(), 2, "{pvd}");
    let last = crate::vti::read_vti(&out.join("fields_000001.vti")).unwrap();
    assert!((last.time.unwrap() - 0.05).abs() < 1e-12);
    let _ = std::fs::remove_dir_all(&d);
}

/// The files under `d` (recursively, relative paths) with their contents.
fn contents(d: &std::path::Path) -> Vec<(String, Vec<u8>)> {
    let mut v = Vec::new();
    let mut todo = vec![d.to_path_buf()];
    while let Some(p) = todo.pop() {
        for e in std::fs::read_dir(&p).unwrap() {
            let e = e.unwrap();
            let path = e.path();
            let rel = path.strip_prefix(d).unwrap().to_string_lossy().into_owned();
            if e.file_type().unwrap().is_dir() {
                v.push((rel + "/", Vec::new()));
                todo.push(path);
            } else {
                v.push((rel, std::fs::read(&path).unwrap()));
            }
        }
    }
    v.sort();
    v
}

/// --force replaces only a directory tumble made: a directory of the user's files, the
/// current directory (`--out .`, even if tumble made it) and the home directory are refused
/// with status 2, a message saying why, and every file left as it was.
#[test]
fn force_refuses_what_tumble_did_not_make_and_touches_nothing() {
    let d = tmp("force");
    let scene = d.join("tiny.ron");
    std::fs::write(&scene, SCENE).unwrap();
    // A directory of the user's files, one of them in a subdirectory.
    let mine = d.join("mine");
    std::fs::create_dir_all(mine.join("notes")).unwrap();
    std::fs::write(mine.join("thesis.tex"), "chapter 1").unwrap();
    std::fs::write(mine.join("notes/todo.txt"), "write chapter 2").unwrap();
    // A run directory tumble made, used as the current directory, and a home directory
    // that (by mistake) holds a marker.
    let run = d.join("run");
    let st = tumble()
        .args(["run", scene.to_str().unwrap(), "--quiet", "--out"])
        .arg(&run)
        .output()
        .unwrap();
    assert!(st.status.success());
    let home = d.join("home");
    std::fs::create_dir_all(&home).unwrap();
    std::fs::write(home.join(".tumble-run"), "").unwrap();
    std::fs::write(home.join(".profile"), "export A=1").unwrap();
    let cases: [(&std::path::Path, PathBuf, &str); 4] = [
        (&d, mine.clone(), "was not made by tumble"),
        (&mine, PathBuf::from("."), "is the current directory"),
        (&run, PathBuf::from("."), "is the current directory"),
        (&d, home.clone(), "is the home directory"),
    ];
    for (cwd, out, want) in cases {
        let before = contents(&d);
        let st = tumble()
            .current_dir(cwd)
            .env("HOME", &home)
            .args([
                "run",
                scene.to_str().unwrap(),
                "--quiet",
                "--force",
                "--out",
            ])
            .arg(&out)
            .output()
            .unwrap();
        let msg = String::from_utf8_lossy(&st.stderr);
        assert_eq!(st.status.code(), Some(2), "{}: {msg}", out.display());
        one_paragraph(&msg);
        assert!(msg.contains(want), "{msg}");
        assert!(msg.contains("--out"), "says what to do: {msg}");
        assert_eq!(contents(&d), before, "{} is left as it was", out.display());
    }
    assert_eq!(
        std::fs::read_to_string(mine.join("notes/todo.txt")).unwrap(),
        "write chapter 2"
    );
    // Without --force the user's directory is refused too, without suggesting --force.
    let st = tumble()
        .args(["run", scene.to_str().unwrap(), "--quiet", "--out"])
        .arg(&mine)
        .output()
        .unwrap();
    assert_eq!(st.status.code(), Some(2));
    let msg = String::from_utf8_lossy(&st.stderr);
    assert!(msg.contains("was not made by tumble"), "{msg}");
    assert!(!msg.contains("--force"), "{msg}");
    let _ = std::fs::remove_dir_all(&d);
}

/// The README's first command, `tumble run <scene> --force` into the default runs/<name>:
/// it works when runs/ does not exist yet (a fresh clone) and again over its own output.
#[test]
fn force_into_the_default_run_dir_works_fresh_and_again() {
    let d = tmp("default-force");
    std::fs::write(d.join("tiny.ron"), SCENE).unwrap();
    for _ in 0..2 {
        let st = tumble()
            .current_dir(&d)
            .args(["run", "tiny.ron", "--quiet", "--force", "--until", "0.1"])
            .output()
            .unwrap();
        assert!(
            st.status.success(),
            "{}",
            String::from_utf8_lossy(&st.stderr)
        );
        assert!(d.join("runs/tiny/.tumble-run").is_file());
        assert!(d.join("runs/tiny/fields_000001.vti").is_file());
    }
    let _ = std::fs::remove_dir_all(&d);
}

/// A scene's output.dir may not leave the current directory (absolute, or with `..`): status
/// 2 and nothing written; the same directory given with --out is the user's choice.
#[test]
fn scene_output_dir_outside_the_current_directory_is_refused() {
    let d = tmp("scene-dir");
    let work = d.join("work");
    std::fs::create_dir_all(&work).unwrap();
    let outside = d.join("outside");
    for (dir, want) in [
        ("../outside", "contains `..`"),
        ("sub/../../outside", "contains `..`"),
        (outside.to_str().unwrap(), "is an absolute path"),
        (".", "names the current directory"),
    ] {
        let scene = SCENE.replace(
            "output: (every: 0.1)",
            &format!("output: (every: 0.1, dir: {dir:?})"),
        );
        std::fs::write(work.join("s.ron"), &scene).unwrap();
        let st = tumble()
            .current_dir(&work)
            .args(["run", "s.ron", "--quiet", "--force"])
            .output()
            .unwrap();
        let msg = String::from_utf8_lossy(&st.stderr);
        assert_eq!(st.status.code(), Some(2), "{dir}: {msg}");
        one_paragraph(&msg);
        assert!(msg.contains(want), "{msg}");
        assert!(msg.contains("--out"), "{msg}");
        assert!(!outside.exists());
        assert_eq!(listing(&work), ["s.ron"]);
    }
    // A plain relative output.dir is used; --out overrides an absolute one.
    let scene = SCENE.replace("output: (every: 0.1)", "output: (every: 0.1, dir: \"a/b\")");
    std::fs::write(work.join("s.ron"), &scene).unwrap();
    let st = tumble()
        .current_dir(&work)
        .args(["run", "s.ron", "--quiet", "--until", "0.1"])
        .output()
        .unwrap();
    assert!(
        st.status.success(),
        "{}",
        String::from_utf8_lossy(&st.stderr)
    );
    assert!(work.join("a/b/.tumble-run").is_file());
    let scene = SCENE.replace(
        "output: (every: 0.1)",
        &format!("output: (every: 0.1, dir: {:?})", outside.to_str().unwrap()),
    );
    std::fs::write(work.join("s.ron"), &scene).unwrap();
    let st = tumble()
        .current_dir(&work)
        .args(["run", "s.ron", "--quiet", "--until", "0.1", "--out"])
        .arg(&outside)
        .output()
        .unwrap();
    assert!(
        st.status.success(),
        "{}",
        String::from_utf8_lossy(&st.stderr)
    );
    assert!(outside.join("fields_000001.vti").is_file());
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn bad_scene_exits_2_and_names_the_line() {
    let d = tmp("bad");
    let scene = d.join("bad.ron");
    std::fs::write(&scene, SCENE.replace("viscosity: 0.001", "viscosity: -1.0")).unwrap();
    let st = tumble()
        .args(["check", scene.to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(st.status.code(), Some(2));
    let msg = String::from_utf8_lossy(&st.stderr);
    assert!(
        msg.contains("line 4") && msg.contains("fluid.viscosity"),
        "{msg}"
    );
    let st = tumble()
        .args([
            "run",
            scene.to_str().unwrap(),
            "--out",
            d.join("o").to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert_eq!(st.status.code(), Some(2));
    assert!(!d.join("o").exists(), "nothing is written for a bad scene");
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn check_summarises_a_good_scene() {
    let d = tmp("check");
    let scene = d.join("tiny.ron");
    std::fs::write(&scene, SCENE).unwrap();
    let st = tumble()
        .args(["check", scene.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(st.status.success());
    let out = String::from_utf8_lossy(&st.stdout);
    assert!(out.contains("32x32"), "{out}");
    let _ = std::fs::remove_dir_all(&d);
}

/// `tumble check --processes N`: the slabs of a 3D flow (48 planes over 5 processes: 9 or 10
/// each), and a clear refusal of a 2D scene, with the reason.
#[test]
fn check_says_how_a_scene_splits_over_processes() {
    let d = tmp("check-split");
    let scene = d.join("box.ron");
    std::fs::write(
        &scene,
        r#"Scene(domain: (extent: [1.0, 1.0, 3.0], cells: [16, 16, 48]), fluid: (viscosity: 0.01),
    numerics: (end_time: 0.1))"#,
    )
    .unwrap();
    let check = |scene: &std::path::Path, n: &str| {
        let st = tumble()
            .args(["check", scene.to_str().unwrap(), "--processes", n])
            .output()
            .unwrap();
        assert!(
            st.status.success(),
            "{}",
            String::from_utf8_lossy(&st.stderr)
        );
        String::from_utf8_lossy(&st.stdout).into_owned()
    };
    let out = check(&scene, "5");
    assert!(
        out.contains("on 5 processes: slabs of 9 to 10 z-planes"),
        "{out}"
    );
    let flat = d.join("flat.ron");
    std::fs::write(&flat, SCENE).unwrap();
    let out = check(&flat, "2");
    assert!(
        out.contains("on 2 processes: cannot split (a 2D grid runs on one process"),
        "{out}"
    );
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn bench_prints_one_json_line() {
    let d = tmp("bench");
    let scene = d.join("tiny.ron");
    std::fs::write(&scene, SCENE).unwrap();
    let st = tumble()
        .args(["bench", scene.to_str().unwrap(), "--steps", "3"])
        .output()
        .unwrap();
    assert!(
        st.status.success(),
        "{}",
        String::from_utf8_lossy(&st.stderr)
    );
    let out = String::from_utf8_lossy(&st.stdout);
    let v: serde_json::Value = serde_json::from_str(out.trim()).unwrap();
    assert_eq!(v["cells"], 1024);
    assert_eq!(v["steps"], 3);
    assert!(v["median_s_per_step"].as_f64().unwrap() > 0.0);
    assert!(v["median_s_per_system"]["transport"].as_f64().is_some());
    // The step as a ratio to the FFT floor of the same grid, measured in the same process.
    let floor = v["fft_floor_s"].as_f64().unwrap();
    let ratio = v["step_per_fft_floor"].as_f64().unwrap();
    assert!(floor > 0.0);
    let med = v["median_s_per_step"].as_f64().unwrap();
    assert!((ratio - med / floor).abs() <= 1e-9 * ratio);
    assert!(v["system_per_fft_floor"]["transport"].as_f64().unwrap() > 0.0);
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn validate_unknown_case_fails() {
    let st = tumble()
        .args(["validate", "nope", "--quick"])
        .output()
        .unwrap();
    assert!(!st.status.success());
}

#[test]
fn validate_writes_the_plots_to_the_plots_dir() {
    // taylor-green-2d --quick: 64², 100 steps, well under a second.
    let d = tmp("valplots");
    let dir = d.join("plots");
    let out = tumble()
        .args(["validate", "taylor-green-2d", "--quick", "--plots"])
        .arg(&dir)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let png = dir.join("taylor-green-2d-quick-energy.png");
    assert!(
        stdout.contains(&png.display().to_string()),
        "the file written is printed: {stdout}"
    );
    let bytes = std::fs::read(&png).unwrap_or_else(|e| panic!("{}: {e}", png.display()));
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "{}", png.display());
    assert!(
        bytes.len() > 10_000,
        "{}: {} bytes",
        png.display(),
        bytes.len()
    );
    // Nothing else: no temporary files left behind.
    let names: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names.len(), 1, "{names:?}");
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn check_warns_of_a_dense_body_with_the_baroclinic_coupling() {
    let d = tmp("dense");
    let scene = |coupling: &str| {
        format!(
            r#"Scene(
    domain: (extent: [1.0, 1.0], cells: [32, 32]),
    fluid: (gravity: [0.0, -1.0]),
    numerics: (body_coupling: {coupling}),
    bodies: [(name: "steel", shape: Disk(radius: 0.1), density: 7.8, position: [0.5, 0.5])],
)"#
        )
    };
    for (coupling, warned) in [("Baroclinic", true), ("Momentum", false)] {
        let file = d.join(format!("{coupling}.ron"));
        std::fs::write(&file, scene(coupling)).unwrap();
        let st = tumble()
            .args(["check", file.to_str().unwrap()])
            .output()
            .unwrap();
        assert!(st.status.success());
        let out = String::from_utf8_lossy(&st.stdout);
        assert_eq!(
            out.contains("warning: body `steel` is 7.800 times as dense"),
            warned,
            "{out}"
        );
    }
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn check_rejects_a_missing_mesh_with_status_2() {
    let d = tmp("mesh");
    let scene = d.join("m.ron");
    std::fs::write(
        &scene,
        r#"Scene(
    domain: (extent: [1.0, 1.0, 1.0], cells: [16, 16, 16]),
    bodies: [(name: "cup", shape: Mesh(file: "cup.obj"), position: [0.5, 0.5, 0.5])],
)"#,
    )
    .unwrap();
    let st = tumble()
        .args(["check", scene.to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(st.status.code(), Some(2));
    let msg = String::from_utf8_lossy(&st.stderr);
    assert!(msg.contains("cup") && msg.contains("not found"), "{msg}");
    assert!(msg.contains("line 3"), "{msg}");
    let st = tumble()
        .args([
            "run",
            scene.to_str().unwrap(),
            "--out",
            d.join("o").to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert_eq!(st.status.code(), Some(2));
    assert!(!d.join("o").exists(), "nothing is written for a bad mesh");
    let _ = std::fs::remove_dir_all(&d);
}

/// The files and directories under `d` (relative), sorted.
fn listing(d: &std::path::Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(d)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// One paragraph: a single line (plus its newline) starting with `error:`.
fn one_paragraph(msg: &str) {
    let msg = msg.trim_end();
    assert!(msg.starts_with("error: "), "{msg}");
    assert!(!msg.contains("\n\n"), "{msg}");
    assert!(msg.lines().count() <= 3, "{msg}");
}

#[test]
fn overlapping_bodies_exit_2_naming_line_and_bodies() {
    let d = tmp("overlap");
    let cases = [
        // Two dynamic disks 0.1 apart with radius 0.1: deeply overlapping.
        (
            r#"Scene(
    domain: (extent: [1.0, 1.0], cells: [32, 32]),
    bodies: [
        (name: "left", shape: Disk(radius: 0.1), position: [0.45, 0.5]),
        (name: "right", shape: Disk(radius: 0.1),
         position: [0.55, 0.5]),
    ],
)"#,
            "line 6",
            ["left", "right"],
        ),
        // A dynamic sphere sunk into a static floor.
        (
            r#"Scene(
    domain: (extent: [1.0, 1.0, 1.0], cells: [16, 16, 16]),
    bodies: [
        (name: "floor", shape: HalfSpace(normal: [0.0, 0.0, 1.0], offset: 0.25), kind: Static, position: [0.0, 0.0, 0.0]),
        (name: "ball", shape: Sphere(radius: 0.1), position: [0.5, 0.5, 0.25]),
    ],
)"#,
            "line 5",
            ["floor", "ball"],
        ),
    ];
    for (k, (text, line, names)) in cases.iter().enumerate() {
        let scene = d.join(format!("o{k}.ron"));
        std::fs::write(&scene, text).unwrap();
        for cmd in ["check", "run"] {
            let out = d.join(format!("out{k}"));
            let st = tumble()
                .args([cmd, scene.to_str().unwrap(), "--out", out.to_str().unwrap()])
                .args(if cmd == "check" {
                    &[][..]
                } else {
                    &["--quiet"][..]
                })
                .output()
                .unwrap();
            // `check` takes no --out: only the run's exit status and message matter there.
            if cmd == "check" {
                continue;
            }
            assert_eq!(st.status.code(), Some(2));
            let msg = String::from_utf8_lossy(&st.stderr);
            one_paragraph(&msg);
            assert!(msg.contains(scene.to_str().unwrap()), "{msg}");
            assert!(msg.contains(line), "{msg}");
            assert!(msg.contains("bodies[1].position"), "{msg}");
            assert!(msg.contains("overlap"), "{msg}");
            for n in names {
                assert!(msg.contains(&format!("`{n}`")), "{msg}");
            }
            assert!(!out.exists(), "nothing is written for overlapping bodies");
        }
        let st = tumble()
            .args(["check", scene.to_str().unwrap()])
            .output()
            .unwrap();
        assert_eq!(st.status.code(), Some(2));
    }
    // Touching (1/4 cell apart) is fine (with a κ: nothing in this scene moves, so it has no
    // scale for the default).
    let scene = d.join("touch.ron");
    let touching = cases[0]
        .0
        .replace("[0.55, 0.5]", "[0.65 , 0.5]")
        .replace("bodies: [", "contact: (kappa: 1.0),\n    bodies: [");
    std::fs::write(&scene, touching).unwrap();
    let st = tumble()
        .args(["check", scene.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(
        st.status.success(),
        "{}",
        String::from_utf8_lossy(&st.stderr)
    );
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn unwritable_output_dir_exits_2_and_writes_nothing() {
    let d = tmp("unwritable");
    let scene = d.join("tiny.ron");
    std::fs::write(&scene, SCENE).unwrap();
    let before = listing(&d);
    // Under a regular file (root can write anywhere else), and a file in place of the dir,
    // with and without --force.
    let file = d.join("a-file");
    std::fs::write(&file, "keep me").unwrap();
    let cases: [(PathBuf, &[&str], &str); 4] = [
        (
            PathBuf::from("/dev/null/x"),
            &[],
            "cannot create the output directory",
        ),
        (file.join("sub"), &[], "cannot create the output directory"),
        (file.clone(), &[], "is a file, not a directory"),
        (file.clone(), &["--force"], "is a file, not a directory"),
    ];
    for (out, extra, want) in cases {
        let st = tumble()
            .args(["run", scene.to_str().unwrap(), "--quiet", "--out"])
            .arg(&out)
            .args(extra)
            .output()
            .unwrap();
        assert_eq!(st.status.code(), Some(2), "{}", out.display());
        let msg = String::from_utf8_lossy(&st.stderr);
        one_paragraph(&msg);
        assert!(msg.contains(want), "{msg}");
        assert!(msg.contains(out.to_str().unwrap()), "{msg}");
        assert_eq!(std::fs::read_to_string(&file).unwrap(), "keep me");
    }
    let mut after = listing(&d);
    after.retain(|f| f != "a-file");
    assert_eq!(after, before, "nothing is written");
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn full_disk_names_the_file_and_fails() {
    let d = tmp("full");
    let mnt = d.join("mnt");
    std::fs::create_dir_all(&mnt).unwrap();
    let mounted = Command::new("mount")
        .args(["-t", "tmpfs", "-o", "size=1m", "tmpfs"])
        .arg(&mnt)
        .output();
    match &mounted {
        Ok(o) if o.status.success() => {}
        Ok(o) => {
            eprintln!(
                "skipping: cannot mount a small tmpfs ({})",
                String::from_utf8_lossy(&o.stderr).trim()
            );
            return;
        }
        Err(e) => {
            eprintln!("skipping: cannot run mount: {e}");
            return;
        }
    }
    // 256x256 nodes: the snapshots (ω, u: 3 floats per node, 786 kB each before
    // compression) would not fit on the 1 MB disk: the run is refused before anything is
    // written, with the numbers.
    let huge = d.join("huge.ron");
    std::fs::write(&huge, SCENE.replace("[32, 32]", "[256, 256]")).unwrap();
    let out = mnt.join("run");
    let refused = tumble()
        .args(["run", huge.to_str().unwrap(), "--quiet", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    // 64x64 nodes fit (about 340 kB); once the run has checked the disk and made its
    // directory, the disk fills up (another program's file): the run stops at the write that
    // fails, naming its file.
    let scene = d.join("big.ron");
    std::fs::write(&scene, SCENE.replace("[32, 32]", "[64, 64]")).unwrap();
    let child = tumble()
        .args([
            "run",
            scene.to_str().unwrap(),
            "--quiet",
            "--force",
            "--out",
        ])
        .arg(mnt.join("run2"))
        .args(["--checkpoint-wall", "0"])
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let filler = mnt.join("filler");
    let start = std::time::Instant::now();
    while !mnt.join("run2").exists() && start.elapsed().as_secs() < 30 {
        std::thread::sleep(std::time::Duration::from_micros(100));
    }
    {
        use std::io::Write;
        let mut f = std::fs::File::create(&filler).unwrap();
        while f.write_all(&[0u8; 512]).is_ok() {}
    }
    let st = child.wait_with_output().unwrap();
    let _ = Command::new("umount").arg(&mnt).status();
    assert_eq!(refused.status.code(), Some(2), "{refused:?}");
    let msg = String::from_utf8_lossy(&refused.stderr);
    one_paragraph(&msg);
    assert!(
        msg.contains("would take about") && msg.contains("free on the disk of"),
        "{msg}"
    );
    assert!(!out.exists(), "the refused run made its directory");
    assert!(!st.status.success());
    // (The log's own failed writes are reported by the logger on stderr too.)
    let all = String::from_utf8_lossy(&st.stderr);
    let msg = all
        .lines()
        .find(|l| l.starts_with("error: "))
        .unwrap_or_else(|| panic!("{all}"));
    assert!(msg.contains("the disk is full writing"), "{all}");
    // It names the file it was writing, in the run directory.
    let named = msg
        .split("writing ")
        .nth(1)
        .and_then(|r| r.split_whitespace().next())
        .unwrap_or("");
    assert!(named.contains("/run2/"), "{msg}");
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn validate_write_docs_refuses_a_file_it_did_not_write() {
    let d = tmp("write-docs");
    let notes = d.join("notes.md");
    std::fs::write(&notes, "# My notes\n").unwrap();
    let st = tumble()
        .args([
            "validate",
            "lamb-oseen",
            "--write-docs",
            notes.to_str().unwrap(),
        ])
        .current_dir(&d)
        .output()
        .unwrap();
    assert_eq!(
        st.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&st.stdout)
    );
    assert!(String::from_utf8_lossy(&st.stderr).contains("refusing"));
    assert_eq!(std::fs::read_to_string(&notes).unwrap(), "# My notes\n");
    // Refused before the run: lamb-oseen, which draws a plot, did not run.
    assert!(!d.join("validation").exists());
    // A new file is written, with the cases it did not run.
    let page = d.join("page.md");
    let st = tumble()
        .args(["validate", "remesh", "--write-docs", page.to_str().unwrap()])
        .current_dir(&d)
        .output()
        .unwrap();
    assert!(
        st.status.success(),
        "{}",
        String::from_utf8_lossy(&st.stderr)
    );
    let text = std::fs::read_to_string(&page).unwrap();
    assert!(
        text.starts_with("# Validation status (full tier)"),
        "{text}"
    );
    assert!(
        text.contains("**Not run**") && text.contains("`poisson`"),
        "{text}"
    );
    std::fs::remove_dir_all(&d).unwrap();
}
