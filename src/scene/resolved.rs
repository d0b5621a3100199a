//! [`Resolved`]: the values a scene leaves to defaults worked out from its other settings (a
//! body's density from the fluid's, the contact range from the grid, κ from the scene's
//! scales, the multigrid decision from the densities), resolved once when the scene is
//! validated. The engine, the summaries, the estimate and the plots read them here; nothing
//! works a default out again from the raw scene.

use super::format::{LiquidRegion, Scene};
use crate::base::fields::Params;
use crate::base::grid::Grid;
use crate::bodies::BodyKind;
use crate::bodies::contact::ContactParams;
use crate::bodies::shapes::ShapeGeometry;
use crate::solvers::variable_poisson::wants_multigrid;

/// A valid scene's defaults, resolved (see [`crate::scene::ValidScene::resolved`]).
#[derive(Debug, Clone)]
pub struct Resolved {
    /// The engine's parameters: the fluid's, `numerics`, what the scene holds, and whether
    /// the pressure solve keeps a multigrid hierarchy.
    pub params: Params,
    /// The contact model: ε (`contact.eps`, else the grid spacing h), the named pairs by body
    /// id, and the default κ of the others (see [`crate::scene::kappa`]).
    pub contact: ContactParams,
    /// Each body's density, mass per volume, in the order of `bodies` (generated bodies
    /// included): its `density`, else the fluid's.
    pub densities: Vec<f64>,
    /// Each body's own contact strength κ, length³/time², in the order of `bodies`: its
    /// `kappa`, else `contact.kappa`; `None` if neither is given (the body then takes each
    /// pair's default).
    pub kappas: Vec<Option<f64>>,
    /// Each `free_surface.liquid` region's wavelength, length: its `wavelength`, else the
    /// grid's extent along the first axis (which a `Shape` region, without a wave, gets too).
    pub wavelengths: Vec<f64>,
}

/// The defaults of `scene` (checked, with its generators expanded) on `grid`, its bodies'
/// shapes `geoms`.
pub(crate) fn resolve(scene: &Scene, grid: &Grid, geoms: &[ShapeGeometry]) -> Resolved {
    let rho_f = scene.fluid.density;
    let densities: Vec<f64> = scene
        .bodies
        .iter()
        .map(|b| b.density.unwrap_or(rho_f))
        .collect();
    // The multigrid hierarchy only where the densities can differ by its contrast: the
    // fluid's (the liquid's with a free surface), the gas's, the moving bodies'.
    let mut moving = vec![rho_f];
    if let Some(fs) = &scene.free_surface {
        moving.push(fs.gas_density);
    }
    for (b, &d) in scene.bodies.iter().zip(&densities) {
        if b.kind != BodyKind::Static {
            moving.push(d);
        }
    }
    // With a free surface the projection holds the walls rigid by giving them the density
    // ρ (1 + λΔt χ) (`systems/pressure.rs`, `rigid_walls`), far beyond any contrast.
    if scene.free_surface.is_some() && scene.bodies.iter().any(|b| b.kind == BodyKind::Static) {
        moving.push(rho_f * scene.numerics.lambda);
    }
    let multigrid = wants_multigrid(grid, moving);
    let eps = scene.contact.eps.unwrap_or(grid.h);
    let id = |n: &str| scene.bodies.iter().position(|b| b.name == n);
    let mut pairs: Vec<(usize, usize, f64)> = scene
        .contact
        .pairs
        .iter()
        .filter_map(|p| {
            let (a, b) = (id(&p.bodies.0)?, id(&p.bodies.1)?);
            Some((a.min(b), a.max(b), p.kappa))
        })
        .collect();
    pairs.sort_by_key(|p| (p.0, p.1));
    let contact = ContactParams {
        eps,
        range: scene.contact.range,
        pairs,
        predict: !scene.vacuum,
        default: super::kappa::kappa_default(scene, grid, geoms, eps),
    };
    let extent = grid.extent()[0];
    let wavelengths = scene
        .free_surface
        .iter()
        .flat_map(|fs| &fs.liquid)
        .map(|r| match r {
            LiquidRegion::Below { wavelength, .. } | LiquidRegion::Above { wavelength, .. } => {
                wavelength.unwrap_or(extent)
            }
            LiquidRegion::Shape { .. } => extent,
        })
        .collect();
    Resolved {
        params: params(scene, multigrid),
        contact,
        kappas: scene
            .bodies
            .iter()
            .map(|b| b.kappa.or(scene.contact.kappa))
            .collect(),
        densities,
        wavelengths,
    }
}

/// The engine's parameters of `scene`.
fn params(scene: &Scene, multigrid: bool) -> Params {
    Params {
        nu: scene.fluid.viscosity,
        rho_fluid: scene.fluid.density,
        gravity: scene.gravity(),
        background: scene.background_velocity(),
        numerics: scene.numerics.clone(),
        has_bodies: !scene.bodies.is_empty(),
        free_surface: scene.free_surface.is_some(),
        multigrid,
    }
}
