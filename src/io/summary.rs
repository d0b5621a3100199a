//! What `tumble check` prints: a scene in words a person reads before running it: the grid, its
//! estimated memory and time per step, the time step policy, the bodies counted by kind and shape (never one line per
//! body), vacuum or not, what will be written and about how large, and the warnings.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use crate::base::params::TimeStep;
use crate::scene::{BodyKind, OutputFormat, Precision, ValidScene};

/// The most distinct densities listed one by one; beyond, their range is given.
const MAX_LISTED_DENSITIES: usize = 8;

/// A byte count as a person reads it.
pub fn human_bytes(b: f64) -> String {
    if b >= 1e12 {
        format!("{:.1} TB", b / 1e12)
    } else if b >= 1e9 {
        format!("{:.1} GB", b / 1e9)
    } else if b >= 1e6 {
        format!("{:.1} MB", b / 1e6)
    } else if b >= 1e3 {
        format!("{:.0} kB", b / 1e3)
    } else {
        format!("{b:.0} B")
    }
}

/// A whole number with thousands separators.
fn grouped(n: usize) -> String {
    let s = n.to_string();
    let mut out = String::new();
    for (i, c) in s.chars().enumerate() {
        if i > 0 && (s.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(c);
    }
    out
}

fn vector(v: &[f64]) -> String {
    let parts: Vec<String> = v.iter().map(|x| format!("{x}")).collect();
    format!("({})", parts.join(", "))
}

/// The time step policy in words.
pub fn time_step_words(dt: &TimeStep, has_bodies: bool, dynamic_bodies: bool) -> String {
    match dt {
        TimeStep::Fixed(dt) => format!("fixed, dt = {dt}"),
        TimeStep::Adaptive {
            c,
            dt_max,
            cfl,
            diffusion_number,
        } => {
            let mut s = format!("adaptive: dt = {c} / max|vorticity|");
            if let Some(m) = dt_max {
                let _ = write!(s, ", at most {m}");
            }
            let _ = write!(s, ", and max|u| dt / h at most {cfl}");
            if has_bodies {
                let _ = write!(s, ", and nu dt / h^2 at most {diffusion_number}");
            }
            if dynamic_bodies {
                let _ = write!(
                    s,
                    ", and a dynamic body starting a step at rest moves at most {} h under gravity, and max body speed dt / h at most {cfl}",
                    sig4(0.5 * c * c)
                );
            }
            s
        }
    }
}

/// `x` to 4 significant digits, without trailing zeros.
fn sig4(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return x.to_string();
    }
    let decimals = (3 - x.abs().log10().floor() as i32).max(0) as usize;
    let t = format!("{x:.decimals$}");
    if t.contains('.') {
        t.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        t
    }
}

/// The contact strength κ the scene's pairs use, in words (for `tumble check` and the run
/// log): the values over every pair a dynamic body is in, and where they come from (the
/// scene's `contact.kappa`, the bodies' and pairs' own values, the scaled default
/// C L² max(|g|, U²/ε)).
pub fn kappa_in_use(scene: &ValidScene) -> String {
    let cp = &scene.resolved().contact;
    let c = &scene.contact;
    let own = &scene.resolved().kappas;
    let dynamic = |i: usize| matches!(scene.bodies[i].kind, BodyKind::Dynamic);
    // Bodies alike for κ (kind, own value, length) give one value per pair of groups.
    let mut groups: BTreeMap<(bool, Option<u64>, u64), (usize, usize)> = BTreeMap::new();
    for (i, k) in own.iter().enumerate() {
        let key = (
            dynamic(i),
            k.map(f64::to_bits),
            cp.default.lengths[i].to_bits(),
        );
        groups.entry(key).or_insert((i, 0)).1 += 1;
    }
    let mut values: Vec<f64> = Vec::new();
    let mut default_lengths: Vec<f64> = Vec::new();
    for (ka, &(a, na)) in &groups {
        if !ka.0 {
            continue;
        }
        for (kb, &(b, _)) in &groups {
            if ka == kb && na < 2 {
                continue;
            }
            values.push(cp.unnamed_kappa(a, b, own[a], own[b]));
            if own[a].is_none() || own[b].is_none() {
                let l = cp.default.lengths[a].min(cp.default.lengths[b]);
                default_lengths.push(l);
            }
        }
    }
    values.extend(
        cp.pairs
            .iter()
            .filter(|p| dynamic(p.0) || dynamic(p.1))
            .map(|p| p.2),
    );
    let distinct = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v.dedup_by(|a, b| (*a - *b).abs() <= 1e-12 * b.abs());
        v
    };
    let values = distinct(values);
    let default_lengths = distinct(default_lengths);
    let mut out = match values.as_slice() {
        [] => match c.kappa {
            Some(k) => format!("{} (no dynamic body has a partner)", sig4(k)),
            None => "none (no dynamic body has a partner)".to_string(),
        },
        [k] => sig4(*k),
        v if v.len() <= 4 => format!(
            "{} by pair",
            v.iter().map(|&k| sig4(k)).collect::<Vec<_>>().join(", ")
        ),
        v => format!(
            "{} to {} by pair ({} values)",
            sig4(v[0]),
            sig4(v[v.len() - 1]),
            v.len()
        ),
    };
    if !default_lengths.is_empty() {
        let d = &cp.default;
        let ls = match default_lengths.as_slice() {
            [l] => sig4(*l),
            v => format!("{} to {}", sig4(v[0]), sig4(v[v.len() - 1])),
        };
        let _ = write!(
            out,
            " (the default {} L² max(|g|, U²/ε), |g| = {}, U = {}, ε = {}, L = {ls}: the \
             equivalent radius of the pair's smaller dynamic body)",
            d.factor,
            sig4(d.gravity),
            sig4(d.speed),
            sig4(d.eps)
        );
    }
    let per_body = scene.bodies.iter().filter(|b| b.kappa.is_some()).count();
    if per_body > 0 || !cp.pairs.is_empty() {
        let _ = write!(
            out,
            " ({per_body} bodies and {} pairs give their own)",
            cp.pairs.len()
        );
    }
    out
}

/// The summary `tumble check` prints, one line per topic.
pub fn describe(scene: &ValidScene) -> String {
    let mut s = String::new();
    grid_lines(&mut s, scene);
    medium_line(&mut s, scene);
    free_surface_line(&mut s, scene);
    time_step_line(&mut s, scene);
    run_length_line(&mut s, scene);
    dissipation_line(&mut s, scene);
    initial_vorticity_line(&mut s, scene);
    bodies_lines(&mut s, scene);
    output_lines(&mut s, scene);
    checkpoints_line(&mut s, scene);
    disk_line(&mut s, scene);
    plugins_line(&mut s, scene);
    warnings_lines(&mut s, scene);
    s
}

/// The plugin sections the scene carries (checked by their plugins before this is printed).
fn plugins_line(s: &mut String, scene: &ValidScene) {
    if scene.plugins.is_empty() {
        return;
    }
    let keys: Vec<&str> = scene.plugins.keys().map(String::as_str).collect();
    let _ = writeln!(s, "  plugin sections: {} (checked)", keys.join(", "));
}

/// The scene's name and grid, its box, and the estimated memory and time per step.
fn grid_lines(s: &mut String, scene: &ValidScene) {
    let g = scene.grid();
    let dims: Vec<String> = g.n[..g.dim].iter().map(|n| n.to_string()).collect();
    let _ = writeln!(
        s,
        "scene `{}`: {}D, grid {} = {} cells, h = {}",
        scene.name,
        g.dim,
        dims.join("x"),
        grouped(g.len()),
        g.h
    );
    let _ = writeln!(
        s,
        "  box: origin {}, extent {} (periodic; walls are static bodies)",
        vector(&g.origin[..g.dim]),
        vector(&g.extent()[..g.dim])
    );
    let _ = writeln!(
        s,
        "  {}",
        crate::io::estimate::words(&crate::io::estimate::estimate(scene))
    );
}

/// Vacuum, or the fluid's density and viscosity; and gravity.
fn medium_line(s: &mut String, scene: &ValidScene) {
    let dim = scene.grid().dim;
    let f = &scene.fluid;
    if scene.vacuum {
        let _ = writeln!(
            s,
            "  vacuum: no flow; gravity {} and contact act on the bodies directly",
            vector(&scene.gravity()[..dim])
        );
    } else {
        let _ = writeln!(
            s,
            "  fluid: density {}, kinematic viscosity {}, gravity {}",
            f.density,
            f.viscosity,
            vector(&scene.gravity()[..dim])
        );
    }
}

/// The free surface's liquid and gas and where the liquid starts, if the scene has one.
fn free_surface_line(s: &mut String, scene: &ValidScene) {
    let Some(fs) = &scene.free_surface else {
        return;
    };
    let f = &scene.fluid;
    let regions: Vec<String> = fs
        .liquid
        .iter()
        .map(|r| match r {
            crate::scene::format::LiquidRegion::Below { height, .. } => {
                format!("a pool below {}", sig4(*height))
            }
            crate::scene::format::LiquidRegion::Above { height, .. } => {
                format!("a layer above {}", sig4(*height))
            }
            crate::scene::format::LiquidRegion::Shape { .. } => "a shape".to_string(),
        })
        .collect();
    let _ = writeln!(
        s,
        "  free surface: liquid of density {} (the fluid's), gas of density {} (ratio 1:{}), liquid at t = 0: {}; an adaptive time step is also at most c (h/|g|)^(1/2)",
        f.density,
        fs.gas_density,
        sig4(f.density / fs.gas_density),
        regions.join(", ")
    );
}

/// The time step policy and the end time.
fn time_step_line(s: &mut String, scene: &ValidScene) {
    let _ = writeln!(
        s,
        "  time step: {}; end time {}",
        time_step_words(
            &scene.numerics.dt,
            !scene.bodies.is_empty(),
            scene
                .bodies
                .iter()
                .any(|b| matches!(b.kind, crate::scene::BodyKind::Dynamic)),
        ),
        number(scene.numerics.end_time)
    );
}

/// A number as written in a scene, in scientific notation when very large or small (an end
/// time of 1e300 is not printed with its 301 digits).
pub fn number(x: f64) -> String {
    if x != 0.0 && x.is_finite() && !(1e-4..1e6).contains(&x.abs()) {
        format!("{x:e}")
    } else {
        format!("{x}")
    }
}

/// The steps and wall time of the whole run, from the largest step the scene can take.
fn run_length_line(s: &mut String, scene: &ValidScene) {
    use crate::io::estimate::{human_seconds, run_length};
    let r = run_length(scene);
    match (r.bound, r.steps, r.wall) {
        (Some(b), Some(n), Some(w)) => {
            let (exactly, at_least) = if b.exact {
                ("", "about ")
            } else {
                ("at least ", "at least ")
            };
            let _ = writeln!(
                s,
                "  run: {exactly}{} steps (dt at most {}: {}), {at_least}{} of wall time on 2 \
                 threads (estimated)",
                grouped_f(n),
                sig4(b.dt),
                b.why,
                human_seconds(w)
            );
        }
        _ => {
            let _ = writeln!(
                s,
                "  run: the number of steps is not known before the run (an adaptive step that \
                 only the flow bounds; numerics.dt's dt_max bounds it); each step about {}",
                human_seconds(crate::io::estimate::estimate(scene).seconds_per_step)
            );
        }
    }
}

/// A count, with thousands separators below 10^12, else in scientific notation.
fn grouped_f(n: f64) -> String {
    if n < 1e12 {
        grouped(n as usize)
    } else {
        format!("{n:.3e}")
    }
}

/// The grid-scale dissipation of a 3D flow.
fn dissipation_line(s: &mut String, scene: &ValidScene) {
    if scene.dim() == 3 && !scene.vacuum {
        use crate::systems::diffusion::{ORDER, SMAGORINSKY};
        let _ = writeln!(
            s,
            "  grid-scale dissipation (3D): the top of the spectrum damped at the rate C_s^2 pi^2 max|vorticity| (|k|/k_N)^{}, C_s = {SMAGORINSKY} (systems/diffusion.rs)",
            2 * ORDER
        );
    }
}

/// The initial vorticity counted by kind (none in a vacuum).
fn initial_vorticity_line(s: &mut String, scene: &ValidScene) {
    if !scene.initial.is_empty() {
        let mut kinds: BTreeMap<String, usize> = BTreeMap::new();
        for i in &scene.initial {
            let name = format!("{i:?}");
            let name = name.split([' ', '{', '(']).next().unwrap_or("").to_string();
            *kinds.entry(name).or_default() += 1;
        }
        let list: Vec<String> = kinds.iter().map(|(k, n)| format!("{n} {k}")).collect();
        let _ = writeln!(s, "  initial vorticity: {}", list.join(", "));
    } else if !scene.vacuum {
        let _ = writeln!(s, "  initial vorticity: none (fluid at rest)");
    }
}

/// The density of body `i` if it is dynamic (the resolved one: its own or the fluid's).
fn dynamic_density(scene: &ValidScene, i: usize) -> Option<f64> {
    match scene.bodies[i].kind {
        BodyKind::Dynamic => Some(scene.resolved().densities[i]),
        _ => None,
    }
}

/// The dynamic bodies counted by density (keyed by the density's bits).
fn density_counts(scene: &ValidScene) -> BTreeMap<u64, usize> {
    let mut densities: BTreeMap<u64, usize> = BTreeMap::new();
    for d in (0..scene.bodies.len()).filter_map(|i| dynamic_density(scene, i)) {
        *densities.entry(d.to_bits()).or_default() += 1;
    }
    densities
}

/// Bodies alike by kind, shape and density: (kind, shape, density label) to (count, least
/// and greatest density). The label is empty when `many` densities are not listed.
type BodyGroups<'a> = BTreeMap<(&'static str, &'a str, String), (usize, f64, f64)>;

/// The bodies grouped by kind, shape and density (the density in the label only when not
/// `many`).
fn body_groups(scene: &ValidScene, many: bool) -> BodyGroups<'_> {
    let mut groups: BodyGroups = BTreeMap::new();
    for (i, b) in scene.bodies.iter().enumerate() {
        let kind = match &b.kind {
            BodyKind::Dynamic => "dynamic",
            BodyKind::Static => "static",
            BodyKind::Kinematic { .. } => "kinematic",
        };
        let d = dynamic_density(scene, i);
        let label = match (d, b.density) {
            (Some(d), Some(_)) if !many => format!("density {d}"),
            (Some(d), None) if !many => format!("density {d} (the fluid's)"),
            _ => String::new(),
        };
        let g = groups.entry((kind, b.shape.name(), label)).or_insert((
            0,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ));
        g.0 += 1;
        if let Some(d) = d {
            g.1 = g.1.min(d);
            g.2 = g.2.max(d);
        }
    }
    groups
}

/// Bodies counted by shape and by density, then grouped by kind, shape and density (a
/// density range when there are too many values to list); then the contact.
fn bodies_lines(s: &mut String, scene: &ValidScene) {
    if scene.bodies.is_empty() {
        let _ = writeln!(s, "  bodies: none");
        return;
    }
    let densities = density_counts(scene);
    let many = densities.len() > MAX_LISTED_DENSITIES;
    let _ = writeln!(s, "{}", bodies_count_line(scene, &densities, many));
    for ((kind, shape, label), (n, lo, hi)) in &body_groups(scene, many) {
        let density = if !label.is_empty() || !lo.is_finite() {
            label.clone()
        } else if lo == hi {
            format!("density {}", sig4(*lo))
        } else {
            format!("densities {} to {}", sig4(*lo), sig4(*hi))
        };
        let sep = if density.is_empty() { "" } else { ", " };
        let _ = writeln!(s, "    {n} {kind} {shape}{sep}{density}");
    }
    contact_line(s, scene);
}

/// The bodies counted by shape (most first), and by density (a range when `many`).
fn bodies_count_line(scene: &ValidScene, densities: &BTreeMap<u64, usize>, many: bool) -> String {
    let mut shapes: BTreeMap<&str, usize> = BTreeMap::new();
    for b in &scene.bodies {
        *shapes.entry(b.shape.name()).or_default() += 1;
    }
    let mut shapes: Vec<(&str, usize)> = shapes.into_iter().collect();
    shapes.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(b.0)));
    let shapes: Vec<String> = shapes.iter().map(|(k, n)| format!("{k} {n}")).collect();
    let mut line = format!("  bodies: {} ({})", scene.bodies.len(), shapes.join(", "));
    if many {
        let lo = densities
            .keys()
            .map(|&d| f64::from_bits(d))
            .fold(f64::INFINITY, f64::min);
        let hi = densities
            .keys()
            .map(|&d| f64::from_bits(d))
            .fold(f64::NEG_INFINITY, f64::max);
        let _ = write!(
            line,
            "; densities: {} values from {} to {}",
            densities.len(),
            sig4(lo),
            sig4(hi)
        );
    } else if !densities.is_empty() {
        let list: Vec<String> = densities
            .iter()
            .map(|(&d, n)| format!("{} x {n}", f64::from_bits(d)))
            .collect();
        let _ = write!(line, "; densities: {}", list.join(", "));
    }
    line
}

/// The contact strength in use and the contact range.
fn contact_line(s: &mut String, scene: &ValidScene) {
    let c = &scene.contact;
    let eps = scene.resolved().contact.eps;
    let eps = match c.eps {
        Some(_) => eps.to_string(),
        None => format!("h = {eps}"),
    };
    let _ = writeln!(
        s,
        "  contact: kappa {}, range eps = {eps}, cut off at {} eps",
        kappa_in_use(scene),
        c.range
    );
}

/// The field snapshots (how many, of what, in which formats, about how large) and the body
/// surfaces.
fn output_lines(s: &mut String, scene: &ValidScene) {
    let o = &scene.output;
    let values = crate::io::estimate::snapshot_values(scene);
    let snapshots = crate::io::estimate::snapshot_count(scene);
    let fields: Vec<String> = o.fields.iter().map(|f| format!("{f:?}")).collect();
    let formats: Vec<&str> = o
        .formats
        .iter()
        .map(|f| match f {
            OutputFormat::Vtk => "VTK (fields.pvd)",
            OutputFormat::Hdf5 => "HDF5 + XDMF (fields.xmf)",
        })
        .collect();
    let (bytes, precision) = match o.precision {
        Precision::Single => (4.0, "single"),
        Precision::Double => (8.0, "double"),
    };
    if fields.is_empty() {
        let _ = writeln!(s, "  output: no field snapshots");
    } else {
        let _ = writeln!(
            s,
            "  output: {} snapshots ({}) of {} in {}, {precision} precision, at most {} each \
             before compression",
            grouped_f(snapshots),
            o.every.map_or("first and last".to_string(), |e| format!(
                "every {}",
                number(e)
            )),
            fields.join(", "),
            formats.join(" and "),
            human_bytes(bytes * values)
        );
    }
    if !scene.bodies.is_empty() {
        let _ = writeln!(s, "  body surfaces: bodies.pvd, with every snapshot");
    }
}

/// When checkpoints are written and how many are kept.
fn checkpoints_line(s: &mut String, scene: &ValidScene) {
    use crate::io::estimate::human_seconds;
    let o = &scene.output;
    let mut when = Vec::new();
    if let Some(w) = o.checkpoint_wall {
        when.push(format!(
            "every {} of wall time (output.checkpoint_wall: {} s)",
            human_seconds(w),
            number(w)
        ));
    }
    if let Some(c) = o.checkpoint_every {
        when.push(format!("every {} of simulated time", number(c)));
    }
    if when.is_empty() {
        let _ = writeln!(
            s,
            "  checkpoints: only if interrupted (Ctrl-C, SIGTERM): output.checkpoint_wall is \
             off, a killed run loses everything; --checkpoint-wall S or --checkpoint-every T \
             for more"
        );
    } else {
        let _ = writeln!(
            s,
            "  checkpoints: {}, and if interrupted (Ctrl-C, SIGTERM); the last {} kept; tumble \
             run --restart DIR continues from the newest",
            when.join(" and "),
            o.checkpoints_kept
        );
    }
}

/// The disk the outputs take, and what is free where the run would write.
fn disk_line(s: &mut String, scene: &ValidScene) {
    let out = crate::io::estimate::outputs(scene);
    // The run directory without --out: the scene's output.dir, else runs/<name>.
    let dir = match &scene.output.dir {
        Some(d) => std::path::PathBuf::from(d),
        None => std::path::Path::new("runs").join(&scene.name),
    };
    let free =
        crate::io::disk::free_bytes(&dir).map(|f| (f, crate::io::disk::existing_ancestor(&dir)));
    let free = match free {
        Some((f, at)) => format!(
            "; {} free on the disk of {}",
            human_bytes(f as f64),
            at.display()
        ),
        None => String::new(),
    };
    let _ = writeln!(
        s,
        "  disk: about {} ({}){free}",
        human_bytes(out.total()),
        out.words()
    );
}

/// The scene's warnings, one a line, or none.
fn warnings_lines(s: &mut String, scene: &ValidScene) {
    let warnings = scene.warnings();
    if warnings.is_empty() {
        let _ = writeln!(s, "  warnings: none");
    } else {
        for w in warnings {
            let _ = writeln!(s, "  warning: {w}");
        }
    }
}
