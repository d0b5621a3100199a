//! `column-collapse`: a 2D column of liquid collapsing in a closed tank, the dam break of Martin &
//! Moyce (1952) (issue 34's first gate; `scenes/column-collapse.ron`).
//!
//! Everything is measured on the grid from the liquid's level set φ_w, sampled every 0.05 in
//! time (the clock lands on the sample times): the liquid area, the connected liquid regions
//! and the surge front. The level set's own volume ∫H_ε(φ_w) (`series.csv`'s `liquid_volume`)
//! is restored to its initial value after every step by construction, so the area row counts
//! the region φ_w > 0 itself instead.

use crate::bodies::free_surface::LiquidLevelSet;
use crate::bodies::shapes::Shape;
use crate::scene::{LiquidRegion, Scene};
use crate::sim::engine::Simulation;
use crate::validate::{Case, PlotSpec, Report, Row, RunTime, bundled_scene};

/// The case: what it checks, against what, and the rows known to fail.
pub const CASE: Case = Case {
    name: "column-collapse",
    description: "a liquid column 1 wide and 2 high collapsing at the left wall of a closed tank [0,12] x [0,3] (|g| = 1, nu = 2.35e-5: water at a = 57 mm) runs to t = 2.3; the liquid area (phi_w > 0 counted on the grid) stays within 0.5% of 2; the liquid stays one connected region (no other of more than 4 nodes) until the front reaches the far wall; the tank's kinetic + potential energy never rises by more than 1% of the potential energy the column releases; the surge front at h = 1/32 and 1/64 agrees within 3% from t = 0.2; the front against Martin & Moyce's experiment is plotted only",
    reference: "issue 34's criteria (conservation, one region, grid convergence); energy balance of a flow with no driving (dE/dt <= 0); Martin & Moyce 1952 (Phil. Trans. R. Soc. A 244, 312-324), Fig. 3, n^2 = 2, as digitised in PySPH (pysph/examples/db_exp_data.py), plotted only",
    full: "scenes/column-collapse.ron at h = 1/32 and 1/64, gas density 1/100 and 1/1000, to t = 2.3",
    quick: "h = 1/32, gas density 1/100 and 1/1000, to t = 2.3, no grid comparison (about 10 seconds on 2 cores)",
    full_time: RunTime::Long,
    quick_time: RunTime::Minutes,
    run: column_collapse,
    known_failures: &[],
};

/// The largest rise of the tank's kinetic + potential energy over an earlier sample that the
/// energy row accepts, as a fraction of the potential energy the column releases: a flow with
/// no driving only loses energy (dE/dt = -dissipation); this leaves room for the sampling of
/// an energy that sloshes between kinetic and potential within a step.
const ENERGY_RISE: f64 = 0.01;

/// Sampling interval in time.
const SAMPLE: f64 = 0.05;

/// Largest size, in nodes, of a liquid region apart from the main one that is not a fragment.
const FRAGMENT_NODES: usize = 4;

/// The front is read along the node row this far above the floor (the first row inside the
/// tank at h = 1/32, the second at 1/64: the same height on both grids).
const FRONT_HEIGHT: f64 = 1.0 / 32.0;

/// The front has reached the far wall when it is this many cells from it.
const FAR_WALL_CELLS: f64 = 4.0;

/// The grid comparison of the front starts here (before, the front has barely moved).
const COMPARE_FROM: f64 = 0.2;

/// Martin & Moyce 1952, Fig. 3 (n² = 2): the surge front Z = z/a against T = t (2g/a)^(1/2),
/// for the column of a = 2.25 in (the a = 57 mm) up to T = 3.4, as digitised in PySPH's
/// `pysph/examples/db_exp_data.py`.
const MARTIN_MOYCE_A225: &[(f64, f64)] = &[
    (0.832, 1.217),
    (1.219, 1.474),
    (1.997, 2.292),
    (2.547, 2.995),
    (3.345, 4.134),
];

/// The same for the column of a = 1.125 in up to T = 3.6.
const MARTIN_MOYCE_A1125: &[(f64, f64)] = &[
    (0.849, 1.245),
    (1.212, 1.443),
    (1.602, 1.884),
    (2.283, 2.689),
    (2.950, 3.728),
    (3.598, 4.528),
];

/// The tank's inner box and the column at t = 0, read from the scene.
struct Geometry {
    /// Lower-left corner of the liquid's side of the walls (their inner faces).
    lo: [f64; 2],
    /// Upper-right corner.
    hi: [f64; 2],
    /// Width a of the column.
    width: f64,
    /// Area of the column.
    area: f64,
}

/// The tank (the first body, the outside of a rectangle) and the column (the first liquid
/// region, a rectangle) of `scenes/column-collapse.ron`.
fn geometry(scene: &Scene) -> anyhow::Result<Geometry> {
    let tank = scene
        .bodies
        .first()
        .ok_or_else(|| anyhow::anyhow!("column-collapse.ron: no tank"))?;
    let Shape::Complement(inner) = &tank.shape else {
        anyhow::bail!("column-collapse.ron: the first body must be the outside of a rectangle");
    };
    let Shape::Rectangle { half_extents: e } = **inner else {
        anyhow::bail!("column-collapse.ron: the first body must be the outside of a rectangle");
    };
    let Some(LiquidRegion::Shape {
        shape: Shape::Rectangle { half_extents: c },
        ..
    }) = scene.free_surface.as_ref().and_then(|f| f.liquid.first())
    else {
        anyhow::bail!("column-collapse.ron: the liquid must be a rectangle");
    };
    let p = &tank.position;
    Ok(Geometry {
        lo: [p[0] - e[0], p[1] - e[1]],
        hi: [p[0] + e[0], p[1] + e[1]],
        width: 2.0 * c[0],
        area: 4.0 * c[0] * c[1],
    })
}

/// What one sample of φ_w shows.
#[derive(Debug, Clone, Copy)]
struct Sample {
    /// Area of the region φ_w > 0 inside the tank (linear interpolation on two triangles per
    /// cell).
    area: f64,
    /// Connected liquid regions apart from the largest with more than [`FRAGMENT_NODES`] nodes.
    fragments: usize,
    /// Connected liquid regions apart from the largest, of any size.
    others: usize,
    /// Nodes of the largest of those.
    biggest_other: usize,
    /// Front of the largest region along the row [`FRONT_HEIGHT`] above the floor, from the
    /// left wall's inner face (NaN if it does not reach that row).
    front: f64,
    /// Kinetic plus potential energy (height from the floor) of both phases inside the tank,
    /// ∫ρ(|u|²/2 + |g| y) over the nodes strictly inside the walls, ρ from φ_w (the liquid's
    /// density 1 and the gas's).
    energy: f64,
}

/// The node index range strictly inside [lo, hi] along an axis (the faces must lie on nodes).
fn inside(lo: f64, hi: f64, origin: f64, h: f64) -> anyhow::Result<(usize, usize)> {
    let (a, b) = ((lo - origin) / h, (hi - origin) / h);
    if (a - a.round()).abs() > 1e-6 || (b - b.round()).abs() > 1e-6 || a.round() < 0.0 {
        anyhow::bail!("column-collapse: the tank's walls must lie on grid nodes (h = {h})");
    }
    Ok((a.round() as usize + 1, b.round() as usize - 1))
}

/// Fraction of a triangle where the linear function with corner values `v` is positive.
fn positive_fraction(v: [f64; 3]) -> f64 {
    let pos = v.iter().filter(|&&x| x > 0.0).count();
    let lone = |want_positive: bool| {
        let k = (0..3).find(|&k| (v[k] > 0.0) == want_positive).unwrap_or(0);
        let a = v[k];
        let (b, c) = (v[(k + 1) % 3], v[(k + 2) % 3]);
        a * a / ((a - b) * (a - c))
    };
    match pos {
        0 => 0.0,
        3 => 1.0,
        1 => lone(true),
        _ => 1.0 - lone(false),
    }
}

fn sample(sim: &Simulation, geo: &Geometry, gas: f64) -> anyhow::Result<Sample> {
    let grid = sim.grid();
    let phi = &sim.world.resource::<LiquidLevelSet>().phi;
    let (h, nx) = (grid.h, grid.n[0]);
    let (i0, i1) = inside(geo.lo[0], geo.hi[0], grid.origin[0], h)?;
    let (j0, j1) = inside(geo.lo[1], geo.hi[1], grid.origin[1], h)?;
    let at = |i: usize, j: usize| phi[i + nx * j];
    let params = sim.world.resource::<crate::base::fields::Params>();
    let g = params.gravity[1].abs();
    let eps = params.numerics.interface_cells * h;
    let u = &sim.fields().u;
    let mut energy = 0.0;
    for j in j0..=j1 {
        for i in i0..=i1 {
            let c = i + nx * j;
            let rho = gas + (1.0 - gas) * crate::base::kernels::heaviside(phi[c], eps);
            let y = grid.pos(i, j, 0)[1] - geo.lo[1];
            energy += rho * (0.5 * (u[0][c] * u[0][c] + u[1][c] * u[1][c]) + g * y);
        }
    }
    energy *= h * h;
    // Area: every cell between the walls' faces (nodes i0 - 1 ..= i1 + 1).
    let mut area = 0.0;
    for j in j0 - 1..=j1 {
        for i in i0 - 1..=i1 {
            let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            area += positive_fraction([a, b, c]) + positive_fraction([a, c, d]);
        }
    }
    area *= 0.5 * h * h;
    // 4-connected regions of the nodes inside the tank with φ_w > 0.
    let mut label = vec![usize::MAX; phi.len()];
    let mut sizes = Vec::new();
    let mut stack = Vec::new();
    for j in j0..=j1 {
        for i in i0..=i1 {
            if at(i, j) <= 0.0 || label[i + nx * j] != usize::MAX {
                continue;
            }
            let id = sizes.len();
            let mut n = 0;
            label[i + nx * j] = id;
            stack.push((i, j));
            while let Some((a, b)) = stack.pop() {
                n += 1;
                for (p, q) in [(a - 1, b), (a + 1, b), (a, b - 1), (a, b + 1)] {
                    if (i0..=i1).contains(&p)
                        && (j0..=j1).contains(&q)
                        && at(p, q) > 0.0
                        && label[p + nx * q] == usize::MAX
                    {
                        label[p + nx * q] = id;
                        stack.push((p, q));
                    }
                }
            }
            sizes.push(n);
        }
    }
    let main = (0..sizes.len()).max_by_key(|&k| sizes[k]);
    let others = sizes.len().saturating_sub(1);
    let rest = || {
        (0..sizes.len())
            .filter(|&k| Some(k) != main)
            .map(|k| sizes[k])
    };
    let fragments = rest().filter(|&n| n > FRAGMENT_NODES).count();
    let biggest_other = rest().max().unwrap_or(0);
    // The front: the last node of the main region along the row, then the zero of φ_w after it.
    let jf = ((geo.lo[1] + FRONT_HEIGHT - grid.origin[1]) / h).round() as usize;
    let last = main.and_then(|m| (i0..=i1).rev().find(|&i| label[i + nx * jf] == m));
    let front = match last {
        None => f64::NAN,
        Some(i) if i == i1 => geo.hi[0] - geo.lo[0],
        Some(i) => {
            let (p, q) = (at(i, jf), at(i + 1, jf));
            grid.pos(i, jf, 0)[0] + h * p / (p - q) - geo.lo[0]
        }
    };
    Ok(Sample {
        area,
        fragments,
        others,
        biggest_other,
        front,
        energy,
    })
}

/// One run: its samples and how it ended.
struct Run {
    ratio: f64,
    h: f64,
    end: f64,
    /// The time reached.
    reached: f64,
    /// The blow-up, if the run stopped at one.
    error: Option<String>,
    /// (t, sample), every [`SAMPLE`] from t = 0.
    samples: Vec<(f64, Sample)>,
    /// Largest |V/V₀ - 1| of the level set's own volume ∫H_ε(φ_w) (held by construction).
    volume_drift: f64,
    /// |g|.
    gravity: f64,
}

impl Run {
    fn label(&self) -> String {
        format!("1:{}, h = 1/{}", self.ratio, (1.0 / self.h).round())
    }

    /// The first sampled time when the front is within [`FAR_WALL_CELLS`] of the far wall.
    fn far_wall(&self, geo: &Geometry) -> Option<f64> {
        let reach = geo.hi[0] - geo.lo[0] - FAR_WALL_CELLS * self.h;
        self.samples
            .iter()
            .find(|(_, s)| s.front >= reach)
            .map(|(t, _)| *t)
    }

    /// Where the run stopped, for a row's text: "" when it ran to its end.
    fn stopped(&self) -> String {
        match self.error {
            Some(_) => format!(
                "; not measured past t = {:.3}, where the run blew up",
                self.reached
            ),
            None => String::new(),
        }
    }
}

/// The column at density ratio 1:`ratio` and grid step `h`, sampled every [`SAMPLE`] to its
/// end or its blow-up (an error of a step).
fn run(ratio: f64, h: f64, geo: &Geometry) -> anyhow::Result<Run> {
    let scene = bundled_scene("column-collapse.ron")?.edit(|s| {
        s.domain.cells = None;
        s.domain.h = Some(h);
        if let Some(fs) = s.free_surface.as_mut() {
            fs.gas_density = 1.0 / ratio;
        }
    })?;
    let end = scene.numerics.end_time;
    let gravity = scene
        .fluid
        .gravity
        .iter()
        .map(|g| g * g)
        .sum::<f64>()
        .sqrt();
    let mut sim = crate::validate::simulation(scene)?;
    let mut samples = vec![(0.0, sample(&sim, geo, 1.0 / ratio)?)];
    let mut drift = 0.0f64;
    let mut error = None;
    for k in 1.. {
        let t = if k as f64 * SAMPLE >= end - 1e-9 {
            end
        } else {
            k as f64 * SAMPLE
        };
        let step = sim.run_until(t, |s| {
            let ls = s.world.resource::<LiquidLevelSet>();
            drift = drift.max((ls.volume / ls.target_volume - 1.0).abs());
        });
        if let Err(e) = step {
            error = Some(format!("{e:#}"));
            break;
        }
        samples.push((sim.time(), sample(&sim, geo, 1.0 / ratio)?));
        if t == end {
            break;
        }
    }
    Ok(Run {
        ratio,
        h,
        end,
        reached: sim.time(),
        error,
        samples,
        volume_drift: drift,
        gravity,
    })
}

/// Rows 1 to 3 of a run: it reaches its end, the liquid area holds, the liquid stays one region.
fn run_rows(rep: &mut Report, r: &Run, geo: &Geometry) {
    let label = r.label();
    let stopped = r.stopped();
    rep.rows.push(Row::yes_no(
        format!(
            "{label}: runs to t = {} (reached t = {:.3})",
            r.end, r.reached
        ),
        r.error.is_none(),
    ));
    let (ta, worst) = r
        .samples
        .iter()
        .map(|(t, s)| (*t, s.area))
        .max_by(|a, b| (a.1 - geo.area).abs().total_cmp(&(b.1 - geo.area).abs()))
        .unwrap_or((0.0, f64::NAN));
    let area = format!(
        "{label}: liquid area (phi_w > 0 on the grid) within 0.5% of {} at all times",
        geo.area
    );
    rep.rows.push(match &r.error {
        None => Row::rel(
            format!("{area} (worst at t = {ta:.2})"),
            geo.area,
            worst,
            0.005,
        ),
        Some(_) => Row::yes_no(
            format!(
                "{area} (worst {worst:.5}, {:+.3}%, at t = {ta:.2}{stopped})",
                100.0 * (worst / geo.area - 1.0)
            ),
            false,
        ),
    });
    let until = r.far_wall(geo).unwrap_or(f64::INFINITY);
    let (tf, worst) = r
        .samples
        .iter()
        .filter(|(t, _)| *t < until)
        .map(|(t, s)| (*t, *s))
        .max_by_key(|(_, s)| s.fragments)
        .map_or((0.0, 0), |(t, s)| (t, s.fragments));
    let biggest = r
        .samples
        .iter()
        .filter(|(t, _)| *t < until)
        .map(|(_, s)| s.biggest_other)
        .max()
        .unwrap_or(0);
    let one = format!(
        "{label}: one connected liquid region until the front reaches the far wall (no other of more than {FRAGMENT_NODES} nodes)"
    );
    let detail =
        format!("largest count of fragments {worst} at t = {tf:.2}, the biggest {biggest} nodes");
    rep.rows.push(match &r.error {
        None => Row::abs(format!("{one} ({detail})"), 0.0, worst as f64, 0.0),
        Some(_) => Row::yes_no(format!("{one} ({detail}{stopped})"), false),
    });
    // Energy: the largest rise of the kinetic + potential energy over an earlier sample, in
    // units of the potential energy the column releases as it spreads into a flat layer.
    let width = geo.hi[0] - geo.lo[0];
    let released = (1.0 - 1.0 / r.ratio)
        * r.gravity
        * (geo.area * geo.area / (2.0 * geo.width) - geo.area * geo.area / (2.0 * width));
    let mut lowest = f64::INFINITY;
    let (mut rise, mut rise_at) = (0.0f64, (0.0, 0.0));
    for (t, s) in &r.samples {
        if s.energy - lowest > rise {
            rise = s.energy - lowest;
            rise_at = (*t, s.energy);
        }
        lowest = lowest.min(s.energy);
    }
    let energy = format!(
        "{label}: kinetic + potential energy never rises over an earlier sample by more than {ENERGY_RISE} of the potential energy the column releases ({released:.3})"
    );
    let detail = if rise > 0.0 {
        format!(
            "largest rise {rise:.3e} to {:.5} at t = {:.2}",
            rise_at.1, rise_at.0
        )
    } else {
        "it never rises".to_string()
    };
    rep.rows.push(match &r.error {
        None => Row::abs(
            format!("{energy} ({detail})"),
            0.0,
            rise / released,
            ENERGY_RISE,
        ),
        Some(_) => Row::yes_no(format!("{energy} ({detail}{stopped})"), false),
    });
    // A quantity at the given sample times, as a list ("-" where the run did not get).
    let at = |times: &[f64], f: fn(&Sample) -> f64| {
        times
            .iter()
            .map(|&t| {
                r.samples
                    .iter()
                    .find(|(s, _)| (s - t).abs() < 1e-9)
                    .map_or("-".to_string(), |(_, s)| format!("{:.4}", f(s)))
            })
            .collect::<Vec<_>>()
            .join(", ")
    };
    let others = r.samples.iter().map(|(_, s)| s.others).max().unwrap_or(0);
    let first = r
        .samples
        .iter()
        .find(|(_, s)| s.fragments > 0)
        .map_or("none".to_string(), |(t, _)| format!("t = {t:.2}"));
    rep.notes.push(format!(
        "{label}: kinetic + potential energy at t = 0, 0.5, 1, 1.5, 2, 2.3: {}; liquid area at t = 0, 0.05, 0.5, 1, 1.5, 2, 2.3: {}; front (x - x_wall)/a at t = 0.1, 0.2, 0.3, 0.5, 0.75, 1, 1.5, 2, 2.3: {}; front at the far wall: {}; first fragment: {first}; most liquid regions besides the main one (any size) {others}; the level set's own volume drifts {:.1e} (restored every step); {}",
        at(&[0.0, 0.5, 1.0, 1.5, 2.0, 2.3], |s| s.energy),
        at(&[0.0, 0.05, 0.5, 1.0, 1.5, 2.0, 2.3], |s| s.area),
        at(&[0.1, 0.2, 0.3, 0.5, 0.75, 1.0, 1.5, 2.0, 2.3], |s| s.front),
        r.far_wall(geo)
            .map_or("not reached".to_string(), |t| format!("t = {t:.2}")),
        r.volume_drift,
        match &r.error {
            Some(e) => format!(
                "stopped at t = {:.3}: {}",
                r.reached,
                e.lines().next().unwrap_or("")
            ),
            None => format!("ran to t = {}", r.end),
        },
    ));
}

/// Row 4: the fronts of a coarse and a fine run at the same sample times, from t = 0.2 until
/// either reaches the far wall, within 3% of the fine one.
fn convergence_row(rep: &mut Report, coarse: &Run, fine: &Run, geo: &Geometry) {
    let until = coarse
        .far_wall(geo)
        .unwrap_or(f64::INFINITY)
        .min(fine.far_wall(geo).unwrap_or(f64::INFINITY));
    let mut worst = (0.0, 0.0f64);
    let mut compared = 0;
    for ((t, c), (_, f)) in coarse.samples.iter().zip(&fine.samples) {
        if *t < COMPARE_FROM - 1e-9 || *t >= until {
            continue;
        }
        compared += 1;
        let d = ((c.front - f.front) / f.front).abs();
        if d.is_nan() || d > worst.1 {
            worst = (*t, if d.is_nan() { f64::INFINITY } else { d });
        }
    }
    let quantity = format!(
        "1:{}: front at h = 1/{} and 1/{} within 3% from t = {COMPARE_FROM} until the far wall",
        coarse.ratio,
        (1.0 / coarse.h).round(),
        (1.0 / fine.h).round()
    );
    let common = coarse.reached.min(fine.reached);
    rep.rows.push(if coarse.error.is_none() && fine.error.is_none() {
        Row::abs(
            format!("{quantity} (largest difference at t = {:.2})", worst.0),
            0.0,
            worst.1,
            0.03,
        )
    } else if compared == 0 {
        Row::yes_no(
            format!(
                "{quantity} (not measured: a run blew up at t = {common:.3}, before t = {COMPARE_FROM})"
            ),
            false,
        )
    } else {
        Row::yes_no(
            format!(
                "{quantity} (largest difference {:.2}% at t = {:.2}; not measured past t = {common:.3}, where a run blew up)",
                100.0 * worst.1,
                worst.0
            ),
            false,
        )
    });
}

/// The column collapse of issue 34 at density ratios 1:100 and 1:1000: each run reaches t = 2.3,
/// its liquid area holds within 0.5%, its liquid stays one region until the front reaches the
/// far wall; in full, the fronts at h = 1/32 and 1/64 agree within 3%. A blow-up ends a run
/// and fails the rows it prevents, with the time reached. The front Z = x/a against T =
/// t (2g/a)^(1/2) is plotted over Martin & Moyce's measurements.
pub fn column_collapse(quick: bool) -> anyhow::Result<Report> {
    let mut rep = Report::new("column-collapse");
    let base = bundled_scene("column-collapse.ron")?;
    let geo = geometry(&base)?;
    let g = glam::DVec3::from_array(base.gravity()).length();
    let hs: &[f64] = if quick {
        &[1.0 / 32.0]
    } else {
        &[1.0 / 32.0, 1.0 / 64.0]
    };
    let mut plot = PlotSpec::new(
        "front",
        "surge front against Martin & Moyce 1952 (n^2 = 2)",
        "T = t (2 g / a)^(1/2)",
        "Z = x_front / a",
    );
    for ratio in [100.0, 1000.0] {
        let runs = hs
            .iter()
            .map(|&h| run(ratio, h, &geo))
            .collect::<anyhow::Result<Vec<_>>>()?;
        for r in &runs {
            run_rows(&mut rep, r, &geo);
            plot = plot.measured(
                r.label(),
                r.samples
                    .iter()
                    .filter(|(_, s)| s.front.is_finite())
                    .map(|(t, s)| (t * (2.0 * g / geo.width).sqrt(), s.front / geo.width))
                    .collect(),
            );
        }
        if let [coarse, fine] = &runs[..] {
            convergence_row(&mut rep, coarse, fine, &geo);
        }
    }
    rep.plots.push(
        plot.reference_points(
            "Martin & Moyce 1952 Fig. 3, a = 2.25 in",
            MARTIN_MOYCE_A225.to_vec(),
        )
        .reference_points(
            "Martin & Moyce 1952 Fig. 3, a = 1.125 in",
            MARTIN_MOYCE_A1125.to_vec(),
        ),
    );
    Ok(rep)
}
