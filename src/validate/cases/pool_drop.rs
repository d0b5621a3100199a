//! `pool-drop`: a light and a heavy sphere dropped onto a pool at the real air/water density
//! ratio 1:1000 (issue 34's 3D gate; `scenes/pool-drop.ron`).
//!
//! Quick: 64³, the grid; full: 48³, 64³ and 96³.
//!
//! The set-up (units of the box side and |g|): a closed tank, the outside of a box with walls
//! 0.0625 thick (4 cells at 64³, 3 at 48³) around the unit box, its inner faces at 0.0625 and
//! 0.9375; water (density 1) up to z = 0.5, gas of density 0.001, g = -1 along z. Two spheres of
//! radius 0.08 (5 cells at 64³), densities 0.5 and 2, side by side at x = 0.3 and 0.7 (0.24
//! apart, 10 cells from the side walls at 64³), released at rest with their bottoms one radius
//! above the surface: they arrive at sqrt(2 g r) = 0.4. ν = 1e-3 puts the heavy sphere's fall at
//! a Reynolds number of about 60 on its diameter at that speed (its terminal speed in water is
//! below it), which 5 cells per radius resolve: the grid is not the question, the density ratio
//! is. The end time 10 is about five periods of the light sphere's heave (ω² ≈ g/r for a
//! half-immersed sphere, ω ≈ 3.5) and three of the tank's first sloshing mode (ω² = g k
//! tanh(k d), k = π/0.875, d = 0.4375: period 3.5); the heavy sphere is on the floor by t = 2.
//!
//! Archimedes: a sphere of density 0.5 (1 - 1e-3 in the gas) floats with (0.5 - 0.001)/(1 -
//! 0.001) of its volume immersed, so with its centre 7e-4 r above the waterline (the section
//! there is π r²): on it, within one cell. Both spheres displace water once in, 3V/2 with V =
//! 4π r³/3, which raises the waterline by 3V/(2A) = 0.0042 (A = 0.875², the tank's section;
//! 0.27 cells at 64³) to 0.5042. Two rows: the light sphere's centre against the waterline
//! measured on the grid in the columns away from both spheres (what the sphere floats in), and
//! against Archimedes' 0.5042 (which also needs the liquid's volume kept). Both are averaged
//! over the last quarter of the run, where the sphere still rides the tank's sloshing; its
//! height's and vertical speed's rms there must stay below those of a heave of one cell.
//!
//! The liquid volume: the level set's own ∫(1 - χ_s)H_ε(φ_w) (`series.csv`'s `liquid_volume`)
//! is restored after every step by construction, and it counts φ_w continued inside the moving
//! bodies as liquid. The row measures the liquid itself instead: along every vertical grid
//! line inside the tank, the length where φ_w (linear between nodes) is positive, outside the
//! spheres (their chords taken exactly), summed with the trapezoid weights of the lines over
//! the tank's section; at t = 0 it is exactly the pool A × 0.4375. The notes add the gas
//! carried under water (φ_w < 0 more than two radii below the surface and a cell from the
//! spheres), which physically rises out long before the end.

use crate::bodies::free_surface::LiquidLevelSet;
use crate::bodies::shapes::Shape;
use crate::scene::{LiquidRegion, Scene};
use crate::sim::engine::Simulation;
use crate::validate::{Case, KnownFailure, Report, Row, RunTime, bundled_scene};

/// The case: what it checks, against what, and the rows known to fail.
pub const CASE: Case = Case {
    name: "pool-drop",
    description: "a sphere of density 0.5 and one of density 2 (radius 0.08) dropped from one radius above a pool at ratio 1:1000 (closed tank, |g| = 1, nu = 1e-3) run to t = 10: both enter the water, the light one floats with its centre within one cell of the waterline (measured, and Archimedes' raised by the displaced water) and settles, the heavy one ends on the floor (gap within the contact's range), the liquid volume (phi_w > 0 on the grid outside the spheres) stays within 1% of the pool's",
    reference: "Archimedes (a sphere of density 0.5 floats half immersed: its centre on the waterline, raised by the displaced volume over the tank's section); conservation of the liquid's volume; issue 34's criteria",
    full: "scenes/pool-drop.ron at 48^3, 64^3 and 96^3, ratio 1:1000, to t = 10 (about 11 minutes on 2 cores: 0.5, 2 and 9)",
    quick: "scenes/pool-drop.ron (64^3, the issue's grid), ratio 1:1000, to t = 10 (about 2 minutes on 2 cores)",
    full_time: RunTime::Long,
    quick_time: RunTime::Minutes,
    run: pool_drop,
    known_failures: &[
        KnownFailure {
            row: "96^3, 1:1000: the light sphere's centre height against Archimedes' waterline",
            quick: false,
            full: true,
            why: "measured on e017c5f, before the contact line moved and the redistancing held the band's gas side (at 64^3 both rows pass since: volume within 0.32%, light sphere 6.9e-3 above Archimedes' waterline), not re-run since: 0.5148 against 0.5042 (1.06e-2, one cell 1.04e-2), on the measured waterline 0.5148 within 5e-6: the liquid has grown by 1.7% (the liquid volume row); issue 34",
        },
        KnownFailure {
            row: "96^3, 1:1000: liquid volume",
            quick: false,
            full: true,
            why: "measured on e017c5f, before the contact line moved and the redistancing held the band's gas side (at 64^3 both rows pass since: volume within 0.32%, light sphere 6.9e-3 above Archimedes' waterline), not re-run since: +1.81% at t = 9.62 (0.34102 against 0.33496; -0.25% at t = 2, +0.34% at 5, +1.71% at 10), gas under water 2.0e-3 at t = 2 and 2.8e-3 at 10: as at 64^3; issue 34",
        },
    ],
};

/// The positions and velocities are averaged over the last quarter of the run (the light
/// sphere still rides the tank's sloshing).
const SETTLED_FROM: f64 = 0.75;

/// The waterline is read in the columns farther than this many radii (horizontally) from
/// both spheres' centres and this many cells from the side walls.
const WATERLINE_RADII: f64 = 2.0;
const WATERLINE_WALL_CELLS: usize = 2;

/// Gas deeper than this many radii below the initial surface is gas carried under water (the
/// light sphere's bottom floats one radius down).
const GAS_DEPTH_RADII: f64 = 2.0;

/// The geometry of `scenes/pool-drop.ron`.
struct Geometry {
    /// Inner faces of the tank (the same on every axis): [lo, hi].
    lo: f64,
    hi: f64,
    /// The initial surface height.
    level: f64,
    /// Radius of the spheres.
    radius: f64,
    /// Densities of the light and heavy spheres.
    light: f64,
    heavy: f64,
}

fn geometry(scene: &Scene) -> anyhow::Result<Geometry> {
    let tank = scene
        .bodies
        .first()
        .ok_or_else(|| anyhow::anyhow!("pool-drop.ron: no tank"))?;
    let (Shape::Complement(inner), [c, ..]) = (&tank.shape, tank.position.as_slice()) else {
        anyhow::bail!("pool-drop.ron: the first body must be the outside of a box");
    };
    let Shape::Box { half_extents: e } = **inner else {
        anyhow::bail!("pool-drop.ron: the first body must be the outside of a box");
    };
    let Some(LiquidRegion::Below { height, .. }) =
        scene.free_surface.as_ref().and_then(|f| f.liquid.first())
    else {
        anyhow::bail!("pool-drop.ron: the liquid must be a pool");
    };
    let sphere = |name: &str| {
        scene
            .bodies
            .iter()
            .find(|b| b.name == name)
            .and_then(|b| match b.shape {
                Shape::Sphere { radius } => b.density.map(|d| (radius, d)),
                _ => None,
            })
            .ok_or_else(|| anyhow::anyhow!("pool-drop.ron: no sphere named {name}"))
    };
    let (radius, light) = sphere("light")?;
    let (r2, heavy) = sphere("heavy")?;
    if r2 != radius {
        anyhow::bail!("pool-drop.ron: the two spheres must have the same radius");
    }
    Ok(Geometry {
        lo: c - e[0],
        hi: c + e[0],
        level: *height,
        radius,
        light,
        heavy,
    })
}

/// The node index of a tank face, which must lie on a node.
fn face_node(x: f64, origin: f64, h: f64) -> anyhow::Result<usize> {
    let a = (x - origin) / h;
    if (a - a.round()).abs() > 1e-6 || a.round() < 1.0 {
        anyhow::bail!("pool-drop: the tank's walls must lie on grid nodes (h = {h})");
    }
    Ok(a.round() as usize)
}

/// What the grid shows of the liquid at one time.
struct Liquid {
    /// Volume of φ_w > 0 inside the tank and outside the spheres.
    volume: f64,
    /// Volume of φ_w > 0 inside the spheres (φ_w continued into them, which the level set's
    /// own volume counts as liquid).
    inside: f64,
    /// Volume of φ_w < 0 more than [`GAS_DEPTH_RADII`] radii below the initial surface and
    /// more than a cell from the spheres: gas carried under water (the cell next to a sphere
    /// is left out: φ_w continued inside it is linear across its surface).
    gas_under: f64,
    /// Mean surface height over the columns away from the spheres and the walls.
    waterline: f64,
}

/// The liquid volume and the waterline, with the spheres' centres `centres`.
fn liquid(sim: &Simulation, geo: &Geometry, centres: &[[f64; 3]]) -> anyhow::Result<Liquid> {
    let grid = sim.grid();
    let phi = &sim.world.resource::<LiquidLevelSet>().phi;
    let h = grid.h;
    let (lo, hi) = (
        face_node(geo.lo, grid.origin[0], h)?,
        face_node(geo.hi, grid.origin[0], h)?,
    );
    let (klo, khi) = (
        face_node(geo.lo, grid.origin[2], h)?,
        face_node(geo.hi, grid.origin[2], h)?,
    );
    if face_node(geo.lo, grid.origin[1], h)? != lo || hi >= grid.n[0] || khi >= grid.n[2] {
        anyhow::bail!("pool-drop: the tank must be a cube inside the grid");
    }
    let r = geo.radius;
    let (mut volume, mut inside, mut gas_under) = (0.0, 0.0, 0.0);
    let (mut line_sum, mut line_count) = (0.0, 0usize);
    let deep = geo.level - GAS_DEPTH_RADII * r;
    for j in lo..=hi {
        for i in lo..=hi {
            let [x, y, _] = grid.pos(i, j, 0);
            let weight = if i == lo || i == hi { 0.5 } else { 1.0 }
                * if j == lo || j == hi { 0.5 } else { 1.0 };
            // The spheres' chords along this line (at most one meets it when they are apart).
            let chords_of = |r: f64| -> Vec<(f64, f64)> {
                centres
                    .iter()
                    .filter_map(|c| {
                        let d2 = (x - c[0]).powi(2) + (y - c[1]).powi(2);
                        (d2 < r * r).then(|| {
                            let s = (r * r - d2).sqrt();
                            (c[2] - s, c[2] + s)
                        })
                    })
                    .collect()
            };
            let (chords, shells) = (chords_of(r), chords_of(r + h));
            let (mut length, mut within, mut gas) = (0.0, 0.0, 0.0);
            for k in klo..khi {
                let (p, q) = (phi[grid.idx(i, j, k)], phi[grid.idx(i, j, k + 1)]);
                let z0 = grid.pos(i, j, k)[2];
                // The part of [z0, z0 + h] below `deep` where the linear φ is negative, outside
                // the spheres.
                if z0 < deep {
                    let top = (z0 + h).min(deep);
                    let (a, b) = match (p > 0.0, q > 0.0) {
                        (true, true) => (z0, z0),
                        (false, false) => (z0, top),
                        (true, false) => ((z0 + h * p / (p - q)).min(top), top),
                        (false, true) => (z0, (z0 + h * p / (p - q)).min(top)),
                    };
                    if b > a {
                        gas += b - a;
                        for &(c, d) in &shells {
                            gas -= (b.min(d) - a.max(c)).max(0.0);
                        }
                    }
                }
                // The part of [z0, z0 + h] where the linear φ is positive.
                let (a, b) = match (p > 0.0, q > 0.0) {
                    (true, true) => (z0, z0 + h),
                    (false, false) => continue,
                    (true, false) => (z0, z0 + h * p / (p - q)),
                    (false, true) => (z0 + h * p / (p - q), z0 + h),
                };
                length += b - a;
                for &(c, d) in &chords {
                    within += (b.min(d) - a.max(c)).max(0.0);
                }
            }
            volume += weight * (length - within);
            inside += weight * within;
            gas_under += weight * gas;
            // The waterline: the zero of φ_w nearest to the initial level.
            let far = centres
                .iter()
                .all(|c| (x - c[0]).hypot(y - c[1]) > WATERLINE_RADII * r);
            let off_wall = i >= lo + WATERLINE_WALL_CELLS
                && i <= hi - WATERLINE_WALL_CELLS
                && j >= lo + WATERLINE_WALL_CELLS
                && j <= hi - WATERLINE_WALL_CELLS;
            if far && off_wall {
                let mut best = f64::NAN;
                for k in klo..khi {
                    let (p, q) = (phi[grid.idx(i, j, k)], phi[grid.idx(i, j, k + 1)]);
                    if (p > 0.0) != (q > 0.0) {
                        let z = grid.pos(i, j, k)[2] + h * p / (p - q);
                        if best.is_nan() || (z - geo.level).abs() < (best - geo.level).abs() {
                            best = z;
                        }
                    }
                }
                if best.is_finite() {
                    line_sum += best;
                    line_count += 1;
                }
            }
        }
    }
    Ok(Liquid {
        volume: volume * h * h,
        inside: inside * h * h,
        gas_under: gas_under * h * h,
        waterline: if line_count > 0 {
            line_sum / line_count as f64
        } else {
            f64::NAN
        },
    })
}

/// A sphere's state at one step: (t, centre, velocity).
type Sample = (f64, [f64; 3], [f64; 3]);

/// A sphere's states, step by step.
type Track = Vec<Sample>;

/// The (centre, velocity) of the light and the heavy sphere.
type Pair = ([f64; 3], [f64; 3]);

fn spheres(sim: &mut Simulation) -> anyhow::Result<(Pair, Pair)> {
    let states = crate::io::checkpoint::body_states(sim);
    let find = |name: &str| {
        states
            .iter()
            .find(|s| s.name == name)
            .map(|s| (s.rigid.center.to_array(), s.rigid.velocity.to_array()))
    };
    find("light")
        .zip(find("heavy"))
        .ok_or_else(|| anyhow::anyhow!("pool-drop.ron: no spheres named light and heavy"))
}

/// The drop at 64³ (quick) or 48³, 64³ and 96³ (full): both spheres enter the water; the
/// light one floats with its centre within one cell of the waterline (measured, and
/// Archimedes') and has settled there (over the last quarter its height varies by less than
/// an oscillation of one cell, h/√2 rms, and its vertical speed by less than such an
/// oscillation's at the heave frequency ω = (g/r)^(1/2), ω h/√2 rms); the heavy one ends on
/// the floor (its gap within the contact's range, 6 ε with ε = h); the liquid volume stays
/// within 1% of the pool's. A run whose velocity passes 10 times the free-fall speed over the
/// tank's height, or whose step fails, stops there as a failing row with the time reached.
///
/// The heave frequency: a half-immersed sphere's hydrostatic stiffness ρ g π r² over its mass
/// ρ/2 · 4π r³/3 plus an added mass of about half the displaced water's (ρ/2 · 2π r³/3, the
/// high-frequency value for a floating hemisphere) gives ω² ≈ g/r.
pub fn pool_drop(quick: bool) -> anyhow::Result<Report> {
    let mut rep = Report::new("pool-drop");
    let grids: &[usize] = if quick { &[64] } else { &[48, 64, 96] };
    for &cells in grids {
        drop_at(&mut rep, cells)?;
    }
    Ok(rep)
}

/// One run at `cells`³: its rows, notes and plot.
fn drop_at(rep: &mut Report, cells: usize) -> anyhow::Result<()> {
    let scene = bundled_scene("pool-drop.ron")?
        .edit(|s| s.domain.cells = Some(vec![cells, cells, cells]))?;
    let geo = geometry(&scene)?;
    let ratio = scene
        .free_surface
        .as_ref()
        .map_or(f64::NAN, |f| 1.0 / f.gas_density);
    let g = glam::DVec3::from_array(scene.gravity()).length();
    let end = scene.numerics.end_time;
    let label = format!("{cells}^3, 1:{ratio:.0}");
    let limit = 10.0 * (2.0 * g * (geo.hi - geo.lo)).sqrt();
    let mut sim = crate::validate::simulation(scene)?;
    sim.set_stop_at(Some(end));
    let h = sim.grid().h;
    let r = geo.radius;
    let area = (geo.hi - geo.lo).powi(2);
    let pool = area * (geo.level - geo.lo);
    let (mut light, mut heavy): (Track, Track) = (Vec::new(), Vec::new());
    let mut volumes: Vec<(f64, Liquid)> = Vec::new();
    let mut drift = 0.0f64;
    let mut failure = None;
    loop {
        let t = sim.time();
        let (l, hv) = spheres(&mut sim)?;
        light.push((t, l.0, l.1));
        heavy.push((t, hv.0, hv.1));
        volumes.push((t, liquid(&sim, &geo, &[l.0, hv.0])?));
        let ls = sim.world.resource::<LiquidLevelSet>();
        drift = drift.max((ls.volume / ls.target_volume - 1.0).abs());
        if t >= end * (1.0 - 1e-12) {
            break;
        }
        if let Err(e) = sim.step() {
            failure = Some(format!("{e:#}"));
            break;
        }
        let umax = sim.sample().max_u;
        if umax.is_nan() || umax >= limit {
            failure = Some(format!("max |u| passed {limit:.1}"));
            break;
        }
    }
    let reached = sim.time();
    let stopped = failure.as_ref().map(|e| {
        format!(
            "stopped at t = {reached:.3}: {}",
            e.lines().next().unwrap_or("")
        )
    });
    rep.rows.push(Row::yes_no(
        match &stopped {
            None => format!("{label}: the run reaches t = {end} without blowing up"),
            Some(s) => format!("{label}: the run reaches t = {end} without blowing up ({s})"),
        },
        failure.is_none(),
    ));
    // Entering: the light sphere's centre goes below the initial surface (arriving at
    // sqrt(2 g r) it overshoots its floating height), the heavy one goes wholly under.
    let lowest = |tr: &Track| tr.iter().map(|s| s.1[2]).fold(f64::INFINITY, f64::min);
    let (low_light, low_heavy) = (lowest(&light), lowest(&heavy));
    rep.rows.push(Row::yes_no(
        format!(
            "{label}: the light sphere enters the water (its centre goes below the surface z = {}: lowest {low_light:.4})",
            geo.level
        ),
        low_light < geo.level,
    ));
    rep.rows.push(Row::yes_no(
        format!(
            "{label}: the heavy sphere goes under (its centre more than a radius below the surface: lowest {low_heavy:.4})",
        ),
        low_heavy < geo.level - r,
    ));
    // Archimedes' waterline: the pool plus the water displaced by the heavy sphere and the
    // light one's immersed fraction (ρ_b - ρ_g)/(ρ_w - ρ_g).
    let gas = 1.0 / ratio;
    let volume = 4.0 / 3.0 * std::f64::consts::PI * r.powi(3);
    let displaced = volume * (1.0 + (geo.light - gas) / (1.0 - gas));
    let raised = geo.level + displaced / area;
    let window = format!("t = {:.1} to {end}", SETTLED_FROM * end);
    let from = SETTLED_FROM * end;
    let last = |tr: &Track| -> Track { tr.iter().filter(|s| s.0 >= from).copied().collect() };
    let (light_end, heavy_end) = (last(&light), last(&heavy));
    if let Some(s) = &stopped {
        for what in [
            "the light sphere's centre height above the waterline",
            "the light sphere's centre height against Archimedes' waterline",
            "the light sphere settles: the rms of its height",
            "the light sphere settles: its rms vertical speed",
            "the heavy sphere ends on the floor",
        ] {
            rep.rows.push(Row::yes_no(
                format!("{label}: {what} (not measured: {s})"),
                false,
            ));
        }
    } else {
        let mean =
            |v: &Track, f: &dyn Fn(&Sample) -> f64| v.iter().map(f).sum::<f64>() / v.len() as f64;
        let late: Vec<f64> = volumes
            .iter()
            .filter(|(t, _)| *t >= from)
            .map(|(_, l)| l.waterline)
            .collect();
        let water = late.iter().sum::<f64>() / late.len() as f64;
        let zl = mean(&light_end, &|s| s.1[2]);
        rep.rows.push(Row::abs(
            format!(
                "{label}: the light sphere's centre height above the waterline ({window}, both averaged), within one cell"
            ),
            0.0,
            zl - water,
            h,
        ));
        rep.rows.push(Row::abs(
            format!(
                "{label}: the light sphere's centre height against Archimedes' waterline (the pool raised by the displaced water over the tank's section; {window}, averaged), within one cell"
            ),
            raised,
            zl,
            h,
        ));
        let z_rms = mean(&light_end, &|s| (s.1[2] - zl).powi(2)).sqrt();
        rep.rows.push(Row::range(
            format!(
                "{label}: the light sphere settles: the rms of its height about its mean ({window}), in cells (an oscillation of one cell: 0.707)"
            ),
            0.0,
            std::f64::consts::FRAC_1_SQRT_2,
            z_rms / h,
        ));
        let omega = (g / r).sqrt();
        let w_rms = mean(&light_end, &|s| s.2[2] * s.2[2]).sqrt();
        rep.rows.push(Row::range(
            format!(
                "{label}: the light sphere settles: its rms vertical speed ({window}), in units of omega h with omega = (g/r)^(1/2) (a heave of one cell: 0.707)"
            ),
            0.0,
            std::f64::consts::FRAC_1_SQRT_2,
            w_rms / (omega * h),
        ));
        let zh = mean(&heavy_end, &|s| s.1[2]);
        rep.rows.push(Row::range(
            format!(
                "{label}: the heavy sphere ends on the floor: its gap ({window}, averaged) in cells (the contact's range: 6)"
            ),
            0.0,
            6.0,
            (zh - r - geo.lo) / h,
        ));
        let peak = light.iter().map(|s| s.2[2].abs()).fold(0.0, f64::max);
        let landed = heavy
            .iter()
            .find(|s| s.1[2] - r - geo.lo < h)
            .map_or("never within a cell of it".to_string(), |s| {
                format!("first within a cell of it at t = {:.2}", s.0)
            });
        let highest_after = heavy
            .iter()
            .skip_while(|s| s.1[2] - r - geo.lo >= h)
            .map(|s| s.1[2])
            .fold(f64::NEG_INFINITY, f64::max);
        rep.notes.push(format!(
            "{label}: waterline {water:.4} ({window}, mean over the columns farther than {WATERLINE_RADII} radii from the spheres; initial {}, Archimedes with the displaced volume {raised:.4}); light sphere centre {zl:.4}, largest vertical speed {peak:.3}, rms height {z_rms:.2e} and vertical speed {w_rms:.2e} over the window; heavy sphere centre {zh:.4} (on the floor at {:.4}; {landed}, highest after that {highest_after:.4})",
            geo.level,
            geo.lo + r
        ));
    }
    let (tw, worst) = volumes
        .iter()
        .map(|(t, l)| (*t, l.volume))
        .max_by(|a, b| (a.1 - pool).abs().total_cmp(&(b.1 - pool).abs()))
        .unwrap_or((0.0, f64::NAN));
    let beyond = volumes
        .iter()
        .find(|(_, l)| (l.volume / pool - 1.0).abs() > 0.01)
        .map_or(String::new(), |(t, _)| {
            format!(", first beyond 1% at t = {t:.2}")
        });
    let until = match &stopped {
        Some(_) => format!("; to t = {reached:.3}"),
        None => String::new(),
    };
    rep.rows.push(Row::rel(
        format!(
            "{label}: liquid volume (phi_w > 0 on the grid, outside the spheres) within 1% of the pool's at all times (worst at t = {tw:.2}{beyond}{until})"
        ),
        pool,
        worst,
        0.01,
    ));
    let at = |want: f64| {
        volumes
            .iter()
            .find(|(t, _)| *t >= want)
            .or(volumes.last())
            .map_or("-".to_string(), |(t, l)| {
                format!(
                    "{:.6} ({:+.3}%; phi_w > 0 inside the spheres {:.2e}, gas deeper than {GAS_DEPTH_RADII} radii under the surface and a cell from the spheres {:.2e}) at t = {t:.2}",
                    l.volume,
                    100.0 * (l.volume / pool - 1.0),
                    l.inside,
                    l.gas_under
                )
            })
    };
    rep.notes.push(format!(
        "{label}: liquid volume on the grid {}, {}, {}, {} (the pool {pool:.6}; the spheres' volume {volume:.3e} each); the level set's volume outside the walls and spheres drifts {drift:.1e} (restored every step); {} steps",
        at(0.0),
        at(2.0),
        at(5.0),
        at(end),
        light.len() - 1,
    ));
    rep.plots.push(
        crate::validate::PlotSpec::new(
            &format!("heights-{cells}"),
            format!("sphere centres, {label}"),
            "t",
            "centre height z",
        )
        .measured(
            format!("density {}", geo.light),
            light.iter().map(|s| (s.0, s.1[2])).collect(),
        )
        .measured(
            format!("density {}", geo.heavy),
            heavy.iter().map(|s| (s.0, s.1[2])).collect(),
        )
        .reference_level("Archimedes: the raised waterline", raised)
        .reference_level("on the floor", geo.lo + r),
    );
    Ok(())
}
