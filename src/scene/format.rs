//! The scene file format: the serde structs a RON scene deserialises into, each field with its
//! unit and default. Nothing here checks values; [`crate::scene::check`] does, and only a
//! [`crate::scene::ValidScene`] reaches the engine. The `numerics` section ([`Numerics`]) is
//! defined with the engine's other typed parameters in `base/params.rs`, so that the engine's
//! `Params` holds it as it is.

pub use crate::base::params::{Experimental, Numerics};
use crate::bodies::BodyKind;
use serde::{Deserialize, Serialize};

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
    /// A free surface: the liquid (density `fluid.density`) fills the regions given and a gas
    /// fills the rest of the box (paper section 5, Fig. 10). Default: none (one fluid).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub free_surface: Option<FreeSurfaceSpec>,
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
    /// Body generators: many bodies on a lattice or packed at random in a region, each
    /// `(name: "grain", layout: Random(..) or Lattice(..), seed: .., shapes: [..], ...)` (see
    /// [`crate::scene::generate::Generator`]). They are expanded when the scene is loaded into
    /// ordinary bodies appended after `bodies`, so a loaded scene holds them in `bodies` and
    /// this list empty. Default: none.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub generators: Vec<crate::scene::generate::Generator>,
    /// Contact between bodies (the level-set collision model, eqs. 20-22).
    #[serde(default)]
    pub contact: Contact,
    /// Vacuum mode: the flow solver is off and gravity and contact act on the bodies directly
    /// (paper Fig. 1 and Fig. 9). Default: false.
    #[serde(default)]
    pub vacuum: bool,
    /// The settings of plugins beyond the built-in ones, by plugin name:
    /// `plugins: {"passive_scalar": (kappa: 1e-3)}`. Each section is checked by the plugin of
    /// its name (see `crate::schedule::Plugin::section`) when the simulation is set up; a
    /// section that no plugin of the simulation reads is an error. Default: none.
    #[serde(default, skip_serializing_if = "std::collections::BTreeMap::is_empty")]
    pub plugins: std::collections::BTreeMap<String, PluginSection>,
    /// Directory that relative mesh paths are resolved against (the scene file's).
    #[serde(skip)]
    pub base_dir: std::path::PathBuf,
}

/// A plugin's section of a scene, kept as its RON text until the plugin reads it.
#[derive(Deserialize, Serialize, Debug, Clone)]
#[serde(transparent)]
pub struct PluginSection(pub Box<ron::value::RawValue>);

impl PluginSection {
    /// The section's RON text.
    pub fn text(&self) -> &str {
        self.0.get_ron()
    }
}

impl PartialEq for PluginSection {
    fn eq(&self, other: &Self) -> bool {
        self.text() == other.text()
    }
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
    /// This body's contact strength κ, length³/time² (≥ 0; see `contact.kappa`): a pair of
    /// bodies uses the mean of their two values unless `contact.pairs` names the pair, a body
    /// without one taking the pair's default. Default: `contact.kappa`.
    #[serde(default)]
    pub kappa: Option<f64>,
}

/// The level-set contact model (paper eqs. 20-22): on the inner band of body i, a force
/// density ρ_i κ_ij/ε ζ(φ_i/ε) e^{-d/ε}/d pushing i away from body j along -∇φ_j, with
/// d = -φ_j the distance to j.
#[derive(Deserialize, Serialize, Debug, Clone, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct Contact {
    /// Strength κ of the repulsion for every pair, length³/time² (≥ 0; 0 turns contact off).
    /// The paper's 1D model ẍ = (κ/x) e^{-x/ε} makes κ a squared velocity, but spread over a
    /// body's surface (ζ/ε is a surface measure) and divided by its mass, the force gains a
    /// length: a body's acceleration is κ times an area over a volume times e^{-d/ε}/d, so κ
    /// scales as length³/time² (a scene rewritten in cm from m needs κ × 10⁶). The paper's
    /// values, in its cgs units: 30 (2D disk on a wall), 25 (two spheres), 5 (in vacuum).
    /// Default: made of the scene's own scales, so the same scene in other units moves the
    /// same: κ = C L² max(|g|, U²/ε) for each pair, with L the equivalent radius (of the disk
    /// or ball of the same area or volume) of the pair's smaller dynamic body (static,
    /// kinematic and unbounded bodies do not count: against a wall a body uses its own; a pair
    /// without a bounded dynamic body gets 0), C = 3 in 3D and 2 in 2D, g the gravity, U the
    /// fastest a body can meet another (initial speeds of the dynamic and kinematic bodies,
    /// plus with the flow on the background velocity and the initial vortices' speeds, plus in
    /// vacuum the speed of a fall from the body's start to the bottom of the domain) and ε the
    /// contact range. With |g| a resting body holds its weight at a gap of about ε/2; with
    /// U²/ε a body arriving at speed U stops about ε short. The paper's cases in fluid come out at their own values (2D disk
    /// of radius 0.125, g = 980: 30.6 against 30; spheres of radius 0.083: 20.3 against 25).
    /// A scene without gravity or any speed has no scale: it must give κ if a dynamic body can
    /// touch another body.
    pub kappa: Option<f64>,
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
            kappa: None,
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
    /// Strength κ for this pair, length³/time² (≥ 0; see `contact.kappa`).
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

/// A free surface between the liquid (`fluid.density`) and a lighter gas.
///
/// Written as `free_surface: Some((gas_density: 0.01, liquid: [Below(height: 0.5)]))`.
/// The vertical is the last axis (y in 2D, z in 3D); the box must be closed along it by
/// static walls (a floor and a ceiling), or the periodic box would stack the liquid on the gas.
#[derive(Deserialize, Serialize, Debug, Clone, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FreeSurfaceSpec {
    /// Density of the gas, mass per volume: positive and below `fluid.density`. Required.
    pub gas_density: f64,
    /// The liquid at t = 0: the union of these regions. Required, at least one.
    pub liquid: Vec<LiquidRegion>,
}

/// A region filled with liquid at t = 0.
#[derive(Deserialize, Serialize, Debug, Clone, PartialEq)]
#[serde(deny_unknown_fields)]
pub enum LiquidRegion {
    /// A pool: the liquid below the surface z = height + amplitude cos(2π (x - x0) / wavelength),
    /// z the vertical (last) axis, x the first axis measured from the box's origin x0.
    Below {
        /// Mean height of the surface, length (a coordinate along the vertical axis).
        height: f64,
        /// Amplitude of the surface's cosine wave, length. Default: 0 (flat).
        #[serde(default)]
        amplitude: f64,
        /// Wavelength of the wave along the first axis, length (> 0 when `amplitude` is not
        /// 0). Default: the box's extent along the first axis.
        #[serde(default)]
        wavelength: Option<f64>,
    },
    /// A heavy layer on top: the liquid above the surface z = height + amplitude
    /// cos(2π (x - x0) / wavelength) (a Rayleigh-Taylor set-up).
    Above {
        /// Mean height of the surface, length.
        height: f64,
        /// Amplitude of the surface's cosine wave, length. Default: 0 (flat).
        #[serde(default)]
        amplitude: f64,
        /// Wavelength of the wave along the first axis, length. Default: the box's extent
        /// along the first axis.
        #[serde(default)]
        wavelength: Option<f64>,
    },
    /// A shape filled with liquid (a drop, a column), centred at `position` (one entry per
    /// axis), unrotated.
    Shape {
        /// The shape (any body shape but `Mesh`; `Complement` fills everything outside it).
        shape: crate::bodies::shapes::Shape,
        /// Where its centre is, length.
        position: Vec<f64>,
    },
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

/// The default `output.checkpoint_wall`, seconds: a checkpoint every 15 minutes of wall time.
pub const DEFAULT_CHECKPOINT_WALL: f64 = 900.0;

/// What is written and how often.
#[derive(Deserialize, Serialize, Debug, Clone, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct Output {
    /// Simulated time between field snapshots, time units; `None` writes only the first and
    /// the last. With a `Fixed` step a snapshot is written after the first step at or after
    /// each output time and carries that step's time, so the run does not depend on this
    /// interval; an `Adaptive` step is shortened to land on each output time (see
    /// `TimeStep`). Default: None.
    pub every: Option<f64>,
    /// Fields in each snapshot. Default: `[Omega, Velocity]`.
    pub fields: Vec<FieldName>,
    /// Output directory; `tumble run --out` overrides it. Default: `runs/<name>`.
    pub dir: Option<String>,
    /// File formats of the field snapshots: `Vtk` (`fields_NNNNNN.vti` + `fields.pvd`) and/or
    /// `Hdf5` (`fields_NNNNNN.h5` + `fields.xmf`, and the body and contact series in
    /// `series.h5`; needs a build with `--features hdf5`). At least one. Default: `[Vtk]`.
    pub formats: Vec<OutputFormat>,
    /// Simulated time between checkpoints (`checkpoint_NNNNNN.bin` in the run directory,
    /// named by step, the latest `checkpoints_kept` kept; `tumble run --restart DIR`
    /// continues from the latest), time units; `tumble run
    /// --checkpoint-every` overrides it. `None` writes a checkpoint only when the run is
    /// interrupted (Ctrl-C, SIGTERM), and those of `checkpoint_wall`. Default: None.
    pub checkpoint_every: Option<f64>,
    /// Wall-clock seconds between checkpoints: one is written after the first step that ends
    /// this long after the run's start (or restart) or its last checkpoint, so a run killed
    /// without warning (SIGKILL, the out-of-memory killer, a batch system's time limit, a
    /// reboot) loses at most about this much work; `tumble run --restart DIR` continues from
    /// the newest. A run that wrote one also writes one at its end. Kept as `checkpoints_kept`
    /// says, next to those of `checkpoint_every`; `tumble run --checkpoint-wall S` overrides
    /// it. `None` (or `--checkpoint-wall 0`) turns it off. Default: 900 (15 minutes).
    pub checkpoint_wall: Option<f64>,
    /// How many checkpoints are kept in the run directory (`checkpoint_NNNNNN.bin`, named by
    /// step; older ones that tumble wrote are deleted once a newer one is complete), ≥ 1.
    /// Default: 2.
    pub checkpoints_kept: usize,
    /// Floating-point precision of the field snapshots' arrays (VTK and HDF5): `Single`
    /// (32-bit, about 7 significant digits, half the size) or `Double` (64-bit, the values
    /// exactly as computed). Checkpoints and the CSV time series are always exact. Default:
    /// Single.
    pub precision: Precision,
    /// Names of the scene's units, a note for the plots' axis labels only (no number depends
    /// on it): `units: (length: "cm", time: "s", mass: "g")` labels the axes "t [s]",
    /// "height [cm]", "velocity [cm/s]". Default: none (the labels say "(scene units)").
    #[serde(skip_serializing_if = "Option::is_none")]
    pub units: Option<Units>,
}

/// The names of a scene's units (`output.units`), for labels: each a short non-empty text such
/// as "cm", "s" or "g". An axis whose unit needs a name that is not given says "(scene units)".
#[derive(Deserialize, Serialize, Debug, Clone, PartialEq, Default)]
#[serde(deny_unknown_fields, default)]
pub struct Units {
    /// Name of the length unit (e.g. "m", "cm"). Default: none.
    pub length: Option<String>,
    /// Name of the time unit (e.g. "s"). Default: none.
    pub time: Option<String>,
    /// Name of the mass unit (e.g. "kg", "g"). Default: none.
    pub mass: Option<String>,
}

/// Floating-point precision of the arrays in field snapshots (`output.precision`).
#[derive(Deserialize, Serialize, Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Precision {
    /// 32-bit floats (`Float32`).
    #[default]
    Single,
    /// 64-bit floats (`Float64`).
    Double,
}

impl Precision {
    /// Bytes per value: 4 or 8.
    pub fn bytes(self) -> usize {
        match self {
            Precision::Single => 4,
            Precision::Double => 8,
        }
    }
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
            checkpoint_wall: Some(DEFAULT_CHECKPOINT_WALL),
            checkpoints_kept: 2,
            precision: Precision::Single,
            units: None,
        }
    }
}

impl Scene {
    /// Serialise back to RON (the scene as run, written into the run directory).
    pub fn to_ron(&self) -> String {
        ron::ser::to_string_pretty(self, ron::ser::PrettyConfig::default())
            .unwrap_or_else(|e| format!("// could not serialise the scene: {e}\n"))
    }

    /// Number of space dimensions (2 or 3).
    pub fn dim(&self) -> usize {
        self.domain.extent.len()
    }

    /// Gravity as a 3-vector (zeros where not given).
    pub fn gravity(&self) -> [f64; 3] {
        pad3(&self.fluid.gravity)
    }

    /// Background velocity as a 3-vector.
    pub fn background_velocity(&self) -> [f64; 3] {
        pad3(&self.fluid.background_velocity)
    }
}

fn pad3(v: &[f64]) -> [f64; 3] {
    let mut out = [0.0; 3];
    for (o, x) in out.iter_mut().zip(v) {
        *o = *x;
    }
    out
}
