//! Scenes: what to simulate, read from RON files.
//!
//! Every struct rejects unknown fields, every field has a documented unit and default, and
//! every problem found while loading is a [`SceneError`] that names the file, the line and the
//! field, so a user can fix the scene without reading code.
//!
//! ```ron
//! Scene(
//!     name: "lamb-oseen",
//!     domain: (extent: [2.0, 2.0], origin: [-1.0, -1.0], cells: [128, 128]),
//!     fluid: (viscosity: 1e-3),
//!     numerics: (end_time: 2.5, dt: Adaptive(c: 0.5, dt_max: 0.05)),
//!     initial: [LambOseen(center: [0.0, 0.0], circulation: 1.0, core_radius: 0.1)],
//!     output: (every: 0.5),
//! )
//! ```

use crate::base::grid::Grid;
pub mod overlap;

pub use crate::base::params::{BodyCoupling, InterfaceAcceleration, RemeshKernel, TimeStep};
pub use crate::bodies::BodyKind;
use serde::{Deserialize, Serialize};
use std::fmt;
use std::path::Path;

/// A whole scene.
#[derive(Deserialize, Serialize, Debug, Clone, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Name of the scene, used for the default output directory `runs/<name>`.
    /// Default: the file name without extension.
    #[serde(default)]
    pub name: String,
    /// The periodic computational box and its grid.
    pub domain: Domain,
    /// Fluid properties.
    #[serde(default)]
    pub fluid: Fluid,
    /// Time stepping and particle parameters.
    #[serde(default)]
    pub numerics: Numerics,
    /// Initial vorticity: the sum of these fields. Default: none (fluid at rest).
    #[serde(default)]
    pub initial: Vec<InitialVorticity>,
    /// What is written and how often.
    #[serde(default)]
    pub output: Output,
    /// Rigid bodies: dynamic (two-way coupled), kinematic (prescribed motion) and static
    /// (walls, tanks). Default: none.
    #[serde(default)]
    pub bodies: Vec<BodySpec>,
    /// Contact between bodies (the level-set collision model, eqs. 20-22).
    #[serde(default)]
    pub contact: Contact,
    /// Vacuum mode: the flow solver is off and gravity and contact act on the bodies directly
    /// (paper Fig. 1 and Fig. 9). Default: false.
    #[serde(default)]
    pub vacuum: bool,
    /// Directory that relative mesh paths are resolved against (the scene file's).
    #[serde(skip)]
    pub base_dir: std::path::PathBuf,
}

/// A rigid body in the scene.
#[derive(Deserialize, Serialize, Debug, Clone, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct BodySpec {
    /// Name in outputs. Default: `body<index>`.
    #[serde(default)]
    pub name: String,
    /// Shape in body coordinates (centred on the body's position).
    pub shape: crate::bodies::shapes::Shape,
    /// How it moves. Default: Dynamic.
    #[serde(default = "default_kind")]
    pub kind: BodyKind,
    /// Density, mass per volume, > 0. Default: the fluid's density (neutrally buoyant).
    #[serde(default)]
    pub density: Option<f64>,
    /// Position of the body's centre, length units (one entry per axis).
    pub position: Vec<f64>,
    /// Initial orientation as a rotation vector (axis times angle, radians): 1 entry (angle
    /// about z) in 2D, 3 in 3D. Default: no rotation.
    #[serde(default)]
    pub rotation: Vec<f64>,
    /// Initial velocity of a dynamic body, length/time. Default: zero.
    #[serde(default)]
    pub velocity: Vec<f64>,
    /// Initial angular velocity of a dynamic body (1 entry in 2D, 3 in 3D), rad/time.
    /// Default: zero.
    #[serde(default)]
    pub angular_velocity: Vec<f64>,
    /// This body's contact strength κ (velocity², ≥ 0): a pair of bodies uses the mean of
    /// their two values unless `contact.pairs` names the pair. Default: `contact.kappa`.
    #[serde(default)]
    pub kappa: Option<f64>,
}

/// The level-set contact model (paper eqs. 20-22): on the inner band of body i, a force
/// density ρ_i κ_ij/ε ζ(φ_i/ε) e^{-d/ε}/d pushing i away from body j along -∇φ_j, with
/// d = -φ_j the distance to j.
#[derive(Deserialize, Serialize, Debug, Clone, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct Contact {
    /// Default strength κ of the repulsion for every pair, velocity² (≥ 0; 0 turns contact
    /// off). The paper uses 30 (2D disk on a wall), 25 (two spheres) and 5 (in vacuum).
    /// Default: 25.
    pub kappa: f64,
    /// Range ε of the repulsion, length (> 0). Default: the grid spacing h.
    pub eps: Option<f64>,
    /// Distance beyond which the force is dropped, in units of ε (≥ 2; e^{-6}/6 ≈ 4e-4 of the
    /// force at d = ε). Default: 6.
    pub range: f64,
    /// κ for named pairs of bodies, overriding the per-body values. Default: none.
    pub pairs: Vec<ContactPair>,
}

impl Default for Contact {
    fn default() -> Self {
        Contact {
            kappa: 25.0,
            eps: None,
            range: 6.0,
            pairs: Vec::new(),
        }
    }
}

/// κ for one pair of bodies.
#[derive(Deserialize, Serialize, Debug, Clone, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ContactPair {
    /// The names of the two bodies.
    pub bodies: (String, String),
    /// Strength κ for this pair, velocity² (≥ 0).
    pub kappa: f64,
}

fn default_kind() -> BodyKind {
    BodyKind::Dynamic
}

/// The box `[origin, origin + extent)`, periodic, with a uniform grid of spacing `h`.
#[derive(Deserialize, Serialize, Debug, Clone, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Domain {
    /// Box size per axis, length units; two entries make a 2D scene, three a 3D one. Required.
    pub extent: Vec<f64>,
    /// Position of the box's lower corner, length units. Default: zeros.
    #[serde(default)]
    pub origin: Option<Vec<f64>>,
    /// Number of cells (= nodes, the box is periodic) per axis. Give `cells` or `h`, not both.
    #[serde(default)]
    pub cells: Option<Vec<usize>>,
    /// Grid spacing, length units; every extent must be a whole multiple of it.
    #[serde(default)]
    pub h: Option<f64>,
}

/// Fluid properties.
#[derive(Deserialize, Serialize, Debug, Clone, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct Fluid {
    /// Density ρ_F, mass per volume. Default: 1.
    pub density: f64,
    /// Kinematic viscosity ν, length²/time, ≥ 0. Default: 0.001.
    pub viscosity: f64,
    /// Gravity vector g, length/time² (one entry per axis). Default: zeros.
    pub gravity: Vec<f64>,
    /// Uniform background velocity (the k = 0 mode of u), length/time. Default: zeros.
    pub background_velocity: Vec<f64>,
}

impl Default for Fluid {
    fn default() -> Self {
        Fluid {
            density: 1.0,
            viscosity: 1e-3,
            gravity: Vec::new(),
            background_velocity: Vec::new(),
        }
    }
}

/// Time stepping and particle parameters.
#[derive(Deserialize, Serialize, Debug, Clone, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct Numerics {
    /// Time step policy. Default: `Adaptive(c: 0.5)`.
    pub dt: TimeStep,
    /// Simulated time at which the run ends, time units, > 0. Default: 1.
    pub end_time: f64,
    /// Particle creation cutoff, relative to max|ω| (dimensionless, in [0, 1)): grid nodes with
    /// |ω| at or below `remesh_cutoff * max|ω|` create no particle and keep their (small)
    /// vorticity in place. Default: 1e-8.
    pub remesh_cutoff: f64,
    /// Stop the run as blown up when max|ω| exceeds this multiple of its initial value
    /// (dimensionless). Default: 1e4.
    pub blowup_factor: f64,
    /// Carry the particles (and stretch the vorticity) with the mid-step velocity
    /// u^{n+1/2} = u^n + (Δt_n / 2Δt_{n-1}) (u^n - u^{n-1}) instead of the frozen u^n, which makes
    /// the step second order in time. Default: true.
    pub midpoint_velocity: bool,
    /// Interpolation and remeshing kernel. Default: `M4Prime` (the paper's eq. 30).
    pub remesh_kernel: RemeshKernel,
    /// Penalization coefficient λ, 1/time, > 0 (implicit, so any value is stable). Default: 1e6.
    pub lambda: f64,
    /// Half-width of the smoothed Heaviside χ = H(φ), in cells (> 0). Default: 1.
    pub interface_cells: f64,
    /// Where the penalization mask of static and kinematic bodies (walls, obstacles) sits
    /// relative to their surface, in cells: the mask is H_ε(φ - offset h), so with an offset
    /// of one half-width the smoothed band lies inside the body and the rigid region does not
    /// reach into the fluid (a fixed cylinder's drag then converges from the first grid).
    /// Dynamic bodies always use the centred χ = H_ε(φ). In [0, 2 interface_cells].
    /// Default: 0.
    pub penalization_offset: f64,
    /// How gravity and a dynamic body's own inertia reach the body. `Baroclinic` (default, the
    /// paper's): gravity makes vorticity on the body's interface (eq. 28, in the form
    /// `boussinesq` and `interface_acceleration` choose) and ū is the flow's mean over the body.
    /// `Momentum`: the body's buoyancy (ρ_i - ρ_F) V g and the inertia of its mass beyond the
    /// fluid's act on its rigid velocity directly, (M_w + (ρ_i - ρ_F) V) Δū = M_w (ũ - ū) +
    /// (ρ_i - ρ_F) V g Δt, with ũ the mean of the flow over the region the penalization moves
    /// and M_w that region's fluid mass; the flow carries the fluid's density everywhere, as
    /// its vorticity equation (one ν = μ/ρ_F) assumes. `Momentum` settles at the right
    /// velocity for any density and stays stable for heavy bodies, see [`BodyCoupling`].
    /// Default: Baroclinic.
    pub body_coupling: BodyCoupling,
    /// Use the Boussinesq form of the baroclinic term, ∇ρ × g / ρ_F (eq. 18), instead of the
    /// full form (eq. 28); with `body_coupling: Baroclinic`. Default: false.
    pub boussinesq: bool,
    /// The fluid acceleration Du/Dt on the bodies' interfaces in the baroclinic term (eq. 28):
    /// `Rigid`, the acceleration of the body's rigid motion (no slip), or `Eulerian`, the grid
    /// estimate ∂u/∂t + (u·∇)u from the last two velocity fields (the paper's); with
    /// `body_coupling: Baroclinic`. Default: Rigid.
    pub interface_acceleration: InterfaceAcceleration,
}

impl Default for Numerics {
    fn default() -> Self {
        Numerics {
            dt: TimeStep::default(),
            end_time: 1.0,
            remesh_cutoff: 1e-8,
            blowup_factor: 1e4,
            midpoint_velocity: true,
            remesh_kernel: RemeshKernel::M4Prime,
            lambda: 1e6,
            interface_cells: 1.0,
            penalization_offset: 0.0,
            body_coupling: BodyCoupling::Baroclinic,
            boussinesq: false,
            interface_acceleration: InterfaceAcceleration::Rigid,
        }
    }
}

/// A named initial vorticity field. Positions are absolute coordinates.
#[derive(Deserialize, Serialize, Debug, Clone, PartialEq)]
#[serde(deny_unknown_fields)]
pub enum InitialVorticity {
    /// 2D Lamb-Oseen vortex ω = Γ/(π σ²) exp(-r²/σ²) (nearest periodic image).
    LambOseen {
        /// Centre, length units (2 entries).
        center: Vec<f64>,
        /// Circulation Γ, length²/time.
        circulation: f64,
        /// Core radius σ, length units, > 0.
        core_radius: f64,
    },
    /// 2D Taylor-Green vortex u = A sin(kx) cos(ky), v = -A cos(kx) sin(ky), so
    /// ω = 2 A k sin(kx) sin(ky) (x, y measured from the box origin).
    TaylorGreen2d {
        /// Velocity amplitude A, length/time. Default: 1.
        #[serde(default = "one")]
        amplitude: f64,
        /// Wavenumber k, 1/length. Default: 1.
        #[serde(default = "one")]
        wavenumber: f64,
    },
    /// 3D Taylor-Green vortex u = A sin(kx) cos(ky) cos(kz), v = -A cos(kx) sin(ky) cos(kz),
    /// w = 0 (x, y, z measured from the box origin).
    TaylorGreen3d {
        /// Velocity amplitude A, length/time. Default: 1.
        #[serde(default = "one")]
        amplitude: f64,
        /// Wavenumber k, 1/length. Default: 1.
        #[serde(default = "one")]
        wavenumber: f64,
    },
    /// 3D vortex ring with a Gaussian core: |ω| = Γ/(π σ²) exp(-ρ²/σ²), ρ the distance to the
    /// ring's centre line, directed along the ring (right-handed about `axis`).
    VortexRing {
        /// Ring centre, length units (3 entries).
        center: Vec<f64>,
        /// Direction of the ring's axis (its self-induced motion), normalised on load.
        axis: Vec<f64>,
        /// Ring radius R, length units, > 0.
        radius: f64,
        /// Core radius σ, length units, > 0.
        core_radius: f64,
        /// Circulation Γ, length²/time.
        circulation: f64,
    },
}

fn one() -> f64 {
    1.0
}

/// A field that can be written to snapshots.
#[derive(Deserialize, Serialize, Debug, Clone, Copy, PartialEq, Eq)]
pub enum FieldName {
    /// Vorticity (scalar in 2D, vector in 3D).
    Omega,
    /// Velocity.
    Velocity,
    /// Density ρ (eq. 19), characteristic function Σχ and the union level set max φ_i
    /// (written only when the scene has bodies).
    Density,
}

/// What is written and how often.
#[derive(Deserialize, Serialize, Debug, Clone, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct Output {
    /// Simulated time between field snapshots, time units; `None` writes only the first and
    /// the last. Default: None.
    pub every: Option<f64>,
    /// Fields in each snapshot. Default: `[Omega, Velocity]`.
    pub fields: Vec<FieldName>,
    /// Output directory; `tumble run --out` overrides it. Default: `runs/<name>`.
    pub dir: Option<String>,
    /// File formats of the field snapshots: `Vtk` (`fields_NNNNNN.vti` + `fields.pvd`) and/or
    /// `Hdf5` (`fields_NNNNNN.h5` + `fields.xmf`, and the body and contact series in
    /// `series.h5`; needs a build with `--features hdf5`). At least one. Default: `[Vtk]`.
    pub formats: Vec<OutputFormat>,
    /// Simulated time between checkpoints (`checkpoint.bin` in the run directory, replaced
    /// each time; `tumble run --restart` continues from it), time units; `tumble run
    /// --checkpoint-every` overrides it. `None` writes a checkpoint only when the run is
    /// interrupted (Ctrl-C, SIGTERM). Default: None.
    pub checkpoint_every: Option<f64>,
}

/// A file format for field snapshots.
#[derive(Deserialize, Serialize, Debug, Clone, Copy, PartialEq, Eq)]
pub enum OutputFormat {
    /// VTK XML image data (`.vti`) indexed by a ParaView `.pvd` collection.
    Vtk,
    /// HDF5 (one `.h5` file per snapshot) indexed by an XDMF `.xmf` temporal collection, which
    /// ParaView and VisIt open as one time series.
    Hdf5,
}

impl Output {
    /// Whether snapshots are written in `format`.
    pub fn has_format(&self, format: OutputFormat) -> bool {
        self.formats.contains(&format)
    }
}

impl Default for Output {
    fn default() -> Self {
        Output {
            every: None,
            fields: vec![FieldName::Omega, FieldName::Velocity, FieldName::Density],
            dir: None,
            formats: vec![OutputFormat::Vtk],
            checkpoint_every: None,
        }
    }
}

/// The most grid nodes a scene may ask for (2^32; about 35 GB per scalar field).
pub const MAX_NODES: u64 = 1 << 32;

/// A problem with a scene, located as precisely as possible.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneError {
    /// The scene file (or `<scene>` for a scene built in code).
    pub file: String,
    /// 1-based line, when known.
    pub line: Option<usize>,
    /// Dotted path of the offending field, when known (e.g. `fluid.viscosity`).
    pub field: Option<String>,
    /// What is wrong.
    pub message: String,
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "scene error in {}", self.file)?;
        if let Some(l) = self.line {
            write!(f, ", line {l}")?;
        }
        if let Some(field) = &self.field {
            write!(f, ", field `{field}`")?;
        }
        write!(f, ": {}", self.message)
    }
}

impl std::error::Error for SceneError {}

impl Scene {
    /// Things in a valid scene that are likely to go wrong, one sentence each: dynamic bodies
    /// heavier than 2.5 ρ_F with the default `Baroclinic` coupling (its excess inertia is
    /// explicit: a sphere of density 3 in a periodic box settled 35% too fast, one of 4 blew
    /// up, a disk of density 3 launched in still fluid oscillated with a growing amplitude;
    /// `Momentum` is right at 0.01 to 20).
    pub fn warnings(&self) -> Vec<String> {
        let mut out = Vec::new();
        let n = &self.numerics;
        if self.vacuum || n.body_coupling != BodyCoupling::Baroclinic || n.boussinesq {
            return out;
        }
        for b in &self.bodies {
            let rho = b.density.unwrap_or(self.fluid.density);
            if matches!(b.kind, BodyKind::Dynamic) && rho > 2.5 * self.fluid.density {
                out.push(format!(
                    "body `{}` is {:.3} times as dense as the fluid: with `body_coupling: Baroclinic` (the default) dense bodies move wrongly (a sphere settling at Re << 1: +13% at 2 times, +35% at 3, blown up at 4; a disk launched at 3 times oscillates with a growing amplitude); `numerics: (body_coupling: Momentum)` does not",
                    b.name,
                    rho / self.fluid.density
                ));
            }
        }
        out
    }

    /// Read and validate a scene file.
    pub fn load(path: &Path) -> Result<Scene, SceneError> {
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| SceneError {
            file: file.clone(),
            line: None,
            field: None,
            message: format!("cannot read the file: {e}"),
        })?;
        let stem = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        let mut scene = Scene::parse(&text, &file, &stem)?;
        scene.base_dir = path.parent().map(|p| p.to_path_buf()).unwrap_or_default();
        // Mesh files are read now, so a missing or broken mesh is a scene error with its line.
        let mut geoms = Vec::with_capacity(scene.bodies.len());
        for (i, b) in scene.bodies.iter().enumerate() {
            match b.shape.build(&scene.base_dir) {
                Ok(g) => geoms.push(g),
                Err(e) => {
                    return Err(SceneError {
                        file: file.clone(),
                        line: body_key_line(&text, i, "shape"),
                        field: Some("bodies.shape".into()),
                        message: format!("body `{}`: {e}", b.name),
                    });
                }
            }
        }
        if let Some(o) = crate::scene::overlap::initial_overlap(&scene, &geoms) {
            let (a, b) = (&scene.bodies[o.a], &scene.bodies[o.b]);
            let dim = scene.dim();
            return Err(SceneError {
                file: file.clone(),
                line: body_key_line(&text, o.b, "position"),
                field: Some("bodies.position".into()),
                message: format!(
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
                    scene.grid().h / 2.0
                ),
            });
        }
        Ok(scene)
    }

    /// Parse and validate scene text; `file` names it in errors, `default_name` is used when
    /// the scene has no `name`.
    pub fn parse(text: &str, file: &str, default_name: &str) -> Result<Scene, SceneError> {
        let opts = ron::Options::default()
            .with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME);
        let mut scene: Scene = opts.from_str(text).map_err(|e| SceneError {
            file: file.to_string(),
            line: Some(e.span.start.line),
            field: None,
            message: format!("{} (column {})", e.code, e.span.start.col),
        })?;
        if scene.name.is_empty() {
            scene.name = default_name.to_string();
        }
        scene.validate().map_err(|(path, message)| SceneError {
            file: file.to_string(),
            line: locate(text, &path),
            field: Some(path.join(".")),
            message,
        })?;
        Ok(scene)
    }

    /// Serialise back to RON (the scene as run, written into the run directory).
    pub fn to_ron(&self) -> String {
        ron::ser::to_string_pretty(self, ron::ser::PrettyConfig::default())
            .unwrap_or_else(|e| format!("// could not serialise the scene: {e}\n"))
    }

    /// Number of space dimensions (2 or 3).
    pub fn dim(&self) -> usize {
        self.domain.extent.len()
    }

    /// The grid this scene runs on (call after validation).
    pub fn grid(&self) -> Grid {
        let d = &self.domain;
        let dim = self.dim();
        let (cells, h) = match (&d.cells, d.h) {
            (Some(c), _) => (c.clone(), d.extent[0] / c[0] as f64),
            (None, Some(h)) => (
                d.extent
                    .iter()
                    .map(|e| (e / h).round() as usize)
                    .collect::<Vec<_>>(),
                h,
            ),
            (None, None) => unreachable!("validated"),
        };
        let mut n = [1usize; 3];
        let mut origin = [0.0; 3];
        for a in 0..dim {
            n[a] = cells[a];
            origin[a] = d.origin.as_ref().map_or(0.0, |o| o[a]);
        }
        Grid::new(n, h, origin)
    }

    /// Gravity as a 3-vector (zeros where not given).
    pub fn gravity(&self) -> [f64; 3] {
        pad3(&self.fluid.gravity)
    }

    /// Background velocity as a 3-vector.
    pub fn background_velocity(&self) -> [f64; 3] {
        pad3(&self.fluid.background_velocity)
    }

    /// Check every value; on failure return the field path and the message.
    fn validate(&mut self) -> Result<(), (Vec<&'static str>, String)> {
        let err = |p: &[&'static str], m: String| Err((p.to_vec(), m));
        let dim = self.dim();
        if dim != 2 && dim != 3 {
            return err(
                &["domain", "extent"],
                format!("needs 2 entries (2D) or 3 (3D), got {dim}"),
            );
        }
        for &e in &self.domain.extent {
            if !(e.is_finite() && e > 0.0) {
                return err(
                    &["domain", "extent"],
                    format!("every extent must be positive, got {e}"),
                );
            }
        }
        if let Some(o) = &self.domain.origin {
            if o.len() != dim {
                return err(
                    &["domain", "origin"],
                    format!("needs {dim} entries like extent, got {}", o.len()),
                );
            }
            if o.iter().any(|x| !x.is_finite()) {
                return err(&["domain", "origin"], "must be finite".into());
            }
        }
        match (&self.domain.cells, self.domain.h) {
            (Some(_), Some(_)) => {
                return err(
                    &["domain", "h"],
                    "give either `cells` or `h`, not both".into(),
                );
            }
            (None, None) => {
                return err(
                    &["domain", "extent"],
                    "the domain needs `cells: [..]` or `h: ..` to define its grid".into(),
                );
            }
            (Some(c), None) => {
                if c.len() != dim {
                    return err(
                        &["domain", "cells"],
                        format!("needs {dim} entries like extent, got {}", c.len()),
                    );
                }
                if let Some(&z) = c.iter().find(|&&n| n < 4) {
                    return err(
                        &["domain", "cells"],
                        format!("every axis needs at least 4 cells, got {z}"),
                    );
                }
                let h = self.domain.extent[0] / c[0] as f64;
                for a in 1..dim {
                    let ha = self.domain.extent[a] / c[a] as f64;
                    if ((ha - h) / h).abs() > 1e-9 {
                        return err(
                            &["domain", "cells"],
                            format!(
                                "cells must give the same spacing on every axis: axis 0 has h = {h}, axis {a} has h = {ha}"
                            ),
                        );
                    }
                }
            }
            (None, Some(h)) => {
                if !(h.is_finite() && h > 0.0) {
                    return err(&["domain", "h"], format!("must be positive, got {h}"));
                }
                for (a, &e) in self.domain.extent.iter().enumerate() {
                    let m = e / h;
                    if (m - m.round()).abs() > 1e-6 * m.max(1.0) || m.round() < 4.0 {
                        return err(
                            &["domain", "h"],
                            format!(
                                "extent[{a}] = {e} is not a whole multiple (at least 4) of h = {h} ({m} cells)"
                            ),
                        );
                    }
                }
            }
        }
        // Node counts in f64 (no overflow), bounded so every index and byte count fits.
        let nodes: Vec<f64> = match (&self.domain.cells, self.domain.h) {
            (Some(c), _) => c.iter().map(|&n| n as f64).collect(),
            (_, Some(h)) => self.domain.extent.iter().map(|e| (e / h).round()).collect(),
            (None, None) => Vec::new(),
        };
        let total: f64 = nodes.iter().product();
        if total > MAX_NODES as f64 {
            let field: &'static str = if self.domain.cells.is_some() {
                "cells"
            } else {
                "h"
            };
            return err(
                &["domain", field],
                format!(
                    "the grid would have {total:.3e} nodes ({}), more than the {MAX_NODES} \
                     (2^32) this version can address; use fewer cells",
                    nodes
                        .iter()
                        .map(|n| format!("{n}"))
                        .collect::<Vec<_>>()
                        .join(" x ")
                ),
            );
        }
        let f = &self.fluid;
        if !(f.density.is_finite() && f.density > 0.0) {
            return err(
                &["fluid", "density"],
                format!("must be positive, got {}", f.density),
            );
        }
        if !(f.viscosity.is_finite() && f.viscosity >= 0.0) {
            return err(
                &["fluid", "viscosity"],
                format!("must be zero or positive, got {}", f.viscosity),
            );
        }
        for (name, v) in [
            ("gravity", &f.gravity),
            ("background_velocity", &f.background_velocity),
        ] {
            if !v.is_empty() && v.len() != dim {
                let key: &'static str = if name == "gravity" {
                    "gravity"
                } else {
                    "background_velocity"
                };
                return err(
                    &["fluid", key],
                    format!("needs {dim} entries, got {}", v.len()),
                );
            }
            if v.iter().any(|x| !x.is_finite()) {
                return err(&["fluid", "gravity"], "must be finite".into());
            }
        }
        let n = &self.numerics;
        match &n.dt {
            TimeStep::Fixed(dt) => {
                if !(dt.is_finite() && *dt > 0.0) {
                    return err(&["numerics", "dt"], format!("must be positive, got {dt}"));
                }
            }
            TimeStep::Adaptive {
                c,
                dt_max,
                cfl,
                diffusion_number,
            } => {
                if !(diffusion_number.is_finite() && *diffusion_number > 0.0) {
                    return err(
                        &["numerics", "diffusion_number"],
                        format!("must be positive, got {diffusion_number}"),
                    );
                }
                if !(c.is_finite() && *c > 0.0) {
                    return err(&["numerics", "c"], format!("must be positive, got {c}"));
                }
                if let Some(m) = dt_max
                    && !(m.is_finite() && *m > 0.0)
                {
                    return err(
                        &["numerics", "dt_max"],
                        format!("must be positive, got {m}"),
                    );
                }
                if !(cfl.is_finite() && *cfl > 0.0) {
                    return err(&["numerics", "cfl"], format!("must be positive, got {cfl}"));
                }
            }
        }
        if !(n.end_time.is_finite() && n.end_time > 0.0) {
            return err(
                &["numerics", "end_time"],
                format!("must be positive, got {}", n.end_time),
            );
        }
        if !(n.remesh_cutoff.is_finite() && (0.0..1.0).contains(&n.remesh_cutoff)) {
            return err(
                &["numerics", "remesh_cutoff"],
                format!("must be in [0, 1), got {}", n.remesh_cutoff),
            );
        }
        if !(n.blowup_factor.is_finite() && n.blowup_factor > 1.0) {
            return err(
                &["numerics", "blowup_factor"],
                format!("must be greater than 1, got {}", n.blowup_factor),
            );
        }
        for init in &mut self.initial {
            match init {
                InitialVorticity::LambOseen {
                    center,
                    core_radius,
                    circulation,
                } => {
                    if dim != 2 {
                        return err(
                            &["initial", "LambOseen"],
                            "LambOseen is a 2D field; this scene is 3D".into(),
                        );
                    }
                    if center.len() != 2 {
                        return err(&["initial", "center"], "needs 2 entries".into());
                    }
                    if !(core_radius.is_finite() && *core_radius > 0.0) {
                        return err(
                            &["initial", "core_radius"],
                            format!("must be positive, got {core_radius}"),
                        );
                    }
                    if !circulation.is_finite() {
                        return err(&["initial", "circulation"], "must be finite".into());
                    }
                }
                InitialVorticity::TaylorGreen2d {
                    amplitude,
                    wavenumber,
                } => {
                    if dim != 2 {
                        return err(
                            &["initial", "TaylorGreen2d"],
                            "TaylorGreen2d is a 2D field; use TaylorGreen3d in 3D".into(),
                        );
                    }
                    check_tg(*amplitude, *wavenumber)?;
                }
                InitialVorticity::TaylorGreen3d {
                    amplitude,
                    wavenumber,
                } => {
                    if dim != 3 {
                        return err(
                            &["initial", "TaylorGreen3d"],
                            "TaylorGreen3d is a 3D field; use TaylorGreen2d in 2D".into(),
                        );
                    }
                    check_tg(*amplitude, *wavenumber)?;
                }
                InitialVorticity::VortexRing {
                    center,
                    axis,
                    radius,
                    core_radius,
                    circulation,
                } => {
                    if dim != 3 {
                        return err(
                            &["initial", "VortexRing"],
                            "VortexRing is a 3D field; this scene is 2D".into(),
                        );
                    }
                    if center.len() != 3 {
                        return err(&["initial", "center"], "needs 3 entries".into());
                    }
                    let norm = axis.iter().map(|a| a * a).sum::<f64>().sqrt();
                    if axis.len() != 3 || !(norm.is_finite() && norm > 0.0) {
                        return err(&["initial", "axis"], "needs 3 entries, not all zero".into());
                    }
                    for a in axis.iter_mut() {
                        *a /= norm;
                    }
                    if !(radius.is_finite() && *radius > 0.0) {
                        return err(
                            &["initial", "radius"],
                            format!("must be positive, got {radius}"),
                        );
                    }
                    if !(core_radius.is_finite() && *core_radius > 0.0) {
                        return err(
                            &["initial", "core_radius"],
                            format!("must be positive, got {core_radius}"),
                        );
                    }
                    if !circulation.is_finite() {
                        return err(&["initial", "circulation"], "must be finite".into());
                    }
                }
            }
        }
        if !(n.lambda.is_finite() && n.lambda > 0.0) {
            return err(
                &["numerics", "lambda"],
                format!("must be positive, got {}", n.lambda),
            );
        }
        if !(n.interface_cells.is_finite() && n.interface_cells > 0.0) {
            return err(
                &["numerics", "interface_cells"],
                format!("must be positive, got {}", n.interface_cells),
            );
        }
        let off = n.penalization_offset;
        if !(off.is_finite() && (0.0..=2.0 * n.interface_cells).contains(&off)) {
            return err(
                &["numerics", "penalization_offset"],
                format!(
                    "must be between 0 and twice interface_cells ({}), got {off}",
                    2.0 * n.interface_cells
                ),
            );
        }
        let extent = self.domain.extent.clone();
        let origin = self.domain.origin.clone().unwrap_or(vec![0.0; dim]);
        let rot_len = if dim == 2 { 1 } else { 3 };
        for (i, b) in self.bodies.iter_mut().enumerate() {
            if b.name.is_empty() {
                b.name = format!("body{i}");
            }
            let name = b.name.clone();
            let berr = |field: &'static str, m: String| {
                Err((vec!["bodies", field], format!("body `{name}`: {m}")))
            };
            if let Err(m) = b.shape.validate(dim) {
                return berr("shape", m);
            }
            if b.position.len() != dim || b.position.iter().any(|x| !x.is_finite()) {
                return berr("position", format!("needs {dim} finite entries"));
            }
            let bounded = !matches!(
                b.shape,
                crate::bodies::shapes::Shape::HalfSpace { .. }
                    | crate::bodies::shapes::Shape::Complement(_)
            );
            if bounded {
                for a in 0..dim {
                    let x = b.position[a];
                    if x < origin[a] || x > origin[a] + extent[a] {
                        return berr(
                            "position",
                            format!(
                                "the centre {:?} is outside the domain [{:?}, {:?}]",
                                b.position,
                                origin,
                                origin
                                    .iter()
                                    .zip(&extent)
                                    .map(|(o, e)| o + e)
                                    .collect::<Vec<_>>()
                            ),
                        );
                    }
                }
            }
            if let Some(d) = b.density
                && !(d.is_finite() && d > 0.0)
            {
                return berr("density", format!("must be positive, got {d}"));
            }
            if !b.rotation.is_empty() && b.rotation.len() != rot_len {
                return berr(
                    "rotation",
                    format!(
                        "needs {rot_len} entries (a rotation vector), got {}",
                        b.rotation.len()
                    ),
                );
            }
            if !b.velocity.is_empty() && b.velocity.len() != dim {
                return berr("velocity", format!("needs {dim} entries"));
            }
            if !b.angular_velocity.is_empty() && b.angular_velocity.len() != rot_len {
                return berr("angular_velocity", format!("needs {rot_len} entries"));
            }
            if let Some(k) = b.kappa
                && !(k.is_finite() && k >= 0.0)
            {
                return berr("kappa", format!("must be zero or positive, got {k}"));
            }
            if let BodyKind::Kinematic {
                velocity,
                angular_velocity,
                amplitude,
                frequency,
            } = &b.kind
            {
                if velocity.len() != dim {
                    return berr("velocity", format!("needs {dim} entries"));
                }
                if !angular_velocity.is_empty() && angular_velocity.len() != rot_len {
                    return berr("angular_velocity", format!("needs {rot_len} entries"));
                }
                if !amplitude.is_empty() && amplitude.len() != dim {
                    return berr("amplitude", format!("needs {dim} entries"));
                }
                if !(frequency.is_finite() && *frequency >= 0.0) {
                    return berr("frequency", "must be zero or positive".into());
                }
            }
        }
        if self.vacuum
            && !self
                .bodies
                .iter()
                .any(|b| matches!(b.kind, BodyKind::Dynamic))
        {
            return err(
                &["vacuum"],
                "vacuum mode moves dynamic bodies under gravity and contact; this scene has none"
                    .into(),
            );
        }
        if self.vacuum && !self.initial.is_empty() {
            return err(
                &["vacuum"],
                "vacuum mode has no flow, so an initial vorticity would be ignored; remove `initial`"
                    .into(),
            );
        }
        let c = &self.contact;
        if !(c.kappa.is_finite() && c.kappa >= 0.0) {
            return err(
                &["contact", "kappa"],
                format!("must be zero or positive, got {}", c.kappa),
            );
        }
        if let Some(e) = c.eps
            && !(e.is_finite() && e > 0.0)
        {
            return err(&["contact", "eps"], format!("must be positive, got {e}"));
        }
        if !(c.range.is_finite() && c.range >= 2.0) {
            return err(
                &["contact", "range"],
                format!("must be at least 2, got {}", c.range),
            );
        }
        for p in &c.pairs {
            for n in [&p.bodies.0, &p.bodies.1] {
                if !self.bodies.iter().any(|b| &b.name == n) {
                    return err(&["contact", "pairs"], format!("no body is named `{n}`"));
                }
            }
            if p.bodies.0 == p.bodies.1 {
                return err(
                    &["contact", "pairs"],
                    format!(
                        "a pair needs two different bodies, got `{}` twice",
                        p.bodies.0
                    ),
                );
            }
            if !(p.kappa.is_finite() && p.kappa >= 0.0) {
                return err(
                    &["contact", "kappa"],
                    format!("must be zero or positive, got {}", p.kappa),
                );
            }
        }
        if let Some(e) = self.output.every
            && !(e.is_finite() && e > 0.0)
        {
            return err(&["output", "every"], format!("must be positive, got {e}"));
        }
        if self.output.formats.is_empty() {
            return err(
                &["output", "formats"],
                "needs at least one format: [Vtk], [Hdf5] or [Vtk, Hdf5]".into(),
            );
        }
        if self.output.has_format(OutputFormat::Hdf5) && !cfg!(feature = "hdf5") {
            return err(
                &["output", "formats"],
                "Hdf5 output needs a tumble built with the `hdf5` feature (install the HDF5 \
                 library, e.g. `apt-get install libhdf5-dev`, then `cargo build --release \
                 --features hdf5`); this build writes only Vtk"
                    .into(),
            );
        }
        if let Some(e) = self.output.checkpoint_every
            && !(e.is_finite() && e > 0.0)
        {
            return err(
                &["output", "checkpoint_every"],
                format!("must be positive, got {e}"),
            );
        }
        Ok(())
    }
}

fn check_tg(amplitude: f64, wavenumber: f64) -> Result<(), (Vec<&'static str>, String)> {
    if !amplitude.is_finite() {
        return Err((vec!["initial", "amplitude"], "must be finite".into()));
    }
    if !(wavenumber.is_finite() && wavenumber > 0.0) {
        return Err((
            vec!["initial", "wavenumber"],
            format!("must be positive, got {wavenumber}"),
        ));
    }
    Ok(())
}

fn pad3(v: &[f64]) -> [f64; 3] {
    let mut out = [0.0; 3];
    for (o, x) in out.iter_mut().zip(v) {
        *o = *x;
    }
    out
}

/// Find the line of a field given by its path (`["fluid", "viscosity"]`): the first
/// occurrence of each key (as `key:` or `key(`) after the previous one. Falls back to the
/// deepest key found.
fn locate(text: &str, path: &[&str]) -> Option<usize> {
    let mut from = 0usize;
    let mut found = None;
    for key in path {
        match find_key(&text[from..], key) {
            Some(off) => {
                from += off;
                found = Some(from);
            }
            None => break,
        }
    }
    found.map(|pos| text[..pos].matches('\n').count() + 1)
}

/// The line of `key` in the `i`-th body (found after the body's `shape:` key, which every
/// body has; `shape` itself for `key == "shape"`).
fn body_key_line(text: &str, i: usize, key: &str) -> Option<usize> {
    let mut from = 0;
    let mut pos = None;
    for _ in 0..=i {
        let off = find_key(&text[from..], "shape")?;
        pos = Some(from + off);
        from += off + 5;
    }
    let mut pos = pos?;
    if key != "shape" {
        // The body's key may come before or after its shape: look back to the body's opening
        // parenthesis, then forwards.
        let start = text[..pos].rfind("(").unwrap_or(0);
        pos = start + find_key(&text[start..], key).unwrap_or(pos - start);
    }
    Some(text[..pos].matches('\n').count() + 1)
}

fn find_key(text: &str, key: &str) -> Option<usize> {
    let bytes = text.as_bytes();
    let mut start = 0;
    while let Some(off) = text[start..].find(key) {
        let pos = start + off;
        let before_ok = pos == 0 || !is_ident(bytes[pos - 1]);
        let rest = text[pos + key.len()..].trim_start();
        let after_ok = rest.starts_with(':') || rest.starts_with('(');
        let ident_end = text[pos + key.len()..]
            .bytes()
            .next()
            .is_none_or(|b| !is_ident(b));
        if before_ok && after_ok && ident_end {
            return Some(pos);
        }
        start = pos + key.len();
    }
    None
}

fn is_ident(b: u8) -> bool {
    b.is_ascii_alphanumeric() || b == b'_'
}

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: &str = r#"Scene(
    domain: (extent: [2.0, 2.0], origin: [-1.0, -1.0], cells: [32, 32]),
    fluid: (
        viscosity: 0.001,
    ),
    initial: [LambOseen(center: [0.0, 0.0], circulation: 1.0, core_radius: 0.1)],
)"#;

    #[test]
    fn good_scene_loads() {
        let s = Scene::parse(GOOD, "good.ron", "good").unwrap();
        assert_eq!(s.name, "good");
        assert_eq!(s.grid().n, [32, 32, 1]);
        assert_eq!(s.grid().h, 2.0 / 32.0);
    }

    #[test]
    fn negative_viscosity_names_line_and_field() {
        let text = GOOD.replace("0.001", "-1.0");
        let e = Scene::parse(&text, "bad.ron", "bad").unwrap_err();
        assert_eq!(e.line, Some(4));
        assert_eq!(e.field.as_deref(), Some("fluid.viscosity"));
    }

    #[test]
    fn unknown_field_names_line() {
        let text = GOOD.replace("viscosity:", "viscosty:");
        let e = Scene::parse(&text, "bad.ron", "bad").unwrap_err();
        assert_eq!(e.line, Some(4));
        assert!(e.message.contains("viscosty"), "{}", e.message);
    }
}
