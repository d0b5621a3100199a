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
//!   and writes the standard plots next to them, titled with the scene's name and labelled
//!   with its units from `scene.ron` ([`RunInfo`], [`chart_title`], [`axis_label`]).
//!
//! Nothing here panics on bad input: malformed CSV rows, missing columns and unplottable data
//! are `anyhow` errors naming the file (and line).

use crate::scene::{Scene, Units};
use anyhow::{Context, Result, anyhow, bail, ensure};
use glam::{DMat3, DQuat, DVec3};
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
pub(crate) const FAMILY: &str = "sans-serif";

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
pub(crate) fn register_bundled_font() -> Result<()> {
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

/// What the plots take from a run directory's `scene.ron` (the scene as run).
#[derive(Clone, Debug, Default)]
pub struct RunInfo {
    /// The scene's name (the run folder's name when there is no readable `scene.ron`).
    pub name: String,
    /// The scene's `output.units` note, if any.
    pub units: Option<Units>,
    /// The contact range ε, length: `contact.eps`, else the grid spacing h.
    pub eps: Option<f64>,
    /// Whether the run was in vacuum (no flow).
    pub vacuum: bool,
    /// Gravity g, length/time².
    pub gravity: [f64; 3],
    /// The scene's bodies, in order.
    pub bodies: Vec<BodyInfo>,
    /// The scene's dimension, 2 or 3 (3 when there is no readable scene).
    pub dim: usize,
}

/// A body of the scene as the plots need it.
#[derive(Clone, Debug)]
pub struct BodyInfo {
    /// Its name (as in `bodies.csv` and `contacts.csv`).
    pub name: String,
    /// Mass ρ |S| (|S| the area of a 2D shape), mass units; `None` for an unbounded shape or
    /// one that could not be built.
    pub mass: Option<f64>,
    /// Inertia tensor ρ ∫(|x|² Id - x xᵀ) about the body origin, in the body frame.
    pub inertia: Option<DMat3>,
}

impl RunInfo {
    /// Reads `dir/scene.ron` (parsed and checked by the scene loader, relative mesh paths
    /// against `dir`); `None` if there is none or it does not load (a run directory written by
    /// an older tumble), and the plots then use the folder's name and no units.
    pub fn read(dir: &Path) -> Option<RunInfo> {
        let file = dir.join("scene.ron");
        let text = std::fs::read_to_string(&file).ok()?;
        let scene = match Scene::parse_in(&text, &file.display().to_string(), "", dir) {
            Ok(s) => s,
            Err(e) => {
                tracing::warn!("plots without the scene's name and units: {e}");
                return None;
            }
        };
        let resolved = scene.resolved();
        let bodies = scene
            .bodies
            .iter()
            .zip(scene.geometries())
            .zip(&resolved.densities)
            .map(|((b, g), &rho)| BodyInfo {
                name: b.name.clone(),
                mass: g.volume().map(|v| rho * v),
                inertia: g.inertia_unit_density().map(|j| rho * j),
            })
            .collect();
        Some(RunInfo {
            name: scene.name.clone(),
            units: scene.output.units.clone(),
            eps: Some(resolved.contact.eps),
            vacuum: scene.vacuum,
            gravity: scene.gravity(),
            bodies,
            dim: scene.grid().dim,
        })
    }

    /// The info of a run directory: [`RunInfo::read`], else the folder's name alone.
    fn of_dir(dir: &Path) -> RunInfo {
        RunInfo::read(dir).unwrap_or_else(|| RunInfo {
            name: dir
                .canonicalize()
                .ok()
                .and_then(|d| d.file_name().map(|n| n.to_string_lossy().into_owned()))
                .unwrap_or_else(|| dir.display().to_string()),
            ..RunInfo::default()
        })
    }

    /// The index of the body named `name`, or numbered `name` (a body id) when no body has
    /// that name.
    fn body(&self, name: &str) -> Option<usize> {
        self.bodies.iter().position(|b| b.name == name).or_else(|| {
            name.parse::<usize>()
                .ok()
                .filter(|&i| i < self.bodies.len())
        })
    }

    /// The body name for a `contacts.csv` entry: the name itself, or the name of body id
    /// `entry`.
    fn body_name<'s>(&'s self, entry: &'s str) -> &'s str {
        self.body(entry)
            .map_or(entry, |i| self.bodies[i].name.as_str())
    }
}

/// A chart's title: what it shows, then the scene's name.
pub fn chart_title(what: &str, scene: &str) -> String {
    format!("{what} \u{2014} {scene}")
}

/// The unit of a quantity of dimension length^`length` time^`time` mass^`mass` in the scene's
/// `units`: `"[cm/s]"`, `"[g cm²/s²]"`; `""` for a pure number; `"(scene units)"` when a
/// unit it needs has no name.
pub fn unit_text(units: Option<&Units>, length: i32, time: i32, mass: i32) -> String {
    let dims = [
        (mass, units.and_then(|u| u.mass.as_deref())),
        (length, units.and_then(|u| u.length.as_deref())),
        (time, units.and_then(|u| u.time.as_deref())),
    ];
    if dims.iter().all(|(p, _)| *p == 0) {
        return String::new();
    }
    let power = |name: &str, p: i32| match p {
        1 => name.to_string(),
        2 => format!("{name}\u{b2}"),
        3 => format!("{name}\u{b3}"),
        p => format!("{name}^{p}"),
    };
    let (mut num, mut den) = (Vec::new(), Vec::new());
    for (p, name) in dims {
        if p == 0 {
            continue;
        }
        let Some(name) = name else {
            return "(scene units)".to_string();
        };
        if p > 0 {
            num.push(power(name, p));
        } else {
            den.push(power(name, -p));
        }
    }
    let num = if num.is_empty() {
        "1".to_string()
    } else {
        num.join(" ")
    };
    if den.is_empty() {
        format!("[{num}]")
    } else if den.len() == 1 {
        format!("[{num}/{}]", den[0])
    } else {
        format!("[{num}/({})]", den.join(" "))
    }
}

/// An axis label: the quantity, then its unit as [`unit_text`] writes it ("t [s]",
/// "height z (scene units)").
pub fn axis_label(
    quantity: &str,
    units: Option<&Units>,
    length: i32,
    time: i32,
    mass: i32,
) -> String {
    let u = unit_text(units, length, time, mass);
    if u.is_empty() {
        quantity.to_string()
    } else {
        format!("{quantity} {u}")
    }
}

/// A series that owns its label, as the run-directory plots build them.
#[derive(Clone, Debug, PartialEq)]
pub struct OwnedSeries {
    /// Legend text.
    pub label: String,
    /// `(x, y)` points.
    pub points: Vec<(f64, f64)>,
    /// How it is drawn.
    pub style: Style,
}

fn borrowed(series: &[OwnedSeries]) -> Vec<Series<'_>> {
    series
        .iter()
        .map(|s| Series {
            label: &s.label,
            points: s.points.clone(),
            style: s.style,
        })
        .collect()
}

/// Reads the CSV files of the run directory `dir` and writes PNG plots next to them; returns
/// the paths written, in this order:
///
/// - `series.csv` (required) → `energy.png`, `enstrophy.png` (against `t`). In a vacuum run
///   (no flow) `energy.png` instead shows the bodies' kinetic, potential and total energy
///   ([`body_energy`]) and there is no `enstrophy.png`.
/// - `bodies.csv` (if present and not empty) → `bodies_height.png` and
///   `bodies_velocity.png`: the vertical coordinate and velocity of each body against `t`, one
///   curve per body name. The vertical axis is z if the run is 3D (any non-zero `z`, `vz`,
///   `wx` or `wy` in the file), else y. Only the first [`MAX_CURVES`] names get a curve; the
///   title then says how many were plotted.
/// - `series.csv` with a `liquid_volume` column (a run with a free surface) →
///   `liquid_volume.png`.
/// - `contacts.csv` (if present and not empty) → `contacts_gap.png`: [`gap_series`].
///
/// Titles name the scene (`scene.ron`'s name, else the folder's) and axis labels carry the
/// scene's `output.units` ([`axis_label`]). Columns are found by header name. A missing
/// `series.csv`, a missing column, a row with the wrong number of fields or an unparsable
/// number is an error naming the file (and line).
pub fn plot_run_dir(dir: &Path) -> Result<Vec<PathBuf>> {
    let series_csv = dir.join("series.csv");
    if !series_csv.is_file() {
        bail!("not a run directory: {} has no series.csv", dir.display());
    }
    let info = RunInfo::of_dir(dir);
    let units = info.units.as_ref();
    let mut written = Vec::new();

    let text = read(&series_csv)?;
    let table = Table::parse(&series_csv, &text)?;
    ensure!(
        !table.rows.is_empty(),
        "{}: no data rows",
        series_csv.display()
    );
    let t = table.column("t")?;
    let t_label = axis_label("t", units, 0, 1, 0);
    let bodies_energy = if info.vacuum {
        body_energy(dir, &info)?
    } else {
        None
    };
    if let Some(e) = &bodies_energy {
        let path = dir.join("energy.png");
        let curve = |label: &str, v: &[f64], style| OwnedSeries {
            label: label.to_string(),
            points: e.t.iter().copied().zip(v.iter().copied()).collect(),
            style,
        };
        let series = [
            curve("kinetic ½mV² + ½Ω·JΩ", &e.kinetic, Style::Line),
            curve("potential −m g·x", &e.potential, Style::Line),
            curve(
                "total (contact energy not counted)",
                &e.total(),
                Style::Dashed,
            ),
        ];
        line_chart(
            &path,
            &chart_title("Energy of the bodies (vacuum)", &info.name),
            &t_label,
            &axis_label("energy", units, 2, -2, 1),
            &borrowed(&series),
        )?;
        written.push(path);
    } else {
        for (column, file, what, length, time) in [
            ("energy", "energy.png", "Kinetic energy ½⟨|u|²⟩", 2, -2),
            ("enstrophy", "enstrophy.png", "Enstrophy ½⟨|ω|²⟩", 0, -2),
        ] {
            let values = table.column(column)?;
            let path = dir.join(file);
            line_chart(
                &path,
                &chart_title(what, &info.name),
                &t_label,
                &axis_label(column, units, length, time, 0),
                &[Series {
                    label: column,
                    points: t.iter().copied().zip(values).collect(),
                    style: Style::Line,
                }],
            )?;
            written.push(path);
        }
    }

    // A run with a free surface: its liquid volume (an area in 2D) against t.
    if table.header.iter().any(|h| h == "liquid_volume") {
        let values = table.column("liquid_volume")?;
        let path = dir.join("liquid_volume.png");
        line_chart(
            &path,
            &chart_title("Liquid volume ∫H(φ_w)", &info.name),
            &t_label,
            &axis_label(
                "liquid volume",
                units,
                if info.dim == 2 { 2 } else { 3 },
                0,
                0,
            ),
            &[Series {
                label: "liquid_volume",
                points: t.iter().copied().zip(values).collect(),
                style: Style::Line,
            }],
        )?;
        written.push(path);
    }

    let bodies_csv = dir.join("bodies.csv");
    if bodies_csv.is_file() {
        written.extend(plot_bodies(dir, &bodies_csv, &info)?);
    }
    let contacts_csv = dir.join("contacts.csv");
    if contacts_csv.is_file() {
        let (series, note) = gap_series_of(&contacts_csv, &info)?;
        if !series.is_empty() {
            let path = dir.join("contacts_gap.png");
            line_chart(
                &path,
                &format!("{}{note}", chart_title("Contact gap", &info.name)),
                &t_label,
                &axis_label("gap", units, 1, 0, 0),
                &borrowed(&series),
            )?;
            written.push(path);
        }
    }
    Ok(written)
}

/// The bodies' energy over time (sums over the moving bodies of `bodies.csv`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BodyEnergy {
    /// Times, time units.
    pub t: Vec<f64>,
    /// Kinetic energy Σ ½ m |V|² + ½ Ω·(R J Rᵀ) Ω at each time, mass length²/time².
    pub kinetic: Vec<f64>,
    /// Potential energy Σ -m g·x (zero at the origin) at each time.
    pub potential: Vec<f64>,
}

impl BodyEnergy {
    /// Kinetic plus potential energy at each time.
    pub fn total(&self) -> Vec<f64> {
        self.kinetic
            .iter()
            .zip(&self.potential)
            .map(|(k, p)| k + p)
            .collect()
    }
}

/// The kinetic (translational ½ m |V|² plus rotational ½ Ω·(R J Rᵀ) Ω, R the orientation in
/// `bodies.csv`) and potential (-m g·x) energy of the moving bodies of the run in `dir`, summed
/// per time, with m and J of the scene's shapes and densities (`info`, see
/// [`RunInfo::read`]). V, Ω and x are the body origin's velocity, angular velocity and
/// position, so this is exact for shapes centred on their origin (every primitive).
/// `None` if there is no `bodies.csv` (or no row), or a body's mass or inertia is not known (an
/// unbounded shape, or no readable `scene.ron`).
pub fn body_energy(dir: &Path, info: &RunInfo) -> Result<Option<BodyEnergy>> {
    let csv = dir.join("bodies.csv");
    if !csv.is_file() {
        return Ok(None);
    }
    let text = read(&csv)?;
    let table = Table::parse(&csv, &text)?;
    if table.rows.is_empty() {
        return Ok(None);
    }
    let c = |name: &str| table.col(name);
    let ti = c("t")?;
    let ni = c("name")?;
    let cols =
        |names: [&str; 3]| -> Result<[usize; 3]> { Ok([c(names[0])?, c(names[1])?, c(names[2])?]) };
    let (xi, vi, wi) = (
        cols(["x", "y", "z"])?,
        cols(["vx", "vy", "vz"])?,
        cols(["wx", "wy", "wz"])?,
    );
    let qi = [c("qw")?, c("qx")?, c("qy")?, c("qz")?];
    let g = DVec3::from_array(info.gravity);
    let mut e = BodyEnergy::default();
    for row in &table.rows {
        let name = row.fields[ni].trim();
        let Some(body) = info.body(name).map(|i| &info.bodies[i]) else {
            return Ok(None);
        };
        let (Some(m), Some(j)) = (body.mass, body.inertia) else {
            return Ok(None);
        };
        let vec3 = |i: [usize; 3]| -> Result<DVec3> {
            Ok(DVec3::new(
                table.num(row, i[0])?,
                table.num(row, i[1])?,
                table.num(row, i[2])?,
            ))
        };
        let (x, v, w) = (vec3(xi)?, vec3(vi)?, vec3(wi)?);
        let q = DQuat::from_xyzw(
            table.num(row, qi[1])?,
            table.num(row, qi[2])?,
            table.num(row, qi[3])?,
            table.num(row, qi[0])?,
        );
        let r = if q.length_squared() > 0.0 {
            DMat3::from_quat(q.normalize())
        } else {
            DMat3::IDENTITY
        };
        let kinetic = 0.5 * m * v.length_squared() + 0.5 * w.dot(r * j * r.transpose() * w);
        let potential = -m * g.dot(x);
        let t = table.num(row, ti)?;
        if e.t.last() != Some(&t) {
            e.t.push(t);
            e.kinetic.push(0.0);
            e.potential.push(0.0);
        }
        *e.kinetic.last_mut().unwrap_or(&mut 0.0) += kinetic;
        *e.potential.last_mut().unwrap_or(&mut 0.0) += potential;
    }
    Ok(Some(e))
}

/// The series of `contacts_gap.png` for the run in `dir`: the gap of each contact pair against
/// `t`, labelled with the two bodies' names (`contacts.csv` entries that are body ids are
/// named from the scene), at most [`MAX_CURVES`] pairs; then, when the scene gives it, the
/// contact range ε as a dashed horizontal line over the same times, labelled "ε = …". Empty
/// if `contacts.csv` is missing or has no row.
pub fn gap_series(dir: &Path) -> Result<Vec<OwnedSeries>> {
    let csv = dir.join("contacts.csv");
    if !csv.is_file() {
        return Ok(Vec::new());
    }
    Ok(gap_series_of(&csv, &RunInfo::of_dir(dir))?.0)
}

/// [`gap_series`] of `csv`, and the title note when pairs were left out.
fn gap_series_of(csv: &Path, info: &RunInfo) -> Result<(Vec<OwnedSeries>, String)> {
    let text = read(csv)?;
    let table = Table::parse(csv, &text)?;
    if table.rows.is_empty() {
        return Ok((Vec::new(), String::new()));
    }
    let (ti, ai, bi, gi) = (
        table.col("t")?,
        table.col("body_a")?,
        table.col("body_b")?,
        table.col("gap")?,
    );
    // A pair is the same whichever body is listed first: key on the sorted names.
    let names: Vec<(&str, &str)> = table
        .rows
        .iter()
        .map(|row| {
            (
                info.body_name(row.fields[ai].trim()),
                info.body_name(row.fields[bi].trim()),
            )
        })
        .collect();
    let keys: Vec<String> = names
        .iter()
        .map(|&(a, b)| {
            if a <= b {
                format!("{a}\n{b}")
            } else {
                format!("{b}\n{a}")
            }
        })
        .collect();
    let mut curves = Curves::new();
    let (mut t0, mut t1) = (f64::INFINITY, f64::NEG_INFINITY);
    for ((row, key), &(a, b)) in table.rows.iter().zip(&keys).zip(&names) {
        let t = table.num(row, ti)?;
        let gap = table.num(row, gi)?;
        if t.is_finite() {
            t0 = t0.min(t);
            t1 = t1.max(t);
        }
        if let Some(curve) = curves.get(key, || format!("{a}\u{2013}{b}")) {
            curve.points[0].push((t, gap));
        }
    }
    let mut series: Vec<OwnedSeries> = curves
        .curves
        .iter()
        .map(|c| OwnedSeries {
            label: c.label.clone(),
            points: c.points[0].clone(),
            style: Style::Line,
        })
        .collect();
    if let Some(eps) = info.eps
        && t0 <= t1
    {
        series.push(OwnedSeries {
            label: format!("ε = {eps:.4} (contact range)"),
            points: vec![(t0, eps), (t1, eps)],
            style: Style::Dashed,
        });
    }
    Ok((series, curves.note("pairs")))
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

fn plot_bodies(dir: &Path, csv: &Path, info: &RunInfo) -> Result<Vec<PathBuf>> {
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
    let units = info.units.as_ref();
    let mut written = Vec::new();
    for (file, what, y_label, pick) in [
        (
            "bodies_height.png",
            "Body height",
            axis_label(&format!("height {axis}"), units, 1, 0, 0),
            0,
        ),
        (
            "bodies_velocity.png",
            "Vertical velocity",
            axis_label(&format!("velocity v{axis}"), units, 1, -1, 0),
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
            &format!("{}{note}", chart_title(what, &info.name)),
            &axis_label("t", units, 0, 1, 0),
            &y_label,
            &series,
        )?;
        written.push(path);
    }
    Ok(written)
}

fn read(path: &Path) -> Result<String> {
    std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))
}

/// A data row of a CSV file: its 1-based line number and its fields.
struct Row {
    line: u64,
    fields: csv::StringRecord,
}

/// A CSV file with a header line, read with the `csv` crate (RFC 4180: a quoted field may hold
/// commas, double quotes and line breaks; blank lines and a leading byte order mark are
/// ignored; header names are trimmed).
struct Table<'a> {
    path: &'a Path,
    header: Vec<String>,
    rows: Vec<Row>,
}

impl<'a> Table<'a> {
    fn parse(path: &'a Path, text: &str) -> Result<Self> {
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        let mut records = csv::ReaderBuilder::new()
            .has_headers(false)
            .flexible(true)
            .from_reader(text.as_bytes())
            .into_records()
            .map(|r| {
                r.map_err(|e| {
                    let line = e
                        .position()
                        .map_or(String::new(), |p| format!(":{}", p.line()));
                    anyhow!("{}{line}: malformed CSV: {e}", path.display())
                })
            })
            // A line of blanks only is a blank line too.
            .filter(|r| {
                r.as_ref()
                    .map_or(true, |r| !(r.len() == 1 && r[0].trim().is_empty()))
            });
        let Some(head) = records.next().transpose()? else {
            bail!("{}: empty file, expected a header line", path.display());
        };
        let header: Vec<String> = head.iter().map(|h| h.trim().to_string()).collect();
        let mut rows = Vec::new();
        for fields in records {
            let fields = fields?;
            let line = fields.position().map_or(0, csv::Position::line);
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
        self.header.iter().position(|h| h == name).ok_or_else(|| {
            anyhow!(
                "{}: no `{name}` column in the header ({})",
                self.path.display(),
                self.header.join(",")
            )
        })
    }

    /// The number in column `col` of `row`.
    fn num(&self, row: &Row, col: usize) -> Result<f64> {
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
