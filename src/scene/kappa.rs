//! The default contact strength κ of a scene that does not give `contact.kappa`: the scales
//! it is made of (gravity, the fastest a body can meet another, the contact range ε and the
//! bodies' sizes), read from the scene itself, so the same scene written in other units moves
//! the same. The rule is [`KappaDefault`]'s; this file finds its numbers.

use super::format::{InitialVorticity, Scene};
use crate::base::grid::Grid;
use crate::bodies::contact::{KappaDefault, default_kappa_factor, equivalent_radius};
use crate::bodies::shapes::ShapeGeometry;
use crate::bodies::{BodyKind, angular3, vec3};
use glam::DVec3;

/// The default κ of `scene` on `grid` with its bodies' shapes `geoms` and the contact range
/// `eps` (resolved: `contact.eps`, else h).
///
/// U bounds the speed at which a dynamic body meets another: its initial speed (|v| plus |ω|
/// times its bounding radius), plus the fastest kinematic body's (|velocity| + |amplitude| +
/// |ω| R), plus with the flow on the background velocity and the fastest initial vortex's
/// speed (Γ/(2πσ) for a Gaussian core, the amplitude of a Taylor-Green field); in vacuum,
/// where nothing but the contact brakes a body, also the speed it gains falling from its start
/// to the bottom of the domain, √(2 |g| H). With the flow on a falling body arrives at its
/// settling speed, braked by the fluid it squeezes out, and gravity alone sets the scale (the
/// paper's own values in fluid match C |g| L²).
pub(crate) fn kappa_default(
    scene: &Scene,
    grid: &Grid,
    geoms: &[ShapeGeometry],
    eps: f64,
) -> KappaDefault {
    let dim = grid.dim;
    let g = DVec3::from_array(scene.gravity());
    let lo = DVec3::from_array(grid.origin);
    let hi = lo + vec3(&scene.domain.extent);
    // The distance from `c` to the bottom of the domain along gravity.
    let fall = |c: DVec3| -> f64 {
        if g == DVec3::ZERO {
            return 0.0;
        }
        let down = g.normalize();
        let bottom: f64 = (0..dim)
            .map(|a| down[a] * if down[a] > 0.0 { hi[a] } else { lo[a] })
            .sum();
        (bottom - down.dot(c)).max(0.0)
    };
    // Radius of a sphere about the body's origin holding it (0 if unbounded).
    let reach = |geom: &ShapeGeometry| {
        geom.bounds()
            .map_or(0.0, |(a, b)| a.abs().max(b.abs()).length())
    };
    let kinematic = scene
        .bodies
        .iter()
        .zip(geoms)
        .filter_map(|(b, geom)| match &b.kind {
            BodyKind::Kinematic {
                velocity,
                angular_velocity,
                amplitude,
                ..
            } => Some(
                vec3(velocity).length()
                    + vec3(amplitude).length()
                    + angular3(angular_velocity).length() * reach(geom),
            ),
            _ => None,
        })
        .fold(0.0, f64::max);
    // The flow's speed: the background velocity plus the fastest initial vortex (the swirl
    // speed Γ/(2πσ) at a Gaussian core's edge, a Taylor-Green amplitude).
    let vortex = scene
        .initial
        .iter()
        .map(|init| match init {
            InitialVorticity::LambOseen {
                circulation,
                core_radius,
                ..
            }
            | InitialVorticity::VortexRing {
                circulation,
                core_radius,
                ..
            } => circulation.abs() / (2.0 * std::f64::consts::PI * core_radius),
            InitialVorticity::TaylorGreen2d { amplitude, .. }
            | InitialVorticity::TaylorGreen3d { amplitude, .. } => amplitude.abs(),
        })
        .fold(0.0, f64::max);
    let flow = if scene.vacuum {
        0.0
    } else {
        vec3(&scene.fluid.background_velocity).length() + vortex
    };
    let speed = scene
        .bodies
        .iter()
        .zip(geoms)
        .filter(|(b, _)| matches!(b.kind, BodyKind::Dynamic))
        .map(|(b, geom)| {
            let own =
                vec3(&b.velocity).length() + angular3(&b.angular_velocity).length() * reach(geom);
            let u = own + kinematic + flow;
            let drop = if scene.vacuum {
                2.0 * g.length() * fall(vec3(&b.position))
            } else {
                0.0
            };
            (u * u + drop).sqrt()
        })
        .fold(0.0, f64::max);
    KappaDefault {
        factor: default_kappa_factor(dim),
        gravity: g.length(),
        speed,
        eps,
        lengths: scene
            .bodies
            .iter()
            .zip(geoms)
            .map(|(b, geom)| match (&b.kind, geom.volume()) {
                (BodyKind::Dynamic, Some(v)) if v > 0.0 => equivalent_radius(v, dim),
                _ => f64::INFINITY,
            })
            .collect(),
    }
}
