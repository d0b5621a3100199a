//! The outputs of a free surface: its zero level as triangles (3D) and segments (2D) placed
//! where the geometry says, the `free_surface` field and part in a snapshot, the slice images,
//! and the `series.csv` columns.

use std::collections::HashMap;
use std::f64::consts::PI;
use std::path::PathBuf;
use tumble::base::grid::Grid;
use tumble::bodies::free_surface::LiquidLevelSet;
use tumble::io::isosurface::zero_level;
use tumble::io::slices::{slice_file, slice_size};
use tumble::io::snapshots::Snapshots;
use tumble::run::SeriesCsv;
use tumble::scene::{Scene, ValidScene};
use tumble::sim::engine::Simulation;

/// A level set sampled at `grid`'s nodes and clipped to ±4h, as the free surface keeps it.
fn sample(grid: &Grid, f: impl Fn([f64; 3]) -> f64) -> Vec<f64> {
    let band = 4.0 * grid.h;
    let mut v = vec![0.0; grid.len()];
    for k in 0..grid.n[2] {
        for j in 0..grid.n[1] {
            for i in 0..grid.n[0] {
                v[grid.idx(i, j, k)] = f(grid.pos(i, j, k)).clamp(-band, band);
            }
        }
    }
    v
}

/// The distance from `p` to the sphere of radius `r` about the periodic images of `c` in a box
/// of side `l`.
fn sphere_distance(p: glam::DVec3, c: [f64; 3], r: f64, l: f64) -> f64 {
    let d = [0, 1, 2].map(|a| {
        let x = p[a] - c[a];
        x - l * (x / l).round()
    });
    ((d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt() - r).abs()
}

/// Each edge of a triangle mesh and how many triangles use it.
fn edge_uses(t: &[[u32; 3]]) -> HashMap<(u32, u32), usize> {
    let mut m = HashMap::new();
    for tri in t {
        for (a, b) in [(tri[0], tri[1]), (tri[1], tri[2]), (tri[2], tri[0])] {
            *m.entry((a.min(b), a.max(b))).or_insert(0) += 1;
        }
    }
    m
}

/// A sphere of radius 0.26 = 8.3 h on a 32³ grid, once inside the box and once across its
/// periodic seam: the surface is closed (inside), its vertices lie within 0.1 h of the sphere
/// and its area is within 3% of 4πr².
///
/// Tolerances from the geometry: each vertex is the mean of points on the cell's edges where
/// the linear interpolant of φ vanishes; those lie within h²/(8r) of the sphere, and their mean
/// lies inside the sphere by at most the sagitta of the cell's diagonal, 3h²/(8r): together
/// h²/(2r) = 0.06 h. A surface through such vertices with facets about h wide has its area
/// within O((h/r)²) = 1.5% of the sphere's.
#[test]
fn a_sphere_level_is_closed_on_the_sphere_with_its_area() {
    let n = 32;
    let h = 1.0 / n as f64;
    let grid = Grid::new([n, n, n], h, [0.0; 3]);
    let r = 0.26;
    for c in [[0.51, 0.49, 0.503], [0.02, 0.5, 0.97]] {
        let phi = sample(&grid, |x| {
            let d = [0, 1, 2].map(|a| {
                let v = x[a] - c[a];
                v - (v).round()
            });
            r - (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
        });
        let m = zero_level(&grid, &phi);
        assert!(m.lines.is_empty() && m.triangles.len() > 1000);
        let worst = m
            .points
            .iter()
            .map(|p| sphere_distance(*p, c, r, 1.0))
            .fold(0.0, f64::max);
        assert!(worst < 0.1 * h, "a vertex {} h off the sphere", worst / h);
        let area = m.measure();
        let exact = 4.0 * PI * r * r;
        let rel = area / exact - 1.0;
        assert!(rel.abs() < 0.03, "area {area} vs {exact}: {rel:+.4}");
        eprintln!(
            "sphere at {c:?}: {} triangles, worst vertex {:.4} h, area {rel:+.4}",
            m.triangles.len(),
            worst / h
        );
        if c[0] > 0.1 {
            // Inside the box: closed, every edge shared by two triangles.
            let uses = edge_uses(&m.triangles);
            assert!(
                uses.values().all(|&u| u == 2),
                "an open or non-manifold edge"
            );
        }
    }
}

/// A horizontal slab of liquid z1 < z < z0 (the box is periodic, so a liquid layer has two
/// surfaces; both off the nodes): every vertex at z0 or z1, and each plane covers the periodic
/// box's cross-section once, area Lx Ly, one triangle pair per cell column.
#[test]
fn a_flat_level_is_at_its_height_and_covers_the_box_once() {
    let grid = Grid::new([24, 16, 20], 0.05, [-0.3, 0.1, 0.2]);
    let (z0, z1) = (0.2 + 7.37 * 0.05, 0.2 + 2.61 * 0.05);
    let phi = sample(&grid, |x| (z0 - x[2]).min(x[2] - z1));
    let m = zero_level(&grid, &phi);
    assert_eq!(m.triangles.len(), 2 * 2 * 24 * 16);
    let mut at = [0, 0];
    for p in &m.points {
        // f32 vertices: 1e-6 of the box.
        let near = [z0, z1].map(|z| (p.z - z).abs() < 1e-6);
        assert!(near[0] || near[1], "vertex at z = {}", p.z);
        at[near[1] as usize] += 1;
    }
    assert_eq!(at[0], at[1]);
    let (lx, ly) = (24.0 * 0.05, 16.0 * 0.05);
    assert!(
        (m.measure() / (2.0 * lx * ly) - 1.0).abs() < 1e-5,
        "{}",
        m.measure()
    );

    // 2D: a layer y1 < y < y0 has two lines, each one segment per cell column, length Lx; a
    // circle of radius
    // 0.3 = 9.6 h has its perimeter within 1% (an inscribed polygon of chords about h long
    // falls short by (h/r)²/24 = 0.05%, the vertices' linear interpolation error h²/(8r) per
    // vertex adds 0.4%), its vertices within h²/(8r) = 0.013 h of the circle.
    let g2 = Grid::new([32, 24, 1], 1.0 / 32.0, [0.0, 0.0, 0.0]);
    let (y0, y1) = (0.4 + 0.3 / 32.0, 0.1 + 0.55 / 32.0);
    let line = zero_level(&g2, &sample(&g2, |x| (y0 - x[1]).min(x[1] - y1)));
    assert!(line.triangles.is_empty());
    assert_eq!(line.lines.len(), 64);
    assert!(
        line.points
            .iter()
            .all(|p| (p.y - y0).abs() < 1e-12 || (p.y - y1).abs() < 1e-12)
    );
    assert!((line.measure() - 2.0).abs() < 1e-12);
    let (c, r, h) = ([0.5, 0.37, 0.0], 0.3, 1.0 / 32.0);
    let circle = zero_level(&g2, &sample(&g2, |x| r - (x[0] - c[0]).hypot(x[1] - c[1])));
    let len = circle.measure();
    assert!((len / (2.0 * PI * r) - 1.0).abs() < 0.01, "perimeter {len}");
    let worst = circle
        .points
        .iter()
        .map(|p| ((p.x - c[0]).hypot(p.y - c[1]) - r).abs())
        .fold(0.0, f64::max);
    assert!(worst < 0.02 * h, "a point {} h off the circle", worst / h);
    // Closed: every point joins two segments.
    let mut uses = vec![0; circle.points.len()];
    for l in &circle.lines {
        uses[l[0] as usize] += 1;
        uses[l[1] as usize] += 1;
    }
    assert!(uses.iter().all(|&u| u == 2));

    // Bad input gives an empty surface, no panic.
    assert!(zero_level(&grid, &phi[1..]).is_empty());
    let mut nan = phi.clone();
    nan[5] = f64::NAN;
    nan[7] = f64::INFINITY;
    assert!(zero_level(&grid, &nan).points.iter().all(|p| p.is_finite()));
}

/// A small 3D scene: a floor (static box) and a dynamic sphere, 32³ nodes.
fn scene(name: &str) -> ValidScene {
    scene_with(name, "")
}

/// [`scene`] with more `output` settings (`extra`, ending in a comma).
fn scene_with(name: &str, extra: &str) -> ValidScene {
    Scene::parse(
        &format!(
            r#"Scene(
    name: "fs-out",
    domain: (extent: [1.0, 1.0, 1.0], cells: [32, 32, 32]),
    fluid: (density: 1.0, viscosity: 0.01, gravity: [0.0, 0.0, -1.0]),
    numerics: (end_time: 0.01),
    bodies: [
        (name: "floor", shape: Box(half_extents: [0.6, 0.6, 0.1]), kind: Static, position: [0.5, 0.5, 0.05]),
        (name: "ball", shape: Sphere(radius: 0.12), kind: Dynamic, density: 2.0, position: [0.5, 0.5, 0.4]),
    ],
    output: ({extra} fields: [Omega, Velocity, Density]),
)"#
        ),
        "fs.ron",
        name,
    )
    .unwrap()
}

/// A liquid layer `z1 < z < z0` on `sim`'s grid (the box is periodic: two free surfaces).
fn liquid(sim: &Simulation, z0: f64, z1: f64) -> LiquidLevelSet {
    let phi = sample(sim.grid(), |x| (z0 - x[2]).min(x[2] - z1));
    LiquidLevelSet {
        phi,
        band: 4.0 * sim.grid().h,
        target_volume: 0.6,
        volume: 0.6,
        area: 1.0,
    }
}

fn temp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("tumble-fsout-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn a_snapshot_holds_the_free_surface_field_part_and_slice() {
    let dir = temp("snap");
    let mut sim = Simulation::new(scene("fs")).unwrap();
    let (z0, z1) = ((19.0 + 0.5) / 32.0, (3.0 + 0.25) / 32.0);
    let ls = liquid(&sim, z0, z1);
    let phi = ls.phi.clone();
    sim.world.insert_resource(ls);
    let mut snaps = Snapshots::new(&dir, &sim);
    let files = snaps.write(&sim).unwrap();
    assert!(
        files.contains(&"slices/slice_000000.png".to_string()),
        "{files:?}"
    );

    // The field: φ_w as given (single precision by default).
    let vti = crate::vti::read_vti(&dir.join("fields_000000.vti")).unwrap();
    let names: Vec<&str> = vti.arrays.iter().map(|a| a.0.as_str()).collect();
    assert_eq!(
        names,
        ["omega", "velocity", "density", "chi", "phi", "free_surface"]
    );
    let f = &vti.arrays[5];
    assert_eq!(f.1, 1);
    assert!(f.2.iter().zip(&phi).all(|(a, b)| (a - b).abs() < 1e-6));

    // The part: named free_surface, last, its triangles at z0.
    let vtp = std::fs::read_to_string(dir.join("bodies_000000.vtp")).unwrap();
    let encoded: String = "free_surface"
        .bytes()
        .map(|b| format!("{b} "))
        .collect::<String>()
        + "0";
    assert!(vtp.contains(&encoded), "no free_surface part name");
    assert!(vtp.contains("<CellData"));

    // The slice: decodes, the documented size, 2 to 4 pixels per cell; black lines (the
    // free surfaces) across the slice at z0's and z1's rows, nowhere else.
    let bytes = std::fs::read(dir.join(slice_file(0))).unwrap();
    let img = image::load_from_memory_with_format(&bytes, image::ImageFormat::Png)
        .unwrap()
        .to_rgb8();
    let (w, h) = slice_size(sim.grid());
    assert_eq!((img.width(), img.height()), (w, h));
    let s = (w - 110) / 32;
    assert!((2..=4).contains(&s) && w - 110 == 32 * s, "{w} x {h}");
    // Node k's block is rows 44 + (31 - k) s ..; the level z = (k + f) h is at
    // 44 + (31.5 - k - f) s from the top.
    let expect = [z0, z1].map(|z| 44.0 + (31.5 - z * 32.0) * s as f64);
    let mut rows = Vec::new();
    for y in 44..h {
        let black = (0..32 * s)
            .filter(|&x| img.get_pixel(x, y).0 == [0, 0, 0])
            .count();
        if black > (32 * s / 2) as usize {
            rows.push(y as f64);
        }
    }
    for e in expect {
        assert!(
            rows.iter().any(|r| (r - e).abs() < 2.0),
            "no line near row {e}: {rows:?}"
        );
    }
    assert!(
        rows.iter()
            .all(|r| expect.iter().any(|e| (r - e).abs() < 2.0)),
        "lines at rows {rows:?}, expected {expect:?}"
    );
    // Green (the bodies' outline) is drawn too.
    let green = img.pixels().filter(|p| p.0 == [0, 140, 0]).count();
    assert!(green > 100, "{green} green pixels");

    // A second snapshot, then a restart that keeps one: the later slice goes.
    snaps.write(&sim).unwrap();
    assert!(dir.join(slice_file(1)).is_file());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn series_csv_has_the_liquid_columns_only_with_a_free_surface() {
    let dir = temp("series");
    let mut sim = Simulation::new(scene("fs")).unwrap();
    // A 3D fluid run also has the grid-scale dissipation's column, last.
    sim.world
        .resource_mut::<tumble::systems::diffusion::GridScaleDissipation>()
        .removed = 0.5;
    let plain = dir.join("plain.csv");
    let mut w = SeriesCsv::create(&plain, &sim).unwrap();
    w.row(&sim).unwrap();
    w.flush().unwrap();
    let text = std::fs::read_to_string(&plain).unwrap();
    assert_eq!(
        text.lines().next(),
        Some("t,dt,energy,enstrophy,circulation,max_omega,grid_scale_removed")
    );
    let v: Vec<&str> = text.lines().nth(1).unwrap().split(',').collect();
    assert_eq!((v.len(), v[6]), (7, "0.5"));

    let mut ls = liquid(&sim, 0.5, 0.2);
    ls.volume = 0.625;
    ls.area = 1.25;
    sim.world.insert_resource(ls);
    let with = dir.join("series.csv");
    let mut w = SeriesCsv::create(&with, &sim).unwrap();
    w.row(&sim).unwrap();
    drop(w);
    // A restart appends with the same columns.
    let mut w = SeriesCsv::append(&with, &sim).unwrap();
    w.row(&sim).unwrap();
    w.flush().unwrap();
    let text = std::fs::read_to_string(&with).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(
        lines[0],
        "t,dt,energy,enstrophy,circulation,max_omega,liquid_volume,liquid_area,grid_scale_removed"
    );
    assert_eq!(lines.len(), 3);
    for l in &lines[1..] {
        let v: Vec<&str> = l.split(',').collect();
        assert_eq!(v.len(), 9);
        assert_eq!((v[6], v[7], v[8]), ("0.625", "1.25", "0.5"));
    }

    // `tumble plot` draws the liquid volume.
    std::fs::write(dir.join("scene.ron"), sim.scene().to_ron()).unwrap();
    let written = tumble::io::plot::plot_run_dir(&dir).unwrap();
    assert!(written.iter().any(|p| p.ends_with("liquid_volume.png")));
    let _ = std::fs::remove_dir_all(&dir);
}

/// The cost at snapshot time of a 128³ free surface: its zero level and a slice image
/// (measured, not asserted: `cargo test --release --test suite -- --ignored --nocapture
/// time_a_128_cubed_surface_and_slice`).
#[test]
#[ignore]
fn time_a_128_cubed_surface_and_slice() {
    use tumble::io::slices::{SliceInput, render};
    let n = 128;
    let grid = Grid::new([n, n, n], 1.0 / n as f64, [0.0; 3]);
    let phi = sample(&grid, |x| {
        0.5 + 0.05 * (2.0 * PI * x[0]).sin() * (2.0 * PI * x[1]).cos() - x[2]
    });
    let body = sample(&grid, |x| {
        0.1 - ((x[0] - 0.5).powi(2) + (x[1] - 0.5).powi(2) + (x[2] - 0.3).powi(2)).sqrt()
    });
    let omega: Vec<f64> = (0..grid.len()).map(|i| (i as f64 * 1e-3).sin()).collect();
    let t0 = std::time::Instant::now();
    let m = zero_level(&grid, &phi);
    let t_mesh = t0.elapsed().as_secs_f64();
    let t1 = std::time::Instant::now();
    let png = render(&SliceInput {
        grid: &grid,
        colour: &omega,
        colour_name: "ω_y",
        liquid: Some(&phi),
        bodies: Some(&body),
        j: 64,
        title: "timing",
    })
    .unwrap();
    let t_slice = t1.elapsed().as_secs_f64();
    let file = std::env::temp_dir().join("tumble-fsout-slice-128.png");
    std::fs::write(&file, &png).unwrap();
    eprintln!("slice image: {}", file.display());
    eprintln!(
        "128^3: zero level {} triangles in {t_mesh:.3} s, slice {} bytes in {t_slice:.3} s",
        m.triangles.len(),
        png.len()
    );
}

/// `tumble run` of a 2D scene with a dynamic body writes a slice image per snapshot without
/// being asked, and its `series.csv` has no liquid columns (no free surface).
#[test]
fn a_run_with_a_dynamic_body_writes_its_slices() {
    use tumble::run::{RunOptions, run_scene};
    let base = temp("run");
    let scene = Scene::parse(
        r#"Scene(
    name: "slices-2d",
    domain: (extent: [1.0, 1.0], cells: [32, 32]),
    fluid: (gravity: [0.0, -1.0]),
    numerics: (end_time: 0.02),
    bodies: [(name: "disk", shape: Disk(radius: 0.1), kind: Dynamic, density: 2.0, position: [0.5, 0.6])],
    output: (every: 0.01),
)"#,
        "slices.ron",
        "slices-2d",
    )
    .unwrap();
    let out = base.join("out");
    let opts = RunOptions {
        out: Some(out.clone()),
        quiet: true,
        ..Default::default()
    };
    run_scene(scene, &opts).unwrap();
    let pvd = std::fs::read_to_string(out.join("bodies.pvd")).unwrap();
    let snapshots = pvd.matches("<DataSet").count();
    assert!(snapshots >= 3, "{pvd}");
    let mut pngs: Vec<_> = std::fs::read_dir(out.join("slices"))
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    pngs.sort();
    let expect: Vec<String> = (0..snapshots)
        .map(|k| slice_file(k).trim_start_matches("slices/").to_string())
        .collect();
    assert_eq!(pngs, expect);
    let series = std::fs::read_to_string(out.join("series.csv")).unwrap();
    assert_eq!(
        series.lines().next(),
        Some("t,dt,energy,enstrophy,circulation,max_omega")
    );
    assert!(!out.join("liquid_volume.png").exists());
    let _ = std::fs::remove_dir_all(&base);
}

/// With HDF5 output, the snapshot's `fields_000000.h5` holds `/free_surface` (nz, ny, nx) and
/// `bodies_000000.h5` the free surface's part after the bodies'.
#[cfg(feature = "hdf5")]
#[test]
fn an_hdf5_snapshot_holds_the_free_surface() {
    let dir = temp("h5");
    let mut sim = Simulation::new(scene_with("fs", "formats: [Vtk, Hdf5],")).unwrap();
    let ls = liquid(&sim, 0.6, 0.1);
    let phi = ls.phi.clone();
    sim.world.insert_resource(ls);
    let mut snaps = Snapshots::new(&dir, &sim);
    snaps.write(&sim).unwrap();
    let h5 = hdf5::File::open(dir.join("fields_000000.h5")).unwrap();
    let ds = h5.dataset("free_surface").unwrap();
    assert_eq!(ds.shape(), [32, 32, 32]);
    let v: Vec<f32> = ds.read_raw().unwrap();
    assert!(
        v.iter()
            .zip(&phi)
            .all(|(a, b)| (*a as f64 - b).abs() < 1e-6)
    );
    let xmf = std::fs::read_to_string(dir.join("fields.xmf")).unwrap();
    assert!(xmf.contains("free_surface"), "{xmf}");
    let b = hdf5::File::open(dir.join("bodies_000000.h5")).unwrap();
    let names: String = b
        .attr("part_names")
        .map(|a| format!("{:?}", a.read_raw::<hdf5::types::VarLenUnicode>().ok()))
        .unwrap_or_default();
    assert!(names.contains("free_surface"), "{names}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// In a closed tank the free surface's part ends at the walls: inside them φ_w is the fluid's
/// continued (so the surface runs on through the side walls), and the periodic box's seam
/// makes a second zero level in the floor and lid; neither is written.
#[test]
fn the_free_surface_part_stops_at_the_tank_walls() {
    let n = 32.0;
    let h = 1.0 / n;
    // Walls 0.06 thick across the seam (two cells on either side of it).
    let scene = Scene::parse(
        r#"Scene(
    name: "tank-out",
    domain: (extent: [1.0, 1.0, 1.0], cells: [32, 32, 32]),
    fluid: (density: 1.0, viscosity: 0.01, gravity: [0.0, 0.0, -1.0]),
    free_surface: Some((gas_density: 0.1, liquid: [Below(height: 0.41)])),
    numerics: (end_time: 0.01),
    bodies: [
        (name: "tank", shape: Complement(Box(half_extents: [0.44, 0.44, 0.44])), kind: Static, position: [0.5, 0.5, 0.5]),
    ],
    output: (fields: [Density]),
)"#,
        "tank.ron",
        "tank-out",
    )
    .unwrap();
    let sim = Simulation::new(scene).unwrap();
    // Without clipping the level reaches into the walls: the seam in the floor and lid.
    let ls = sim.world.resource::<LiquidLevelSet>();
    let raw = zero_level(sim.grid(), &ls.phi);
    let (lo, hi) = (0.06 - h, 0.94 + h);
    let outside = |p: &glam::DVec3| p.to_array().iter().any(|&x| x < lo || x > hi);
    assert!(
        raw.points.iter().any(|p| p.z < lo || p.z > hi),
        "the test needs a seam level in the walls"
    );
    assert!(raw.points.iter().any(outside));
    let dir = temp("tank");
    let mut snaps = Snapshots::new(&dir, &sim);
    snaps.write(&sim).unwrap();
    // Every point of the surfaces file (the tank's inner faces and the free surface) lies
    // within a cell of the tank's inner box, and the free surface at z = 0.41 is there.
    let vtp = std::fs::read_to_string(dir.join("bodies_000000.vtp")).unwrap();
    let start = vtp.find("<Points>").unwrap();
    let body = &vtp[start..];
    let open = body.find('>').unwrap() + 1;
    let data = &body[open..];
    let data = &data[data.find('>').unwrap() + 1..data.find("</DataArray>").unwrap()];
    let v: Vec<f64> = data
        .split_whitespace()
        .map(|x| x.parse().unwrap())
        .collect();
    let points: Vec<glam::DVec3> = v
        .chunks_exact(3)
        .map(|c| glam::DVec3::new(c[0], c[1], c[2]))
        .collect();
    let bad: Vec<_> = points.iter().filter(|p| outside(p)).collect();
    assert!(
        bad.is_empty(),
        "{} points outside the tank: {:?}",
        bad.len(),
        &bad[..bad.len().min(5)]
    );
    let at_level = points
        .iter()
        .filter(|p| (p.z - 0.41).abs() < 0.1 * h)
        .count();
    assert!(at_level > 500, "{at_level} points on the free surface");
    let _ = std::fs::remove_dir_all(&dir);
}
