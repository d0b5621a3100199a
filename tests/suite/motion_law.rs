//! Which dynamic bodies move by Newton-Euler with their own mass (`MotionLaw`): those at least
//! twice as heavy as the largest added mass their shape can have, so that the explicit update,
//! which amplifies an error by m_a / m per step, is stable. The thresholds below are the
//! analytic added masses: a sphere's is ρ_F V / 2, a disk's ρ_F A, an ellipse's broadside
//! ρ_F π a² (a the semi-axis across the motion; Lamb, Hydrodynamics, sections 71 and 92).

use std::path::Path;
use tumble::bodies::coupling::{MotionLaw, motion_law};
use tumble::bodies::levelset::LocalLevelSet;
use tumble::bodies::shapes::Shape;

fn law(shape: Shape, dim: usize, density: f64) -> MotionLaw {
    let h = 1.0 / 64.0;
    let geom = shape.build(Path::new(".")).expect("shape");
    let ls = LocalLevelSet::new(geom, h, 4.0 * h, dim);
    motion_law(&ls, h, dim, density, 1.0)
}

/// A sphere (m_a = V/2): Newton-Euler from density 1 (twice its added mass), not below.
#[test]
fn sphere_moves_by_newton_euler_from_twice_its_added_mass() {
    let s = || Shape::Sphere { radius: 0.1 };
    assert_eq!(law(s(), 3, 0.9), MotionLaw::Projected);
    assert_eq!(law(s(), 3, 1.1), MotionLaw::NewtonEuler);
    assert_eq!(law(s(), 3, 1000.0), MotionLaw::NewtonEuler);
}

/// A disk (m_a = A): from density 2.
#[test]
fn disk_moves_by_newton_euler_from_twice_its_added_mass() {
    let d = || Shape::Disk { radius: 0.1 };
    assert_eq!(law(d(), 2, 1.8), MotionLaw::Projected);
    assert_eq!(law(d(), 2, 2.2), MotionLaw::NewtonEuler);
}

/// An ellipse of aspect ratio 10 moving broadside has ten times the added mass of its own
/// fluid: at density 5 the explicit update would amplify an error twofold per step, so it
/// stays with the projection; at 50 (m_a / m = 0.2) it moves by Newton-Euler.
#[test]
fn thin_ellipse_needs_its_broadside_added_mass() {
    let e = || Shape::Ellipse { radii: [0.2, 0.02] };
    assert_eq!(law(e(), 2, 5.0), MotionLaw::Projected);
    assert_eq!(law(e(), 2, 50.0), MotionLaw::NewtonEuler);
}

/// A cube of half-side 0.1 (added mass about 0.7 of its displaced fluid; the bound from its
/// equivalent ellipsoid is 0.69, so Newton-Euler from density 1.4): at density 3, not at 0.5.
#[test]
fn cube_is_classified_by_its_shape() {
    let b = || Shape::Box {
        half_extents: [0.1, 0.1, 0.1],
    };
    assert_eq!(law(b(), 3, 0.5), MotionLaw::Projected);
    assert_eq!(law(b(), 3, 3.0), MotionLaw::NewtonEuler);
}

/// The momentum of a Newton-Euler body's step: over `rigid_velocity`, the contact and the
/// penalization, the flow's momentum ∫ρu changes by exactly what the body's excess mass E loses,
/// -E (V^{n+1} - V^n), with gravity off: the rigid region's weights, its centroid and the
/// body's update are one balance, to round-off.
mod conservation {
    use bevy_ecs::prelude::*;
    use glam::DVec3;
    use tumble::base::fields::Fields;
    use tumble::base::grid::Grid;
    use tumble::bodies::{Body, BodyFields, Material, RigidState};
    use tumble::scene::Scene;
    use tumble::schedule::{PhysicsSet, Plugin, PluginContext};
    use tumble::sim::engine::Simulation;

    /// ∫ρu before the body's velocity is updated, and the velocity then; the largest error seen.
    #[derive(Resource, Default)]
    struct Balance {
        before: DVec3,
        v_before: DVec3,
        worst: f64,
        scale: f64,
        checked: usize,
    }

    fn momentum(grid: &Grid, fields: &Fields, bf: &BodyFields) -> DVec3 {
        let mut p = DVec3::ZERO;
        for q in 0..grid.dim {
            p[q] = fields.u[q]
                .iter()
                .zip(&bf.rho)
                .map(|(u, r)| u * r)
                .sum::<f64>()
                * grid.cell_volume();
        }
        p
    }

    fn before(
        grid: Res<Grid>,
        fields: Res<Fields>,
        bf: Res<BodyFields>,
        mut bal: ResMut<Balance>,
        bodies: Query<(&Body, &RigidState)>,
    ) {
        bal.before = momentum(&grid, &fields, &bf);
        bal.v_before = bodies.iter().next().map(|b| b.1.velocity).unwrap();
    }

    fn after(
        grid: Res<Grid>,
        fields: Res<Fields>,
        bf: Res<BodyFields>,
        mut bal: ResMut<Balance>,
        bodies: Query<(&Body, &Material, &RigidState)>,
    ) {
        let (_, mat, st) = bodies.iter().next().unwrap();
        // The fluid is of density 1: E = (ρ_i - 1) |S_i|.
        let e = (mat.density - 1.0) * st.volume;
        let gained = momentum(&grid, &fields, &bf) - bal.before;
        let lost = -e * (st.velocity - bal.v_before);
        if fields.dt_prev > 0.0 {
            bal.worst = bal.worst.max((gained - lost).length());
            bal.scale = bal.scale.max(gained.length());
            bal.checked += 1;
        }
    }

    struct Probe;
    impl Plugin for Probe {
        fn name(&self) -> &'static str {
            "momentum_probe"
        }
        fn build(&self, ctx: &mut PluginContext) -> anyhow::Result<()> {
            ctx.insert_resource(Balance::default());
            ctx.add_system(PhysicsSet::Density, "momentum_before", before)?;
            ctx.add_system(PhysicsSet::Penalization, "momentum_after", after)
        }
    }

    /// A sphere of density 5 (Newton-Euler) launched through fluid at rest, no gravity, 3D.
    #[test]
    fn newton_euler_step_conserves_momentum_to_round_off() {
        let text = r#"Scene(
            name: "momentum",
            domain: (extent: [1.0, 1.0, 1.0], cells: [24, 24, 24]),
            fluid: (viscosity: 0.01, gravity: [0.0, 0.0, 0.0]),
            numerics: (end_time: 0.05),
            bodies: [(name: "sphere", shape: Sphere(radius: 0.15), density: 5.0,
                      position: [0.5, 0.5, 0.5], velocity: [0.3, 0.1, -0.2],
                      angular_velocity: [0.0, 0.0, 2.0])],
        )"#;
        let scene = Scene::parse(text, "momentum", "momentum").unwrap();
        let mut sim = Simulation::builder(scene)
            .add_plugin(Probe)
            .build()
            .unwrap();
        for _ in 0..8 {
            sim.step().unwrap();
        }
        let bal = sim.world.resource::<Balance>();
        eprintln!(
            "{} steps: largest |d(rho u) + E dV| = {:.3e}, |d(rho u)| up to {:.3e}",
            bal.checked, bal.worst, bal.scale
        );
        assert!(bal.checked >= 7);
        assert!(bal.scale > 1e-6, "the body exchanged no momentum");
        assert!(bal.worst <= 1e-12 * bal.scale.max(1.0), "{}", bal.worst);
    }
}
