//! PNG plots: `line_chart`, `plot_run_dir` and `tumble plot`.

use std::path::{Path, PathBuf};
use std::process::Command;
use tumble::io::plot::{Series, Style, line_chart, plot_run_dir};

/// A fresh, empty directory under the system temp dir, unique to this process and `name`.
fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("tumble-plot-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
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
fn run_dir(name: &str, bodies: usize) -> PathBuf {
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
