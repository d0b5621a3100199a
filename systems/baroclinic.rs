//! # baroclinic: vorticity made by density gradients (paper eq. 28; Boussinesq form eq. 18)
//!
//! ∂ω/∂t = -(∇ρ/ρ) × (∂u/∂t + (u·∇)u - g), integrated over one step: this is how gravity
//! reaches a body whose density differs from the fluid's. ∂u/∂t comes from the last two
//! velocity fields, (u^n - u^{n-1})/Δt_{n-1} (zero on the first step), and ∇ρ and (u·∇)u from
//! centred differences; only nodes where ρ varies are touched. With `numerics.boussinesq` the
//! term is ∇ρ × g / ρ_F instead.

use crate::bodies::BodyFields;
use crate::fields::{Fields, Params, SimTime, SystemTimer, Timings};
use crate::grid::Grid;
use bevy_ecs::prelude::*;
use glam::DVec3;
use rayon::prelude::*;

/// The baroclinic system.
pub fn baroclinic(
    grid: Res<Grid>,
    params: Res<Params>,
    time: Res<SimTime>,
    mut fields: ResMut<Fields>,
    bf: Res<BodyFields>,
    mut timings: ResMut<Timings>,
) {
    let timer = SystemTimer::start();
    let dt = time.dt;
    let g = DVec3::from_array(params.gravity);
    let fields = &mut *fields;
    let inv_dtp = if fields.dt_prev > 0.0 {
        1.0 / fields.dt_prev
    } else {
        0.0
    };
    let [nx, ny, nz] = grid.n;
    let dim = grid.dim;
    let inv2h = 0.5 / grid.h;
    let rho = &bf.rho;
    let rho_f = params.rho_fluid;
    let boussinesq = params.boussinesq;
    let nb = |i: usize, n: usize| {
        (
            if i == 0 { n - 1 } else { i - 1 },
            if i + 1 == n { 0 } else { i + 1 },
        )
    };
    let u = std::mem::take(&mut fields.u);
    let u_prev = std::mem::take(&mut fields.u_prev);
    let omega = fields.omega_mut();
    // One task per row; each writes only its own row of ω.
    let ptrs = crate::grid::component_ptrs(omega);
    (0..ny * nz).into_par_iter().for_each(|row| {
        let (j, k) = (row % ny, row / ny);
        let (jm, jp) = nb(j, ny);
        let (km, kp) = if dim == 3 { nb(k, nz) } else { (0, 0) };
        for i in 0..nx {
            let (im, ip) = nb(i, nx);
            let id = |i: usize, j: usize, k: usize| i + nx * (j + ny * k);
            let c = id(i, j, k);
            let grad = |f: &[f64]| {
                DVec3::new(
                    (f[id(ip, j, k)] - f[id(im, j, k)]) * inv2h,
                    (f[id(i, jp, k)] - f[id(i, jm, k)]) * inv2h,
                    if dim == 3 {
                        (f[id(i, j, kp)] - f[id(i, j, km)]) * inv2h
                    } else {
                        0.0
                    },
                )
            };
            let grho = grad(rho);
            if grho == DVec3::ZERO {
                continue;
            }
            let src = if boussinesq {
                grho.cross(g) / rho_f
            } else {
                let uc = DVec3::new(u[0][c], u[1][c], if dim == 3 { u[2][c] } else { 0.0 });
                let mut acc = DVec3::ZERO;
                for q in 0..dim {
                    let dudt = (u[q][c] - u_prev[q][c]) * inv_dtp;
                    acc[q] = dudt + uc.dot(grad(&u[q])) - g[q];
                }
                -(grho / rho[c]).cross(acc)
            };
            // SAFETY: node c belongs to this row only.
            unsafe {
                if dim == 2 {
                    ptrs[0].write(c, ptrs[0].read(c) + dt * src.z);
                } else {
                    for q in 0..3 {
                        ptrs[q].write(c, ptrs[q].read(c) + dt * src[q]);
                    }
                }
            }
        }
    });
    fields.u = u;
    fields.u_prev = u_prev;
    timer.stop(&mut timings, "baroclinic");
}
