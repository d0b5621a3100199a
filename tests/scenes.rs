//! Every bundled scene loads; bad scenes give errors that name the file, line and field.

use std::path::Path;
use tumble::scene::Scene;
use tumble::sim::engine::Simulation;

#[test]
fn every_bundled_scene_loads_and_steps() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut n = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "ron") {
            let scene = Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
            // One step at a small size: the scene's setup works end to end. Coarsen h by the
            // largest whole factor that keeps every extent a whole number (≥ 8) of cells.
            let h0 = scene.grid().h;
            let m = (1..=64)
                .rev()
                .find(|&m| {
                    scene.domain.extent.iter().all(|e| {
                        let c = e / (h0 * m as f64);
                        (c - c.round()).abs() < 1e-6 && c.round() >= 8.0
                    })
                })
                .unwrap_or(1);
            let scene = scene
                .edit(|s| {
                    s.domain.cells = None;
                    s.domain.h = Some(h0 * m as f64);
                })
                .unwrap_or_else(|e| panic!("{e}"));
            let mut sim =
                Simulation::new(scene).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            sim.step().unwrap();
            assert!(sim.sample().energy.is_finite());
            n += 1;
        }
    }
    assert!(n >= 4, "found only {n} scenes");
}

const GOOD: &str = r#"Scene(
    name: "t",
    domain: (
        extent: [1.0, 1.0],
        cells: [16, 16],
    ),
    fluid: (
        viscosity: 0.01,
    ),
    numerics: (
        end_time: 1.0,
    ),
)"#;

fn err(text: &str) -> tumble::scene::SceneError {
    Scene::parse(text, "bad.ron", "bad").expect_err("must be rejected")
}

#[test]
fn good_scene_parses() {
    let s = Scene::parse(GOOD, "good.ron", "good").unwrap();
    assert_eq!(s.grid().n, [16, 16, 1]);
}

#[test]
fn misspelt_field_names_line() {
    let e = err(&GOOD.replace("viscosity:", "viscosityy:"));
    assert_eq!(e.line, Some(8), "{e}");
    assert!(e.to_string().contains("bad.ron"));
    assert!(e.message.contains("viscosityy"), "{e}");
}

#[test]
fn wrong_type_names_line() {
    let e = err(&GOOD.replace("end_time: 1.0", "end_time: \"soon\""));
    assert_eq!(e.line, Some(11), "{e}");
}

#[test]
fn negative_viscosity_names_field_and_line() {
    let e = err(&GOOD.replace("viscosity: 0.01", "viscosity: -0.01"));
    assert_eq!(e.field.as_deref(), Some("fluid.viscosity"));
    assert_eq!(e.line, Some(8));
}

#[test]
fn zero_cells_rejected() {
    let e = err(&GOOD.replace("cells: [16, 16]", "cells: [0, 16]"));
    assert_eq!(e.field.as_deref(), Some("domain.cells"));
    assert_eq!(e.line, Some(5));
}

#[test]
fn extent_not_multiple_of_h_rejected() {
    let e = err(&GOOD.replace("cells: [16, 16]", "h: 0.3"));
    assert_eq!(e.field.as_deref(), Some("domain.h"));
    assert_eq!(e.line, Some(5));
    assert!(e.message.contains("multiple"), "{e}");
}

#[test]
fn unequal_spacing_rejected() {
    let e = err(&GOOD.replace("cells: [16, 16]", "cells: [16, 32]"));
    assert_eq!(e.field.as_deref(), Some("domain.cells"));
}

#[test]
fn malformed_ron_names_line() {
    let e = err(&GOOD.replace("end_time: 1.0,", "end_time: 1.0,,"));
    assert_eq!(e.line, Some(11), "{e}");
}

#[test]
fn three_d_field_in_2d_rejected() {
    let text = GOOD.replace(
        "    numerics:",
        "    initial: [TaylorGreen3d()],\n    numerics:",
    );
    let e = err(&text);
    assert!(e.message.contains("3D"), "{e}");
}

#[test]
fn missing_file_is_an_error() {
    let e = Scene::load(Path::new("/no/such/scene.ron")).unwrap_err();
    assert!(e.message.contains("cannot read"));
}

#[test]
fn vacuum_without_dynamic_bodies_rejected() {
    let e = err(&GOOD.replace("    name: \"t\",", "    name: \"t\",\n    vacuum: true,"));
    assert_eq!(e.field.as_deref(), Some("vacuum"), "{e}");
    assert_eq!(e.line, Some(3), "{e}");
}

#[test]
fn contact_pair_with_unknown_body_rejected() {
    let text = GOOD.replace(
        "    numerics: (",
        "    bodies: [(name: \"ball\", shape: Disk(radius: 0.1), position: [0.5, 0.5])],\n    contact: (pairs: [(bodies: (\"ball\", \"wall\"), kappa: 3.0)]),\n    numerics: (",
    );
    let e = err(&text);
    assert!(e.message.contains("`wall`"), "{e}");
    assert!(e.line.is_some(), "{e}");
}

#[test]
fn negative_kappa_rejected() {
    let e = err(&GOOD.replace(
        "    numerics: (",
        "    contact: (kappa: -1.0),\n    numerics: (",
    ));
    assert!(
        e.field.as_deref().is_some_and(|f| f.contains("kappa")),
        "{e}"
    );
}

#[test]
fn absurd_grid_rejected_without_overflow() {
    let e = err(&GOOD.replace(
        "cells: [16, 16]",
        "cells: [18446744073709551615, 18446744073709551615]",
    ));
    assert_eq!(e.field.as_deref(), Some("domain.cells"), "{e}");
    assert_eq!(e.line, Some(5), "{e}");
    assert!(e.message.contains("nodes"), "{e}");
    let e = err(&GOOD.replace("cells: [16, 16]", "h: 1e-300"));
    assert_eq!(e.field.as_deref(), Some("domain.h"), "{e}");
}

#[test]
fn output_formats_default_to_vtk_and_hdf5_needs_the_feature() {
    use tumble::scene::OutputFormat;
    let s = Scene::parse(GOOD, "good.ron", "good").unwrap();
    assert_eq!(s.output.formats, vec![OutputFormat::Vtk]);
    let text = GOOD.replace(
        "    numerics: (",
        "    output: (\n        formats: [Vtk, Hdf5],\n    ),\n    numerics: (",
    );
    let r = Scene::parse(&text, "h5.ron", "h5");
    if cfg!(feature = "hdf5") {
        assert!(r.is_ok());
    } else {
        let e = r.unwrap_err();
        assert_eq!(e.field.as_deref(), Some("output.formats"), "{e}");
        assert_eq!(e.line, Some(11), "{e}");
        assert!(e.to_string().contains("h5.ron") && e.message.contains("--features hdf5"));
    }
    let e = err(&GOOD.replace(
        "    numerics: (",
        "    output: (formats: []),\n    numerics: (",
    ));
    assert_eq!(e.field.as_deref(), Some("output.formats"), "{e}");
    let e = err(&GOOD.replace(
        "    numerics: (",
        "    output: (formats: [Vtk, Netcdf]),\n    numerics: (",
    ));
    assert!(e.message.contains("Netcdf"), "{e}");
}
