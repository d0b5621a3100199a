//! `periodic-array`: a sphere settling through the periodic box's boundary again and again (a
//! simple cubic array of spheres, one per box), its mean velocity against Hasimoto (1959).
//!
//! `stokes-settling` measures the same array's drag with a sphere that moves a few thousandths
//! of its radius; here the sphere crosses the whole box several times, through the bottom face
//! and in at the top, so its level set, patch, integrals and pose wrap around the periodic
//! boundary many times (issue 45). The mean velocity over whole traversals is
//! the steady settling velocity of the array (the motion is periodic with the box once the
//! start is forgotten, and a traversal averages the wobble that comes from the sphere's
//! position on the grid). At Re = U a/ν = 0.05 the inertial correction is negligible: in an
//! ordered array it starts at O(Re²) (Hill, Koch & Ladd 2001), not at Oseen's O(Re).
//!
//! The sphere is larger than `stokes-settling`'s (a = 0.2 in the unit box, volume fraction
//! 0.034, so U/U_Stokes = 0.465) so that the quick tier's 16³ grid keeps the same 3.2 cells per
//! radius and the same 2% tolerance: U_H is then half of Stokes's, and the same absolute error
//! of the staircase of rigid nodes is a larger relative one, which is why a row may fail
//! where `stokes-settling`'s reached -2.6%.
//!
//! The full tier adds a body-centred cubic array: two spheres per cubic box, at a quarter and
//! three quarters of its diagonal, so that several bodies cross the boundary. Both spheres
//! are points of one Bravais lattice, so each sees the same surroundings and they move alike
//! (and, half a box apart along every axis in a box of an even node count, sit on the grid
//! alike): their velocities must agree. Hasimoto's expansion holds for any cubic lattice,
//! K⁻¹ = 1 - α c^{1/3} + c + O(c²): α is the lattice sum of the periodic Stokeslet's regular
//! part, which is the lattice's Madelung constant in Wigner-Seitz units (1.760119 simple cubic,
//! Hasimoto's 1.7601; 1.791859 body-centred, Coldwell-Horsfall & Maradudin 1960; Sangani &
//! Acrivos 1982 give 1.7918), and the O(c) term comes from the Stokeslet's Laplacian, the same
//! for every cubic lattice. The O(c²) term, 1.5593 c² for the simple cubic array, is 0.18% at
//! the body-centred array's c = 0.034 and is left out of its reference.
//! Its measurements are in docs/numerics.md (issue 45).

use super::common::{MODEL, dynamic_states};
use crate::scene::Scene;
use crate::validate::{Case, KnownFailure, Report, Row, RunTime};
use std::f64::consts::PI;

/// The case: what it checks, against what, and the rows known to fail.
pub const CASE: Case = Case {
    name: "periodic-array",
    description: "a sphere (a = 0.2, volume fraction 0.034) settling at Re = 0.05 through the periodic box's boundary again and again: its mean velocity over whole traversals within 2% of Hasimoto's for a simple cubic array, and the same from one traversal to the next within 0.5%; in the full tier, two spheres as a body-centred cubic array, within 2% of Hasimoto's expansion for that lattice and moving alike",
    reference: "Hasimoto 1959, Sangani & Acrivos 1982",
    full: "h = 1/16 and 1/24 (3.2 and 4.8 cells per radius), density 2, four traversals after the first; a body-centred cubic array (two spheres in a box of 1.25, the same volume fraction) at h = 1/16, three traversals after the first",
    quick: "h = 1/16 (3.2 cells per radius), density 2, three traversals after the first",
    full_time: RunTime::Minutes,
    quick_time: RunTime::Minutes,
    run: periodic_array,
    known_failures: &[KnownFailure {
        row: "body-centred cubic: largest velocity difference of the two spheres",
        quick: false,
        full: true,
        why: "0.10 of U_Hasimoto (1e-6 allowed; the mean of the pair passes, 1.0105 of Hasimoto's 1.7919 lattice): two spheres that are points of one lattice and sit on the grid alike move differently. Measured 2026-11-27 with 20^3 scenes (box 1.25, density 2, diffusion number 2): after one step they agree to 1e-12, after the second their vertical velocities differ by 3e-7 and their lateral ones are +-6e-8 (antisymmetric), after the fourth 2e-4, and the difference persists at 1-2% of U over t = 0.3 with the no-slip's warm start and without it; swapping the two bodies' order in the scene swaps nothing (the difference follows the positions, 5 and 15 cells from the origin). A single sphere at diffusion number 2 shows the related lateral jitter: its sideways velocity, round-off after three steps, jumps to about 1e-5 at the fourth and grows to 1-4% of U, alternating in sign from step to step, with the warm start (1e-4 without it; none above 1e-8 at diffusion numbers 0.5 and 0.125). Cause not found: a discrete decision that breaks the translation symmetry at the 1e-6 level (candidates: the particles' creation threshold, the rigid region's node set) amplified by the warm-started no-slip at high diffusion numbers; issue 45",
    }],
};

/// What [`settle`] returns: (time, box lengths travelled) after every step, the first
/// sphere's crossings of the bottom face, the largest velocity difference of the spheres.
type Settled = (Vec<(f64, f64)>, usize, f64);

/// The spheres of radius `a` and density `rho` at `centres` (fractions of the box), settling
/// from rest in a periodic cubic box of side `side` of fluid (ρ_F = 1, ν = 1) on `n`³ nodes
/// under gravity `g`, at diffusion number `d`, until they have travelled `distance` box
/// lengths: the time and the mean distance travelled in box lengths (Σ U Δt: the stored
/// centres are wrapped into the box) after every step, the number of times the first centre
/// crossed the box's bottom face, and the largest difference between the spheres' velocities
/// (0 for one sphere).
#[allow(clippy::too_many_arguments)]
fn settle(
    n: usize,
    side: f64,
    centres: &[[f64; 3]],
    a: f64,
    rho: f64,
    g: f64,
    d: f64,
    distance: f64,
) -> anyhow::Result<Settled> {
    let bodies: Vec<String> = centres
        .iter()
        .enumerate()
        .map(|(i, c)| {
            format!(
                r#"(name: "sphere{i}", shape: Sphere(radius: {a}), density: {rho},
                  position: [{}, {}, {}])"#,
                c[0] * side,
                c[1] * side,
                c[2] * side
            )
        })
        .collect();
    let text = format!(
        r#"Scene(
        name: "periodic-array",
        domain: (extent: [{side}, {side}, {side}], cells: [{n}, {n}, {n}]),
        fluid: (viscosity: 1.0, gravity: [0.0, 0.0, {}]),
        numerics: (end_time: 1.0e9, dt: Adaptive(diffusion_number: {d}), {MODEL}),
        bodies: [{}],
    )"#,
        -g,
        bodies.join(", "),
    );
    let mut sim =
        crate::validate::simulation(Scene::parse(&text, "periodic-array", "periodic-array")?)?;
    sim.set_stop_at(None);
    let (mut travelled, mut curve, mut crossings, mut spread) = (0.0, Vec::new(), 0, 0.0f64);
    let mut z = 0.5 * side;
    while travelled < distance {
        let t0 = sim.time();
        sim.step()?;
        let st = dynamic_states(&mut sim);
        if st.len() != centres.len() {
            anyhow::bail!("{} spheres, {} expected", st.len(), centres.len());
        }
        // The spheres moved by U Δt over the step (`rigid_update` moves them with the velocity
        // they have after the step's solve).
        let mean = st.iter().map(|s| -s.1.velocity.z).sum::<f64>() / st.len() as f64;
        for s in &st {
            let dv = (s.1.velocity - st[0].1.velocity).length();
            spread = spread.max(dv);
        }
        travelled += mean * (sim.time() - t0) / side;
        let zc = st[0].1.center.z;
        if zc > z + 0.5 * side {
            crossings += 1;
        }
        z = zc;
        curve.push((sim.time(), travelled));
        if sim.steps() > 200_000 {
            anyhow::bail!("travelled only {travelled:.3} box lengths in 200000 steps");
        }
    }
    Ok((curve, crossings, spread))
}

/// Mean velocity (box lengths over time) over each whole traversal of the box, between the
/// samples where the distance travelled first reaches 1, 2, ... box lengths (the first holds
/// the start).
fn traversal_means(curve: &[(f64, f64)]) -> Vec<f64> {
    let mut marks = Vec::new();
    for &(t, x) in curve {
        if x >= (marks.len() + 1) as f64 {
            marks.push((t, x));
        }
    }
    marks
        .windows(2)
        .map(|w| (w[1].1 - w[0].1) / (w[1].0 - w[0].0))
        .collect()
}

/// The traversals' mean velocities over `u_h`, for the notes.
fn by_traversal(means: &[f64], u_h: f64) -> String {
    means
        .iter()
        .map(|m| format!("{:.4}", m / u_h))
        .collect::<Vec<_>>()
        .join(", ")
}

fn periodic_array(quick: bool) -> anyhow::Result<Report> {
    let mut rep = Report::new("periodic-array");
    let (a, mu, rho) = (0.2f64, 1.0, 2.0);
    let c = 4.0 * PI * a.powi(3) / 3.0;
    let k = 1.0 - 1.7601 * c.cbrt() + c - 1.5593 * c * c;
    // U_Hasimoto = 0.25: Re = U a / ν = 0.05.
    let u_target = 0.25;
    let g = u_target * 9.0 * mu / (2.0 * (rho - 1.0) * a * a * k);
    let u_h = 2.0 * (rho - 1.0) * g * a * a / (9.0 * mu) * k;
    let grids: &[usize] = if quick { &[16] } else { &[16, 24] };
    let traversals = if quick { 3 } else { 4 };
    for &n in grids {
        let cells = a * n as f64;
        let start = std::time::Instant::now();
        let (curve, crossings, _) = settle(
            n,
            1.0,
            &[[0.5; 3]],
            a,
            rho,
            g,
            2.0,
            1.0 + traversals as f64 + 1e-9,
        )?;
        let means = traversal_means(&curve);
        let u = means.last().copied().unwrap_or(f64::NAN);
        rep.rows.push(Row::rel(
            format!(
                "h = 1/{n} ({cells:.1} cells per radius): mean U over the last traversal / U_Hasimoto"
            ),
            1.0,
            u / u_h,
            0.02,
        ));
        let (lo, hi) = means
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(l, h), &m| (l.min(m), h.max(m)));
        rep.rows.push(Row::abs(
            format!(
                "h = 1/{n}: (max - min) / min of the mean U over {} traversals",
                means.len()
            ),
            0.0,
            hi / lo - 1.0,
            0.005,
        ));
        rep.notes.push(format!(
            "h = 1/{n} ({cells:.1} cells per radius): {crossings} crossings of the box's bottom \
             face in {} steps ({:.1} s); mean U / U_Hasimoto by traversal: {}",
            curve.len(),
            start.elapsed().as_secs_f64(),
            by_traversal(&means, u_h)
        ));
    }
    if !quick {
        bcc(&mut rep, a, rho, mu)?;
    }
    rep.notes.push(format!(
        "{MODEL}; diffusion number 2; density 2, g = {g:.3}; Re = U a / ν = {:.2}; volume \
         fraction {c:.4}, U_Hasimoto / U_Stokes = {k:.4}",
        u_h * a / mu
    ));
    Ok(rep)
}

/// The body-centred cubic array: two spheres of radius `a` in a box of side 1.25 on 20³ nodes
/// (3.2 cells per radius, as the simple cubic array's quick grid; volume fraction 0.0343),
/// three traversals after the first, against Hasimoto's expansion to O(c) for that lattice
/// (module doc).
fn bcc(rep: &mut Report, a: f64, rho: f64, mu: f64) -> anyhow::Result<()> {
    let (n, side, traversals) = (20usize, 1.25f64, 3usize);
    let c = 2.0 * 4.0 * PI * a.powi(3) / 3.0 / side.powi(3);
    let k = 1.0 - 1.791859 * c.cbrt() + c;
    let u_target = 0.25;
    let g = u_target * 9.0 * mu / (2.0 * (rho - 1.0) * a * a * k);
    let u_h = 2.0 * (rho - 1.0) * g * a * a / (9.0 * mu) * k;
    let start = std::time::Instant::now();
    let (curve, crossings, spread) = settle(
        n,
        side,
        &[[0.25; 3], [0.75; 3]],
        a,
        rho,
        g,
        2.0,
        1.0 + traversals as f64 + 1e-9,
    )?;
    let means: Vec<f64> = traversal_means(&curve).iter().map(|m| m * side).collect();
    let u = means.last().copied().unwrap_or(f64::NAN);
    let cells = a * n as f64 / side;
    rep.rows.push(Row::rel(
        format!(
            "body-centred cubic, two spheres, h = 1/16 ({cells:.1} cells per radius): mean U over the last traversal / U_Hasimoto"
        ),
        1.0,
        u / u_h,
        0.02,
    ));
    // Both spheres are points of one lattice and sit on the grid alike: only round-off can
    // tell them apart.
    rep.rows.push(Row::abs(
        "body-centred cubic: largest velocity difference of the two spheres / U_Hasimoto",
        0.0,
        spread / u_h,
        1e-6,
    ));
    rep.notes.push(format!(
        "body-centred cubic (box 1.25, 20^3, volume fraction {c:.4}, U_Hasimoto / U_Stokes = \
         {k:.4}, g = {g:.3}): {crossings} crossings of the bottom face by the first sphere in {} \
         steps ({:.1} s); mean U / U_Hasimoto by traversal: {}",
        curve.len(),
        start.elapsed().as_secs_f64(),
        by_traversal(&means, u_h)
    ));
    Ok(())
}
