//! `tumble validate`: rerun the validation cases, write their plots and, optionally, the
//! Markdown page of their results.

use crate::validate::{CASES, find_case};
use std::path::Path;

/// `tumble validate [CASES..] [--quick] [--list] [--write-docs FILE] [--plots DIR]`: exit
/// status 1 if a case fails.
///
/// Under `mpirun` (`comm` of several processes) every process runs the cases, each case's
/// simulations split over the processes where their scenes split
/// ([`crate::validate::builder`]); rank 0 alone prints and writes.
pub fn validate(
    cases: &[String],
    quick: bool,
    list: bool,
    write_docs: Option<&Path>,
    plots: &Path,
    comm: Option<std::sync::Arc<crate::parallel::Comm>>,
) -> u8 {
    match comm.filter(|c| c.size() > 1) {
        Some(c) => {
            let root = c.is_root();
            crate::validate::on_processes(c, || {
                validate_on(cases, quick, list, write_docs, plots, root)
            })
        }
        None => validate_on(cases, quick, list, write_docs, plots, true),
    }
}

/// [`validate`] on this process; only `root` prints and writes files.
fn validate_on(
    cases: &[String],
    quick: bool,
    list: bool,
    write_docs: Option<&Path>,
    plots: &Path,
    root: bool,
) -> u8 {
    macro_rules! say {
        ($($t:tt)*) => {
            if root {
                println!($($t)*);
            }
        };
    }
    if list {
        for c in CASES {
            say!(
                "{}: {}\n    reference: {}\n    full ({}): {}\n    quick ({}): {}",
                c.name,
                c.description,
                c.reference,
                c.full_time,
                c.full,
                c.quick_time,
                c.quick
            );
        }
        return 0;
    }
    let mut selected = Vec::new();
    for name in cases {
        match find_case(name) {
            Some(c) => selected.push(c),
            None => {
                say!(
                    "== {name}\n  error: unknown validation case `{name}`; the cases are: {}\nFAIL {name}",
                    CASES.iter().map(|c| c.name).collect::<Vec<_>>().join(", ")
                );
                return 1;
            }
        }
    }
    if cases.is_empty() {
        selected = CASES.iter().collect();
    }
    // Refuse before the (possibly hours-long) run, not after it.
    if let Some(file) = &write_docs
        && let Err(e) = crate::validate::docs::may_write(file)
    {
        eprintln!("error: {e}");
        return 2;
    }
    let start = std::time::Instant::now();
    let mut reports = Vec::new();
    for case in selected {
        let rep = case.run(quick);
        say!("{rep}");
        say!("  ({:.1} s)", rep.seconds);
        if root {
            write_validation_plots(&rep, plots);
        }
        reports.push(rep);
    }
    let wall = start.elapsed().as_secs_f64();
    let failed = reports.iter().filter(|r| !r.passed()).count();
    say!(
        "{} passed, {} failed ({wall:.1} s)",
        reports.len() - failed,
        failed
    );
    if let Some(file) = write_docs.filter(|_| root) {
        let date = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map(|d| crate::validate::docs::utc_date(d.as_secs()))
            .unwrap_or_else(|_| "unknown".into());
        let mut machine = format!(
            "nproc {}, {} worker threads",
            std::thread::available_parallelism().map_or(0, |n| n.get()),
            rayon::current_num_threads()
        );
        // On Linux: the load at the end (other work inflates the wall times) and the
        // CPU time of this run (user + system, /proc/self/stat fields 14 and 15 in
        // clock ticks of 1/100 s).
        if let Ok(load) = std::fs::read_to_string("/proc/loadavg") {
            let l: Vec<&str> = load.split_whitespace().take(3).collect();
            machine += &format!("; load average {} at the end", l.join(" "));
        }
        if let Ok(stat) = std::fs::read_to_string("/proc/self/stat")
            && let Some(rest) = stat.rsplit(')').next()
        {
            let f: Vec<f64> = rest
                .split_whitespace()
                .skip(11)
                .take(2)
                .filter_map(|x| x.parse().ok())
                .collect();
            if f.len() == 2 {
                machine += &format!(
                    "; CPU time of the run {:.1} s (user + system)",
                    (f[0] + f[1]) / 100.0
                );
            }
        }
        let text = crate::validate::docs::markdown(&reports, quick, &date, &machine, wall);
        if let Err(e) = std::fs::write(file, text) {
            eprintln!("error: cannot write {}: {e}", file.display());
            return 1;
        }
        println!("wrote {}", file.display());
    }
    if failed > 0 { 1 } else { 0 }
}

/// Writes the plots of a validation report to `dir` (created if needed), printing one line
/// per file written; a plot that cannot be written is a warning, not a failure of the case.
fn write_validation_plots(rep: &crate::validate::Report, dir: &std::path::Path) {
    if rep.plots.is_empty() {
        return;
    }
    if let Err(e) = std::fs::create_dir_all(dir) {
        eprintln!(
            "warning: {}: cannot create the plot directory {}: {e}",
            rep.case,
            dir.display()
        );
        return;
    }
    for (path, res) in rep.write_plots(dir) {
        match res {
            Ok(()) => println!("  plot {}", path.display()),
            Err(e) => eprintln!("warning: {}: plot not written: {e:#}", rep.case),
        }
    }
}
