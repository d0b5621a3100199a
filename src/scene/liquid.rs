//! The checks of a scene's free surface: its values, that its initial surface lies in the
//! box, the coupling it needs, and that static walls close the box along the vertical.

use super::error::{Check, Issue, Seg, fail};
use super::format::{FreeSurfaceSpec, LiquidRegion, Scene};
use crate::base::grid::Grid;
use crate::base::params::BodyCoupling;
use crate::bodies::BodyKind;
use crate::bodies::shapes::{Shape, ShapeGeometry};
use glam::{DQuat, DVec3};

impl FreeSurfaceSpec {
    /// Check the values in a `dim`-dimensional box `[lo, hi)` with liquid density `liquid`.
    pub(crate) fn check(&self, dim: usize, liquid: f64, lo: &[f64], hi: &[f64]) -> Check {
        let g = self.gas_density;
        if !(g.is_finite() && g > 0.0) {
            return fail(&["gas_density"], format!("must be positive, got {g}"));
        }
        if g >= liquid {
            return fail(
                &["gas_density"],
                format!(
                    "must be below the liquid's density (`fluid.density` = {liquid}), got {g}: \
                     the liquid is the heavier phase (for heavy over light, put the liquid \
                     `Above`)"
                ),
            );
        }
        if self.liquid.is_empty() {
            return fail(
                &["liquid"],
                "needs at least one region, e.g. [Below(height: 0.5)]",
            );
        }
        let up = dim - 1;
        let axis = if dim == 2 { "y" } else { "z" };
        for (i, r) in self.liquid.iter().enumerate() {
            let at = |m: String| {
                Err(Issue::new(&[], m)
                    .under(Seg::Index(i))
                    .under(Seg::Key("liquid")))
            };
            match r {
                LiquidRegion::Below {
                    height,
                    amplitude,
                    wavelength,
                }
                | LiquidRegion::Above {
                    height,
                    amplitude,
                    wavelength,
                } => {
                    let (a, b) = (lo[up], hi[up]);
                    if !height.is_finite() || !amplitude.is_finite() {
                        return at("height and amplitude must be finite".into());
                    }
                    if height - amplitude.abs() <= a || height + amplitude.abs() >= b {
                        return at(format!(
                            "the surface at {axis} = {height} (amplitude {amplitude}) does not \
                             lie inside the box, which spans {axis} = {a} to {b}: a free \
                             surface must cross the box"
                        ));
                    }
                    if let Some(l) = wavelength
                        && !(l.is_finite() && *l > 0.0)
                    {
                        return at(format!("wavelength must be positive, got {l}"));
                    }
                }
                LiquidRegion::Shape { shape, position } => {
                    if let Err(m) = shape.validate(dim) {
                        return at(m);
                    }
                    if matches!(shape, Shape::Mesh { .. }) {
                        return at("a liquid region cannot be a Mesh".into());
                    }
                    if position.len() != dim || position.iter().any(|x| !x.is_finite()) {
                        return at(format!("position needs {dim} finite entries"));
                    }
                }
            }
        }
        Ok(())
    }
}

/// The scene-level conditions of a free surface: a fluid run, the `Pressure` coupling, and
/// static walls that cover the box's periodic seam along the vertical (checked at a lattice
/// of points on the bottom face), so the liquid is not stacked on the gas of the periodic copy.
pub(crate) fn check_tank(scene: &Scene, grid: &Grid, geoms: &[ShapeGeometry]) -> Check {
    if scene.free_surface.is_none() {
        return Ok(());
    }
    if scene.vacuum {
        return fail(&[], "a free surface needs the fluid: remove `vacuum: true`");
    }
    if scene.numerics.body_coupling != BodyCoupling::Pressure {
        return fail(
            &[],
            format!(
                "a free surface needs `numerics.body_coupling: Pressure` (the variable-density \
                 projection), not {:?}",
                scene.numerics.body_coupling
            ),
        );
    }
    let dim = grid.dim;
    let walls: Vec<(&ShapeGeometry, DVec3, DQuat)> = scene
        .bodies
        .iter()
        .zip(geoms)
        .filter(|(b, _)| matches!(b.kind, BodyKind::Static))
        .map(|(b, g)| {
            let q = crate::bodies::rotation(&b.rotation);
            (g, crate::bodies::vec3(&b.position), q.inverse())
        })
        .collect();
    let up = dim - 1;
    let ext = grid.extent();
    let m = 24usize;
    let count = if dim == 2 { m } else { m * m };
    for s in 0..count {
        let mut p = DVec3::ZERO;
        let (a, b) = (s % m, s / m);
        p[0] = grid.origin[0] + (a as f64 + 0.5) / m as f64 * ext[0];
        if dim == 3 {
            p[1] = grid.origin[1] + (b as f64 + 0.5) / m as f64 * ext[1];
        }
        p[up] = grid.origin[up];
        let covered = walls.iter().any(|(g, c, inv)| g.phi(*inv * (p - *c)) > 0.0);
        if !covered {
            let axis = if dim == 2 { "y" } else { "z" };
            let at = p.to_array()[..dim]
                .iter()
                .map(|x| format!("{x:.4}"))
                .collect::<Vec<_>>()
                .join(", ");
            return fail(
                &[],
                format!(
                    "the box is periodic, so a free surface needs it closed along the vertical \
                     ({axis}) by static walls (a floor and a ceiling, e.g. `HalfSpace` bodies \
                     with `kind: Static`): the point ({at}) on the box's bottom face is inside \
                     no static body, and the liquid would sit on the gas of the periodic copy \
                     below"
                ),
            );
        }
    }
    Ok(())
}
