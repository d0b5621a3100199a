//! The checks of a scene, one per type: each returns the first problem as an `Issue` with
//! the field's path relative to the checked value, and the caller puts it under its own key.
//! `check_scene` runs them all, then builds the bodies' shapes (reading mesh files), looks for
//! bodies overlapping at the start and resolves the defaults ([`super::resolved`]); it is the
//! only way to a [`ValidScene`](crate::scene::ValidScene).

use super::error::{Check, Issue, Seg, fail};
use super::format::{
    BodySpec, Contact, Domain, Fluid, InitialVorticity, Numerics, Output, OutputFormat, Scene,
};
use super::generate::Span;
use super::resolved::Resolved;
use crate::base::grid::Grid;
use crate::base::params::{BodyCoupling, InterfaceAcceleration, TimeStep};
use crate::bodies::BodyKind;
use crate::bodies::shapes::{Shape, ShapeGeometry};

/// The most grid nodes a scene may ask for (2^32; about 35 GB per scalar field).
pub const MAX_NODES: u64 = 1 << 32;

/// The outcome of the checks: the scene's grid, its bodies' shapes and its resolved defaults.
pub(crate) type Checked = (Grid, Vec<ShapeGeometry>, Resolved);

/// Check every value of `scene` (filling in defaults: body names, normalised axes), build its
/// shapes, check for initial overlaps and resolve its defaults.
pub(crate) fn check_scene(scene: &mut Scene) -> Check<Checked> {
    check_name(&scene.name).map_err(|i| i.under(Seg::Key("name")))?;
    let grid = scene
        .domain
        .check()
        .map_err(|i| i.under(Seg::Key("domain")))?;
    let dim = grid.dim;
    scene
        .fluid
        .check(dim)
        .map_err(|i| i.under(Seg::Key("fluid")))?;
    scene
        .numerics
        .check()
        .map_err(|i| i.under(Seg::Key("numerics")))?;
    for (i, init) in scene.initial.iter_mut().enumerate() {
        init.check(dim)
            .map_err(|e| e.under(Seg::Index(i)).under(Seg::Key("initial")))?;
    }
    let lo = scene.domain.origin.clone().unwrap_or(vec![0.0; dim]);
    let hi: Vec<f64> = lo
        .iter()
        .zip(&scene.domain.extent)
        .map(|(o, e)| o + e)
        .collect();
    for (i, b) in scene.bodies.iter_mut().enumerate() {
        if b.name.is_empty() {
            b.name = format!("body{i}");
        }
        b.check(dim, &lo, &hi)
            .map_err(|e| e.under(Seg::Index(i)).under(Seg::Key("bodies")))?;
    }
    // Generators become bodies after the listed ones; a problem with one of theirs is
    // located at the generator.
    let listed = scene.bodies.len();
    let generators = std::mem::take(&mut scene.generators);
    let spans = super::generate::expand(
        &generators,
        &mut scene.bodies,
        dim,
        &lo,
        &hi,
        &scene.base_dir,
    )?;
    check_bodies_and_rest(scene, &grid, listed, &lo, &hi).map_err(|i| in_generator(i, &spans))
}

/// A problem with a generated body, located at its generator (`generators[g]`).
fn in_generator(mut issue: Issue, spans: &[Span]) -> Issue {
    if let [Seg::Key("bodies"), Seg::Index(b), ..] = issue.path[..]
        && let Some(s) = spans.iter().find(|s| (s.start..s.end).contains(&b))
    {
        issue.path = vec![Seg::Key("generators"), Seg::Index(s.generator)];
        issue.message = format!(
            "{} (a body made by generators[{}])",
            issue.message, s.generator
        );
    }
    issue
}

/// The checks after the generators' expansion: the generated bodies (from index `listed`
/// on), then everything that looks at all bodies.
fn check_bodies_and_rest(
    scene: &mut Scene,
    grid: &Grid,
    listed: usize,
    lo: &[f64],
    hi: &[f64],
) -> Check<Checked> {
    let dim = grid.dim;
    for (i, b) in scene.bodies.iter().enumerate().skip(listed) {
        b.check(dim, lo, hi)
            .map_err(|e| e.under(Seg::Index(i)).under(Seg::Key("bodies")))?;
    }
    if let Some(fs) = &scene.free_surface {
        fs.check(dim, scene.fluid.density, lo, hi)
            .map_err(|i| i.under(Seg::Key("free_surface")))?;
    }
    check_vacuum(scene).map_err(|i| i.under(Seg::Key("vacuum")))?;
    check_unique_names(&scene.bodies)?;
    scene
        .contact
        .check(&scene.bodies)
        .map_err(|i| i.under(Seg::Key("contact")))?;
    scene
        .output
        .check()
        .map_err(|i| i.under(Seg::Key("output")))?;
    let geoms = check_geometry(scene, grid)?;
    super::liquid::check_tank(scene, grid, &geoms)
        .map_err(|i| i.under(Seg::Key("free_surface")))?;
    let resolved = super::resolved::resolve(scene, grid, &geoms);
    check_kappa_scale(scene, &resolved).map_err(|i| i.under(Seg::Key("contact")))?;
    check_step_count(scene, grid, &resolved).map_err(|i| i.under(Seg::Key("numerics")))?;
    Ok((grid.clone(), geoms, resolved))
}

/// Bodies are named in `bodies.csv`, `bodies.pvd`, the plots and `contact.pairs`: every name
/// once. A repeated name is reported at the later body's `name`.
fn check_unique_names(bodies: &[BodySpec]) -> Check {
    let mut seen: std::collections::HashMap<&str, usize> = std::collections::HashMap::new();
    for (i, b) in bodies.iter().enumerate() {
        if let Some(&j) = seen.get(b.name.as_str()) {
            return Err(Issue::new(
                &["name"],
                format!(
                    "`{}` is already the name of bodies[{j}]: bodies.csv, bodies.pvd, the plots \
                     and contact.pairs name bodies by name, so every body needs its own",
                    b.name
                ),
            )
            .under(Seg::Index(i))
            .under(Seg::Key("bodies")));
        }
        seen.insert(&b.name, i);
    }
    Ok(())
}

/// An end time the clock cannot count to: more than [`super::steps::MAX_STEPS`] steps even at
/// the largest step the scene can take.
fn check_step_count(scene: &Scene, grid: &Grid, resolved: &Resolved) -> Check {
    let Some(b) = super::steps::step_bound(scene, grid, resolved) else {
        return Ok(());
    };
    let end = scene.numerics.end_time;
    let steps = b.steps(end);
    if steps.is_finite() && steps <= super::steps::MAX_STEPS {
        return Ok(());
    }
    let count = if b.exact {
        format!("{steps:.3e}")
    } else {
        format!("at least {steps:.3e}")
    };
    fail(
        &["end_time"],
        format!(
            "end_time = {end:e} takes {count} steps of at most dt = {:e} ({}), more than the \
             2^53 = {:.3e} a run can count (a step that small no longer moves a clock near the \
             end time); shorten the end time or lengthen the step",
            b.dt,
            b.why,
            super::steps::MAX_STEPS
        ),
    )
}

/// A scene's name names its run directory `runs/<name>`: one plain path component.
fn check_name(name: &str) -> Check {
    if name.is_empty() {
        return fail(
            &[],
            "must not be empty: give the scene a `name: \"...\"` (it names the run directory)",
        );
    }
    if name == "." || name == ".." {
        return fail(
            &[],
            format!("`{name}` is not a plain name (it names a directory)"),
        );
    }
    if let Some(c) = name.chars().find(|c| matches!(c, '/' | '\\' | '\0')) {
        return fail(
            &[],
            format!(
                "`{name}` is not a plain name: it contains {c:?} (the name becomes the run \
                 directory runs/<name>, so it may not hold a path)"
            ),
        );
    }
    Ok(())
}

impl Domain {
    /// Check the box and its grid; on success, the grid.
    pub(crate) fn check(&self) -> Check<Grid> {
        let dim = self.extent.len();
        if dim != 2 && dim != 3 {
            return fail(
                &["extent"],
                format!("needs 2 entries (2D) or 3 (3D), got {dim}"),
            );
        }
        for &e in &self.extent {
            if !(e.is_finite() && e > 0.0) {
                return fail(
                    &["extent"],
                    format!("every extent must be positive, got {e}"),
                );
            }
        }
        if let Some(o) = &self.origin {
            if o.len() != dim {
                return fail(
                    &["origin"],
                    format!("needs {dim} entries like extent, got {}", o.len()),
                );
            }
            if o.iter().any(|x| !x.is_finite()) {
                return fail(&["origin"], "must be finite");
            }
        }
        let (cells, h): (Vec<usize>, f64) = match (&self.cells, self.h) {
            (Some(_), Some(_)) => return fail(&["h"], "give either `cells` or `h`, not both"),
            (None, None) => {
                return fail(
                    &["extent"],
                    "the domain needs `cells: [..]` or `h: ..` to define its grid",
                );
            }
            (Some(c), None) => {
                if c.len() != dim {
                    return fail(
                        &["cells"],
                        format!("needs {dim} entries like extent, got {}", c.len()),
                    );
                }
                if let Some(&z) = c.iter().find(|&&n| n < 4) {
                    return fail(
                        &["cells"],
                        format!("every axis needs at least 4 cells, got {z}"),
                    );
                }
                let h = self.extent[0] / c[0] as f64;
                for a in 1..dim {
                    let ha = self.extent[a] / c[a] as f64;
                    if ((ha - h) / h).abs() > 1e-9 {
                        return fail(
                            &["cells"],
                            format!(
                                "cells must give the same spacing on every axis: axis 0 has h = {h}, axis {a} has h = {ha}"
                            ),
                        );
                    }
                }
                (c.clone(), h)
            }
            (None, Some(h)) => {
                if !(h.is_finite() && h > 0.0) {
                    return fail(&["h"], format!("must be positive, got {h}"));
                }
                for (a, &e) in self.extent.iter().enumerate() {
                    let m = e / h;
                    if (m - m.round()).abs() > 1e-6 * m.max(1.0) || m.round() < 4.0 {
                        return fail(
                            &["h"],
                            format!(
                                "extent[{a}] = {e} is not a whole multiple (at least 4) of h = {h} ({m} cells)"
                            ),
                        );
                    }
                }
                (
                    self.extent
                        .iter()
                        .map(|e| (e / h).round() as usize)
                        .collect(),
                    h,
                )
            }
        };
        // Node counts in f64 (no overflow), bounded so every index and byte count fits.
        let nodes: Vec<f64> = cells.iter().map(|&n| n as f64).collect();
        if nodes.iter().product::<f64>() > MAX_NODES as f64 {
            let field = if self.cells.is_some() { "cells" } else { "h" };
            return fail(&[field], too_many(&nodes));
        }
        let mut n = [1usize; 3];
        let mut origin = [0.0; 3];
        for a in 0..dim {
            n[a] = cells[a];
            origin[a] = self.origin.as_ref().map_or(0.0, |o| o[a]);
        }
        Ok(Grid::new(n, h, origin))
    }
}

fn too_many(nodes: &[f64]) -> String {
    let total: f64 = nodes.iter().product();
    format!(
        "the grid would have {total:.3e} nodes ({}), more than the {MAX_NODES} (2^32) this \
         version can address; use fewer cells",
        nodes
            .iter()
            .map(|n| format!("{n}"))
            .collect::<Vec<_>>()
            .join(" x ")
    )
}

impl Fluid {
    pub(crate) fn check(&self, dim: usize) -> Check {
        if !(self.density.is_finite() && self.density > 0.0) {
            return fail(
                &["density"],
                format!("must be positive, got {}", self.density),
            );
        }
        if !(self.viscosity.is_finite() && self.viscosity >= 0.0) {
            return fail(
                &["viscosity"],
                format!("must be zero or positive, got {}", self.viscosity),
            );
        }
        for (key, v) in [
            ("gravity", &self.gravity),
            ("background_velocity", &self.background_velocity),
        ] {
            if !v.is_empty() && v.len() != dim {
                return fail(&[key], format!("needs {dim} entries, got {}", v.len()));
            }
            if v.iter().any(|x| !x.is_finite()) {
                return fail(&[key], "must be finite");
            }
        }
        Ok(())
    }
}

impl Numerics {
    pub(crate) fn check(&self) -> Check {
        match &self.dt {
            TimeStep::Fixed(dt) => {
                if !(dt.is_finite() && *dt > 0.0) {
                    return fail(&["dt"], format!("must be positive, got {dt}"));
                }
            }
            TimeStep::Adaptive {
                c,
                dt_max,
                cfl,
                diffusion_number,
            } => {
                let bad = |k, m: String| fail(&["dt", k], m);
                if !(diffusion_number.is_finite() && *diffusion_number > 0.0) {
                    return bad(
                        "diffusion_number",
                        format!("must be positive, got {diffusion_number}"),
                    );
                }
                if !(c.is_finite() && *c > 0.0) {
                    return bad("c", format!("must be positive, got {c}"));
                }
                if let Some(m) = dt_max
                    && !(m.is_finite() && *m > 0.0)
                {
                    return bad("dt_max", format!("must be positive, got {m}"));
                }
                if !(cfl.is_finite() && *cfl > 0.0) {
                    return bad("cfl", format!("must be positive, got {cfl}"));
                }
            }
        }
        if !(self.end_time.is_finite() && self.end_time > 0.0) {
            return fail(
                &["end_time"],
                format!("must be positive, got {}", self.end_time),
            );
        }
        if !(self.remesh_cutoff.is_finite() && (0.0..1.0).contains(&self.remesh_cutoff)) {
            return fail(
                &["remesh_cutoff"],
                format!("must be in [0, 1), got {}", self.remesh_cutoff),
            );
        }
        if !(self.blowup_factor.is_finite() && self.blowup_factor > 1.0) {
            return fail(
                &["blowup_factor"],
                format!("must be greater than 1, got {}", self.blowup_factor),
            );
        }
        if !(self.lambda.is_finite() && self.lambda > 0.0) {
            return fail(
                &["lambda"],
                format!("must be positive, got {}", self.lambda),
            );
        }
        if !(self.interface_cells.is_finite() && self.interface_cells > 0.0) {
            return fail(
                &["interface_cells"],
                format!("must be positive, got {}", self.interface_cells),
            );
        }
        let off = self.penalization_offset;
        if !(off.is_finite() && (0.0..=2.0 * self.interface_cells).contains(&off)) {
            return fail(
                &["penalization_offset"],
                format!(
                    "must be between 0 and twice interface_cells ({}), got {off}",
                    2.0 * self.interface_cells
                ),
            );
        }
        Ok(())
    }
}

fn positive(key: &'static str, x: f64) -> Check {
    if x.is_finite() && x > 0.0 {
        Ok(())
    } else {
        fail(&[key], format!("must be positive, got {x}"))
    }
}

fn finite(key: &'static str, x: f64) -> Check {
    if x.is_finite() {
        Ok(())
    } else {
        fail(&[key], "must be finite")
    }
}

impl InitialVorticity {
    /// Check the field for a `dim`-dimensional scene; normalises a vortex ring's axis.
    pub(crate) fn check(&mut self, dim: usize) -> Check {
        match self {
            InitialVorticity::LambOseen {
                center,
                core_radius,
                circulation,
            } => {
                if dim != 2 {
                    return fail(&["LambOseen"], "LambOseen is a 2D field; this scene is 3D");
                }
                if center.len() != 2 {
                    return fail(&["center"], "needs 2 entries");
                }
                positive("core_radius", *core_radius)?;
                finite("circulation", *circulation)
            }
            InitialVorticity::TaylorGreen2d {
                amplitude,
                wavenumber,
            } => {
                if dim != 2 {
                    return fail(
                        &["TaylorGreen2d"],
                        "TaylorGreen2d is a 2D field; use TaylorGreen3d in 3D",
                    );
                }
                finite("amplitude", *amplitude)?;
                positive("wavenumber", *wavenumber)
            }
            InitialVorticity::TaylorGreen3d {
                amplitude,
                wavenumber,
            } => {
                if dim != 3 {
                    return fail(
                        &["TaylorGreen3d"],
                        "TaylorGreen3d is a 3D field; use TaylorGreen2d in 2D",
                    );
                }
                finite("amplitude", *amplitude)?;
                positive("wavenumber", *wavenumber)
            }
            InitialVorticity::VortexRing {
                center,
                axis,
                radius,
                core_radius,
                circulation,
            } => {
                if dim != 3 {
                    return fail(
                        &["VortexRing"],
                        "VortexRing is a 3D field; this scene is 2D",
                    );
                }
                if center.len() != 3 {
                    return fail(&["center"], "needs 3 entries");
                }
                let norm = axis.iter().map(|a| a * a).sum::<f64>().sqrt();
                if axis.len() != 3 || !(norm.is_finite() && norm > 0.0) {
                    return fail(&["axis"], "needs 3 entries, not all zero");
                }
                for a in axis.iter_mut() {
                    *a /= norm;
                }
                positive("radius", *radius)?;
                positive("core_radius", *core_radius)?;
                finite("circulation", *circulation)
            }
        }
    }
}

impl BodySpec {
    /// Check the body (its name already given) in the box `[lo, hi]` of a `dim`-dimensional
    /// scene; messages name the body.
    pub(crate) fn check(&self, dim: usize, lo: &[f64], hi: &[f64]) -> Check {
        let rot_len = if dim == 2 { 1 } else { 3 };
        let name = &self.name;
        let at = |path: &[&'static str], m: String| fail(path, format!("body `{name}`: {m}"));
        let berr = |field: &'static str, m: String| at(&[field], m);
        if let Err(m) = self.shape.validate(dim) {
            return berr("shape", m);
        }
        if self.position.len() != dim || self.position.iter().any(|x| !x.is_finite()) {
            return berr("position", format!("needs {dim} finite entries"));
        }
        let bounded = !matches!(self.shape, Shape::HalfSpace { .. } | Shape::Complement(_));
        if bounded && (0..dim).any(|a| self.position[a] < lo[a] || self.position[a] > hi[a]) {
            return berr(
                "position",
                format!(
                    "the centre {:?} is outside the domain [{lo:?}, {hi:?}]",
                    self.position
                ),
            );
        }
        if let Some(d) = self.density
            && !(d.is_finite() && d > 0.0)
        {
            return berr("density", format!("must be positive, got {d}"));
        }
        if !self.rotation.is_empty() && self.rotation.len() != rot_len {
            return berr(
                "rotation",
                format!(
                    "needs {rot_len} entries (a rotation vector), got {}",
                    self.rotation.len()
                ),
            );
        }
        if !self.velocity.is_empty() && self.velocity.len() != dim {
            return berr("velocity", format!("needs {dim} entries"));
        }
        if !self.angular_velocity.is_empty() && self.angular_velocity.len() != rot_len {
            return berr("angular_velocity", format!("needs {rot_len} entries"));
        }
        if let Some(k) = self.kappa
            && !(k.is_finite() && k >= 0.0)
        {
            return berr("kappa", format!("must be zero or positive, got {k}"));
        }
        if let BodyKind::Kinematic {
            velocity,
            angular_velocity,
            amplitude,
            frequency,
        } = &self.kind
        {
            let kerr = |field: &'static str, m: String| at(&["kind", "Kinematic", field], m);
            if velocity.len() != dim {
                return kerr("velocity", format!("needs {dim} entries"));
            }
            if !angular_velocity.is_empty() && angular_velocity.len() != rot_len {
                return kerr("angular_velocity", format!("needs {rot_len} entries"));
            }
            if !amplitude.is_empty() && amplitude.len() != dim {
                return kerr("amplitude", format!("needs {dim} entries"));
            }
            if !(frequency.is_finite() && *frequency >= 0.0) {
                return kerr("frequency", "must be zero or positive".into());
            }
        }
        Ok(())
    }
}

/// A scene that leaves κ to its default needs a scale for it: gravity, or bodies that move
/// (see [`super::kappa`]).
fn check_kappa_scale(scene: &Scene, resolved: &Resolved) -> Check {
    if scene.contact.kappa.is_some() {
        return Ok(());
    }
    let Some((a, b)) = scene.contact.pair_without_kappa(&scene.bodies) else {
        return Ok(());
    };
    if resolved.contact.default.acceleration() > 0.0 {
        return Ok(());
    }
    fail(
        &["kappa"],
        format!(
            "must be given when gravity is zero, nothing in the scene has a speed and bodies \
             can touch (`{a}` and `{b}` here): the default, C L² max(|g|, U²/ε), scales with \
             gravity and with the speeds U of the bodies and the flow; give \
             `contact: (kappa: ...)` in length³/time² (or per body or per pair)"
        ),
    )
}

fn check_vacuum(scene: &Scene) -> Check {
    if scene.vacuum
        && !scene
            .bodies
            .iter()
            .any(|b| matches!(b.kind, BodyKind::Dynamic))
    {
        return fail(
            &[],
            "vacuum mode moves dynamic bodies under gravity and contact; this scene has none",
        );
    }
    if scene.vacuum && !scene.initial.is_empty() {
        return fail(
            &[],
            "vacuum mode has no flow, so an initial vorticity would be ignored; remove `initial`",
        );
    }
    Ok(())
}

impl Contact {
    /// Check the contact model for a scene with `bodies` (named).
    pub(crate) fn check(&self, bodies: &[BodySpec]) -> Check {
        if let Some(k) = self.kappa
            && !(k.is_finite() && k >= 0.0)
        {
            return fail(&["kappa"], format!("must be zero or positive, got {k}"));
        }
        if let Some(e) = self.eps
            && !(e.is_finite() && e > 0.0)
        {
            return fail(&["eps"], format!("must be positive, got {e}"));
        }
        if !(self.range.is_finite() && self.range >= 2.0) {
            return fail(
                &["range"],
                format!("must be at least 2, got {}", self.range),
            );
        }
        for (i, p) in self.pairs.iter().enumerate() {
            let at = |e: Issue| e.under(Seg::Index(i)).under(Seg::Key("pairs"));
            for n in [&p.bodies.0, &p.bodies.1] {
                if !bodies.iter().any(|b| &b.name == n) {
                    return fail(&["bodies"], format!("no body is named `{n}`")).map_err(at);
                }
            }
            if p.bodies.0 == p.bodies.1 {
                return fail(
                    &["bodies"],
                    format!(
                        "a pair needs two different bodies, got `{}` twice",
                        p.bodies.0
                    ),
                )
                .map_err(at);
            }
            if !(p.kappa.is_finite() && p.kappa >= 0.0) {
                return fail(
                    &["kappa"],
                    format!("must be zero or positive, got {}", p.kappa),
                )
                .map_err(at);
            }
        }
        Ok(())
    }

    /// The first pair of bodies that can touch (one of them dynamic) and has no κ of its own:
    /// not in `pairs` and at least one of them without `kappa`.
    fn pair_without_kappa<'a>(&self, bodies: &'a [BodySpec]) -> Option<(&'a str, &'a str)> {
        if bodies.iter().all(|b| b.kappa.is_some()) {
            return None;
        }
        let named: std::collections::HashSet<(&str, &str)> = self
            .pairs
            .iter()
            .flat_map(|p| {
                let (a, b) = (p.bodies.0.as_str(), p.bodies.1.as_str());
                [(a, b), (b, a)]
            })
            .collect();
        for (i, a) in bodies.iter().enumerate() {
            if !matches!(a.kind, BodyKind::Dynamic) {
                continue;
            }
            for (j, b) in bodies.iter().enumerate() {
                if i != j
                    && (a.kappa.is_none() || b.kappa.is_none())
                    && !named.contains(&(a.name.as_str(), b.name.as_str()))
                {
                    return Some((&a.name, &b.name));
                }
            }
        }
        None
    }
}

impl Output {
    pub(crate) fn check(&self) -> Check {
        if let Some(e) = self.every
            && !(e.is_finite() && e > 0.0)
        {
            return fail(&["every"], format!("must be positive, got {e}"));
        }
        if self.formats.is_empty() {
            return fail(
                &["formats"],
                "needs at least one format: [Vtk], [Hdf5] or [Vtk, Hdf5]",
            );
        }
        if self.has_format(OutputFormat::Hdf5) && !cfg!(feature = "hdf5") {
            return fail(
                &["formats"],
                "Hdf5 output needs a tumble built with the `hdf5` feature (install the HDF5 \
                 library, e.g. `apt-get install libhdf5-dev`, then `cargo build --release \
                 --features hdf5`); this build writes only Vtk",
            );
        }
        if let Some(e) = self.checkpoint_every
            && !(e.is_finite() && e > 0.0)
        {
            return fail(&["checkpoint_every"], format!("must be positive, got {e}"));
        }
        if let Some(w) = self.checkpoint_wall
            && !(w.is_finite() && w > 0.0)
        {
            return fail(
                &["checkpoint_wall"],
                format!(
                    "must be a positive number of seconds, got {w} (`checkpoint_wall: None` \
                     turns the wall-clock checkpoints off)"
                ),
            );
        }
        if self.checkpoints_kept == 0 {
            return fail(
                &["checkpoints_kept"],
                "must be at least 1 (the checkpoint a restart continues from)",
            );
        }
        if let Some(u) = &self.units {
            for (key, name) in [("length", &u.length), ("time", &u.time), ("mass", &u.mass)] {
                if let Some(n) = name
                    && (n.trim().is_empty() || n.chars().any(char::is_control))
                {
                    return fail(
                        &["units", key],
                        format!(
                            "a unit name is a short text such as \"cm\" or \"s\", got {n:?} \
                             (leave it out if the scene has no named unit)"
                        ),
                    );
                }
            }
        }
        Ok(())
    }
}

/// Build every body's shape (mesh files are read now, so a missing or broken mesh is a scene
/// error with its line) and reject bodies that overlap at the start; the shapes, in order.
fn check_geometry(scene: &Scene, grid: &Grid) -> Check<Vec<ShapeGeometry>> {
    let mut geoms: Vec<ShapeGeometry> = Vec::with_capacity(scene.bodies.len());
    for (i, b) in scene.bodies.iter().enumerate() {
        let g = b.shape.build(&scene.base_dir).map_err(|e| {
            Issue::new(&["shape"], format!("body `{}`: {e}", b.name))
                .under(Seg::Index(i))
                .under(Seg::Key("bodies"))
        })?;
        geoms.push(g);
    }
    check_periodic_images(scene, grid, &geoms)?;
    if let Some(o) = super::overlap::initial_overlap(scene, grid, &geoms) {
        let (a, b) = (&scene.bodies[o.a], &scene.bodies[o.b]);
        let dim = grid.dim;
        return Err(Issue::new(
            &["position"],
            format!(
                "bodies `{}` and `{}` overlap at the start: the point ({}) is {:.3e} deep \
                 inside both (more than half a cell, h/2 = {:.3e}); move them apart so that \
                 they at most touch",
                a.name,
                b.name,
                o.point.to_array()[..dim]
                    .iter()
                    .map(|x| format!("{x:.4}"))
                    .collect::<Vec<_>>()
                    .join(", "),
                o.depth,
                grid.h / 2.0
            ),
        )
        .under(Seg::Index(o.b))
        .under(Seg::Key("bodies")));
    }
    Ok(geoms)
}

/// The gap a moving body must leave to its own periodic image along each axis, in cells:
/// its smoothed edge (`numerics.interface_cells` on either side) plus one cell on either side.
fn image_gap(scene: &Scene, h: f64) -> f64 {
    2.0 * (scene.numerics.interface_cells + 1.0) * h
}

/// The box is periodic along every axis: a dynamic or kinematic body longer than the box along
/// an axis overlaps its own periodic image, and one that leaves less than [`image_gap`] between
/// itself and its image touches it through its smoothed edge. Measured on the body's world
/// bounding box at the start (rotated as given). Static bodies are walls: a floor may span the
/// box and continue into its image.
fn check_periodic_images(scene: &Scene, grid: &Grid, geoms: &[ShapeGeometry]) -> Check {
    let ext = grid.extent();
    let gap = image_gap(scene, grid.h);
    for (i, (b, g)) in scene.bodies.iter().zip(geoms).enumerate() {
        if matches!(b.kind, BodyKind::Static) {
            continue;
        }
        let Some((lo, hi)) = g.bounds() else {
            continue;
        };
        let m = glam::DMat3::from_quat(crate::bodies::rotation(&b.rotation));
        let half = 0.5 * (hi - lo);
        for a in 0..grid.dim {
            let size = 2.0 * m.row(a).abs().dot(half);
            let axis = ["x", "y", "z"][a];
            let (l, rotated) = (
                ext[a],
                if b.rotation.is_empty() {
                    ""
                } else {
                    ", as rotated"
                },
            );
            let message = if size >= l {
                format!(
                    "body `{}` is {size:.4} long along {axis}{rotated}, not shorter than the \
                     periodic box ({l}): it overlaps its own periodic image; make it smaller or \
                     the box larger",
                    b.name
                )
            } else if l - size < gap {
                format!(
                    "body `{}` overlaps its own periodic image along {axis}: it is {size:.4} \
                     long{rotated} in a periodic box of {l}, leaving {:.4} to its image, less \
                     than the {gap:.4} (2 (interface_cells + 1) h) its smoothed edges need; \
                     make it smaller or the box larger",
                    b.name,
                    l - size
                )
            } else {
                continue;
            };
            return Err(Issue::new(&["shape"], message)
                .under(Seg::Index(i))
                .under(Seg::Key("bodies")));
        }
    }
    Ok(())
}

impl Scene {
    /// Things in a valid scene that are likely to go wrong, one sentence each: under the
    /// default `Pressure` coupling, dynamic bodies lighter than half the fluid's density (the
    /// smoothed band the penalization moves rigidly adds fluid to their mass: a disk of
    /// density 0.1 launched in still fluid kept 0.159 of its speed against 0.091 at 12.8
    /// cells per radius); under `Baroclinic`, bodies heavier than 2.5 ρ_F (its excess inertia
    /// is explicit: a sphere of density 3 in a periodic box settled 35% too fast, one of 4 blew
    /// up); and the baroclinic options set under another coupling, which ignores them.
    /// `densities` are the bodies' (resolved, see [`Resolved::densities`]).
    pub(crate) fn warnings(&self, densities: &[f64]) -> Vec<String> {
        let mut out = Vec::new();
        let n = &self.numerics;
        if self.vacuum {
            return out;
        }
        let baroclinic = n.body_coupling == BodyCoupling::Baroclinic;
        if !baroclinic
            && (n.boussinesq || n.interface_acceleration != InterfaceAcceleration::default())
        {
            out.push(format!(
                "`numerics.boussinesq` and `numerics.interface_acceleration` act only with `body_coupling: Baroclinic`; with {:?} they are ignored",
                n.body_coupling
            ));
        }
        for (b, density) in self.bodies.iter().zip(densities) {
            if !matches!(b.kind, BodyKind::Dynamic) {
                continue;
            }
            let ratio = density / self.fluid.density;
            if baroclinic && !n.boussinesq && ratio > 2.5 {
                out.push(format!(
                    "body `{}` is {ratio:.3} times as dense as the fluid: with `body_coupling: Baroclinic` dense bodies move wrongly (a sphere settling at Re << 1: +13% at 2 times, +35% at 3, blown up at 4); the default coupling (`Pressure`) does not",
                    b.name
                ));
            }
            if n.body_coupling == BodyCoupling::Pressure && ratio < 0.5 {
                out.push(format!(
                    "body `{}` is {ratio:.3} times as dense as the fluid: bodies lighter than the fluid are resolved poorly (the smoothed band moved rigidly with the body adds fluid to its mass: a disk of density 0.1 launched in still fluid kept 0.159 of its speed instead of 0.091 at 12.8 cells per radius, a sphere of density 0.01 settled 7.9% fast at 3.2 cells per radius); give it more cells per radius",
                    b.name
                ));
            }
        }
        out
    }
}
