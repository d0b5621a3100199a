//! `tumble validate`: the validation cases, each checked against an analytic solution or a
//! published reference, never against the code's own earlier output.
//!
//! A case prints a table of quantity, reference, measured value, error and tolerance, then
//! `PASS <case>` or `FAIL <case>`. `quick` runs a reduced version (used by `cargo test`).
//!
//! Cases with a reference curve or reference values also collect [`PlotSpec`]s while they run:
//! the measured curve over the reference. [`run_case`] only collects them; `tumble validate`
//! writes them as PNG files with [`Report::write_plots`].

use crate::base::grid::Grid;
use crate::scene::{RemeshKernel, Scene, ValidScene};
use crate::sim::engine::Simulation;
use crate::solvers::Spectral;
use crate::systems::transport::{LinePool, LineScratch, sweep};
use std::f64::consts::PI;
use std::fmt;

mod contact;
pub mod docs;
mod free_surface;
mod high_re_sphere;
mod report;

pub use report::{Check, PlotSeries, PlotSpec, Report, Row};

/// How long a version of a case takes on the 2-core reference machine.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RunTime {
    /// Under about 10 seconds.
    Seconds,
    /// Up to a few minutes.
    Minutes,
    /// Tens of minutes or more.
    Long,
}

impl fmt::Display for RunTime {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.pad(match self {
            RunTime::Seconds => "seconds",
            RunTime::Minutes => "minutes",
            RunTime::Long => "tens of minutes or more",
        })
    }
}

/// One validation case: the single list [`CASES`] is what `tumble validate`, `tumble
/// validate --list`, the quick tier of `cargo test` and `docs/validation.md` all read.
#[derive(Debug, Clone, Copy)]
pub struct Case {
    /// Name on the command line.
    pub name: &'static str,
    /// What is checked.
    pub description: &'static str,
    /// The analytic solution or publication the checks compare with.
    pub reference: &'static str,
    /// What the full version runs.
    pub full: &'static str,
    /// What the quick version (`--quick`, `cargo test --release`) runs.
    pub quick: &'static str,
    /// Run time class of the full version.
    pub full_time: RunTime,
    /// Run time class of the quick version.
    pub quick_time: RunTime,
    /// Rows known to fail (shown as failing, tracked by an issue).
    pub known_failures: &'static [KnownFailure],
    /// Runs the case (`true`: the quick version).
    run: fn(bool) -> anyhow::Result<Report>,
}

impl Case {
    /// Runs the case; an error of the run (a blow-up, a scene that does not load) is a
    /// failed report carrying the error, so that every tier shows it as failing.
    pub fn run(&self, quick: bool) -> Report {
        let start = std::time::Instant::now();
        let mut rep = (self.run)(quick).unwrap_or_else(|e| {
            let mut rep = Report::new(self.name);
            rep.error = Some(format!("{e:#}"));
            rep
        });
        rep.quick = quick;
        rep.seconds = start.elapsed().as_secs_f64();
        rep.known = self
            .known_failures
            .iter()
            .filter(|k| if quick { k.quick } else { k.full })
            .copied()
            .collect();
        rep
    }
}

/// A row of a case that is known to fail, with the reason and the issue that owns it. The
/// row still runs and is still shown as FAIL (by `tumble validate`, in `docs/validation.md`
/// and in the quick tier's output); the quick-tier test fails if any other row fails, and
/// also if a known failure starts passing, so the list cannot go stale.
#[derive(Debug, Clone, Copy)]
pub struct KnownFailure {
    /// The start of the row's quantity text.
    pub row: &'static str,
    /// Whether it fails in the quick version.
    pub quick: bool,
    /// Whether it fails in the full version.
    pub full: bool,
    /// Why, with the measured numbers and the issue that will decide it.
    pub why: &'static str,
}

/// Every case, in the order `tumble validate` runs them.
pub const CASES: &[Case] = &[
    Case {
        name: "poisson",
        description: "velocity from a smooth periodic vorticity, 2D and 3D, within 1e-10",
        reference: "analytic",
        full: "2D 128x192, 3D 64x48x80",
        quick: "2D 32x48, 3D 16x24x20",
        full_time: RunTime::Seconds,
        quick_time: RunTime::Seconds,
        run: |quick| Ok(poisson(quick)),
        known_failures: &[],
    },
    Case {
        name: "remesh",
        description: "push + M'4 remesh conserves circulation to round-off, first and second moments exactly",
        reference: "analytic",
        full: "64x64, uniform and sheared displacement",
        quick: "the full case (it takes milliseconds)",
        full_time: RunTime::Seconds,
        quick_time: RunTime::Seconds,
        run: |_| Ok(remesh()),
        known_failures: &[],
    },
    Case {
        name: "lamb-oseen",
        description: "peak vorticity and core radius within 1% once the core area has doubled",
        reference: "analytic",
        full: "scenes/lamb-oseen.ron (128x128)",
        quick: "the full case (under a second)",
        full_time: RunTime::Seconds,
        quick_time: RunTime::Seconds,
        run: lamb_oseen,
        known_failures: &[],
    },
    Case {
        name: "taylor-green-2d",
        description: "kinetic energy against exp(-2 nu k^2 t) within 0.5% over one decay time",
        reference: "analytic",
        full: "128x128",
        quick: "64x64",
        full_time: RunTime::Seconds,
        quick_time: RunTime::Seconds,
        run: taylor_green_2d,
        known_failures: &[],
    },
    Case {
        name: "taylor-green-3d",
        description: "E(t = 5) within 2% of 0.1184 at Re = 1600",
        reference: "spectral DNS (Brachet et al. 1983; van Rees et al. 2011)",
        full: "64^3, 96^3 and 128^3; the grid-scale dissipation's share of the energy lost falls with h",
        quick: "48^3 (the same 2% tolerance)",
        full_time: RunTime::Minutes,
        quick_time: RunTime::Seconds,
        run: taylor_green_3d,
        known_failures: &[],
    },
    Case {
        name: "high-re-sphere",
        description: "a sphere of density 1.2 falling through water (nu = 1e-4 cgs, Re about 1.4e4, cell Reynolds number about 1000) with the default numerics: it runs to the end, rests on the floor of a closed box, the fluid's energy never grows once it rests, and the grid-scale dissipation removes the same energy per unit time at any step",
        reference: "energy balance of a flow with no driving (dE/dt <= 0 once the body rests); the dissipation's rate per unit time (issue 32); the standard drag curve (Clift & Gauvin 1970) for the open box, printed only",
        full: "closed box at 64^3 and 96^3 to t = 0.6, the dissipation at 1/2 and 1/4 of the step, the open periodic box 64x64x128 to t = 0.3",
        quick: "closed box at 64^3 to t = 0.6, the dissipation at 1/2 and 1/4 of the step",
        full_time: RunTime::Minutes,
        quick_time: RunTime::Minutes,
        run: high_re_sphere::high_re_sphere,
        known_failures: &[KnownFailure {
            row: "64^3: energy removed by the grid-scale dissipation by t = 0.1 at 0.25 of the step",
            quick: true,
            full: true,
            why: "+18.7% (2.618e-3 against 2.206e-3, each interpolated to t = 0.1 between the steps around it; +4.4% at half the step). The dissipation is a rate per unit time, exactly (tests/suite/spectral.rs), but the state it acts on is not: the M'4 remesh, the method's other sink at the grid scale, damps a mode by O(delta^2) per step, so over a fixed time by O(dt), and at a smaller step more energy reaches the grid scale and the dissipation removes more. Taylor-Green at 64^3 shows the same: removed by t = 5 2.79e-4, 3.61e-4, 4.51e-4 at c = 0.5, 0.25, 0.125 (a per-step filter would remove 2 and 4 times as much); issue 32",
        }],
    },
    Case {
        name: "sedimentation-2d",
        description: "a disk settling onto the floor of a cavity: max fall velocity of two grids within 2% of each other; the disk stays above the floor, rebounds and rests without oscillating; doubling kappa moves the height curve by less than 2h at every time",
        reference: "paper section 4.1",
        full: "h = 1/256 and 1/384, kappa doubled at 1/256",
        quick: "h = 1/64 and 1/96, kappa doubled at 1/64 (the same tolerances)",
        full_time: RunTime::Long,
        quick_time: RunTime::Seconds,
        run: sedimentation_2d,
        known_failures: &[KnownFailure {
            row: "max fall velocity, finer grid against coarser",
            quick: true,
            full: false,
            why: "the quick grids (h = 1/64 and 1/96, 8 and 12 cells per radius) refine h and dt together far from the range of the paper's 2% (h = 1/256 against 1/384, where the full case measured 1.9% with Baroclinic): 6.7% here under Pressure (10.92 and 11.66; Baroclinic 5.5%); at a common dt = 7.5e-4 the two grids differ by 3.9% under either coupling; issue 16",
        }],
    },
    Case {
        name: "sphere-settling",
        description: "terminal velocities at h = 1/64 within 8% of the experimental U_E; grid study at a fixed diffusion number converging monotonically, extrapolated within 5% of the paper's 1.51; mesh icosphere within 2% of the analytic sphere",
        reference: "paper Table 1",
        full: "the six (d, nu) cases, grid study h = 1/32 to 1/96, icosphere",
        quick: "d = 0.3, nu = 0.02 at h = 1/48 (the same 8% against U_E)",
        full_time: RunTime::Long,
        quick_time: RunTime::Minutes,
        run: sphere_settling,
        known_failures: &[],
    },
    Case {
        name: "stokes-settling",
        description: "a sphere settling at Re << 1 in a periodic box: U within 2% of Hasimoto's for body/fluid densities 0.01 to 1000 at diffusion number 0.5, and within 2% of each other at diffusion numbers 0.125, 0.5 and 2 (density 2)",
        reference: "Hasimoto 1959, Sangani & Acrivos 1982",
        full: "h = 1/32 and 1/48, densities 0.01, 0.1, 0.5, 1.1, 2, 5, 20, 100, 1000",
        quick: "h = 1/32, densities 0.01, 0.5, 2 and 20 (100 and 1000 relax over 0.2 and 2.2 time units: thousands of steps)",
        full_time: RunTime::Long,
        quick_time: RunTime::Minutes,
        run: stokes_settling,
        known_failures: &[
            KnownFailure {
                row: "h = 1/32 (3.2 cells per radius), density 0.01:",
                quick: true,
                full: true,
                why: "+6.7% (body_coupling: Pressure); the rigid band beyond the surface and the no-slip imposed once per step; issue 16",
            },
            KnownFailure {
                row: "h = 1/32 (3.2 cells per radius), density 20:",
                quick: true,
                full: true,
                why: "-6.9% (body_coupling: Pressure; the error grows with the density: -1.6% at 2); issue 16",
            },
            KnownFailure {
                row: "h = 1/32 (3.2 cells per radius), density 100:",
                quick: false,
                full: true,
                why: "-16% (Aitken from 0.7361, 0.7925, 0.8184 of U_H at t = 0.30, 0.41, 0.52): the drag grows with the body's density under Pressure (-1.6% at 2, -6.9% at 20); measured before the spectral diffusion (2026-11-24); issue 16",
            },
            KnownFailure {
                row: "h = 1/32 (3.2 cells per radius), density 1000:",
                quick: false,
                full: true,
                why: "-59% (Aitken from 0.149, 0.295, 0.359 of U_H at t = 0.30, 0.85, 1.40: the drag is 2.4 times Hasimoto's while the start accelerates at the right rate; measured before the spectral diffusion, 2026-11-24); issue 16",
            },
            KnownFailure {
                row: "h = 1/32, density 2: (max - min) / min of U over diffusion numbers",
                quick: true,
                full: true,
                why: "U / U_Hasimoto = 0.826, 0.984, 1.456 at diffusion numbers 0.125, 0.5, 2: the no-slip is imposed once per step and the implicit diffusion softens it in between; issue 16 (penalization inside the diffusion solve)",
            },
        ],
    },
    Case {
        name: "dt-independence",
        description: "Table 1's d = 0.3, nu = 0.02: terminal velocity within 1% at dt, dt/2 and dt/4 (dt the default adaptive step); a step shortened to land on an output time changes the velocity by less than 0.1% beyond the trend",
        reference: "issue 16 (a converged method does not depend on the time step)",
        full: "h = 1/48",
        quick: "h = 1/32 (the same tolerances)",
        full_time: RunTime::Minutes,
        quick_time: RunTime::Minutes,
        run: dt_independence,
        known_failures: &[
            KnownFailure {
                row: "h = 1/32, Δt: velocity jump at a step shortened",
                quick: true,
                full: false,
                why: "4.2% in the one shortened step (0.1% asked; 0.65% before the grid-scale dissipation of issue 32, which removes within a step whatever the penalization puts in the corners of the cube of wavenumbers, whatever the step's length; a weight summed per axis instead, which never does, gave 1.1% but let the high-re-sphere closed box blow up at t = 0.227): the drag depends on the step length (no-slip imposed once per step); issue 35",
            },
            KnownFailure {
                row: "h = 1/32: U(t = 1.2) at Δt/2",
                quick: true,
                full: false,
                why: "1.2634 against 1.2851 at Δt (-1.7%; before the grid-scale dissipation of issue 32: 1.2085 against 1.3233, -8.7%): the drag depends on ν Δt / h² and on the step; issue 35",
            },
            KnownFailure {
                row: "h = 1/32: U(t = 1.2) at Δt/4",
                quick: true,
                full: false,
                why: "1.1862 against 1.2851 at Δt (-7.7%; before the grid-scale dissipation of issue 32: 1.1831 against 1.3233, -10.6%); issue 35",
            },
            KnownFailure {
                row: "h = 1/48: U(t = 1.2) at Δt/",
                quick: false,
                full: true,
                why: "measured in the last session with the same coupling and Fixed steps 0.005, 0.0025, 0.00125: 1.3657, 1.3254, 1.2963 (-3.0%, -5.1%); issue 16",
            },
        ],
    },
    Case {
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
                why: "the smoothed band the penalization moves rigidly (about 0.87 eps beyond the surface) adds fluid to a light body's mass: +79% at 12.8 cells per radius, +41% at 25.6 (before the excess momentum travelled with the body: +75% at 12.8); issue 16",
            },
            KnownFailure {
                row: "disk, density 1.5,",
                quick: true,
                full: true,
                why: "-6.3% at 12.8 cells per radius, -3.9% at 25.6: the rigid band beyond the surface (first order in eps/R); issue 16",
            },
            KnownFailure {
                row: "disk, density 3,",
                quick: true,
                full: true,
                why: "-5.3% at 12.8 cells per radius, -3.2% at 25.6: the rigid band beyond the surface; issue 16",
            },
            KnownFailure {
                row: "sphere, density 0.1,",
                quick: true,
                full: true,
                why: "+97% at 8 cells per radius, +80% at 12: the rigid band adds fluid to a light body's mass (about 3 x 0.87 eps/R of its volume); issue 16",
            },
            KnownFailure {
                row: "sphere, density 1.5,",
                quick: true,
                full: true,
                why: "-11.4% at 8 cells per radius, -8.0% at 12: the rigid band beyond the surface; issue 16",
            },
            KnownFailure {
                row: "sphere, density 3,",
                quick: true,
                full: true,
                why: "-8.9% at 8 cells per radius, -6.0% at 12: the rigid band beyond the surface; issue 16",
            },
            KnownFailure {
                row: "sphere, density 10,",
                quick: true,
                full: false,
                why: "-3.8% at 8 cells per radius (-2.5% at 12): the rigid band beyond the surface; issue 16",
            },
            KnownFailure {
                row: "disk, density 0.001, 12.8 cells per radius, released",
                quick: true,
                full: false,
                why: "2.31 a0 t: a body lighter than the fluid around it is wrong under Pressure (the fluid's share of the flow's change is divided by a mass that is mostly the rigid band's fluid); issue 16",
            },
            KnownFailure {
                row: "disk, density 0.001, 25.6 cells per radius, released",
                quick: false,
                full: true,
                why: "4.52 a0 t (2.31 at 12.8 cells per radius): a disk much lighter than the fluid accelerates too fast, and more so on the finer grid; not understood (the sphere converges: 0.65 at 8 cells, 0.963 at 12); issue 16",
            },
            KnownFailure {
                row: "sphere, density 0.001, 12.0 cells per radius, released",
                quick: false,
                full: true,
                why: "0.963 a0 t (-3.7%; 0.65 at 8 cells per radius): the rigid band's fluid mass, shrinking with h; issue 16",
            },
            KnownFailure {
                row: "sphere, density 0.001, 8.0 cells per radius, released",
                quick: true,
                full: false,
                why: "0.65 a0 t: the rigid band's fluid mass (about 0.5 of the sphere's volume at 8 cells per radius) is added to the body; issue 16",
            },
        ],
    },
    Case {
        name: "stratified-rest",
        description: "a two-layer fluid at rest (density 10 below 1, walls above and below) stays at rest: max |u| below 1e-6 sqrt(g L) for 1000 steps",
        reference: "hydrostatics (exact discrete balance)",
        full: "2D 96^2 and 3D 32^3",
        quick: "2D 48^2",
        full_time: RunTime::Seconds,
        quick_time: RunTime::Seconds,
        run: stratified_rest,
        known_failures: &[],
    },
    Case {
        name: "rebound-vacuum",
        description: "three rebounds within 2% of the drop height; smallest gap in [0.1, 3] eps",
        reference: "paper Fig. 1",
        full: "scenes/rebound-vacuum.ron",
        quick: "the full case (a few seconds)",
        full_time: RunTime::Seconds,
        quick_time: RunTime::Seconds,
        run: contact::rebound_vacuum,
        known_failures: &[],
    },
    Case {
        name: "ellipsoid-sphere",
        description: "after contact the ellipsoid turns about all three axes; total energy within 5%",
        reference: "paper Fig. 9",
        full: "scenes/ellipsoid-sphere.ron",
        quick: "the full case (a few seconds)",
        full_time: RunTime::Seconds,
        quick_time: RunTime::Seconds,
        run: contact::ellipsoid_sphere,
        known_failures: &[],
    },
    Case {
        name: "dkt",
        description: "drafting, kissing and tumbling: kiss between t = 0.25 and 0.4, smallest gap below 2h and never negative, horizontal distance above one radius and growing by t = 0.6",
        reference: "paper section 4.2.2",
        full: "scenes/dkt.ron (h = 1/60) to t = 0.7",
        quick: "the full case (at h = 1/30 the spheres would be 2.5 cells in radius)",
        full_time: RunTime::Minutes,
        quick_time: RunTime::Minutes,
        run: contact::dkt,
        known_failures: &[KnownFailure {
            row: "horizontal distance of the centres at t = 0.6 exceeds one radius",
            quick: true,
            full: true,
            why: "0.028 at t = 0.6 and 0.041 at 0.65 under the default Pressure coupling: the pair tumbles late (kiss at 0.318). Not a converged criterion for either coupling: Baroclinic passes at the scene's step (0.094) but does not tumble at half of it, Pressure (before the excess-momentum fix) reached 0.052 at half of it; issue 16",
        }],
    },
    Case {
        name: "tank-vacuum",
        description: "spheres dropped in a box in vacuum: total energy within 5%, no overlap deeper than eps/2",
        reference: "conservation of energy",
        full: "200 spheres (scenes/tank-200-vacuum.ron)",
        quick: "the first 50 spheres to t = 0.5",
        full_time: RunTime::Minutes,
        quick_time: RunTime::Seconds,
        run: contact::tank_vacuum,
        known_failures: &[],
    },
    Case {
        name: "tank-pile",
        description: "spheres dropped in a box of fluid: no overlap deeper than eps/2; at the end at rest (under 2% of the Stokes velocity) and every sphere touching another or the floor",
        reference: "issue criterion (Stokes settling velocity)",
        full: "200 spheres (scenes/tank-200.ron) to t = 6",
        quick: "the bottom layer (36 spheres) to t = 1.5",
        full_time: RunTime::Long,
        quick_time: RunTime::Minutes,
        run: contact::tank_pile,
        known_failures: &[],
    },
    Case {
        name: "still-pool",
        description: "a pool at rest (liquid 0.5 deep under 0.5 of gas, floor and lid) stays at rest: max |u| below 1e-3 sqrt(g H) over 1000 steps, liquid volume within 0.1%",
        reference: "hydrostatics",
        full: "2D, h = 1/128, density ratios 1:10, 1:100, 1:1000",
        quick: "2D, h = 1/64, ratios 1:10 and 1:100",
        full_time: RunTime::Minutes,
        quick_time: RunTime::Seconds,
        run: free_surface::still_pool,
        known_failures: &[],
    },
    Case {
        name: "standing-wave",
        description: "a standing wave (wavelength 1, amplitude 0.01, depth 0.5 under 0.5 of gas) oscillates at the two-fluid dispersion frequency within 2%; its amplitude never grows",
        reference: "linear theory: omega^2 = g k (rho1 - rho2) / (rho1 coth k h1 + rho2 coth k h2)",
        full: "2D, h = 1/128, 3 periods, ratios 1:10, 1:100, 1:1000",
        quick: "2D, h = 1/64, 2 periods, ratios 1:10 and 1:100",
        full_time: RunTime::Minutes,
        quick_time: RunTime::Seconds,
        run: free_surface::standing_wave,
        known_failures: &[
            KnownFailure {
                row: "1:10 wave, h = 1/64: frequency",
                quick: true,
                full: false,
                why: "-2.1% (2.2150 against 2.2631): an error of first order in h (at density ratio 1:2, -3.9% at h = 1/64 and -1.6% at 1/128), the interface's smoothed density over 2h; the full tier (h = 1/128) was not run yet; issue 17",
            },
            KnownFailure {
                row: "1:100 wave: amplitude never grows",
                quick: true,
                full: false,
                why: "the fourth half-period peak is 0.01004 against 0.00982 a period before (+2.2%): at ratios of 1:100 and above the interface gets noisy after two periods (at 1:1000 and h = 1/128 the zero crossings become erratic after t = 5); issue 17",
            },
        ],
    },
    Case {
        name: "rayleigh-taylor",
        description: "heavy over light, Atwood 0.5, single mode of amplitude 0.002 from rest: growth rate within 5% of sqrt(A g k + nu^2 k^4) - nu k^2",
        reference: "linear theory (Chandrasekhar 1961)",
        full: "2D, h = 1/64 and 1/128",
        quick: "2D, h = 1/64",
        full_time: RunTime::Minutes,
        quick_time: RunTime::Seconds,
        run: free_surface::rayleigh_taylor,
        known_failures: &[],
    },
    Case {
        name: "floating",
        description: "flat boxes of density 0.25, 0.5, 0.75 settle at Archimedes' draft within one cell; a disk of density 0.5 released under water floats with its centre within one cell of the waterline; a disk of density 2 sinks to the floor",
        reference: "Archimedes",
        full: "2D, h = 1/128, ratio 1:1000",
        quick: "2D, h = 1/64, ratio 1:100",
        full_time: RunTime::Minutes,
        quick_time: RunTime::Seconds,
        run: free_surface::floating,
        known_failures: &[],
    },
    Case {
        name: "cup",
        description: "the paper's Fig. 10: a cup of density 1.2 dropped onto water enters it, rises again briefly after the impact, turns, fills and ends on the floor; liquid volume within 1%",
        reference: "Coquerelle & Cottet 2008, section 5, Fig. 10",
        full: "scenes/cup.ron (128^3, ratio 1:100) to t = 0.6",
        quick: "scenes/cup.ron at 48^3 (about 2 minutes on 2 cores)",
        full_time: RunTime::Long,
        quick_time: RunTime::Minutes,
        run: free_surface::cup,
        known_failures: &[
            KnownFailure {
                row: "the run reaches t = 0.6 without blowing up",
                quick: false,
                full: true,
                why: "at 128^3 the run passes t = 0.0154, where it blew up before the grid-scale dissipation of issue 32, but its energy climbs from 1.86 at t = 0.024 to 17 at 0.033 and 200 at 0.036 (max |vorticity| 5e4, the step down to 3e-6), in the gas at the waterline after the impact: the interface at a density ratio of 1:100 in a violent flow; issue 34",
            },
            KnownFailure {
                row: "the cup ends on the floor",
                quick: true,
                full: true,
                why: "since the grid-scale dissipation (issue 32) the 48^3 run reaches t = 0.6: the cup enters the water, its centre rises 0.109 after the impact, it turns (20.9 rad per unit time), the volume holds to 3e-14, but at t = 0.6 its centre is still 1.21 cup heights above the floor (it has not filled and sunk yet; at 64^3, 0.83 cup heights, sinking at 0.3, with the gas at the waterline stirred to an energy of about 20). Before, it blew up at t = 0.055 (48^3); issues 32 and 34",
            },
        ],
    },
];

/// A case by name.
pub fn find_case(name: &str) -> Option<&'static Case> {
    CASES.iter().find(|c| c.name == name)
}

/// The bundled scenes, by file name (so validation runs from any directory).
pub const SCENES: &[(&str, &str)] = &[
    (
        "lamb-oseen.ron",
        include_str!("../../scenes/lamb-oseen.ron"),
    ),
    (
        "taylor-green-2d.ron",
        include_str!("../../scenes/taylor-green-2d.ron"),
    ),
    (
        "taylor-green-3d.ron",
        include_str!("../../scenes/taylor-green-3d.ron"),
    ),
    (
        "vortex-ring.ron",
        include_str!("../../scenes/vortex-ring.ron"),
    ),
    (
        "sedimentation-2d.ron",
        include_str!("../../scenes/sedimentation-2d.ron"),
    ),
    (
        "sphere-settling.ron",
        include_str!("../../scenes/sphere-settling.ron"),
    ),
    (
        "rebound-vacuum.ron",
        include_str!("../../scenes/rebound-vacuum.ron"),
    ),
    (
        "ellipsoid-sphere.ron",
        include_str!("../../scenes/ellipsoid-sphere.ron"),
    ),
    ("dkt.ron", include_str!("../../scenes/dkt.ron")),
    ("cup.ron", include_str!("../../scenes/cup.ron")),
    ("tank-200.ron", include_str!("../../scenes/tank-200.ron")),
    (
        "tank-200-vacuum.ron",
        include_str!("../../scenes/tank-200-vacuum.ron"),
    ),
];

/// A bundled scene by file name.
pub fn bundled_scene(file: &str) -> anyhow::Result<ValidScene> {
    let (_, text) = SCENES
        .iter()
        .find(|(f, _)| *f == file)
        .ok_or_else(|| anyhow::anyhow!("no bundled scene {file}"))?;
    let stem = file.trim_end_matches(".ron");
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    Ok(Scene::parse_in(
        text,
        &format!("scenes/{file}"),
        stem,
        &dir,
    )?)
}

/// Run one case by name (an error only for an unknown name; a case whose run fails gives a
/// failed report).
pub fn run_case(case: &str, quick: bool) -> anyhow::Result<Report> {
    match find_case(case) {
        Some(c) => Ok(c.run(quick)),
        None => anyhow::bail!(
            "unknown validation case `{case}`; the cases are: {}",
            CASES.iter().map(|c| c.name).collect::<Vec<_>>().join(", ")
        ),
    }
}

/// Velocity from a smooth periodic vorticity against the analytic velocity (2D and 3D).
fn poisson(quick: bool) -> Report {
    let mut rep = Report::new("poisson");
    // 2D: ψ = sin(2πx/Lx) cos(4πy/Ly) on a non-square box; ω = -Δψ, u = ∂ψ/∂y, v = -∂ψ/∂x.
    let (nx, ny) = if quick { (32, 48) } else { (128, 192) };
    let (lx, ly) = (1.0, 1.5);
    let g = Grid::new([nx, ny, 1], lx / nx as f64, [0.3, -0.2, 0.0]);
    let (a, b) = (2.0 * PI / lx, 4.0 * PI / ly);
    let mut omega = vec![vec![0.0; g.len()]];
    let mut exact = vec![vec![0.0; g.len()]; 2];
    for j in 0..ny {
        for i in 0..nx {
            let p = g.pos(i, j, 0);
            let (x, y) = (p[0] - g.origin[0], p[1] - g.origin[1]);
            let idx = g.idx(i, j, 0);
            omega[0][idx] = (a * a + b * b) * (a * x).sin() * (b * y).cos();
            exact[0][idx] = -b * (a * x).sin() * (b * y).sin();
            exact[1][idx] = -a * (a * x).cos() * (b * y).cos();
        }
    }
    let mut u = vec![vec![0.0; g.len()]; 2];
    Spectral::new(&g).velocity(&mut omega, 1, [0.0; 3], &mut u);
    rep.rows.push(Row::abs(
        format!("2D {nx}x{ny}: max |u - u_exact|"),
        0.0,
        max_diff(&u, &exact),
        1e-10,
    ));
    // 3D: ψ = (sin(ky y) sin(kz z), sin(kz z) sin(kx x), sin(kx x) sin(ky y)) (div ψ = 0),
    // ω = -Δψ, u = ∇×ψ.
    let n = if quick { [16, 24, 20] } else { [64, 48, 80] };
    let h = 2.0 * PI / n[0] as f64;
    let g = Grid::new(n, h, [0.0; 3]);
    let ext = g.extent();
    let k = [2.0 * PI / ext[0], 4.0 * PI / ext[1], 2.0 * PI / ext[2]];
    let mut omega = vec![vec![0.0; g.len()]; 3];
    let mut exact = vec![vec![0.0; g.len()]; 3];
    for kk in 0..n[2] {
        for j in 0..n[1] {
            for i in 0..n[0] {
                let p = g.pos(i, j, kk);
                let (sx, cx) = (k[0] * p[0]).sin_cos();
                let (sy, cy) = (k[1] * p[1]).sin_cos();
                let (sz, cz) = (k[2] * p[2]).sin_cos();
                let idx = g.idx(i, j, kk);
                omega[0][idx] = (k[1] * k[1] + k[2] * k[2]) * sy * sz;
                omega[1][idx] = (k[2] * k[2] + k[0] * k[0]) * sz * sx;
                omega[2][idx] = (k[0] * k[0] + k[1] * k[1]) * sx * sy;
                // u = ∇×ψ
                exact[0][idx] = k[1] * sx * cy - k[2] * sx * cz;
                exact[1][idx] = k[2] * sy * cz - k[0] * cx * sy;
                exact[2][idx] = k[0] * cx * sz - k[1] * cy * sz;
            }
        }
    }
    let mut u = vec![vec![0.0; g.len()]; 3];
    Spectral::new(&g).velocity(&mut omega, 1, [0.0; 3], &mut u);
    rep.rows.push(Row::abs(
        format!("3D {}x{}x{}: max |u - u_exact|", n[0], n[1], n[2]),
        0.0,
        max_diff(&u, &exact),
        1e-10,
    ));
    rep
}

fn max_diff(a: &[Vec<f64>], b: &[Vec<f64>]) -> f64 {
    a.iter()
        .zip(b)
        .flat_map(|(x, y)| x.iter().zip(y).map(|(p, q)| (p - q).abs()))
        .fold(0.0, f64::max)
}

/// Moments of a 2D scalar field: Σω, Σωx, Σωy, Σωx², Σωy², Σωxy (grid units, cell sums).
fn moments(g: &Grid, w: &[f64]) -> [f64; 6] {
    let mut m = [0.0; 6];
    for j in 0..g.n[1] {
        for i in 0..g.n[0] {
            let v = w[g.idx(i, j, 0)];
            let (x, y) = (i as f64, j as f64);
            m[0] += v;
            m[1] += v * x;
            m[2] += v * y;
            m[3] += v * x * x;
            m[4] += v * y * y;
            m[5] += v * x * y;
        }
    }
    m
}

/// The M'4 push-and-remesh sweeps conserve circulation to round-off and move the first and
/// second moments exactly as the particles move.
fn remesh() -> Report {
    let mut rep = Report::new("remesh");
    let n = 64;
    let g = Grid::new([n, n, 1], 1.0, [0.0; 3]);
    // A smooth blob with a sign change, far from the box edges.
    let mut w = vec![0.0; g.len()];
    for j in 0..n {
        for i in 0..n {
            let (x, y) = (i as f64 - 30.3, j as f64 - 28.7);
            w[g.idx(i, j, 0)] = (1.0 + 0.3 * x - 0.2 * y) * (-(x * x + y * y) / 30.0).exp();
        }
    }
    let pool = LinePool::per_thread(move || LineScratch::new(n, 1));
    // Uniform velocity: every particle moves by d cells; Σω' = Σω, Σω'x' = Σωx + d Σω,
    // Σω'x'² = Σωx² + 2d Σωx + d² Σω.
    let m0 = moments(&g, &w);
    let (dx, dy) = (0.37, -1.63);
    let mut omega = vec![w.clone()];
    let ux = vec![dx; g.len()];
    let uy = vec![dy; g.len()];
    sweep(
        &g,
        0,
        1.0,
        &mut omega,
        &ux,
        0.0,
        RemeshKernel::M4Prime,
        &pool,
    );
    sweep(
        &g,
        1,
        1.0,
        &mut omega,
        &uy,
        0.0,
        RemeshKernel::M4Prime,
        &pool,
    );
    let m1 = moments(&g, &omega[0]);
    let scale = m0[0].abs().max(1.0);
    rep.rows.push(Row::abs(
        "uniform shift: circulation Σω",
        m0[0],
        m1[0],
        1e-12 * scale,
    ));
    rep.rows.push(Row::abs(
        "uniform shift: first moment Σωx",
        m0[1] + dx * m0[0],
        m1[1],
        1e-10 * m0[1].abs().max(1.0),
    ));
    rep.rows.push(Row::abs(
        "uniform shift: first moment Σωy",
        m0[2] + dy * m0[0],
        m1[2],
        1e-10 * m0[2].abs().max(1.0),
    ));
    rep.rows.push(Row::abs(
        "uniform shift: second moment Σωx²",
        m0[3] + 2.0 * dx * m0[1] + dx * dx * m0[0],
        m1[3],
        1e-10 * m0[3].abs().max(1.0),
    ));
    rep.rows.push(Row::abs(
        "uniform shift: second moment Σωy²",
        m0[4] + 2.0 * dy * m0[2] + dy * dy * m0[0],
        m1[4],
        1e-10 * m0[4].abs().max(1.0),
    ));
    rep.rows.push(Row::abs(
        "uniform shift: cross moment Σωxy",
        m0[5] + dx * m0[2] + dy * m0[1] + dx * dy * m0[0],
        m1[5],
        1e-10 * m0[5].abs().max(1.0),
    ));
    // A non-uniform (sheared, compressive along the line) velocity: circulation is still
    // conserved to round-off.
    let mut omega = vec![w.clone()];
    let mut us = vec![0.0; g.len()];
    for j in 0..n {
        for i in 0..n {
            us[g.idx(i, j, 0)] = 0.8 * (2.0 * PI * (i as f64 + 0.5 * j as f64) / n as f64).sin();
        }
    }
    sweep(
        &g,
        0,
        1.0,
        &mut omega,
        &us,
        0.0,
        RemeshKernel::M4Prime,
        &pool,
    );
    sweep(
        &g,
        1,
        1.0,
        &mut omega,
        &us,
        0.0,
        RemeshKernel::M4Prime,
        &pool,
    );
    let m2 = moments(&g, &omega[0]);
    rep.rows.push(Row::abs(
        "sheared flow: circulation Σω",
        m0[0],
        m2[0],
        1e-12 * scale,
    ));
    rep.notes
        .push("64x64 grid, displacement (0.37, -1.63) cells; moments in grid units".into());
    rep
}

/// Lamb-Oseen: peak vorticity and core radius after the core area has doubled.
fn lamb_oseen(quick: bool) -> anyhow::Result<Report> {
    // The full case takes a fraction of a second, so `quick` runs it unchanged: at 64² the
    // core (σ0 = 3.2 h) is too coarse for M'4 remeshing (peak 7% low), at 128² it is resolved.
    let _ = quick;
    let scene = bundled_scene("lamb-oseen.ron")?;
    let (gamma, s0) = match &scene.initial[0] {
        crate::scene::InitialVorticity::LambOseen {
            circulation,
            core_radius,
            ..
        } => (*circulation, *core_radius),
        _ => anyhow::bail!("lamb-oseen.ron must start with a LambOseen field"),
    };
    let nu = scene.fluid.viscosity;
    let t_end = s0 * s0 / (4.0 * nu);
    let mut sim = Simulation::new(scene)?;
    let peak_of = |s: &Simulation| {
        s.fields().omega()[0]
            .iter()
            .cloned()
            .fold(f64::MIN, f64::max)
    };
    let mut peaks = vec![(sim.time(), peak_of(&sim))];
    sim.run_until(t_end, |s| peaks.push((s.time(), peak_of(s))))?;
    let g = sim.grid().clone();
    let w = &sim.fields().omega()[0];
    let s2 = s0 * s0 + 4.0 * nu * sim.time();
    let peak = w.iter().cloned().fold(f64::MIN, f64::max);
    // Second moment about the centroid: ∫r²ω / ∫ω = σ² for the Gaussian.
    let (mut m0, mut mx, mut my) = (0.0, 0.0, 0.0);
    for j in 0..g.n[1] {
        for i in 0..g.n[0] {
            let p = g.pos(i, j, 0);
            let v = w[g.idx(i, j, 0)];
            m0 += v;
            mx += v * p[0];
            my += v * p[1];
        }
    }
    let (cx, cy) = (mx / m0, my / m0);
    let mut m2 = 0.0;
    for j in 0..g.n[1] {
        for i in 0..g.n[0] {
            let p = g.pos(i, j, 0);
            m2 += w[g.idx(i, j, 0)] * ((p[0] - cx).powi(2) + (p[1] - cy).powi(2));
        }
    }
    let mut rep = Report::new("lamb-oseen");
    rep.rows.push(Row::rel(
        format!("peak vorticity at t = {:.3}", sim.time()),
        gamma / (PI * s2),
        peak,
        0.01,
    ));
    rep.rows.push(Row::rel(
        "core radius σ (from ∫r²ω/∫ω)",
        s2.sqrt(),
        (m2 / m0).sqrt(),
        0.01,
    ));
    rep.notes.push(format!(
        "{}x{} grid, ν = {nu}, σ0 = {s0}, {} steps",
        g.n[0],
        g.n[1],
        sim.steps()
    ));
    let exact: Vec<(f64, f64)> = peaks
        .iter()
        .map(|&(t, _)| (t, gamma / (PI * (s0 * s0 + 4.0 * nu * t))))
        .collect();
    rep.plots.push(
        PlotSpec::new("peak", "peak vorticity", "t", "max ω")
            .measured(format!("measured ({}x{})", g.n[0], g.n[1]), peaks)
            .reference("analytic: Γ / (π (σ0² + 4νt))", exact),
    );
    Ok(rep)
}

/// 2D Taylor-Green: kinetic energy against exp(-2νk²t) over one decay time.
fn taylor_green_2d(quick: bool) -> anyhow::Result<Report> {
    let mut scene = bundled_scene("taylor-green-2d.ron")?;
    if quick {
        scene = scene.edit(|s| s.domain.cells = Some(vec![64, 64]))?;
    }
    let k = match &scene.initial[0] {
        crate::scene::InitialVorticity::TaylorGreen2d { wavenumber, .. } => *wavenumber,
        _ => anyhow::bail!("taylor-green-2d.ron must start with a TaylorGreen2d field"),
    };
    let nu = scene.fluid.viscosity;
    let t_end = 1.0 / (2.0 * nu * 2.0 * k * k);
    let mut sim = Simulation::new(scene)?;
    let e0 = sim.sample().energy;
    let mut worst = (0.0f64, 0.0f64, 0.0f64);
    let mut curve = vec![(sim.time(), 1.0)];
    sim.run_until(t_end, |s| {
        let sm = s.sample();
        let exact = e0 * (-4.0 * nu * k * k * sm.t).exp();
        let err = ((sm.energy - exact) / exact).abs();
        if err > worst.0 {
            worst = (err, sm.t, sm.energy);
        }
        curve.push((sm.t, sm.energy / e0));
    })?;
    let sm = sim.sample();
    let mut rep = Report::new("taylor-green-2d");
    rep.rows.push(Row::rel(
        format!("E(t = {:.3}) / E0 (one decay time)", sm.t),
        (-4.0 * nu * k * k * sm.t).exp(),
        sm.energy / e0,
        0.005,
    ));
    rep.rows.push(Row::rel(
        format!("worst E(t)/E0 over the run (at t = {:.3})", worst.1),
        (-4.0 * nu * k * k * worst.1).exp(),
        worst.2 / e0,
        0.005,
    ));
    rep.notes.push(format!(
        "{}x{} grid, ν = {nu}, {} steps",
        sim.grid().n[0],
        sim.grid().n[1],
        sim.steps()
    ));
    let exact: Vec<(f64, f64)> = curve
        .iter()
        .map(|&(t, _)| (t, (-4.0 * nu * k * k * t).exp()))
        .collect();
    rep.plots.push(
        PlotSpec::new("energy", "kinetic energy decay", "t", "E(t) / E0")
            .measured(
                format!("measured ({}x{})", sim.grid().n[0], sim.grid().n[1]),
                curve,
            )
            .reference("analytic: exp(-2ν|k|²t), |k|² = 2k²", exact),
    );
    Ok(rep)
}

/// 3D Taylor-Green at Re = 1600: kinetic energy at t = 5 against the spectral reference.
fn taylor_green_3d(quick: bool) -> anyhow::Result<Report> {
    // Reference: E(5) = 0.1184 for E0 = 0.125 (spectral DNS of the Re = 1600 Taylor-Green
    // vortex, e.g. Brachet et al. 1983; van Rees et al., J. Comput. Phys. 230 (2011)).
    const E5: f64 = 0.1184;
    let mut rep = Report::new("taylor-green-3d");
    let sizes: &[usize] = if quick { &[48] } else { &[64, 96, 128] };
    let mut plot = PlotSpec::new("energy", "kinetic energy, Re = 1600", "t", "E(t)");
    // What the grid-scale dissipation removed by t = 5, relative to the energy lost.
    let mut share = Vec::new();
    for &n in sizes {
        let scene =
            bundled_scene("taylor-green-3d.ron")?.edit(|s| s.domain.cells = Some(vec![n, n, n]))?;
        let mut sim = Simulation::new(scene)?;
        let e0 = sim.sample().energy;
        let start = std::time::Instant::now();
        let mut curve = vec![(sim.time(), e0)];
        sim.run_until(5.0, |s| curve.push((s.time(), s.sample().energy)))?;
        plot = plot.measured(format!("measured {n}^3"), curve);
        let e = sim.sample().energy;
        rep.rows
            .push(Row::rel(format!("{n}^3: E(t = 5)"), E5, e, 0.02));
        let removed = sim
            .world
            .resource::<crate::systems::diffusion::GridScaleDissipation>()
            .removed;
        share.push((n, removed / (e0 - e)));
        rep.notes.push(format!(
            "{n}^3: E0 = {e0:.6} (0.125 exact), {} steps, {:.1} s; the grid-scale dissipation removed {removed:.3e} by t = 5, {:.3}% of the energy lost",
            sim.steps(),
            start.elapsed().as_secs_f64(),
            100.0 * removed / (e0 - e)
        ));
    }
    if share.len() > 1 {
        rep.rows.push(Row::yes_no(
            format!(
                "the grid-scale dissipation's share of the energy lost by t = 5 falls as h does ({})",
                share
                    .iter()
                    .map(|(n, f)| format!("{n}^3: {:.3}%", 100.0 * f))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
            share.windows(2).all(|w| w[1].1 < w[0].1),
        ));
    }
    if quick {
        rep.notes
            .push("quick: 48^3 only, with the 2% tolerance the case sets for 128^3".into());
    }
    rep.plots
        .push(plot.reference_points("spectral DNS: E(5) = 0.1184", vec![(5.0, E5)]));
    Ok(rep)
}

/// The state of the first dynamic body.
pub(crate) fn dynamic_body(sim: &mut Simulation) -> Option<crate::bodies::RigidState> {
    let mut q = sim
        .world
        .query::<(&crate::bodies::Body, &crate::bodies::RigidState)>();
    q.iter(&sim.world)
        .find(|(b, _)| b.is_dynamic())
        .map(|(_, s)| *s)
}

/// What one sedimentation-2d run measured.
struct Sedimentation {
    /// Largest fall speed.
    vmax: f64,
    /// Lowest point of the disk relative to the cavity floor (negative: below it).
    ymin: f64,
    /// Largest relative deviation from rigid motion of the vertical velocity across the disk
    /// during the fall.
    dev: f64,
    /// Height of the first bounce: the first maximum of the centre's height after the impact
    /// minus the impact minimum.
    rebound: f64,
    /// Speed at the end of the run (0.3 after the first impact), relative to `vmax`.
    final_speed: f64,
    /// Local minima of the height after the first impact, deeper than 1% of the radius (1 or
    /// 2: impact, landing; more is an oscillation).
    bounces: usize,
    /// Why the run stopped early, if it did.
    failure: Option<String>,
    /// (t, vertical velocity of the disk) after every step.
    vy: Vec<(f64, f64)>,
    /// (t, height of the disk's centre) after every step.
    y: Vec<(f64, f64)>,
}

/// One sedimentation-2d run at spacing `h`, step `dt` and contact strength `kappa`.
fn sedimentation_run(h: f64, dt: f64, kappa: f64) -> anyhow::Result<Sedimentation> {
    let wall = 8.0 * h;
    let scene = bundled_scene("sedimentation-2d.ron")?.edit(|scene| {
        scene.domain.origin = Some(vec![-wall, -wall]);
        scene.domain.extent = vec![2.0 + 2.0 * wall, 6.0 + 2.0 * wall];
        scene.domain.h = Some(h);
        scene.domain.cells = None;
        scene.numerics.dt = crate::scene::TimeStep::Fixed(dt);
        scene.contact.kappa = Some(kappa);
    })?;
    let r = 0.125;
    let mut sim = Simulation::new(scene)?;
    let mut out = Sedimentation {
        vmax: 0.0,
        ymin: f64::INFINITY,
        dev: 0.0,
        rebound: 0.0,
        final_speed: f64::NAN,
        bounces: 0,
        failure: None,
        vy: Vec::new(),
        y: Vec::new(),
    };
    let mut t_contact = None;
    let mut y_impact = f64::INFINITY;
    let mut ys: Vec<f64> = Vec::new();
    sim.set_stop_at(Some(1.5));
    while sim.time() < 1.5 - 1e-12 {
        if let Err(e) = sim.step() {
            out.failure = Some(e.to_string());
            break;
        }
        let Some(st) = dynamic_body(&mut sim) else {
            break;
        };
        out.vy.push((sim.time(), st.velocity.y));
        out.y.push((sim.time(), st.center.y));
        out.vmax = out.vmax.max(-st.velocity.y);
        out.ymin = out.ymin.min(st.center.y - r);
        if t_contact.is_none() && st.velocity.y >= 0.0 && sim.steps() > 10 {
            t_contact = Some(sim.time());
        }
        if t_contact.is_some() {
            y_impact = y_impact.min(st.center.y);
            ys.push(st.center.y);
            out.final_speed = st.velocity.length() / out.vmax;
        }
        if t_contact.is_some_and(|tc| sim.time() > tc + 0.3) {
            break;
        }
        // Rigidity during the fall (disk well away from the floor): on the horizontal line
        // through the centre, nodes at least one cell inside the disk.
        if st.center.y > 1.0 && st.velocity.y < -1.0 && sim.steps() % 20 == 0 {
            let g = sim.grid().clone();
            let u = &sim.fields().u;
            let j = ((st.center.y - g.origin[1]) / g.h).round() as usize;
            for i in 0..g.n[0] {
                let x = g.pos(i, j, 0);
                let d = ((x[0] - st.center.x).powi(2) + (x[1] - st.center.y).powi(2)).sqrt();
                if d < r - g.h {
                    let uy = u[1][g.idx(i, j, 0)];
                    out.dev = out.dev.max(((uy - st.velocity.y) / st.velocity.y).abs());
                }
            }
        }
    }
    // Local minima and maxima of the height after the impact, ignoring wiggles below 1% of
    // the radius: the rebound is the first maximum above the impact minimum, and more than
    // two minima (impact, landing) is an oscillation.
    let tol = 1e-2 * r;
    let mut falling = true;
    let mut extreme = ys.first().copied().unwrap_or(0.0);
    let mut first_min = None;
    let mut first_max = None;
    out.bounces = 1;
    for &y in &ys {
        if falling {
            if y > extreme + tol {
                first_min.get_or_insert(extreme);
                falling = false;
                extreme = y;
            } else {
                extreme = extreme.min(y);
            }
        } else if y < extreme - tol {
            first_max.get_or_insert(extreme);
            falling = true;
            out.bounces += 1;
            extreme = y;
        } else {
            extreme = extreme.max(y);
        }
    }
    let lo = first_min.unwrap_or(y_impact);
    let hi = first_max.unwrap_or(if falling { lo } else { extreme });
    out.rebound = hi - lo;
    Ok(out)
}

/// Paper section 4.1: a 2D disk settling in a cavity onto its floor, with contact.
fn sedimentation_2d(quick: bool) -> anyhow::Result<Report> {
    let mut rep = Report::new("sedimentation-2d");
    let runs: &[(f64, f64)] = if quick {
        &[(1.0 / 64.0, 3e-3), (1.0 / 96.0, 2e-3)]
    } else {
        &[(1.0 / 256.0, 7.5e-4), (1.0 / 384.0, 5e-4)]
    };
    let mut res = Vec::new();
    for &(h, dt) in runs {
        let s = sedimentation_run(h, dt, 30.0)?;
        rep.notes.push(format!(
            "h = 1/{:.0}, dt = {dt}, kappa = 30: max fall velocity {:.4}, lowest point of the disk {:.5} ({:.2} h above the floor), rebound {:.5}, {} local minima of the height after the impact, final speed {:.2e} of the max, max deviation from rigid motion across the disk during the fall {:.2}% (paper, Fig. 2: about 2% at h = 1/512){}",
            1.0 / h,
            s.vmax,
            s.ymin,
            s.ymin / h,
            s.rebound,
            s.bounces,
            s.final_speed,
            100.0 * s.dev,
            s.failure.as_ref().map(|f| format!("; stopped: {f}")).unwrap_or_default()
        ));
        // "Does not pass through": never h/2 (= ε/2) into the wall, the same bound as for
        // the 200-body pile of the collision issue.
        rep.rows.push(Row::yes_no(
            format!(
                "h = 1/{:.0}: the disk never reaches h/2 into the floor",
                1.0 / h
            ),
            s.ymin > -0.5 * h,
        ));
        rep.rows.push(Row::yes_no(
            format!(
                "h = 1/{:.0}: at rest 0.3 after the impact, no oscillation (speed < 1% of max, at most 2 minima > 1% r)",
                1.0 / h
            ),
            s.final_speed < 0.01 && s.bounces <= 2,
        ));
        res.push(s);
    }
    rep.rows.push(Row::rel(
        "max fall velocity, finer grid against coarser",
        res[0].vmax,
        res[1].vmax,
        0.02,
    ));
    let (h, dt) = runs[0];
    let doubled = sedimentation_run(h, dt, 60.0)?;
    // The paper found "almost no effect" of doubling κ: the height curves at the grid's scale.
    // Both runs take the same Fixed steps, so their samples are at the same times.
    let shift = res[0]
        .y
        .iter()
        .zip(&doubled.y)
        .map(|(a, b)| (a.1 - b.1).abs())
        .fold(0.0f64, f64::max);
    rep.rows.push(Row::abs(
        format!(
            "h = 1/{:.0}: largest change of the height curve with kappa = 60 against 30, in h",
            1.0 / h
        ),
        0.0,
        shift / h,
        2.0,
    ));
    rep.notes.push(format!(
        "kappa = 60: rebound {:.5} (kappa = 30: {:.5}), lowest point {:.5}",
        doubled.rebound, res[0].rebound, doubled.ymin
    ));
    // No external reference curve: the resolutions (and the stiffer contact) over each other.
    let mut velocity = PlotSpec::new("velocity", "vertical velocity of the disk", "t", "v_y");
    let mut height = PlotSpec::new("height", "height of the disk's centre", "t", "y");
    for (&(h, dt), s) in runs.iter().zip(&res) {
        let label = format!("h = 1/{:.0}, dt = {dt}, kappa = 30", 1.0 / h);
        velocity = velocity.measured(label.clone(), s.vy.clone());
        height = height.measured(label, s.y.clone());
    }
    let label = format!("h = 1/{:.0}, dt = {dt}, kappa = 60", 1.0 / h);
    velocity = velocity.measured(label.clone(), doubled.vy);
    height = height
        .measured(label, doubled.y)
        .reference_level("touching the floor (y = r)", 0.125);
    rep.plots.push(velocity);
    rep.plots.push(height);
    Ok(rep)
}

/// The coupling the issue-16 rows measure, as a line for a scene's `numerics` block: the
/// default (`Pressure`), written out so the reports say which.
const MODEL: &str = "body_coupling: Pressure";

/// Velocity along gravity of a sphere of radius 0.1 and density `rho` settling in a periodic
/// unit box of fluid (ρ_F = 1, ν = 1) on `n`³ nodes under gravity of magnitude `g`, with the
/// adaptive step at diffusion number `d` and the coupling `coupling` (a line of `numerics`).
/// Returns (t, U) after every step to `t_end`, U > 0 when the body moves the way its excess
/// weight pulls it (down if heavier than the fluid, up if lighter); the error of the run if it
/// fails (a blow-up).
fn periodic_settling(
    n: usize,
    rho: f64,
    g: f64,
    d: f64,
    coupling: &str,
    t_end: f64,
) -> anyhow::Result<Vec<(f64, f64)>> {
    let text = format!(
        r#"Scene(
        name: "stokes-settling",
        domain: (extent: [1.0, 1.0, 1.0], cells: [{n}, {n}, {n}]),
        fluid: (viscosity: 1.0, gravity: [0.0, 0.0, {}]),
        numerics: (end_time: {}, dt: Adaptive(diffusion_number: {d}), {coupling}),
        bodies: [(name: "sphere", shape: Sphere(radius: 0.1), density: {rho},
                  position: [0.5, 0.5, 0.5])],
    )"#,
        -g,
        2.0 * t_end
    );
    let mut sim = Simulation::new(Scene::parse(&text, "stokes-settling", "stokes-settling")?)?;
    // No landing on t_end: every step is the policy's own.
    sim.set_stop_at(None);
    let sign = if rho > 1.0 { -1.0 } else { 1.0 };
    let mut curve = Vec::new();
    while sim.time() < t_end {
        sim.step()?;
        let st = dynamic_body(&mut sim).ok_or_else(|| anyhow::anyhow!("no sphere"))?;
        curve.push((sim.time(), sign * st.velocity.z));
    }
    Ok(curve)
}

/// The steady value of a velocity that relaxes exponentially: Aitken's Δ² on the samples
/// nearest to t_end - 2s, t_end - s and t_end (exact for U∞ + C e^{-t/τ}); the last sample
/// when the second difference is below 1e-9 of it (already steady).
fn steady_value(curve: &[(f64, f64)], s: f64) -> f64 {
    let at = |t0: f64| {
        curve
            .iter()
            .min_by(|x, y| (x.0 - t0).abs().total_cmp(&(y.0 - t0).abs()))
            .map_or(f64::NAN, |e| e.1)
    };
    let t_end = curve.last().map_or(0.0, |e| e.0);
    let (u1, u2, u3) = (at(t_end - 2.0 * s), at(t_end - s), at(t_end));
    let dd = u3 - 2.0 * u2 + u1;
    if dd.abs() <= 1e-9 * u3.abs() {
        u3
    } else {
        u3 - (u3 - u2) * (u3 - u2) / dd
    }
}

/// A sphere settling at Re ≪ 1 in a periodic box (a simple cubic array) against the analytic
/// drag of Hasimoto (1959) and Sangani & Acrivos (1982), for body/fluid density ratios from
/// 0.01 to 1000 and for three diffusion numbers.
fn stokes_settling(quick: bool) -> anyhow::Result<Report> {
    let mut rep = Report::new("stokes-settling");
    let (a, mu, g0) = (0.1f64, 1.0, 1.0);
    let c = 4.0 * PI * a.powi(3) / 3.0;
    let k = 1.0 - 1.7601 * c.cbrt() + c - 1.5593 * c * c;
    // g = g0 / |ρ - 1|: every density settles (or rises) at the same U_Hasimoto, Re = U a / ν
    // = 2.0e-4, far inside the Stokes regime the reference assumes.
    let u_h = 2.0 * g0 * a * a / (9.0 * mu) * k;
    let grids: &[usize] = if quick { &[32] } else { &[32, 48] };
    let t0 = if quick { 0.15 } else { 0.3 };
    let densities: &[f64] = if quick {
        &[0.01, 0.5, 2.0, 20.0]
    } else {
        &[0.01, 0.1, 0.5, 1.1, 2.0, 5.0, 20.0, 100.0, 1000.0]
    };
    // U / U_Hasimoto at density 2, h = 1/32, diffusion number 0.5 (also the middle of the
    // diffusion-number row).
    let mut rho2 = None;
    for &n in grids {
        let mut line = Vec::new();
        for &rho in densities {
            // The slowest relaxations: the periodic flow's, e^{-4π²νt} (0.25% left at
            // t = 0.15, 6e-6 at 0.3), and the sphere's, τ = (2ρ_s/ρ_F + 1) a²/(9ν) (0.2 at
            // density 100, 2.2 at 1000). Past t0 only the sphere's is left, a single
            // exponential, and U∞ is Aitken's extrapolation from three samples s apart.
            let tau = (2.0 * rho + 1.0) * a * a / (9.0 * mu);
            let s = (0.5 * tau).clamp(0.01, 0.25 * 2.2);
            let t_end = t0 + 2.0 * s;
            let g = g0 / (rho - 1.0).abs();
            let row = format!(
                "h = 1/{n} ({:.1} cells per radius), density {rho}: U / U_Hasimoto",
                a * n as f64
            );
            match periodic_settling(n, rho, g, 0.5, MODEL, t_end) {
                Ok(curve) => {
                    let u = steady_value(&curve, s);
                    if n == 32 && rho == 2.0 {
                        rho2 = Some(u / u_h);
                    }
                    line.push(format!("{rho}: {:+.1}%", 100.0 * (u / u_h - 1.0)));
                    rep.rows.push(Row::rel(row, 1.0, u / u_h, 0.02));
                }
                Err(e) => {
                    line.push(format!("{rho}: failed"));
                    rep.notes.push(format!("h = 1/{n}, density {rho}: {e}"));
                    rep.rows.push(Row::rel(row, 1.0, f64::NAN, 0.02));
                }
            }
        }
        rep.notes.push(format!(
            "h = 1/{n}, diffusion number 0.5, U against Hasimoto by density: {}",
            line.join(", ")
        ));
    }
    // The drag must not depend on the time step: density 2 at diffusion numbers 0.125, 0.5
    // and 2 (Δt = d h²/ν), h = 1/32.
    let n = 32;
    let tau = 5.0 * a * a / (9.0 * mu);
    let mut us = Vec::new();
    for d in [0.125, 0.5, 2.0] {
        if let (0.5, Some(r)) = (d, rho2) {
            us.push((d, r));
            continue;
        }
        let s = (0.5 * tau).max(0.01);
        let curve = periodic_settling(n, 2.0, g0, d, MODEL, t0 + 2.0 * s)?;
        us.push((d, steady_value(&curve, s) / u_h));
    }
    let (lo, hi) = us.iter().fold((f64::INFINITY, 0.0f64), |(l, h), &(_, r)| {
        (l.min(r), h.max(r))
    });
    rep.rows.push(Row::abs(
        format!(
            "h = 1/{n}, density 2: (max - min) / min of U over diffusion numbers 0.125, 0.5, 2"
        ),
        0.0,
        hi / lo - 1.0,
        0.02,
    ));
    rep.notes.push(format!(
        "h = 1/{n}, density 2, U / U_Hasimoto by diffusion number: {}",
        us.iter()
            .map(|(d, r)| format!("{d}: {r:.4}"))
            .collect::<Vec<_>>()
            .join(", ")
    ));
    rep.notes.push(format!(
        "{MODEL}; Re = U a / ν = {:.1e}; volume fraction {c:.4}, U_Hasimoto / U_Stokes = {k:.4}",
        u_h * a / mu
    ));
    Ok(rep)
}

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
    let mut sim = Simulation::new(Scene::parse(&text, "added-mass", "added-mass")?)?;
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

/// Writes a two-layer fluid into the fluid-phase density at startup: 10 below the middle
/// of the box in the direction of gravity (the last axis), 1 above, as a free surface will.
struct TwoLayers;

impl crate::schedule::Plugin for TwoLayers {
    fn name(&self) -> &'static str {
        "two_layers"
    }

    fn build(&self, ctx: &mut crate::schedule::PluginContext) -> anyhow::Result<()> {
        use bevy_ecs::prelude::*;
        fn layers(grid: Res<Grid>, mut bf: ResMut<crate::bodies::BodyFields>) {
            let (a, mid) = (grid.dim - 1, 0.5 * grid.extent()[grid.dim - 1]);
            for k in 0..grid.n[2] {
                for j in 0..grid.n[1] {
                    for i in 0..grid.n[0] {
                        let high = grid.pos(i, j, k)[a] >= mid;
                        bf.rho_phase[grid.idx(i, j, k)] = if high { 1.0 } else { 10.0 };
                    }
                }
            }
        }
        ctx.add_startup_system("two_layers", layers)
    }
}

/// A two-layer fluid at rest, density ratio 1:10, between two walls, its density written by a
/// plugin into the fluid-phase density (as a free surface will be): max |u| must stay at
/// round-off for 1000 steps. What this can catch is limited: in the vorticity form, a
/// correction that depends on the height alone has no curl, so any discretisation that keeps
/// the horizontal translation invariance keeps these layers at rest; the case fails on
/// anything that breaks it (the solver's stencil, the walls' penalization, the phase density
/// not reaching the model). It cannot see the imbalance of a layering tilted to the grid.
fn stratified_rest(quick: bool) -> anyhow::Result<Report> {
    let mut rep = Report::new("stratified-rest");
    let (g, l) = (9.81f64, 1.0f64);
    let runs: &[(usize, usize)] = if quick {
        &[(2, 48)]
    } else {
        &[(2, 96), (3, 32)]
    };
    for &(dim, n) in runs {
        let text = if dim == 2 {
            format!(
                r#"Scene(
                name: "stratified-rest",
                domain: (extent: [1.0, 1.0], cells: [{n}, {n}]),
                fluid: (viscosity: 0.01, gravity: [0.0, -9.81]),
                numerics: (end_time: 10.0, dt: Fixed(0.001), body_coupling: Pressure),
                bodies: [(name: "walls", shape: Complement(Rectangle(half_extents: [0.6, 0.4])),
                          kind: Static, position: [0.5, 0.5])],
            )"#
            )
        } else {
            format!(
                r#"Scene(
                name: "stratified-rest",
                domain: (extent: [1.0, 1.0, 1.0], cells: [{n}, {n}, {n}]),
                fluid: (viscosity: 0.01, gravity: [0.0, 0.0, -9.81]),
                numerics: (end_time: 10.0, dt: Fixed(0.001), body_coupling: Pressure),
                bodies: [(name: "walls", shape: Complement(Box(half_extents: [0.6, 0.6, 0.4])),
                          kind: Static, position: [0.5, 0.5, 0.5])],
            )"#
            )
        };
        let scene = Scene::parse(&text, "stratified-rest", "stratified-rest")?;
        let mut sim = Simulation::builder(scene).add_plugin(TwoLayers).build()?;
        let mut umax = 0.0f64;
        for _ in 0..1000 {
            sim.step()?;
            for c in &sim.fields().u {
                umax = c.iter().fold(umax, |m, v| m.max(v.abs()));
            }
        }
        let bf = sim.world.resource::<crate::bodies::BodyFields>();
        let (lo, hi) = bf
            .rho
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(a, b), &r| (a.min(r), b.max(r)));
        rep.rows.push(Row::yes_no(
            format!("{dim}D {n} cells per side: the density field holds both layers (1 and 10)"),
            lo == 1.0 && hi == 10.0,
        ));
        rep.rows.push(Row::abs(
            format!("{dim}D {n} cells per side: max |u| / sqrt(g L) over 1000 steps"),
            0.0,
            umax / (g * l).sqrt(),
            1e-6,
        ));
    }
    Ok(rep)
}

/// One sphere-settling run for the grid study: terminal velocity (downwards) at t = 1.2, with
/// the time step set by the diffusion-number bound alone (ν Δt / h² = 0.5 on every grid unless
/// the vorticity bound is smaller), so that Δt ∝ h² and the splitting error at the body's
/// surface, which grows like √(ν Δt), stays the same fraction of h on every grid. (With the
/// scene's cap Δt ≤ 0.005 the diffusion number is 0.1 at h = 1/32 and 0.5 at 1/96: the study
/// then mixes the time and space errors.)
fn settling_run(h: f64, d: f64, nu: f64) -> anyhow::Result<f64> {
    Ok(settling_run_dt(h, d, nu, None, true)?.0)
}

/// The three-grid Richardson extrapolation with the observed order (Celik et al., J. Fluids
/// Eng. 130, 2008): for h1 > h2 > h3 and u = u0 - C h^p, p from (h1^p - h2^p)/(h2^p - h3^p) =
/// (u2 - u1)/(u3 - u2), then u0. None if the convergence is not monotone or p is outside
/// [0.5, 4].
pub fn richardson_observed(pts: &[(f64, f64); 3]) -> Option<(f64, f64)> {
    let [(h1, u1), (h2, u2), (h3, u3)] = *pts;
    let r = (u2 - u1) / (u3 - u2);
    if !(r.is_finite() && r > 0.0) {
        return None;
    }
    let f = |p: f64| (h1.powf(p) - h2.powf(p)) / (h2.powf(p) - h3.powf(p)) - r;
    let (mut lo, mut hi) = (0.5, 4.0);
    if f(lo) * f(hi) > 0.0 {
        return None;
    }
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if f(lo) * f(mid) <= 0.0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    let p = 0.5 * (lo + hi);
    Some((p, u3 + (u3 - u2) * h3.powf(p) / (h2.powf(p) - h3.powf(p))))
}

/// A sphere-settling run, optionally with the sphere replaced by a mesh file (relative to
/// `scenes/`): the velocity (downwards) at t = 1.2 and (t, velocity) after every step.
fn settling_run_with(
    h: f64,
    d: f64,
    nu: f64,
    mesh: Option<&str>,
) -> anyhow::Result<(f64, Vec<(f64, f64)>)> {
    settling_run_dt(h, d, nu, mesh, false)
}

/// The Table 1 tube (`scenes/sphere-settling.ron`) at grid step `h` with a sphere of diameter
/// `d` (or the mesh file `mesh`, relative to `scenes/`), viscosity `nu`, and its time-step
/// policy passed through `dt`. The periodic box is the tube's [0,1]² grown by 2 cells of wall
/// on each side in x and y; the tube's caps keep 2 cells of wall.
fn tube_scene(
    h: f64,
    d: f64,
    nu: f64,
    mesh: Option<&str>,
    dt: impl FnOnce(&mut crate::scene::TimeStep),
) -> anyhow::Result<ValidScene> {
    let wall = 2.0 * h;
    Ok(bundled_scene("sphere-settling.ron")?.edit(|scene| {
        dt(&mut scene.numerics.dt);
        scene.base_dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
        scene.domain.origin = Some(vec![-wall, -wall, 0.0]);
        scene.domain.extent = vec![1.0 + 2.0 * wall, 1.0 + 2.0 * wall, 4.0];
        scene.domain.h = Some(h);
        scene.domain.cells = None;
        scene.fluid.viscosity = nu;
        for b in &mut scene.bodies {
            match &mut b.shape {
                crate::bodies::shapes::Shape::Sphere { radius } => {
                    *radius = 0.5 * d;
                    if let Some(file) = mesh {
                        b.shape = crate::bodies::shapes::Shape::Mesh {
                            file: file.to_string(),
                            scale: 1.0,
                        };
                    }
                }
                crate::bodies::shapes::Shape::Complement(inner) => {
                    **inner = crate::bodies::shapes::Shape::Cylinder {
                        radius: 0.5,
                        half_height: 2.0 - wall,
                    }
                }
                _ => {}
            }
        }
    })?)
}

/// [`settling_run_with`], with the scene's time-step policy or (`diffusion_dt`) the
/// diffusion-number bound alone (no cap on Δt).
fn settling_run_dt(
    h: f64,
    d: f64,
    nu: f64,
    mesh: Option<&str>,
    diffusion_dt: bool,
) -> anyhow::Result<(f64, Vec<(f64, f64)>)> {
    let scene = tube_scene(h, d, nu, mesh, |dt| {
        if let (true, crate::scene::TimeStep::Adaptive { dt_max, .. }) = (diffusion_dt, dt) {
            *dt_max = None;
        }
    })?;
    let mut sim = Simulation::new(scene)?;
    let mut curve = Vec::new();
    sim.set_stop_at(Some(1.2));
    while sim.time() < 1.2 * (1.0 - 1e-12) {
        sim.step()?;
        if let Some(st) = dynamic_body(&mut sim) {
            curve.push((sim.time(), -st.velocity.z));
        }
    }
    let st = dynamic_body(&mut sim).ok_or_else(|| anyhow::anyhow!("no sphere"))?;
    Ok((-st.velocity.z, curve))
}

/// The Table 1 case d = 0.3, ν = 0.02 (radius 0.15, density 1.02, tube of diameter 1) at grid
/// step `h` with the default adaptive step policy scaled by `scale` (c, diffusion number and
/// CFL bound all times `scale`, no cap on Δt), run to t = 1.2 landing on the times in `land`
/// first. Returns (t, U downwards) after every step.
fn table1_run(h: f64, scale: f64, land: &[f64]) -> anyhow::Result<Vec<(f64, f64)>> {
    let scene = tube_scene(h, 0.3, 0.02, None, |dt| {
        *dt = crate::scene::TimeStep::Adaptive {
            c: 0.5 * scale,
            dt_max: None,
            cfl: 4.0 * scale,
            diffusion_number: 0.5 * scale,
        }
    })?;
    let mut sim = Simulation::new(scene)?;
    let mut curve = Vec::new();
    for &t_stop in land.iter().chain([1.2].iter()) {
        sim.set_stop_at(Some(t_stop));
        while sim.time() < t_stop * (1.0 - 1e-12) {
            sim.step()?;
            let st = dynamic_body(&mut sim).ok_or_else(|| anyhow::anyhow!("no sphere"))?;
            curve.push((sim.time(), -st.velocity.z));
        }
    }
    Ok(curve)
}

/// The terminal velocity must not depend on the time step (issue 16): Table 1's d = 0.3,
/// ν = 0.02 at Δt, Δt/2 and Δt/4 (Δt the default adaptive step), and a step shortened to land
/// on an output time must not jump the body's velocity.
fn dt_independence(quick: bool) -> anyhow::Result<Report> {
    let mut rep = Report::new("dt-independence");
    let h = if quick { 1.0 / 32.0 } else { 1.0 / 48.0 };
    let hs = format!("1/{:.0}", 1.0 / h);
    // A landing at t = 0.9537 (an arbitrary time well into the steady fall) in the Δt run.
    let t_land = 0.9537;
    let mut us = Vec::new();
    let mut plot = PlotSpec::new(
        "velocity",
        format!("settling velocity, d = 0.3, ν = 0.02, h = {hs}"),
        "t",
        "U (downwards)",
    );
    for (scale, label) in [(1.0, "Δt"), (0.5, "Δt/2"), (0.25, "Δt/4")] {
        let land: &[f64] = if scale == 1.0 { &[t_land] } else { &[] };
        let curve = table1_run(h, scale, land)?;
        let u = curve.last().map_or(f64::NAN, |e| e.1);
        if scale == 1.0 {
            // The landing step ends exactly on t_land; the velocity there against the line
            // through the steps either side of it.
            let i = curve
                .iter()
                .position(|e| (e.0 - t_land).abs() < 1e-9)
                .ok_or_else(|| anyhow::anyhow!("no step landed on {t_land}"))?;
            let ((ta, ua), (tl, ul), (tb, ub)) = (curve[i - 1], curve[i], curve[i + 1]);
            let line = ua + (ub - ua) * (tl - ta) / (tb - ta);
            rep.rows.push(Row::abs(
                format!("h = {hs}, Δt: velocity jump at a step shortened to land on t = {t_land}, relative to U"),
                0.0,
                (ul - line).abs() / ul,
                0.001,
            ));
            rep.notes.push(format!(
                "landing step: from t = {ta:.5} to {tl:.5} (the steps either side are {:.5} and {:.5} long)",
                tl - ta,
                tb - tl
            ));
        }
        plot = plot.measured(label, curve.clone());
        us.push((label, u, curve.len()));
    }
    for &(label, u, _) in &us[1..] {
        rep.rows.push(Row::rel(
            format!("h = {hs}: U(t = 1.2) at {label} against Δt"),
            us[0].1,
            u,
            0.01,
        ));
    }
    rep.notes.push(format!(
        "U(t = 1.2): {} (experiment U_E = 1.4359)",
        us.iter()
            .map(|(l, u, s)| format!("{l}: {u:.4} ({s} steps)"))
            .collect::<Vec<_>>()
            .join(", ")
    ));
    rep.plots.push(plot);
    Ok(rep)
}

/// Paper section 4.2.1, Table 1: terminal velocities of spheres settling in a tube.
fn sphere_settling(quick: bool) -> anyhow::Result<Report> {
    let mut rep = Report::new("sphere-settling");
    // (d, ν, U_E experimental, the paper's U at h = 1/64 and extrapolated to h → 0)
    let table: &[(f64, f64, f64, f64, f64)] = &[
        (0.2, 0.10, 0.2571, 0.256, 0.275),
        (0.2, 0.05, 0.4603, 0.475, 0.513),
        (0.2, 0.02, 0.9129, 0.937, 1.016),
        (0.3, 0.10, 0.4047, 0.401, 0.435),
        (0.3, 0.05, 0.7493, 0.748, 0.795),
        (0.3, 0.02, 1.4359, 1.39, 1.51),
    ];
    let cases: Vec<_> = if quick {
        vec![table[5]]
    } else {
        table.to_vec()
    };
    // The quick version runs d = 0.3, ν = 0.02 at h = 1/48 (2.4 times fewer nodes than 1/64,
    // the same number of steps: Δt is capped at 0.005 on both grids; at 1/64 the case alone
    // takes about three minutes on two cores), against the same experimental value and
    // tolerance.
    let h = if quick { 1.0 / 48.0 } else { 1.0 / 64.0 };
    let mut u64_d3_nu02 = None;
    for (d, nu, ue, up, u0) in cases {
        let hs = format!("1/{:.0}", 1.0 / h);
        let (u, curve) = settling_run_with(h, d, nu, None)?;
        if d == 0.3 && nu == 0.02 {
            u64_d3_nu02 = Some(u);
        }
        rep.plots.push(
            PlotSpec::new(
                &format!("velocity-d{d}-nu{nu}"),
                format!("settling velocity, d = {d}, ν = {nu}, h = {hs}"),
                "t",
                "U (downwards)",
            )
            .measured(format!("measured, h = {hs}"), curve)
            .reference_level(format!("paper, h = 1/64: U = {up}"), up)
            .reference_level(format!("paper, h → 0: U = {u0}"), u0)
            .reference_level(format!("experiment: U_E = {ue}"), ue),
        );
        rep.rows.push(Row::rel(
            format!("d = {d}, ν = {nu}: U(t = 1.2) at h = {hs} vs experiment U_E"),
            ue,
            u,
            0.08,
        ));
        let pct = |r: f64| format!("{:+.1}%", 100.0 * (u - r) / r);
        rep.notes.push(format!(
            "d = {d}, ν = {nu}, h = {hs}: U = {u:.4}; against U_E = {ue}: {}, the paper's h = 1/64 ({up}): {}, its h → 0 ({u0}): {}",
            pct(ue),
            pct(up),
            pct(u0)
        ));
    }
    if !quick {
        let mut us = Vec::new();
        for n in [32.0, 48.0, 64.0, 96.0] {
            us.push((1.0 / n, settling_run(1.0 / n, 0.3, 0.02)?));
        }
        // The icosphere mesh (radius 0.15) against the analytic sphere of the same size.
        if let Some(u) = u64_d3_nu02 {
            let um = settling_run_with(h, 0.3, 0.02, Some("meshes/icosphere.obj"))?.0;
            rep.rows.push(Row::rel(
                "d = 0.3, ν = 0.02: mesh icosphere U vs analytic sphere U",
                u,
                um,
                0.02,
            ));
        }
        let monotone = us.windows(3).all(|w| {
            let (a, b) = (w[1].1 - w[0].1, w[2].1 - w[1].1);
            a * b > 0.0 && b.abs() < a.abs()
        });
        // Richardson extrapolation from the three finest grids with the observed order (the
        // paper finds the method "roughly first order"; the first-order value from the two
        // finest grids is reported too).
        let n = us.len();
        let (h1, u1) = us[n - 2];
        let (h2, u2) = us[n - 1];
        let first_order = u2 + (u2 - u1) * h2 / (h1 - h2);
        let observed = richardson_observed(&[us[n - 3], us[n - 2], us[n - 1]]);
        let (order, extrap) = observed.unwrap_or((f64::NAN, f64::NAN));
        rep.rows.push(Row::rel(
            "d = 0.3, ν = 0.02: extrapolated U (h → 0, observed order, three finest grids) vs paper",
            1.51,
            extrap,
            0.05,
        ));
        rep.notes.push(format!(
            "grid study at ν Δt/h² = 0.5: observed order {order:.2} from h = 1/48, 1/64, 1/96, extrapolated U = {extrap:.4}; first order from the two finest grids: {first_order:.4} ({:+.1}% against 1.51)",
            100.0 * (first_order - 1.51) / 1.51
        ));
        rep.rows.push(Row::yes_no(
            "grid study 1/32, 1/48, 1/64, 1/96 converges monotonically",
            monotone,
        ));
        rep.plots.push(
            PlotSpec::new(
                "grid-study",
                "grid study, d = 0.3, ν = 0.02: U(t = 1.2) against h",
                "h",
                "U (downwards)",
            )
            .measured("measured", us.clone())
            .measured_points(
                "extrapolation h → 0 (observed order)",
                vec![(0.0, if extrap.is_finite() { extrap } else { 0.0 })],
            )
            .reference_points("paper, h = 1/64: U = 1.39", vec![(1.0 / 64.0, 1.39)])
            .reference_points("paper, h → 0: U = 1.51", vec![(0.0, 1.51)]),
        );
        rep.notes.push(format!(
            "grid study d = 0.3, ν = 0.02: {}",
            us.iter()
                .map(|(h, u)| format!("h = 1/{:.0}: {u:.4}", 1.0 / h))
                .collect::<Vec<_>>()
                .join(", ")
        ));
    }
    Ok(rep)
}
