//! Output files are read back and checked, not assumed.

use std::fs;
use std::io::{self, Write};
use std::path::Path;

use tumble::base::grid::Grid;
use tumble::io::output::{
    CsvWriter, PvdSeries, VtkField, atomic_write, atomic_write_with, peak_memory_bytes, write_vti,
};

use crate::common::Scratch;
use crate::vti::read_vti;

/// This file's scratch directories.
fn scratch(test: &str) -> Scratch {
    Scratch::new("output", test)
}

/// Names of the files in `dir` that look like leftover temporaries.
fn temp_files(dir: &Path) -> Vec<String> {
    fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains(".tmp-"))
        .collect()
}

fn field(grid: &Grid, f: impl Fn([usize; 3]) -> f64) -> Vec<f64> {
    let mut v = vec![0.0; grid.len()];
    for k in 0..grid.n[2] {
        for j in 0..grid.n[1] {
            for i in 0..grid.n[0] {
                v[grid.idx(i, j, k)] = f([i, j, k]);
            }
        }
    }
    v
}

#[test]
fn vti_3d_round_trip() {
    let s = scratch("vti3d");
    let grid = Grid::new([5, 4, 3], 0.125, [-1.5, 0.25, 3.0]);
    // Values that do not survive a decimal text round trip unless written exactly.
    let p = field(&grid, |[i, j, k]| {
        (i as f64 + 0.1) * (j as f64 + 1.0 / 3.0) - k as f64
    });
    let ux = field(&grid, |[i, j, k]| (i + 10 * j + 100 * k) as f64 * 0.1);
    let uy = field(&grid, |[i, _, _]| (i as f64).sin());
    let uz = field(&grid, |[_, _, k]| -1e-300 * k as f64);
    let time = 0.1 + 0.2;
    let path = s.path().join("snap_000001.vti");
    write_vti(
        &path,
        &grid,
        time,
        &[
            VtkField {
                name: "pressure",
                components: &[&p],
            },
            VtkField {
                name: "velocity",
                components: &[&ux, &uy, &uz],
            },
        ],
    )
    .unwrap();

    let text = fs::read(&path).unwrap();
    assert!(text.starts_with(b"<?xml") || text.starts_with(b"<VTKFile"));
    let head = String::from_utf8_lossy(&text[..text.len().min(2000)]);
    for needle in [
        "<VTKFile type=\"ImageData\" version=\"1.0\" byte_order=\"LittleEndian\" \
         header_type=\"UInt64\">",
        "<ImageData WholeExtent=\"0 4 0 3 0 2\"",
        "<Piece Extent=\"0 4 0 3 0 2\">",
        "<PointData",
        "Name=\"pressure\" NumberOfComponents=\"1\" format=\"appended\" offset=\"0\"",
        "Name=\"velocity\" NumberOfComponents=\"3\" format=\"appended\"",
        "<FieldData>",
        "Name=\"TIME\"",
        "<AppendedData encoding=\"raw\">",
    ] {
        assert!(head.contains(needle), "missing {needle:?} in\n{head}");
    }
    assert!(text.ends_with(b"</AppendedData>\n</VTKFile>\n"));

    let d = read_vti(&path).unwrap();
    assert_eq!(d.whole_extent, [0, 4, 0, 3, 0, 2]);
    assert_eq!(d.origin, [-1.5, 0.25, 3.0]);
    assert_eq!(d.spacing, [0.125; 3]);
    assert_eq!(d.time, Some(time));
    assert_eq!(d.arrays.len(), 2);
    assert_eq!(d.arrays[0].0, "pressure");
    assert_eq!(d.arrays[0].1, 1);
    assert_eq!(d.arrays[0].2, p);
    assert_eq!(d.arrays[1].0, "velocity");
    assert_eq!(d.arrays[1].1, 3);
    let v = &d.arrays[1].2;
    assert_eq!(v.len(), 3 * grid.len());
    for n in 0..grid.len() {
        assert_eq!(
            [v[3 * n], v[3 * n + 1], v[3 * n + 2]],
            [ux[n], uy[n], uz[n]]
        );
    }
    // x is the fastest axis in the file: point 1 is (1, 0, 0), point 5 is (0, 1, 0).
    assert_eq!(v[3], 0.1);
    assert_eq!(v[3 * 5], 1.0);
    assert!(temp_files(s.path()).is_empty());
}

#[test]
fn vti_2d_vector_padded_with_zero_z() {
    let s = scratch("vti2d");
    let grid = Grid::new([6, 7, 1], 0.5, [1.0, -2.0, 99.0]);
    let ux = field(&grid, |[i, j, _]| i as f64 - 0.7 * j as f64);
    let uy = field(&grid, |[i, j, _]| 1.0 / (1.0 + i as f64 + j as f64));
    let w = field(&grid, |[i, j, _]| (i * j) as f64 / 7.0);
    let path = s.path().join("flow.vti");
    write_vti(
        &path,
        &grid,
        12.5,
        &[
            VtkField {
                name: "velocity",
                components: &[&ux, &uy],
            },
            VtkField {
                name: "vorticity",
                components: &[&w],
            },
        ],
    )
    .unwrap();

    let head = String::from_utf8_lossy(&fs::read(&path).unwrap()[..1000]).into_owned();
    assert!(head.contains("WholeExtent=\"0 5 0 6 0 0\""), "{head}");

    let d = read_vti(&path).unwrap();
    assert_eq!(d.whole_extent, [0, 5, 0, 6, 0, 0]);
    assert_eq!(d.origin, [1.0, -2.0, 0.0]);
    assert_eq!(d.spacing, [0.5; 3]);
    assert_eq!(d.time, Some(12.5));
    assert_eq!(d.arrays.len(), 2);
    let (name, nc, v) = &d.arrays[0];
    assert_eq!((name.as_str(), *nc), ("velocity", 3));
    assert_eq!(v.len(), 3 * grid.len());
    for n in 0..grid.len() {
        assert_eq!([v[3 * n], v[3 * n + 1], v[3 * n + 2]], [ux[n], uy[n], 0.0]);
    }
    assert_eq!(d.arrays[1], ("vorticity".to_string(), 1, w));
}

#[test]
fn vti_rejects_bad_fields() {
    let s = scratch("vtibad");
    let grid = Grid::new([3, 3, 1], 1.0, [0.0; 3]);
    let short = vec![0.0; 8];
    let path = s.path().join("bad.vti");
    let err = write_vti(
        &path,
        &grid,
        0.0,
        &[VtkField {
            name: "x",
            components: &[&short],
        }],
    )
    .unwrap_err();
    assert_eq!(err.kind(), io::ErrorKind::InvalidInput);
    let err = write_vti(
        &path,
        &grid,
        0.0,
        &[VtkField {
            name: "x",
            components: &[],
        }],
    )
    .unwrap_err();
    assert_eq!(err.kind(), io::ErrorKind::InvalidInput);
    assert!(!path.exists());
    assert!(temp_files(s.path()).is_empty());
}

#[test]
fn pvd_series_lists_pushed_snapshots() {
    let s = scratch("pvd");
    let pvd_path = s.path().join("run.pvd");
    let mut pvd = PvdSeries::new(&pvd_path);
    let times = [0.0, 0.1 + 0.2, 1.0 / 3.0];
    let files = ["snap_000000.vti", "snap_000001.vti", "snap_000002.vti"];
    for (n, (&t, f)) in times.iter().zip(files).enumerate() {
        pvd.push(t, f).unwrap();
        // After every push the file is complete and lists exactly the pushed entries.
        let text = fs::read_to_string(&pvd_path).unwrap();
        assert_eq!(text.matches("<DataSet").count(), n + 1);
        assert!(text.trim_end().ends_with("</VTKFile>"));
    }
    assert_eq!(pvd.entries().len(), 3);
    assert_eq!(pvd.path(), pvd_path.as_path());

    let text = fs::read_to_string(&pvd_path).unwrap();
    assert!(text.starts_with("<?xml") || text.starts_with("<VTKFile"));
    assert!(text.contains("<VTKFile type=\"Collection\""));
    assert!(text.contains("<Collection>") && text.contains("</Collection>"));
    let datasets: Vec<&str> = text
        .lines()
        .map(str::trim)
        .filter(|l| l.starts_with("<DataSet"))
        .collect();
    assert_eq!(datasets.len(), 3);
    let attr = |line: &str, key: &str| -> String {
        let pat = format!(" {key}=\"");
        let start = line.find(&pat).unwrap() + pat.len();
        let end = start + line[start..].find('"').unwrap();
        line[start..end].to_string()
    };
    for (line, (&t, f)) in datasets.iter().zip(times.iter().zip(files)) {
        assert_eq!(attr(line, "timestep").parse::<f64>().unwrap(), t);
        assert_eq!(attr(line, "file"), f);
        assert_eq!(attr(line, "part"), "0");
    }
    assert!(temp_files(s.path()).is_empty());
}

#[test]
fn atomic_write_replaces_and_failure_keeps_old() {
    let s = scratch("atomic");
    let path = s.path().join("state.json");
    fs::write(&path, b"old contents").unwrap();

    atomic_write(&path, b"new contents").unwrap();
    assert_eq!(fs::read(&path).unwrap(), b"new contents");
    assert!(temp_files(s.path()).is_empty());

    let err = atomic_write_with(&path, |w| {
        w.write_all(b"partial garbage that must never appear")?;
        Err(io::Error::other("writer failed"))
    })
    .unwrap_err();
    assert_eq!(err.to_string(), "writer failed");
    assert_eq!(fs::read(&path).unwrap(), b"new contents");
    assert!(temp_files(s.path()).is_empty());

    // Streaming writes create a file that did not exist.
    let fresh = s.path().join("fresh.bin");
    atomic_write_with(&fresh, |w| {
        for i in 0u32..1000 {
            w.write_all(&i.to_le_bytes())?;
        }
        Ok(())
    })
    .unwrap();
    assert_eq!(fs::read(&fresh).unwrap().len(), 4000);
    assert!(temp_files(s.path()).is_empty());

    // A path in a missing directory fails without side effects.
    assert!(atomic_write(&s.path().join("no/such/dir/x"), b"x").is_err());
}

#[test]
fn csv_round_trip() {
    let s = scratch("csv");
    let path = s.path().join("series.csv");
    let header = ["time", "energy", "enstrophy"];
    let rows = [
        [0.0, 1.0 / 3.0, -2.5e-17],
        [0.1 + 0.2, 1e300, 6.02214076e23],
        [f64::MIN_POSITIVE, -0.0, 123_456_789.123_456_79 / 7.0],
    ];
    let mut csv = CsvWriter::create(&path, &header).unwrap();
    for r in &rows {
        csv.row(r).unwrap();
    }
    // Rows are flushed as written: readable before the writer is dropped.
    assert_eq!(fs::read_to_string(&path).unwrap().lines().count(), 4);
    assert_eq!(
        csv.row(&[1.0]).unwrap_err().kind(),
        io::ErrorKind::InvalidInput
    );
    csv.flush().unwrap();
    drop(csv);

    let text = fs::read_to_string(&path).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next().unwrap(), "time,energy,enstrophy");
    let parsed: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse::<f64>().unwrap()).collect())
        .collect();
    assert_eq!(parsed.len(), rows.len());
    for (p, r) in parsed.iter().zip(&rows) {
        assert_eq!(p.len(), 3);
        for (a, b) in p.iter().zip(r) {
            assert_eq!(a.to_bits(), b.to_bits());
        }
    }
}

#[test]
fn peak_memory_is_reported_on_linux() {
    let m = peak_memory_bytes();
    if cfg!(target_os = "linux") {
        let m = m.expect("VmHWM should be readable on Linux");
        assert!(m > 1024 * 1024, "peak RSS {m} bytes is implausibly small");
    }
}

/// Two runs in one thread, one after the other, and one in another thread at the same time:
/// each writes its own log.txt (a scoped tracing subscriber per run, nothing global).
#[test]
fn each_run_logs_to_its_own_log_txt() {
    use tumble::run::{RunOptions, run_scene};
    let base = std::env::temp_dir().join(format!("tumble-log-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&base);
    let scene = |name: &str| {
        tumble::scene::Scene::parse(
            &format!(
                r#"Scene(
    name: "{name}",
    domain: (extent: [1.0, 1.0], cells: [16, 16]),
    numerics: (end_time: 0.05),
    initial: [LambOseen(center: [0.5, 0.5], circulation: 1.0, core_radius: 0.1)],
    bodies: [(name: "disk", shape: Disk(radius: 0.1), position: [0.5, 0.7])],
)"#
            ),
            "log.ron",
            name,
        )
        .unwrap()
    };
    let run = |name: &str| {
        let opts = RunOptions {
            out: Some(base.join(name)),
            quiet: true,
            ..Default::default()
        };
        run_scene(scene(name), &opts).unwrap();
        std::fs::read_to_string(base.join(name).join("log.txt")).unwrap()
    };
    let other = std::thread::scope(|s| {
        let h = s.spawn(|| run("third"));
        for name in ["first", "second"] {
            let log = run(name);
            assert!(log.contains(&format!("run of scene `{name}`")), "{log}");
            assert_eq!(log.matches("run of scene").count(), 1, "{log}");
            assert!(log.contains("scene: 1 bodies (1 dynamic"), "{log}");
            assert!(log.contains("output: step 0, t = 0.000000"), "{log}");
            assert!(log.contains("fastest body `disk`"), "{log}");
            assert!(log.contains("finished: "), "{log}");
            assert!(log.contains("timings over"), "{log}");
            assert!(log.contains("transport"), "{log}");
            assert!(!log.contains('\x1b'), "no ANSI escapes: {log}");
        }
        h.join().unwrap()
    });
    assert!(other.contains("run of scene `third`"), "{other}");
    assert_eq!(other.matches("run of scene").count(), 1, "{other}");
    assert!(base.join("first/timings.csv").exists());
    let _ = std::fs::remove_dir_all(&base);
}

/// Body names with a comma and a quote are quoted in bodies.csv and contacts.csv as RFC 4180
/// says, so a CSV reader gets them back whole. The run is the paper's disk dropped in vacuum
/// (Fig. 1): before it touches the floor it falls freely, y = 0.3 - t^2/2 (g = 1).
#[test]
fn body_names_with_commas_and_quotes_round_trip_through_the_csvs() {
    use tumble::run::{BODIES_HEADER, CONTACTS_HEADER, RunOptions, run_scene};
    let dir = scratch("csv-names");
    let (floor, disk) = (r#"floor, "west""#, r#"disk "a", b"#);
    let scene = tumble::scene::Scene::parse(
        r#"Scene(
    name: "csv-names",
    domain: (origin: [0.0, -0.0625], extent: [0.5, 0.5], h: 0.0078125),
    fluid: (gravity: [0.0, -1.0]),
    vacuum: true,
    contact: (kappa: 1.0),
    numerics: (dt: Fixed(0.00078125), end_time: 0.6),
    bodies: [
        (name: "floor, \"west\"", shape: HalfSpace(normal: [0.0, 1.0, 0.0], offset: 0.0),
         kind: Static, position: [0.25, 0.0]),
        (name: "disk \"a\", b", shape: Disk(radius: 0.1), position: [0.25, 0.3]),
    ],
    output: (every: 0.6, fields: []),
)"#,
        "csv-names.ron",
        "",
    )
    .unwrap();
    let out = dir.path().join("run");
    let opts = RunOptions {
        out: Some(out.clone()),
        quiet: true,
        ..Default::default()
    };
    run_scene(scene, &opts).unwrap();

    let text = fs::read_to_string(out.join("bodies.csv")).unwrap();
    assert!(text.contains(r#","disk ""a"", b","#), "{text}");
    let mut r = csv::Reader::from_path(out.join("bodies.csv")).unwrap();
    let header: Vec<String> = r.headers().unwrap().iter().map(String::from).collect();
    assert_eq!(header.join(","), BODIES_HEADER);
    let rows: Vec<csv::StringRecord> = r.records().map(Result::unwrap).collect();
    assert!(rows.len() > 700, "{} rows", rows.len());
    let mut checked = 0;
    for row in &rows {
        assert_eq!(row.len(), header.len(), "{row:?}");
        assert_eq!(&row[2], disk);
        let t: f64 = row[0].parse().unwrap();
        let y: f64 = row[4].parse().unwrap();
        if t <= 0.5 {
            assert!((y - (0.3 - 0.5 * t * t)).abs() < 1e-3, "t = {t}: y = {y}");
            checked += 1;
        }
    }
    assert!(checked > 600, "{checked} rows in free fall");

    let text = fs::read_to_string(out.join("contacts.csv")).unwrap();
    assert!(
        text.contains(r#","floor, ""west""","disk ""a"", b","#),
        "{text}"
    );
    let mut r = csv::Reader::from_path(out.join("contacts.csv")).unwrap();
    let header: Vec<String> = r.headers().unwrap().iter().map(String::from).collect();
    assert_eq!(header.join(","), CONTACTS_HEADER);
    let rows: Vec<csv::StringRecord> = r.records().map(Result::unwrap).collect();
    assert!(
        !rows.is_empty(),
        "the disk comes close to the floor before t = 0.6"
    );
    for row in &rows {
        assert_eq!(row.len(), 5, "{row:?}");
        assert_eq!((&row[1], &row[2]), (floor, disk));
    }
}

/// The t = 0 snapshot holds the bodies as they start: χ = Σ H_ε(φ_i) integrates (sum times
/// cell volume) to the bodies' volume, and φ is finite everywhere (never a sentinel).
///
/// Tolerance, relative: (h / r_min)², O(h²) as the errors are. With the cosine-smoothed
/// Heaviside of half-width ε = h, H(s) - step(s) is odd in s, so the smoothing shifts the
/// volume by exactly -2π ∫ s (H - step) ds = 0.41 ε² per disk and 8π r (0.065 ε²) per
/// sphere: 0.13 (ε/r)² and 0.49 (ε/r)² relative. The trilinear interpolation of the
/// reference distance and the lattice sum of χ (its transition spans about two cells) add
/// O(h²) of either sign. A body missing from the snapshot (at least 30% of the volume here)
/// or an unsmoothed, shifted χ fails.
#[test]
fn the_first_snapshot_holds_the_bodies_and_a_finite_phi() {
    use std::f64::consts::PI;
    use tumble::run::{RunOptions, run_scene};
    let dir = scratch("t0-bodies");
    let cases = [
        (
            r#"Scene(
    name: "t0-disks",
    domain: (extent: [1.0, 1.0], cells: [64, 64]),
    fluid: (gravity: [0.0, -1.0]),
    numerics: (dt: Fixed(0.001), end_time: 0.001),
    bodies: [
        (name: "a", shape: Disk(radius: 0.1), density: 2.0, position: [0.3, 0.4]),
        (name: "b", shape: Disk(radius: 0.15), density: 0.5, position: [0.65, 0.6],
         rotation: [0.4]),
    ],
    output: (fields: [Density]),
)"#,
            vec![0.1, 0.15],
            2,
        ),
        (
            r#"Scene(
    name: "t0-spheres",
    domain: (extent: [1.0, 1.0, 1.0], cells: [32, 32, 32]),
    fluid: (gravity: [0.0, 0.0, -1.0]),
    numerics: (dt: Fixed(0.001), end_time: 0.001),
    bodies: [
        (name: "a", shape: Sphere(radius: 0.15), density: 2.0, position: [0.3, 0.4, 0.5]),
        (name: "b", shape: Sphere(radius: 0.2), density: 3.0, position: [0.7, 0.6, 0.5]),
    ],
    output: (fields: [Density]),
)"#,
            vec![0.15, 0.2],
            3,
        ),
    ];
    for (text, radii, dim) in cases {
        let scene = tumble::scene::Scene::parse(text, "t0.ron", "").unwrap();
        let out = dir.path().join(scene.name.clone());
        let h: f64 = 1.0 / if dim == 2 { 64.0 } else { 32.0 };
        let opts = RunOptions {
            out: Some(out.clone()),
            quiet: true,
            ..Default::default()
        };
        run_scene(scene, &opts).unwrap();
        let snap = read_vti(&out.join("fields_000000.vti")).unwrap();
        assert_eq!(snap.time, Some(0.0));
        let field = |name: &str| {
            &snap
                .arrays
                .iter()
                .find(|a| a.0 == name)
                .unwrap_or_else(|| panic!("no {name}"))
                .2
        };
        let cell = h.powi(dim);
        let chi: f64 = field("chi").iter().sum::<f64>() * cell;
        let exact: f64 = if dim == 2 {
            radii.iter().map(|r| PI * r * r).sum()
        } else {
            radii.iter().map(|r| 4.0 / 3.0 * PI * r * r * r).sum()
        };
        let r_min = radii.iter().cloned().fold(f64::INFINITY, f64::min);
        assert!(
            (chi / exact - 1.0).abs() < (h / r_min).powi(2),
            "{dim}D: chi integrates to {chi}, the bodies' volume is {exact}"
        );
        let phi = field("phi");
        assert!(phi.iter().all(|p| p.is_finite() && *p >= -6.0 * h - 1e-12));
        assert!(phi.iter().any(|p| *p > 0.0));
        // Far from both bodies (a corner), φ is the band's edge, -6 h.
        assert_eq!(phi[0], -6.0 * h);
    }
}
