//! `tumble validate`: the validation cases, each checked against an analytic solution or a
//! published reference, never against the code's own earlier output.
//!
//! A case prints a table of quantity, reference, measured value, error and tolerance, then
//! `PASS <case>` or `FAIL <case>`. `quick` runs a reduced version (used by `cargo test`).
//!
//! Cases with a reference curve or reference values also collect [`PlotSpec`]s while they run:
//! the measured curve over the reference. [`run_case`] only collects them; `tumble validate`
//! writes them as PNG files with [`Report::write_plots`].
//!
//! Layout: this file holds the case type and the registry [`CASES`]; `report.rs` the
//! [`Report`] and its rows; `docs.rs` the generated `docs/validation.md`; `cases/<name>.rs`
//! one case each, exporting its `CASE` (description, references, tolerances, known failures)
//! beside its code, with the helpers several cases share in `cases/common.rs`.

use crate::scene::{Scene, ValidScene};
use std::fmt;

mod cases;
pub mod docs;
mod report;

pub use cases::sphere_settling::richardson_observed;
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
    cases::poisson::CASE,
    cases::remesh::CASE,
    cases::lamb_oseen::CASE,
    cases::taylor_green_2d::CASE,
    cases::taylor_green_3d::CASE,
    cases::high_re_sphere::CASE,
    cases::sedimentation_2d::CASE,
    cases::sphere_settling::CASE,
    cases::stokes_settling::CASE,
    cases::periodic_array::CASE,
    cases::dt_independence::CASE,
    cases::added_mass::CASE,
    cases::stratified_rest::CASE,
    cases::rebound_vacuum::CASE,
    cases::ellipsoid_sphere::CASE,
    cases::dkt::CASE,
    cases::tank_vacuum::CASE,
    cases::tank_pile::CASE,
    cases::still_pool::CASE,
    cases::standing_wave::CASE,
    cases::rayleigh_taylor::CASE,
    cases::floating::CASE,
    cases::column_collapse::CASE,
    cases::cup::CASE,
    cases::pool_drop::CASE,
    cases::kleefsman::CASE,
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
    (
        "column-collapse.ron",
        include_str!("../../scenes/column-collapse.ron"),
    ),
    ("pool-drop.ron", include_str!("../../scenes/pool-drop.ron")),
    ("kleefsman.ron", include_str!("../../scenes/kleefsman.ron")),
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

thread_local! {
    /// The processes `tumble validate` runs on under `mpirun` ([`on_processes`]).
    static PROCESSES: std::cell::RefCell<Option<std::sync::Arc<crate::parallel::Comm>>> =
        const { std::cell::RefCell::new(None) };
}

/// Runs `f` (cases) with their simulations split over the processes of `comm`
/// ([`builder`]); every process runs the same cases and gets the same reports.
pub fn on_processes<R>(comm: std::sync::Arc<crate::parallel::Comm>, f: impl FnOnce() -> R) -> R {
    PROCESSES.with(|p| *p.borrow_mut() = Some(comm));
    let r = f();
    PROCESSES.with(|p| *p.borrow_mut() = None);
    r
}

/// The builder of a case's simulation of `scene`: split over the processes of
/// [`on_processes`] where the scene splits (a 3D scene whose grid has planes enough) and has
/// no free surface (the cases with one measure the liquid's level set over the whole grid),
/// else whole on every process (the same run on each). A split run is the whole run bit for
/// bit (README, "On several processes"), so the case's rows are the one-process rows.
pub fn builder(scene: crate::scene::ValidScene) -> crate::sim::engine::SimulationBuilder {
    let comm = PROCESSES.with(|p| p.borrow().clone());
    let splits = |c: &std::sync::Arc<crate::parallel::Comm>| {
        c.size() > 1
            && scene.grid().dim == 3
            && scene.free_surface.is_none()
            && crate::sim::engine::unsplittable(&scene).is_none()
            && crate::parallel::Slabs::new(scene.grid().n, c.size(), c.rank()).is_ok()
    };
    match comm.filter(splits) {
        Some(c) => crate::sim::engine::Simulation::builder(scene).on_processes(c),
        None => crate::sim::engine::Simulation::builder(scene),
    }
}

/// [`builder`]`(scene).build()`: a case's simulation.
pub fn simulation(
    scene: crate::scene::ValidScene,
) -> anyhow::Result<crate::sim::engine::Simulation> {
    builder(scene).build()
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
