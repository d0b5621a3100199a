//! PNG plots: `line_chart`, `plot_run_dir` and `tumble plot`.

use crate::common::Scratch;
use std::path::{Path, PathBuf};
use std::process::Command;
use tumble::io::plot::{
    RunInfo, Series, Style, axis_label, body_energy, chart_title, gap_series, line_chart,
    plot_run_dir, unit_text,
};
use tumble::scene::Units;

/// A fresh, empty directory under the system temp dir, unique to this process and `name`.
fn tmp(name: &str) -> Scratch {
    Scratch::new("plot", name)
}

/// Checks the PNG signature and that the IHDR chunk says 900x600.
fn assert_png_900x600(path: &Path) {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert!(bytes.len() > 33, "{}: too short", path.display());
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "{}", path.display());
    assert_eq!(&bytes[12..16], b"IHDR", "{}", path.display());
    let w = u32::from_be_bytes(bytes[16..20].try_into().unwrap());
    let h = u32::from_be_bytes(bytes[20..24].try_into().unwrap());
    assert_eq!((w, h), (900, 600), "{}", path.display());
}

/// Names of the files in `dir`, sorted.
fn files(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn line_chart_writes_a_900x600_png_and_no_temp_file() {
    let d = tmp("chart");
    let path = d.join("chart.png");
    let measured: Vec<(f64, f64)> = (0..100)
        .map(|i| {
            let t = i as f64 * 0.05;
            (t, (-t).exp())
        })
        .collect();
    let reference = vec![(0.0, 1.0), (1.0, (-1f64).exp()), (2.0, (-2f64).exp())];
    line_chart(
        &path,
        "Decay",
        "t",
        "energy",
        &[
            Series {
                label: "measured",
                points: measured,
                style: Style::Line,
            },
            Series {
                label: "paper",
                points: reference,
                style: Style::Markers,
            },
            Series {
                label: "analytic, broken by a NaN and an isolated point",
                points: vec![
                    (0.0, 1.0),
                    (2.5, (-2.5f64).exp()),
                    (3.0, f64::NAN),
                    (3.5, 0.05),
                    (4.0, f64::INFINITY),
                    (4.5, 0.02),
                    (5.0, (-5f64).exp()),
                ],
                style: Style::Dashed,
            },
        ],
    )
    .unwrap();
    assert_png_900x600(&path);
    assert_eq!(files(&d), ["chart.png"]);

    // Overwriting an existing chart works too.
    line_chart(
        &path,
        "Again",
        "x",
        "y",
        &[Series {
            label: "one",
            points: vec![(0.0, 0.0), (1.0, 1.0)],
            style: Style::Line,
        }],
    )
    .unwrap();
    assert_png_900x600(&path);
    assert_eq!(files(&d), ["chart.png"]);
}

#[test]
fn line_chart_handles_degenerate_data() {
    let d = tmp("degenerate");
    let cases: Vec<(&str, Vec<Series>)> = vec![
        (
            "constant.png",
            vec![Series {
                label: "c",
                points: vec![(0.0, 3.0), (1.0, 3.0), (2.0, 3.0)],
                style: Style::Line,
            }],
        ),
        (
            "zero.png",
            vec![Series {
                label: "z",
                points: vec![(0.0, 0.0)],
                style: Style::Markers,
            }],
        ),
        (
            "gaps.png",
            vec![
                Series {
                    label: "with NaN and inf",
                    points: vec![
                        (0.0, 1.0),
                        (0.5, 1.2),
                        (1.0, f64::NAN),
                        (1.5, 1.8),
                        (2.0, 2.0),
                        (f64::INFINITY, 5.0),
                        (3.0, 1.5),
                    ],
                    style: Style::Line,
                },
                Series {
                    label: "empty",
                    points: vec![],
                    style: Style::Line,
                },
                Series {
                    label: "reference",
                    points: vec![(0.0, 1.1), (2.5, f64::NAN), (3.0, 1.6)],
                    style: Style::Markers,
                },
            ],
        ),
        (
            "tiny_and_huge.png",
            vec![Series {
                label: "s",
                points: vec![(1e-9, 1e12), (2e-9, 3e12), (3e-9, -1e12)],
                style: Style::Line,
            }],
        ),
        (
            "nearly_constant.png",
            vec![Series {
                label: "s",
                points: vec![(0.0, 1.0), (1.0, 1.0 + 1e-15)],
                style: Style::Line,
            }],
        ),
        (
            "widest.png",
            vec![Series {
                label: "s",
                points: vec![(-1e300, 1e300), (1e300, -1e300), (0.0, f64::MAX)],
                style: Style::Line,
            }],
        ),
        (
            "subnormal.png",
            vec![Series {
                label: "s",
                points: vec![(0.0, 1e-310), (1e-310, 1e-310), (2e-310, 3e-310)],
                style: Style::Markers,
            }],
        ),
        (
            "offset.png",
            vec![Series {
                label: "s",
                points: vec![(1e15, 1e15), (1e15 + 1.0, 1e15 + 2.0), (1e15 + 3.0, 1e15)],
                style: Style::Line,
            }],
        ),
    ];
    for (name, series) in &cases {
        let path = d.join(name);
        line_chart(&path, name, "x", "y", series).unwrap_or_else(|e| panic!("{name}: {e:#}"));
        assert_png_900x600(&path);
    }
    // Nothing plottable: an error, and nothing written.
    let path = d.join("nothing.png");
    let err = line_chart(
        &path,
        "nothing",
        "x",
        "y",
        &[Series {
            label: "nan",
            points: vec![(0.0, f64::NAN), (f64::NAN, 1.0), (f64::MAX, 0.0)],
            style: Style::Line,
        }],
    )
    .unwrap_err();
    assert!(format!("{err:#}").contains("nothing to plot"), "{err:#}");
    assert!(line_chart(&path, "none", "x", "y", &[]).is_err());
    assert!(!path.exists());
    // Not a .png name.
    assert!(
        line_chart(
            &d.join("chart.svg"),
            "t",
            "x",
            "y",
            &[Series {
                label: "s",
                points: vec![(0.0, 1.0)],
                style: Style::Line,
            }],
        )
        .is_err()
    );
    assert!(
        !files(&d).iter().any(|f| f.starts_with('.')),
        "{:?}",
        files(&d)
    );
}

const SERIES: &str = "t,dt,energy,enstrophy,circulation,max_omega
0,0.01,1.0,5.0,0,2.0
0.01,0.01,0.99,4.9,0,1.9
0.02,0.01,0.98,4.8,0,1.8
";

/// A synthetic run directory: series.csv, bodies.csv with `bodies` 2D bodies (columns in a
/// shuffled order, to check lookup by name), contacts.csv.
fn run_dir(name: &str, bodies: usize) -> Scratch {
    let d = tmp(name);
    std::fs::write(d.join("series.csv"), SERIES).unwrap();
    let cols = [
        "t", "id", "name", "x", "y", "z", "vx", "vy", "vz", "wx", "wy", "wz", "qw", "qx", "qy",
        "qz", "fx", "fy", "fz", "tx", "ty", "tz",
    ];
    let mut order: Vec<&str> = cols.to_vec();
    order.reverse();
    let mut s = order.join(",") + "\n";
    for step in 0..5 {
        let t = step as f64 * 0.1;
        for b in 0..bodies {
            let row: Vec<String> = order
                .iter()
                .map(|c| match *c {
                    "t" => t.to_string(),
                    "id" => b.to_string(),
                    "name" => format!("body{b}"),
                    "y" => (1.0 - t * t - 0.01 * b as f64).to_string(),
                    "vy" => (-2.0 * t).to_string(),
                    "qw" => "1".to_string(),
                    _ => "0".to_string(),
                })
                .collect();
            s += &(row.join(",") + "\n");
        }
    }
    std::fs::write(d.join("bodies.csv"), s).unwrap();
    std::fs::write(
        d.join("contacts.csv"),
        "t,body_a,body_b,gap,normal_force\n\
         0,body0,floor,0.1,0\n0,body0,body1,0.05,0\n\
         0.1,body0,floor,0.05,1\n0.1,body1,body0,0.02,0\n\
         0.2,body0,floor,0,2\n0.2,body0,body1,-0.001,3\n",
    )
    .unwrap();
    d
}

const PLOTS: [&str; 5] = [
    "energy.png",
    "enstrophy.png",
    "bodies_height.png",
    "bodies_velocity.png",
    "contacts_gap.png",
];

#[test]
fn plot_run_dir_writes_the_plots() {
    let d = run_dir("run", 3);
    let written = plot_run_dir(&d).unwrap();
    let expect: Vec<PathBuf> = PLOTS.iter().map(|f| d.join(f)).collect();
    assert_eq!(written, expect);
    for p in &written {
        assert_png_900x600(p);
    }
    assert!(!files(&d).iter().any(|f| f.starts_with('.')));

    // Many bodies: still works (only the first 8 are drawn); 3D (z moves) works too.
    let d = run_dir("many", 20);
    assert_eq!(plot_run_dir(&d).unwrap().len(), 5);
    let d = tmp("three-d");
    std::fs::write(d.join("series.csv"), SERIES).unwrap();
    std::fs::write(
        d.join("bodies.csv"),
        "t,id,name,x,y,z,vx,vy,vz,wx,wy,wz,qw,qx,qy,qz,fx,fy,fz,tx,ty,tz\n\
         0,0,ball,0,0,1,0,0,0,0,0,0,1,0,0,0,0,0,0,0,0,0\n\
         0.1,0,ball,0,0,0.9,0,0,-1,0,0,0,1,0,0,0,0,0,0,0,0,0\n",
    )
    .unwrap();
    assert_eq!(plot_run_dir(&d).unwrap().len(), 4);

    // Only series.csv; and header-only bodies/contacts files are skipped.
    let d = tmp("series-only");
    std::fs::write(d.join("series.csv"), SERIES).unwrap();
    assert_eq!(plot_run_dir(&d).unwrap().len(), 2);
    std::fs::write(
        d.join("bodies.csv"),
        "t,id,name,x,y,z,vx,vy,vz,wx,wy,wz,qw,qx,qy,qz,fx,fy,fz,tx,ty,tz\n",
    )
    .unwrap();
    std::fs::write(d.join("contacts.csv"), "t,body_a,body_b,gap,normal_force\n").unwrap();
    assert_eq!(plot_run_dir(&d).unwrap().len(), 2);
}

#[test]
fn plot_run_dir_errors_name_the_file() {
    // Missing series.csv.
    let d = tmp("empty");
    let err = format!("{:#}", plot_run_dir(&d).unwrap_err());
    assert!(err.contains("not a run directory"), "{err}");
    assert!(err.contains("series.csv"), "{err}");

    // A row with too few fields: file and line.
    let d = run_dir("short-row", 2);
    std::fs::write(
        d.join("series.csv"),
        "t,dt,energy,enstrophy,circulation,max_omega\n0,0.01,1,5,0,2\n0.01,0.01,1\n",
    )
    .unwrap();
    let err = format!("{:#}", plot_run_dir(&d).unwrap_err());
    assert!(err.contains("series.csv:3"), "{err}");

    // A field that is not a number, in bodies.csv.
    let d = run_dir("bad-number", 2);
    std::fs::write(
        d.join("bodies.csv"),
        "t,id,name,x,y,z,vx,vy,vz,wx,wy,wz,qw,qx,qy,qz,fx,fy,fz,tx,ty,tz\n\
         0,0,ball,0,1,0,0,0,0,0,0,0,1,0,0,0,0,0,0,0,0,0\n\
         0.1,0,ball,0,zero,0,0,0,0,0,0,0,1,0,0,0,0,0,0,0,0,0\n",
    )
    .unwrap();
    let err = format!("{:#}", plot_run_dir(&d).unwrap_err());
    assert!(err.contains("bodies.csv:3"), "{err}");
    assert!(err.contains("zero"), "{err}");

    // A name with a comma left unquoted (a hand-edited file): one field too many, file and
    // line; the quoted name on the line before reads as one field.
    let d = run_dir("unquoted-name", 2);
    std::fs::write(
        d.join("bodies.csv"),
        "t,id,name,x,y,z,vx,vy,vz,wx,wy,wz,qw,qx,qy,qz,fx,fy,fz,tx,ty,tz\n\
         0,0,\"ball,red\",0,1,0,0,0,0,0,0,0,1,0,0,0,0,0,0,0,0,0\n\
         0.1,0,ball,red,0,1,0,0,0,0,0,0,0,1,0,0,0,0,0,0,0,0,0\n",
    )
    .unwrap();
    let err = format!("{:#}", plot_run_dir(&d).unwrap_err());
    assert!(
        err.contains("bodies.csv:3: malformed row: 23 fields, the header has 22"),
        "{err}"
    );

    // A missing column in contacts.csv.
    let d = run_dir("no-gap", 2);
    std::fs::write(d.join("contacts.csv"), "t,body_a,body_b\n0,a,b\n").unwrap();
    let err = format!("{:#}", plot_run_dir(&d).unwrap_err());
    assert!(err.contains("contacts.csv"), "{err}");
    assert!(err.contains("`gap`"), "{err}");
}

#[test]
fn cli_plot_writes_and_prints_the_paths() {
    let d = run_dir("cli", 2);
    let out = Command::new(env!("CARGO_BIN_EXE_tumble"))
        .args(["plot", d.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    for f in PLOTS {
        assert!(stdout.contains(f), "{f} not printed: {stdout}");
        assert_png_900x600(&d.join(f));
    }

    let empty = tmp("cli-empty");
    let out = Command::new(env!("CARGO_BIN_EXE_tumble"))
        .args(["plot", empty.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("no series.csv"), "{stderr}");
}

#[test]
fn titles_name_the_scene_and_labels_carry_its_units() {
    assert!(chart_title("Contact gap", "rebound-vacuum").contains("rebound-vacuum"));
    assert!(chart_title("Contact gap", "rebound-vacuum").contains("Contact gap"));
    let cgs = Units {
        length: Some("cm".into()),
        time: Some("s".into()),
        mass: Some("g".into()),
    };
    let u = Some(&cgs);
    assert_eq!(axis_label("t", u, 0, 1, 0), "t [s]");
    assert_eq!(axis_label("height z", u, 1, 0, 0), "height z [cm]");
    assert_eq!(axis_label("velocity vz", u, 1, -1, 0), "velocity vz [cm/s]");
    assert_eq!(
        axis_label("energy", u, 2, -2, 1),
        "energy [g cm\u{b2}/s\u{b2}]"
    );
    assert_eq!(unit_text(u, 0, -2, 0), "[1/s\u{b2}]");
    assert_eq!(unit_text(u, -3, 0, 1), "[g/cm\u{b3}]");
    assert_eq!(axis_label("Re", u, 0, 0, 0), "Re");
    // No units note, or one without the unit a label needs: "(scene units)".
    assert_eq!(axis_label("t", None, 0, 1, 0), "t (scene units)");
    let no_mass = Units {
        mass: None,
        ..cgs.clone()
    };
    assert_eq!(axis_label("t", Some(&no_mass), 0, 1, 0), "t [s]");
    assert_eq!(
        axis_label("energy", Some(&no_mass), 2, -2, 1),
        "energy (scene units)"
    );
}

/// A 2D scene.ron matching the bodies of [`run_dir`] (`floor`, `body0`, `body1`).
const SCENE_2D: &str = r#"Scene(
    name: "two-disks",
    domain: (extent: [1.0, 1.0], h: 0.0625),
    fluid: (gravity: [0.0, -1.0]),
    vacuum: true,
    contact: (eps: 0.02),
    output: (fields: [], units: (length: "cm", time: "s")),
    bodies: [
        (name: "floor", shape: HalfSpace(normal: [0.0, 1.0, 0.0], offset: 0.0), kind: Static,
         position: [0.5, 0.1]),
        (name: "body0", shape: Disk(radius: 0.1), position: [0.3, 0.5]),
        (name: "body1", shape: Disk(radius: 0.1), position: [0.7, 0.5]),
    ],
)"#;

#[test]
fn gap_plot_names_the_pairs_and_draws_eps() {
    let d = run_dir("gap-names", 2);
    std::fs::write(d.join("scene.ron"), SCENE_2D).unwrap();
    // Entries given as body ids are named from the scene (0 = floor, 2 = body1).
    std::fs::write(
        d.join("contacts.csv"),
        "t,body_a,body_b,gap,normal_force\n\
         0,body0,floor,0.1,0\n0,1,2,0.05,0\n\
         0.1,body0,0,0.05,1\n0.1,body1,body0,0.02,0\n\
         0.3,body0,floor,0,2\n",
    )
    .unwrap();
    let series = gap_series(&d).unwrap();
    let labels: Vec<&str> = series.iter().map(|s| s.label.as_str()).collect();
    assert_eq!(
        labels[..2],
        ["body0\u{2013}floor", "body0\u{2013}body1"],
        "{labels:?}"
    );
    assert_eq!(series[0].points, [(0.0, 0.1), (0.1, 0.05), (0.3, 0.0)]);
    assert_eq!(series[1].points, [(0.0, 0.05), (0.1, 0.02)]);
    let eps = series.last().unwrap();
    assert_eq!(series.len(), 3);
    assert!(
        eps.label.contains("ε") && eps.label.contains("0.02"),
        "{}",
        eps.label
    );
    assert_eq!(eps.style, Style::Dashed);
    // A horizontal line at ε = contact.eps over the contacts' time span.
    assert_eq!(eps.points, [(0.0, 0.02), (0.3, 0.02)]);

    // Without contact.eps, ε is the grid spacing h.
    let scene = SCENE_2D.replace("contact: (eps: 0.02),", "");
    std::fs::write(d.join("scene.ron"), scene).unwrap();
    let series = gap_series(&d).unwrap();
    assert_eq!(series.last().unwrap().points[0].1, 0.0625);

    let info = RunInfo::read(&d).unwrap();
    assert_eq!(info.name, "two-disks");
    assert_eq!(info.units.as_ref().unwrap().length.as_deref(), Some("cm"));
    assert!(
        plot_run_dir(&d)
            .unwrap()
            .contains(&d.join("contacts_gap.png"))
    );

    // No scene.ron (an older run directory): the pairs as written (ids stay ids), no ε line.
    std::fs::remove_file(d.join("scene.ron")).unwrap();
    let series = gap_series(&d).unwrap();
    assert_eq!(series.len(), 4);
    assert!(series.iter().all(|s| !s.label.contains("ε")));
    assert_eq!(series[1].label, "1\u{2013}2");
}

#[test]
fn vacuum_free_fall_energy_is_analytic_and_conserved() {
    use tumble::run::{RunOptions, run_scene};
    // A sphere falling freely in vacuum (no other body, so no contact): V(t) = g t, so the
    // kinetic energy is ½ m (g t)² and, with the potential energy -m g·x, the total is
    // constant.
    let (r, rho, g, dt, end): (f64, f64, f64, f64, f64) = (0.15, 2.0, 1.0, 0.01, 0.3);
    let text = format!(
        r#"Scene(
        name: "free-fall",
        domain: (extent: [1.0, 1.0, 1.0], h: 0.0625),
        fluid: (gravity: [0.0, 0.0, -{g}]),
        vacuum: true,
        numerics: (dt: Fixed({dt}), end_time: {end}),
        output: (fields: [], units: (length: "m", time: "s", mass: "kg")),
        bodies: [(name: "ball", shape: Sphere(radius: {r}), density: {rho},
                  position: [0.5, 0.5, 0.7])],
    )"#
    );
    let scene = tumble::scene::Scene::parse(&text, "free-fall.ron", "free-fall").unwrap();
    let scratch = tmp("free-fall");
    let d = scratch.join("run");
    let opts = RunOptions {
        out: Some(d.clone()),
        quiet: true,
        ..Default::default()
    };
    run_scene(scene, &opts).unwrap();
    let info = RunInfo::read(&d).unwrap();
    assert!(info.vacuum);
    assert_eq!(info.name, "free-fall");
    // The units note survives into the run directory's scene.ron.
    assert_eq!(info.units.as_ref().unwrap().mass.as_deref(), Some("kg"));
    let e = body_energy(&d, &info).unwrap().expect("the ball's energy");
    let m = rho * 4.0 / 3.0 * std::f64::consts::PI * r.powi(3);
    assert!(e.t.len() >= 30, "{} rows", e.t.len());
    assert!((e.t.last().unwrap() - end).abs() < 1e-9);
    let total = e.total();
    for ((&t, &k), &tot) in e.t.iter().zip(&e.kinetic).zip(&total) {
        // Gravity alone: the velocity update V += g Δt is exact, so is the kinetic energy.
        let exact = 0.5 * m * (g * t).powi(2);
        assert!(
            (k - exact).abs() <= 1e-9 * m + 1e-9 * exact,
            "t = {t}: kinetic {k}, ½ m (g t)² = {exact}"
        );
        // The time integration (symplectic Euler) moves the body with the new velocity:
        // x_n = x_0 + g Δt² n(n+1)/2, so E_n - E_0 = -½ m g² Δt t_n exactly; allow that drift
        // (3 % of the kinetic energy at t = 0.3), plus rounding.
        let drift = 0.5 * m * g * g * dt * t;
        assert!(
            (tot - total[0]).abs() <= drift * (1.0 + 1e-6) + 1e-12,
            "t = {t}: total energy {tot}, at t = 0 {}: drift beyond ½ m g² Δt t = {drift}",
            total[0]
        );
    }
    // The energy plot of a vacuum run is the bodies' energy; no flat enstrophy plot.
    let written = plot_run_dir(&d).unwrap();
    assert!(written.contains(&d.join("energy.png")), "{written:?}");
    assert!(!written.contains(&d.join("enstrophy.png")), "{written:?}");
    assert_png_900x600(&d.join("energy.png"));
}

#[test]
fn a_blank_unit_name_is_a_scene_error_naming_the_field() {
    let text = SCENE_2D.replace(r#"length: "cm""#, r#"length: " ""#);
    let e = tumble::scene::Scene::parse(&text, "units.ron", "units").unwrap_err();
    assert_eq!(e.field.as_deref(), Some("output.units.length"), "{e}");
    let text = SCENE_2D.replace(r#"length: "cm""#, r#"lenght: "cm""#);
    assert!(tumble::scene::Scene::parse(&text, "units.ron", "units").is_err());
}

/// A body named with a comma, a double quote and a non-ASCII letter runs through `tumble run`,
/// its name is quoted in `bodies.csv` and `contacts.csv` (the numbers are not) and read back
/// whole by a CSV reader, and `tumble plot` draws it: the bodies' and the contact gap's plots,
/// the gap labelled with both names.
#[test]
fn a_body_named_with_a_comma_a_quote_and_an_accent_runs_and_is_plotted() {
    let d = tmp("odd-name");
    let (floor, ball) = ("floor", r#"ball,"red" é"#);
    let scene = r#"Scene(
    name: "odd-name",
    domain: (origin: [0.0, -0.0625], extent: [0.5, 0.5], h: 0.015625),
    fluid: (gravity: [0.0, -1.0]),
    vacuum: true,
    numerics: (dt: Fixed(0.004), end_time: 0.04),
    bodies: [
        (name: "floor", shape: HalfSpace(normal: [0.0, 1.0, 0.0], offset: 0.0),
         kind: Static, position: [0.25, 0.0]),
        (name: "ball,\"red\" é", shape: Disk(radius: 0.1), position: [0.25, 0.11]),
    ],
    output: (every: 0.04, fields: []),
)"#;
    std::fs::write(d.join("odd-name.ron"), scene).unwrap();
    let run = d.join("run");
    let out = Command::new(env!("CARGO_BIN_EXE_tumble"))
        .arg("run")
        .arg(d.join("odd-name.ron"))
        .arg("--out")
        .arg(&run)
        .arg("--quiet")
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let plots = [
        "bodies_height.png",
        "bodies_velocity.png",
        "contacts_gap.png",
    ];
    for f in plots {
        std::fs::remove_file(run.join(f)).unwrap();
    }
    let out = Command::new(env!("CARGO_BIN_EXE_tumble"))
        .arg("plot")
        .arg(&run)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for f in plots {
        assert_png_900x600(&run.join(f));
    }

    let text = std::fs::read_to_string(run.join("bodies.csv")).unwrap();
    assert!(text.contains(r#",1,"ball,""red"" é",0.25,"#), "{text}");
    let mut r = csv::Reader::from_path(run.join("bodies.csv")).unwrap();
    assert_eq!(r.headers().unwrap().len(), 22);
    let rows: Vec<csv::StringRecord> = r.records().map(Result::unwrap).collect();
    assert_eq!(rows.len(), 11, "t = 0 and 10 steps");
    for row in &rows {
        assert_eq!(row.len(), 22, "{row:?}");
        assert_eq!(&row[2], ball);
    }
    let mut r = csv::Reader::from_path(run.join("contacts.csv")).unwrap();
    let rows: Vec<csv::StringRecord> = r.records().map(Result::unwrap).collect();
    assert!(!rows.is_empty(), "the ball starts 0.01 above the floor");
    for row in &rows {
        assert_eq!((&row[1], &row[2]), (floor, ball));
    }
    let gap = gap_series(&run).unwrap();
    assert_eq!(gap[0].label, format!("{floor}\u{2013}{ball}"));
}
