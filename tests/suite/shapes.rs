//! Body shapes: analytic signed distances, meshes (OBJ/STL loading, inside test on non-convex
//! meshes, errors), local level sets, and volumes/inertias against textbook formulas.

use std::f64::consts::PI;
use std::path::{Path, PathBuf};
use std::time::Instant;

use glam::{DMat3, DVec3};
use tumble::bodies::levelset::LocalLevelSet;
use tumble::bodies::shapes::{Shape, ShapeGeometry};

// ------------------------------------------------------------------------------------------
// helpers
// ------------------------------------------------------------------------------------------

/// Deterministic xorshift64* generator.
struct Rng(u64);
impl Rng {
    fn next_u64(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    /// uniform in [0, 1)
    fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.uniform()
    }
    fn in_box(&mut self, lo: DVec3, hi: DVec3) -> DVec3 {
        DVec3::new(
            self.range(lo.x, hi.x),
            self.range(lo.y, hi.y),
            self.range(lo.z, hi.z),
        )
    }
    fn unit(&mut self) -> DVec3 {
        loop {
            let v = self.in_box(DVec3::splat(-1.0), DVec3::ONE);
            let l = v.length();
            if l > 0.1 && l <= 1.0 {
                return v / l;
            }
        }
    }
}

fn build(shape: Shape) -> ShapeGeometry {
    shape.build(Path::new(".")).expect("build")
}

fn tmpdir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("tumble-shapes-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn assert_close(a: f64, b: f64, tol: f64, what: &str) {
    assert!(
        (a - b).abs() <= tol,
        "{what}: got {a}, expected {b} (tolerance {tol}, error {})",
        (a - b).abs()
    );
}

fn mesh_in(dir: &Path, file: &str) -> Result<ShapeGeometry, String> {
    Shape::Mesh {
        file: file.to_string(),
        scale: 1.0,
    }
    .build(dir)
}

type Tris = Vec<[usize; 3]>;

fn obj_text(verts: &[DVec3], tris: &[[usize; 3]]) -> String {
    let mut s = String::new();
    for v in verts {
        s += &format!("v {:.9} {:.9} {:.9}\n", v.x, v.y, v.z);
    }
    for t in tris {
        s += &format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    s
}

/// Icosphere: icosahedron subdivided `levels` times, vertices projected on the sphere of the
/// given radius, outward-oriented triangles.
fn icosphere(radius: f64, levels: usize) -> (Vec<DVec3>, Tris) {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let mut v: Vec<DVec3> = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .iter()
    .map(|a| DVec3::from_array(*a).normalize())
    .collect();
    let mut f: Tris = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..levels {
        let mut cache = std::collections::HashMap::new();
        let mut mid = |a: usize, b: usize, v: &mut Vec<DVec3>| -> usize {
            *cache.entry((a.min(b), a.max(b))).or_insert_with(|| {
                v.push((0.5 * (v[a] + v[b])).normalize());
                v.len() - 1
            })
        };
        let mut nf = Vec::with_capacity(f.len() * 4);
        for [a, b, c] in f {
            let ab = mid(a, b, &mut v);
            let bc = mid(b, c, &mut v);
            let ca = mid(c, a, &mut v);
            nf.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        f = nf;
    }
    (v.into_iter().map(|p| p * radius).collect(), f)
}

const ICO_RADIUS: f64 = 0.15;
const ICO_LEVELS: usize = 3;

fn manifest_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Closed surface of a union of unit voxels (scaled by `size`), outward oriented; the voxels
/// must meet along full faces (no edge-only or vertex-only contacts).
fn voxel_mesh(cells: &[[i32; 3]], size: f64) -> (Vec<DVec3>, Tris) {
    let filled = |c: [i32; 3]| cells.contains(&c);
    let mut index = std::collections::HashMap::new();
    let mut verts = Vec::new();
    let mut vid = |p: [i32; 3], verts: &mut Vec<DVec3>| -> usize {
        *index.entry(p).or_insert_with(|| {
            verts.push(DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64) * size);
            verts.len() - 1
        })
    };
    let mut tris = Vec::new();
    for &c in cells {
        for a in 0..3 {
            for s in [-1, 1] {
                let mut nb = c;
                nb[a] += s;
                if filled(nb) {
                    continue;
                }
                let (b, d) = ((a + 1) % 3, (a + 2) % 3);
                let mut base = c;
                if s > 0 {
                    base[a] += 1;
                }
                let mut q = [base; 4];
                q[1][b] += 1;
                q[2][b] += 1;
                q[2][d] += 1;
                q[3][d] += 1;
                let mut ids = q.map(|p| vid(p, &mut verts));
                if s < 0 {
                    ids.reverse();
                }
                tris.push([ids[0], ids[1], ids[2]]);
                tris.push([ids[0], ids[2], ids[3]]);
            }
        }
    }
    (verts, tris)
}

/// Exact signed distance to a union of voxels for points OUTSIDE (minimum of the distances to
/// each voxel), and the inside test.
fn voxel_union(cells: &[[i32; 3]], size: f64, p: DVec3) -> (bool, f64) {
    let mut inside = false;
    let mut dmin = f64::INFINITY;
    let mut phimax = f64::NEG_INFINITY;
    for c in cells {
        let lo = DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64) * size;
        let centre = lo + DVec3::splat(0.5 * size);
        let q = (p - centre).abs() - DVec3::splat(0.5 * size);
        let sdf = q.max(DVec3::ZERO).length() + q.max_element().min(0.0);
        inside |= sdf < 0.0;
        dmin = dmin.min(sdf.max(0.0));
        phimax = phimax.max(-sdf);
    }
    (inside, if inside { phimax } else { -dmin })
}

fn cube_triangles(half: f64) -> Vec<[DVec3; 3]> {
    let (v, t) = voxel_mesh(&[[0, 0, 0]], 2.0 * half);
    t.iter()
        .map(|t| t.map(|i| v[i] - DVec3::splat(half)))
        .collect()
}

fn ascii_stl(tris: &[[DVec3; 3]]) -> String {
    let mut s = String::from("solid cube\n");
    for t in tris {
        let n = (t[1] - t[0]).cross(t[2] - t[0]).normalize();
        s += &format!("  facet normal {} {} {}\n    outer loop\n", n.x, n.y, n.z);
        for v in t {
            s += &format!("      vertex {} {} {}\n", v.x, v.y, v.z);
        }
        s += "    endloop\n  endfacet\n";
    }
    s + "endsolid cube\n"
}

fn binary_stl(tris: &[[DVec3; 3]]) -> Vec<u8> {
    let mut b = vec![0u8; 80];
    b[..12].copy_from_slice(b"binary cube ");
    b.extend((tris.len() as u32).to_le_bytes());
    for t in tris {
        let n = (t[1] - t[0]).cross(t[2] - t[0]).normalize();
        for v in std::iter::once(n).chain(t.iter().copied()) {
            for c in v.to_array() {
                b.extend((c as f32).to_le_bytes());
            }
        }
        b.extend([0u8, 0u8]);
    }
    b
}

// ------------------------------------------------------------------------------------------
// analytic primitives
// ------------------------------------------------------------------------------------------

#[test]
fn primitives_signed_distance_at_known_points() {
    let e = 1e-12;
    let v = DVec3::new;

    let s = build(Shape::Sphere { radius: 0.5 });
    assert_close(s.phi(DVec3::ZERO), 0.5, e, "sphere centre");
    assert_close(s.phi(v(0.3, 0.0, 0.0)), 0.2, e, "sphere inside");
    assert_close(s.phi(v(0.0, 0.0, -1.5)), -1.0, e, "sphere outside");
    assert_close(s.phi(v(0.3, 0.4, 0.0)), 0.0, e, "sphere surface");

    let b = build(Shape::Box {
        half_extents: [1.0, 2.0, 3.0],
    });
    assert_close(b.phi(DVec3::ZERO), 1.0, e, "box centre");
    assert_close(b.phi(v(0.5, 1.9, 0.0)), 0.1, e, "box inside near y face");
    assert_close(b.phi(v(3.0, 0.0, 0.0)), -2.0, e, "box outside face");
    assert_close(
        b.phi(v(2.0, 3.0, 0.0)),
        -(2f64).sqrt(),
        e,
        "box outside edge",
    );
    assert_close(
        b.phi(v(-2.0, -3.0, 4.0)),
        -(3f64).sqrt(),
        e,
        "box outside corner",
    );

    let c = build(Shape::Cylinder {
        radius: 1.0,
        half_height: 2.0,
    });
    assert_close(c.phi(DVec3::ZERO), 1.0, e, "cylinder centre");
    assert_close(c.phi(v(0.0, 0.0, 1.5)), 0.5, e, "cylinder inside near cap");
    assert_close(c.phi(v(0.0, 3.0, 0.0)), -2.0, e, "cylinder outside side");
    assert_close(c.phi(v(0.0, 0.0, -5.0)), -3.0, e, "cylinder outside cap");
    assert_close(c.phi(v(0.6, 0.8, 0.0)), 0.0, e, "cylinder side surface");
    assert_close(c.phi(v(4.0, 0.0, 6.0)), -5.0, e, "cylinder outside rim");

    let k = build(Shape::Capsule {
        radius: 0.5,
        half_height: 1.0,
    });
    assert_close(k.phi(DVec3::ZERO), 0.5, e, "capsule centre");
    assert_close(k.phi(v(0.0, 0.0, 1.4)), 0.1, e, "capsule inside cap");
    assert_close(k.phi(v(0.0, 0.0, 2.5)), -1.0, e, "capsule outside above");
    assert_close(k.phi(v(0.0, 2.0, 0.7)), -1.5, e, "capsule outside side");
    assert_close(
        k.phi(v(3.0, 0.0, 5.0)),
        0.5 - 5.0,
        e,
        "capsule outside diagonal",
    );

    let h = build(Shape::HalfSpace {
        normal: [0.0, 0.0, 2.0],
        offset: 2.0,
    });
    // plane z = 1, solid below
    assert_close(h.phi(DVec3::ZERO), 1.0, e, "half-space inside");
    assert_close(h.phi(v(5.0, -7.0, 3.0)), -2.0, e, "half-space outside");
    let h2 = build(Shape::HalfSpace {
        normal: [1.0, 1.0, 0.0],
        offset: 0.0,
    });
    assert_close(
        h2.phi(v(1.0, 1.0, 9.0)),
        -(2f64).sqrt(),
        e,
        "oblique half-space",
    );

    let d = build(Shape::Disk { radius: 0.25 });
    assert_close(d.phi(v(0.0, 0.0, 7.0)), 0.25, e, "disk centre (z ignored)");
    assert_close(d.phi(v(0.0, -1.25, 0.0)), -1.0, e, "disk outside");

    let r = build(Shape::Rectangle {
        half_extents: [1.0, 0.5],
    });
    assert_close(
        r.phi(v(0.0, 0.0, -3.0)),
        0.5,
        e,
        "rectangle centre (z ignored)",
    );
    assert_close(
        r.phi(v(2.0, 1.5, 0.0)),
        -(2f64).sqrt(),
        e,
        "rectangle corner",
    );
    assert_close(r.phi(v(0.9, 0.0, 0.0)), 0.1, e, "rectangle inside");

    let el = build(Shape::Ellipse { radii: [2.0, 1.0] });
    assert_close(el.phi(DVec3::ZERO), 1.0, e, "ellipse centre");
    assert_close(
        el.phi(v(3.0, 0.0, 5.0)),
        -1.0,
        e,
        "ellipse outside on major axis",
    );
    assert_close(
        el.phi(v(0.0, -3.0, 0.0)),
        -2.0,
        e,
        "ellipse outside on minor axis",
    );
    assert_close(
        el.phi(v(0.0, 0.5, 0.0)),
        0.5,
        e,
        "ellipse inside on minor axis",
    );

    let ed = build(Shape::Ellipsoid {
        radii: [1.0, 3.0, 2.0],
    });
    assert_close(ed.phi(DVec3::ZERO), 1.0, e, "ellipsoid centre");
    assert_close(
        ed.phi(v(0.0, 4.0, 0.0)),
        -1.0,
        e,
        "ellipsoid outside y axis",
    );
    assert_close(
        ed.phi(v(0.0, 0.0, -2.5)),
        -0.5,
        e,
        "ellipsoid outside z axis",
    );
    assert_close(ed.phi(v(0.5, 0.0, 0.0)), 0.5, e, "ellipsoid inside x axis");
    assert_close(ed.phi(v(0.0, 3.0, 0.0)), 0.0, e, "ellipsoid surface");

    // complement flips the sign everywhere, and is unbounded
    let tube = build(Shape::Complement(Box::new(Shape::Cylinder {
        radius: 1.0,
        half_height: 2.0,
    })));
    let mut rng = Rng(7);
    for _ in 0..100 {
        let p = rng.in_box(DVec3::splat(-4.0), DVec3::splat(4.0));
        assert_close(tube.phi(p), -c.phi(p), 0.0, "complement");
    }
    assert!(tube.bounds().is_none() && h.bounds().is_none());
    assert!(tube.volume().is_none() && tube.inertia_unit_density().is_none());
    // double complement is the shape itself
    let cc = build(Shape::Complement(Box::new(Shape::Complement(Box::new(
        Shape::Sphere { radius: 0.5 },
    )))));
    assert_close(cc.phi(DVec3::ZERO), 0.5, e, "double complement");
    assert!(cc.bounds().is_some());

    // bounds
    assert_eq!(
        k.bounds().unwrap(),
        (v(-0.5, -0.5, -1.5), v(0.5, 0.5, 1.5)),
        "capsule bounds"
    );
    assert_eq!(
        d.bounds().unwrap(),
        (v(-0.25, -0.25, 0.0), v(0.25, 0.25, 0.0))
    );
    assert_eq!(
        ed.bounds().unwrap(),
        (v(-1.0, -3.0, -2.0), v(1.0, 3.0, 2.0))
    );
}

/// Points at distance `t` along the normal from a surface point of an ellipse(oid), with `|t|`
/// below the smallest radius of curvature, have that surface point as their closest point, so
/// phi = -t exactly; phi vanishes on the surface and |grad phi| = 1.
#[test]
fn ellipsoid_and_ellipse_distance_is_exact_and_eikonal() {
    let mut rng = Rng(12345);
    let fd = 1e-6;
    for (radii, dim2) in [
        (DVec3::new(0.3, 0.2, 0.1), false),
        (DVec3::new(0.1, 0.25, 0.4), false),
        (DVec3::new(0.3, 0.1, 0.0), true),
    ] {
        let geom = if dim2 {
            build(Shape::Ellipse {
                radii: [radii.x, radii.y],
            })
        } else {
            build(Shape::Ellipsoid {
                radii: radii.to_array(),
            })
        };
        let (rmin, rmax) = if dim2 {
            (radii.x.min(radii.y), radii.x.max(radii.y))
        } else {
            (radii.min_element(), radii.max_element())
        };
        let rho = rmin * rmin / rmax; // smallest radius of curvature
        let mut worst_grad: f64 = 0.0;
        let mut worst_phi: f64 = 0.0;
        for trial in 0..4000 {
            let mut u = rng.unit();
            if dim2 {
                u.z = 0.0;
                u = u.normalize();
            }
            // some directions in the coordinate planes / on the axes (special branches)
            match trial % 8 {
                0 => u.z = 0.0,
                1 => u.y = 0.0,
                2 => u.x = 0.0,
                3 => u = DVec3::new(u.x.signum(), 0.0, 0.0),
                4 if !dim2 => u = DVec3::new(0.0, 0.0, u.z.signum()),
                _ => {}
            }
            if u.length() == 0.0 {
                continue;
            }
            let u = u.normalize();
            let s = radii * u; // on the surface
            let nrm = if dim2 {
                DVec3::new(s.x / radii.x.powi(2), s.y / radii.y.powi(2), 0.0).normalize()
            } else {
                (s / (radii * radii)).normalize()
            };
            assert!(geom.phi(s).abs() < 1e-12, "phi on surface {}", geom.phi(s));
            let t = rng.range(-0.9 * rho, 0.9 * rho);
            let p = s + t * nrm;
            let phi = geom.phi(p);
            worst_phi = worst_phi.max((phi + t).abs());
            if t.abs() < 10.0 * fd {
                continue;
            }
            let axes = if dim2 { 2 } else { 3 };
            let mut g = DVec3::ZERO;
            for a in 0..axes {
                let mut dp = DVec3::ZERO;
                dp[a] = fd;
                g[a] = (geom.phi(p + dp) - geom.phi(p - dp)) / (2.0 * fd);
            }
            worst_grad = worst_grad.max((g.length() - 1.0).abs());
        }
        assert!(worst_phi < 1e-12, "{radii}: phi vs -t error {worst_phi}");
        assert!(
            worst_grad < 1e-3,
            "{radii}: ||grad phi| - 1| = {worst_grad}"
        );

        // further away (outside) and deep inside: still eikonal
        for _ in 0..2000 {
            let mut p = rng.in_box(-2.0 * radii, 2.0 * radii);
            if dim2 {
                p.z = 0.0;
            }
            let phi = geom.phi(p);
            assert!(
                phi <= rmin + 1e-12,
                "phi {phi} above the largest inscribed radius"
            );
            let axes = if dim2 { 2 } else { 3 };
            let mut g = DVec3::ZERO;
            for a in 0..axes {
                let mut dp = DVec3::ZERO;
                dp[a] = fd;
                g[a] = (geom.phi(p + dp) - geom.phi(p - dp)) / (2.0 * fd);
            }
            // outside a convex body the distance is smooth (inside, the medial axis is not)
            if phi < 0.0 {
                assert!(
                    (g.length() - 1.0).abs() < 1e-3,
                    "outside |grad| {}",
                    g.length()
                );
            }
        }
    }
}

// ------------------------------------------------------------------------------------------
// meshes
// ------------------------------------------------------------------------------------------

/// The committed `scenes/meshes/icosphere.obj` is exactly this generator's output; regenerate
/// with `cargo test --release --test suite -- --ignored shapes::regenerate_icosphere_obj`.
#[test]
#[ignore]
fn regenerate_icosphere_obj() {
    let (v, t) = icosphere(ICO_RADIUS, ICO_LEVELS);
    let path = manifest_dir().join("scenes/meshes/icosphere.obj");
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    let header = format!(
        "# icosphere: icosahedron subdivided {ICO_LEVELS} times, radius {ICO_RADIUS}, centred at the origin\n# {} vertices, {} triangles, outward oriented (generated by tests/suite/shapes.rs)\n",
        v.len(),
        t.len()
    );
    std::fs::write(&path, header + &obj_text(&v, &t)).unwrap();
}

#[test]
fn icosphere_mesh_matches_sphere() {
    let scenes = manifest_dir().join("scenes");
    let text = std::fs::read_to_string(scenes.join("meshes/icosphere.obj"))
        .expect("scenes/meshes/icosphere.obj is committed");
    let (v, t) = icosphere(ICO_RADIUS, ICO_LEVELS);
    assert!(
        text.ends_with(&obj_text(&v, &t)),
        "committed icosphere.obj differs from the generator"
    );

    let shape = Shape::Mesh {
        file: "meshes/icosphere.obj".into(),
        scale: 1.0,
    };
    shape.validate(3).unwrap();
    let t0 = Instant::now();
    let mesh = shape.build(&scenes).unwrap();
    let load = t0.elapsed();

    // Hausdorff distance between the sphere and the inscribed polyhedron: r minus the
    // smallest distance from the centre to a face plane. |phi_mesh - phi_sphere| <= H.
    let hausdorff = t
        .iter()
        .map(|f| {
            let n = (v[f[1]] - v[f[0]]).cross(v[f[2]] - v[f[0]]).normalize();
            ICO_RADIUS - n.dot(v[f[0]]).abs()
        })
        .fold(0.0, f64::max);
    assert!(hausdorff < 1e-3, "faceting {hausdorff}");

    let mut rng = Rng(99);
    let mut worst: f64 = 0.0;
    for _ in 0..5000 {
        let p = rng.in_box(DVec3::splat(-0.3), DVec3::splat(0.3));
        let exact = ICO_RADIUS - p.length();
        let err = (mesh.phi(p) - exact).abs();
        worst = worst.max(err);
        assert!(
            err <= hausdorff + 1e-9 && err <= 0.002,
            "p {p}: mesh {} sphere {exact}",
            mesh.phi(p)
        );
    }
    // volume/inertia of the polyhedron vs the sphere (inscribed: slightly smaller)
    let vs = 4.0 / 3.0 * PI * ICO_RADIUS.powi(3);
    let vm = mesh.volume().unwrap();
    assert!(vm < vs && vm > vs * (1.0 - 3.0 * hausdorff / ICO_RADIUS - 1e-3));
    let im = mesh.inertia_unit_density().unwrap();
    let is = 0.4 * vs * ICO_RADIUS * ICO_RADIUS;
    for a in 0..3 {
        assert_close(im.col(a)[a], is, 0.02 * is, "icosphere inertia");
    }
    assert!(im.x_axis.y.abs() < 1e-3 * is && im.x_axis.z.abs() < 1e-3 * is);
    let (lo, hi) = mesh.bounds().unwrap();
    assert!((hi - DVec3::splat(ICO_RADIUS)).abs().max_element() < 0.01);
    assert!((lo + DVec3::splat(ICO_RADIUS)).abs().max_element() < 0.01);

    // local level set at h = 1/64: construction cost, accuracy (faceting + interpolation)
    let h = 1.0 / 64.0;
    let t0 = Instant::now();
    let ls = LocalLevelSet::new(mesh, h, 4.0 * h, 3);
    let build = t0.elapsed();
    eprintln!(
        "icosphere ({} triangles): load {load:?}, local level set {:?} nodes built in {build:?}, {} bytes; max |phi - sphere| {worst:.2e} (faceting bound {hausdorff:.2e})",
        t.len(),
        ls.dims().unwrap(),
        ls.memory_bytes()
    );
    assert!(build.as_secs_f64() < 1.0, "mesh level set took {build:?}");
    for _ in 0..5000 {
        let p = rng.in_box(DVec3::splat(-0.2), DVec3::splat(0.2));
        if p.length() < 3.0 * h {
            continue;
        }
        let exact = ICO_RADIUS - p.length();
        // faceting + trilinear interpolation (3 h^2 / (8 (|p| - sqrt3 h)))
        let tol = hausdorff + 3.0 * h * h / (8.0 * (p.length() - 3f64.sqrt() * h));
        assert!((ls.phi(p) - exact).abs() <= tol, "level set at {p}");
    }
}

#[test]
fn nonconvex_meshes_inside_outside_and_distance() {
    let dir = tmpdir("nonconvex");
    let size = 0.1;
    // an L-shaped prism (3 voxels) and a ring (3x3 voxels minus the centre: a hole through it)
    let l_shape: Vec<[i32; 3]> = vec![[0, 0, 0], [1, 0, 0], [0, 1, 0]];
    let ring: Vec<[i32; 3]> = (0..3)
        .flat_map(|i| (0..3).map(move |j| [i, j, 0]))
        .filter(|c| *c != [1, 1, 0])
        .collect();
    for (name, cells) in [("l_shape", &l_shape), ("ring", &ring)] {
        let (v, t) = voxel_mesh(cells, size);
        let file = format!("{name}.obj");
        std::fs::write(dir.join(&file), obj_text(&v, &t)).unwrap();
        let mesh = mesh_in(&dir, &file).unwrap();
        assert_close(
            mesh.volume().unwrap(),
            cells.len() as f64 * size.powi(3),
            1e-12,
            "voxel volume",
        );

        let mut rng = Rng(2024);
        let (lo, hi) = (DVec3::splat(-0.1), DVec3::new(0.4, 0.4, 0.2));
        for _ in 0..20000 {
            let p = rng.in_box(lo, hi);
            let (inside, phi_ref) = voxel_union(cells, size, p);
            let phi = mesh.phi(p);
            if phi_ref.abs() < 1e-9 {
                continue;
            }
            assert_eq!(phi > 0.0, inside, "{name}: sign at {p}: phi {phi}");
            if inside {
                // distance to the union's boundary is at least that to any voxel's boundary
                assert!(phi >= phi_ref - 1e-12, "{name}: inside distance at {p}");
                assert!(phi <= 0.5 * size + 1e-12);
            } else {
                assert_close(
                    phi,
                    phi_ref,
                    1e-12,
                    &format!("{name}: outside distance at {p}"),
                );
            }
        }
        // points in the notch / the hole, where the closest features are concave edges
        let notch = DVec3::new(1.5, 1.5, 0.5) * size;
        // (L: the missing corner voxel; ring: the hole) 0.5 size from the nearest faces
        let expected = -0.5 * size;
        assert_close(mesh.phi(notch), expected, 1e-12, &format!("{name}: notch"));
        // just outside the concave corner (closest feature: the concave edge)
        let near_edge = DVec3::new(1.0 + 1e-3, 1.0 + 1e-3, 0.5) * size;
        assert!(mesh.phi(near_edge) < 0.0, "{name}: near the concave edge");
        let inside_edge = DVec3::new(1.0 - 1e-3, 1.0 - 1e-3, 0.5) * size;
        assert!(
            mesh.phi(inside_edge) > 0.0,
            "{name}: inside at the concave edge"
        );

        // the sampled level set agrees in sign away from the surface
        let h = size / 8.0;
        let ls = LocalLevelSet::new(mesh, h, 4.0 * h, 3);
        for _ in 0..2000 {
            let p = rng.in_box(lo, hi);
            let (inside, phi_ref) = voxel_union(cells, size, p);
            if phi_ref.abs() > h {
                assert_eq!(ls.phi(p) > 0.0, inside, "{name}: level set sign at {p}");
            }
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn stl_ascii_and_binary_cube() {
    let dir = tmpdir("stl");
    let tris = cube_triangles(0.5);
    std::fs::write(dir.join("ascii.stl"), ascii_stl(&tris)).unwrap();
    std::fs::write(dir.join("binary.STL"), binary_stl(&tris)).unwrap();
    // inward-oriented: accepted, flipped
    let inward: Vec<[DVec3; 3]> = tris.iter().map(|t| [t[0], t[2], t[1]]).collect();
    std::fs::write(dir.join("inward.stl"), binary_stl(&inward)).unwrap();
    for file in ["ascii.stl", "binary.STL", "inward.stl"] {
        let m = mesh_in(&dir, file).unwrap_or_else(|e| panic!("{file}: {e}"));
        let v = DVec3::new;
        assert_close(m.phi(DVec3::ZERO), 0.5, 1e-12, file);
        assert_close(m.phi(v(0.2, -0.3, 0.1)), 0.2, 1e-12, file);
        assert_close(m.phi(v(1.0, 0.0, 0.0)), -0.5, 1e-12, file);
        assert_close(m.phi(v(1.0, -1.0, 1.0)), -0.5 * 3f64.sqrt(), 1e-12, file);
        assert_close(m.volume().unwrap(), 1.0, 1e-12, file);
        let i = m.inertia_unit_density().unwrap();
        let ib = Shape::Box {
            half_extents: [0.5; 3],
        }
        .inertia_unit_density()
        .unwrap();
        assert!((i - ib).abs().to_cols_array().iter().all(|x| *x < 1e-12));
        assert_eq!(m.bounds().unwrap(), (DVec3::splat(-0.5), DVec3::splat(0.5)));
    }
    // scale
    let scaled = Shape::Mesh {
        file: "ascii.stl".into(),
        scale: 2.0,
    }
    .build(&dir)
    .unwrap();
    assert_close(scaled.phi(DVec3::ZERO), 1.0, 1e-12, "scaled cube");
    assert_close(scaled.volume().unwrap(), 8.0, 1e-12, "scaled cube volume");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn mesh_errors_name_the_problem() {
    let dir = tmpdir("errors");
    let err = mesh_in(&dir, "nope.obj").unwrap_err();
    assert!(
        err.contains("nope.obj") && err.contains("not found"),
        "{err}"
    );

    std::fs::write(
        dir.join("garbage.obj"),
        "this is not\na mesh at all\n\u{1}\u{2}",
    )
    .unwrap();
    let err = mesh_in(&dir, "garbage.obj").unwrap_err();
    assert!(
        err.contains("garbage.obj") && err.contains("no triangles"),
        "{err}"
    );

    std::fs::write(dir.join("bad_face.obj"), "v 0 0 0\nv 1 0 0\nf 1 2 x\n").unwrap();
    let err = mesh_in(&dir, "bad_face.obj").unwrap_err();
    assert!(err.contains("not a readable OBJ"), "{err}");

    let bytes: Vec<u8> = (0..1000u32).map(|i| (i * 7919 % 251) as u8).collect();
    std::fs::write(dir.join("garbage.stl"), &bytes).unwrap();
    let err = mesh_in(&dir, "garbage.stl").unwrap_err();
    assert!(
        err.contains("garbage.stl") && err.contains("not a readable STL"),
        "{err}"
    );
    std::fs::write(dir.join("short.stl"), b"abc").unwrap();
    let err = mesh_in(&dir, "short.stl").unwrap_err();
    assert!(err.contains("not a readable STL"), "{err}");
    std::fs::write(
        dir.join("truncated.stl"),
        "solid x\n facet normal 0 0 1\n outer loop\n vertex 0 0 0\n",
    )
    .unwrap();
    let err = mesh_in(&dir, "truncated.stl").unwrap_err();
    assert!(err.contains("not a readable STL"), "{err}");

    std::fs::write(dir.join("cube.ply"), "ply\n").unwrap();
    let err = mesh_in(&dir, "cube.ply").unwrap_err();
    assert!(err.contains("unsupported"), "{err}");

    // cube with one face (two triangles) removed: the 4 edges of the hole are open
    let (v, mut t) = voxel_mesh(&[[0, 0, 0]], 1.0);
    t.truncate(10);
    std::fs::write(dir.join("open.obj"), obj_text(&v, &t)).unwrap();
    let err = mesh_in(&dir, "open.obj").unwrap_err();
    assert!(
        err.contains("not closed") && err.contains("4 open edges"),
        "{err}"
    );
    let open_stl: Vec<[DVec3; 3]> = cube_triangles(0.5).into_iter().take(10).collect();
    std::fs::write(dir.join("open.stl"), binary_stl(&open_stl)).unwrap();
    let err = mesh_in(&dir, "open.stl").unwrap_err();
    assert!(
        err.contains("not closed") && err.contains("4 open edges"),
        "{err}"
    );

    // one triangle flipped: inconsistent orientation
    let (v, mut t) = voxel_mesh(&[[0, 0, 0]], 1.0);
    t[0].swap(1, 2);
    std::fs::write(dir.join("flipped.obj"), obj_text(&v, &t)).unwrap();
    let err = mesh_in(&dir, "flipped.obj").unwrap_err();
    assert!(err.contains("not consistently oriented"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

// ------------------------------------------------------------------------------------------
// local level sets
// ------------------------------------------------------------------------------------------

/// Trilinear interpolation error bound: |f - I f| <= h^2/8 (|f_xx| + |f_yy| + |f_zz|) over the
/// cell. For the sphere's signed distance r - |p| each |f_ii| <= 1/|p|, so the error at p is
/// at most 3 h^2 / (8 (|p| - sqrt(3) h)) (2 h^2 / (8 (|p| - sqrt(2) h)) bilinear in 2D):
/// about 0.03 h near the surface of a sphere r = 0.2 at h = 1/64.
#[test]
fn local_level_set_sphere_interpolation_and_memory() {
    let (r, h) = (0.2, 1.0 / 64.0);
    let band = 4.0 * h;
    let t0 = Instant::now();
    let ls = LocalLevelSet::new(build(Shape::Sphere { radius: r }), h, band, 3);
    eprintln!(
        "sphere r = {r}: local level set {:?} built in {:?}",
        ls.dims().unwrap(),
        t0.elapsed()
    );
    assert!(ls.is_sampled());
    let (lo, hi) = ls.bounds().unwrap();
    assert_eq!(
        (lo, hi),
        (DVec3::splat(-(r + band)), DVec3::splat(r + band))
    );
    let mut rng = Rng(31);
    let mut worst_rel: f64 = 0.0;
    let mut worst_surface: f64 = 0.0;
    for _ in 0..100_000 {
        let p = rng.in_box(lo, hi);
        let d = p.length();
        if d < 3.0 * h {
            continue;
        }
        let bound = 3.0 * h * h / (8.0 * (d - 3f64.sqrt() * h));
        let err = (ls.phi(p) - (r - d)).abs();
        assert!(err <= bound, "p {p}: error {err} > bound {bound}");
        worst_rel = worst_rel.max(err / bound);
        if (d - r).abs() < band {
            worst_surface = worst_surface.max(err);
        }
    }
    eprintln!(
        "max error within the band {:.3e} h (bound near the surface {:.3e} h), worst error/bound {worst_rel:.2}",
        worst_surface / h,
        3.0 * h / (8.0 * (r - band - 3f64.sqrt() * h))
    );
    assert!(worst_surface < 0.05 * h);

    // outside the local grid: continuous, <= -band, decreasing with the distance
    for _ in 0..1000 {
        let p = rng.unit() * rng.range(r + band + 2.0 * h, 2.0);
        let q = p * 3.0;
        assert!(ls.phi(p) <= -band + 1e-3 * h, "outside phi {}", ls.phi(p));
        assert!(ls.phi(q) < ls.phi(p));
        // never closer to the body than the true distance (phi_clamped - dist(p, box) is a
        // lower bound of the signed distance, up to the interpolation error at the box)
        assert!(ls.phi(q) <= r - q.length() + 1e-3 * h);
        assert!(ls.phi(p) <= r - p.length() + 1e-3 * h);
    }
    // across the grid box boundary (between hi.x and hi.x + h): 1-Lipschitz, no jump
    let steps = 4000;
    let dx = 4.0 * h / steps as f64;
    for s in 0..steps {
        let x = hi.x - 2.0 * h + s as f64 * dx;
        let p = DVec3::new(x, 0.01, -0.02);
        let jump = (ls.phi(p + DVec3::X * dx) - ls.phi(p)).abs();
        assert!(jump <= dx * (1.0 + 1e-9), "jump {jump} at x = {x}");
    }

    // memory: the local grid vs a full domain grid of the unit cube at the same spacing
    let domain = 65usize.pow(3) * std::mem::size_of::<f64>();
    eprintln!(
        "memory: local {} bytes, unit-cube domain grid {domain} bytes",
        ls.memory_bytes()
    );
    assert!(ls.memory_bytes() * 5 < domain);

    // 2D: a disk on a one-layer grid, z ignored
    let ls2 = LocalLevelSet::new(build(Shape::Disk { radius: r }), h, band, 2);
    let dims = ls2.dims().unwrap();
    assert_eq!(dims[2], 1);
    let (lo2, hi2) = ls2.bounds().unwrap();
    assert_eq!((lo2.z, hi2.z), (0.0, 0.0));
    for _ in 0..20000 {
        let mut p = rng.in_box(lo2, hi2);
        p.z = rng.range(-1.0, 1.0);
        let d = p.truncate().length();
        if d < 3.0 * h {
            continue;
        }
        let bound = 2.0 * h * h / (8.0 * (d - 2f64.sqrt() * h));
        assert!((ls2.phi(p) - (r - d)).abs() <= bound, "2D at {p}");
    }
    assert!(ls2.memory_bytes() < 40 * 40 * 8 + 1000);
}

#[test]
fn local_level_set_unbounded_and_expensive_shapes() {
    let h = 1.0 / 64.0;
    let band = 4.0 * h;
    let mut rng = Rng(5);

    // half-space and complements of primitives stay analytic (exact)
    for shape in [
        Shape::HalfSpace {
            normal: [0.0, 1.0, 0.0],
            offset: -0.5,
        },
        Shape::Complement(Box::new(Shape::Cylinder {
            radius: 0.5,
            half_height: 1.0,
        })),
    ] {
        let geom = build(shape.clone());
        let ls = LocalLevelSet::new(geom.clone(), h, band, 3);
        assert!(!ls.is_sampled() && ls.bounds().is_none(), "{shape:?}");
        for _ in 0..100 {
            let p = rng.in_box(DVec3::splat(-1.0), DVec3::ONE);
            assert_eq!(ls.phi(p), geom.phi(p));
        }
    }

    // an ellipsoid is sampled; its complement is sampled through the inner grid, negated
    let radii = [0.3, 0.2, 0.1];
    let t0 = Instant::now();
    let ell = LocalLevelSet::new(build(Shape::Ellipsoid { radii }), h, band, 3);
    eprintln!(
        "ellipsoid {radii:?}: local level set {:?} built in {:?}",
        ell.dims().unwrap(),
        t0.elapsed()
    );
    let geom = build(Shape::Ellipsoid { radii });
    let container = LocalLevelSet::new(
        build(Shape::Complement(Box::new(Shape::Ellipsoid { radii }))),
        h,
        band,
        3,
    );
    assert!(container.is_sampled() && container.bounds().is_none());
    // curvature radii down to c^2/a = 0.033: the interpolation bound 3 h^2/(8 rho)
    let tol = 3.0 * h * h / (8.0 * 0.1 * 0.1 / 0.3 * 0.5);
    for _ in 0..20000 {
        let p = rng.in_box(
            -DVec3::from_array(radii) - band,
            DVec3::from_array(radii) + band,
        );
        let exact = geom.phi(p);
        if exact.abs() > 0.02 {
            continue;
        }
        assert!((ell.phi(p) - exact).abs() < tol, "ellipsoid at {p}");
        assert_eq!(container.phi(p), -ell.phi(p));
    }
    assert!(container.phi(DVec3::splat(5.0)) > band);

    // a 2D ellipse on a 2D grid
    let e2 = LocalLevelSet::new(build(Shape::Ellipse { radii: [0.3, 0.15] }), h, band, 2);
    assert_eq!(e2.dims().unwrap()[2], 1);
    // (0, 0.1): closest point (0, 0.15), curvature radius there a^2/b = 0.6
    assert!((e2.phi(DVec3::new(0.0, 0.1, 0.7)) - 0.05).abs() < 0.01 * h);
}

// ------------------------------------------------------------------------------------------
// volumes and inertia
// ------------------------------------------------------------------------------------------

fn diag(m: DMat3) -> DVec3 {
    DVec3::new(m.x_axis.x, m.y_axis.y, m.z_axis.z)
}

fn off_diagonal_zero(m: DMat3) -> bool {
    m.x_axis.y == 0.0
        && m.x_axis.z == 0.0
        && m.y_axis.x == 0.0
        && m.y_axis.z == 0.0
        && m.z_axis.x == 0.0
        && m.z_axis.y == 0.0
}

#[test]
fn volumes_and_inertia_textbook() {
    let tol = 1e-12;
    let close3 = |a: DVec3, b: DVec3, what: &str| {
        assert!(
            (a - b).abs().max_element() <= tol * b.abs().max_element(),
            "{what}: {a} vs {b}"
        )
    };

    // sphere: V = 4/3 pi r^3, I = 2/5 m r^2
    let r = 0.3;
    let s = Shape::Sphere { radius: r };
    let m = 4.0 / 3.0 * PI * r.powi(3);
    assert_close(s.volume().unwrap(), m, tol, "sphere volume");
    close3(
        diag(s.inertia_unit_density().unwrap()),
        DVec3::splat(0.4 * m * r * r),
        "sphere inertia",
    );

    // ellipsoid: V = 4/3 pi abc, I_xx = m (b^2 + c^2) / 5
    let (a, b, c) = (0.3, 0.2, 0.1);
    let e = Shape::Ellipsoid { radii: [a, b, c] };
    let m = 4.0 / 3.0 * PI * a * b * c;
    assert_close(e.volume().unwrap(), m, tol, "ellipsoid volume");
    close3(
        diag(e.inertia_unit_density().unwrap()),
        DVec3::new(b * b + c * c, a * a + c * c, a * a + b * b) * m / 5.0,
        "ellipsoid inertia",
    );

    // box with sides (w, d, t): m = w d t, I_xx = m (d^2 + t^2) / 12
    let (w, d, t) = (0.4, 0.6, 1.0);
    let bx = Shape::Box {
        half_extents: [w / 2.0, d / 2.0, t / 2.0],
    };
    let m = w * d * t;
    assert_close(bx.volume().unwrap(), m, tol, "box volume");
    close3(
        diag(bx.inertia_unit_density().unwrap()),
        DVec3::new(d * d + t * t, w * w + t * t, w * w + d * d) * m / 12.0,
        "box inertia",
    );

    // cylinder radius r, height H: m = pi r^2 H, I_zz = m r^2 / 2, I_xx = m (3 r^2 + H^2) / 12
    let (r, hh) = (0.2, 0.5);
    let cy = Shape::Cylinder {
        radius: r,
        half_height: hh,
    };
    let m = PI * r * r * 2.0 * hh;
    assert_close(cy.volume().unwrap(), m, tol, "cylinder volume");
    let ix = m * (3.0 * r * r + 4.0 * hh * hh) / 12.0;
    close3(
        diag(cy.inertia_unit_density().unwrap()),
        DVec3::new(ix, ix, m * r * r / 2.0),
        "cylinder inertia",
    );

    // disk: area pi r^2, polar moment pi r^4 / 2; ellipse; rectangle (laminas)
    let dk = Shape::Disk { radius: r };
    assert_close(dk.volume().unwrap(), PI * r * r, tol, "disk area");
    let i = dk.inertia_unit_density().unwrap();
    assert_close(i.z_axis.z, PI * r.powi(4) / 2.0, tol, "disk polar moment");
    assert_close(i.x_axis.x, PI * r.powi(4) / 4.0, tol, "disk I_xx");
    let el = Shape::Ellipse { radii: [a, b] };
    assert_close(el.volume().unwrap(), PI * a * b, tol, "ellipse area");
    assert_close(
        el.inertia_unit_density().unwrap().z_axis.z,
        PI * a * b * (a * a + b * b) / 4.0,
        tol,
        "ellipse polar moment",
    );
    let re = Shape::Rectangle {
        half_extents: [w / 2.0, d / 2.0],
    };
    assert_close(re.volume().unwrap(), w * d, tol, "rectangle area");
    assert_close(
        re.inertia_unit_density().unwrap().z_axis.z,
        w * d * (w * w + d * d) / 12.0,
        tol,
        "rectangle polar moment",
    );

    for s in [&s, &e, &bx, &cy, &dk, &el, &re] {
        assert!(off_diagonal_zero(s.inertia_unit_density().unwrap()));
        // ShapeGeometry agrees with Shape
        let g = build((*s).clone());
        assert_eq!(g.volume(), s.volume());
        assert_eq!(g.inertia_unit_density(), s.inertia_unit_density());
    }
    for s in [
        Shape::HalfSpace {
            normal: [0.0, 0.0, 1.0],
            offset: 0.0,
        },
        Shape::Complement(Box::new(s.clone())),
        Shape::Mesh {
            file: "x.obj".into(),
            scale: 1.0,
        },
    ] {
        assert!(s.volume().is_none() && s.inertia_unit_density().is_none());
    }
}

/// The capsule's (and cylinder's) volume and inertia against midpoint quadrature of the
/// indicator phi > 0 on a fine grid.
#[test]
fn capsule_and_cylinder_inertia_by_quadrature() {
    for shape in [
        Shape::Capsule {
            radius: 0.2,
            half_height: 0.3,
        },
        Shape::Cylinder {
            radius: 0.2,
            half_height: 0.3,
        },
    ] {
        let g = build(shape.clone());
        let (lo, hi) = g.bounds().unwrap();
        let n = 200;
        let dx = (hi - lo) / n as f64;
        let cell = dx.x * dx.y * dx.z;
        let mut vol = 0.0;
        let mut second = DVec3::ZERO; // integral of x^2, y^2, z^2
        for k in 0..n {
            for j in 0..n {
                for i in 0..n {
                    let p = lo + (DVec3::new(i as f64, j as f64, k as f64) + 0.5) * dx;
                    if g.phi(p) > 0.0 {
                        vol += cell;
                        second += p * p * cell;
                    }
                }
            }
        }
        let inertia = DVec3::new(
            second.y + second.z,
            second.x + second.z,
            second.x + second.y,
        );
        let v = shape.volume().unwrap();
        let i = diag(shape.inertia_unit_density().unwrap());
        assert_close(vol, v, 2e-3 * v, &format!("{shape:?} volume"));
        for a in 0..3 {
            assert_close(
                inertia[a],
                i[a],
                3e-3 * i[a],
                &format!("{shape:?} inertia {a}"),
            );
        }
    }
}

// ------------------------------------------------------------------------------------------
// validation and scene syntax
// ------------------------------------------------------------------------------------------

#[test]
fn validate_messages() {
    let err = Shape::Sphere { radius: 0.1 }.validate(2).unwrap_err();
    assert!(err.contains("3D") && err.contains("Disk"), "{err}");
    let err = Shape::Disk { radius: 0.1 }.validate(3).unwrap_err();
    assert!(err.contains("2D") && err.contains("Sphere"), "{err}");
    let err = Shape::Box {
        half_extents: [1.0, 1.0, 1.0],
    }
    .validate(2)
    .unwrap_err();
    assert!(err.contains("Rectangle"), "{err}");
    let err = Shape::Sphere { radius: -1.0 }.validate(3).unwrap_err();
    assert!(err.contains("radius") && err.contains("positive"), "{err}");
    let err = Shape::Ellipsoid {
        radii: [1.0, 0.0, 1.0],
    }
    .validate(3)
    .unwrap_err();
    assert!(err.contains("along y"), "{err}");
    let err = Shape::Cylinder {
        radius: 1.0,
        half_height: f64::NAN,
    }
    .validate(3)
    .unwrap_err();
    assert!(err.contains("half_height"), "{err}");
    let err = Shape::HalfSpace {
        normal: [0.0; 3],
        offset: 1.0,
    }
    .validate(3)
    .unwrap_err();
    assert!(err.contains("normal") && err.contains("non-zero"), "{err}");
    let err = Shape::HalfSpace {
        normal: [0.0, 1.0, 1.0],
        offset: 1.0,
    }
    .validate(2)
    .unwrap_err();
    assert!(err.contains("xy plane"), "{err}");
    Shape::HalfSpace {
        normal: [0.0, 1.0, 0.0],
        offset: 1.0,
    }
    .validate(2)
    .unwrap();
    let err = Shape::Complement(Box::new(Shape::Rectangle {
        half_extents: [1.0, -1.0],
    }))
    .validate(2)
    .unwrap_err();
    assert!(
        err.contains("Complement") && err.contains("along y"),
        "{err}"
    );
    let err = Shape::Mesh {
        file: "a.obj".into(),
        scale: 1.0,
    }
    .validate(2)
    .unwrap_err();
    assert!(err.contains("3D"), "{err}");
    let err = Shape::Mesh {
        file: "a.obj".into(),
        scale: 0.0,
    }
    .validate(3)
    .unwrap_err();
    assert!(err.contains("scale"), "{err}");
    assert!(Shape::Disk { radius: 1.0 }.validate(4).is_err());
    for ok3 in [
        Shape::Sphere { radius: 1.0 },
        Shape::Capsule {
            radius: 0.1,
            half_height: 0.2,
        },
        Shape::Complement(Box::new(Shape::Cylinder {
            radius: 1.0,
            half_height: 1.0,
        })),
    ] {
        ok3.validate(3).unwrap();
    }
    for ok2 in [
        Shape::Ellipse { radii: [1.0, 0.5] },
        Shape::Rectangle {
            half_extents: [1.0, 0.5],
        },
    ] {
        ok2.validate(2).unwrap();
    }
}

#[test]
fn ron_syntax() {
    let s: Shape = ron::from_str("Complement(Cylinder(radius: 1.0, half_height: 2.0))").unwrap();
    assert_eq!(
        s,
        Shape::Complement(Box::new(Shape::Cylinder {
            radius: 1.0,
            half_height: 2.0
        }))
    );
    let s: Shape = ron::from_str("Mesh(file: \"meshes/icosphere.obj\")").unwrap();
    assert_eq!(
        s,
        Shape::Mesh {
            file: "meshes/icosphere.obj".into(),
            scale: 1.0
        }
    );
    let s: Shape = ron::from_str("Box(half_extents: [0.1, 0.2, 0.3])").unwrap();
    assert_eq!(
        s,
        Shape::Box {
            half_extents: [0.1, 0.2, 0.3]
        }
    );
    assert!(ron::from_str::<Shape>("Sphere(radius: 1.0, colour: 2)").is_err());
    assert!(ron::from_str::<Shape>("Sphere(radius: 1.0)").is_ok());
    let back = ron::to_string(&s).unwrap();
    assert_eq!(ron::from_str::<Shape>(&back).unwrap(), s);
}

/// The gradient the contact force uses is the gradient of the interpolated level set itself:
/// it matches a central difference of `phi` (inside the sampled box, where the interpolant is
/// trilinear, and outside it, where the distance term takes over), in 3D and 2D.
#[test]
fn level_set_gradient_is_the_gradient_of_the_interpolant() {
    let h = 0.05;
    let shapes = [
        (
            Shape::Ellipsoid {
                radii: [0.3, 0.2, 0.15],
            },
            3,
        ),
        (Shape::Ellipse { radii: [0.3, 0.2] }, 2),
    ];
    for (shape, dim) in shapes {
        let ls = LocalLevelSet::new(build(shape), h, 3.0 * h, dim);
        let mut worst = 0.0f64;
        let mut seed = 7u64;
        let mut rnd = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        for _ in 0..2000 {
            let mut p = DVec3::new(rnd(), rnd(), rnd()) * 1.2;
            if dim == 2 {
                p.z = 0.0;
            }
            let (v, g) = ls.phi_grad(p, 1e-4 * h, dim);
            assert_eq!(v, ls.phi(p));
            let d = 1e-7;
            for ax in 0..dim {
                let mut e = DVec3::ZERO;
                e[ax] = d;
                let fd = (ls.phi(p + e) - ls.phi(p - e)) / (2.0 * d);
                worst = worst.max((fd - g[ax]).abs());
            }
        }
        assert!(worst < 1e-6, "dim {dim}: largest gradient mismatch {worst}");
    }
}
