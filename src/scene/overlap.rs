//! Bodies that overlap at the start of a run: a scene mistake (the contact force would fling
//! them apart with an enormous impulse on the first step), found when the scene is loaded.
//!
//! Every pair with a dynamic body is checked: bounding spheres first, then the level sets are
//! sampled on a lattice of spacing h/2 over the part of the domain both bodies' boxes cover.
//! A pair overlaps if some point lies more than half a cell inside both (bodies that touch
//! or sit within the contact range are fine). Two bounded moving bodies are compared through
//! the nearest periodic image of the second (they may overlap across the box's boundary).

use crate::base::grid::Grid;
use crate::bodies::BodyKind;
use crate::bodies::shapes::ShapeGeometry;
use crate::scene::Scene;
use glam::{DQuat, DVec3};

/// The most lattice points sampled per pair (the lattice is coarsened beyond).
const MAX_POINTS: f64 = 2.0e5;

/// Two bodies found overlapping.
#[derive(Clone, Debug, PartialEq)]
pub struct Overlap {
    /// Index of the first body in the scene's list.
    pub a: usize,
    /// Index of the second (later) body.
    pub b: usize,
    /// A point inside both (world coordinates; z = 0 in 2D).
    pub point: DVec3,
    /// How deep the point is inside the shallower of the two, length.
    pub depth: f64,
}

struct Placed<'a> {
    geom: &'a ShapeGeometry,
    center: DVec3,
    inverse: DQuat,
    /// Bounding sphere radius about the centre (None: unbounded).
    radius: Option<f64>,
}

impl Placed<'_> {
    fn phi(&self, x: DVec3) -> f64 {
        self.geom.phi(self.inverse * (x - self.center))
    }
}

/// The first pair of bodies (with a dynamic one) that overlap by more than half a cell, if
/// any. `geoms` are the scene's bodies' built shapes, in order; `grid` is the scene's.
pub fn initial_overlap(scene: &Scene, grid: &Grid, geoms: &[ShapeGeometry]) -> Option<Overlap> {
    let dim = grid.dim;
    let h = grid.h;
    let placed: Vec<Placed> = scene
        .bodies
        .iter()
        .zip(geoms)
        .map(|(b, g)| {
            let q = crate::bodies::rotation(&b.rotation);
            Placed {
                geom: g,
                center: crate::bodies::vec3(&b.position),
                inverse: q.inverse(),
                radius: g.bounds().map(|(lo, hi)| lo.length().max(hi.length())),
            }
        })
        .collect();
    let dom_lo = DVec3::from_array(grid.origin);
    let dom_hi = dom_lo + DVec3::from_array(grid.extent());
    let depth = 0.5 * h;
    for a in 0..placed.len() {
        for b in a + 1..placed.len() {
            let dynamic = |i: usize| matches!(scene.bodies[i].kind, BodyKind::Dynamic);
            if !dynamic(a) && !dynamic(b) {
                continue;
            }
            let (pa, pb) = (&placed[a], &placed[b]);
            // The box is periodic for moving bodies: two bounded ones are compared through
            // b's image nearest a (they may touch across the boundary).
            let moving = |i: usize| !matches!(scene.bodies[i].kind, BodyKind::Static);
            let bounded = pa.radius.is_some() && pb.radius.is_some();
            let image;
            let pb = if bounded && moving(a) && moving(b) {
                let shift = DVec3::from_array(grid.image_shift((pb.center - pa.center).to_array()));
                image = Placed {
                    center: pb.center + shift,
                    ..*pb
                };
                &image
            } else {
                pb
            };
            if let (Some(ra), Some(rb)) = (pa.radius, pb.radius)
                && pa.center.distance(pb.center) >= ra + rb
            {
                continue;
            }
            // The box both bounding spheres (and, unless both are bounded, the domain) cover.
            let (mut lo, mut hi) = if bounded {
                (DVec3::splat(f64::NEG_INFINITY), DVec3::splat(f64::INFINITY))
            } else {
                (dom_lo, dom_hi)
            };
            for p in [pa, pb] {
                if let Some(r) = p.radius {
                    lo = lo.max(p.center - DVec3::splat(r));
                    hi = hi.min(p.center + DVec3::splat(r));
                }
            }
            if dim == 2 {
                lo.z = 0.0;
                hi.z = 0.0;
            }
            if (0..dim).any(|k| hi[k] <= lo[k]) {
                continue;
            }
            let size = hi - lo;
            let volume: f64 = (0..dim).map(|k| size[k]).product();
            let mut s = 0.5 * h;
            if volume / s.powi(dim as i32) > MAX_POINTS {
                s = (volume / MAX_POINTS).powf(1.0 / dim as f64);
            }
            let count = |k: usize| {
                if k < dim {
                    (size[k] / s).floor() as usize + 1
                } else {
                    1
                }
            };
            let (nx, ny, nz) = (count(0), count(1), count(2));
            for k in 0..nz {
                for j in 0..ny {
                    for i in 0..nx {
                        let x = lo + DVec3::new(i as f64, j as f64, k as f64) * s;
                        let x = if dim == 2 { x.with_z(0.0) } else { x };
                        let fa = pa.phi(x);
                        if fa <= depth {
                            continue;
                        }
                        let fb = pb.phi(x);
                        if fb > depth {
                            return Some(Overlap {
                                a,
                                b,
                                point: x,
                                depth: fa.min(fb),
                            });
                        }
                    }
                }
            }
        }
    }
    None
}
