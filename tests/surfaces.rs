//! Body surfaces for ParaView: tessellations measure what the shapes' formulas say, and a
//! written `.vtp` parses with VTK's XML rules and places each part at its pose.

use glam::{DQuat, DVec3};
use std::f64::consts::PI;
use std::path::Path;
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
    let s = geom(Shape::Sphere { radius: 0.5 }).surface(1.0);
    let a = s.measure();
    assert!((a / (PI) - 1.0).abs() < 0.03, "sphere area {a} vs {PI}");
    assert!(s.lines.is_empty() && !s.triangles.is_empty());
    let d = geom(Shape::Disk { radius: 0.25 }).surface(1.0);
    let l = d.measure();
    assert!((l / (0.5 * PI) - 1.0).abs() < 1e-3, "disk perimeter {l}");
    // A box's area is exact: 2 (ab + bc + ca) with full sides 0.2, 0.4, 0.6.
    let b = geom(Shape::Box {
        half_extents: [0.1, 0.2, 0.3],
    })
    .surface(1.0);
    assert!((b.measure() - 2.0 * (0.08 + 0.24 + 0.12)).abs() < 1e-12);
    // Every surface point of a sphere is on the sphere (phi = 0 to round-off).
    let g = geom(Shape::Sphere { radius: 0.5 });
    for p in &g.surface(1.0).points {
        assert!(g.phi(*p).abs() < 1e-12);
    }
    // A cylinder along the body's z: its tessellation's points satisfy phi = 0 too.
    let c = geom(Shape::Cylinder {
        radius: 0.2,
        half_height: 0.5,
    });
    for p in &c.surface(1.0).points {
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
    let sphere = geom(Shape::Sphere { radius: 0.1 }).surface(1.0);
    let cube = geom(Shape::Box {
        half_extents: [0.1, 0.1, 0.1],
    })
    .surface(1.0);
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
