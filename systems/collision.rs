//! # collision: level-set contact forces between bodies (paper eqs. 20-22, section 3.2)
//!
//! The 1D model ẍ = (κ/x) e^{-x/ε} (eq. 20) is a short-range Hamiltonian repulsion that stops a
//! point at a distance O(ε) from a wall and sends it back with the speed it came in with.
//! Spread over body i's interface with the level sets, it is the force density (eq. 22, with
//! the sign the physics needs, see DESIGN.md)
//!
//!   f_ij(x) = ρ_i (κ_ij/ε) ζ(φ_i(x)/ε) (e^{-d/ε}/d) (-∇φ_j(x)),   d = -φ_j(x),
//!
//! on the inner band 0 < φ_i < ε of body i only (the one-sided cut-off of section 3.2:
//! ζ(s) = 1 - cos 2πs on (0, 1), ∫ζ = 1). The band integral is a quadrature over points fixed
//! in body i (a lattice of spacing min(h, ε)/2 in its frame, see `ContactPoints`) rather than
//! over the flow grid's nodes: the points move with the body, so the discrete force is the
//! exact gradient of a discrete potential and the contact conserves energy however the body
//! sits on the grid (with grid nodes, an ellipsoid bouncing off a sphere at h = 1/64 gained
//! 6% energy). ∇φ_j points into body j, so body i is pushed
//! away from j along j's normal; distances and normals come from j's reference level set
//! through its current pose. The force and its moment about i's centroid are summed over the
//! band; `contact_impulse` turns them into a velocity change F Δt/m_i and J_i⁻¹ T Δt of the
//! rigid velocity the flow gave the body this step (the paper adds the body average of the
//! collision force to ū_i directly, so the singular force is never differentiated on the
//! grid). An off-centre contact therefore spins the body.
//!
//! ρ_i is the body's own density, so the acceleration κ gives is independent of the material:
//! about κ (A/V) e^{-d/ε}/d for a band of area A within range and a body of volume V, which
//! makes κ a length³/time² (not the squared velocity of the 1D model: ζ/ε is a surface
//! measure), the unit of its scene default C L² max(|g|, U²/ε) (`KappaDefault`).
//! d is clamped below at ε/20 (overlap cannot make the force infinite) and the force is
//! dropped beyond d > `range` ε.
//!
//! With the flow on, each pair's contact is resolved in time over the step (`substepped`): at
//! the paper's time steps a falling body crosses more than ε per step, and a force that only
//! sees the current pose comes a step late, lets the body sink into a wall and makes the
//! rebound depend on κ. In vacuum the time step resolves the contact and the plain force at
//! the current poses keeps symplectic Euler symplectic.
//!
//! Broad phase: each bounded body's box (its grid patch) grown by the contact range; boxes
//! are swept along x (sort and sweep) and only overlapping pairs are evaluated, so the cost
//! follows the number of close pairs, not the number of bodies squared. An unbounded body (a
//! wall, a tank) is tested against a body i by its signed distance at i's centre.
//!
//! The box is periodic: two moving bodies near each other across its boundary touch through
//! their periodic images. A body whose grown box reaches past the box's boundary is also
//! tested against every periodic image of every other bounded body within reach (each such
//! pair carries the whole box lengths `shift` by which the source body is moved to that
//! image, in the narrow phase and in the pair's lever arms): two bodies half a box apart
//! touch through two images at once; bodies wholly inside the box, and every pair the sweep
//! finds directly, are treated as before. Pairs are
//! evaluated in parallel and added in a fixed order, so results do not depend on the thread
//! count.

use crate::base::fields::SimTime;
use crate::base::grid::Grid;
use crate::bodies::contact::{ContactParams, contact_velocity_change, inverse_inertia};
use crate::bodies::{
    Body, BodyShape, ContactPoints, ContactState, GridPatch, Material, RigidState, patch_pos,
};
use bevy_ecs::prelude::*;
use glam::DVec3;
use parry3d_f64::bounding_volume::{Aabb, BoundingVolume};
use parry3d_f64::math::Vector as PVec;
use rayon::prelude::*;

/// One close pair of bodies after a step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactRecord {
    /// Scene id of the first body (the smaller id).
    pub a: usize,
    /// Scene id of the second body.
    pub b: usize,
    /// Smallest gap between the two surfaces seen on the band (length; negative if they
    /// overlap).
    pub gap: f64,
    /// Magnitude of the contact force between them (mean over the directions evaluated).
    pub force: f64,
}

#[derive(Debug, Clone, Copy)]
struct BodyBox {
    entity: Entity,
    id: usize,
    dynamic: bool,
    /// World box of the body grown to the contact range; `None` if unbounded.
    aabb: Option<Aabb>,
    /// Radius of a sphere about the centre holding the body.
    radius: f64,
    center: DVec3,
    /// The body's own κ (`None`: each pair's default).
    kappa: Option<f64>,
}

#[derive(Debug, Clone, Copy, Default)]
struct PairResult {
    force: DVec3,
    torque: DVec3,
    potential: f64,
    gap: f64,
    any: bool,
    /// Set when both bodies of a dynamic pair were stepped together (`substepped_pair`):
    /// `force`, `torque` are already the pair's balanced values, and `partner` holds the
    /// partner's (force, torque, potential), for the reverse directed pair.
    partner: Option<(DVec3, DVec3, f64)>,
}

/// The exponential integral E₁(x) = ∫_x^∞ e^{-s}/s ds for x > 0 (series below 1, continued
/// fraction above; relative error below 1e-12).
pub fn exp_integral_e1(x: f64) -> f64 {
    if x <= 0.0 {
        return f64::INFINITY;
    }
    if x < 1.0 {
        // E₁(x) = -γ - ln x - Σ_{k≥1} (-x)^k / (k k!)
        let mut sum = 0.0;
        let mut term = 1.0;
        for k in 1..40 {
            term *= -x / k as f64;
            sum += term / k as f64;
            if term.abs() < 1e-17 {
                break;
            }
        }
        -0.577_215_664_901_532_9 - x.ln() - sum
    } else {
        // Lentz's method for the continued fraction e^{-x} / (x + 1 - 1/(x + 3 - 4/(x + 5 - ...))).
        let tiny = 1e-300;
        let mut b = x + 1.0;
        let mut c = 1.0 / tiny;
        let mut d = 1.0 / b;
        let mut f = d;
        for i in 1..200 {
            let a = -((i * i) as f64);
            b += 2.0;
            d = 1.0 / (a * d + b);
            c = b + a / c;
            let delta = c * d;
            f *= delta;
            if (delta - 1.0).abs() < 1e-15 {
                break;
            }
        }
        f * (-x).exp()
    }
}

/// E₁ for the contact potential, by cubic Hermite interpolation in ln x of a table of exact
/// values and slopes (d E₁/d ln x = -e^{-x}) on [1/32, 64], 4096 intervals (absolute error
/// below 1e-14; about 1e-11 relative at x = 6, the default cut-off); the exact function
/// outside. The continued fraction took half the collision system's time with 200 spheres.
pub fn exp_integral_e1_fast(x: f64) -> f64 {
    const N: usize = 4096;
    const LO: f64 = -3.465_735_902_799_726_5; // ln(1/32)
    const HI: f64 = 4.158_883_083_359_671_5; // ln 64
    static TABLE: std::sync::OnceLock<Vec<(f64, f64)>> = std::sync::OnceLock::new();
    let t = x.ln();
    if !(LO..HI).contains(&t) {
        return exp_integral_e1(x);
    }
    let dt = (HI - LO) / N as f64;
    // (E₁, dt d E₁/d ln x) at the nodes.
    let table = TABLE.get_or_init(|| {
        (0..=N)
            .map(|k| {
                let x = (LO + dt * k as f64).exp();
                (exp_integral_e1(x), -(-x).exp() * dt)
            })
            .collect()
    });
    let u = (t - LO) / dt;
    let k = (u as usize).min(N - 1);
    let s = u - k as f64;
    let ((y0, m0), (y1, m1)) = (table[k], table[k + 1]);
    let (s2, s3) = (s * s, s * s * s);
    (2.0 * s3 - 3.0 * s2 + 1.0) * y0
        + (s3 - 2.0 * s2 + s) * m0
        + (-2.0 * s3 + 3.0 * s2) * y1
        + (s3 - s2) * m1
}

/// The close pairs of the last step (`records`) and the system's scratch buffers, kept so a
/// step does not allocate once they have grown.
#[derive(Resource, Debug, Default)]
pub struct Contacts {
    /// Close pairs (gap within the contact range), ordered by (a, b).
    pub records: Vec<ContactRecord>,
    boxes: Vec<BodyBox>,
    order: Vec<usize>,
    pairs: Vec<Pair>,
    results: Vec<PairResult>,
}

impl Contacts {
    /// Buffers for `n` bodies.
    pub fn with_capacity(n: usize) -> Self {
        Contacts {
            records: Vec::with_capacity(4 * n),
            boxes: Vec::with_capacity(n),
            order: Vec::with_capacity(n),
            pairs: Vec::with_capacity(8 * n),
            results: Vec::with_capacity(8 * n),
        }
    }
}

/// A directed pair for the narrow phase: receiver, source, κ, and the shift (whole box lengths)
/// that moves the source to its periodic image nearest the receiver (zero for most pairs).
type Pair = (usize, usize, f64, DVec3);

/// A body's state moved by `shift` (its periodic image).
fn image(s: &RigidState, shift: DVec3) -> RigidState {
    if shift == DVec3::ZERO {
        return *s;
    }
    RigidState {
        center: s.center + shift,
        centroid: s.centroid + shift,
        ..*s
    }
}

type BodyQuery<'w, 's> = Query<
    'w,
    's,
    (
        Entity,
        &'static Body,
        &'static RigidState,
        &'static BodyShape,
        &'static GridPatch,
        &'static Material,
        &'static ContactPoints,
    ),
>;

/// The collision system: the bodies' boxes, the broad phase, the pair forces (narrow
/// phase), one pair potential for two dynamic bodies, and the accumulation of the forces
/// into each body's [`ContactState`] with one record per close pair.
pub fn collision(
    grid: Res<Grid>,
    time: Res<SimTime>,
    cp: Res<ContactParams>,
    mut contacts: ResMut<Contacts>,
    bodies: BodyQuery,
    mut states: Query<&mut ContactState>,
) {
    let eps = cp.eps;
    let cut = cp.range * eps;
    let c = &mut *contacts;
    body_boxes(&grid, cut, c, &bodies, &states);
    for mut s in &mut states {
        s.force = DVec3::ZERO;
        s.torque = DVec3::ZERO;
        s.potential = 0.0;
    }
    broad_phase(&grid, &cp, cut, c, &bodies);
    pair_forces(&grid, &cp, time.dt, eps, cut, c, &bodies);
    one_potential_per_dynamic_pair(c, &bodies);
    accumulate(c, &mut states);
}

/// Each body's box for the broad phase (sorted by id): its grid patch grown by the contact
/// range, its bounding radius, centre and κ; no box for an unbounded body.
fn body_boxes(
    grid: &Grid,
    cut: f64,
    c: &mut Contacts,
    bodies: &BodyQuery,
    states: &Query<&mut ContactState>,
) {
    // The patch reaches only a few cells beyond the body (`level_sets::patch_reach`): grow its
    // box by the whole contact range, plus a cell for the node rounding.
    let grow = cut + grid.h;
    c.boxes.clear();
    for (entity, body, state, shape, patch, _, points) in bodies {
        let kappa = states.get(entity).map_or(Some(0.0), |s| s.kappa);
        let (aabb, radius) = match shape.level_set.bounds() {
            Some((lo, hi)) => {
                // Unwrapped: next to the body, possibly past the box's boundary.
                // (The whole box: on a slab the patch holds only its planes.)
                let (wlo, wdims) = patch.whole;
                let (plo, phi) = (patch_pos(grid, wlo, 0, 0, 0), {
                    let top = wdims.map(|d| d.max(1) - 1);
                    patch_pos(grid, wlo, top[0], top[1], top[2])
                });
                let mut mins = PVec::new(plo[0], plo[1], plo[2]);
                let mut maxs = PVec::new(phi[0], phi[1], phi[2]);
                if grid.dim == 2 {
                    mins.z = -1.0;
                    maxs.z = 1.0;
                }
                let aabb = Aabb::new(mins, maxs).loosened(grow);
                (Some(aabb), points.radius.min(0.5 * (hi - lo).length()))
            }
            None => (None, f64::INFINITY),
        };
        c.boxes.push(BodyBox {
            entity,
            id: body.id,
            dynamic: body.is_dynamic(),
            aabb,
            radius,
            center: state.center,
            kappa,
        });
    }
    c.boxes.sort_unstable_by_key(|b| b.id);
}

/// Broad phase: the directed pairs (receiver, source, κ) whose boxes and grown bounding
/// spheres overlap (sweep and prune along x), plus every dynamic body against each unbounded
/// one it is near; the receiver is dynamic. In a fixed order: by unordered pair, then
/// receiver.
fn broad_phase(grid: &Grid, cp: &ContactParams, cut: f64, c: &mut Contacts, bodies: &BodyQuery) {
    c.pairs.clear();
    c.order.clear();
    c.order
        .extend((0..c.boxes.len()).filter(|&i| c.boxes[i].aabb.is_some()));
    let boxes = &c.boxes;
    c.order.sort_unstable_by(|&x, &y| {
        let (ax, ay) = (boxes[x].aabb.unwrap(), boxes[y].aabb.unwrap());
        ax.mins.x.total_cmp(&ay.mins.x).then(x.cmp(&y))
    });
    let push = |pairs: &mut Vec<Pair>, r: usize, s: usize, shift: DVec3| {
        let (br, bs) = (&boxes[r], &boxes[s]);
        if br.dynamic {
            let k = cp.kappa(br.id, bs.id, br.kappa, bs.kappa);
            if k > 0.0 {
                pairs.push((r, s, k, shift));
            }
        }
    };
    for (n, &x) in c.order.iter().enumerate() {
        let ax = boxes[x].aabb.unwrap();
        for &y in &c.order[n + 1..] {
            let ay = boxes[y].aabb.unwrap();
            if ay.mins.x > ax.maxs.x {
                break;
            }
            // Boxes first, then the bodies' bounding spheres grown by the range.
            let reach = boxes[x].radius + boxes[y].radius + cut;
            if ax.intersects(&ay)
                && (boxes[x].center - boxes[y].center).length_squared() <= reach * reach
            {
                push(&mut c.pairs, x, y, DVec3::ZERO);
                push(&mut c.pairs, y, x, DVec3::ZERO);
            }
        }
    }
    // Across the periodic boundary: a box reaching past it against every periodic image of
    // the other bodies within reach (each unordered pair and image once; the pairs the sweep
    // found directly are the zero shift). Two bodies half a box apart meet through two images
    // at once, whose forces cancel; the nearest image alone pushed them apart.
    let ext = grid.extent();
    let (o, dim) = (grid.origin, grid.dim);
    let past = |b: &Aabb| (0..dim).any(|a| b.mins[a] < o[a] || b.maxs[a] >= o[a] + ext[a]);
    let images = if dim == 3 { 27 } else { 9 };
    for &x in &c.order {
        let ax = boxes[x].aabb.unwrap();
        if !past(&ax) {
            continue;
        }
        for &y in &c.order {
            if y == x || (past(&boxes[y].aabb.unwrap()) && y < x) {
                continue;
            }
            let d = boxes[y].center - boxes[x].center;
            let reach = boxes[x].radius + boxes[y].radius + cut;
            let ay0 = boxes[y].aabb.unwrap();
            for m in 0..images {
                let shift = DVec3::new(
                    ((m % 3) as f64 - 1.0) * ext[0],
                    ((m / 3 % 3) as f64 - 1.0) * ext[1],
                    if dim == 3 {
                        ((m / 9) as f64 - 1.0) * ext[2]
                    } else {
                        0.0
                    },
                );
                if shift == DVec3::ZERO {
                    continue;
                }
                let sh = PVec::new(shift.x, shift.y, shift.z);
                let ay = Aabb::new(ay0.mins + sh, ay0.maxs + sh);
                if ax.intersects(&ay) && (d + shift).length_squared() <= reach * reach {
                    push(&mut c.pairs, x, y, shift);
                    push(&mut c.pairs, y, x, -shift);
                }
            }
        }
    }
    for (j, bj) in boxes.iter().enumerate() {
        if bj.aabb.is_some() {
            continue;
        }
        let Ok((_, _, sj, shj, _, _, _)) = bodies.get(bj.entity) else {
            continue;
        };
        let inv = sj.orientation.inverse();
        for (i, bi) in boxes.iter().enumerate() {
            if i == j || !bi.dynamic {
                continue;
            }
            let phi_c = shj.level_set.phi(inv * (bi.center - sj.center));
            if bi.aabb.is_none() || phi_c > -(bi.radius + cut + grid.h) {
                push(&mut c.pairs, i, j, DVec3::ZERO);
            }
        }
    }
    // A fixed order: by unordered pair, then image (the shift seen from the lower id, in
    // whole box lengths), then receiver: the two directions of one image are adjacent.
    c.pairs.sort_unstable_by_key(|&(r, s, _, shift)| {
        let (a, b) = (boxes[r].id, boxes[s].id);
        let seen = if a < b { shift } else { -shift };
        let lengths: [i64; 3] = std::array::from_fn(|q| {
            if q < dim {
                (seen[q] / ext[q]).round() as i64
            } else {
                0
            }
        });
        (a.min(b), a.max(b), lengths, a)
    });
}

/// Narrow phase, in parallel over the directed pairs: the force, torque and potential of each
/// (sub-stepped over the step when `cp.predict`), into `c.results` in pair order.
fn pair_forces(
    grid: &Grid,
    cp: &ContactParams,
    dt: f64,
    eps: f64,
    cut: f64,
    c: &mut Contacts,
    bodies: &BodyQuery,
) {
    let boxes = &c.boxes;
    c.pairs
        .par_iter()
        .map(|&(r, s, kappa, shift)| {
            let (Ok(ri), Ok(sj)) = (bodies.get(boxes[r].entity), bodies.get(boxes[s].entity))
            else {
                return PairResult::default();
            };
            // The source's periodic image nearest the receiver.
            let sj_state = image(sj.2, shift);
            let sj = (sj.0, sj.1, &sj_state, sj.3, sj.4, sj.5, sj.6);
            if !cp.predict {
                return directed(
                    grid,
                    ri.2,
                    ri.6,
                    ri.5.density,
                    sj.2,
                    sj.3,
                    boxes[s].radius,
                    kappa,
                    eps,
                    cut,
                );
            }
            if boxes[r].dynamic && boxes[s].dynamic {
                // Both bodies are stepped together, once, in the task of the lower id; the
                // reverse directed pair takes its share from that result.
                if boxes[r].id > boxes[s].id {
                    return PairResult::default();
                }
                return substepped_pair(
                    grid,
                    (ri.1, ri.2, ri.6, ri.5.density, ri.3, boxes[r].radius),
                    (sj.1, sj.2, sj.6, sj.5.density, sj.3, boxes[s].radius),
                    kappa,
                    eps,
                    cut,
                    dt,
                );
            }
            substepped(
                grid,
                (ri.1, ri.2, ri.6, ri.5.density),
                (sj.1, sj.2, sj.3, boxes[s].radius),
                kappa,
                eps,
                cut,
                dt,
            )
        })
        .collect_into_vec(&mut c.results);
}

/// Two dynamic bodies: one pair potential for both (see below), written over the two
/// directed results.
fn one_potential_per_dynamic_pair(c: &mut Contacts, bodies: &BodyQuery) {
    let boxes = &c.boxes;
    // Two dynamic bodies: one pair potential for both. Each direction is the exact gradient of
    // its own band's potential U_ij (i's band in φ_j), and the two discrete potentials are not
    // equal (the band is about one lattice spacing thick), so using each alone breaks
    // Newton's third law and lets a dense pile gain energy collision after collision (200
    // spheres in vacuum: +8% in one time unit, the same at half the step). The pair instead
    // derives both forces from V = (U_ij + U_ji)/2: F_i = (F_ij - F_ji)/2 and
    // T_i = (T_ij - T_ji - (x_j - x_i) × F_ji)/2 about the centroids (by translation
    // invariance, -∇_i U_ji is the reaction of F_ji and -∂U_ji/∂θ_i its moment about x_i),
    // which conserves momentum, angular momentum and energy exactly.
    // The two directions of one image are adjacent (`broad_phase`); a pair of bodies may
    // meet through several images, one after the other.
    let mut k = 0;
    while k + 1 < c.pairs.len() {
        let ((r, s, _, shift), (r2, s2, _, shift2)) = (c.pairs[k], c.pairs[k + 1]);
        if r2 != s || s2 != r || shift2 != -shift || !boxes[s].dynamic {
            k += 1;
            continue;
        }
        let next = k + 2;
        if let Some((f, t, potential)) = c.results[k].partner {
            let (any, gap) = (c.results[k].any, c.results[k].gap);
            c.results[k + 1] = PairResult {
                force: f,
                torque: t,
                potential,
                gap,
                any,
                partner: None,
            };
            k = next;
            continue;
        }
        let (Ok(bi), Ok(bj)) = (bodies.get(boxes[r].entity), bodies.get(boxes[s].entity)) else {
            k = next;
            continue;
        };
        let arm = bj.2.centroid + shift - bi.2.centroid;
        let (a, b) = (&c.results[k], &c.results[k + 1]);
        let (fi, fj) = (0.5 * (a.force - b.force), 0.5 * (b.force - a.force));
        let ti = 0.5 * (a.torque - b.torque - arm.cross(b.force));
        let tj = 0.5 * (b.torque - a.torque + arm.cross(a.force));
        let any = a.any || b.any;
        let gap = a.gap.min(b.gap);
        for (res, f, t) in [(k, fi, ti), (k + 1, fj, tj)] {
            let out = &mut c.results[res];
            out.force = f;
            out.torque = t;
            out.any = any;
            out.gap = gap;
        }
        k = next;
    }
}

/// Sum the pair results into each receiver's [`ContactState`], in the fixed pair order; one
/// record per unordered close pair.
fn accumulate(c: &mut Contacts, states: &mut Query<&mut ContactState>) {
    let boxes = &c.boxes;
    c.records.clear();
    for (&(r, s, _, _), res) in c.pairs.iter().zip(&c.results) {
        if !res.any {
            continue;
        }
        if let Ok(mut st) = states.get_mut(boxes[r].entity) {
            st.force += res.force;
            st.torque += res.torque;
            // Between two dynamic bodies each pushes the other from its own band with the
            // same pair potential (for spheres), so half of each goes to each body.
            let share = if boxes[s].dynamic { 0.5 } else { 1.0 };
            st.potential += share * res.potential;
        }
        let (a, b) = (boxes[r].id.min(boxes[s].id), boxes[r].id.max(boxes[s].id));
        match c.records.last_mut() {
            Some(last) if last.a == a && last.b == b => {
                last.gap = last.gap.min(res.gap);
                last.force = 0.5 * (last.force + res.force.length());
            }
            _ => c.records.push(ContactRecord {
                a,
                b,
                gap: res.gap,
                force: res.force.length(),
            }),
        }
    }
}

/// Contact (section 3.2): the body average of the collision force goes straight into the
/// rigid velocity the flow has just given the body (`rigid_velocity` runs first), as F Δt/m_i
/// and (ρ_i J_i)⁻¹ T Δt with the mass and inertia of χ; the penalization then imposes it. The
/// sub-stepped contact starts from that same velocity, so the impulse it returns is the one
/// that stops (or turns back) the body as it actually moves this step. (Applied to a velocity
/// that the flow then replaces, an impulse computed from the previous step's velocity made
/// a disk hitting a floor alternate up and down from step to step.)
pub fn contact_impulse(
    grid: Res<Grid>,
    time: Res<SimTime>,
    mut bodies: Query<(&Body, &Material, &ContactState, &mut RigidState)>,
) {
    let dt = time.dt;
    for (body, mat, contact, mut state) in &mut bodies {
        if !body.is_dynamic()
            || state.volume <= 0.0
            || (contact.force == DVec3::ZERO && contact.torque == DVec3::ZERO)
        {
            continue;
        }
        let (dv, dw) = contact_velocity_change(grid.dim, mat.density, &state, contact, dt);
        state.velocity += dv;
        state.angular_velocity += dw;
    }
}

/// The contact force on body i from body j over a step of length `dt`, resolved in time: the
/// step is cut into sub-steps short enough that the bodies approach by at most ε/4 in each,
/// body j moves on at its velocity, and body i's velocity (linear and angular) is advanced by
/// this pair's force in every sub-step (symplectic Euler), so that a body hitting a wall at a
/// speed of several ε per step is stopped and sent back by the force itself, not by one
/// late, oversized kick. Returns the mean force and torque over the step (the impulse over
/// Δt), the potential and the gap at the start.
fn substepped(
    grid: &Grid,
    i: (&Body, &RigidState, &ContactPoints, f64),
    j: (&Body, &RigidState, &BodyShape, f64),
    kappa: f64,
    eps: f64,
    cut: f64,
    dt: f64,
) -> PairResult {
    let (bi, si, pi, rho_i) = i;
    let (bj, sj, shj, radius_j) = j;
    let first = directed(grid, si, pi, rho_i, sj, shj, radius_j, kappa, eps, cut);
    let mass = rho_i * si.volume;
    if dt <= 0.0 || mass <= 0.0 || !bi.is_dynamic() {
        return first;
    }
    let vj = if bj.is_static() {
        DVec3::ZERO
    } else {
        sj.velocity
    };
    let approach = (si.velocity - vj).length() * dt;
    let n = ((approach / (0.25 * eps)).ceil() as usize).clamp(1, 64);
    if n == 1 && !first.any {
        return first;
    }
    let jinv = inverse_inertia(grid.dim, rho_i, si);
    let tau = dt / n as f64;
    let mut s = *si;
    let mut force = DVec3::ZERO;
    let mut torque = DVec3::ZERO;
    let mut any = false;
    for k in 0..n {
        let sj_k = ahead(bj, sj, k as f64 * tau);
        let r = directed(grid, &s, pi, rho_i, &sj_k, shj, radius_j, kappa, eps, cut);
        any |= r.any;
        force += r.force * tau;
        torque += r.torque * tau;
        s.velocity += r.force * tau / mass;
        s.angular_velocity += jinv * (r.torque * tau);
        s = ahead(bi, &s, tau);
    }
    PairResult {
        force: force / dt,
        torque: torque / dt,
        potential: first.potential,
        gap: first.gap,
        any: any || first.any,
        partner: None,
    }
}

/// Two dynamic bodies in contact over a step of length `dt`, resolved in time together: the
/// step is cut into sub-steps in which they approach by at most ε/4, and in each both bodies'
/// velocities (linear and angular) are advanced by the pair's balanced force and torques (the
/// combination of the two directed forces described in `collision`), then both move on. With
/// each body sub-stepped against a partner moving on unaffected (`substepped`), each would
/// absorb the whole relative velocity: a stiff head-on contact between equal spheres within one
/// step would exchange twice the right impulse. Returns the mean force and torque on `i` over
/// the step, the same for `j` in `partner`, each body's band potential and the gap at the
/// start.
#[allow(clippy::too_many_arguments)]
fn substepped_pair(
    grid: &Grid,
    i: (&Body, &RigidState, &ContactPoints, f64, &BodyShape, f64),
    j: (&Body, &RigidState, &ContactPoints, f64, &BodyShape, f64),
    kappa: f64,
    eps: f64,
    cut: f64,
    dt: f64,
) -> PairResult {
    let (bi, si, pi, rho_i, shi, radius_i) = i;
    let (bj, sj, pj, rho_j, shj, radius_j) = j;
    let pair = |a: &RigidState, b: &RigidState| {
        let ra = directed(grid, a, pi, rho_i, b, shj, radius_j, kappa, eps, cut);
        let rb = directed(grid, b, pj, rho_j, a, shi, radius_i, kappa, eps, cut);
        let arm = b.centroid - a.centroid;
        let fa = 0.5 * (ra.force - rb.force);
        let ta = 0.5 * (ra.torque - rb.torque - arm.cross(rb.force));
        let tb = 0.5 * (rb.torque - ra.torque + arm.cross(ra.force));
        (ra, rb, fa, ta, tb)
    };
    let (ra, rb, fa, ta, tb) = pair(si, sj);
    let first = PairResult {
        force: fa,
        torque: ta,
        potential: ra.potential,
        gap: ra.gap.min(rb.gap),
        any: ra.any || rb.any,
        partner: Some((-fa, tb, rb.potential)),
    };
    let (mi, mj) = (rho_i * si.volume, rho_j * sj.volume);
    if dt <= 0.0 || mi <= 0.0 || mj <= 0.0 {
        return first;
    }
    let approach = (si.velocity - sj.velocity).length() * dt;
    let n = ((approach / (0.25 * eps)).ceil() as usize).clamp(1, 64);
    if n == 1 && !first.any {
        return first;
    }
    let (ji, jj) = (
        inverse_inertia(grid.dim, rho_i, si),
        inverse_inertia(grid.dim, rho_j, sj),
    );
    let tau = dt / n as f64;
    let (mut a, mut b) = (*si, *sj);
    let (mut f, mut t_a, mut t_b) = (DVec3::ZERO, DVec3::ZERO, DVec3::ZERO);
    let mut any = first.any;
    for k in 0..n {
        let (fa, ta, tb) = if k == 0 {
            (
                first.force,
                first.torque,
                first.partner.map_or(DVec3::ZERO, |p| p.1),
            )
        } else {
            let (ra, rb, fa, ta, tb) = pair(&a, &b);
            any |= ra.any || rb.any;
            (fa, ta, tb)
        };
        f += fa * tau;
        t_a += ta * tau;
        t_b += tb * tau;
        a.velocity += fa * tau / mi;
        b.velocity -= fa * tau / mj;
        a.angular_velocity += ji * (ta * tau);
        b.angular_velocity += jj * (tb * tau);
        a = ahead(bi, &a, tau);
        b = ahead(bj, &b, tau);
    }
    PairResult {
        force: f / dt,
        torque: t_a / dt,
        any,
        partner: Some((-f / dt, t_b / dt, first.partner.map_or(0.0, |p| p.2))),
        ..first
    }
}

/// The pose a body reaches after `dt` at its current velocities (static bodies stay).
fn ahead(body: &Body, s: &RigidState, dt: f64) -> RigidState {
    if dt == 0.0 || body.is_static() {
        *s
    } else {
        s.advanced(dt)
    }
}

/// The contact force and torque on body i (state `si`, contact points `pi`, density `rho_i`)
/// from body j (state `sj`, shape `shj`), the contact potential, and the smallest gap seen.
#[allow(clippy::too_many_arguments)]
fn directed(
    grid: &Grid,
    si: &RigidState,
    pi: &ContactPoints,
    rho_i: f64,
    sj: &RigidState,
    shj: &BodyShape,
    radius_j: f64,
    kappa: f64,
    eps: f64,
    cut: f64,
) -> PairResult {
    let mut out = PairResult {
        gap: f64::INFINITY,
        ..Default::default()
    };
    // Points farther than this from j's origin cannot be within range of j.
    let far = (radius_j + cut).powi(2);
    let inv = sj.orientation.inverse();
    let ls = &shj.level_set;
    // The gradient of φ_j is that of its (trilinear) interpolant, exactly for a sampled level
    // set and by a narrow central difference for an analytic one.
    let delta = 1e-3 * grid.h;
    let d_min = 0.05 * eps;
    let coef = rho_i * kappa;
    // The force is dropped beyond d = cut, so the potential of the force actually applied is
    // κ ∫_d^cut e^{-s/ε}/s ds = κ (E₁(d/ε) - E₁(cut/ε)): continuous where a point leaves the
    // range. (Without the shift, every point crossing the cut-off took E₁(6) with it: two
    // spheres pushed apart from a gap of 2.2ε seemed to lose 12% of their energy.)
    let e1_cut = exp_integral_e1(cut / eps);
    for ((p, &phi_i), &w) in pi.points.iter().zip(&pi.phi).zip(&pi.weights) {
        let x = si.center + si.orientation * *p;
        if (x - sj.center).length_squared() > far {
            continue;
        }
        let xl = inv * (x - sj.center);
        let (phi_j, g) = ls.phi_grad(xl, delta, grid.dim);
        let d = -phi_j;
        if d > cut {
            continue;
        }
        // Not normalised: the force is then the exact gradient of the potential below, also
        // where an interpolated φ_j has |∇φ_j| slightly off 1.
        let n = sj.orientation * g;
        let dd = d.max(d_min);
        let f = -(coef * w * (-dd / eps).exp() / dd) * n;
        // The potential whose (rigid-motion) gradient this force is.
        out.potential += coef * w * (exp_integral_e1_fast(dd / eps) - e1_cut);
        out.force += f;
        out.torque += (x - si.centroid).cross(f);
        out.gap = out.gap.min(d - phi_i);
        out.any = true;
    }
    out
}

/// Contact forces (every run with bodies), applied as impulses to the rigid velocities
/// in a fluid run.
#[derive(Debug, Clone, Copy, Default)]
pub struct CollisionPlugin;

impl crate::schedule::Plugin for CollisionPlugin {
    fn name(&self) -> &'static str {
        "collision"
    }

    fn build(&self, ctx: &mut crate::schedule::PluginContext) -> anyhow::Result<()> {
        use crate::schedule::PhysicsSet;
        let mode = ctx.mode();
        if mode.has_bodies() {
            ctx.insert_resource(Contacts::with_capacity(mode.bodies));
            ctx.add_system(PhysicsSet::Collision, "collision", collision)?;
            if mode.fluid() {
                ctx.add_system(PhysicsSet::Collision, "contact_impulse", contact_impulse)?;
            }
        }
        Ok(())
    }
}
