//! Rigid-body shapes and their signed distance functions.
//!
//! Conventions (Coquerelle & Cottet 2008): a body's level set `phi` is a *signed distance*,
//! **positive inside** the body (the solid), negative outside, with `|grad phi| = 1`.
//! Shapes are described in *body coordinates*: centred at the body's origin, axes along the
//! body's axes. Every size is a length in scene units. In 2D scenes positions have `z = 0`
//! and the 2D shapes ([`Shape::Disk`], [`Shape::Ellipse`], [`Shape::Rectangle`]) ignore `z`.
//!
//! A [`Shape`] is the scene-file description; [`Shape::build`] turns it into a
//! [`ShapeGeometry`] (loading mesh files) whose [`ShapeGeometry::phi`] is the exact signed
//! distance. Bodies do not call `phi` on the fly: they sample it once on a local grid, see
//! [`crate::bodies::levelset::LocalLevelSet`].

use std::collections::HashMap;
use std::f64::consts::PI;
use std::fmt;
use std::path::{Path, PathBuf};

use crate::bodies::surface::SurfaceMesh;
use glam::{DMat3, DVec2, DVec3};
use parry3d_f64::math::Vector as PVec;
use parry3d_f64::query::PointQuery;
use parry3d_f64::shape::{TriMesh, TriMeshFlags};

fn default_scale() -> f64 {
    1.0
}

/// The shape of a rigid body (or of a fixed wall), in body coordinates.
#[derive(serde::Deserialize, serde::Serialize, Debug, Clone, PartialEq)]
#[serde(deny_unknown_fields)]
pub enum Shape {
    /// 3D ball of the given radius (length) centred at the body origin.
    Sphere { radius: f64 },
    /// 3D ellipsoid with semi-axes `radii` (lengths) along body x, y, z.
    Ellipsoid {
        #[serde(with = "seq_array")]
        radii: [f64; 3],
    },
    /// 3D box with half side lengths `half_extents` (lengths) along body x, y, z.
    Box {
        #[serde(with = "seq_array")]
        half_extents: [f64; 3],
    },
    /// 3D circular cylinder, axis along body z: `radius` (length), `half_height` (length) = half
    /// the length along z; flat end caps.
    Cylinder { radius: f64, half_height: f64 },
    /// 3D capsule, axis along body z: the set of points within `radius` (length) of the segment
    /// from `(0, 0, -half_height)` to `(0, 0, half_height)` (`half_height`: length). Total
    /// length along z is `2 (half_height + radius)`.
    Capsule { radius: f64, half_height: f64 },
    /// The half-space `{x : n . x <= offset}` is INSIDE (solid); the normal `n` (any non-zero
    /// length, it is normalised) points out of the solid. `offset` is a length when `n` is a
    /// unit vector (in general the plane is at signed distance `offset / |n|` from the origin
    /// along `n`). Valid in 2D if `normal[2] == 0` (a half-plane) and in 3D.
    HalfSpace {
        #[serde(with = "seq_array")]
        normal: [f64; 3],
        offset: f64,
    },
    /// 2D disk of the given radius (length).
    Disk { radius: f64 },
    /// 2D ellipse with semi-axes `radii` (lengths) along body x, y.
    Ellipse {
        #[serde(with = "seq_array")]
        radii: [f64; 2],
    },
    /// 2D rectangle with half side lengths `half_extents` (lengths) along body x, y.
    Rectangle {
        #[serde(with = "seq_array")]
        half_extents: [f64; 2],
    },
    /// The complement (outside) of a shape: a container. E.g. `Complement(Cylinder(..))` is a
    /// tube wall whose fluid region is the cylinder's interior. Valid in 2D and 3D, as its shape.
    Complement(Box<Shape>),
    /// Closed triangle mesh (OBJ or STL, ASCII or binary), 3D only. `file` is relative to the
    /// scene file's directory; vertex coordinates are multiplied by `scale` (dimensionless,
    /// default 1), so the mesh must be modelled in body coordinates (around its origin).
    Mesh {
        file: String,
        #[serde(default = "default_scale")]
        scale: f64,
    },
}

fn positive(what: &str, v: f64) -> Result<(), String> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(format!("{what} must be a positive finite length, got {v}"))
    }
}

impl Shape {
    /// Short name of the variant, for messages.
    pub fn name(&self) -> &'static str {
        match self {
            Shape::Sphere { .. } => "Sphere",
            Shape::Ellipsoid { .. } => "Ellipsoid",
            Shape::Box { .. } => "Box",
            Shape::Cylinder { .. } => "Cylinder",
            Shape::Capsule { .. } => "Capsule",
            Shape::HalfSpace { .. } => "HalfSpace",
            Shape::Disk { .. } => "Disk",
            Shape::Ellipse { .. } => "Ellipse",
            Shape::Rectangle { .. } => "Rectangle",
            Shape::Complement(_) => "Complement",
            Shape::Mesh { .. } => "Mesh",
        }
    }

    /// Checks sizes (positive, finite), the half-space normal (non-zero) and that the shape
    /// fits the scene's dimension: Disk/Ellipse/Rectangle only in 2D; Sphere, Ellipsoid, Box,
    /// Cylinder, Capsule and Mesh only in 3D; HalfSpace and Complement in both.
    pub fn validate(&self, dim: usize) -> Result<(), String> {
        if dim != 2 && dim != 3 {
            return Err(format!("dimension must be 2 or 3, got {dim}"));
        }
        let only_3d = |alt: &str| -> Result<(), String> {
            if dim == 2 {
                Err(format!(
                    "{} is a 3D shape and cannot be used in a 2D scene; {alt}",
                    self.name()
                ))
            } else {
                Ok(())
            }
        };
        let only_2d = |alt: &str| -> Result<(), String> {
            if dim == 3 {
                Err(format!(
                    "{} is a 2D shape and cannot be used in a 3D scene; {alt}",
                    self.name()
                ))
            } else {
                Ok(())
            }
        };
        match self {
            Shape::Sphere { radius } => {
                only_3d("use Disk { radius } instead")?;
                positive("Sphere radius", *radius)
            }
            Shape::Ellipsoid { radii } => {
                only_3d("use Ellipse { radii: [a, b] } instead")?;
                for (r, axis) in radii.iter().zip(["x", "y", "z"]) {
                    positive(&format!("Ellipsoid radius along {axis}"), *r)?;
                }
                Ok(())
            }
            Shape::Box { half_extents } => {
                only_3d("use Rectangle { half_extents: [a, b] } instead")?;
                for (r, axis) in half_extents.iter().zip(["x", "y", "z"]) {
                    positive(&format!("Box half extent along {axis}"), *r)?;
                }
                Ok(())
            }
            Shape::Cylinder {
                radius,
                half_height,
            } => {
                only_3d("its 2D cross-section is Disk { radius }")?;
                positive("Cylinder radius", *radius)?;
                positive("Cylinder half_height", *half_height)
            }
            Shape::Capsule {
                radius,
                half_height,
            } => {
                only_3d("use Disk or Rectangle in 2D")?;
                positive("Capsule radius", *radius)?;
                positive("Capsule half_height", *half_height)
            }
            Shape::HalfSpace { normal, offset } => {
                let n = DVec3::from_array(*normal);
                if !n.is_finite() || n.length() == 0.0 {
                    return Err(format!(
                        "HalfSpace normal must be a non-zero finite vector, got {normal:?}"
                    ));
                }
                if !offset.is_finite() {
                    return Err(format!("HalfSpace offset must be finite, got {offset}"));
                }
                if dim == 2 && normal[2] != 0.0 {
                    return Err(format!(
                        "HalfSpace normal must lie in the xy plane in a 2D scene (normal[2] == 0), got {normal:?}"
                    ));
                }
                Ok(())
            }
            Shape::Disk { radius } => {
                only_2d("use Sphere { radius } or Cylinder { radius, half_height } instead")?;
                positive("Disk radius", *radius)
            }
            Shape::Ellipse { radii } => {
                only_2d("use Ellipsoid { radii: [a, b, c] } instead")?;
                for (r, axis) in radii.iter().zip(["x", "y"]) {
                    positive(&format!("Ellipse radius along {axis}"), *r)?;
                }
                Ok(())
            }
            Shape::Rectangle { half_extents } => {
                only_2d("use Box { half_extents: [a, b, c] } instead")?;
                for (r, axis) in half_extents.iter().zip(["x", "y"]) {
                    positive(&format!("Rectangle half extent along {axis}"), *r)?;
                }
                Ok(())
            }
            Shape::Complement(inner) => inner
                .validate(dim)
                .map_err(|e| format!("in Complement: {e}")),
            Shape::Mesh { file, scale } => {
                only_3d("meshes are 3D only")?;
                if file.trim().is_empty() {
                    return Err("Mesh file name is empty".to_string());
                }
                if !(scale.is_finite() && *scale > 0.0) {
                    return Err(format!(
                        "Mesh scale must be a positive finite number, got {scale}"
                    ));
                }
                Ok(())
            }
        }
    }

    /// The analytic geometry of a primitive (not Complement, not Mesh).
    fn primitive(&self) -> Option<Kind> {
        Some(match self {
            Shape::Sphere { radius } => Kind::Sphere { r: *radius },
            Shape::Ellipsoid { radii } => Kind::Ellipsoid {
                radii: DVec3::from_array(*radii),
            },
            Shape::Box { half_extents } => Kind::Box {
                he: DVec3::from_array(*half_extents),
            },
            Shape::Cylinder {
                radius,
                half_height,
            } => Kind::Cylinder {
                r: *radius,
                hh: *half_height,
            },
            Shape::Capsule {
                radius,
                half_height,
            } => Kind::Capsule {
                r: *radius,
                hh: *half_height,
            },
            Shape::HalfSpace { normal, offset } => {
                let n = DVec3::from_array(*normal);
                let len = n.length();
                Kind::HalfSpace {
                    n: n / len,
                    offset: offset / len,
                }
            }
            Shape::Disk { radius } => Kind::Disk { r: *radius },
            Shape::Ellipse { radii } => Kind::Ellipse {
                radii: DVec2::from_array(*radii),
            },
            Shape::Rectangle { half_extents } => Kind::Rectangle {
                he: DVec2::from_array(*half_extents),
            },
            Shape::Complement(_) | Shape::Mesh { .. } => return None,
        })
    }

    /// Builds the geometry: loads and checks mesh files (relative to `base_dir`, the scene
    /// file's directory). `Complement(Complement(s))` simplifies to `s`. Sizes are not
    /// checked here: call [`Shape::validate`] first.
    pub fn build(&self, base_dir: &Path) -> Result<ShapeGeometry, String> {
        let kind = match self {
            Shape::Complement(inner) => match inner.as_ref() {
                Shape::Complement(s) => return s.build(base_dir),
                s => Kind::Complement(Box::new(s.build(base_dir)?.kind)),
            },
            Shape::Mesh { file, scale } => {
                Kind::Mesh(Box::new(MeshGeom::load(&base_dir.join(file), *scale)?))
            }
            s => s.primitive().expect("primitive shape"),
        };
        Ok(ShapeGeometry { kind })
    }

    /// Analytic volume (3D) or area (2D) of a primitive; `None` for HalfSpace, Complement and
    /// Mesh (use [`ShapeGeometry::volume`] for a loaded mesh).
    pub fn volume(&self) -> Option<f64> {
        self.primitive().and_then(|k| k.volume())
    }

    /// Analytic inertia tensor at unit density of a primitive, see
    /// [`ShapeGeometry::inertia_unit_density`]; `None` for HalfSpace, Complement and Mesh.
    pub fn inertia_unit_density(&self) -> Option<DMat3> {
        self.primitive().and_then(|k| k.inertia())
    }
}

/// A shape ready for signed-distance queries (meshes loaded), in body coordinates.
#[derive(Clone, Debug)]
pub struct ShapeGeometry {
    kind: Kind,
}

#[derive(Clone, Debug)]
enum Kind {
    Sphere {
        r: f64,
    },
    Ellipsoid {
        radii: DVec3,
    },
    Box {
        he: DVec3,
    },
    Cylinder {
        r: f64,
        hh: f64,
    },
    Capsule {
        r: f64,
        hh: f64,
    },
    /// unit normal, offset along it
    HalfSpace {
        n: DVec3,
        offset: f64,
    },
    Disk {
        r: f64,
    },
    Ellipse {
        radii: DVec2,
    },
    Rectangle {
        he: DVec2,
    },
    Complement(Box<Kind>),
    Mesh(Box<MeshGeom>),
}

impl ShapeGeometry {
    /// Signed distance at the body-frame point `p`: positive inside the solid, negative
    /// outside, `|grad phi| = 1`. Exact for every shape (meshes: exact distance to the
    /// triangles, sign from parry's pseudo-normal inside test; ellipse/ellipsoid: closest
    /// point by a robust bisection to full double precision). 2D shapes ignore `p.z`.
    ///
    /// Ellipse, ellipsoid and mesh queries cost far more than the others (an iterative solve,
    /// a BVH traversal): sample them once, see [`crate::bodies::levelset::LocalLevelSet`].
    #[inline]
    pub fn phi(&self, p: DVec3) -> f64 {
        self.kind.phi(p)
    }

    /// Body-frame bounding box `(min, max)` of the solid; `None` if unbounded (HalfSpace,
    /// Complement). 2D shapes have `min.z = max.z = 0`.
    pub fn bounds(&self) -> Option<(DVec3, DVec3)> {
        self.kind.bounds()
    }

    /// Volume (3D) or area (2D shapes) of the solid; `None` if unbounded. For a mesh, the exact
    /// volume of the (scaled) polyhedron.
    pub fn volume(&self) -> Option<f64> {
        self.kind.volume()
    }

    /// Inertia tensor `I = integral (|x|^2 Id - x x^T) dV` at unit density, about the body
    /// ORIGIN, in the body frame (for a mesh whose centroid is not at the origin this is not
    /// the central inertia). For 2D shapes the integral is over the area (a lamina):
    /// `I_zz` is the polar moment `integral (x^2 + y^2) dA`, `I_xx = integral y^2 dA`,
    /// `I_yy = integral x^2 dA`. `None` if unbounded.
    pub fn inertia_unit_density(&self) -> Option<DMat3> {
        self.kind.inertia()
    }

    /// Whether the solid is bounded (`bounds()` is `Some`).
    pub fn is_bounded(&self) -> bool {
        self.bounds().is_some()
    }

    /// Whether the signed distance costs an iterative solve or a mesh query (ellipse,
    /// ellipsoid, mesh, or a complement of one) rather than a closed formula.
    pub fn is_expensive(&self) -> bool {
        self.kind.is_expensive()
    }

    /// The boundary of the solid in the body frame, for viewing (see
    /// [`crate::bodies::surface`]): `half_size` is the half-width of the patch drawn for a
    /// half-space (length); in a 2D domain (`dim` 2) a half-space is a line segment.
    pub fn surface(&self, half_size: f64, dim: usize) -> SurfaceMesh {
        self.kind.surface(half_size, dim)
    }

    /// The geometry whose complement this is, if it is a `Complement`.
    pub fn complement_inner(&self) -> Option<ShapeGeometry> {
        match &self.kind {
            Kind::Complement(inner) => Some(ShapeGeometry {
                kind: inner.as_ref().clone(),
            }),
            _ => None,
        }
    }
}

/// Signed distance to a box of half extents `he` (positive inside).
#[inline]
fn box_phi(p: DVec3, he: DVec3) -> f64 {
    let q = p.abs() - he;
    -(q.max(DVec3::ZERO).length() + q.max_element().min(0.0))
}

#[inline]
fn rect_phi(p: DVec2, he: DVec2) -> f64 {
    rect_phi_from_q(p.abs() - he)
}

impl Kind {
    fn surface(&self, half_size: f64, dim: usize) -> SurfaceMesh {
        use parry3d_f64::shape::{Ball, Capsule, Cuboid, Cylinder};
        // parry's cylinders and capsules run along y; ours along the body's z.
        let y_to_z = |p: DVec3| DVec3::new(p.x, -p.z, p.y);
        // Polar subdivisions: fine enough to look round at a few cells per radius.
        const NT: u32 = 32;
        const NP: u32 = 16;
        let ring = |n: usize, f: &dyn Fn(f64) -> DVec3| {
            SurfaceMesh::closed_polyline(
                (0..n).map(|i| f(2.0 * PI * i as f64 / n as f64)).collect(),
            )
        };
        match self {
            Kind::Sphere { r } => {
                let (v, t) = Ball::new(*r).to_trimesh(NT, NP);
                SurfaceMesh::from_parry(v, t)
            }
            Kind::Ellipsoid { radii } => {
                let (v, t) = Ball::new(1.0).to_trimesh(NT, NP);
                SurfaceMesh::from_parry(v, t).map(|p| p * *radii)
            }
            Kind::Box { he } => {
                let (v, t) = Cuboid::new(PVec::new(he.x, he.y, he.z)).to_trimesh();
                SurfaceMesh::from_parry(v, t)
            }
            Kind::Cylinder { r, hh } => {
                let (v, t) = Cylinder::new(*hh, *r).to_trimesh(NT);
                SurfaceMesh::from_parry(v, t).map(y_to_z)
            }
            Kind::Capsule { r, hh } => {
                let (v, t) = Capsule::new_y(*hh, *r).to_trimesh(NT, NP);
                SurfaceMesh::from_parry(v, t).map(y_to_z)
            }
            Kind::HalfSpace { n, offset } => {
                // The plane n.x = offset (the solid is n.x <= offset or >= offset: either way
                // its boundary is this plane).
                let c = *n * *offset;
                if dim == 2 {
                    let t = DVec3::new(-n.y, n.x, 0.0).normalize_or_zero() * half_size;
                    return SurfaceMesh {
                        points: vec![c - t, c + t],
                        triangles: Vec::new(),
                        lines: vec![[0, 1]],
                    };
                }
                let (u, w) = n.any_orthonormal_pair();
                let (u, w) = (u * half_size, w * half_size);
                SurfaceMesh {
                    points: vec![c - u - w, c + u - w, c + u + w, c - u + w],
                    triangles: vec![[0, 1, 2], [0, 2, 3]],
                    lines: Vec::new(),
                }
            }
            Kind::Disk { r } => ring(96, &|a| DVec3::new(r * a.cos(), r * a.sin(), 0.0)),
            Kind::Ellipse { radii } => ring(96, &|a| {
                DVec3::new(radii.x * a.cos(), radii.y * a.sin(), 0.0)
            }),
            Kind::Rectangle { he } => SurfaceMesh::closed_polyline(vec![
                DVec3::new(-he.x, -he.y, 0.0),
                DVec3::new(he.x, -he.y, 0.0),
                DVec3::new(he.x, he.y, 0.0),
                DVec3::new(-he.x, he.y, 0.0),
            ]),
            Kind::Complement(inner) => inner.surface(half_size, dim),
            Kind::Mesh(m) => SurfaceMesh {
                points: m
                    .trimesh
                    .vertices()
                    .iter()
                    .map(|p| DVec3::new(p.x, p.y, p.z))
                    .collect(),
                triangles: m.trimesh.indices().to_vec(),
                lines: Vec::new(),
            },
        }
    }

    #[inline]
    fn phi(&self, p: DVec3) -> f64 {
        match self {
            Kind::Sphere { r } => r - p.length(),
            Kind::Ellipsoid { radii } => ellipsoid_phi(*radii, p),
            Kind::Box { he } => box_phi(p, *he),
            Kind::Cylinder { r, hh } => {
                let d = DVec2::new(p.truncate().length() - r, p.z.abs() - hh);
                rect_phi_from_q(d)
            }
            Kind::Capsule { r, hh } => {
                let z = p.z.clamp(-hh, *hh);
                r - DVec3::new(p.x, p.y, p.z - z).length()
            }
            Kind::HalfSpace { n, offset } => offset - n.dot(p),
            Kind::Disk { r } => r - p.truncate().length(),
            Kind::Ellipse { radii } => ellipse_phi(*radii, p.truncate()),
            Kind::Rectangle { he } => rect_phi(p.truncate(), *he),
            Kind::Complement(inner) => -inner.phi(p),
            Kind::Mesh(m) => m.phi(p),
        }
    }

    fn bounds(&self) -> Option<(DVec3, DVec3)> {
        let b = match self {
            Kind::Sphere { r } => DVec3::splat(*r),
            Kind::Ellipsoid { radii } => *radii,
            Kind::Box { he } => *he,
            Kind::Cylinder { r, hh } => DVec3::new(*r, *r, *hh),
            Kind::Capsule { r, hh } => DVec3::new(*r, *r, hh + r),
            Kind::Disk { r } => DVec3::new(*r, *r, 0.0),
            Kind::Ellipse { radii } => radii.extend(0.0),
            Kind::Rectangle { he } => he.extend(0.0),
            Kind::HalfSpace { .. } | Kind::Complement(_) => return None,
            Kind::Mesh(m) => return Some((m.lo, m.hi)),
        };
        Some((-b, b))
    }

    fn is_expensive(&self) -> bool {
        match self {
            Kind::Ellipsoid { .. } | Kind::Ellipse { .. } | Kind::Mesh(_) => true,
            Kind::Complement(inner) => inner.is_expensive(),
            _ => false,
        }
    }

    fn volume(&self) -> Option<f64> {
        Some(match self {
            Kind::Sphere { r } => 4.0 / 3.0 * PI * r.powi(3),
            Kind::Ellipsoid { radii } => 4.0 / 3.0 * PI * radii.x * radii.y * radii.z,
            Kind::Box { he } => 8.0 * he.x * he.y * he.z,
            Kind::Cylinder { r, hh } => PI * r * r * 2.0 * hh,
            Kind::Capsule { r, hh } => PI * r * r * 2.0 * hh + 4.0 / 3.0 * PI * r.powi(3),
            Kind::Disk { r } => PI * r * r,
            Kind::Ellipse { radii } => PI * radii.x * radii.y,
            Kind::Rectangle { he } => 4.0 * he.x * he.y,
            Kind::Mesh(m) => m.volume,
            Kind::HalfSpace { .. } | Kind::Complement(_) => return None,
        })
    }

    fn inertia(&self) -> Option<DMat3> {
        let m = self.volume()?;
        let diag = match self {
            Kind::Sphere { r } => DVec3::splat(0.4 * m * r * r),
            Kind::Ellipsoid { radii: e } => {
                let e2 = *e * *e;
                DVec3::new(e2.y + e2.z, e2.x + e2.z, e2.x + e2.y) * (m / 5.0)
            }
            Kind::Box { he } => {
                let e2 = *he * *he;
                DVec3::new(e2.y + e2.z, e2.x + e2.z, e2.x + e2.y) * (m / 3.0)
            }
            Kind::Cylinder { r, hh } => {
                let t = m * (r * r / 4.0 + hh * hh / 3.0);
                DVec3::new(t, t, m * r * r / 2.0)
            }
            Kind::Capsule { r, hh } => {
                // cylinder part + two hemispheres (parallel-axis theorem about the origin)
                let mc = PI * r * r * 2.0 * hh;
                let ms = 4.0 / 3.0 * PI * r.powi(3);
                let t = mc * (r * r / 4.0 + hh * hh / 3.0)
                    + ms * (0.4 * r * r + hh * hh + 0.75 * hh * r);
                DVec3::new(t, t, mc * r * r / 2.0 + ms * 0.4 * r * r)
            }
            Kind::Disk { r } => {
                let t = m * r * r / 4.0;
                DVec3::new(t, t, 2.0 * t)
            }
            Kind::Ellipse { radii } => {
                let (ix, iy) = (m * radii.y * radii.y / 4.0, m * radii.x * radii.x / 4.0);
                DVec3::new(ix, iy, ix + iy)
            }
            Kind::Rectangle { he } => {
                let (ix, iy) = (m * he.y * he.y / 3.0, m * he.x * he.x / 3.0);
                DVec3::new(ix, iy, ix + iy)
            }
            Kind::Mesh(mesh) => return Some(mesh.inertia),
            Kind::HalfSpace { .. } | Kind::Complement(_) => return None,
        };
        Some(DMat3::from_diagonal(diag))
    }
}

/// `-sdf` of the 2D "box" given `q = |p| - he` (used by the cylinder).
#[inline]
fn rect_phi_from_q(q: DVec2) -> f64 {
    -(q.max(DVec2::ZERO).length() + q.max_element().min(0.0))
}

// ---------------------------------------------------------------------------------------------
// Ellipse / ellipsoid distance: D. Eberly, "Distance from a point to an ellipse, an ellipsoid,
// or a hyperellipsoid" (Geometric Tools, 2013). Robust bisection on the Lagrange parameter.
// ---------------------------------------------------------------------------------------------

const MAX_BISECTION: usize = 200;

fn robust_length(v: &[f64]) -> f64 {
    let m = v.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    if m == 0.0 {
        return 0.0;
    }
    m * v.iter().map(|x| (x / m) * (x / m)).sum::<f64>().sqrt()
}

fn get_root2(r0: f64, z0: f64, z1: f64, g: f64) -> f64 {
    let n0 = r0 * z0;
    let mut s0 = z1 - 1.0;
    let mut s1 = if g < 0.0 {
        0.0
    } else {
        robust_length(&[n0, z1]) - 1.0
    };
    let mut s = 0.0;
    for _ in 0..MAX_BISECTION {
        s = 0.5 * (s0 + s1);
        if s == s0 || s == s1 {
            break;
        }
        let a = n0 / (s + r0);
        let b = z1 / (s + 1.0);
        let g = a * a + b * b - 1.0;
        if g > 0.0 {
            s0 = s;
        } else if g < 0.0 {
            s1 = s;
        } else {
            break;
        }
    }
    s
}

/// Unsigned distance from `(y0, y1)` (both >= 0) to the ellipse with semi-axes `e0 >= e1 > 0`.
fn ellipse_distance(e0: f64, e1: f64, y0: f64, y1: f64) -> f64 {
    if y1 > 0.0 {
        if y0 > 0.0 {
            let z0 = y0 / e0;
            let z1 = y1 / e1;
            let g = z0 * z0 + z1 * z1 - 1.0;
            if g != 0.0 {
                let r0 = (e0 / e1) * (e0 / e1);
                let sbar = get_root2(r0, z0, z1, g);
                let x0 = r0 * y0 / (sbar + r0);
                let x1 = y1 / (sbar + 1.0);
                ((x0 - y0).powi(2) + (x1 - y1).powi(2)).sqrt()
            } else {
                0.0
            }
        } else {
            (y1 - e1).abs()
        }
    } else {
        let numer0 = e0 * y0;
        let denom0 = e0 * e0 - e1 * e1;
        if numer0 < denom0 {
            let xde0 = numer0 / denom0;
            let x0 = e0 * xde0;
            let x1 = e1 * (1.0 - xde0 * xde0).max(0.0).sqrt();
            ((x0 - y0).powi(2) + x1 * x1).sqrt()
        } else {
            (y0 - e0).abs()
        }
    }
}

fn get_root3(r0: f64, r1: f64, z0: f64, z1: f64, z2: f64, g: f64) -> f64 {
    let n0 = r0 * z0;
    let n1 = r1 * z1;
    let mut s0 = z2 - 1.0;
    let mut s1 = if g < 0.0 {
        0.0
    } else {
        robust_length(&[n0, n1, z2]) - 1.0
    };
    let mut s = 0.0;
    for _ in 0..MAX_BISECTION {
        s = 0.5 * (s0 + s1);
        if s == s0 || s == s1 {
            break;
        }
        let a = n0 / (s + r0);
        let b = n1 / (s + r1);
        let c = z2 / (s + 1.0);
        let g = a * a + b * b + c * c - 1.0;
        if g > 0.0 {
            s0 = s;
        } else if g < 0.0 {
            s1 = s;
        } else {
            break;
        }
    }
    s
}

/// Unsigned distance from `y` (all >= 0) to the ellipsoid with semi-axes `e0 >= e1 >= e2 > 0`.
fn ellipsoid_distance(e: [f64; 3], y: [f64; 3]) -> f64 {
    let [e0, e1, e2] = e;
    let [y0, y1, y2] = y;
    if y2 > 0.0 {
        if y1 > 0.0 {
            if y0 > 0.0 {
                let (z0, z1, z2) = (y0 / e0, y1 / e1, y2 / e2);
                let g = z0 * z0 + z1 * z1 + z2 * z2 - 1.0;
                if g != 0.0 {
                    let r0 = (e0 / e2) * (e0 / e2);
                    let r1 = (e1 / e2) * (e1 / e2);
                    let sbar = get_root3(r0, r1, z0, z1, z2, g);
                    let x0 = r0 * y0 / (sbar + r0);
                    let x1 = r1 * y1 / (sbar + r1);
                    let x2 = y2 / (sbar + 1.0);
                    ((x0 - y0).powi(2) + (x1 - y1).powi(2) + (x2 - y2).powi(2)).sqrt()
                } else {
                    0.0
                }
            } else {
                ellipse_distance(e1, e2, y1, y2)
            }
        } else if y0 > 0.0 {
            ellipse_distance(e0, e2, y0, y2)
        } else {
            (y2 - e2).abs()
        }
    } else {
        let denom0 = e0 * e0 - e2 * e2;
        let denom1 = e1 * e1 - e2 * e2;
        let numer0 = e0 * y0;
        let numer1 = e1 * y1;
        if numer0 < denom0 && numer1 < denom1 {
            let xde0 = numer0 / denom0;
            let xde1 = numer1 / denom1;
            let discr = 1.0 - xde0 * xde0 - xde1 * xde1;
            if discr > 0.0 {
                let x0 = e0 * xde0;
                let x1 = e1 * xde1;
                let x2 = e2 * discr.sqrt();
                return ((x0 - y0).powi(2) + (x1 - y1).powi(2) + x2 * x2).sqrt();
            }
        }
        ellipse_distance(e0, e1, y0, y1)
    }
}

/// Signed distance to the ellipse with semi-axes `radii` (positive inside).
fn ellipse_phi(radii: DVec2, p: DVec2) -> f64 {
    let (a, b) = (p.abs(), radii);
    let d = if b.x >= b.y {
        ellipse_distance(b.x, b.y, a.x, a.y)
    } else {
        ellipse_distance(b.y, b.x, a.y, a.x)
    };
    if (p / radii).length_squared() < 1.0 {
        d
    } else {
        -d
    }
}

/// Signed distance to the ellipsoid with semi-axes `radii` (positive inside).
fn ellipsoid_phi(radii: DVec3, p: DVec3) -> f64 {
    let e = radii.to_array();
    let y = p.abs().to_array();
    // sort the axes by decreasing semi-axis
    let mut idx = [0usize, 1, 2];
    idx.sort_by(|&i, &j| e[j].total_cmp(&e[i]));
    let d = ellipsoid_distance(idx.map(|i| e[i]), idx.map(|i| y[i]));
    if (p / radii).length_squared() < 1.0 {
        d
    } else {
        -d
    }
}

// ---------------------------------------------------------------------------------------------
// Meshes
// ---------------------------------------------------------------------------------------------

/// A loaded, closed, outward-oriented triangle mesh.
#[derive(Clone)]
struct MeshGeom {
    file: PathBuf,
    trimesh: TriMesh,
    lo: DVec3,
    hi: DVec3,
    volume: f64,
    inertia: DMat3,
}

impl fmt::Debug for MeshGeom {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("MeshGeom")
            .field("file", &self.file)
            .field("triangles", &self.trimesh.indices().len())
            .field("vertices", &self.trimesh.vertices().len())
            .field("lo", &self.lo)
            .field("hi", &self.hi)
            .field("volume", &self.volume)
            .finish()
    }
}

/// Raw triangle soup read from a file: positions (body units) and triangles.
type Soup = (Vec<[f64; 3]>, Vec<[usize; 3]>);

fn read_obj(path: &Path) -> Result<Soup, String> {
    // `..Default::default()` covers the fields behind tobj's optional features
    #[allow(clippy::needless_update)]
    let opts = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    let (models, _materials) = tobj::load_obj(path, &opts).map_err(|e| {
        format!(
            "mesh file {} is not a readable OBJ file: {e}",
            path.display()
        )
    })?;
    let mut pos = Vec::new();
    let mut tris = Vec::new();
    for model in &models {
        let m = &model.mesh;
        let base = pos.len();
        for c in m.positions.chunks_exact(3) {
            // tobj's `use_f64` feature: coordinates are parsed as f64
            pos.push([c[0], c[1], c[2]]);
        }
        for t in m.indices.chunks_exact(3) {
            tris.push([
                base + t[0] as usize,
                base + t[1] as usize,
                base + t[2] as usize,
            ]);
        }
    }
    Ok((pos, tris))
}

fn read_stl(path: &Path) -> Result<Soup, String> {
    let bad = |e: std::io::Error| {
        format!(
            "mesh file {} is not a readable STL file: {e}",
            path.display()
        )
    };
    let mut f = std::fs::File::open(path).map_err(bad)?;
    let len = f.metadata().map_err(bad)?.len();
    // A binary STL is 84 + 50 n bytes; reject a header that promises more triangles than the
    // file holds before stl_io tries to read them.
    let mut head = [0u8; 84];
    use std::io::{Read, Seek};
    let is_ascii = {
        let n = f.read(&mut head).map_err(bad)?;
        f.rewind().map_err(bad)?;
        head[..n.min(5)].eq_ignore_ascii_case(b"solid")
    };
    if !is_ascii {
        if len < 84 {
            return Err(format!(
                "mesh file {} is not a readable STL file: too short for a binary STL ({len} bytes)",
                path.display()
            ));
        }
        let n = u32::from_le_bytes([head[80], head[81], head[82], head[83]]) as u64;
        if 84 + 50 * n != len {
            return Err(format!(
                "mesh file {} is not a readable STL file: binary header says {n} triangles ({} bytes) but the file has {len} bytes",
                path.display(),
                84 + 50 * n
            ));
        }
    }
    let mut reader = std::io::BufReader::new(f);
    let mesh = stl_io::read_stl(&mut reader).map_err(bad)?;
    let pos = mesh.vertices.iter().map(|v| v.0.map(f64::from)).collect();
    let tris = mesh.faces.iter().map(|t| t.vertices).collect();
    Ok((pos, tris))
}

impl MeshGeom {
    fn load(path: &Path, scale: f64) -> Result<Self, String> {
        let shown = path.display();
        if !path.exists() {
            return Err(format!("mesh file {shown} not found"));
        }
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase());
        let (pos, tris) = match ext.as_deref() {
            Some("obj") => read_obj(path)?,
            Some("stl") => read_stl(path)?,
            _ => {
                return Err(format!(
                    "mesh file {shown}: unsupported format (expected a .obj or .stl file)"
                ));
            }
        };
        if tris.is_empty() {
            return Err(format!(
                "mesh file {shown} is not a readable mesh: it contains no triangles"
            ));
        }
        if pos.iter().flatten().any(|c| !c.is_finite()) {
            return Err(format!(
                "mesh file {shown} is corrupt: it has non-finite vertex coordinates"
            ));
        }
        if let Some(t) = tris.iter().find(|t| t.iter().any(|&i| i >= pos.len())) {
            return Err(format!(
                "mesh file {shown} is corrupt: triangle {t:?} refers to a missing vertex"
            ));
        }

        // Merge vertices with identical coordinates (STL stores each triangle's corners
        // separately; OBJ objects may repeat them), treating -0 as 0.
        let mut remap = Vec::with_capacity(pos.len());
        let mut verts: Vec<DVec3> = Vec::new();
        let mut seen: HashMap<[u64; 3], u32> = HashMap::new();
        for p in &pos {
            let key = p.map(|c| (c + 0.0).to_bits());
            let id = *seen.entry(key).or_insert_with(|| {
                verts.push(DVec3::from_array(*p) * scale);
                (verts.len() - 1) as u32
            });
            remap.push(id);
        }
        // drop triangles with a repeated corner (zero area after merging)
        let mut idx: Vec<[u32; 3]> = tris
            .iter()
            .map(|t| t.map(|i| remap[i]))
            .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
            .collect();
        if idx.is_empty() {
            return Err(format!("mesh file {shown} has only degenerate triangles"));
        }

        // Closed: every edge is shared by exactly two triangles; consistently oriented: they
        // traverse it in opposite directions.
        let mut edges: HashMap<(u32, u32), (u32, i32)> = HashMap::new();
        for t in &idx {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                let e = edges.entry((a.min(b), a.max(b))).or_insert((0, 0));
                e.0 += 1;
                e.1 += if a < b { 1 } else { -1 };
            }
        }
        let open = edges.values().filter(|e| e.0 != 2).count();
        if open > 0 {
            let boundary = edges.values().filter(|e| e.0 == 1).count();
            return Err(format!(
                "mesh file {shown} is not closed: {open} open edges (not shared by exactly two triangles; {boundary} of them belong to a single triangle, {} to three or more); a body mesh must be a closed surface",
                open - boundary
            ));
        }
        let flipped = edges.values().filter(|e| e.1 != 0).count();
        if flipped > 0 {
            return Err(format!(
                "mesh file {shown} is not consistently oriented: {flipped} edges are traversed in the same direction by both of their triangles"
            ));
        }

        // Volume and inertia about the origin (signed tetrahedra with the origin); flip the
        // triangles if the mesh is oriented inwards.
        let (mut volume, mut inertia) = polyhedron_mass(&verts, &idx);
        if volume == 0.0 || !volume.is_finite() {
            return Err(format!("mesh file {shown} encloses no volume"));
        }
        if volume < 0.0 {
            for t in &mut idx {
                t.swap(1, 2);
            }
            volume = -volume;
            inertia = -inertia;
        }

        let (lo, hi) = verts.iter().fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), v| (lo.min(*v), hi.max(*v)),
        );
        let pverts: Vec<PVec> = verts.iter().map(|v| PVec::new(v.x, v.y, v.z)).collect();
        let trimesh = TriMesh::with_flags(pverts, idx, TriMeshFlags::ORIENTED)
            .map_err(|e| format!("mesh file {shown}: cannot build the triangle mesh: {e:?}"))?;
        Ok(MeshGeom {
            file: path.to_path_buf(),
            trimesh,
            lo,
            hi,
            volume,
            inertia,
        })
    }

    #[inline]
    fn phi(&self, p: DVec3) -> f64 {
        let pt = PVec::new(p.x, p.y, p.z);
        let proj = self.trimesh.project_local_point(pt, false);
        let d = (proj.point - pt).length();
        if proj.is_inside { d } else { -d }
    }
}

/// Signed volume and inertia tensor (unit density, about the origin) of a closed triangle
/// mesh, summing the tetrahedra (origin, a, b, c): covariance `C = det(A) A C0 A^T` with
/// `C0 = (1 + delta_ij) / 120`, then `I = tr(C) Id - C`.
fn polyhedron_mass(verts: &[DVec3], idx: &[[u32; 3]]) -> (f64, DMat3) {
    let c0 = DMat3::from_cols_array(&[2.0, 1.0, 1.0, 1.0, 2.0, 1.0, 1.0, 1.0, 2.0]) / 120.0;
    let mut vol = 0.0;
    let mut cov = DMat3::ZERO;
    for t in idx {
        let a = DMat3::from_cols(
            verts[t[0] as usize],
            verts[t[1] as usize],
            verts[t[2] as usize],
        );
        let det = a.determinant();
        vol += det / 6.0;
        cov += (a * c0 * a.transpose()) * det;
    }
    let tr = cov.x_axis.x + cov.y_axis.y + cov.z_axis.z;
    (vol, DMat3::from_diagonal(DVec3::splat(tr)) - cov)
}

/// Fixed-size arrays read and written as RON lists (`[1.0, 2.0]`), like every other vector in
/// a scene, instead of serde's default tuples.
mod seq_array {
    use serde::{Deserialize, Deserializer, Serializer, de::Error};

    pub fn serialize<S: Serializer, const N: usize>(v: &[f64; N], s: S) -> Result<S::Ok, S::Error> {
        s.collect_seq(v.iter())
    }

    pub fn deserialize<'de, D: Deserializer<'de>, const N: usize>(
        d: D,
    ) -> Result<[f64; N], D::Error> {
        let v = Vec::<f64>::deserialize(d)?;
        let n = v.len();
        v.try_into()
            .map_err(|_| D::Error::custom(format!("expected a list of {N} numbers, got {n}")))
    }
}
