//! Helpers shared by several cases.

use crate::scene::ValidScene;
use crate::sim::engine::Simulation;
use crate::validate::bundled_scene;

/// The state of the first dynamic body.
pub(crate) fn dynamic_body(sim: &mut Simulation) -> Option<crate::bodies::RigidState> {
    let mut q = sim
        .world
        .query::<(&crate::bodies::Body, &crate::bodies::RigidState)>();
    q.iter(&sim.world)
        .find(|(b, _)| b.is_dynamic())
        .map(|(_, s)| *s)
}

/// The coupling the issue-16 rows measure, as a line for a scene's `numerics` block: the
/// default (`Pressure`), written out so the reports say which.
pub(super) const MODEL: &str = "body_coupling: Pressure";

/// The Table 1 tube (`scenes/sphere-settling.ron`) at grid step `h` with a sphere of diameter
/// `d` (or the mesh file `mesh`, relative to `scenes/`), viscosity `nu`, and its time-step
/// policy passed through `dt`. The periodic box is the tube's [0,1]² grown by 2 cells of wall
/// on each side in x and y; the tube's caps keep 2 cells of wall.
pub(super) fn tube_scene(
    h: f64,
    d: f64,
    nu: f64,
    mesh: Option<&str>,
    dt: impl FnOnce(&mut crate::scene::TimeStep),
) -> anyhow::Result<ValidScene> {
    let wall = 2.0 * h;
    Ok(bundled_scene("sphere-settling.ron")?.edit(|scene| {
        dt(&mut scene.numerics.dt);
        scene.base_dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
        scene.domain.origin = Some(vec![-wall, -wall, 0.0]);
        scene.domain.extent = vec![1.0 + 2.0 * wall, 1.0 + 2.0 * wall, 4.0];
        scene.domain.h = Some(h);
        scene.domain.cells = None;
        scene.fluid.viscosity = nu;
        for b in &mut scene.bodies {
            match &mut b.shape {
                crate::bodies::shapes::Shape::Sphere { radius } => {
                    *radius = 0.5 * d;
                    if let Some(file) = mesh {
                        b.shape = crate::bodies::shapes::Shape::Mesh {
                            file: file.to_string(),
                            scale: 1.0,
                        };
                    }
                }
                crate::bodies::shapes::Shape::Complement(inner) => {
                    **inner = crate::bodies::shapes::Shape::Cylinder {
                        radius: 0.5,
                        half_height: 2.0 - wall,
                    }
                }
                _ => {}
            }
        }
    })?)
}
