//! Body generators (`generators: [...]` in a scene): many bodies placed without listing each,
//! on a lattice or as a random non-overlapping packing in a region, expanded when the scene is
//! loaded into ordinary [`BodySpec`]s appended after the listed bodies.
//!
//! The expansion is deterministic for a given `seed`: the random numbers come from ChaCha8
//! (`rand_chacha`), a generator whose output for a seed is fixed by its specification and
//! kept stable by the crate across versions, machines and thread counts (the expansion runs on
//! one thread), and every draw is turned into a number by integer arithmetic and one exact
//! scaling (no platform-dependent function), so a scene gives the same bodies everywhere.
//!
//! Shapes and list-valued densities are given out in equal shares (entry `k` of a list of `n`
//! gets `count / n` bodies, the first `count % n` entries one more) in a random order, so the
//! counts per shape and density are exact; sizes (`scale`), range-valued densities and
//! orientations are drawn per body.
//!
//! A random packing samples centres uniformly in the region and rejects one whose bounding
//! sphere, widened by `gap`, meets the bounding sphere of a body already placed (listed or
//! generated), sticks out of the region, or reaches into an unbounded static body (a wall:
//! its signed distance at the centre must be at least the radius plus the gap). Bodies are
//! placed from the largest to the smallest, each with at most [`MAX_ATTEMPTS`] tries, and a
//! hash grid of the placed spheres keeps each try O(1), so a packing costs O(count) tries.

use super::error::{Check, Issue, Seg, fail};
use super::format::BodySpec;
use crate::bodies::BodyKind;
use crate::bodies::shapes::Shape;
use glam::{DQuat, DVec3};
use rand_chacha::ChaCha8Rng;
use rand_core::{RngCore, SeedableRng};
use serde::{Deserialize, Serialize};
use std::collections::HashMap;
use std::path::Path;

/// How many positions a random packing tries for one body before it gives up.
pub const MAX_ATTEMPTS: usize = 10_000;

/// The most bodies one generator may make (a guard against a mistyped count).
pub const MAX_GENERATED: usize = 1_000_000;

/// A generator: many bodies of the given shapes, densities and orientations, placed by its
/// `layout`. Written in a scene as
/// `(name: "grain", layout: Random(region: (min: [..], max: [..]), count: 100), shapes: [..])`.
#[derive(Deserialize, Serialize, Debug, Clone, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Generator {
    /// Prefix of the bodies' names: body `k` of this generator (from 0) is `<name><k>`.
    /// Default: `gen<index>_` (the generator's index in the list).
    #[serde(default)]
    pub name: String,
    /// Where the bodies go: `Random(..)` or `Lattice(..)`. Required.
    pub layout: Layout,
    /// Seed of the random draws (shapes' order, sizes, densities, orientations, positions),
    /// any whole number; the same seed gives the same bodies. Default: 0.
    #[serde(default)]
    pub seed: u64,
    /// The shapes, each given to an equal share of the bodies (bounded shapes only: no
    /// `HalfSpace` or `Complement`). Required, at least one.
    pub shapes: Vec<Shape>,
    /// Size factor range (dimensionless, > 0): each body's shape has every length multiplied
    /// by a factor drawn uniformly in `[min, max]` (a mesh's `scale` too). Default: 1 (no
    /// change).
    #[serde(default)]
    pub scale: Option<Range>,
    /// Densities, mass per volume (> 0): one value, a list (each value given to an equal
    /// share of the bodies) or a range `(min: .., max: ..)` (drawn uniformly). Default: the
    /// fluid's density.
    #[serde(default)]
    pub densities: Option<Values>,
    /// Orientation of each body: `None` (the shape's own axes) or `Random` (uniform over
    /// rotations in 3D, a uniform angle in 2D). Default: None.
    #[serde(default)]
    pub rotation: Orientation,
    /// How the bodies move. Default: Dynamic.
    #[serde(default = "dynamic")]
    pub kind: BodyKind,
    /// Every body's contact strength κ, length³/time² (≥ 0; see `bodies[..].kappa`).
    /// Default: `contact.kappa`.
    #[serde(default)]
    pub kappa: Option<f64>,
}

fn dynamic() -> BodyKind {
    BodyKind::Dynamic
}

/// Where a generator's bodies go.
#[derive(Deserialize, Serialize, Debug, Clone, PartialEq)]
#[serde(deny_unknown_fields)]
pub enum Layout {
    /// A random packing: `count` bodies with centres uniform in `region`, none overlapping
    /// another's bounding sphere (plus `gap`) and each bounding sphere inside the region.
    Random {
        /// The box the bodies (their bounding spheres) must lie in, length units; inside the
        /// domain. Required.
        region: Region,
        /// How many bodies, ≥ 1. Required.
        count: usize,
        /// Least distance between two bodies' bounding spheres, and between a bounding
        /// sphere and a wall, length (≥ 0). Default: 0.
        #[serde(default)]
        gap: f64,
    },
    /// A lattice: body `k` sits at `start + (i, j, l) * spacing` with `i` running fastest,
    /// `0 <= i < counts[0]` and so on (the bodies are numbered x first, then y, then z).
    Lattice {
        /// Centre of the first body, length units (one entry per axis). Required.
        start: Vec<f64>,
        /// Distance between neighbouring centres along each axis, length (> 0). Required.
        spacing: Vec<f64>,
        /// Number of bodies along each axis (≥ 1 each). Required.
        counts: Vec<usize>,
    },
}

/// An axis-aligned box `[min, max]`, length units.
#[derive(Deserialize, Serialize, Debug, Clone, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Region {
    /// Lower corner (one entry per axis).
    pub min: Vec<f64>,
    /// Upper corner (one entry per axis), above `min` on every axis.
    pub max: Vec<f64>,
}

/// A range of numbers `(min: .., max: ..)`, drawn uniformly; `min <= max`.
#[derive(Deserialize, Serialize, Debug, Clone, Copy, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Range {
    /// Smallest value.
    pub min: f64,
    /// Largest value.
    pub max: f64,
}

/// Values given to a generator's bodies: `1.5`, `[0.5, 2.0]` or `(min: 0.5, max: 2.0)`.
#[derive(Deserialize, Serialize, Debug, Clone, PartialEq)]
#[serde(untagged)]
pub enum Values {
    /// Every body gets this value.
    One(f64),
    /// Each value goes to an equal share of the bodies.
    List(Vec<f64>),
    /// Drawn uniformly in the range for each body.
    Range(Range),
}

/// A generated body's orientation.
#[derive(Deserialize, Serialize, Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Orientation {
    /// No rotation: the shape's axes along the domain's.
    #[default]
    None,
    /// Uniform over rotations (3D), a uniform angle about z (2D).
    Random,
}

/// Which bodies of the scene's list a generator made: `bodies[start..end]`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Span {
    /// The generator's index in `generators`.
    pub generator: usize,
    /// First body index.
    pub start: usize,
    /// One past the last.
    pub end: usize,
}

/// The seeded random numbers of one generator.
pub struct Draw(ChaCha8Rng);

impl Draw {
    /// The stream of `seed` (ChaCha8).
    pub fn new(seed: u64) -> Self {
        Draw(ChaCha8Rng::seed_from_u64(seed))
    }

    /// Uniform in [0, 1): the top 53 bits of a 64-bit draw, scaled exactly.
    fn unit(&mut self) -> f64 {
        (self.0.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Uniform in [a, b].
    fn between(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.unit()
    }

    /// Uniform whole number in [0, n), n ≥ 1 (multiply-shift, no platform dependence).
    fn below(&mut self, n: usize) -> usize {
        ((self.0.next_u64() as u128 * n as u128) >> 64) as usize
    }

    /// `values` shuffled (Fisher-Yates).
    fn shuffle<T>(&mut self, values: &mut [T]) {
        for i in (1..values.len()).rev() {
            let j = self.below(i + 1);
            values.swap(i, j);
        }
    }
}

/// `count` indices into a list of `n`, each index `count / n` times (the first `count % n`
/// once more), in a random order.
pub fn shares(count: usize, n: usize, draw: &mut Draw) -> Vec<usize> {
    let mut v: Vec<usize> = (0..count).map(|k| k % n).collect();
    draw.shuffle(&mut v);
    v
}

/// `shape` with every length multiplied by `s`.
pub fn scaled(shape: &Shape, s: f64) -> Shape {
    let m3 = |a: &[f64; 3]| a.map(|x| x * s);
    let m2 = |a: &[f64; 2]| a.map(|x| x * s);
    match shape {
        Shape::Sphere { radius } => Shape::Sphere { radius: radius * s },
        Shape::Ellipsoid { radii } => Shape::Ellipsoid { radii: m3(radii) },
        Shape::Box { half_extents } => Shape::Box {
            half_extents: m3(half_extents),
        },
        Shape::Cylinder {
            radius,
            half_height,
        } => Shape::Cylinder {
            radius: radius * s,
            half_height: half_height * s,
        },
        Shape::Capsule {
            radius,
            half_height,
        } => Shape::Capsule {
            radius: radius * s,
            half_height: half_height * s,
        },
        Shape::HalfSpace { normal, offset } => Shape::HalfSpace {
            normal: *normal,
            offset: offset * s,
        },
        Shape::Disk { radius } => Shape::Disk { radius: radius * s },
        Shape::Ellipse { radii } => Shape::Ellipse { radii: m2(radii) },
        Shape::Rectangle { half_extents } => Shape::Rectangle {
            half_extents: m2(half_extents),
        },
        Shape::Complement(inner) => Shape::Complement(Box::new(scaled(inner, s))),
        Shape::Mesh { file, scale } => Shape::Mesh {
            file: file.clone(),
            scale: scale * s,
        },
    }
}

/// Radius about the body's origin of a sphere holding the built shape, `None` if unbounded.
fn bounding_radius(shape: &Shape, base_dir: &Path) -> Result<Option<f64>, String> {
    let g = shape.build(base_dir)?;
    Ok(g.bounds().map(|(lo, hi)| {
        (0..3)
            .map(|k| lo[k].abs().max(hi[k].abs()).powi(2))
            .sum::<f64>()
            .sqrt()
    }))
}

fn check_range(path: &[&'static str], r: &Range, positive: bool) -> Check {
    let ok = |x: f64| x.is_finite() && (!positive || x > 0.0);
    if !ok(r.min) || !ok(r.max) {
        let what = if positive { "positive" } else { "finite" };
        return fail(
            path,
            format!("min and max must be {what}, got ({}, {})", r.min, r.max),
        );
    }
    if r.min > r.max {
        return fail(
            path,
            format!(
                "min ({}) is above max ({}); write (min: {}, max: {})",
                r.min, r.max, r.max, r.min
            ),
        );
    }
    Ok(())
}

/// A `Random` layout: a count from 1 to [`MAX_GENERATED`], a gap not negative, and a region
/// of `dim` finite entries, not empty, inside the domain `[lo, hi]`.
fn check_random(
    region: &Region,
    count: usize,
    gap: f64,
    dim: usize,
    lo: &[f64],
    hi: &[f64],
) -> Check {
    let at = |k: &'static str, m: String| fail(&["layout", "Random", k], m);
    if count == 0 {
        return at(
            "count",
            "must be at least 1 (leave the generator out for none)".into(),
        );
    }
    if count > MAX_GENERATED {
        return at(
            "count",
            format!("at most {MAX_GENERATED} bodies per generator, got {count}"),
        );
    }
    if !(gap.is_finite() && gap >= 0.0) {
        return at("gap", format!("must be zero or positive, got {gap}"));
    }
    for (k, v) in [("min", &region.min), ("max", &region.max)] {
        if v.len() != dim || v.iter().any(|x| !x.is_finite()) {
            return fail(
                &["layout", "Random", "region", k],
                format!("needs {dim} finite entries, got {v:?}"),
            );
        }
    }
    if let Some(a) = (0..dim).find(|&a| region.min[a] >= region.max[a]) {
        return at(
            "region",
            format!(
                "min[{a}] = {} must be below max[{a}] = {}",
                region.min[a], region.max[a]
            ),
        );
    }
    if (0..dim).any(|a| region.min[a] < lo[a] || region.max[a] > hi[a]) {
        return at(
            "region",
            format!(
                "the region [{:?}, {:?}] is not inside the domain [{lo:?}, {hi:?}]",
                region.min, region.max
            ),
        );
    }
    Ok(())
}

/// A `Lattice` layout: `dim` finite starts, positive spacings and counts of at least 1, at
/// most [`MAX_GENERATED`] bodies, all inside the domain `[lo, hi]`.
fn check_lattice(
    start: &[f64],
    spacing: &[f64],
    counts: &[usize],
    dim: usize,
    lo: &[f64],
    hi: &[f64],
) -> Check {
    let at = |k: &'static str, m: String| fail(&["layout", "Lattice", k], m);
    if start.len() != dim || start.iter().any(|x| !x.is_finite()) {
        return at(
            "start",
            format!("needs {dim} finite entries, got {start:?}"),
        );
    }
    if spacing.len() != dim || spacing.iter().any(|x| !(x.is_finite() && *x > 0.0)) {
        return at(
            "spacing",
            format!("needs {dim} positive entries, got {spacing:?}"),
        );
    }
    if counts.len() != dim || counts.contains(&0) {
        return at(
            "counts",
            format!("needs {dim} entries of at least 1, got {counts:?}"),
        );
    }
    let total = counts.iter().try_fold(1usize, |a, &n| a.checked_mul(n));
    if total.is_none_or(|n| n > MAX_GENERATED) {
        return at(
            "counts",
            format!("at most {MAX_GENERATED} bodies per generator, got {counts:?}"),
        );
    }
    for a in 0..dim {
        let last = start[a] + (counts[a] - 1) as f64 * spacing[a];
        if start[a] < lo[a] || last > hi[a] {
            return at(
                "start",
                format!(
                    "the lattice runs from {} to {last} along axis {a}, outside the \
                     domain [{}, {}]",
                    start[a], lo[a], hi[a]
                ),
            );
        }
    }
    Ok(())
}

impl Generator {
    /// Check the values that do not depend on other bodies, in a `dim`-dimensional scene in
    /// the box `[lo, hi]`.
    fn check(&self, dim: usize, lo: &[f64], hi: &[f64]) -> Check {
        self.check_shapes(dim)?;
        if let Some(r) = &self.scale {
            check_range(&["scale"], r, true)?;
        }
        self.check_densities()?;
        if let Some(k) = self.kappa
            && !(k.is_finite() && k >= 0.0)
        {
            return fail(&["kappa"], format!("must be zero or positive, got {k}"));
        }
        if self.name.chars().any(|c| c.is_control()) {
            return fail(&["name"], "must not hold control characters");
        }
        match &self.layout {
            Layout::Random { region, count, gap } => {
                check_random(region, *count, *gap, dim, lo, hi)
            }
            Layout::Lattice {
                start,
                spacing,
                counts,
            } => check_lattice(start, spacing, counts, dim, lo, hi),
        }
    }

    /// At least one shape, each valid in `dim` dimensions and bounded.
    fn check_shapes(&self, dim: usize) -> Check {
        if self.shapes.is_empty() {
            return fail(
                &["shapes"],
                "needs at least one shape, e.g. `shapes: [Sphere(radius: 0.05)]`",
            );
        }
        for (i, s) in self.shapes.iter().enumerate() {
            let at = |m: String| {
                Err(Issue::new(&[], m)
                    .under(Seg::Index(i))
                    .under(Seg::Key("shapes")))
            };
            if let Err(m) = s.validate(dim) {
                return at(m);
            }
            if matches!(s, Shape::HalfSpace { .. } | Shape::Complement(_)) {
                return at(format!(
                    "a generator places bounded bodies; {} is unbounded (list walls in `bodies`)",
                    s.name()
                ));
            }
        }
        Ok(())
    }

    /// The densities, if given: positive, and a list not empty.
    fn check_densities(&self) -> Check {
        match &self.densities {
            None => {}
            Some(Values::One(d)) if !(d.is_finite() && *d > 0.0) => {
                return fail(&["densities"], format!("must be positive, got {d}"));
            }
            Some(Values::One(_)) => {}
            Some(Values::List(v)) => {
                if v.is_empty() {
                    return fail(&["densities"], "the list is empty: give at least one value");
                }
                if let Some(d) = v.iter().find(|d| !(d.is_finite() && **d > 0.0)) {
                    return fail(
                        &["densities"],
                        format!("every density must be positive, got {d}"),
                    );
                }
            }
            Some(Values::Range(r)) => check_range(&["densities"], r, true)?,
        }
        Ok(())
    }

    /// How many bodies it makes (after [`Generator::check`]).
    fn count(&self) -> usize {
        match &self.layout {
            Layout::Random { count, .. } => *count,
            Layout::Lattice { counts, .. } => counts.iter().product(),
        }
    }
}

/// A placed body as the packing sees it.
#[derive(Clone, Copy)]
struct Ball {
    center: DVec3,
    radius: f64,
}

/// Hash grid of bounding spheres with radius at most `rmax` (cells of side `2 rmax + gap`).
struct Hash {
    cell: f64,
    cells: HashMap<[i64; 3], Vec<Ball>>,
}

impl Hash {
    fn key(&self, x: DVec3) -> [i64; 3] {
        let c = (x / self.cell).floor();
        [c.x as i64, c.y as i64, c.z as i64]
    }

    fn insert(&mut self, b: Ball) {
        let k = self.key(b.center);
        self.cells.entry(k).or_default().push(b);
    }

    /// Whether a ball of radius ≤ rmax at `x` comes within `gap` of any ball stored.
    fn hits(&self, b: Ball, gap: f64) -> bool {
        let k = self.key(b.center);
        for dz in -1..=1 {
            for dy in -1..=1 {
                for dx in -1..=1 {
                    let key = [k[0] + dx, k[1] + dy, k[2] + dz];
                    if let Some(v) = self.cells.get(&key)
                        && v.iter()
                            .any(|o| o.center.distance(b.center) < o.radius + b.radius + gap)
                    {
                        return true;
                    }
                }
            }
        }
        false
    }
}

/// Expand `generators` of a `dim`-dimensional scene in the box `[lo, hi]` into bodies appended
/// to `bodies` (the listed ones already checked and named); the spans they fill. Errors are
/// located in the generator (`generators[i]`).
pub(crate) fn expand(
    generators: &[Generator],
    bodies: &mut Vec<BodySpec>,
    dim: usize,
    lo: &[f64],
    hi: &[f64],
    base_dir: &Path,
) -> Check<Vec<Span>> {
    let mut spans = Vec::with_capacity(generators.len());
    for (gi, g) in generators.iter().enumerate() {
        let under = |i: Issue| i.under(Seg::Index(gi)).under(Seg::Key("generators"));
        g.check(dim, lo, hi).map_err(under)?;
        let start = bodies.len();
        make(g, gi, bodies, dim, base_dir).map_err(under)?;
        spans.push(Span {
            generator: gi,
            start,
            end: bodies.len(),
        });
    }
    Ok(spans)
}

/// One generator's bodies, appended to `bodies`.
fn make(
    g: &Generator,
    gi: usize,
    bodies: &mut Vec<BodySpec>,
    dim: usize,
    base_dir: &Path,
) -> Check {
    let count = g.count();
    let mut draw = Draw::new(g.seed);
    // The draws, in a fixed order: shape shares, density shares, then per body its scale,
    // density (a range) and orientation; positions last.
    let shape_of = shares(count, g.shapes.len(), &mut draw);
    let density_of: Vec<Option<f64>> = match &g.densities {
        None => vec![None; count],
        Some(Values::One(d)) => vec![Some(*d); count],
        Some(Values::List(v)) => shares(count, v.len(), &mut draw)
            .into_iter()
            .map(|k| Some(v[k]))
            .collect(),
        Some(Values::Range(_)) => Vec::new(),
    };
    let base_radius: Vec<f64> = g
        .shapes
        .iter()
        .enumerate()
        .map(|(i, s)| {
            match bounding_radius(s, base_dir) {
                Ok(Some(r)) => Ok(r),
                Ok(None) => Err(Issue::new(&[], "the shape is unbounded")),
                Err(m) => Err(Issue::new(&[], m)),
            }
            .map_err(|e| e.under(Seg::Index(i)).under(Seg::Key("shapes")))
        })
        .collect::<Check<_>>()?;
    let prefix = if g.name.is_empty() {
        format!("gen{gi}_")
    } else {
        g.name.clone()
    };
    let mut made: Vec<(BodySpec, f64)> = Vec::with_capacity(count);
    for (k, &si) in shape_of.iter().enumerate() {
        let s = g.scale.map_or(1.0, |r| draw.between(r.min, r.max));
        let density = match &g.densities {
            Some(Values::Range(r)) => Some(draw.between(r.min, r.max)),
            _ => density_of[k],
        };
        let rotation = match (g.rotation, dim) {
            (Orientation::None, _) => Vec::new(),
            (Orientation::Random, 2) => vec![std::f64::consts::TAU * draw.unit()],
            (Orientation::Random, _) => random_rotation(&mut draw),
        };
        let shape = if s == 1.0 {
            g.shapes[si].clone()
        } else {
            scaled(&g.shapes[si], s)
        };
        made.push((
            BodySpec {
                name: format!("{prefix}{k}"),
                shape,
                kind: g.kind.clone(),
                density,
                position: Vec::new(),
                rotation,
                velocity: Vec::new(),
                angular_velocity: Vec::new(),
                kappa: g.kappa,
            },
            base_radius[si] * s,
        ));
    }
    match &g.layout {
        Layout::Lattice {
            start,
            spacing,
            counts,
        } => {
            for (k, (b, _)) in made.iter_mut().enumerate() {
                let idx = [k % counts[0], k / counts[0] % counts[1], {
                    if dim == 3 {
                        k / (counts[0] * counts[1])
                    } else {
                        0
                    }
                }];
                b.position = (0..dim)
                    .map(|a| start[a] + idx[a] as f64 * spacing[a])
                    .collect();
            }
        }
        Layout::Random { region, gap, .. } => {
            pack(&mut made, bodies, region, *gap, dim, base_dir, &mut draw)?;
        }
    }
    let names: std::collections::HashSet<&str> = bodies.iter().map(|b| b.name.as_str()).collect();
    if let Some((b, _)) = made.iter().find(|(b, _)| names.contains(b.name.as_str())) {
        return fail(
            &["name"],
            format!(
                "makes a body named `{}`, which another body already has; give the generator \
                 another `name`",
                b.name
            ),
        );
    }
    bodies.extend(made.into_iter().map(|(b, _)| b));
    Ok(())
}

/// A rotation vector uniform over rotations (Shoemake's uniform unit quaternion).
fn random_rotation(draw: &mut Draw) -> Vec<f64> {
    let (u1, u2, u3) = (draw.unit(), draw.unit(), draw.unit());
    let tau = std::f64::consts::TAU;
    let (a, b) = ((1.0 - u1).sqrt(), u1.sqrt());
    let q = DQuat::from_xyzw(
        a * (tau * u2).sin(),
        a * (tau * u2).cos(),
        b * (tau * u3).sin(),
        b * (tau * u3).cos(),
    );
    let q = if q.w < 0.0 { -q } else { q };
    q.to_scaled_axis().to_array().to_vec()
}

/// Place `made` (body, bounding radius) at random in `region`, largest first, away from
/// `existing` bodies.
fn pack(
    made: &mut [(BodySpec, f64)],
    existing: &[BodySpec],
    region: &Region,
    gap: f64,
    dim: usize,
    base_dir: &Path,
    draw: &mut Draw,
) -> Check {
    let rmax = made.iter().map(|m| m.1).fold(0.0, f64::max);
    let mut hash = Hash {
        cell: 2.0 * rmax + gap,
        cells: HashMap::new(),
    };
    // Listed and earlier generated bodies: small bounded ones in the hash, large ones checked
    // one by one, unbounded static ones (walls) by their signed distance.
    let mut large: Vec<Ball> = Vec::new();
    let mut walls = Vec::new();
    for b in existing {
        let center = crate::bodies::vec3(&b.position);
        let q = crate::bodies::rotation(&b.rotation);
        let geom = b.shape.build(base_dir).map_err(|m| Issue::new(&[], m))?;
        match bounding_radius(&b.shape, base_dir).map_err(|m| Issue::new(&[], m))? {
            Some(radius) if radius <= rmax => hash.insert(Ball { center, radius }),
            Some(radius) => large.push(Ball { center, radius }),
            None => walls.push((geom, center, q.inverse())),
        }
    }
    let mut order: Vec<usize> = (0..made.len()).collect();
    order.sort_by(|&a, &b| made[b].1.total_cmp(&made[a].1));
    for (placed, &k) in order.iter().enumerate() {
        let radius = made[k].1;
        let lo: Vec<f64> = (0..dim).map(|a| region.min[a] + radius).collect();
        let hi: Vec<f64> = (0..dim).map(|a| region.max[a] - radius).collect();
        if (0..dim).any(|a| lo[a] > hi[a]) {
            return fail(
                &["layout", "Random", "region"],
                format!(
                    "body `{}` (bounding radius {radius:.4}) does not fit in the region; use a \
                     bigger region or smaller shapes",
                    made[k].0.name
                ),
            );
        }
        let mut found = None;
        for _ in 0..MAX_ATTEMPTS {
            let mut c = DVec3::ZERO;
            for a in 0..dim {
                c[a] = draw.between(lo[a], hi[a]);
            }
            let ball = Ball { center: c, radius };
            if hash.hits(ball, gap)
                || large
                    .iter()
                    .any(|o| o.center.distance(c) < o.radius + radius + gap)
                || walls
                    .iter()
                    .any(|(g, wc, inv)| g.phi(*inv * (c - *wc)) > -(radius + gap))
            {
                continue;
            }
            found = Some(ball);
            break;
        }
        let Some(ball) = found else {
            return fail(
                &["layout", "Random", "count"],
                format!(
                    "placed only {placed} of {} bodies without overlap ({MAX_ATTEMPTS} tries for \
                     the next, `{}`); use a bigger region, fewer or smaller bodies, or a smaller \
                     gap",
                    made.len(),
                    made[k].0.name
                ),
            );
        };
        hash.insert(ball);
        made[k].0.position = ball.center.to_array()[..dim].to_vec();
    }
    Ok(())
}
