//! Helpers shared by several cases: the bodies' states and energies, the Table 1 tube, and
//! the free-surface cases' 2D tank and its surface height.

use crate::bodies::free_surface::LiquidLevelSet;
use crate::bodies::{Body, ContactState, Material, RigidState};
use crate::scene::{Scene, ValidScene};
use crate::sim::engine::Simulation;
use crate::validate::{PlotSpec, bundled_scene};
use glam::DVec3;

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

/// State of every dynamic body: (name, state, density, contact potential).
pub(super) fn dynamic_states(sim: &mut Simulation) -> Vec<(String, RigidState, f64, f64)> {
    let mut q = sim
        .world
        .query::<(&Body, &RigidState, &Material, &ContactState)>();
    let mut v: Vec<_> = q
        .iter(&sim.world)
        .filter(|(b, _, _, _)| b.is_dynamic())
        .map(|(b, s, m, c)| (b.id, b.name.clone(), *s, m.density, c.potential))
        .collect();
    v.sort_by_key(|e| e.0);
    v.into_iter().map(|(_, n, s, d, p)| (n, s, d, p)).collect()
}

/// Kinetic plus potential energy of a body (potential zero at height `z0` along gravity `g`).
pub(super) fn energy(s: &RigidState, density: f64, g: DVec3, x0: DVec3) -> f64 {
    let m = density * s.volume;
    let jw = density * (s.inertia * s.angular_velocity);
    0.5 * m * s.velocity.length_squared() + 0.5 * s.angular_velocity.dot(jw)
        - m * g.dot(s.center - x0)
}

/// The leapfrog state at the previous positions: symplectic Euler leaves x_{k+1} and
/// v_{k+1/2} after step k, so the energy of x_k is taken with v_k = (v_{k-1/2} + v_{k+1/2})/2
/// (and likewise Ω); `prev` is the state after step k-1, `s` after step k.
pub(super) fn leapfrog_mid(prev: &RigidState, s: &RigidState) -> RigidState {
    RigidState {
        center: prev.center,
        velocity: 0.5 * (prev.velocity + s.velocity),
        angular_velocity: 0.5 * (prev.angular_velocity + s.angular_velocity),
        ..*s
    }
}

/// The smallest gap among spheres of radius `r` (pairwise) and between them and the walls of
/// the box [lo, hi]³ (negative: an overlap).
pub(super) fn smallest_sphere_gap<'a>(
    states: impl Iterator<Item = &'a RigidState> + Clone,
    r: f64,
    lo: f64,
    hi: f64,
) -> f64 {
    let mut worst = f64::INFINITY;
    for (a, sa) in states.clone().enumerate() {
        for ax in 0..3 {
            let c = sa.center[ax];
            worst = worst.min((c - lo - r).min(hi - c - r));
        }
        for sb in states.clone().skip(a + 1) {
            worst = worst.min((sb.center - sa.center).length() - 2.0 * r);
        }
    }
    worst
}

/// The geometry of a `tank-200` scene, read from the scene itself: the walls of the cubic box
/// (the first body, the outside of a centred box) as [lo, hi] on every axis, and the radius of
/// the spheres (the second body).
pub(super) fn tank_geometry(scene: &crate::scene::Scene) -> anyhow::Result<(f64, f64, f64)> {
    use crate::bodies::shapes::Shape;
    let (Some(tank), Some(sphere)) = (scene.bodies.first(), scene.bodies.get(1)) else {
        anyhow::bail!("the tank scene needs the box and at least one sphere");
    };
    let Shape::Complement(inner) = &tank.shape else {
        anyhow::bail!("the tank scene's first body must be the outside of a box");
    };
    let Shape::Box { half_extents } = **inner else {
        anyhow::bail!("the tank scene's first body must be the outside of a box");
    };
    let Shape::Sphere { radius } = sphere.shape else {
        anyhow::bail!("the tank scene's second body must be a sphere");
    };
    let c = tank.position.first().copied().unwrap_or(0.0);
    Ok((c - half_extents[0], c + half_extents[0], radius))
}

/// The relative change of the total energy against t, with the exact value 0 (the cases allow
/// 5%; the tolerance is not drawn, it would flatten the curve).
pub(super) fn energy_plot(echange: Vec<(f64, f64)>) -> PlotSpec {
    PlotSpec::new(
        "energy",
        "total energy (kinetic + gravity + contact)",
        "t",
        "(E - E0) / E0",
    )
    .measured("measured", echange)
    .reference_level("exact: conserved", 0.0)
}

/// A 2D tank `width` wide: floor at y = 0, lid at y = `top`, two cells of wall beyond each,
/// grid step `h`; the liquid (density 1) fills `liquid` (a RON list of regions), the gas has
/// density `gas`; gravity -g along y. `bodies` are more RON body entries.
#[allow(clippy::too_many_arguments)]
pub(super) fn tank(
    name: &str,
    width: f64,
    top: f64,
    h: f64,
    gas: f64,
    liquid: &str,
    g: f64,
    nu: f64,
    end: f64,
    bodies: &str,
) -> anyhow::Result<crate::scene::ValidScene> {
    let text = format!(
        r#"Scene(
        name: "{name}",
        domain: (origin: [0.0, {o}], extent: [{width}, {e}], h: {h}),
        fluid: (density: 1.0, viscosity: {nu}, gravity: [0.0, {mg}]),
        free_surface: Some((gas_density: {gas}, liquid: {liquid})),
        numerics: (end_time: {end}),
        bodies: [
            (name: "floor", shape: HalfSpace(normal: [0.0, 1.0, 0.0], offset: 0.0), kind: Static, position: [0.0, 0.0]),
            (name: "lid", shape: HalfSpace(normal: [0.0, -1.0, 0.0], offset: {mtop}), kind: Static, position: [0.0, 0.0]),
            {bodies}
        ],
    )"#,
        o = -2.0 * h,
        e = top + 4.0 * h,
        mg = -g,
        mtop = -top,
    );
    Ok(Scene::parse(&text, name, name)?)
}

/// Height of the free surface in column `i` (2D): the zero of φ_w nearest to `guess` along
/// y, by linear interpolation between the two nodes around it.
pub fn surface_height(sim: &Simulation, i: usize, guess: f64) -> f64 {
    let grid = sim.grid();
    let phi = &sim.world.resource::<LiquidLevelSet>().phi;
    let [nx, ny, _] = grid.n;
    let mut best = f64::NAN;
    for j in 0..ny - 1 {
        let (p, q) = (phi[i + nx * j], phi[i + nx * (j + 1)]);
        if (p > 0.0) != (q > 0.0) {
            let y = grid.pos(i, j, 0)[1] + grid.h * p / (p - q);
            if best.is_nan() || (y - guess).abs() < (best - guess).abs() {
                best = y;
            }
        }
    }
    best
}

/// The gas : liquid density ratios of the free-surface gates, up to air and water (1:1000,
/// issue 34), in both tiers.
pub(super) const RATIOS: [f64; 3] = [10.0, 100.0, 1000.0];
