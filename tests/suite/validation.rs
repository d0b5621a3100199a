//! The quick tier: the reduced version of every case of the registry (`tumble::validate::CASES`,
//! the one list `tumble validate` also runs), each asserting against an analytic solution or a
//! published reference with the case's own tolerances. Each case is its own test
//! (`quick_tier::<minutes|seconds>::<case>`, e.g. `cargo test --release --test suite
//! quick_tier::minutes::dkt` reruns one),
//! so a failing case is named by the harness and never hides another, and the harness runs
//! the cases side by side, each on one worker thread: on two cores most cases run no faster on
//! two threads than on one (their loops are short), so two at a time halve the tier's wall
//! time (the results do not depend on the number of threads). Rows the registry lists as known
//! failures (with the reason and the issue that owns them) are printed as FAIL and do not fail
//! the test; a known failure that starts passing does. A registered case without a test here
//! fails `every_registered_case_has_a_quick_test`.

use tumble::validate::{CASES, RunTime, run_case};

/// Runs the quick version of the registered case `name` on one worker thread and fails on a
/// row that fails unexpectedly, on the run's error, or on a known failure that now passes.
fn quick(name: &str) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("a one-thread pool");
    let rep = pool
        .install(|| run_case(name, true))
        .unwrap_or_else(|e| panic!("{e:#}"));
    println!("{rep}\n  ({:.1} s)", rep.seconds);
    for r in rep.rows.iter().filter(|r| !r.pass()) {
        if let Some(k) = rep.known_failure(r) {
            println!("  FAIL (known) {}: {} ({})", name, r.quantity, k.why);
        }
    }
    let unexpected = rep.unexpected_failures();
    let stale = rep.stale_known_failures();
    assert!(
        unexpected.is_empty() && stale.is_empty(),
        "{name}: failing unexpectedly: [{}]; known failures that now pass (remove them from the registry): [{}]",
        unexpected.join("; "),
        stale.join("; ")
    );
}

/// One test per case, grouped by the registry's quick run time, and the list of their names.
/// The harness starts tests in the order of their names, so `minutes` (the long cases) start
/// before `seconds`, and the short cases fill the end of the run instead of one long case
/// running alone on one core.
macro_rules! quick_tier {
    ($($group:ident: $time:ident { $($test:ident => $name:literal,)* })*) => {
        /// The cases this file has a test for, with the run time of their group.
        const LISTED: &[(&str, RunTime)] = &[$($(($name, RunTime::$time),)*)*];
        mod quick_tier {
            $(
                mod $group {
                    $(
                        #[test]
                        fn $test() {
                            super::super::quick($name);
                        }
                    )*
                }
            )*
        }
    };
}

quick_tier! {
    minutes: Minutes {
        column_collapse => "column-collapse",
        cup => "cup",
        dkt => "dkt",
        dt_independence => "dt-independence",
        high_re_sphere => "high-re-sphere",
        kleefsman => "kleefsman",
        periodic_array => "periodic-array",
        pool_drop => "pool-drop",
        sphere_settling => "sphere-settling",
        stokes_settling => "stokes-settling",
        tank_pile => "tank-pile",
    }
    seconds: Seconds {
        added_mass => "added-mass",
        ellipsoid_sphere => "ellipsoid-sphere",
        floating => "floating",
        lamb_oseen => "lamb-oseen",
        poisson => "poisson",
        rayleigh_taylor => "rayleigh-taylor",
        rebound_vacuum => "rebound-vacuum",
        remesh => "remesh",
        sedimentation_2d => "sedimentation-2d",
        standing_wave => "standing-wave",
        still_pool => "still-pool",
        stratified_rest => "stratified-rest",
        tank_vacuum => "tank-vacuum",
        taylor_green_2d => "taylor-green-2d",
        taylor_green_3d => "taylor-green-3d",
    }
}

#[test]
fn every_registered_case_has_a_quick_test() {
    let missing: Vec<_> = CASES
        .iter()
        .filter(|c| !LISTED.iter().any(|(n, _)| *n == c.name))
        .map(|c| c.name)
        .collect();
    let unknown: Vec<_> = LISTED
        .iter()
        .filter(|(n, _)| CASES.iter().all(|c| c.name != *n))
        .collect();
    let misplaced: Vec<_> = LISTED
        .iter()
        .filter(|(n, t)| CASES.iter().any(|c| c.name == *n && c.quick_time != *t))
        .collect();
    assert!(
        missing.is_empty() && unknown.is_empty() && misplaced.is_empty(),
        "registered cases without a quick test: {missing:?}; quick tests of no registered case: {unknown:?}; in the wrong run-time group: {misplaced:?}"
    );
}

#[test]
fn unknown_case_is_an_error() {
    assert!(run_case("no-such-case", true).is_err());
}

#[test]
fn the_registry_names_each_case_once_with_its_versions() {
    for (i, c) in CASES.iter().enumerate() {
        assert!(
            CASES[..i].iter().all(|d| d.name != c.name),
            "{} twice",
            c.name
        );
        for (what, text) in [
            ("description", c.description),
            ("reference", c.reference),
            ("full version", c.full),
            ("quick version", c.quick),
        ] {
            assert!(!text.trim().is_empty(), "{}: no {what}", c.name);
        }
    }
}
