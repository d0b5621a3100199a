//! Named initial vorticity fields, sampled at the grid nodes.

use crate::base::grid::Grid;
use crate::scene::InitialVorticity;
use rayon::prelude::*;
use std::f64::consts::PI;

/// Add the field `init` to `omega` (1 component in 2D, 3 in 3D).
pub fn add_initial(grid: &Grid, init: &InitialVorticity, omega: &mut [Vec<f64>]) {
    let [nx, ny, _] = grid.n;
    let ext = grid.extent();
    let plane = nx * ny;
    let nc = omega.len();
    // Evaluate per z-plane into each component.
    let value = |i: usize, j: usize, k: usize| -> [f64; 3] {
        let p = grid.pos(i, j, k);
        let rel = [
            p[0] - grid.origin[0],
            p[1] - grid.origin[1],
            p[2] - grid.origin[2],
        ];
        match init {
            InitialVorticity::LambOseen {
                center,
                circulation,
                core_radius,
            } => {
                let dx = periodic(p[0] - center[0], ext[0]);
                let dy = periodic(p[1] - center[1], ext[1]);
                let s2 = core_radius * core_radius;
                [
                    circulation / (PI * s2) * (-(dx * dx + dy * dy) / s2).exp(),
                    0.0,
                    0.0,
                ]
            }
            InitialVorticity::TaylorGreen2d {
                amplitude,
                wavenumber: k,
            } => [
                2.0 * amplitude * k * (k * rel[0]).sin() * (k * rel[1]).sin(),
                0.0,
                0.0,
            ],
            InitialVorticity::TaylorGreen3d {
                amplitude: a,
                wavenumber: kw,
            } => {
                let (sx, cx) = (kw * rel[0]).sin_cos();
                let (sy, cy) = (kw * rel[1]).sin_cos();
                let (sz, cz) = (kw * rel[2]).sin_cos();
                [
                    -a * kw * cx * sy * sz,
                    -a * kw * sx * cy * sz,
                    2.0 * a * kw * sx * sy * cz,
                ]
            }
            InitialVorticity::VortexRing {
                center,
                axis,
                radius,
                core_radius,
                circulation,
            } => {
                let d = [
                    periodic(p[0] - center[0], ext[0]),
                    periodic(p[1] - center[1], ext[1]),
                    periodic(p[2] - center[2], ext[2]),
                ];
                let along = d[0] * axis[0] + d[1] * axis[1] + d[2] * axis[2];
                let radial = [
                    d[0] - along * axis[0],
                    d[1] - along * axis[1],
                    d[2] - along * axis[2],
                ];
                let r = (radial[0].powi(2) + radial[1].powi(2) + radial[2].powi(2)).sqrt();
                if r == 0.0 {
                    return [0.0; 3];
                }
                let rho2 = (r - radius).powi(2) + along * along;
                let s2 = core_radius * core_radius;
                let mag = circulation / (PI * s2) * (-rho2 / s2).exp();
                // Azimuthal direction axis × e_r: right-handed about the axis, so the ring
                // moves along +axis.
                let er = [radial[0] / r, radial[1] / r, radial[2] / r];
                let et = [
                    axis[1] * er[2] - axis[2] * er[1],
                    axis[2] * er[0] - axis[0] * er[2],
                    axis[0] * er[1] - axis[1] * er[0],
                ];
                [mag * et[0], mag * et[1], mag * et[2]]
            }
        }
    };
    for (c, comp) in omega.iter_mut().enumerate().take(nc) {
        comp.par_chunks_mut(plane).enumerate().for_each(|(k, pl)| {
            for j in 0..ny {
                for i in 0..nx {
                    pl[i + nx * j] += value(i, j, k)[c];
                }
            }
        });
    }
}

/// The nearest periodic image of a separation `d` in a box of size `l`.
#[inline]
pub fn periodic(d: f64, l: f64) -> f64 {
    if l <= 0.0 {
        return d;
    }
    d - l * (d / l).round()
}
