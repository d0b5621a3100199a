//! The variable-density pressure projection (`numerics.body_coupling: Pressure`,
//! `systems/pressure.rs`) on a density field that is not only bodies: a stratified two-layer
//! fluid at rest, density ratio 1:10, written into the fluid-phase density `rho_phase` by a
//! plugin (as a free surface will be), must stay at rest. (In the vorticity form a correction
//! that depends on the height alone has no curl, so this fails only on what breaks the
//! horizontal translation invariance: the solver's stencil, the walls' penalization, the phase
//! density not reaching the model; `tumble validate stratified-rest` runs the same in 2D and
//! 3D.)

use bevy_ecs::prelude::*;
use tumble::base::grid::Grid;
use tumble::bodies::BodyFields;
use tumble::scene::Scene;
use tumble::schedule::{Plugin, PluginContext};
use tumble::sim::engine::Simulation;

/// Heavy fluid (10) below y = 0.5, light (1) above.
struct TwoLayers;

fn layers(grid: Res<Grid>, mut bf: ResMut<BodyFields>) {
    for j in 0..grid.n[1] {
        for i in 0..grid.n[0] {
            let y = grid.pos(i, j, 0)[1];
            bf.rho_phase[grid.idx(i, j, 0)] = if y < 0.5 { 10.0 } else { 1.0 };
        }
    }
}

impl Plugin for TwoLayers {
    fn name(&self) -> &'static str {
        "two_layers"
    }
    fn build(&self, ctx: &mut PluginContext) -> anyhow::Result<()> {
        ctx.add_startup_system("two_layers", layers)
    }
}

#[test]
fn stratified_two_layer_fluid_stays_at_rest() {
    let (g, l) = (9.81f64, 1.0f64);
    let text = r#"Scene(
        name: "stratified",
        domain: (extent: [1.0, 1.0], cells: [48, 48]),
        fluid: (viscosity: 0.01, density: 1.0, gravity: [0.0, -9.81]),
        numerics: (end_time: 1.0, dt: Fixed(0.001), body_coupling: Pressure),
        bodies: [(name: "walls", shape: Complement(Rectangle(half_extents: [0.6, 0.4])),
                  kind: Static, position: [0.5, 0.5])],
    )"#;
    let scene = Scene::parse(text, "stratified", "stratified").unwrap();
    let mut sim = Simulation::builder(scene)
        .add_plugin(TwoLayers)
        .build()
        .unwrap();
    let mut umax = 0.0f64;
    for _ in 0..1000 {
        sim.step().unwrap();
        for c in &sim.fields().u {
            umax = c.iter().fold(umax, |m, v| m.max(v.abs()));
        }
    }
    // The layers really are there: the density field holds both.
    let bf = sim.world.resource::<BodyFields>();
    let (lo, hi) = bf
        .rho
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(a, b), &r| (a.min(r), b.max(r)));
    assert_eq!((lo, hi), (1.0, 10.0));
    let bound = 1e-6 * (g * l).sqrt();
    assert!(
        umax < bound,
        "max |u| over 1000 steps {umax:.3e}, asked below {bound:.3e}"
    );
}
