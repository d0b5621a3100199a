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

/// A scene with two entries in each list (lines numbered in the comments), to check that an
/// error in the second entry points at the second entry.
const LISTS: &str = r#"Scene(
    name: "lists",
    domain: (extent: [2.0, 2.0], cells: [32, 32]),
    initial: [
        LambOseen(center: [0.5, 0.5], circulation: 1.0, core_radius: 0.1),
        LambOseen(
            center: [1.5, 1.5],
            circulation: 1.0,
            core_radius: 0.1,
        ),
    ],
    bodies: [
        (name: "a", shape: Disk(radius: 0.1), density: 2.0, position: [0.5, 1.5]),
        (
            name: "b",
            shape: Disk(radius: 0.1),
            density: 2.0,
            position: [1.5, 0.5],
        ),
    ],
    contact: (pairs: [
        (bodies: ("a", "b"), kappa: 1.0),
        (bodies: ("b", "a"),
         kappa: 2.0),
    ]),
)"#;

#[test]
fn list_scene_is_valid() {
    let s = Scene::parse(LISTS, "lists.ron", "lists").unwrap_or_else(|e| panic!("{e}"));
    assert_eq!((s.initial.len(), s.bodies.len()), (2, 2));
}

#[test]
fn error_in_second_initial_entry_points_at_it() {
    // Line 9 is the second entry's core_radius; line 5 would be the first entry's.
    let e = err(&LISTS.replace("core_radius: 0.1,\n", "core_radius: -0.1,\n"));
    assert_eq!(e.field.as_deref(), Some("initial[1].core_radius"), "{e}");
    assert_eq!(e.line, Some(9), "{e}");
    // The first entry is found as well (line 5).
    let e = err(&LISTS.replace(
        "circulation: 1.0, core_radius: 0.1)",
        "circulation: 1.0, core_radius: 0.0)",
    ));
    assert_eq!(e.field.as_deref(), Some("initial[0].core_radius"), "{e}");
    assert_eq!(e.line, Some(5), "{e}");
}

#[test]
fn error_in_second_body_points_at_it() {
    // The second body's density is on line 17, its position on line 18.
    let e = err(&LISTS.replace("density: 2.0,\n", "density: -2.0,\n"));
    assert_eq!(e.field.as_deref(), Some("bodies[1].density"), "{e}");
    assert_eq!(e.line, Some(17), "{e}");
    assert!(e.message.contains("`b`"), "{e}");
    let e = err(&LISTS.replace("position: [1.5, 0.5]", "position: [1.5]"));
    assert_eq!(e.field.as_deref(), Some("bodies[1].position"), "{e}");
    assert_eq!(e.line, Some(18), "{e}");
    // Overlapping bodies name the later one, at its position (line 18).
    let e = err(&LISTS.replace("position: [1.5, 0.5]", "position: [0.55, 1.5]"));
    assert_eq!(e.field.as_deref(), Some("bodies[1].position"), "{e}");
    assert_eq!(e.line, Some(18), "{e}");
    assert!(e.message.contains("overlap"), "{e}");
}

#[test]
fn error_in_second_contact_pair_points_at_it() {
    // The second pair's kappa is on line 24, its names on line 23.
    let e = err(&LISTS.replace("kappa: 2.0", "kappa: -2.0"));
    assert_eq!(e.field.as_deref(), Some("contact.pairs[1].kappa"), "{e}");
    assert_eq!(e.line, Some(24), "{e}");
    let e = err(&LISTS.replace("(\"b\", \"a\")", "(\"b\", \"c\")"));
    assert_eq!(e.field.as_deref(), Some("contact.pairs[1].bodies"), "{e}");
    assert_eq!(e.line, Some(23), "{e}");
}

#[test]
fn wrong_type_names_the_field() {
    // Issue 15: `end_time: "0.01"` said only `line 5: Expected float (column 43)`.
    let text = r#"Scene(domain: (extent: [1.0, 1.0], cells: [16, 16]),
    numerics: (dt: Fixed(0.01), end_time: "0.01"))"#;
    let e = err(text);
    assert_eq!(e.field.as_deref(), Some("numerics.end_time"), "{e}");
    assert_eq!(e.line, Some(2), "{e}");
    assert!(e.to_string().contains("field `numerics.end_time`"), "{e}");
    // Inside a list entry, the entry is named.
    let e = err(&LISTS.replace("circulation: 1.0,\n", "circulation: \"one\",\n"));
    assert_eq!(e.field.as_deref(), Some("initial[1].circulation"), "{e}");
    assert_eq!(e.line, Some(8), "{e}");
    // And in a body's shape.
    let e = err(&LISTS.replace(
        "shape: Disk(radius: 0.1),\n",
        "shape: Disk(radius: [0.1]),\n",
    ));
    assert_eq!(e.field.as_deref(), Some("bodies[1].shape.radius"), "{e}");
}

#[test]
fn name_must_be_plain() {
    for bad in ["../x", "/", ".", "..", "a/b", "a\\\\b"] {
        let e = err(&GOOD.replace("name: \"t\"", &format!("name: \"{bad}\"")));
        assert_eq!(e.field.as_deref(), Some("name"), "{bad}: {e}");
        assert_eq!(e.line, Some(2), "{bad}: {e}");
        assert!(e.message.contains("plain name"), "{bad}: {e}");
    }
    // No name and no file name to default to.
    let text = GOOD.replace("    name: \"t\",\n", "");
    let e = Scene::parse(&text, "<scene>", "").unwrap_err();
    assert_eq!(e.field.as_deref(), Some("name"), "{e}");
    // The same check guards a scene changed in code.
    let s = Scene::parse(GOOD, "good.ron", "good").unwrap();
    let e = s.edit(|s| s.name = "../up".into()).unwrap_err();
    assert_eq!(e.field.as_deref(), Some("name"), "{e}");
}

#[test]
fn scene_named_up_is_rejected_at_load() {
    let dir = std::env::temp_dir().join(format!("tumble-scene-name-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("up.ron");
    std::fs::write(&path, GOOD.replace("name: \"t\"", "name: \"../x\"")).unwrap();
    let e = Scene::load(&path).unwrap_err();
    std::fs::remove_dir_all(&dir).unwrap();
    assert_eq!(e.field.as_deref(), Some("name"), "{e}");
    assert!(e.to_string().contains("up.ron"), "{e}");
}

#[test]
fn edit_checks_again() {
    let s = Scene::parse(GOOD, "good.ron", "good").unwrap();
    let s = s.edit(|s| s.domain.cells = Some(vec![32, 32])).unwrap();
    assert_eq!(s.grid().n, [32, 32, 1]);
    assert_eq!(s.grid().h, 1.0 / 32.0);
    let e = s.edit(|s| s.domain.cells = Some(vec![32, 16])).unwrap_err();
    assert_eq!(e.field.as_deref(), Some("domain.cells"), "{e}");
    assert_eq!(e.file, "good.ron");
}

#[test]
fn leftover_numerics_live_under_experimental() {
    use tumble::scene::RemeshKernel;
    // The old top-level keys are gone: the error names the unknown field.
    let e = err(&GOOD.replace("end_time: 1.0,", "end_time: 1.0, midpoint_velocity: false,"));
    assert!(e.message.contains("midpoint_velocity"), "{e}");
    let text = GOOD.replace(
        "end_time: 1.0,",
        "end_time: 1.0, experimental: (midpoint_velocity: false, remesh_kernel: Lambda42),",
    );
    let s = Scene::parse(&text, "x.ron", "x").unwrap_or_else(|e| panic!("{e}"));
    let x = &s.numerics.experimental;
    assert!(!x.midpoint_velocity);
    assert_eq!(x.remesh_kernel, RemeshKernel::Lambda42);
    // Written back when set, left out at the defaults.
    assert!(s.to_ron().contains("experimental"));
    let d = Scene::parse(GOOD, "good.ron", "good").unwrap();
    assert!(d.numerics.experimental.midpoint_velocity);
    assert_eq!(d.numerics.experimental.remesh_kernel, RemeshKernel::M4Prime);
    assert!(!d.to_ron().contains("experimental"), "{}", d.to_ron());
}

#[test]
fn free_surface_ratio_beyond_the_tested_one_warns_with_its_line() {
    let text = |gas: &str| {
        format!(
            r#"Scene(
    name: "pool",
    domain: (origin: [0.0, -0.125], extent: [1.0, 1.25], h: 0.0625),
    fluid: (density: 1.0, viscosity: 0.001, gravity: [0.0, -1.0]),
    free_surface: Some((
        gas_density: {gas},
        liquid: [Below(height: 0.5)],
    )),
    bodies: [
        (name: "floor", shape: HalfSpace(normal: [0.0, 1.0, 0.0], offset: 0.0), kind: Static, position: [0.0, 0.0]),
        (name: "lid", shape: HalfSpace(normal: [0.0, -1.0, 0.0], offset: -1.0), kind: Static, position: [0.0, 0.0]),
    ],
)"#
        )
    };
    let ok = tumble::scene::Scene::parse(&text("0.001"), "pool.ron", "pool").unwrap();
    assert!(ok.warnings().iter().all(|w| !w.contains("gas_density")));
    let far = tumble::scene::Scene::parse(&text("0.0001"), "pool.ron", "pool").unwrap();
    let w = far.warnings();
    assert!(
        w.iter()
            .any(|w| w.contains("pool.ron, line 6") && w.contains("1:10000")),
        "{w:?}"
    );
}
