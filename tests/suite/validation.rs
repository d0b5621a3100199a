//! The quick tier: the reduced version of every case of the registry (`tumble::validate::CASES`,
//! the one list `tumble validate` also runs), each asserting against an analytic solution or a
//! published reference with the case's own tolerances. Every case runs, and the test fails
//! naming every case that failed (a failing case is never skipped). Rows the registry lists as
//! known failures (with the reason and the issue that owns them) are printed as FAIL and do
//! not fail the test; a known failure that starts passing does.
//!
//! `TUMBLE_QUICK_CASES=a,b` runs only the named cases (to rerun one while working on it).

use tumble::validate::{CASES, run_case};

#[test]
fn quick_tier_of_every_registered_case() {
    let only = std::env::var("TUMBLE_QUICK_CASES").ok();
    let selected: Vec<_> = CASES
        .iter()
        .filter(|c| {
            only.as_deref()
                .is_none_or(|o| o.split(',').any(|n| n.trim() == c.name))
        })
        .collect();
    assert!(!selected.is_empty(), "no case selected");
    let start = std::time::Instant::now();
    let mut failed = Vec::new();
    let mut known = Vec::new();
    let mut stale = Vec::new();
    for case in selected {
        let rep = case.run(true);
        println!("{rep}\n  ({:.1} s)", rep.seconds);
        let unexpected = rep.unexpected_failures();
        if !unexpected.is_empty() {
            failed.push(format!("{}: {}", case.name, unexpected.join("; ")));
        }
        for r in rep.rows.iter().filter(|r| !r.pass()) {
            if let Some(k) = rep.known_failure(r) {
                known.push(format!("{}: {} ({})", case.name, r.quantity, k.why));
            }
        }
        for k in rep.stale_known_failures() {
            stale.push(format!("{}: {k}", case.name));
        }
    }
    println!(
        "quick tier: {:.1} s, {} case(s) failing unexpectedly, {} known failing row(s)",
        start.elapsed().as_secs_f64(),
        failed.len(),
        known.len()
    );
    for k in &known {
        println!("  FAIL (known) {k}");
    }
    assert!(
        failed.is_empty(),
        "quick tier: failing cases: {}",
        failed.join(", ")
    );
    assert!(
        stale.is_empty(),
        "known failures that now pass (remove them from the registry): {}",
        stale.join(", ")
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
