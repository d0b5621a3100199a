//! From a validated scene to the world's body entities and its free surface. The typed
//! resources, `Params` and `ContactParams`, were made when the scene was checked, with its
//! defaults ([`crate::scene::Resolved`]).

use crate::base::grid::Grid;
use crate::base::params::BodyCoupling;
use crate::bodies::coupling::{MotionLaw, VirtualMass, newton_euler};
use crate::bodies::levelset::LocalLevelSet;
use crate::bodies::{
    Body, BodyKind, BodyShape, BodySurface, ContactPoints, ContactState, FreeMotion, GridPatch,
    Hydro, Material, PreviousVelocity, RigidState, ShapeVolume, angular3, band, vec3,
};
use crate::scene::ValidScene;
use bevy_ecs::prelude::*;
use glam::{DMat3, DVec3};

/// Spawn the scene's bodies into `world` (their shapes were built when the scene was checked);
/// returns how many.
pub fn spawn_bodies(world: &mut World, scene: &ValidScene, grid: &Grid) -> anyhow::Result<usize> {
    let resolved = scene.resolved();
    // A half-space is drawn as a square patch as wide as the domain's diagonal.
    let diagonal = {
        let e = grid.extent();
        (0..grid.dim).map(|a| e[a] * e[a]).sum::<f64>().sqrt()
    };
    for (id, (spec, geom)) in scene.bodies.iter().zip(scene.geometries()).enumerate() {
        let level_set = LocalLevelSet::new(geom.clone(), grid.h, band(grid), grid.dim);
        let eps = resolved.contact.eps;
        // Quadrature lattice: half a cell in 2D; in 3D a whole cell (8 times fewer points, the
        // cost of dense piles; the points being material, the force stays conservative).
        let spacing = if grid.dim == 2 { 0.5 } else { 1.0 } * grid.h.min(eps);
        let contact_points = ContactPoints::new(
            &level_set,
            eps,
            spacing,
            grid.dim,
            matches!(spec.kind, BodyKind::Dynamic),
        );
        let density = resolved.densities[id];
        // Newton-Euler or the projection: decided once, from the density and the shape. With
        // a free surface every body stays `Projected`, whose projection holds the body's
        // inertia implicitly: Newton-Euler's virtual mass lags the acceleration, and against
        // a floating body's restoring moment the lag capsized the boxes of `floating`
        // (docs/numerics.md, "The momentum form").
        let params = &resolved.params;
        let exact_volume = geom.volume().unwrap_or(0.0);
        let (law, virtual_mass) = match spec.kind {
            BodyKind::Dynamic
                if params.numerics.body_coupling == BodyCoupling::Pressure
                    && !params.free_surface =>
            {
                newton_euler(
                    &level_set,
                    grid.h,
                    grid.dim,
                    density,
                    params.rho_fluid,
                    exact_volume,
                )
            }
            _ => (MotionLaw::Projected, VirtualMass::default()),
        };
        // A Newton-Euler body's no-slip is held at markers on its surface; a body too thin
        // to carry any (under about 1.1 cells across) stays with the projection.
        let markers = if law == MotionLaw::NewtonEuler {
            crate::bodies::markers::Markers::new(&level_set, grid.h, grid.dim)
        } else {
            crate::bodies::markers::Markers::default()
        };
        let (law, virtual_mass) = if law == MotionLaw::NewtonEuler && markers.points.is_empty() {
            (MotionLaw::Projected, VirtualMass::default())
        } else {
            (law, virtual_mass)
        };
        let orientation = crate::bodies::rotation(&spec.rotation);
        let (velocity, angular_velocity) = match &spec.kind {
            BodyKind::Dynamic => (vec3(&spec.velocity), angular3(&spec.angular_velocity)),
            BodyKind::Static => (DVec3::ZERO, DVec3::ZERO),
            BodyKind::Kinematic {
                velocity,
                angular_velocity,
                ..
            } => (vec3(velocity), angular3(angular_velocity)),
        };
        let mut patch = GridPatch::default();
        // The largest box the body can need in any orientation: its bounding sphere.
        let cap = match crate::bodies::box_span(&level_set, grid.h) {
            Some(n) => {
                // (Along z the whole grid's count: on a slab a patch that wraps round it spans
                // its whole box, `GridPatch::holds`.)
                let whole = grid.whole();
                let mut c = 1;
                for a in 0..grid.dim {
                    c *= n.min(whole.n[a]);
                }
                c
            }
            None => grid.len(),
        };
        patch.phi.reserve_exact(cap);
        patch.chi.reserve_exact(cap);
        world.spawn((
            Body {
                id,
                name: spec.name.clone(),
                kind: spec.kind.clone(),
            },
            RigidState {
                center: vec3(&spec.position),
                orientation,
                velocity,
                angular_velocity,
                volume: 0.0,
                centroid: vec3(&spec.position),
                inertia: DMat3::ZERO,
            },
            Material { density },
            ShapeVolume(exact_volume),
            law,
            virtual_mass,
            BodyShape { level_set },
            patch,
            Hydro::default(),
            ContactState {
                kappa: resolved.kappas[id],
                ..Default::default()
            },
            FreeMotion::default(),
            PreviousVelocity {
                velocity,
                angular_velocity,
                ..Default::default()
            },
            contact_points,
            BodySurface(geom.surface(diagonal, grid.dim)),
            markers,
        ));
    }
    Ok(scene.bodies.len())
}

/// The scene's free surface, if it has one: its entity and the liquid's level set at t = 0
/// (the union of the liquid regions, φ_w = max over regions, clipped to the band; the
/// `free_surface` plugin redistances it before the first step). Returns whether there is one.
pub fn spawn_free_surface(
    world: &mut World,
    scene: &ValidScene,
    grid: &Grid,
) -> anyhow::Result<bool> {
    use crate::bodies::free_surface::{FreeSurface, LiquidLevelSet};
    use crate::scene::LiquidRegion;
    let Some(spec) = &scene.free_surface else {
        return Ok(false);
    };
    let dim = grid.dim;
    let up = dim - 1;
    let lo = grid.origin;
    let shapes: Vec<Option<(crate::bodies::shapes::ShapeGeometry, DVec3)>> = spec
        .liquid
        .iter()
        .map(|r| match r {
            LiquidRegion::Shape { shape, position } => shape
                .build(&scene.base_dir)
                .map(|g| Some((g, vec3(position))))
                .map_err(|e| anyhow::anyhow!("free_surface.liquid: {e}")),
            _ => Ok(None),
        })
        .collect::<anyhow::Result<_>>()?;
    let wave = |x: f64, amplitude: f64, l: f64| {
        amplitude * (2.0 * std::f64::consts::PI * (x - lo[0]) / l).cos()
    };
    let band = band(grid);
    let phi_at = |p: [f64; 3]| -> f64 {
        let mut best = f64::NEG_INFINITY;
        let regions = spec.liquid.iter().zip(&shapes);
        for ((r, s), &l) in regions.zip(&scene.resolved().wavelengths) {
            let v = match r {
                LiquidRegion::Below {
                    height, amplitude, ..
                } => height + wave(p[0], *amplitude, l) - p[up],
                LiquidRegion::Above {
                    height, amplitude, ..
                } => p[up] - height - wave(p[0], *amplitude, l),
                LiquidRegion::Shape { .. } => match s {
                    Some((g, c)) => g.phi(DVec3::from_array(p) - *c),
                    None => f64::NEG_INFINITY,
                },
            };
            best = best.max(v);
        }
        best.clamp(-band, band)
    };
    let [nx, ny, _] = grid.n;
    let mut phi = vec![0.0; grid.len()];
    {
        use rayon::prelude::*;
        phi.par_chunks_mut(nx).enumerate().for_each(|(row, out)| {
            let (j, k) = (row % ny, row / ny);
            for (i, o) in out.iter_mut().enumerate() {
                *o = phi_at(grid.pos(i, j, k));
            }
        });
    }
    world.spawn(FreeSurface {
        liquid_density: scene.fluid.density,
        gas_density: spec.gas_density,
    });
    world.insert_resource(LiquidLevelSet {
        phi,
        band,
        target_volume: 0.0,
        volume: 0.0,
        area: 0.0,
    });
    Ok(true)
}
