//! The validation reports' helpers: the three-grid Richardson extrapolation and the Markdown
//! status page.

use tumble::validate::docs::{markdown, may_write, utc_date};
use tumble::validate::{Report, Row, richardson_observed};

#[test]
fn richardson_with_the_observed_order_recovers_a_power_law() {
    for (u0, c, p) in [(1.5, 3.0, 1.7), (0.25, -0.8, 1.0), (2.0, 40.0, 2.5)] {
        let pts = [48.0, 64.0, 96.0].map(|n: f64| (1.0 / n, u0 - c * (1.0 / n).powf(p)));
        let (q, v) = richardson_observed(&pts).expect("monotone");
        assert!((q - p).abs() < 1e-9, "order {q} against {p}");
        assert!(
            (v - u0).abs() < 1e-9 * u0.abs().max(1.0),
            "{v} against {u0}"
        );
    }
    // Oscillating convergence has no observed order.
    assert!(richardson_observed(&[(0.02, 1.0), (0.015, 1.2), (0.01, 1.1)]).is_none());
}

#[test]
fn a_failing_row_and_a_failed_run_show_as_fail_with_their_numbers() {
    let mut a = Report::new("sphere-settling");
    a.rows.push(Row::rel("U vs paper", 0.256, 0.2403, 0.04));
    a.rows.push(Row::yes_no("converges monotonically", true));
    a.rows.push(Row::range("gap / eps", 0.1, 3.0, 3.5));
    let mut b = Report::new("dkt");
    b.error = Some("body `upper` left the domain".into());
    let page = markdown(&[a, b], false, "2026-01-02", "nproc 2", 12.0);
    assert!(page.contains("# Validation status (full tier)"), "{page}");
    assert!(page.contains("| `sphere-settling` | FAIL |"), "{page}");
    assert!(
        page.contains("| U vs paper | 2.560000e-1 | 2.403000e-1 | 6.133% | 4.000% | **FAIL** |"),
        "{page}"
    );
    assert!(
        page.contains("| converges monotonically | yes | yes | - | - | PASS |"),
        "{page}"
    );
    assert!(
        page.contains("| gap / eps | [0.1, 3] | 3.500000e0 | 5.00e-1 | in range | **FAIL** |"),
        "{page}"
    );
    assert!(page.contains("| `dkt` | FAIL |"), "{page}");
    assert!(
        page.contains("**The run failed:** body `upper` left the domain"),
        "{page}"
    );
    assert!(page.contains("- date: 2026-01-02"), "{page}");
    assert!(page.contains("- result: 0 passed, 2 failed"), "{page}");
    // A run of two cases says which it did not run, so it cannot pass for the whole tier.
    let not_run = page
        .lines()
        .find(|l| l.starts_with("**Not run**"))
        .unwrap_or_else(|| panic!("no 'Not run' line: {page}"));
    assert!(
        not_run.contains("`poisson`") && not_run.contains("`cup`"),
        "{not_run}"
    );
    assert!(!not_run.contains("`dkt`"), "{not_run}");
}

#[test]
fn write_docs_replaces_only_its_own_pages() {
    let dir = std::env::temp_dir().join(format!("tumble-docs-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let missing = dir.join("new.md");
    assert!(may_write(&missing).is_ok());
    let own = dir.join("validation.md");
    std::fs::write(&own, markdown(&[], true, "2026-01-02", "nproc 2", 1.0)).unwrap();
    assert!(may_write(&own).is_ok());
    let users = dir.join("notes.md");
    std::fs::write(&users, "# My notes\n").unwrap();
    let err = may_write(&users).unwrap_err();
    assert!(err.contains("refusing"), "{err}");
    // A file shorter than the title is not a page either.
    let short = dir.join("short.md");
    std::fs::write(&short, "# Valid").unwrap();
    assert!(may_write(&short).is_err());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn dates_of_known_days() {
    assert_eq!(utc_date(0), "1970-01-01");
    // 2000-02-29 00:00 UTC (a leap day of a century leap year) is 951782400.
    assert_eq!(utc_date(951_782_400), "2000-02-29");
    assert_eq!(utc_date(951_782_400 + 86_400), "2000-03-01");
    // 2024-12-31 23:59:59 UTC.
    assert_eq!(utc_date(1_735_689_599), "2024-12-31");
}
