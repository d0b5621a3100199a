//! HDF5 + XDMF output (`--features hdf5`): the XDMF index describes the HDF5 files exactly,
//! the data is the simulation's, and the time series of the bodies are complete.
#![cfg(feature = "hdf5")]

#[allow(dead_code)]
#[path = "suite/common.rs"]
mod common;

use common::Scratch;
use std::path::Path;
use tumble::run::{RunOptions, run_scene};
use tumble::scene::Scene;
use tumble::sim::engine::Simulation;

fn tmp(name: &str) -> Scratch {
    Scratch::new("hdf5", name)
}

const SCENE_2D: &str = r#"Scene(
    name: "h5-2d",
    domain: (extent: [1.0, 2.0], origin: [-0.5, 0.25], cells: [16, 32]),
    fluid: (viscosity: 0.01, gravity: [0.0, -9.81]),
    numerics: (end_time: 0.06, dt: Adaptive(c: 0.5, dt_max: 0.01)),
    initial: [LambOseen(center: [0.0, 0.75], circulation: 0.5, core_radius: 0.15)],
    bodies: [
        (name: "disk", shape: Disk(radius: 0.12), density: 2.0, position: [0.1, 1.3]),
        (name: "floor", shape: HalfSpace(normal: [0.0, 1.0, 0.0], offset: 0.5), kind: Static, position: [0.0, 0.0]),
    ],
    output: (every: 0.02, formats: [Vtk, Hdf5], precision: Double),
)"#;

const SCENE_3D: &str = r#"Scene(
    name: "h5-3d",
    domain: (extent: [1.0, 1.0, 1.0], cells: [16, 16, 16]),
    fluid: (viscosity: 0.01, gravity: [0.0, 0.0, -9.81]),
    numerics: (end_time: 0.04, dt: Adaptive(c: 0.5, dt_max: 0.01)),
    initial: [TaylorGreen3d(amplitude: 0.1, wavenumber: 6.283185307179586)],
    bodies: [
        (name: "ball", shape: Sphere(radius: 0.15), density: 2.0, position: [0.5, 0.45, 0.6]),
        (name: "cube", shape: Box(half_extents: [0.1, 0.1, 0.1]), density: 1.5, position: [0.5, 0.5, 0.2], rotation: [0.0, 0.0, 0.3]),
    ],
    output: (every: 0.02, formats: [Hdf5]),
)"#;

/// The attributes of one `<Grid>` of the temporal collection.
struct Snap {
    time: f64,
    dims: Vec<usize>,
    /// (name, components, file, path in file, dimensions)
    attrs: Vec<(String, usize, String, String, Vec<usize>)>,
}

fn nums<T: std::str::FromStr>(s: &str) -> Vec<T>
where
    T::Err: std::fmt::Debug,
{
    s.split_whitespace().map(|x| x.parse().unwrap()).collect()
}

/// `precision`: the bytes per value every field dataset must be declared with.
fn parse_xmf(path: &Path, precision: &str) -> Vec<Snap> {
    let text = std::fs::read_to_string(path).unwrap();
    let opts = roxmltree::ParsingOptions {
        allow_dtd: true,
        ..Default::default()
    };
    let doc = roxmltree::Document::parse_with_options(&text, opts).unwrap();
    let root = doc.root_element();
    assert_eq!(root.tag_name().name(), "Xdmf");
    let domain = root.children().find(|n| n.has_tag_name("Domain")).unwrap();
    let coll = domain.children().find(|n| n.has_tag_name("Grid")).unwrap();
    assert_eq!(coll.attribute("GridType"), Some("Collection"));
    assert_eq!(coll.attribute("CollectionType"), Some("Temporal"));
    let mut out = Vec::new();
    for g in coll.children().filter(|n| n.has_tag_name("Grid")) {
        assert_eq!(g.attribute("GridType"), Some("Uniform"));
        let time: f64 = g
            .children()
            .find(|n| n.has_tag_name("Time"))
            .unwrap()
            .attribute("Value")
            .unwrap()
            .parse()
            .unwrap();
        let topo = g.children().find(|n| n.has_tag_name("Topology")).unwrap();
        let dims: Vec<usize> = nums(topo.attribute("Dimensions").unwrap());
        let geom = g.children().find(|n| n.has_tag_name("Geometry")).unwrap();
        let items: Vec<_> = geom
            .children()
            .filter(|n| n.has_tag_name("DataItem"))
            .collect();
        assert_eq!(items.len(), 2);
        let mut attrs = Vec::new();
        for a in g.children().filter(|n| n.has_tag_name("Attribute")) {
            assert_eq!(a.attribute("Center"), Some("Node"));
            let comps = match a.attribute("AttributeType").unwrap() {
                "Scalar" => 1,
                "Vector" => 3,
                t => panic!("attribute type {t}"),
            };
            let item = a.children().find(|n| n.has_tag_name("DataItem")).unwrap();
            assert_eq!(item.attribute("Format"), Some("HDF"));
            assert_eq!(item.attribute("Precision"), Some(precision));
            let shape: Vec<usize> = nums(item.attribute("Dimensions").unwrap());
            let (file, dset) = item.text().unwrap().trim().split_once(':').unwrap();
            attrs.push((
                a.attribute("Name").unwrap().to_string(),
                comps,
                file.to_string(),
                dset.to_string(),
                shape,
            ));
        }
        out.push(Snap { time, dims, attrs });
    }
    out
}

/// The field `name` of `sim` in the dataset's layout: C order (z, y, x[, component]), vectors
/// with 3 components (z = 0 in 2D), φ clamped below at minus the band kept around each body
/// (6 h).
fn expected(sim: &Simulation, name: &str) -> Vec<f64> {
    let f = sim.fields();
    let comps: Vec<&Vec<f64>> = match name {
        "omega" => f.omega().iter().collect(),
        "velocity" => f.u.iter().collect(),
        _ => {
            let b = sim.world.resource::<tumble::bodies::BodyFields>();
            let v = match name {
                "density" => b.rho.clone(),
                "chi" => b.chi.clone(),
                "phi" => {
                    let band = 6.0 * sim.grid().h;
                    b.phi.iter().map(|p| p.max(-band)).collect()
                }
                n => panic!("unexpected field {n}"),
            };
            return v;
        }
    };
    if comps.len() == 1 {
        return comps[0].clone();
    }
    let n = sim.grid().len();
    let mut out = Vec::with_capacity(3 * n);
    for p in 0..n {
        for c in 0..3 {
            out.push(comps.get(c).map_or(0.0, |v| v[p]));
        }
    }
    out
}

fn check_run(text: &str, name: &str) {
    let d = tmp(name);
    let scene_path = d.join(format!("{name}.ron"));
    std::fs::write(&scene_path, text).unwrap();
    let scene = Scene::load(&scene_path).unwrap();
    let out = d.join("out");
    let opts = RunOptions {
        out: Some(out.clone()),
        quiet: true,
        ..Default::default()
    };
    let summary = run_scene(scene.clone(), &opts).unwrap();
    let grid = scene.grid();

    let double = scene.output.precision == tumble::scene::Precision::Double;
    let snaps = parse_xmf(&out.join("fields.xmf"), if double { "8" } else { "4" });
    // Snapshots at 0, every, 2 every, ..., end.
    let every = scene.output.every.unwrap();
    let end = scene.numerics.end_time;
    let n = (end / every).round() as usize + 1;
    assert_eq!(snaps.len(), n);
    for (k, s) in snaps.iter().enumerate() {
        let want = (k as f64 * every).min(end);
        assert!((s.time - want).abs() < 1e-12, "snapshot {k} at {}", s.time);
        if k > 0 {
            assert!(s.time > snaps[k - 1].time);
        }
        // Topology slowest first: (nz,) ny, nx.
        let want_dims: Vec<usize> = if grid.dim == 3 {
            vec![grid.n[2], grid.n[1], grid.n[0]]
        } else {
            vec![grid.n[1], grid.n[0]]
        };
        assert_eq!(s.dims, want_dims);
        let names: Vec<&str> = s.attrs.iter().map(|a| a.0.as_str()).collect();
        assert_eq!(names, ["omega", "velocity", "density", "chi", "phi"]);
    }

    // A second simulation of the same scene, stepped to each snapshot time the way the run
    // does, holds the data of each snapshot bit for bit.
    let mut sim = Simulation::new(scene.clone()).unwrap();
    for (k, s) in snaps.iter().enumerate() {
        sim.set_stop_at(Some(s.time));
        while sim.time() < s.time * (1.0 - 1e-12) {
            sim.step().unwrap();
        }
        assert_eq!(sim.time(), s.time, "snapshot {k}");
        for (aname, comps, file, dset, shape) in &s.attrs {
            assert_eq!(file, &format!("fields_{k:06}.h5"));
            let h5 = hdf5::File::open(out.join(file)).unwrap();
            let t: f64 = h5.attr("time").unwrap().read_scalar().unwrap();
            assert_eq!(t, s.time, "{file}: time attribute");
            let origin: Vec<f64> = h5.attr("origin").unwrap().read_raw().unwrap();
            assert_eq!(origin, grid.origin.to_vec());
            let spacing: Vec<f64> = h5.attr("spacing").unwrap().read_raw().unwrap();
            assert_eq!(spacing, vec![grid.h; 3]);
            let dims: Vec<u64> = h5.attr("dims").unwrap().read_raw().unwrap();
            assert_eq!(dims, grid.n.map(|n| n as u64).to_vec());
            let ds = h5
                .dataset(dset)
                .unwrap_or_else(|e| panic!("{file}:{dset}: {e}"));
            assert_eq!(&ds.shape(), shape, "{file}:{dset}");
            let mut want_shape = s.dims.clone();
            if *comps == 3 {
                want_shape.push(3);
            }
            assert_eq!(shape, &want_shape, "{aname}");
            // Chunked and deflate-compressed; stored in the scene's precision: Double is the
            // field bit for bit, Single the field rounded to the nearest f32.
            assert!(ds.chunk().is_some(), "{file}:{dset} is not chunked");
            assert!(
                ds.filters()
                    .iter()
                    .any(|f| matches!(f, hdf5::filters::Filter::Deflate(_))),
                "{file}:{dset} is not compressed"
            );
            assert_eq!(ds.dtype().unwrap().size(), if double { 8 } else { 4 });
            let data: Vec<f64> = if double {
                ds.read_raw().unwrap()
            } else {
                let v: Vec<f32> = ds.read_raw().unwrap();
                v.into_iter().map(f64::from).collect()
            };
            let want = expected(&sim, aname);
            assert_eq!(data.len(), want.len(), "{file}:{dset}");
            let same = data.iter().zip(&want).all(|(a, b)| {
                if double {
                    a.to_bits() == b.to_bits()
                } else {
                    *a == *b as f32 as f64 && (a - b).abs() <= b.abs() * 2f64.powi(-24)
                }
            });
            assert!(same, "{file}:{dset} differs from the in-memory field");
        }
    }
    assert_eq!(sim.steps(), summary.steps);

    // series.h5: one entry per step (and the initial state) for the run and each moving body.
    let series = hdf5::File::open(out.join("series.h5")).unwrap();
    let steps = summary.steps as usize + 1;
    let t: Vec<f64> = series.dataset("series/t").unwrap().read_raw().unwrap();
    assert_eq!(t.len(), steps);
    assert!(t.windows(2).all(|w| w[1] > w[0]));
    assert_eq!(*t.last().unwrap(), end);
    // Appended to, not rewritten: every dataset of series.h5 is chunked and grows along its
    // first axis without limit.
    for name in ["series/t", "series/energy", "contacts/t", "contacts/body_a"] {
        let ds = series.dataset(name).unwrap();
        assert!(ds.is_resizable(), "{name}");
        assert!(ds.chunk().is_some(), "{name}");
        assert_eq!(ds.space().unwrap().maxdims()[0], None, "{name}");
    }
    // Its times are the rows of series.csv (the decimal text reads back to the same f64).
    let csv_t: Vec<f64> = std::fs::read_to_string(out.join("series.csv"))
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| l.split(',').next().unwrap().parse().unwrap())
        .collect();
    assert_eq!(csv_t, t);
    let mut q = sim
        .world
        .query::<(&tumble::bodies::Body, &tumble::bodies::RigidState)>();
    let mut moving = 0;
    for (b, st) in q.iter(&sim.world) {
        if b.is_static() {
            assert!(series.group(&format!("bodies/{}", b.name)).is_err());
            continue;
        }
        moving += 1;
        let g = series.group(&format!("bodies/{}", b.name)).unwrap();
        let bt: Vec<f64> = g.dataset("t").unwrap().read_raw().unwrap();
        assert_eq!(bt, t);
        let c = g.dataset("center").unwrap();
        assert_eq!(c.shape(), vec![steps, 3]);
        let c: Vec<f64> = c.read_raw().unwrap();
        assert_eq!(&c[c.len() - 3..], &st.center.to_array());
        assert_eq!(g.dataset("orientation").unwrap().shape(), vec![steps, 4]);
    }
    assert!(moving >= 1);
    let ct = series.dataset("contacts/t").unwrap();
    let cg = series.dataset("contacts/gap").unwrap();
    assert_eq!(ct.shape(), cg.shape());

    // The tools of the HDF5 distribution read the files too.
    if let Ok(st) = std::process::Command::new("h5dump")
        .arg("-H")
        .arg(out.join("fields_000001.h5"))
        .output()
    {
        assert!(
            st.status.success(),
            "h5dump -H failed: {}",
            String::from_utf8_lossy(&st.stderr)
        );
        let st = std::process::Command::new("h5dump")
            .arg("-H")
            .arg(out.join("series.h5"))
            .output()
            .unwrap();
        assert!(st.status.success());
    } else {
        eprintln!("h5dump not found (package hdf5-tools): skipping the h5dump check");
    }
    // The VTK files are there exactly when asked for; no temporary file is left behind.
    let vtk = scene.output.has_format(tumble::scene::OutputFormat::Vtk);
    assert_eq!(out.join("fields.pvd").exists(), vtk);
    assert_eq!(out.join("fields_000000.vti").exists(), vtk);
    for e in std::fs::read_dir(&out).unwrap() {
        let n = e.unwrap().file_name().to_string_lossy().into_owned();
        assert!(!n.contains(".tmp-"), "temporary file {n} left");
    }
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn hdf5_2d_with_bodies_matches_xdmf_and_memory() {
    check_run(SCENE_2D, "h5-2d");
}

#[test]
fn hdf5_3d_with_bodies_matches_xdmf_and_memory() {
    check_run(SCENE_3D, "h5-3d");
}

/// Vacuum, 3D: a rotated box falls and spins above a static floor (which it does not reach).
const FALLING_3D: &str = r#"Scene(
    name: "fall3d",
    domain: (extent: [1.0, 1.0, 1.0], cells: [16, 16, 16]),
    fluid: (gravity: [0.0, 0.0, -9.81]),
    vacuum: true,
    numerics: (end_time: 0.06, dt: Fixed(0.005)),
    bodies: [
        (name: "floor", shape: HalfSpace(normal: [0.0, 0.0, 1.0], offset: 0.0), kind: Static,
         position: [0.5, 0.5, 0.05]),
        (name: "box", shape: Box(half_extents: [0.1, 0.07, 0.05]), density: 2.0,
         position: [0.45, 0.55, 0.7], rotation: [0.2, 0.3, 0.4],
         velocity: [0.5, 0.0, 0.0], angular_velocity: [1.0, 2.0, 3.0]),
    ],
    output: (every: 0.02, formats: [Vtk, Hdf5]),
)"#;

/// Vacuum, 2D: a disk falls beside a static floor.
const FALLING_2D: &str = r#"Scene(
    name: "fall2d",
    domain: (extent: [1.0, 2.0], origin: [-0.5, 0.25], cells: [16, 32]),
    fluid: (gravity: [0.0, -9.81]),
    vacuum: true,
    numerics: (end_time: 0.06, dt: Fixed(0.005)),
    bodies: [
        (name: "floor", shape: HalfSpace(normal: [0.0, 1.0, 0.0], offset: 0.5), kind: Static, position: [0.0, 0.0]),
        (name: "disk", shape: Disk(radius: 0.12), density: 2.0, position: [0.1, 1.3],
         velocity: [0.3, 0.0]),
    ],
    output: (every: 0.02, formats: [Vtk, Hdf5]),
)"#;

/// `bodies.xmf` lists every snapshot with its time and describes its HDF5 file exactly; the
/// moving body's surface points are centred on its centre in `bodies.csv` and move.
fn check_body_surfaces(text: &str, name: &str, body: &str, nodes: usize) {
    let d = tmp(name);
    let scene_path = d.join(format!("{name}.ron"));
    std::fs::write(&scene_path, text).unwrap();
    let scene = Scene::load(&scene_path).unwrap();
    let out = d.join("out");
    let opts = RunOptions {
        out: Some(out.clone()),
        quiet: true,
        ..Default::default()
    };
    run_scene(scene.clone(), &opts).unwrap();
    let part = scene.bodies.iter().position(|b| b.name == body).unwrap() as i32;

    // bodies.csv: (t, x, y, z) of the body's rows.
    let csv = std::fs::read_to_string(out.join("bodies.csv")).unwrap();
    let rows: Vec<[f64; 4]> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect::<Vec<_>>())
        .filter(|c| c[2] == body)
        .map(|c| [0, 3, 4, 5].map(|i| c[i].parse().unwrap()))
        .collect();

    let text = std::fs::read_to_string(out.join("bodies.xmf")).unwrap();
    let opts = roxmltree::ParsingOptions {
        allow_dtd: true,
        ..Default::default()
    };
    let doc = roxmltree::Document::parse_with_options(&text, opts).unwrap();
    let domain = doc
        .root_element()
        .children()
        .find(|n| n.has_tag_name("Domain"))
        .unwrap();
    let coll = domain.children().find(|n| n.has_tag_name("Grid")).unwrap();
    assert_eq!(coll.attribute("CollectionType"), Some("Temporal"));
    let grids: Vec<_> = coll.children().filter(|n| n.has_tag_name("Grid")).collect();
    let every = scene.output.every.unwrap();
    let end = scene.numerics.end_time;
    assert_eq!(grids.len(), (end / every).round() as usize + 1);
    let item = |n: roxmltree::Node| -> (Vec<usize>, String) {
        let di = n.children().find(|c| c.has_tag_name("DataItem")).unwrap();
        assert_eq!(di.attribute("Format"), Some("HDF"));
        (
            nums(di.attribute("Dimensions").unwrap()),
            di.text().unwrap().trim().to_string(),
        )
    };
    let mut centres: Vec<[f64; 3]> = Vec::new();
    for (k, g) in grids.iter().enumerate() {
        let time: f64 = g
            .children()
            .find(|n| n.has_tag_name("Time"))
            .unwrap()
            .attribute("Value")
            .unwrap()
            .parse()
            .unwrap();
        assert!(
            (time - (k as f64 * every).min(end)).abs() < 1e-12,
            "{k}: {time}"
        );
        let topo = g.children().find(|n| n.has_tag_name("Topology")).unwrap();
        let want_topo = if nodes == 3 { "Triangle" } else { "Polyline" };
        assert_eq!(topo.attribute("TopologyType"), Some(want_topo));
        let geo = g.children().find(|n| n.has_tag_name("Geometry")).unwrap();
        assert_eq!(geo.attribute("GeometryType"), Some("XYZ"));
        let (cdims, cref) = item(topo);
        let (pdims, pref) = item(geo);
        let (file, cpath) = cref.split_once(":/").unwrap();
        assert_eq!(file, format!("bodies_{k:06}.h5"));
        assert_eq!(pref, format!("{file}:/points"));
        let h5 = hdf5::File::open(out.join(file)).unwrap();
        let t_attr: f64 = h5.attr("time").unwrap().read_scalar().unwrap();
        assert_eq!(t_attr.to_bits(), time.to_bits());
        let pts_ds = h5.dataset("points").unwrap();
        assert_eq!(pts_ds.shape(), pdims);
        assert_eq!(pdims[1], 3);
        let pts: Vec<f64> = pts_ds.read_raw().unwrap();
        let cells_ds = h5.dataset(cpath).unwrap();
        assert_eq!(cells_ds.shape(), cdims);
        assert_eq!(cdims[1], nodes);
        let cells: Vec<i64> = cells_ds.read_raw().unwrap();
        let n_pts = pdims[0] as i64;
        assert!(cells.iter().all(|&i| (0..n_pts).contains(&i)));
        let m = cdims[0];
        let mut ids = Vec::new();
        for a in g.children().filter(|n| n.has_tag_name("Attribute")) {
            assert_eq!(a.attribute("Center"), Some("Cell"));
            let (adims, aref) = item(a);
            let aname = a.attribute("Name").unwrap();
            assert_eq!(aref, format!("{file}:/{aname}"));
            assert_eq!(adims[0], m);
            assert_eq!(h5.dataset(aname).unwrap().shape(), adims);
            ids.push(aname.to_string());
        }
        assert_eq!(ids, ["part_id", "velocity", "angular_velocity", "force"]);
        let part_id: Vec<i32> = h5.dataset("part_id").unwrap().read_raw().unwrap();
        // The distinct points of the body's cells.
        let mut used: Vec<usize> = cells
            .chunks(nodes)
            .zip(&part_id)
            .filter(|(_, p)| **p == part)
            .flat_map(|(c, _)| c.iter().map(|&i| i as usize))
            .collect();
        used.sort_unstable();
        used.dedup();
        assert!(!used.is_empty());
        let mut mean = [0.0; 3];
        for &i in &used {
            for c in 0..3 {
                mean[c] += pts[3 * i + c] / used.len() as f64;
            }
        }
        let row = rows
            .iter()
            .find(|r| (r[0] - time).abs() < 1e-12)
            .unwrap_or_else(|| panic!("no bodies.csv row at t = {time}"));
        for c in 0..3 {
            assert!(
                (mean[c] - row[c + 1]).abs() < 1e-9,
                "{k}: {mean:?} vs {row:?}"
            );
        }
        if let Some(prev) = centres.last() {
            assert!(prev != &mean, "snapshot {k} did not move");
        }
        centres.push(mean);
    }
    // The VTK side is still written.
    assert!(out.join("bodies.pvd").exists());
}

#[test]
fn body_surfaces_in_xdmf_3d() {
    check_body_surfaces(FALLING_3D, "fall3d", "box", 3);
}

#[test]
fn body_surfaces_in_xdmf_2d() {
    check_body_surfaces(FALLING_2D, "fall2d", "disk", 2);
}
