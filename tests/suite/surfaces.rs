//! Body surfaces for ParaView: tessellations measure what the shapes' formulas say, and a
//! written `.vtp` parses with VTK's XML rules and places each part at its pose.

use glam::{DQuat, DVec3};
use std::f64::consts::PI;
use std::path::{Path, PathBuf};
use tumble::bodies::shapes::Shape;
use tumble::io::surfaces::{SurfacePart, SurfaceSeries};

fn geom(shape: Shape) -> tumble::bodies::shapes::ShapeGeometry {
    shape.build(Path::new(".")).expect("shape builds")
}

#[test]
fn tessellations_have_the_shapes_area_and_perimeter() {
    // An inscribed UV sphere with 16 latitude bands and 32 meridians falls short of 4 pi r^2
    // by about (pi/16)^2/3 = 1.3%: 3% bounds it. A 96-gon's perimeter is within
    // (2 pi/96)^2/6 = 0.07% of 2 pi r.
    let s = geom(Shape::Sphere { radius: 0.5 }).surface(1.0, 3);
    let a = s.measure();
    assert!((a / (PI) - 1.0).abs() < 0.03, "sphere area {a} vs {PI}");
    assert!(s.lines.is_empty() && !s.triangles.is_empty());
    let d = geom(Shape::Disk { radius: 0.25 }).surface(1.0, 3);
    let l = d.measure();
    assert!((l / (0.5 * PI) - 1.0).abs() < 1e-3, "disk perimeter {l}");
    // A box's area is exact: 2 (ab + bc + ca) with full sides 0.2, 0.4, 0.6.
    let b = geom(Shape::Box {
        half_extents: [0.1, 0.2, 0.3],
    })
    .surface(1.0, 3);
    assert!((b.measure() - 2.0 * (0.08 + 0.24 + 0.12)).abs() < 1e-12);
    // Every surface point of a sphere is on the sphere (phi = 0 to round-off).
    let g = geom(Shape::Sphere { radius: 0.5 });
    for p in &g.surface(1.0, 3).points {
        assert!(g.phi(*p).abs() < 1e-12);
    }
    // A cylinder along the body's z: its tessellation's points satisfy phi = 0 too.
    let c = geom(Shape::Cylinder {
        radius: 0.2,
        half_height: 0.5,
    });
    for p in &c.surface(1.0, 3).points {
        assert!(
            c.phi(*p).abs() < 1e-12,
            "cylinder point {p} has phi {}",
            c.phi(*p)
        );
    }
}

#[test]
fn a_snapshot_parses_and_places_each_part_at_its_pose() {
    let dir = std::env::temp_dir().join(format!("tumble-surfaces-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let sphere = geom(Shape::Sphere { radius: 0.1 }).surface(1.0, 3);
    let cube = geom(Shape::Box {
        half_extents: [0.1, 0.1, 0.1],
    })
    .surface(1.0, 3);
    let rot = DQuat::from_rotation_z(0.3);
    let parts = [
        SurfacePart {
            name: "ball",
            mesh: &sphere,
            center: DVec3::new(0.5, 0.5, 0.5),
            orientation: DQuat::IDENTITY,
            vectors: vec![DVec3::new(0.0, 0.0, -1.0)],
        },
        SurfacePart {
            name: "cube",
            mesh: &cube,
            center: DVec3::new(0.2, 0.3, 0.4),
            orientation: rot,
            vectors: vec![DVec3::ZERO],
        },
    ];
    let mut series = SurfaceSeries::new(&dir, "bodies", &["velocity"]);
    let name = series.write(0, 0.25, &parts).unwrap();
    let text = std::fs::read_to_string(dir.join(&name)).unwrap();
    let doc = roxmltree::Document::parse(&text).expect("well-formed XML");
    let piece = doc.descendants().find(|n| n.has_tag_name("Piece")).unwrap();
    let n_points: usize = piece.attribute("NumberOfPoints").unwrap().parse().unwrap();
    let n_polys: usize = piece.attribute("NumberOfPolys").unwrap().parse().unwrap();
    assert_eq!(n_points, sphere.points.len() + cube.points.len());
    assert_eq!(n_polys, sphere.triangles.len() + cube.triangles.len());
    let nums = |tag: &str, name: &str| -> Vec<f64> {
        let parent = piece.descendants().find(|n| n.has_tag_name(tag)).unwrap();
        let arr = parent
            .descendants()
            .find(|n| n.has_tag_name("DataArray") && n.attribute("Name") == Some(name))
            .unwrap();
        arr.text()
            .unwrap()
            .split_whitespace()
            .map(|x| x.parse().unwrap())
            .collect()
    };
    let pts = nums("Points", "Points");
    assert_eq!(pts.len(), 3 * n_points);
    // The cube's points are the body-frame corners rotated by 0.3 about z and moved to its
    // centre: every one at distance sqrt(3) * 0.1 from (0.2, 0.3, 0.4) (single precision).
    for k in sphere.points.len()..n_points {
        let p = DVec3::new(pts[3 * k], pts[3 * k + 1], pts[3 * k + 2]);
        assert!(((p - DVec3::new(0.2, 0.3, 0.4)).length() - 0.1 * 3f64.sqrt()).abs() < 1e-6);
    }
    let first_corner = DVec3::new(0.2, 0.3, 0.4) + rot * cube.points[0];
    let k = sphere.points.len();
    assert!(
        (DVec3::new(pts[3 * k], pts[3 * k + 1], pts[3 * k + 2]) - first_corner).length() < 1e-6
    );
    let conn = nums("Polys", "connectivity");
    let offs = nums("Polys", "offsets");
    assert_eq!(offs.len(), n_polys);
    assert_eq!(*offs.last().unwrap() as usize, conn.len());
    assert!(conn.iter().all(|&i| (i as usize) < n_points));
    let ids = nums("CellData", "part_id");
    assert_eq!(ids.len(), n_polys);
    assert_eq!(
        ids.iter().filter(|&&i| i == 1.0).count(),
        cube.triangles.len()
    );
    let vel = nums("CellData", "velocity");
    assert_eq!(vel.len(), 3 * n_polys);
    assert_eq!(vel[2], -1.0);
    // The .pvd lists the snapshot with its time.
    let pvd = std::fs::read_to_string(dir.join("bodies.pvd")).unwrap();
    assert!(pvd.contains("timestep=\"0.25\"") && pvd.contains(&name));
    std::fs::remove_dir_all(&dir).ok();
}

/// The `(time, file)` entries of a `.pvd`.
fn pvd_entries(path: &Path) -> Vec<(f64, String)> {
    let text = std::fs::read_to_string(path).unwrap();
    let doc = roxmltree::Document::parse(&text).expect("well-formed .pvd");
    doc.descendants()
        .filter(|n| n.has_tag_name("DataSet"))
        .map(|n| {
            (
                n.attribute("timestep").unwrap().parse().unwrap(),
                n.attribute("file").unwrap().to_string(),
            )
        })
        .collect()
}

/// The snapshot's time and the mean of the points used by the cells of part `part`.
fn part_mean(path: &Path, part: usize) -> (f64, DVec3) {
    let text = std::fs::read_to_string(path).unwrap();
    let doc = roxmltree::Document::parse(&text).expect("well-formed .vtp");
    let array = |parent: &str, name: &str| -> Vec<f64> {
        let p = doc.descendants().find(|n| n.has_tag_name(parent)).unwrap();
        p.descendants()
            .find(|n| n.attribute("Name") == Some(name))
            .unwrap_or_else(|| panic!("no {parent}/{name}"))
            .text()
            .unwrap()
            .split_whitespace()
            .map(|x| x.parse().unwrap())
            .collect()
    };
    let t = array("FieldData", "TimeValue")[0];
    let pts = array("Points", "Points");
    let ids = array("CellData", "part_id");
    // The disk's cells are lines; VTK lists a PolyData's cells lines first, then polygons.
    let conn = array("Lines", "connectivity");
    let offs = array("Lines", "offsets");
    assert!(offs.len() <= ids.len());
    let mut used = std::collections::BTreeSet::new();
    let mut start = 0;
    for (c, &end) in offs.iter().enumerate() {
        if ids[c] as usize == part {
            for &i in &conn[start..end as usize] {
                used.insert(i as usize);
            }
        }
        start = end as usize;
    }
    assert!(!used.is_empty(), "part {part} has no cell");
    let sum: DVec3 = used
        .iter()
        .map(|&i| DVec3::new(pts[3 * i], pts[3 * i + 1], pts[3 * i + 2]))
        .sum();
    (t, sum / used.len() as f64)
}

/// A disk spinning as it falls in vacuum onto a floor: the run writes `bodies.pvd` listing
/// every snapshot (t = 0, 0.1, ..., 0.6) and no field files (`fields: []`); in each snapshot
/// the disk's outline is centred on the body's centre in `bodies.csv` (single precision: the
/// 96-gon's points are symmetric about it) and moves between snapshots. A run stopped at
/// t = 0.5 and restarted from its checkpoint (t = 0.4) ends with the same series, file for
/// file.
#[test]
fn a_run_writes_the_bodies_surfaces_moving_with_them_and_a_restart_continues_them() {
    use tumble::run::{RunOptions, restart_run, run_scene};
    let dir = std::env::temp_dir().join(format!("tumble-surfaces-run-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let text = r#"Scene(
    name: "falling-disk",
    domain: (origin: [0.0, -0.0625], extent: [0.5, 0.5], h: 0.0078125),
    fluid: (gravity: [0.0, -1.0]),
    vacuum: true,
    contact: (kappa: 1.0),
    numerics: (dt: Fixed(0.00078125), end_time: 0.6),
    bodies: [
        (name: "floor", shape: HalfSpace(normal: [0.0, 1.0, 0.0], offset: 0.0),
         kind: Static, position: [0.25, 0.0]),
        (name: "disk", shape: Disk(radius: 0.1), position: [0.25, 0.3],
         velocity: [0.05, 0.0], angular_velocity: [2.0]),
    ],
    output: (every: 0.1, fields: [], checkpoint_every: 0.2),
)"#;
    let scene = || tumble::scene::Scene::parse(text, "falling-disk.ron", "").unwrap();
    let straight = dir.join("straight");
    let opts = |out: Option<&Path>, until: Option<f64>| RunOptions {
        out: out.map(Path::to_path_buf),
        until,
        quiet: true,
        ..Default::default()
    };
    run_scene(scene(), &opts(Some(&straight), None)).unwrap();

    let names: Vec<String> = std::fs::read_dir(&straight)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    assert!(
        !names
            .iter()
            .any(|n| n.ends_with(".vti") || n == "fields.pvd"),
        "{names:?}"
    );
    let entries = pvd_entries(&straight.join("bodies.pvd"));
    assert_eq!(entries.len(), 7, "{entries:?}");
    let csv = std::fs::read_to_string(straight.join("bodies.csv")).unwrap();
    let rows: Vec<Vec<f64>> = csv
        .lines()
        .skip(1)
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            vec![
                f[0].parse().unwrap(),
                f[3].parse().unwrap(),
                f[4].parse().unwrap(),
            ]
        })
        .collect();
    let mut last: Option<DVec3> = None;
    for (k, (t, file)) in entries.iter().enumerate() {
        assert_eq!(file, &format!("bodies_{k:06}.vtp"));
        assert!((t - 0.1 * k as f64).abs() < 1e-9, "snapshot {k} at t = {t}");
        // Part 1 is the disk (parts in body-id order; the floor is 0).
        let (time, mean) = part_mean(&straight.join(file), 1);
        assert_eq!(time, *t);
        let row = rows
            .iter()
            .find(|r| (r[0] - t).abs() < 1e-12)
            .unwrap_or_else(|| panic!("no bodies.csv row at t = {t}"));
        let centre = DVec3::new(row[1], row[2], 0.0);
        assert!(
            (mean - centre).length() < 1e-6,
            "t = {t}: outline centred at {mean}, body at {centre}"
        );
        if let Some(prev) = last {
            assert!((mean - prev).length() > 1e-3, "the disk did not move");
        }
        last = Some(mean);
    }

    let stopped = dir.join("stopped");
    run_scene(scene(), &opts(Some(&stopped), Some(0.5))).unwrap();
    assert_eq!(pvd_entries(&stopped.join("bodies.pvd")).len(), 6);
    let mut ck: Vec<PathBuf> = std::fs::read_dir(&stopped)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| {
            let n = p.file_name().unwrap().to_str().unwrap();
            n.starts_with("checkpoint") && n.ends_with(".bin")
        })
        .collect();
    ck.sort();
    let ck = ck.last().expect("a checkpoint");
    restart_run(ck, None, &opts(None, Some(0.6))).unwrap();
    for k in 0..7 {
        let f = format!("bodies_{k:06}.vtp");
        assert_eq!(
            std::fs::read(straight.join(&f)).unwrap(),
            std::fs::read(stopped.join(&f)).unwrap(),
            "{f}"
        );
    }
    assert!(!stopped.join("bodies_000007.vtp").exists());
    assert_eq!(
        std::fs::read(straight.join("bodies.pvd")).unwrap(),
        std::fs::read(stopped.join("bodies.pvd")).unwrap()
    );
    std::fs::remove_dir_all(&dir).ok();
}
