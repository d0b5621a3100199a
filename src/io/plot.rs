//! PNG line plots of a run's CSV outputs (`tumble plot RUN_DIR`).
//!
//! Charts are drawn with `plotters`' bitmap backend and written as 900x600 PNG files. Text is
//! rasterised in pure Rust (`ab_glyph`) with the DejaVu Sans font bundled in `assets/` and
//! embedded in the binary, so plotting needs no system library (no fontconfig, no freetype)
//! and looks the same on every machine.
//!
//! - [`line_chart`] draws any number of [`Series`] (lines, or markers for reference values)
//!   on one pair of axes and writes the PNG atomically.
//! - [`plot_run_dir`] reads `series.csv`, `bodies.csv` and `contacts.csv` of a run directory
//!   and writes the standard plots next to them.
//!
//! Nothing here panics on bad input: malformed CSV rows, missing columns and unplottable data
//! are `anyhow` errors naming the file (and line).

use anyhow::{Context, Result, anyhow, bail, ensure};
use plotters::prelude::*;
use plotters::style::{FontStyle, register_font};
use std::collections::HashMap;
use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;
use std::sync::atomic::{AtomicU64, Ordering};

/// Width and height of every chart, in pixels.
pub const SIZE: (u32, u32) = (900, 600);

/// At most this many bodies (or contact pairs) get a curve in one chart.
pub const MAX_CURVES: usize = 8;

/// DejaVu Sans (Bitstream Vera licence, see `assets/LICENSE-DejaVu.txt`).
static FONT: &[u8] = include_bytes!("../../assets/DejaVuSans.ttf");

/// The family name the bundled font is registered under. `plotters` asks for "sans-serif"
/// wherever no font is given explicitly, so the bundled font serves those too.
const FAMILY: &str = "sans-serif";

/// Distinct colours (Tableau 10), used in order and then cycled.
const COLORS: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

/// How a [`Series`] is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Style {
    /// A polyline through the points in the order given; a non-finite point breaks the line.
    Line,
    /// A hollow circle at each point, e.g. reference or published values drawn over a
    /// measured curve.
    Markers,
    /// A dashed polyline, broken like [`Style::Line`]: a reference curve (analytic solution,
    /// published value) drawn over a measured one.
    Dashed,
}

/// One curve of a chart.
#[derive(Clone, Debug)]
pub struct Series<'a> {
    /// Legend text (the legend is shown when more than one series has points to draw).
    pub label: &'a str,
    /// `(x, y)` points; points with a non-finite coordinate (or one beyond 1e300) are skipped.
    pub points: Vec<(f64, f64)>,
    /// Line or markers.
    pub style: Style,
}

/// Writes a 900x600 PNG line chart of `series` to `path`.
///
/// Axis ranges cover the finite points of all series with a 5 % margin (constant data gets a
/// range around its value). Points with a NaN or infinite coordinate, or one beyond 1e300 in
/// magnitude, are skipped; a [`Style::Line`] or [`Style::Dashed`] series is broken there (an
/// isolated point between gaps is drawn as a dot). Series with no such point are left out, also
/// of the legend. If no series has a finite point, nothing is written and an error is returned.
///
/// `path` must end in `.png`. The chart is rendered to a temporary file `.tmp-*-NAME.png` in the
/// same directory and renamed over `path`, so `path` is either the old file or the complete
/// new one; on error the temporary file is removed.
pub fn line_chart(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series<'_>],
) -> Result<()> {
    let name = path
        .file_name()
        .ok_or_else(|| anyhow!("no file name in {}", path.display()))?;
    ensure!(
        path.extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("png")),
        "{}: a chart is written as PNG, the file name must end in .png",
        path.display()
    );
    let drawn = finite_series(series);
    ensure!(
        !drawn.is_empty(),
        "{}: nothing to plot (no finite points within 1e300)",
        path.display()
    );
    register_bundled_font()?;

    static SEQ: AtomicU64 = AtomicU64::new(0);
    let mut tmp_name = OsString::from(format!(
        ".tmp-{}-{}-",
        std::process::id(),
        SEQ.fetch_add(1, Ordering::Relaxed)
    ));
    tmp_name.push(name);
    let tmp = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.join(&tmp_name),
        _ => PathBuf::from(&tmp_name),
    };

    // `plotters` reports most failures as errors, but guard against a panic deep inside it too:
    // this function's contract is an error, never a panic.
    let rendered = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        render(&tmp, title, x_label, y_label, &drawn)
    }))
    .unwrap_or_else(|_| Err(anyhow!("the plotting library panicked")));
    let result = rendered
        .and_then(|()| std::fs::rename(&tmp, path).map_err(anyhow::Error::from))
        .with_context(|| format!("cannot write {}", path.display()));
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// A series reduced to what is drawn: runs of consecutive finite points.
struct Drawn<'a> {
    label: &'a str,
    style: Style,
    runs: Vec<Vec<(f64, f64)>>,
}

fn finite_series<'a>(series: &[Series<'a>]) -> Vec<Drawn<'a>> {
    let mut out = Vec::new();
    for s in series {
        let mut runs: Vec<Vec<(f64, f64)>> = Vec::new();
        let mut cur = Vec::new();
        for &(x, y) in &s.points {
            if x.abs() <= LIMIT && y.abs() <= LIMIT {
                cur.push((x, y));
            } else if !cur.is_empty() && s.style != Style::Markers {
                runs.push(std::mem::take(&mut cur));
            }
        }
        if !cur.is_empty() {
            runs.push(cur);
        }
        if !runs.is_empty() {
            out.push(Drawn {
                label: s.label,
                style: s.style,
                runs,
            });
        }
    }
    out
}

/// Registers the bundled font with `plotters` (once per process).
fn register_bundled_font() -> Result<()> {
    static OK: OnceLock<bool> = OnceLock::new();
    let ok = *OK.get_or_init(|| register_font(FAMILY, FontStyle::Normal, FONT).is_ok());
    ensure!(ok, "the bundled font (DejaVu Sans) could not be loaded");
    Ok(())
}

/// Coordinates beyond this magnitude are skipped like non-finite ones: `plotters`' tick layout
/// needs the axis span to be a finite number (and loops forever when it is not).
const LIMIT: f64 = 1e300;

/// The smallest axis span: below it `plotters`' tick layout underflows.
const MIN_SPAN: f64 = 1e-280;

/// The axis range `[lo, hi]` of `values` (at least one, all within [`LIMIT`]) with a 5 %
/// margin each side; constant (or constant to 12 digits) data get a range of ±10 % of the
/// value around it, or ±1 around zero. The span is at most `2.2 LIMIT` and at least
/// [`MIN_SPAN`].
fn axis_range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    let span = hi - lo;
    let mid = 0.5 * (lo + hi);
    let pad = if span > mid.abs() * 1e-12 {
        0.05 * span
    } else if mid != 0.0 {
        0.1 * mid.abs()
    } else {
        1.0
    };
    let pad = pad.max(MIN_SPAN);
    (lo - pad, hi + pad)
}

/// Tick label text for an axis spanning `[lo, hi]` (finite, `lo < hi`): fixed point with as
/// many decimals as the tick spacing needs, or scientific notation for very large or very
/// small magnitudes.
fn tick_formatter(lo: f64, hi: f64) -> impl Fn(&f64) -> String {
    let k = tick_exponent(lo, hi);
    let mag = lo.abs().max(hi.abs());
    let scientific = !(1e-3..1e5).contains(&mag);
    let step = 10f64.powi(k);
    move |v: &f64| {
        if v.abs() < step * 1e-6 {
            "0".to_string()
        } else if scientific {
            let e = v.abs().log10().floor() as i64;
            let d = (e - i64::from(k)).clamp(0, 12) as usize;
            format!("{v:.d$e}")
        } else {
            let d = (-i64::from(k)).clamp(0, 12) as usize;
            format!("{v:.d$}")
        }
    }
}

/// The power of ten `k` of the tick spacing `m 10^k` (`m` = 1, 2 or 5) that `plotters` uses on
/// `[lo, hi]`: the finest spacing that puts at most [`TICKS`] ticks in the range.
fn tick_exponent(lo: f64, hi: f64) -> i32 {
    let span = hi - lo;
    if !(span.is_finite() && span > 0.0) {
        return 0;
    }
    let mut k = ((span / TICKS as f64).log10().floor() as i32).clamp(-320, 310);
    for _ in 0..4 {
        for m in [1.0, 2.0, 5.0] {
            let s = m * 10f64.powi(k);
            let count = (hi / s).floor() - (lo / s).ceil() + 1.0;
            if count <= TICKS as f64 {
                return k;
            }
        }
        k += 1;
    }
    k
}

/// Labelled ticks per axis (`plotters`' default, set explicitly so [`tick_exponent`] agrees).
const TICKS: usize = 11;

fn plot_error(e: impl std::fmt::Display) -> anyhow::Error {
    anyhow!("plotting failed: {e}")
}

/// Draws the chart into `file` (a `.png` name).
fn render(
    file: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Drawn<'_>],
) -> Result<()> {
    let points = || series.iter().flat_map(|s| s.runs.iter().flatten());
    let (x0, x1) = axis_range(points().map(|p| p.0));
    let (y0, y1) = axis_range(points().map(|p| p.1));
    let x_fmt = tick_formatter(x0, x1);
    let y_fmt = tick_formatter(y0, y1);

    let root = BitMapBackend::new(file, SIZE).into_drawing_area();
    root.fill(&WHITE).map_err(plot_error)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, (FAMILY, 24))
        .margin(16)
        .margin_right(36)
        .x_label_area_size(50)
        .y_label_area_size(90)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(plot_error)?;
    chart
        .configure_mesh()
        .x_desc(x_label)
        .y_desc(y_label)
        .label_style((FAMILY, 14))
        .axis_desc_style((FAMILY, 17))
        .x_label_formatter(&x_fmt)
        .y_label_formatter(&y_fmt)
        .x_labels(TICKS)
        .y_labels(TICKS)
        .light_line_style(RGBColor(235, 235, 235))
        .bold_line_style(RGBColor(200, 200, 200))
        .draw()
        .map_err(plot_error)?;

    for (i, s) in series.iter().enumerate() {
        let color = COLORS[i % COLORS.len()];
        let line = color.stroke_width(2);
        match s.style {
            Style::Line => {
                for (k, run) in s.runs.iter().enumerate() {
                    let anno = if run.len() == 1 {
                        // An isolated point (between gaps): a dot, as a line through it has no length.
                        chart
                            .draw_series(run.iter().map(|&p| Circle::new(p, 2, color.filled())))
                            .map_err(plot_error)?
                    } else {
                        chart
                            .draw_series(LineSeries::new(run.iter().copied(), line))
                            .map_err(plot_error)?
                    };
                    if k == 0 {
                        anno.label(s.label).legend(move |(x, y)| {
                            PathElement::new(vec![(x, y), (x + 24, y)], line)
                        });
                    }
                }
            }
            Style::Dashed => {
                for (k, run) in s.runs.iter().enumerate() {
                    let anno = if run.len() == 1 {
                        chart
                            .draw_series(run.iter().map(|&p| Circle::new(p, 2, color.filled())))
                            .map_err(plot_error)?
                    } else {
                        chart
                            .draw_series(DashedLineSeries::new(run.iter().copied(), 10, 6, line))
                            .map_err(plot_error)?
                    };
                    if k == 0 {
                        anno.label(s.label).legend(move |(x, y)| {
                            EmptyElement::at((x, y))
                                + PathElement::new(vec![(0, 0), (9, 0)], line)
                                + PathElement::new(vec![(15, 0), (24, 0)], line)
                        });
                    }
                }
            }
            Style::Markers => {
                let anno = chart
                    .draw_series(s.runs.iter().flatten().map(|&p| Circle::new(p, 4, line)))
                    .map_err(plot_error)?;
                anno.label(s.label)
                    .legend(move |(x, y)| Circle::new((x + 12, y), 4, line));
            }
        }
    }
    if series.len() > 1 {
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .label_font((FAMILY, 14))
            .background_style(WHITE.mix(0.85))
            .border_style(RGBColor(160, 160, 160))
            .draw()
            .map_err(plot_error)?;
    }
    root.present().map_err(plot_error)?;
    Ok(())
}

/// Reads the CSV files of the run directory `dir` and writes PNG plots next to them; returns
/// the paths written, in this order:
///
/// - `series.csv` (required) → `energy.png`, `enstrophy.png` (against `t`).
/// - `bodies.csv` (if present and not empty) → `bodies_height.png` and
///   `bodies_velocity.png`: the vertical coordinate and velocity of each body against `t`, one
///   curve per body name. The vertical axis is z if the run is 3D (any non-zero `z`, `vz`,
///   `wx` or `wy` in the file), else y. Only the first [`MAX_CURVES`] names get a curve; the
///   title then says how many were plotted.
/// - `contacts.csv` (if present and not empty) → `contacts_gap.png`: the gap of each contact
///   pair `body_a`–`body_b` against `t` (at most [`MAX_CURVES`] pairs).
///
/// Columns are found by header name. A missing `series.csv`, a missing column, a row with the
/// wrong number of fields or an unparsable number is an error naming the file (and line).
pub fn plot_run_dir(dir: &Path) -> Result<Vec<PathBuf>> {
    let series_csv = dir.join("series.csv");
    if !series_csv.is_file() {
        bail!("not a run directory: {} has no series.csv", dir.display());
    }
    let run = dir
        .canonicalize()
        .ok()
        .and_then(|d| d.file_name().map(|n| n.to_string_lossy().into_owned()))
        .unwrap_or_else(|| dir.display().to_string());
    let mut written = Vec::new();

    let text = read(&series_csv)?;
    let table = Table::parse(&series_csv, &text)?;
    ensure!(
        !table.rows.is_empty(),
        "{}: no data rows",
        series_csv.display()
    );
    let t = table.column("t")?;
    for (column, file, title) in [
        ("energy", "energy.png", "Kinetic energy"),
        ("enstrophy", "enstrophy.png", "Enstrophy"),
    ] {
        let values = table.column(column)?;
        let path = dir.join(file);
        line_chart(
            &path,
            &format!("{title} ({run})"),
            "t",
            column,
            &[Series {
                label: column,
                points: t.iter().copied().zip(values).collect(),
                style: Style::Line,
            }],
        )?;
        written.push(path);
    }

    let bodies_csv = dir.join("bodies.csv");
    if bodies_csv.is_file() {
        written.extend(plot_bodies(dir, &bodies_csv, &run)?);
    }
    let contacts_csv = dir.join("contacts.csv");
    if contacts_csv.is_file() {
        written.extend(plot_contacts(dir, &contacts_csv, &run)?);
    }
    Ok(written)
}

/// The points of one body (or contact pair), for up to two charts.
struct Curve {
    label: String,
    points: [Vec<(f64, f64)>; 2],
}

/// One curve per name, in order of first appearance; only the first [`MAX_CURVES`] names keep
/// their points, the rest are only counted.
struct Curves<'a> {
    index: HashMap<&'a str, usize>,
    curves: Vec<Curve>,
}

impl<'a> Curves<'a> {
    fn new() -> Self {
        Curves {
            index: HashMap::new(),
            curves: Vec::new(),
        }
    }

    /// The curve of `key` (labelled `label` if new), or `None` past the first
    /// [`MAX_CURVES`] keys.
    fn get(&mut self, key: &'a str, label: impl FnOnce() -> String) -> Option<&mut Curve> {
        let n = self.index.len();
        let i = *self.index.entry(key).or_insert(n);
        if i == self.curves.len() && i < MAX_CURVES {
            self.curves.push(Curve {
                label: label(),
                points: [Vec::new(), Vec::new()],
            });
        }
        self.curves.get_mut(i)
    }

    /// " (8 of 200 bodies)" when some were left out, else "".
    fn note(&self, what: &str) -> String {
        if self.index.len() > self.curves.len() {
            format!(" ({} of {} {what})", self.curves.len(), self.index.len())
        } else {
            String::new()
        }
    }
}

fn plot_bodies(dir: &Path, csv: &Path, run: &str) -> Result<Vec<PathBuf>> {
    let text = read(csv)?;
    let table = Table::parse(csv, &text)?;
    if table.rows.is_empty() {
        return Ok(Vec::new());
    }
    let c = |name| table.col(name);
    let (ti, ni) = (c("t")?, c("name")?);
    let (yi, zi, vyi, vzi, wxi, wyi) = (c("y")?, c("z")?, c("vy")?, c("vz")?, c("wx")?, c("wy")?);
    let mut three_d = false;
    for row in &table.rows {
        for col in [zi, vzi, wxi, wyi] {
            let v = table.num(row, col)?;
            three_d |= v != 0.0 && !v.is_nan();
        }
    }
    let (hi, vi, axis) = if three_d {
        (zi, vzi, "z")
    } else {
        (yi, vyi, "y")
    };
    let mut curves = Curves::new();
    for row in &table.rows {
        let t = table.num(row, ti)?;
        let h = table.num(row, hi)?;
        let v = table.num(row, vi)?;
        let name = row.fields[ni].trim();
        if let Some(curve) = curves.get(name, || name.to_string()) {
            curve.points[0].push((t, h));
            curve.points[1].push((t, v));
        }
    }
    let note = curves.note("bodies");
    let mut written = Vec::new();
    for (file, what, y_label, pick) in [
        ("bodies_height.png", "Body height", axis.to_string(), 0),
        (
            "bodies_velocity.png",
            "Vertical velocity",
            format!("v{axis}"),
            1,
        ),
    ] {
        let series: Vec<Series<'_>> = curves
            .curves
            .iter()
            .map(|c| Series {
                label: &c.label,
                points: c.points[pick].clone(),
                style: Style::Line,
            })
            .collect();
        let path = dir.join(file);
        line_chart(
            &path,
            &format!("{what} ({run}){note}"),
            "t",
            &y_label,
            &series,
        )?;
        written.push(path);
    }
    Ok(written)
}

fn plot_contacts(dir: &Path, csv: &Path, run: &str) -> Result<Vec<PathBuf>> {
    let text = read(csv)?;
    let table = Table::parse(csv, &text)?;
    if table.rows.is_empty() {
        return Ok(Vec::new());
    }
    let (ti, ai, bi, gi) = (
        table.col("t")?,
        table.col("body_a")?,
        table.col("body_b")?,
        table.col("gap")?,
    );
    // A pair is the same whichever body is listed first: key on the sorted names.
    let keys: Vec<String> = table
        .rows
        .iter()
        .map(|row| {
            let (a, b) = (row.fields[ai].trim(), row.fields[bi].trim());
            if a <= b {
                format!("{a}\n{b}")
            } else {
                format!("{b}\n{a}")
            }
        })
        .collect();
    let mut curves = Curves::new();
    for (row, key) in table.rows.iter().zip(&keys) {
        let t = table.num(row, ti)?;
        let gap = table.num(row, gi)?;
        let label = || format!("{}\u{2013}{}", row.fields[ai].trim(), row.fields[bi].trim());
        if let Some(curve) = curves.get(key, label) {
            curve.points[0].push((t, gap));
        }
    }
    let series: Vec<Series<'_>> = curves
        .curves
        .iter()
        .map(|c| Series {
            label: &c.label,
            points: c.points[0].clone(),
            style: Style::Line,
        })
        .collect();
    let path = dir.join("contacts_gap.png");
    let note = curves.note("pairs");
    line_chart(
        &path,
        &format!("Contact gap ({run}){note}"),
        "t",
        "gap",
        &series,
    )?;
    Ok(vec![path])
}

fn read(path: &Path) -> Result<String> {
    std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))
}

/// A data row of a CSV file: its 1-based line number and its fields.
struct Row<'a> {
    line: usize,
    fields: Vec<&'a str>,
}

/// A comma-separated file with a header line (no quoting; blank lines are ignored).
struct Table<'a> {
    path: &'a Path,
    header: Vec<&'a str>,
    rows: Vec<Row<'a>>,
}

impl<'a> Table<'a> {
    fn parse(path: &'a Path, text: &'a str) -> Result<Self> {
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        let mut lines = text
            .lines()
            .enumerate()
            .map(|(i, l)| (i + 1, l))
            .filter(|(_, l)| !l.trim().is_empty());
        let Some((_, head)) = lines.next() else {
            bail!("{}: empty file, expected a header line", path.display());
        };
        let header: Vec<&str> = head.split(',').map(str::trim).collect();
        let mut rows = Vec::new();
        for (line, l) in lines {
            let fields: Vec<&str> = l.split(',').collect();
            ensure!(
                fields.len() == header.len(),
                "{}:{line}: malformed row: {} fields, the header has {}",
                path.display(),
                fields.len(),
                header.len()
            );
            rows.push(Row { line, fields });
        }
        Ok(Table { path, header, rows })
    }

    /// The index of column `name`.
    fn col(&self, name: &str) -> Result<usize> {
        self.header.iter().position(|h| *h == name).ok_or_else(|| {
            anyhow!(
                "{}: no `{name}` column in the header ({})",
                self.path.display(),
                self.header.join(",")
            )
        })
    }

    /// The number in column `col` of `row`.
    fn num(&self, row: &Row<'_>, col: usize) -> Result<f64> {
        let s = row.fields[col].trim();
        s.parse().map_err(|_| {
            anyhow!(
                "{}:{}: malformed row: `{}` is not a number (column `{}`)",
                self.path.display(),
                row.line,
                s,
                self.header[col]
            )
        })
    }

    /// Every value of column `name`.
    fn column(&self, name: &str) -> Result<Vec<f64>> {
        let col = self.col(name)?;
        self.rows.iter().map(|r| self.num(r, col)).collect()
    }
}
