//! Reduced versions of the `tumble validate` cases: each asserts against an analytic solution
//! or a published reference with the case's own tolerance (see `src/validate.rs`).

use tumble::validate::run_case;

fn check(case: &str) {
    let rep = run_case(case, true).expect("case runs");
    println!("{rep}");
    assert!(rep.passed(), "{rep}");
}

#[test]
fn poisson_matches_analytic_velocity() {
    check("poisson");
}

#[test]
fn remesh_conserves_circulation_and_moments() {
    check("remesh");
}

#[test]
fn lamb_oseen_peak_and_core_radius() {
    check("lamb-oseen");
}

#[test]
fn taylor_green_2d_energy_decay() {
    check("taylor-green-2d");
}

#[test]
fn taylor_green_3d_energy() {
    check("taylor-green-3d");
}

#[test]
fn unknown_case_is_an_error() {
    assert!(run_case("no-such-case", true).is_err());
}

#[test]
fn stokes_settling_in_a_periodic_box_against_hasimoto() {
    // body_coupling: Momentum at h = 1/32, densities 0.5, 1.1, 2 and 5, and the paper's
    // Eulerian form at ln 2 of it (about 20 s).
    check("stokes-settling");
}

#[test]
fn sphere_settling_terminal_velocity_at_h_1_64() {
    // Paper Table 1, d = 0.3, ν = 0.02 at h = 1/64 (about a minute).
    check("sphere-settling");
}

#[test]
fn rebound_in_vacuum_keeps_the_drop_height() {
    // Paper Fig. 1, full resolution (a few seconds).
    check("rebound-vacuum");
}

#[test]
fn tank_of_fifty_spheres_in_vacuum_keeps_its_energy() {
    // 50 of the 200 spheres of `tank-200-vacuum` to t = 0.5 (about 10 s): total energy within 5%.
    check("tank-vacuum");
}

#[test]
fn ellipsoid_on_sphere_spins_about_three_axes_and_keeps_its_energy() {
    // Paper Fig. 9, full resolution (a few seconds).
    check("ellipsoid-sphere");
}

#[test]
fn dkt_spheres_draft_kiss_and_tumble() {
    // Paper section 4.2.2, full case (h = 1/60 to t = 0.7, about 30 s): drafting, kissing and
    // tumbling.
    check("dkt");
}

#[test]
fn tank_bottom_layer_settles_on_the_floor_in_fluid() {
    // The bottom layer (36 spheres) of `tank-200` settles onto the floor through the fluid to
    // t = 1.5 (about 15 s): at rest, touching, never overlapping by more than ε/2.
    check("tank-pile");
}
