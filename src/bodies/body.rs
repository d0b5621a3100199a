//! Rigid bodies as ECS entities, and the grid fields they make (density, χ, union level set).
//!
//! A body is an entity with a [`Body`] (id, name, kind), a [`RigidState`] (pose, velocities,
//! volume and inertia), a [`Material`], a [`BodyShape`] (its reference signed distance on a
//! local grid in body coordinates) and a [`GridPatch`] (φ and χ sampled on the part of the flow
//! grid it covers). Memory and work per body scale with the body's size, not the domain's,
//! except for unbounded shapes (walls), whose patch is the whole grid.

use crate::base::grid::Grid;
pub use crate::base::kernels::heaviside;
use crate::bodies::levelset::LocalLevelSet;
use bevy_ecs::prelude::*;
use glam::{DMat3, DQuat, DVec3};
use serde::{Deserialize, Serialize};

/// How a body moves.
#[derive(Deserialize, Serialize, Debug, Clone, PartialEq)]
#[serde(deny_unknown_fields)]
pub enum BodyKind {
    /// Moves with the mean motion of the fluid inside it (two-way coupled, eq. 7).
    Dynamic,
    /// Never moves (walls, floors, tanks).
    Static,
    /// Prescribed motion: velocity(t) = velocity + amplitude sin(2π frequency t), and a constant
    /// angular velocity.
    Kinematic {
        /// Constant part of the velocity, length/time (one entry per axis).
        velocity: Vec<f64>,
        /// Angular velocity, rad/time: 1 entry (about z) in 2D, 3 in 3D. Default: zero.
        #[serde(default)]
        angular_velocity: Vec<f64>,
        /// Amplitude of the oscillating part of the velocity, length/time. Default: zero.
        #[serde(default)]
        amplitude: Vec<f64>,
        /// Frequency of the oscillation, 1/time. Default: 0.
        #[serde(default)]
        frequency: f64,
    },
}

/// Identity and kind of a body.
#[derive(Component, Debug, Clone)]
pub struct Body {
    /// Index in the scene's body list.
    pub id: usize,
    /// Name from the scene.
    pub name: String,
    /// How it moves.
    pub kind: BodyKind,
}

impl Body {
    /// Whether the flow moves this body.
    pub fn is_dynamic(&self) -> bool {
        matches!(self.kind, BodyKind::Dynamic)
    }
    /// Whether it never moves.
    pub fn is_static(&self) -> bool {
        matches!(self.kind, BodyKind::Static)
    }
}

/// The rigid state of a body.
#[derive(Component, Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RigidState {
    /// Centre (the body frame's origin), world coordinates.
    pub center: DVec3,
    /// Orientation: body frame to world frame.
    pub orientation: DQuat,
    /// Translational velocity V.
    pub velocity: DVec3,
    /// Angular velocity Ω (only z is used in 2D).
    pub angular_velocity: DVec3,
    /// Volume (area in 2D) ∫χ, from the grid.
    pub volume: f64,
    /// Centroid of χ on the grid, ∫χx/∫χ: the point the rigid rotation is taken about.
    pub centroid: DVec3,
    /// Inertia tensor of the body at unit density about its centroid, world frame,
    /// ∫χ(|r|²I - rrᵀ).
    pub inertia: DMat3,
}

impl RigidState {
    /// The pose after `dt` at the current velocities: the centroid moves with V and the body
    /// turns about it by Ω dt (the orientation composed with rot(Ω dt), the frame's origin
    /// carried along).
    pub fn advanced(&self, dt: f64) -> RigidState {
        let q = DQuat::from_scaled_axis(self.angular_velocity * dt);
        let centroid = self.centroid + self.velocity * dt;
        RigidState {
            center: centroid + q * (self.center - self.centroid),
            orientation: (q * self.orientation).normalize(),
            centroid,
            ..*self
        }
    }
}

/// The rigid velocity ū of the previous step (V, Ω), kept by `rigid_update`: with the
/// current one it gives the body's acceleration, which the baroclinic term uses as the
/// acceleration of the fluid on the body's interface (no slip).
#[derive(Component, Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct PreviousVelocity {
    /// V of the previous step.
    pub velocity: DVec3,
    /// Ω of the previous step.
    pub angular_velocity: DVec3,
    /// The acceleration over the previous step, (V - V_prev)/Δt: a Newton-Euler body's
    /// virtual mass takes it as the next step's extrapolated acceleration
    /// ([`crate::bodies::coupling::VirtualMass`]). The contact's part is left out.
    pub acceleration: DVec3,
    /// The angular acceleration over the previous step, (Ω - Ω_prev)/Δt.
    pub angular_acceleration: DVec3,
}

/// Material of a body.
#[derive(Component, Debug, Clone, Copy, PartialEq)]
pub struct Material {
    /// Density ρ_i.
    pub density: f64,
}

/// The exact volume (area in 2D) of a body's solid, from its shape ([`ShapeGeometry::volume`];
/// 0 for an unbounded one). The grid's χ integrates to more (the smoothed step adds about
/// 0.39 (ε/a)² of a sphere's volume), so the mass of a body that moves by Newton-Euler is taken
/// from this.
///
/// [`ShapeGeometry::volume`]: crate::bodies::shapes::ShapeGeometry::volume
#[derive(Component, Debug, Clone, Copy, Default, PartialEq)]
pub struct ShapeVolume(pub f64);

/// The reference signed distance of a body, in body coordinates.
#[derive(Component, Debug, Clone)]
pub struct BodyShape {
    /// φ > 0 inside, sampled on a local grid (or analytic for unbounded shapes).
    pub level_set: LocalLevelSet,
}

/// φ and χ of one body on the flow grid, over the box of nodes it can affect.
///
/// The box is the body's own: `lo` is its first node *unwrapped* (an index that may be
/// negative or reach past `n - 1` when a moving body straddles the periodic box's boundary),
/// and patch node `(a, b, c)` sits at the unwrapped position `origin + (lo + (a, b, c)) h`,
/// next to the body, while it reads and writes grid node `(lo + (a, b, c)) mod n`
/// ([`GridPatch::grid_index`], [`GridPatch::row`]). Lever arms, moments and contact points
/// use the unwrapped position ([`GridPatch::pos`]); field access the wrapped index. A box is
/// never longer than `n` along an axis, so each grid node appears at most once in it.
#[derive(Component, Debug, Clone, Default)]
pub struct GridPatch {
    /// First node of the box (grid indices, unwrapped: may lie outside `0..n`).
    pub lo: [isize; 3],
    /// Node counts of the box (at most `n` per axis).
    pub dims: [usize; 3],
    /// φ at the box's nodes (x fastest).
    pub phi: Vec<f64>,
    /// χ = H(φ) at the box's nodes.
    pub chi: Vec<f64>,
    /// Whether the patch holds the current pose (static bodies are sampled once).
    pub sampled: bool,
    /// The body's whole box (`lo`, `dims` of the whole grid): on several processes a slab's
    /// patch holds only the box's planes in the slab (possibly none), while this is the same
    /// on every process (what the broad phase and the choice of the bodies in a step's sums
    /// read). Equal to (`lo`, `dims`) on one process.
    pub whole: ([isize; 3], [usize; 3]),
}

/// The grid nodes of one patch row along x: node `a` of the row is grid node
/// [`PatchRow::index`]`(a)`, wrapping once past the grid's last node along x.
#[derive(Debug, Clone, Copy)]
pub struct PatchRow {
    /// Grid index of the row's node at x index 0.
    base: usize,
    /// Wrapped x index of the row's first node.
    i0: usize,
    /// Nodes along x.
    nx: usize,
}

impl PatchRow {
    /// Grid index of the row's node `a`.
    #[inline(always)]
    pub fn index(&self, a: usize) -> usize {
        let i = self.i0 + a;
        self.base + if i >= self.nx { i - self.nx } else { i }
    }
}

impl GridPatch {
    /// Number of nodes.
    pub fn len(&self) -> usize {
        self.dims[0] * self.dims[1] * self.dims[2]
    }
    /// Whether the patch is empty (on a slab: holds none of the slab's nodes).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Whether plane `c` of the patch is one of `grid`'s (always, unless `grid` is a slab whose
    /// patch wraps round it: then the planes between its two ends are other processes').
    /// Loops over the patch skip the others' rows.
    #[inline]
    pub fn holds(&self, grid: &Grid, c: usize) -> bool {
        let k = (self.lo[2] + c as isize).rem_euclid(grid.nz_whole as isize) as usize;
        k >= grid.k0 && k < grid.k0 + grid.n[2]
    }
    /// Whether the body's whole box holds grid nodes (the same on every process).
    pub fn on_grid(&self) -> bool {
        self.whole.1.iter().all(|&d| d > 0)
    }
    /// Grid index (wrapped) along `axis` of the patch's node `a` on that axis. Along z the
    /// box wraps in the whole grid and the index is the slab's (a slab's patch holds only its
    /// own planes).
    #[inline(always)]
    pub fn wrapped(&self, grid: &Grid, axis: usize, a: usize) -> usize {
        if axis == 2 {
            (self.lo[2] + a as isize).rem_euclid(grid.nz_whole as isize) as usize - grid.k0
        } else {
            (self.lo[axis] + a as isize).rem_euclid(grid.n[axis] as isize) as usize
        }
    }
    /// Grid index of patch node `(a, b, c)`, wrapped into the periodic grid.
    #[inline]
    pub fn grid_index(&self, grid: &Grid, a: usize, b: usize, c: usize) -> usize {
        grid.idx(
            self.wrapped(grid, 0, a),
            self.wrapped(grid, 1, b),
            self.wrapped(grid, 2, c),
        )
    }
    /// The grid nodes of patch row `(b, c)` (see [`PatchRow`]).
    #[inline]
    pub fn row(&self, grid: &Grid, b: usize, c: usize) -> PatchRow {
        PatchRow {
            base: grid.idx(0, self.wrapped(grid, 1, b), self.wrapped(grid, 2, c)),
            i0: self.wrapped(grid, 0, 0),
            nx: grid.n[0],
        }
    }
    /// Unwrapped position of patch node `(a, b, c)`: next to the body, possibly outside the
    /// box (the node's periodic image); z is 0 in 2D. Equal to `grid.pos` of the node when
    /// the patch does not wrap.
    #[inline(always)]
    pub fn pos(&self, grid: &Grid, a: usize, b: usize, c: usize) -> [f64; 3] {
        patch_pos(grid, self.lo, a, b, c)
    }
    /// The position `x` of a grid node of this patch moved by whole box lengths into the
    /// patch's unwrapped window `[origin + lo h, origin + (lo + n) h)`: the image of the node
    /// that [`GridPatch::pos`] gives. Unchanged (bit for bit) when it already lies there.
    #[inline]
    pub fn unwrap(&self, grid: &Grid, x: DVec3) -> DVec3 {
        patch_unwrap(grid, self.lo, x)
    }
}

/// [`GridPatch::pos`] of a patch whose first node is `lo`.
#[inline(always)]
pub fn patch_pos(grid: &Grid, lo: [isize; 3], a: usize, b: usize, c: usize) -> [f64; 3] {
    let x = |axis: usize, a: usize| grid.origin[axis] + (lo[axis] + a as isize) as f64 * grid.h;
    [x(0, a), x(1, b), if grid.dim == 3 { x(2, c) } else { 0.0 }]
}

/// [`GridPatch::unwrap`] of a patch whose first node is `lo`.
#[inline]
pub fn patch_unwrap(grid: &Grid, lo: [isize; 3], mut x: DVec3) -> DVec3 {
    let ext = grid.extent();
    for a in 0..grid.dim {
        let lo = grid.origin[a] + lo[a] as f64 * grid.h - 0.5 * grid.h;
        if x[a] < lo {
            x[a] += ext[a];
        } else if x[a] >= lo + ext[a] {
            x[a] -= ext[a];
        }
    }
    x
}

/// Hydrodynamic force and torque on a body (from the penalization term), world frame.
#[derive(Component, Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Hydro {
    /// Force.
    pub force: DVec3,
    /// Torque about the centre.
    pub torque: DVec3,
}

/// Contact state of a body: its own κ, and the contact force and torque the collision
/// system found this step (world frame; torque about the χ-centroid).
#[derive(Component, Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct ContactState {
    /// This body's contact strength κ, length³/time²: its `kappa`, else the scene's
    /// `contact.kappa`; `None` if neither is given, the body then taking each pair's default
    /// ([`crate::bodies::contact::KappaDefault`]). A pair uses the mean of its bodies' values.
    pub kappa: Option<f64>,
    /// Contact force on the body this step.
    pub force: DVec3,
    /// Contact torque on the body this step, about its centroid.
    pub torque: DVec3,
    /// Contact potential energy of the body this step: the sum over its band of
    /// ρ_i κ/ε ζ(φ_i/ε) (E₁(d/ε) - E₁(range)) dV (zero where the force is cut off), whose
    /// rigid-motion gradient is the contact force; halved
    /// for a pair of dynamic bodies (each pair potential is shared by the two bodies).
    pub potential: f64,
}

/// Quadrature points of a body's contact band 0 < φ_i < ε, fixed in the body frame (material
/// points), with weights ζ(φ_i/ε)/ε dV: the surface measure the contact force (eq. 22) is
/// spread with. Because the points move with the body, the discrete contact force is exactly
/// the rigid-motion gradient of a discrete potential, whatever the body's pose on the grid.
#[derive(Component, Debug, Clone, Default)]
pub struct ContactPoints {
    /// Body-frame positions.
    pub points: Vec<DVec3>,
    /// φ_i at each point.
    pub phi: Vec<f64>,
    /// Weight ζ(φ_i/ε)/ε times the volume element.
    pub weights: Vec<f64>,
    /// Radius of a sphere about the body origin that holds the body (∞ if unbounded).
    pub radius: f64,
}

impl ContactPoints {
    /// Sample the band 0 < φ < `eps` of `level_set` on a body-frame lattice of spacing
    /// `spacing` (no points for unbounded shapes, or if `with_points` is false: the radius is
    /// still found).
    pub fn new(
        level_set: &LocalLevelSet,
        eps: f64,
        spacing: f64,
        dim: usize,
        with_points: bool,
    ) -> Self {
        let mut out = ContactPoints {
            radius: f64::INFINITY,
            ..Default::default()
        };
        let Some((lo, hi)) = level_set.bounds() else {
            return out;
        };
        out.radius = 0.0;
        // A lattice through the body origin, so a symmetric body gets a symmetric point set
        // (equal and opposite forces between mirror-image bodies).
        let first = |a: usize| (lo[a] / spacing).floor() as i64;
        let count = |a: usize| ((hi[a] / spacing).ceil() as i64 - first(a) + 1).max(0) as usize;
        let (nx, ny, nz) = (count(0), count(1), if dim == 3 { count(2) } else { 1 });
        let dv = spacing.powi(dim as i32);
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    let p = DVec3::new(
                        (first(0) + i as i64) as f64 * spacing,
                        (first(1) + j as i64) as f64 * spacing,
                        if dim == 3 {
                            (first(2) + k as i64) as f64 * spacing
                        } else {
                            0.0
                        },
                    );
                    let phi = level_set.phi(p);
                    if phi > -spacing {
                        out.radius = out.radius.max(p.length() + spacing);
                    }
                    let w = crate::bodies::contact::zeta(phi / eps) / eps * dv;
                    if with_points && w > 0.0 {
                        out.points.push(p);
                        out.phi.push(phi);
                        out.weights.push(w);
                    }
                }
            }
        }
        out
    }
}

/// Angular momentum ρ_i J Ω of a body moving in vacuum (the flow solver off), world frame;
/// `None` until the first step sets it.
#[derive(Component, Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct FreeMotion {
    /// ρ_i J Ω, kept so a free body's rotation conserves angular momentum as J turns.
    pub angular_momentum: Option<DVec3>,
}

/// A body's surface in its own frame, for viewing (see [`crate::bodies::surface`]): the
/// output places it at the body's pose (world = centre + orientation · p).
#[derive(Component, Debug, Clone, Default)]
pub struct BodySurface(pub crate::bodies::surface::SurfaceMesh);

/// Grid fields made by the bodies.
#[derive(Resource, Debug, Clone)]
pub struct BodyFields {
    /// Density ρ = ρ_P (1 - Σχ_i) + Σ ρ_i χ_i (eq. 19), with ρ_P = `rho_phase`.
    pub rho: Vec<f64>,
    /// The density of the fluid phases alone, ρ_P (without the bodies): ρ_F unless a plugin
    /// writes a stratification or a second phase here (before the `density` system, e.g. in
    /// `PhysicsSet::LevelSets`). Gravity acts on it through the pressure projection; a
    /// body's weight beyond the fluid it displaces, (ρ_i - ρ_P) χ_i g, acts on its rigid
    /// velocity.
    pub rho_phase: Vec<f64>,
    /// Σ χ_i.
    pub chi: Vec<f64>,
    /// Union level set max_i φ_i (φ > 0 inside some body); -∞ where no body's patch reaches
    /// (the output clamps it at [`band`]'s edge, see `io::snapshots`).
    pub phi: Vec<f64>,
    /// Velocity change made by the penalization this step (scratch, `dim` components).
    pub du: Vec<Vec<f64>>,
    /// The body whose level set is the largest at each node (its `Body::id`), [`NO_BODY`]
    /// where no body's patch reaches.
    pub owner: Vec<u32>,
    /// Per body id: the rigid acceleration field's parameters this step (scratch of the
    /// baroclinic system, sized at spawn).
    pub rigid_accel: Vec<RigidAccel>,
}

/// No body at this node.
pub const NO_BODY: u32 = u32::MAX;

/// The acceleration of a rigid motion: a(x) = A + α × r + Ω × (Ω × r), r = x - x_G.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct RigidAccel {
    /// Acceleration of the centroid A.
    pub linear: DVec3,
    /// Angular acceleration α.
    pub angular: DVec3,
    /// Angular velocity Ω.
    pub omega: DVec3,
    /// Centroid x_G.
    pub centroid: DVec3,
    /// The body's density as the density field counts it (the fluid's for static bodies).
    pub density: f64,
    /// The first node of the body's patch (see [`GridPatch`]), which places a grid node at
    /// its image next to the body ([`RigidAccel::at_node`]).
    pub patch_lo: [isize; 3],
}

impl RigidAccel {
    /// The acceleration at `x`.
    #[inline]
    pub fn at(&self, x: DVec3) -> DVec3 {
        let r = x - self.centroid;
        self.linear + self.angular.cross(r) + self.omega.cross(self.omega.cross(r))
    }

    /// The acceleration at grid node position `x` (inside the box), taken at the node's image
    /// in the body's patch (a body straddling the periodic boundary owns nodes on both
    /// sides of the box).
    #[inline]
    pub fn at_node(&self, grid: &Grid, x: DVec3) -> DVec3 {
        self.at(patch_unwrap(grid, self.patch_lo, x))
    }
}

impl BodyFields {
    /// Fields for `grid` and `n_bodies` bodies, filled with the fluid's density.
    pub fn new(grid: &Grid, rho_fluid: f64, n_bodies: usize) -> Self {
        BodyFields {
            rho: vec![rho_fluid; grid.len()],
            rho_phase: vec![rho_fluid; grid.len()],
            chi: vec![0.0; grid.len()],
            phi: vec![f64::NEG_INFINITY; grid.len()],
            du: vec![vec![0.0; grid.len()]; grid.dim],
            owner: vec![NO_BODY; grid.len()],
            rigid_accel: vec![RigidAccel::default(); n_bodies],
        }
    }
}

/// The most nodes along an axis a body's grid box can span in any orientation, on a grid of
/// spacing `h`: its bounding sphere (the reference level set's box, band included) across, and
/// a node of rounding on each side and one of margin; `None` for an unbounded shape.
pub fn box_span(level_set: &crate::bodies::levelset::LocalLevelSet, h: f64) -> Option<usize> {
    level_set
        .bounds()
        .map(|(lo, hi)| ((hi - lo).length() / h).ceil() as usize + 3)
}

/// A 3-vector from a scene list (missing entries are zero).
pub fn vec3(v: &[f64]) -> DVec3 {
    DVec3::new(
        v.first().copied().unwrap_or(0.0),
        v.get(1).copied().unwrap_or(0.0),
        v.get(2).copied().unwrap_or(0.0),
    )
}

/// An angular vector from a scene list: 1 entry is about z (2D), 3 entries are a vector.
pub fn angular3(v: &[f64]) -> DVec3 {
    match v.len() {
        0 => DVec3::ZERO,
        1 => DVec3::new(0.0, 0.0, v[0]),
        _ => vec3(v),
    }
}

/// The orientation a scene's rotation vector gives (axis times angle; 1 entry in 2D, 3 in
/// 3D): identity for a zero or empty vector.
pub fn rotation(v: &[f64]) -> glam::DQuat {
    let r = angular3(v);
    if r.length() > 0.0 {
        glam::DQuat::from_scaled_axis(r)
    } else {
        glam::DQuat::IDENTITY
    }
}

/// The band (length) kept around each body's reference level set: the collision and
/// interface computations need φ a few cells outside the body.
pub fn band(grid: &Grid) -> f64 {
    6.0 * grid.h
}

/// The kinematic velocity of a body at time `t`.
pub fn kinematic_velocity(kind: &BodyKind, t: f64) -> Option<(DVec3, DVec3)> {
    match kind {
        BodyKind::Kinematic {
            velocity,
            angular_velocity,
            amplitude,
            frequency,
        } => {
            let osc = (2.0 * std::f64::consts::PI * frequency * t).sin();
            Some((
                vec3(velocity) + osc * vec3(amplitude),
                angular3(angular_velocity),
            ))
        }
        _ => None,
    }
}
