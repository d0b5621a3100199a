//! `stratified-rest`: a two-layer fluid at rest between two walls stays at rest.

use crate::base::grid::Grid;
use crate::scene::Scene;
use crate::validate::{Case, Report, Row, RunTime};

/// The case: what it checks, against what, and the rows known to fail.
pub const CASE: Case = Case {
    name: "stratified-rest",
    description: "a two-layer fluid at rest (density 10 below 1, walls above and below) stays at rest: max |u| below 1e-6 sqrt(g L) for 1000 steps",
    reference: "hydrostatics (exact discrete balance)",
    full: "2D 96^2 and 3D 32^3",
    quick: "2D 48^2",
    full_time: RunTime::Seconds,
    quick_time: RunTime::Seconds,
    run: stratified_rest,
    known_failures: &[],
};

/// Writes a two-layer fluid into the fluid-phase density at startup: 10 below the middle
/// of the box in the direction of gravity (the last axis), 1 above, as a free surface will.
struct TwoLayers;

impl crate::schedule::Plugin for TwoLayers {
    fn name(&self) -> &'static str {
        "two_layers"
    }

    fn build(&self, ctx: &mut crate::schedule::PluginContext) -> anyhow::Result<()> {
        use bevy_ecs::prelude::*;
        fn layers(grid: Res<Grid>, mut bf: ResMut<crate::bodies::BodyFields>) {
            let (a, mid) = (grid.dim - 1, 0.5 * grid.extent()[grid.dim - 1]);
            for k in 0..grid.n[2] {
                for j in 0..grid.n[1] {
                    for i in 0..grid.n[0] {
                        let high = grid.pos(i, j, k)[a] >= mid;
                        bf.rho_phase[grid.idx(i, j, k)] = if high { 1.0 } else { 10.0 };
                    }
                }
            }
        }
        ctx.add_startup_system("two_layers", layers)
    }
}

/// A two-layer fluid at rest, density ratio 1:10, between two walls, its density written by a
/// plugin into the fluid-phase density (as a free surface will be): max |u| must stay at
/// round-off for 1000 steps. What this can catch is limited: in the vorticity form, a
/// correction that depends on the height alone has no curl, so any discretisation that keeps
/// the horizontal translation invariance keeps these layers at rest; the case fails on
/// anything that breaks it (the solver's stencil, the walls' penalization, the phase density
/// not reaching the model). It cannot see the imbalance of a layering tilted to the grid.
fn stratified_rest(quick: bool) -> anyhow::Result<Report> {
    let mut rep = Report::new("stratified-rest");
    let (g, l) = (9.81f64, 1.0f64);
    let runs: &[(usize, usize)] = if quick {
        &[(2, 48)]
    } else {
        &[(2, 96), (3, 32)]
    };
    for &(dim, n) in runs {
        let text = if dim == 2 {
            format!(
                r#"Scene(
                name: "stratified-rest",
                domain: (extent: [1.0, 1.0], cells: [{n}, {n}]),
                fluid: (viscosity: 0.01, gravity: [0.0, -9.81]),
                numerics: (end_time: 10.0, dt: Fixed(0.001), body_coupling: Pressure),
                bodies: [(name: "walls", shape: Complement(Rectangle(half_extents: [0.6, 0.4])),
                          kind: Static, position: [0.5, 0.5])],
            )"#
            )
        } else {
            format!(
                r#"Scene(
                name: "stratified-rest",
                domain: (extent: [1.0, 1.0, 1.0], cells: [{n}, {n}, {n}]),
                fluid: (viscosity: 0.01, gravity: [0.0, 0.0, -9.81]),
                numerics: (end_time: 10.0, dt: Fixed(0.001), body_coupling: Pressure),
                bodies: [(name: "walls", shape: Complement(Box(half_extents: [0.6, 0.6, 0.4])),
                          kind: Static, position: [0.5, 0.5, 0.5])],
            )"#
            )
        };
        let scene = Scene::parse(&text, "stratified-rest", "stratified-rest")?;
        let mut sim = crate::validate::builder(scene)
            .add_plugin(TwoLayers)
            .build()?;
        let mut umax = 0.0f64;
        for _ in 0..1000 {
            sim.step()?;
            for c in &sim.fields().u {
                umax = c.iter().fold(umax, |m, v| m.max(v.abs()));
            }
        }
        let bf = sim.world.resource::<crate::bodies::BodyFields>();
        let (lo, hi) = bf
            .rho
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(a, b), &r| (a.min(r), b.max(r)));
        // Over every process's slab when split.
        let split = sim.world.get_resource::<crate::parallel::Decomposition>();
        let global_max = |x: f64| crate::parallel::global_max(split, x);
        let (umax, lo, hi) = (global_max(umax), -global_max(-lo), global_max(hi));
        rep.rows.push(Row::yes_no(
            format!("{dim}D {n} cells per side: the density field holds both layers (1 and 10)"),
            lo == 1.0 && hi == 10.0,
        ));
        rep.rows.push(Row::abs(
            format!("{dim}D {n} cells per side: max |u| / sqrt(g L) over 1000 steps"),
            0.0,
            umax / (g * l).sqrt(),
            1e-6,
        ));
    }
    Ok(rep)
}
