//! The report of one run of a case: its rows (quantity, reference, measured value, error,
//! tolerance, pass or fail), the notes under them, the plots collected while it ran, and how
//! they print and draw.

use super::KnownFailure;
use crate::io::plot::{Series, Style, line_chart};
use std::fmt;
use std::path::{Path, PathBuf};

/// What one row checks: each kind prints its reference, error and tolerance its own way.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Check {
    /// |measured - reference| / |reference| <= tolerance.
    Relative {
        /// The reference value (analytic or published).
        reference: f64,
        /// The measured value.
        measured: f64,
        /// The relative tolerance.
        tolerance: f64,
    },
    /// |measured - reference| <= tolerance.
    Absolute {
        /// The reference value (analytic or published).
        reference: f64,
        /// The measured value.
        measured: f64,
        /// The absolute tolerance.
        tolerance: f64,
    },
    /// lo <= measured <= hi (either bound may be infinite).
    Range {
        /// Lower bound.
        lo: f64,
        /// Upper bound.
        hi: f64,
        /// The measured value.
        measured: f64,
    },
    /// A condition, stated by the row's quantity, that holds or not.
    YesNo {
        /// Whether it holds.
        holds: bool,
    },
}

/// One checked quantity.
#[derive(Debug, Clone)]
pub struct Row {
    /// What is measured (for a yes/no row: the condition).
    pub quantity: String,
    /// The check.
    pub check: Check,
}

impl Row {
    pub fn rel(quantity: impl Into<String>, reference: f64, measured: f64, tolerance: f64) -> Row {
        Row {
            quantity: quantity.into(),
            check: Check::Relative {
                reference,
                measured,
                tolerance,
            },
        }
    }
    pub fn abs(quantity: impl Into<String>, reference: f64, measured: f64, tolerance: f64) -> Row {
        Row {
            quantity: quantity.into(),
            check: Check::Absolute {
                reference,
                measured,
                tolerance,
            },
        }
    }
    pub fn range(quantity: impl Into<String>, lo: f64, hi: f64, measured: f64) -> Row {
        Row {
            quantity: quantity.into(),
            check: Check::Range { lo, hi, measured },
        }
    }
    pub fn yes_no(condition: impl Into<String>, holds: bool) -> Row {
        Row {
            quantity: condition.into(),
            check: Check::YesNo { holds },
        }
    }
    /// The error as compared with the tolerance: relative or absolute; for a range, how far
    /// the value lies outside it (0 inside); none for a yes/no row.
    pub fn error(&self) -> Option<f64> {
        match self.check {
            Check::Relative {
                reference,
                measured,
                ..
            } => Some(((measured - reference) / reference).abs()),
            Check::Absolute {
                reference,
                measured,
                ..
            } => Some((measured - reference).abs()),
            Check::Range { lo, hi, measured } => Some((lo - measured).max(measured - hi).max(0.0)),
            Check::YesNo { .. } => None,
        }
    }
    /// Whether the check holds (a NaN never passes).
    pub fn pass(&self) -> bool {
        match self.check {
            Check::Relative { tolerance, .. } | Check::Absolute { tolerance, .. } => {
                self.error().is_some_and(|e| e <= tolerance)
            }
            Check::Range { lo, hi, measured } => lo <= measured && measured <= hi,
            Check::YesNo { holds } => holds,
        }
    }
    /// The reference, measured value, error and tolerance as printed: relative errors in
    /// percent, absolute ones in scientific notation, a range as `[lo, hi]`, a yes/no row as
    /// `yes` against `yes`/`no`.
    pub fn columns(&self) -> [String; 4] {
        match self.check {
            Check::Relative {
                reference,
                measured,
                tolerance,
            } => [
                format!("{reference:.6e}"),
                format!("{measured:.6e}"),
                format!("{:.3}%", 100.0 * self.error().unwrap_or(f64::NAN)),
                format!("{:.3}%", 100.0 * tolerance),
            ],
            Check::Absolute {
                reference,
                measured,
                tolerance,
            } => [
                format!("{reference:.6e}"),
                format!("{measured:.6e}"),
                format!("{:.2e}", self.error().unwrap_or(f64::NAN)),
                format!("{tolerance:.1e}"),
            ],
            Check::Range { lo, hi, measured } => [
                format!("[{lo}, {hi}]"),
                format!("{measured:.6e}"),
                format!("{:.2e}", self.error().unwrap_or(f64::NAN)),
                "in range".to_string(),
            ],
            Check::YesNo { holds } => [
                "yes".to_string(),
                if holds { "yes" } else { "no" }.to_string(),
                "-".to_string(),
                "-".to_string(),
            ],
        }
    }
}

/// One curve of a validation plot.
#[derive(Debug, Clone)]
pub struct PlotSeries {
    /// Legend text; a reference says what it is ("analytic: ...", "paper: ...").
    pub label: String,
    /// `(x, y)` points.
    pub points: Vec<(f64, f64)>,
    /// Whether this is a reference (drawn dashed, or as markers) rather than a measurement.
    pub reference: bool,
    /// How it is drawn.
    pub style: Style,
}

/// A validation chart: measured curves over their references.
#[derive(Debug, Clone)]
pub struct PlotSpec {
    /// File stem: the chart is written as `<case>[-quick]-<stem>.png`.
    pub stem: String,
    /// Chart title.
    pub title: String,
    /// Horizontal axis label.
    pub x_label: String,
    /// Vertical axis label.
    pub y_label: String,
    /// The curves, measured and reference.
    pub series: Vec<PlotSeries>,
}

impl PlotSpec {
    pub(crate) fn new(stem: &str, title: impl Into<String>, x_label: &str, y_label: &str) -> Self {
        PlotSpec {
            stem: stem.to_string(),
            title: title.into(),
            x_label: x_label.to_string(),
            y_label: y_label.to_string(),
            series: Vec::new(),
        }
    }
    /// Adds a measured curve (solid line).
    pub(crate) fn measured(mut self, label: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        self.series.push(PlotSeries {
            label: label.into(),
            points,
            reference: false,
            style: Style::Line,
        });
        self
    }
    /// Adds measured values drawn as markers (e.g. one value per grid).
    pub(crate) fn measured_points(
        mut self,
        label: impl Into<String>,
        points: Vec<(f64, f64)>,
    ) -> Self {
        self.series.push(PlotSeries {
            label: label.into(),
            points,
            reference: false,
            style: Style::Markers,
        });
        self
    }
    /// Adds a reference curve (dashed line).
    pub(crate) fn reference(mut self, label: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        self.series.push(PlotSeries {
            label: label.into(),
            points,
            reference: true,
            style: Style::Dashed,
        });
        self
    }
    /// Adds reference values drawn as markers.
    pub(crate) fn reference_points(
        mut self,
        label: impl Into<String>,
        points: Vec<(f64, f64)>,
    ) -> Self {
        self.series.push(PlotSeries {
            label: label.into(),
            points,
            reference: true,
            style: Style::Markers,
        });
        self
    }
    /// Adds a horizontal reference line at `y` across the x range of the series so far.
    pub(crate) fn reference_level(self, label: impl Into<String>, y: f64) -> Self {
        let (lo, hi) = self.x_range();
        self.reference(label, vec![(lo, y), (hi, y)])
    }
    /// The smallest and largest finite x of the series so far ((0, 1) if there is none).
    fn x_range(&self) -> (f64, f64) {
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for s in &self.series {
            for &(x, _) in &s.points {
                if x.is_finite() {
                    lo = lo.min(x);
                    hi = hi.max(x);
                }
            }
        }
        if lo <= hi { (lo, hi) } else { (0.0, 1.0) }
    }
}

/// The outcome of one case.
#[derive(Debug, Clone)]
pub struct Report {
    /// Case name.
    pub case: String,
    /// Checked quantities.
    pub rows: Vec<Row>,
    /// Extra information printed under the table.
    pub notes: Vec<String>,
    /// Measured curves over their references, collected during the run (not yet drawn).
    pub plots: Vec<PlotSpec>,
    /// Whether this is the reduced (`quick`) version; part of the plot file names.
    pub quick: bool,
    /// Why the run stopped before it could be checked, if it did (the case fails).
    pub error: Option<String>,
    /// Wall time of the run in seconds.
    pub seconds: f64,
    /// The rows of this version known to fail (from the case's registry entry).
    pub known: Vec<KnownFailure>,
}

impl Report {
    pub fn new(case: &str) -> Self {
        Report {
            case: case.to_string(),
            rows: Vec::new(),
            notes: Vec::new(),
            plots: Vec::new(),
            quick: false,
            error: None,
            seconds: 0.0,
            known: Vec::new(),
        }
    }
    /// Whether the run finished and every row passes.
    pub fn passed(&self) -> bool {
        self.error.is_none() && !self.rows.is_empty() && self.rows.iter().all(Row::pass)
    }
    /// The known failure a row matches, if any.
    pub fn known_failure(&self, row: &Row) -> Option<&KnownFailure> {
        self.known.iter().find(|k| row.quantity.starts_with(k.row))
    }
    /// Failures that are not known (rows, or the run's error): what the quick tier rejects.
    pub fn unexpected_failures(&self) -> Vec<String> {
        let mut out: Vec<String> = self
            .rows
            .iter()
            .filter(|r| !r.pass() && self.known_failure(r).is_none())
            .map(|r| r.quantity.clone())
            .collect();
        if let Some(e) = &self.error {
            out.push(format!("error: {e}"));
        }
        if self.rows.is_empty() && self.error.is_none() {
            out.push("no row was checked".into());
        }
        out
    }
    /// Known failures that passed (or whose row is gone): the registry must be updated.
    pub fn stale_known_failures(&self) -> Vec<String> {
        if self.error.is_some() {
            return Vec::new();
        }
        self.known
            .iter()
            .filter(|k| {
                !self
                    .rows
                    .iter()
                    .any(|r| r.quantity.starts_with(k.row) && !r.pass())
            })
            .map(|k| k.row.to_string())
            .collect()
    }
    /// The file a plot is written to in `dir`: `<case>[-quick]-<stem>.png`.
    pub fn plot_path(&self, dir: &Path, plot: &PlotSpec) -> PathBuf {
        let quick = if self.quick { "-quick" } else { "" };
        dir.join(format!("{}{quick}-{}.png", self.case, plot.stem))
    }
    /// Draws every plot of the report as a PNG in `dir` (which must exist); returns each
    /// file with whether it was written.
    pub fn write_plots(&self, dir: &Path) -> Vec<(PathBuf, anyhow::Result<()>)> {
        self.plots
            .iter()
            .map(|p| {
                let path = self.plot_path(dir, p);
                let series: Vec<Series<'_>> = p
                    .series
                    .iter()
                    .map(|s| Series {
                        label: &s.label,
                        points: s.points.clone(),
                        style: s.style,
                    })
                    .collect();
                let title = format!(
                    "{}{}: {}",
                    self.case,
                    if self.quick { " (quick)" } else { "" },
                    p.title
                );
                let res = line_chart(&path, &title, &p.x_label, &p.y_label, &series);
                (path, res)
            })
            .collect()
    }
}

impl fmt::Display for Report {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "== {}", self.case)?;
        writeln!(
            f,
            "  {:<52} {:>13} {:>13} {:>10} {:>10}  ",
            "quantity", "reference", "measured", "error", "tolerance"
        )?;
        for r in &self.rows {
            let [reference, measured, e, t] = r.columns();
            writeln!(
                f,
                "  {:<52} {:>13} {:>13} {:>10} {:>10}  {}",
                r.quantity,
                reference,
                measured,
                e,
                t,
                if r.pass() { "ok" } else { "FAIL" }
            )?;
        }
        for r in &self.rows {
            if let Some(k) = self.known_failure(r).filter(|_| !r.pass()) {
                writeln!(f, "  known failure: {}: {}", k.row, k.why)?;
            }
        }
        for n in &self.notes {
            writeln!(f, "  {n}")?;
        }
        if let Some(e) = &self.error {
            writeln!(f, "  error: {e}")?;
        }
        write!(
            f,
            "{} {}",
            if self.passed() { "PASS" } else { "FAIL" },
            self.case
        )
    }
}
