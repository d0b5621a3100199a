//! What `tumble check` prints: a scene in words a person reads before running it: the grid and
//! its memory, the time step policy, the bodies counted by kind and shape (never one line per
//! body), vacuum or not, what will be written and about how large, and the warnings.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use crate::base::params::TimeStep;
use crate::scene::{BodyKind, FieldName, OutputFormat, Precision, ValidScene};

/// Bytes per grid cell a 3D run holds (fields, particles, FFT scratch), measured by `tumble
/// bench` on `taylor-green-3d` at 128^3 (130 B per cell); 2D runs hold about half as many
/// arrays per cell.
const BYTES_PER_CELL_3D: f64 = 130.0;
const BYTES_PER_CELL_2D: f64 = 70.0;

/// A byte count as a person reads it.
pub fn human_bytes(b: f64) -> String {
    if b >= 1e9 {
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
pub fn time_step_words(dt: &TimeStep, has_bodies: bool) -> String {
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
            s
        }
    }
}

/// The summary `tumble check` prints, one line per topic.
pub fn describe(scene: &ValidScene) -> String {
    let g = scene.grid();
    let cells = g.len();
    let mut s = String::new();
    let dims: Vec<String> = g.n[..g.dim].iter().map(|n| n.to_string()).collect();
    let _ = writeln!(
        s,
        "scene `{}`: {}D, grid {} = {} cells, h = {}",
        scene.name,
        g.dim,
        dims.join("x"),
        grouped(cells),
        g.h
    );
    let _ = writeln!(
        s,
        "  box: origin {}, extent {} (periodic; walls are static bodies)",
        vector(&g.origin[..g.dim]),
        vector(&g.extent()[..g.dim])
    );
    let per_cell = if g.dim == 3 {
        BYTES_PER_CELL_3D
    } else {
        BYTES_PER_CELL_2D
    };
    let _ = writeln!(
        s,
        "  memory: about {} for the fields, particles and FFTs",
        human_bytes(per_cell * cells as f64)
    );
    let f = &scene.fluid;
    if scene.vacuum {
        let _ = writeln!(
            s,
            "  vacuum: no flow; gravity {} and contact act on the bodies directly",
            vector(&scene.gravity()[..g.dim])
        );
    } else {
        let _ = writeln!(
            s,
            "  fluid: density {}, kinematic viscosity {}, gravity {}",
            f.density,
            f.viscosity,
            vector(&scene.gravity()[..g.dim])
        );
    }
    let _ = writeln!(
        s,
        "  time step: {}; end time {}",
        time_step_words(&scene.numerics.dt, !scene.bodies.is_empty()),
        scene.numerics.end_time
    );
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
    // Bodies grouped by kind, shape and density.
    let mut groups: BTreeMap<(String, String, String), usize> = BTreeMap::new();
    for b in &scene.bodies {
        let kind = match &b.kind {
            BodyKind::Dynamic => "dynamic",
            BodyKind::Static => "static",
            BodyKind::Kinematic { .. } => "kinematic",
        };
        let density = match (&b.kind, b.density) {
            (BodyKind::Dynamic, Some(d)) => format!("density {d}"),
            (BodyKind::Dynamic, None) => format!("density {} (the fluid's)", f.density),
            _ => String::new(),
        };
        *groups
            .entry((kind.to_string(), b.shape.name().to_string(), density))
            .or_default() += 1;
    }
    if scene.bodies.is_empty() {
        let _ = writeln!(s, "  bodies: none");
    } else {
        let _ = writeln!(s, "  bodies: {}", scene.bodies.len());
        for ((kind, shape, density), n) in &groups {
            let sep = if density.is_empty() { "" } else { ", " };
            let _ = writeln!(s, "    {n} {kind} {shape}{sep}{density}");
        }
        let c = &scene.contact;
        let eps = c.eps.map_or(format!("h = {}", g.h), |e| e.to_string());
        let _ = writeln!(
            s,
            "  contact: kappa {}, range eps = {eps}, cut off at {} eps",
            c.kappa, c.range
        );
    }
    // Outputs.
    let o = &scene.output;
    let comps = |fname: &FieldName| -> usize {
        match fname {
            FieldName::Omega => g.omega_components(),
            FieldName::Velocity => 3,
            FieldName::Density => {
                if scene.bodies.is_empty() {
                    0
                } else {
                    3
                }
            }
        }
    };
    let values: usize = o.fields.iter().map(comps).sum::<usize>() * cells;
    let snapshots = match o.every {
        Some(e) if e > 0.0 => (scene.numerics.end_time / e).ceil() as usize + 1,
        _ => 2,
    };
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
            snapshots,
            o.every
                .map_or("first and last".to_string(), |e| format!("every {e}")),
            fields.join(", "),
            formats.join(" and "),
            human_bytes(bytes * values as f64)
        );
    }
    if !scene.bodies.is_empty() {
        let _ = writeln!(s, "  body surfaces: bodies.pvd, with every snapshot");
    }
    match o.checkpoint_every {
        Some(c) => {
            let _ = writeln!(
                s,
                "  checkpoints every {c}, the last {} kept",
                o.checkpoints_kept
            );
        }
        None => {
            let _ = writeln!(
                s,
                "  checkpoints: only if interrupted (Ctrl-C); --checkpoint-every T for more"
            );
        }
    }
    let warnings = scene.warnings();
    if warnings.is_empty() {
        let _ = writeln!(s, "  warnings: none");
    } else {
        for w in warnings {
            let _ = writeln!(s, "  warning: {w}");
        }
    }
    s
}
