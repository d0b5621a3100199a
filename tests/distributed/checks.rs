//! Checks of the distributed layer that hold on any number of processes: the suite runs them on
//! one process (the transposes with itself), `tests/mpi.rs` under `mpirun -np 2` and `-np 3`
//! (uneven slabs). Each compares the split computation with the same computation done whole on
//! every process, with a tolerance that round-off of the transforms explains (1e-12 of the
//! field's size) or exact equality where no arithmetic differs.

use std::sync::Arc;

use tumble::base::grid::Grid;
use tumble::parallel::{Comm, Slabs};
use tumble::solvers::fft::{C64, FftEngine};
use tumble::solvers::operators::{Spectral, TopDamping};

/// A smooth-plus-rough deterministic field on the whole grid (every mode present).
pub fn field(grid: &Grid, seed: usize) -> Vec<f64> {
    (0..grid.len())
        .map(|i| {
            let r = ((i * 2654435761 + seed * 97) % 1000003) as f64 / 1000003.0 - 0.5;
            let [x, y, z] = grid.pos(i % grid.n[0], (i / grid.n[0]) % grid.n[1], i / grid.plane());
            (2.0 * x + 0.3).sin() * (3.0 * y).cos() + (z - 0.1 * x).sin() + r
        })
        .collect()
}

/// This process's planes of a whole field.
pub fn local_planes(grid: &Grid, whole: &[f64], planes: std::ops::Range<usize>) -> Vec<f64> {
    whole[planes.start * grid.plane()..planes.end * grid.plane()].to_vec()
}

fn max_abs_c(v: &[C64]) -> f64 {
    v.iter().map(|z| z.norm()).fold(0.0, f64::max)
}

/// The split forward transform equals the whole one on this process's spectral rows, and the
/// split inverse gives back this process's planes; returns the largest relative difference
/// (over every process).
pub fn fft_matches_whole(comm: Arc<Comm>, n: [usize; 3]) -> f64 {
    let grid = Grid::new(n, 0.1, [0.0, -0.2, 0.3]);
    let whole = field(&grid, 1);
    let mut serial = FftEngine::new(&grid);
    let mut spec = vec![C64::default(); serial.complex_len()];
    serial.forward(&whole, &mut spec);
    let scale = max_abs_c(&spec);

    let mut eng = FftEngine::split(&grid, comm.clone()).expect("grid splits");
    let mine = local_planes(&grid, &whole, eng.planes());
    let mut out = vec![C64::default(); eng.complex_len()];
    eng.forward(&mine, &mut out);
    // The serial layout (i, j, k) restricted to this process's rows.
    let ([_, nyl, nz], nxh) = eng.dims();
    let rows = eng.spectral_rows();
    let mut worst = 0.0f64;
    for k in 0..nz {
        for jl in 0..nyl {
            for i in 0..nxh {
                let a = out[i + nxh * (jl + nyl * k)];
                let b = spec[i + nxh * (rows.start + jl + n[1] * k)];
                worst = worst.max((a - b).norm() / scale);
            }
        }
    }
    let mut back = vec![0.0; eng.real_len()];
    eng.inverse(
        Some(&out),
        &mut vec![C64::default(); eng.complex_len()],
        &mut back,
    );
    let amp = whole.iter().map(|x| x.abs()).fold(0.0, f64::max);
    for (a, b) in back.iter().zip(&mine) {
        worst = worst.max((a - b).abs() / amp);
    }
    comm.max_one(worst)
}

/// Halo planes from the neighbours (periodic in z) are the whole field's planes next to this
/// process's slab; returns the number of wrong values over every process (0 expected).
pub fn halo_planes_are_the_neighbours(comm: Arc<Comm>, n: [usize; 3]) -> f64 {
    let grid = Grid::new(n, 0.1, [0.0; 3]);
    let whole = field(&grid, 2);
    let slabs = Slabs::new(n, comm.size(), comm.rank()).expect("grid splits");
    let planes = slabs.my_planes();
    let p = grid.plane();
    let mine = local_planes(&grid, &whole, planes.clone());
    let (first, last) = (&mine[..p], &mine[mine.len() - p..]);
    let (mut below, mut above) = (vec![0.0; p], vec![0.0; p]);
    comm.exchange(&slabs, first, last, &mut below, &mut above);
    let kb = (planes.start + n[2] - 1) % n[2];
    let ka = planes.end % n[2];
    let wrong = below
        .iter()
        .zip(&whole[kb * p..(kb + 1) * p])
        .chain(above.iter().zip(&whole[ka * p..(ka + 1) * p]))
        .filter(|(a, b)| a != b)
        .count();
    comm.sum_one(wrong as f64)
}

/// Sums over the processes are the same bits on every process, and are the rank-ordered sum;
/// returns the number of processes that disagree (0 expected).
pub fn sums_are_identical_everywhere(comm: Arc<Comm>) -> f64 {
    // Values whose sum depends on the order of the additions.
    let term = |r: usize| {
        [
            1e16 * (r as f64 + 1.0).sin(),
            1.0 / (r as f64 + 3.0),
            -(r as f64),
        ]
    };
    let mut v = term(comm.rank());
    comm.sum(&mut v);
    let mut ordered = term(0);
    for r in 1..comm.size() {
        let t = term(r);
        for e in 0..3 {
            ordered[e] += t[e];
        }
    }
    let mine = v
        .iter()
        .zip(&ordered)
        .any(|(a, b)| a.to_bits() != b.to_bits());
    let mut m = [comm.max_one(v[0]), -comm.max_one(-v[0])];
    // The maximum and minimum over the processes of the first sum agree only if every process
    // holds the same bits.
    m[0] -= m[1];
    comm.sum_one(f64::from(u8::from(mine))) + f64::from(u8::from(m[0] != 0.0))
}

/// The split spectral operators give the whole grid's results on this process's planes: the
/// diffusion with damping (and the energy it removed), the velocity from the diffused
/// vorticity with a background flow, the Laplacian's inverse and the forcing's velocity;
/// returns the largest difference relative to each result's size (over every process).
pub fn spectral_matches_whole(comm: Arc<Comm>, n: [usize; 3]) -> f64 {
    let grid = Grid::new(n, 0.05, [0.1, 0.0, -0.3]);
    let damp = TopDamping {
        strength: 0.5,
        order: 2,
    };
    let (nu_dt, bg) = (2e-3, [0.1, -0.2, 0.3]);
    let omega: Vec<Vec<f64>> = (0..3).map(|c| field(&grid, 4 + c)).collect();

    let mut whole = Spectral::new(&grid);
    whole.reserve_forcing();
    let mut w_whole = omega.clone();
    let e_whole = whole.diffuse(&mut w_whole, nu_dt, damp, 1);
    let mut u_whole = vec![vec![0.0; grid.len()]; 3];
    whole.velocity(&mut w_whole, 1, bg, &mut u_whole);
    let mut x_whole = vec![0.0; grid.len()];
    whole.solve_laplacian(&omega[0], &mut x_whole);
    let mut f_whole = vec![vec![0.0; grid.len()]; 3];
    whole.forcing_velocity(&omega, nu_dt, &mut f_whole);

    let mut sp = Spectral::split(&grid, comm.clone()).expect("grid splits");
    sp.reserve_forcing();
    let planes = Slabs::new(n, comm.size(), comm.rank()).unwrap().my_planes();
    let local = |v: &Vec<f64>| local_planes(&grid, v, planes.clone());
    let om: Vec<Vec<f64>> = omega.iter().map(local).collect();
    let mut w = om.clone();
    let e = sp.diffuse(&mut w, nu_dt, damp, 1);
    let mut u = vec![vec![0.0; w[0].len()]; 3];
    sp.velocity(&mut w, 1, bg, &mut u);
    let mut x = vec![0.0; w[0].len()];
    sp.solve_laplacian(&om[0], &mut x);
    let mut f = vec![vec![0.0; w[0].len()]; 3];
    sp.forcing_velocity(&om, nu_dt, &mut f);

    let rel = |a: &[f64], whole: &[f64]| {
        let scale = whole.iter().map(|v| v.abs()).fold(0.0, f64::max);
        let b = &whole[planes.start * grid.plane()..planes.end * grid.plane()];
        a.iter()
            .zip(b)
            .map(|(p, q)| (p - q).abs())
            .fold(0.0, f64::max)
            / scale
    };
    let mut worst = ((e - e_whole) / e_whole).abs();
    for c in 0..3 {
        worst = worst
            .max(rel(&w[c], &w_whole[c]))
            .max(rel(&u[c], &u_whole[c]))
            .max(rel(&f[c], &f_whole[c]));
    }
    worst = worst.max(rel(&x, &x_whole));
    comm.max_one(worst)
}

/// `scene` built whole (on this process alone) and split over the processes of `comm`.
fn whole_and_split(
    comm: &Arc<Comm>,
    scene: &str,
) -> (
    tumble::sim::engine::Simulation,
    tumble::sim::engine::Simulation,
) {
    use tumble::scene::Scene;
    use tumble::sim::engine::Simulation;
    let parse = || Scene::parse(scene, "check.ron", "check").expect("scene parses");
    let whole = Simulation::new(parse()).expect("whole simulation builds");
    let split = Simulation::builder(parse())
        .on_processes(comm.clone())
        .build()
        .expect("split simulation builds");
    (whole, split)
}

/// A scene stepped on the processes of `comm` gives the same global quantities, step by step,
/// as on one process (run whole on every process); returns the largest relative difference of
/// energy, enstrophy, max|ω|, max|u|, the time step and the time, and of the circulation
/// against max|ω| times the volume, over `steps` steps (over every process).
pub fn simulation_matches_whole(comm: Arc<Comm>, scene: &str, steps: usize) -> f64 {
    let (mut whole, mut split) = whole_and_split(&comm, scene);
    let rel = |a: f64, b: f64| {
        if a == b {
            0.0
        } else {
            (a - b).abs() / a.abs().max(b.abs())
        }
    };
    let volume: f64 = whole.grid().extent().iter().product();
    let mut worst = 0.0f64;
    for _ in 0..=steps {
        let (a, b) = (whole.sample(), split.sample());
        // |∫ω dV| of a periodic flow is zero up to round-off: held to its natural scale,
        // max|ω| times the box's volume.
        let circ = (a.circulation - b.circulation).abs() / (a.max_omega * volume);
        worst = worst.max(circ);
        for (x, y) in [
            (a.energy, b.energy),
            (a.enstrophy, b.enstrophy),
            (a.max_omega, b.max_omega),
            (a.max_u, b.max_u),
            (a.dt, b.dt),
            (a.t, b.t),
        ] {
            worst = worst.max(rel(x, y));
        }
        whole.step().expect("whole step");
        split.step().expect("split step");
    }
    comm.max_one(worst)
}

/// A 3D Taylor-Green vortex at Re = 1600 on 24 x 20 x 36 nodes (three box lengths along z, so
/// that every process holds six planes or more on 2 and 3 processes).
pub const TAYLOR_GREEN: &str = r#"Scene(
    name: "tg",
    domain: (extent: [6.283185307179586, 5.235987755982989, 9.42477796076938], cells: [24, 20, 36]),
    fluid: (viscosity: 0.000625),
    numerics: (dt: Adaptive(c: 0.5, dt_max: 0.1), end_time: 5.0),
    initial: [TaylorGreen3d(amplitude: 1.0, wavenumber: 1.0)],
)"#;

/// A vortex ring travelling along z across the processes' slabs.
pub const VORTEX_RING: &str = r#"Scene(
    name: "ring",
    domain: (extent: [2.0, 2.0, 2.0], cells: [24, 24, 24]),
    fluid: (viscosity: 0.0005),
    numerics: (dt: Adaptive(c: 0.5, dt_max: 0.02), end_time: 1.0),
    initial: [VortexRing(center: [1.0, 1.0, 0.6], axis: [0.0, 0.0, 1.0], radius: 0.4,
        core_radius: 0.15, circulation: 1.0)],
)"#;

/// Two spheres and an ellipsoid falling in a closed channel (a static body), two of them
/// touching within the first steps.
pub const BODIES: &str = r#"Scene(
    name: "bodies",
    domain: (extent: [1.0, 1.0, 2.0], cells: [20, 20, 40]),
    fluid: (density: 1.0, viscosity: 0.01, gravity: [0.0, 0.0, -980.0]),
    numerics: (dt: Adaptive(c: 0.8, dt_max: 0.07), end_time: 1.0),
    contact: (kappa: 25.0),
    bodies: [
        (name: "channel", shape: Complement(Box(half_extents: [0.425, 0.425, 0.925])), kind: Static, position: [0.5, 0.5, 1.0]),
        (name: "upper", shape: Sphere(radius: 0.15), density: 1.5, position: [0.5, 0.5, 1.15]),
        (name: "lower", shape: Sphere(radius: 0.15), density: 1.2, position: [0.55, 0.55, 0.8]),
        (name: "bar", shape: Ellipsoid(radii: [0.2, 0.1, 0.08]), density: 2.0, position: [0.45, 0.5, 0.3], rotation: [0.3, 0.2, 0.1]),
    ],
)"#;

/// A sphere settling in a periodic box whose patch (13 planes of 18) wraps round the periodic
/// z axis so that on two processes it holds both ends of the first one's slab but not its
/// middle (the patch is then the whole box there, `GridPatch::holds`).
pub const PERIODIC_SPHERE: &str = r#"Scene(
    name: "periodic-sphere",
    domain: (extent: [1.0, 1.0, 1.125], cells: [16, 16, 18]),
    fluid: (density: 1.0, viscosity: 0.05, gravity: [0.0, 0.0, -60.0]),
    numerics: (end_time: 1.0),
    bodies: [(name: "ball", shape: Sphere(radius: 0.2), density: 2.0, position: [0.5, 0.5, 0.8125])],
)"#;

/// A pool in a tank (static walls) at the air/water ratio 1:1000, a light and a heavy sphere
/// dropped into it: the momentum form's transport, the free surface's extensions into the walls
/// and the spheres (which straddle the processes' slabs on 2 and 3 processes), its
/// redistancing and volume, and the multigrid-preconditioned pressure solve.
pub const POOL: &str = r#"Scene(
    name: "pool",
    domain: (extent: [1.0, 1.0, 1.5], cells: [24, 24, 36]),
    fluid: (density: 1.0, viscosity: 0.001, gravity: [0.0, 0.0, -1.0]),
    free_surface: Some((gas_density: 0.001, liquid: [Below(height: 0.6)])),
    numerics: (end_time: 1.0),
    bodies: [
        (name: "tank", shape: Complement(Box(half_extents: [0.4, 0.4, 0.65])), kind: Static, position: [0.5, 0.5, 0.75]),
        (name: "light", shape: Sphere(radius: 0.12), density: 0.5, position: [0.35, 0.5, 0.68]),
        (name: "heavy", shape: Sphere(radius: 0.12), density: 2.0, position: [0.65, 0.5, 0.62]),
    ],
)"#;

/// Two runs of a scene on the same processes are the same to the bit: the global quantities
/// and this process's fields after `steps` steps; returns the number of processes where they
/// differ (0 expected).
pub fn split_runs_are_bit_identical(comm: Arc<Comm>, scene: &str, steps: usize) -> f64 {
    use tumble::scene::Scene;
    use tumble::sim::engine::Simulation;
    let run = || {
        let scene = Scene::parse(scene, "check.ron", "check").expect("scene parses");
        let mut sim = Simulation::builder(scene)
            .on_processes(comm.clone())
            .build()
            .expect("split simulation builds");
        for _ in 0..steps {
            sim.step().expect("split step");
        }
        let s = sim.sample();
        let f = sim.fields();
        let mut bits: Vec<u64> = [s.energy, s.enstrophy, s.circulation, s.max_omega, s.t]
            .iter()
            .map(|v| v.to_bits())
            .collect();
        for c in f.omega().iter().chain(&f.u) {
            bits.extend(c.iter().map(|v| v.to_bits()));
        }
        bits
    };
    let differ = run() != run();
    comm.sum_one(f64::from(u8::from(differ)))
}

/// A density field with a 1:1000 jump: "water" (1000) below 0.4 of the box's height along z
/// and in a ball, "air" (1) elsewhere, each node varied by up to ±20% (deterministic).
fn water_and_air(grid: &Grid) -> Vec<f64> {
    let [nx, ny, nz] = grid.n;
    (0..grid.len())
        .map(|c| {
            let (i, j, k) = (c % nx, (c / nx) % ny, c / grid.plane());
            let d = [
                i as f64 - 0.6 * nx as f64,
                j as f64 - 0.45 * ny as f64,
                k as f64 - 0.7 * nz as f64,
            ];
            let ball = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt() < 0.2 * nz as f64;
            let r = ((c * 2654435761 + 12345) % 1000003) as f64 / 1000003.0 - 0.5;
            let rho = if (k as f64) < 0.4 * nz as f64 || ball {
                1000.0
            } else {
                1.0
            };
            rho * (1.0 + 0.4 * r)
        })
        .collect()
}

/// β = 1/ρ̄ on the faces toward +x, +y, +z, ρ̄ the mean of the face's two nodes (the pressure
/// system's rule), stored at the lower node, on the whole grid.
fn face_beta(grid: &Grid, rho: &[f64]) -> Vec<Vec<f64>> {
    let n = grid.n;
    (0..3)
        .map(|a| {
            (0..grid.len())
                .map(|c| {
                    let mut q = [c % n[0], (c / n[0]) % n[1], c / grid.plane()];
                    q[a] = (q[a] + 1) % n[a];
                    2.0 / (rho[c] + rho[grid.idx(q[0], q[1], q[2])])
                })
                .collect()
        })
        .collect()
}

/// The values of `a` whose bits differ from `b`'s.
fn differing(a: &[f64], b: &[f64]) -> usize {
    a.iter()
        .zip(b)
        .filter(|(x, y)| x.to_bits() != y.to_bits())
        .count()
        + a.len().abs_diff(b.len())
}

/// The split multigrid V-cycle ([`Multigrid::split`], from this process's planes of β at a
/// 1:1000 contrast) applied to two rough fields gives the whole grid's V-cycle on this
/// process's planes, bit for bit; returns the number of differing values over every process
/// (0 expected).
pub fn multigrid_matches_whole(comm: Arc<Comm>, n: [usize; 3]) -> f64 {
    use tumble::parallel::Decomposition;
    use tumble::solvers::multigrid::Multigrid;
    let grid = Grid::new(n, 1.0 / n[0] as f64, [0.0; 3]);
    let beta = face_beta(&grid, &water_and_air(&grid));
    let mut whole = Multigrid::new(&grid);
    whole.set_coefficients(&beta);
    let d = Decomposition::new(&grid, comm.clone()).expect("grid splits");
    let local = d.local_grid(&grid);
    let planes = d.slabs.my_planes();
    let mine = |v: &Vec<f64>| local_planes(&grid, v, planes.clone());
    let mut split = Multigrid::split(&local, &d);
    split.set_coefficients(&beta.iter().map(mine).collect::<Vec<_>>());
    let mut wrong = 0;
    for seed in [5, 6] {
        let r = field(&grid, seed);
        let mut z = vec![0.0; grid.len()];
        whole.apply(&r, &mut z);
        let mut zl = vec![1.0; local.len()];
        split.apply(&mine(&r), &mut zl);
        wrong += differing(&zl, &mine(&z));
    }
    comm.sum_one(wrong as f64)
}

/// The variable-coefficient Poisson solve preconditioned by the split multigrid (β at a
/// 1:1000 contrast) gives the whole grid's solve bit for bit: the same iterations, residual
/// and φ on this process's planes; returns the number of differing values over every process
/// (0 expected; infinite if either solve was not preconditioned by multigrid).
pub fn variable_poisson_matches_whole(comm: Arc<Comm>, n: [usize; 3]) -> f64 {
    use tumble::parallel::Decomposition;
    use tumble::solvers::Spectral;
    use tumble::solvers::variable_poisson::{Preconditioner, VariablePoisson};
    let grid = Grid::new(n, 1.0 / n[0] as f64, [0.0; 3]);
    let beta = face_beta(&grid, &water_and_air(&grid));
    let rhs = field(&grid, 8);
    let solve = |grid: &Grid, d: Option<&Decomposition>, mine: &dyn Fn(&Vec<f64>) -> Vec<f64>| {
        let mut vp = VariablePoisson::new(grid, true, d);
        vp.beta = beta.iter().map(mine).collect();
        vp.fill_beta_halo(grid);
        vp.rhs = mine(&rhs);
        let with = vp.choose();
        let mut phi = vec![0.0; grid.len()];
        let mut spectral = Spectral::of_grid(grid, d);
        let (it, res) = vp.solve(grid, &mut phi, &mut spectral, with, 1e-7);
        (vp.preconditioner, it, res, phi)
    };
    let (pw, iw, rw, phi_w) = solve(&grid, None, &|v: &Vec<f64>| v.clone());
    let d = Decomposition::new(&grid, comm.clone()).expect("grid splits");
    let local = d.local_grid(&grid);
    let planes = d.slabs.my_planes();
    let mine = |v: &Vec<f64>| local_planes(&grid, v, planes.clone());
    let (ps, is, rs, phi_s) = solve(&local, Some(&d), &mine);
    if pw != Preconditioner::Multigrid || ps != Preconditioner::Multigrid {
        return f64::INFINITY;
    }
    let wrong = differing(&phi_s, &mine(&phi_w))
        + usize::from(iw != is)
        + usize::from(rw.to_bits() != rs.to_bits());
    comm.sum_one(wrong as f64)
}

/// [`BODIES`] with a sphere of density 10 as well, moved at a prescribed velocity (a kinematic
/// body, which the projection moves: its density is part of ρ, unlike the Newton-Euler bodies'),
/// so that β spans a ratio of 10 and the pressure solve is preconditioned by multigrid.
pub fn dense_bodies() -> String {
    BODIES.replace(
        "\n    ],",
        "\n        (name: \"dense\", shape: Sphere(radius: 0.12), density: 10.0, position: [0.3, 0.7, 1.6], \
         kind: Kinematic(velocity: [0.0, 0.0, -3.0], angular_velocity: [0.0, 0.0, 2.0])),\n    ],",
    )
}

/// Whether the last pressure solve of `sim` was preconditioned by multigrid.
fn solved_by_multigrid(sim: &tumble::sim::engine::Simulation) -> bool {
    use tumble::solvers::variable_poisson::Preconditioner;
    use tumble::systems::pressure::PressureSolver;
    sim.world
        .get_resource::<PressureSolver>()
        .is_some_and(|p| p.poisson.preconditioner == Preconditioner::Multigrid)
}

/// A scene stepped on the processes of `comm` gives one process's run bit for bit: every
/// step's global quantities and, after `steps` steps, this process's planes of ω and u;
/// returns the number of differing values over every process (0 expected; infinite if a
/// step's pressure solve was not preconditioned by multigrid, which this check is about).
pub fn multigrid_scene_matches_whole_bit_for_bit(
    comm: Arc<Comm>,
    scene: &str,
    steps: usize,
) -> f64 {
    use tumble::sim::engine::Simulation;
    let (mut whole, mut split) = whole_and_split(&comm, scene);
    let sample = |s: &Simulation| {
        let s = s.sample();
        [
            s.energy,
            s.enstrophy,
            s.circulation,
            s.max_omega,
            s.max_u,
            s.dt,
            s.t,
        ]
    };
    let mut wrong = 0;
    for _ in 0..steps {
        whole.step().expect("whole step");
        split.step().expect("split step");
        wrong += differing(&sample(&whole), &sample(&split));
        if !solved_by_multigrid(&whole) || !solved_by_multigrid(&split) {
            return f64::INFINITY;
        }
    }
    let grid = whole.grid().clone();
    let planes = split.grid().k0..split.grid().k0 + split.grid().n[2];
    let (fw, fs) = (whole.fields(), split.fields());
    for (a, b) in fw
        .omega()
        .iter()
        .zip(fs.omega())
        .chain(fw.u.iter().zip(&fs.u))
    {
        wrong += differing(b, &local_planes(&grid, a, planes.clone()));
    }
    comm.sum_one(wrong as f64)
}
