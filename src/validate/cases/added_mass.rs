//! `added-mass`: a disk and a sphere launched in still inviscid fluid against the potential-flow
//! added mass.

use super::common::{MODEL, dynamic_body};
use crate::scene::Scene;
use crate::validate::{Case, KnownFailure, Report, Row, RunTime};

/// The case: what it checks, against what, and the rows known to fail.
pub const CASE: Case = Case {
    name: "added-mass",
    description: "a disk (2D) and a sphere (3D) launched at V0 in still inviscid fluid: the velocity six steps later within 3% of the potential-flow V0 rho_s/(rho_s + C_m rho_F) (C_m = 1 disk, 1/2 sphere) for densities 0.1, 1.5, 3 and 10; released from rest under gravity at densities 0.001 and 1000: the acceleration within 3% of (rho_s - rho_F) g/(rho_s + C_m rho_F); no step-to-step oscillation",
    reference: "potential flow (Lamb, Hydrodynamics, sections 68 and 92)",
    full: "disk at 25.6 cells per radius (512^2), sphere at 12 cells per radius (96^3)",
    quick: "disk at 12.8 cells per radius (256^2), sphere at 8 cells per radius (64^3)",
    full_time: RunTime::Minutes,
    quick_time: RunTime::Seconds,
    run: added_mass,
    known_failures: &[
        KnownFailure {
            row: "disk, density 0.1,",
            quick: true,
            full: true,
            why: "-38.0% at 12.8 cells per radius (0.0564 against 0.0909) since light bodies move by Newton-Euler with a virtual mass (E + M_v at least 0.1 rho_F V, here M_v = rho_F V): six steps are within the virtual mass's lag, and the converged value is below the theory as at density 1.5 (+26.6% with the no-slip on the nodes inside the surface); issues 35 and 45",
        },
        KnownFailure {
            row: "disk, density 1.5,",
            quick: true,
            full: true,
            why: "-7.0% at 12.8 cells per radius (-6.9% on the nodes inside the surface; -3.8% at 25.6 then) with the no-slip held at surface markers (issue 45): the kernel carries a shell of fluid about half a cell thick beyond the surface with the body, so the converged added mass is first order in h/R above the theory (sphere released at density 1.5, inviscid: C_m 0.87 / 0.78 / 0.69 at 6 / 8 / 12 cells per radius, 0.5 + 2.3 h/R; disk 1.21 / 1.12 at 16 / 32); the retraction that gives the Stokes drag does not give the inviscid added mass; issue 45",
        },
        KnownFailure {
            row: "disk at density 1.5 does not oscillate",
            quick: false,
            full: true,
            why: "one reversal of the step-to-step change above 1e-3 V0 over the eight steps at 25.6 cells per radius, since the disk moves by Newton-Euler with a virtual mass (issue 35): the lagged virtual mass's correction (M_v = A/2 here) against the flow's own relaxation after the launch; none at 12.8; issue 35",
        },
        KnownFailure {
            row: "disk, density 3,",
            quick: true,
            full: false,
            why: "-4.4% at 12.8 cells per radius (-4.4% on the nodes): as at density 1.5; issue 45",
        },
        KnownFailure {
            row: "sphere, density 0.1,",
            quick: true,
            full: true,
            why: "-33.4% at 8 cells per radius (0.111 against 0.167; -32% on the nodes inside the surface): the virtual mass's lag over six steps (M_v = rho_F V) and the excess added mass of the row at density 1.5; issues 35 and 45",
        },
        KnownFailure {
            row: "sphere, density 1.5,",
            quick: true,
            full: true,
            why: "-12.6% at 8 cells per radius (-13.2% on the nodes inside the surface, -9.2% at 12 then) with the no-slip held at surface markers (issue 45): the kernel carries a shell of fluid about half a cell thick beyond the surface with the body, so the converged added mass is first order in h/R above the theory (sphere released at density 1.5, inviscid: C_m 0.87 / 0.78 / 0.69 at 6 / 8 / 12 cells per radius, 0.5 + 2.3 h/R; disk 1.21 / 1.12 at 16 / 32); the retraction that gives the Stokes drag does not give the inviscid added mass; issue 45",
        },
        KnownFailure {
            row: "sphere, density 3,",
            quick: true,
            full: true,
            why: "-7.6% at 8 cells per radius (-7.7% on the nodes): as at density 1.5; issue 45",
        },
        KnownFailure {
            row: "disk, density 0.001, 12.8 cells per radius, released",
            quick: true,
            full: false,
            why: "0.759 a0 t (0.637 on the nodes inside the surface, 2.31 with the projection) since light bodies move by Newton-Euler with a virtual mass: the virtual mass lags the acceleration over the first steps and the kernel's shell adds to the added mass (see density 1.5); issues 35 and 45",
        },
        KnownFailure {
            row: "disk, density 0.001, 25.6 cells per radius, released",
            quick: false,
            full: true,
            why: "0.662 a0 t (4.52 with the projection, 2.31 at 12.8 cells per radius then) since light bodies move by Newton-Euler with a virtual mass (0.645 at 12.8: the virtual mass's lag over the first steps and the discrete no-slip layer's added mass); issue 35",
        },
        KnownFailure {
            row: "sphere, density 0.001, 12.0 cells per radius, released",
            quick: false,
            full: true,
            why: "0.588 a0 t (0.963 with the projection, 0.65 at 8 cells per radius then) since light bodies move by Newton-Euler with a virtual mass (0.554 at 8: the virtual mass's lag over the first steps and the discrete no-slip layer's added mass); issue 35",
        },
        KnownFailure {
            row: "sphere, density 0.001, 8.0 cells per radius, released",
            quick: true,
            full: false,
            why: "0.520 a0 t (0.549 on the nodes inside the surface, 0.65 with the projection): the virtual mass's lag over the first steps and the kernel's shell's added mass (0.78 instead of 0.5 at 8 cells per radius, see density 1.5); issues 35 and 45",
        },
    ],
};

/// One launch: a disk (2D) or sphere (3D) of radius `r` and density `rho` at the centre of a
/// periodic unit box of `n` cells per side, in still inviscid fluid with the coupling
/// [`MODEL`], Δt = h/4, launched at `v0` along the last axis with gravity `g` along it.
/// Returns its velocity along that axis after each of `steps` steps.
fn launch_run(
    dim: usize,
    n: usize,
    r: f64,
    rho: f64,
    steps: usize,
    v0: f64,
    g: f64,
) -> anyhow::Result<Vec<f64>> {
    let dt = 0.25 / n as f64;
    let text = if dim == 2 {
        format!(
            r#"Scene(
            name: "added-mass",
            domain: (extent: [1.0, 1.0], cells: [{n}, {n}]),
            fluid: (viscosity: 0.0, gravity: [0.0, {g}]),
            numerics: (end_time: 1.0, dt: Fixed({dt}), {MODEL}),
            bodies: [(name: "disk", shape: Disk(radius: {r}), density: {rho},
                      position: [0.5, 0.5], velocity: [0.0, {v0}])],
        )"#
        )
    } else {
        format!(
            r#"Scene(
            name: "added-mass",
            domain: (extent: [1.0, 1.0, 1.0], cells: [{n}, {n}, {n}]),
            fluid: (viscosity: 0.0, gravity: [0.0, 0.0, {g}]),
            numerics: (end_time: 1.0, dt: Fixed({dt}), {MODEL}),
            bodies: [(name: "sphere", shape: Sphere(radius: {r}), density: {rho},
                      position: [0.5, 0.5, 0.5], velocity: [0.0, 0.0, {v0}])],
        )"#
        )
    };
    let mut sim = crate::validate::simulation(Scene::parse(&text, "added-mass", "added-mass")?)?;
    let mut v = Vec::with_capacity(steps);
    for _ in 0..steps {
        sim.step()?;
        let st = dynamic_body(&mut sim).ok_or_else(|| anyhow::anyhow!("no body"))?;
        v.push(if dim == 2 {
            st.velocity.y
        } else {
            st.velocity.z
        });
    }
    Ok(v)
}

/// Step-to-step oscillation of a velocity history: the number of consecutive changes of
/// opposite signs, both above `floor` (the old explicit coupling went 1.0, 0.48, 1.06, 0.40,
/// ... at density 3).
fn sign_flips(v: &[f64], floor: f64) -> usize {
    let d: Vec<f64> = v.windows(2).map(|w| w[1] - w[0]).collect();
    d.windows(2)
        .filter(|w| w[0] * w[1] < 0.0 && w[0].abs().min(w[1].abs()) > floor)
        .count()
}

/// A body launched at V0 in still fluid shares its momentum with the fluid it sets moving:
/// potential flow gives V = V0 ρ_s/(ρ_s + C_m ρ_F), C_m = 1 for a circular cylinder and 1/2
/// for a sphere. The box is periodic: the disk fills 0.8% of the area and the sphere 0.8% of
/// the volume, which raises C_m by a few times that fraction (well under 1% of V, inside the
/// tolerance). The issue asks for 25 cells per radius; the 3D full version runs 12 (96³) to
/// stay in minutes.
fn added_mass(quick: bool) -> anyhow::Result<Report> {
    let mut rep = Report::new("added-mass");
    let steps = 8;
    let configs: [(usize, usize, f64, f64, &str); 2] = if quick {
        [(2, 256, 0.05, 1.0, "disk"), (3, 64, 0.125, 0.5, "sphere")]
    } else {
        [(2, 512, 0.05, 1.0, "disk"), (3, 96, 0.125, 0.5, "sphere")]
    };
    for (dim, n, r, cm, what) in configs {
        for rho in [0.1, 1.5, 3.0, 10.0] {
            let v = launch_run(dim, n, r, rho, steps, 1.0, 0.0)?;
            let theory = rho / (rho + cm);
            rep.rows.push(Row::rel(
                format!(
                    "{what}, density {rho}, {:.1} cells per radius: V / V0 after 6 steps",
                    r * n as f64
                ),
                theory,
                v[5],
                0.03,
            ));
            // Over the steps after the first (which imposes the launch), changes above
            // 1e-3 V0.
            let flips = sign_flips(&v, 1e-3);
            rep.rows.push(Row::yes_no(
                format!(
                    "{what} at density {rho} does not oscillate from step to step ({flips} sign changes of dV above 1e-3 V0)"
                ),
                flips == 0,
            ));
        }
        // The ends of the density range, released from rest under gravity g = -1: the
        // acceleration is (ρ_s - ρ_F) g / (ρ_s + C_m ρ_F), 2 g upwards for a sphere of
        // density 0.001, g for the disk, g (1 - 1.5/1000) downwards at density 1000.
        for rho in [0.001, 1000.0] {
            let g = -1.0;
            let v = launch_run(dim, n, r, rho, steps, 0.0, g)?;
            let dt = 0.25 / n as f64;
            let a0 = (rho - 1.0) * g / (rho + cm);
            rep.rows.push(Row::rel(
                format!(
                    "{what}, density {rho}, {:.1} cells per radius, released under gravity: V after 6 steps / (a0 t)",
                    r * n as f64
                ),
                1.0,
                v[5] / (a0 * 6.0 * dt),
                0.03,
            ));
            let flips = sign_flips(&v, 1e-3 * (a0 * dt).abs());
            rep.rows.push(Row::yes_no(
                format!(
                    "{what} at density {rho} released under gravity does not oscillate ({flips} sign changes of dV above 1e-3 of a0 dt)"
                ),
                flips == 0 && v.iter().all(|x| x.is_finite()),
            ));
        }
    }
    Ok(rep)
}
