//! The cup (issue 17, the paper's Fig. 10 scene) as a closed, non-convex triangle mesh: the
//! generator's surface, `tumble mesh cup`, the committed `scenes/meshes/cup.obj`, and the body
//! the engine makes of it (signed distance with the cavity outside the solid; volume, centroid
//! and inertia integrated from χ on the grid). Every reference value is the analytic geometry
//! of the polygonal solid (regular `N`-gon prisms), not the code's own output.

use crate::common::Scratch;
use std::collections::HashMap;
use std::f64::consts::PI;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use glam::{DMat3, DVec3};
use tumble::bodies::heaviside;
use tumble::bodies::levelset::LocalLevelSet;
use tumble::bodies::meshgen::CupParams;
use tumble::bodies::shapes::{Shape, ShapeGeometry};

fn manifest_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn tmpdir(name: &str) -> Scratch {
    Scratch::new("cup", name)
}

fn tumble() -> Command {
    Command::new(env!("CARGO_BIN_EXE_tumble"))
}

/// Small deterministic generator (xorshift64*).
struct Rng(u64);
impl Rng {
    fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
    }
    fn in_box(&mut self, lo: DVec3, hi: DVec3) -> DVec3 {
        lo + (hi - lo) * DVec3::new(self.uniform(), self.uniform(), self.uniform())
    }
}

/// The analytic polygonal cup: outer prism (circumradius R, height H) minus the cavity
/// (circumradius R - t, height H - b), regular N-gons, axis z. `z0` is the base; the test
/// derives it from the requirement that the centre of volume is at the origin.
struct Cup {
    n: u32,
    r: f64,
    ri: f64,
    z0: f64,
    zb: f64,
    z1: f64,
}

impl Cup {
    fn new(p: &CupParams) -> Cup {
        let a = |r: f64| 0.5 * p.segments as f64 * r * r * (2.0 * PI / p.segments as f64).sin();
        let ri = p.radius - p.wall;
        let (h, b) = (p.height, p.bottom);
        // centroid height above the base: (A_R H H/2 - A_Ri (H-b)(b + (H-b)/2)) / V
        let v = a(p.radius) * h - a(ri) * (h - b);
        let zc = (a(p.radius) * h * h / 2.0 - a(ri) * (h - b) * (b + (h - b) / 2.0)) / v;
        let z0 = -zc;
        Cup {
            n: p.segments,
            r: p.radius,
            ri,
            z0,
            zb: z0 + b,
            z1: z0 + h,
        }
    }
    fn alpha(&self) -> f64 {
        2.0 * PI / self.n as f64
    }
    /// Area of the N-gon of circumradius r.
    fn area(&self, r: f64) -> f64 {
        0.5 * self.n as f64 * r * r * self.alpha().sin()
    }
    /// Polar second moment of the N-gon about its centre, sum of the N triangles (0, p, q):
    /// (A/6)(|p|^2 + p.q + |q|^2).
    fn polar(&self, r: f64) -> f64 {
        let a = self.alpha();
        self.n as f64 * r.powi(4) * a.sin() * (2.0 + a.cos()) / 12.0
    }
    /// Volume, first moment along z and inertia about the origin of the prism of the N-gon
    /// of circumradius r between za and zb.
    fn prism(&self, r: f64, za: f64, zb: f64) -> (f64, f64, DVec3) {
        let (l, a, j) = (zb - za, self.area(r), self.polar(r));
        let z2 = (zb.powi(3) - za.powi(3)) / 3.0;
        let ixx = j / 2.0 * l + a * z2;
        (
            a * l,
            a * (zb * zb - za * za) / 2.0,
            DVec3::new(ixx, ixx, j * l),
        )
    }
    /// Volume, centroid z and diagonal inertia about the origin of the solid.
    fn mass(&self) -> (f64, f64, DVec3) {
        let (vo, mo, io) = self.prism(self.r, self.z0, self.z1);
        let (vi, mi, ii) = self.prism(self.ri, self.zb, self.z1);
        (vo - vi, (mo - mi) / (vo - vi), io - ii)
    }
    /// The apothem coordinate of p: its projection on the normal of the polygon edge whose
    /// angular sector holds it (the polygon of circumradius r holds p iff s < r cos(alpha/2)).
    fn apothem(&self, p: DVec3) -> f64 {
        let a = self.alpha();
        let th = p.y.atan2(p.x).rem_euclid(2.0 * PI);
        let mid = ((th / a).floor() + 0.5) * a;
        p.x * mid.cos() + p.y * mid.sin()
    }
    /// Exact inside test and the distance to the nearest face plane involved (to skip points
    /// that are too close to the surface to judge).
    fn inside(&self, p: DVec3) -> (bool, f64) {
        let c = (self.alpha() / 2.0).cos();
        let s = self.apothem(p);
        let in_outer = p.z > self.z0 && p.z < self.z1 && s < self.r * c;
        let in_cavity = p.z > self.zb && s < self.ri * c;
        let margin = [
            p.z - self.z0,
            p.z - self.z1,
            p.z - self.zb,
            s - self.r * c,
            s - self.ri * c,
        ]
        .map(f64::abs)
        .into_iter()
        .fold(f64::INFINITY, f64::min);
        (in_outer && !in_cavity, margin)
    }
}

fn load(dir: &Path, file: &str) -> ShapeGeometry {
    let s = Shape::Mesh {
        file: file.into(),
        scale: 1.0,
    };
    s.validate(3).unwrap();
    s.build(dir).unwrap()
}

#[test]
fn generated_cup_is_closed_outward_and_exact() {
    let p = CupParams::default();
    let m = p.mesh().unwrap();
    let n = p.segments as usize;
    assert_eq!(m.vertices.len(), 4 * n + 2);
    assert_eq!(m.triangles.len(), 8 * n);
    // every edge in exactly two triangles, traversed in opposite directions
    let mut edges: HashMap<(u32, u32), i32> = HashMap::new();
    for t in &m.triangles {
        for k in 0..3 {
            *edges.entry((t[k], t[(k + 1) % 3])).or_insert(0) += 1;
        }
    }
    for (&(a, b), &c) in &edges {
        assert_eq!(c, 1, "edge {a}->{b} used {c} times in one direction");
        assert_eq!(edges.get(&(b, a)), Some(&1), "edge {a}->{b} has no twin");
    }
    // Euler characteristic of a sphere-like closed surface: V - E + F = 2
    let (v, e, f) = (m.vertices.len(), edges.len() / 2, m.triangles.len());
    assert_eq!(v as i64 - e as i64 + f as i64, 2);
    // signed volume (divergence theorem) and moments vs the analytic polygonal solid:
    // positive (outward normals), exact to rounding
    let cup = Cup::new(&p);
    let (va, za, ia) = cup.mass();
    let mut vol = 0.0;
    let mut mz = 0.0;
    for t in &m.triangles {
        let [a, b, c] = t.map(|i| m.vertices[i as usize]);
        let d = a.dot(b.cross(c)) / 6.0;
        assert!((b - a).cross(c - a).length() > 1e-8, "degenerate triangle");
        vol += d;
        mz += d * (a.z + b.z + c.z) / 4.0;
    }
    assert!((vol - va).abs() < 1e-12 * va, "volume {vol} vs {va}");
    assert!((mz / vol - za).abs() < 1e-12, "centroid z {}", mz / vol);
    assert!(za.abs() < 1e-15, "analytic centroid at the origin: {za}");
    assert!((p.volume() - va).abs() < 1e-12 * va);
    // every vertex on the profile: radius 0, R or R - t; height z0, zb or z1
    for x in &m.vertices {
        let r = x.truncate().length();
        assert!([0.0, cup.r, cup.ri].iter().any(|q| (r - q).abs() < 1e-12));
        assert!(
            [cup.z0, cup.zb, cup.z1]
                .iter()
                .any(|q| (x.z - q).abs() < 1e-12)
        );
    }
    // through the loader: the polyhedron's volume and inertia about the origin
    let dir = tmpdir("exact");
    std::fs::write(dir.join("c.obj"), m.to_obj("test")).unwrap();
    let g = load(&dir, "c.obj");
    assert!((g.volume().unwrap() - va).abs() < 1e-12 * va);
    let i = g.inertia_unit_density().unwrap();
    for a in 0..3 {
        assert!((i.col(a)[a] - ia[a]).abs() < 1e-10 * ia[a], "I[{a}]");
    }
    assert!(i.x_axis.y.abs() + i.x_axis.z.abs() + i.y_axis.z.abs() < 1e-12 * ia.z);
    let (lo, hi) = g.bounds().unwrap();
    assert!((lo.z - cup.z0).abs() < 1e-12 && (hi.z - cup.z1).abs() < 1e-12);

    // bad numbers are errors, not panics
    for (bad, what) in [
        (CupParams { wall: 0.1, ..p }, "thinner than the radius"),
        (CupParams { bottom: 0.3, ..p }, "thinner than the height"),
        (CupParams { radius: -1.0, ..p }, "radius"),
        (
            CupParams {
                height: f64::NAN,
                ..p
            },
            "height",
        ),
        (CupParams { segments: 3, ..p }, "segments"),
    ] {
        let e = bad.mesh().unwrap_err();
        assert!(e.contains(what), "{e}");
    }
}

#[test]
fn signed_distance_cavity_is_outside() {
    let p = CupParams::default();
    let cup = Cup::new(&p);
    let g = load(&manifest_dir().join("scenes"), "meshes/cup.obj");
    let c = (cup.alpha() / 2.0).cos();
    // known values (the nearest feature is a face, the distance is to its plane)
    let mid_edge = |s: f64, z: f64| {
        let a = cup.alpha() / 2.0;
        DVec3::new(s * a.cos(), s * a.sin(), z)
    };
    let zw = 0.5 * (cup.zb + cup.z1);
    let known = [
        // cavity, just above the floor: outside, the floor at 0.01
        (
            DVec3::new(0.0, 0.0, cup.zb + 0.01),
            -0.01,
            "cavity above floor",
        ),
        // cavity centre, mid-height: outside, nearest the inner wall's edge midpoints
        (DVec3::new(0.0, 0.0, zw), -cup.ri * c, "cavity centre"),
        // inside the bottom, on the axis: between base and floor
        (
            DVec3::new(0.0, 0.0, cup.z0 + p.bottom / 2.0),
            p.bottom / 2.0,
            "bottom",
        ),
        // below the base
        (DVec3::new(0.0, 0.0, cup.z0 - 0.01), -0.01, "below base"),
        // inside the wall, half way through it
        (
            mid_edge(0.5 * (cup.r + cup.ri) * c, zw),
            0.5 * (cup.r - cup.ri) * c,
            "wall",
        ),
        // above the rim
        (
            mid_edge(0.5 * (cup.r + cup.ri) * c, cup.z1 + 0.01),
            -0.01,
            "above rim",
        ),
        // just inside the rim, below it
        (
            mid_edge(0.5 * (cup.r + cup.ri) * c, cup.z1 - 0.005),
            0.005,
            "under rim",
        ),
        // outside the outer wall
        (mid_edge(cup.r * c + 0.02, 0.0), -0.02, "outside wall"),
        // cavity, next to the inner wall
        (
            mid_edge(cup.ri * c - 0.004, zw),
            -0.004,
            "cavity by the wall",
        ),
    ];
    for (x, want, what) in known {
        let got = g.phi(x);
        assert!(
            (got - want).abs() < 1e-12,
            "{what}: phi({x}) = {got}, expected {want}"
        );
    }
    // sign everywhere around the cup, with extra points near the rim (the corners where a
    // pseudo-normal sign could go wrong) and the poles of the base and the floor
    let mut rng = Rng(17);
    let lo = DVec3::new(-cup.r - 0.03, -cup.r - 0.03, cup.z0 - 0.03);
    let hi = DVec3::new(cup.r + 0.03, cup.r + 0.03, cup.z1 + 0.03);
    let mut checked = [0usize; 2];
    let regions = [
        (lo, hi),
        // the rim, all around
        (
            DVec3::new(-cup.r - 0.005, -cup.r - 0.005, cup.z1 - 0.005),
            DVec3::new(cup.r + 0.005, cup.r + 0.005, cup.z1 + 0.005),
        ),
        // the floor's and the base's centres
        (
            DVec3::new(-0.005, -0.005, cup.zb - 0.005),
            DVec3::new(0.005, 0.005, cup.zb + 0.005),
        ),
        (
            DVec3::new(-0.005, -0.005, cup.z0 - 0.005),
            DVec3::new(0.005, 0.005, cup.z0 + 0.005),
        ),
    ];
    for (k, &(a, b)) in regions.iter().enumerate() {
        for _ in 0..if k == 0 { 40_000 } else { 10_000 } {
            let x = rng.in_box(a, b);
            let (inside, margin) = cup.inside(x);
            if margin < 1e-9 {
                continue;
            }
            let phi = g.phi(x);
            assert_eq!(phi > 0.0, inside, "sign of phi({x}) = {phi}");
            checked[inside as usize] += 1;
        }
    }
    assert!(checked[0] > 10_000 && checked[1] > 5_000, "{checked:?}");
    // inside the cavity, below the rim: always outside the solid
    for _ in 0..5000 {
        let x = rng.in_box(
            DVec3::new(-cup.ri, -cup.ri, cup.zb),
            DVec3::new(cup.ri, cup.ri, cup.z1),
        );
        if cup.apothem(x) < cup.ri * c - 1e-9 && x.z > cup.zb + 1e-9 {
            assert!(g.phi(x) < 0.0, "cavity point {x} inside the solid");
        }
    }
}

/// χ = H_ε(φ) of the body's local level set, integrated on a flow grid of spacing `h` as the
/// engine does (node sums times h³, ε = h, the default `interface_cells` 1), the body centred
/// at `centre` (off the nodes): volume, centroid, inertia about the centroid.
fn chi_moments(ls: &LocalLevelSet, h: f64, centre: DVec3) -> (f64, DVec3, DMat3) {
    let (lo, hi) = ls.bounds().unwrap();
    let (lo, hi) = (lo + centre, hi + centre);
    let i0 = (lo / h).floor();
    let n = ((hi - lo) / h).ceil() + DVec3::splat(2.0);
    let (mut v, mut m1, mut m2) = (0.0, DVec3::ZERO, DMat3::ZERO);
    for k in 0..n.z as i64 {
        for j in 0..n.y as i64 {
            for i in 0..n.x as i64 {
                let x = (i0 + DVec3::new(i as f64, j as f64, k as f64)) * h;
                let chi = heaviside(ls.phi(x - centre), h);
                if chi == 0.0 {
                    continue;
                }
                let r = x - centre;
                v += chi;
                m1 += chi * r;
                m2 += chi * DMat3::from_cols(r * r.x, r * r.y, r * r.z);
            }
        }
    }
    let dv = h * h * h;
    let vol = v * dv;
    let d = m1 * dv / vol;
    // second moments about the centroid, then I = tr(C) Id - C
    let cov = m2 * dv - vol * DMat3::from_cols(d * d.x, d * d.y, d * d.z);
    let tr = cov.x_axis.x + cov.y_axis.y + cov.z_axis.z;
    (vol, d, DMat3::from_diagonal(DVec3::splat(tr)) - cov)
}

#[test]
fn voxelised_cup_volume_centroid_inertia() {
    let p = CupParams::default();
    let cup = Cup::new(&p);
    let (va, za, ia) = cup.mass();
    let g = load(&manifest_dir().join("scenes"), "meshes/cup.obj");
    let middle = 0.5 * (cup.z0 + cup.z1);
    // Tolerances from the resolution. At 128 cells per unit the wall is 3.2 cells thick: its
    // distance ridge (1.6 h) is above eps = h, χ = 1 across its middle, and the errors are
    // curvature and corner terms of order h^2: 2% (the bound). At 64 the wall is 1.6
    // cells: the ridge (0.8 h) is below eps, and the trilinear interpolation of the local
    // level set cuts it by delta (h - delta) per unit length (delta: the ridge's offset from
    // a node; mean h^2 / 6) where H' is 0.1/eps to 0.8/eps: the wall (85% of the volume) loses
    // 0.02 h to 0.13 h of its 1.6 h, 1% to 7%: 6% on the total.
    for (cells, vol_tol) in [(128.0, 0.02), (64.0, 0.06)] {
        let h = 1.0 / cells;
        let t0 = Instant::now();
        // the engine's reference band, `bodies::band`: 6 h
        let ls = LocalLevelSet::new(g.clone(), h, 6.0 * h, 3);
        let build = t0.elapsed();
        let centre = DVec3::new(0.5 + 0.31 * h, 0.5 + 0.17 * h, 0.5 + 0.43 * h);
        let (vol, d, i) = chi_moments(&ls, h, centre);
        let ev = vol / va - 1.0;
        let ei = DVec3::new(i.x_axis.x, i.y_axis.y, i.z_axis.z) / ia - DVec3::ONE;
        eprintln!(
            "cup at h = 1/{cells}: local level set {:?} nodes built in {build:?}; volume {vol:.6e} (analytic {va:.6e}, {:+.3}%), centroid {d} (analytic (0, 0, {za:.1e}), geometric middle z {middle:.4}), inertia diag {:?} (analytic {:?}, {:+.3?}%), off-diagonal {:.2e} {:.2e} {:.2e}",
            ls.dims().unwrap(),
            100.0 * ev,
            [i.x_axis.x, i.y_axis.y, i.z_axis.z],
            ia.to_array(),
            (100.0 * ei).to_array(),
            i.x_axis.y,
            i.x_axis.z,
            i.y_axis.z,
        );
        assert!(ev.abs() < vol_tol, "volume error {ev}");
        // the centroid on the axis (the grid's offset breaks the symmetry by at most a
        // small fraction of a cell), at the analytic one along it, below the middle
        assert!(
            d.x.abs() < 0.02 * h && d.y.abs() < 0.02 * h,
            "off axis: {d}"
        );
        assert!((d.z - za).abs() < 0.2 * h, "centroid z {}", d.z);
        assert!(
            d.z < middle - 0.5 * (middle - za),
            "centroid {} not below",
            d.z
        );
        // inertia: diagonal, Ixx = Iyy, near the analytic polygonal solid's
        for a in 0..3 {
            assert!(ei[a].abs() < 1.5 * vol_tol, "inertia [{a}] error {}", ei[a]);
        }
        // Ixx = Iyy up to the grid's anisotropy (the cup is off the nodes): a tenth of the
        // volume tolerance
        assert!(
            (i.x_axis.x - i.y_axis.y).abs() < 0.1 * vol_tol * ia.x,
            "Ixx != Iyy"
        );
        for off in [i.x_axis.y, i.x_axis.z, i.y_axis.z] {
            assert!(off.abs() < 1e-3 * ia.x, "off-diagonal {off}");
        }
    }
}

#[test]
fn obj_and_stl_give_the_same_body() {
    let dir = tmpdir("formats");
    for f in ["cup.obj", "cup.stl"] {
        let out = tumble()
            .args(["mesh", "cup", "--out"])
            .arg(dir.join(f))
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    let obj = load(&dir, "cup.obj");
    let stl = load(&dir, "cup.stl");
    // STL stores f32: coordinates below 0.2 move by at most 0.2 * 2^-24 = 1.2e-8
    let (vo, vs) = (obj.volume().unwrap(), stl.volume().unwrap());
    assert!((vo - vs).abs() < 1e-6 * vo, "volumes {vo} {vs}");
    let mut rng = Rng(5);
    for _ in 0..20_000 {
        let x = rng.in_box(DVec3::splat(-0.13), DVec3::splat(0.13));
        let (a, b) = (obj.phi(x), stl.phi(x));
        assert!((a - b).abs() < 5e-8, "phi({x}): obj {a} stl {b}");
    }
    let h = 1.0 / 64.0;
    let c = DVec3::splat(0.5);
    let (va, _, _) = chi_moments(&LocalLevelSet::new(obj, h, 6.0 * h, 3), h, c);
    let (vb, _, _) = chi_moments(&LocalLevelSet::new(stl, h, 6.0 * h, 3), h, c);
    assert!((va - vb).abs() < 1e-5 * va, "voxelised volumes {va} {vb}");
}

#[test]
fn committed_cup_is_the_commands_output() {
    let dir = tmpdir("committed");
    let out = dir.join("cup.obj");
    let run = |force: bool| {
        let mut c = tumble();
        c.args(["mesh", "cup", "--out"]).arg(&out);
        if force {
            c.arg("--force");
        }
        c.output().unwrap()
    };
    let st = run(false);
    assert!(
        st.status.success(),
        "{}",
        String::from_utf8_lossy(&st.stderr)
    );
    let made = std::fs::read_to_string(&out).unwrap();
    let committed = std::fs::read_to_string(manifest_dir().join("scenes/meshes/cup.obj")).unwrap();
    assert!(
        made == committed,
        "scenes/meshes/cup.obj differs from `tumble mesh cup --out scenes/meshes/cup.obj`"
    );
    // no overwrite without --force; --force replaces only a file tumble mesh wrote
    let st = run(false);
    assert_eq!(st.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&st.stderr).contains("--force"));
    assert!(run(true).status.success());
    std::fs::write(&out, "v 0 0 0\n").unwrap();
    let st = run(true);
    assert_eq!(st.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&st.stderr).contains("did not write"));
    assert_eq!(std::fs::read_to_string(&out).unwrap(), "v 0 0 0\n");
    // bad numbers and formats: clear errors, exit 2, nothing written
    for (args, msg) in [
        (&["--wall", "0.1"][..], "thinner than the radius"),
        (&["--bottom", "0.2"][..], "thinner than the height"),
        (&["--radius", "nan"][..], "radius must be a positive"),
        (&["--segments", "4"][..], "segments"),
    ] {
        let bad = dir.join("bad.obj");
        let st = tumble()
            .args(["mesh", "cup"])
            .args(args)
            .arg("--out")
            .arg(&bad)
            .output()
            .unwrap();
        assert_eq!(st.status.code(), Some(2), "{args:?}");
        assert!(
            String::from_utf8_lossy(&st.stderr).contains(msg),
            "{args:?}"
        );
        assert!(!bad.exists());
    }
    let st = tumble()
        .args(["mesh", "cup", "--out"])
        .arg(dir.join("cup.ply"))
        .output()
        .unwrap();
    assert_eq!(st.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&st.stderr).contains(".obj or .stl"));
}
