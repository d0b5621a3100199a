//! Closed triangle meshes the project generates itself (for `Mesh` bodies): a cup, as a solid
//! of revolution of a polygonal profile.
//!
//! No file I/O here: [`TriangleMesh::to_obj`] and [`TriangleMesh::to_binary_stl`] format the
//! mesh, the caller writes it (the `tumble mesh cup` subcommand).
//!
//! Conventions: the solid is the region the surface encloses; triangles are listed
//! counter-clockwise seen from outside (outward normals); every edge is shared by exactly two
//! triangles, which traverse it in opposite directions.

use std::f64::consts::PI;
use std::fmt::Write as _;

use glam::DVec3;

/// A closed, outward-oriented triangle mesh: vertex positions and triangles (indices into
/// `vertices`, counter-clockwise seen from outside).
#[derive(Clone, Debug, PartialEq)]
pub struct TriangleMesh {
    /// Vertex positions (lengths).
    pub vertices: Vec<DVec3>,
    /// Triangles as vertex indices, counter-clockwise seen from outside the solid.
    pub triangles: Vec<[u32; 3]>,
}

/// The parameters of a cup (lengths in scene units): a cylindrical wall of outer radius
/// `radius` and thickness `wall`, total height `height`, a solid bottom of thickness `bottom`
/// and an open top whose rim is the flat annulus between the outer and inner wall. The circles
/// are regular polygons of `segments` sides inscribed in them (their vertices on the circles).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CupParams {
    /// Outer radius R (length).
    pub radius: f64,
    /// Total height H (length), bottom face to rim.
    pub height: f64,
    /// Wall thickness t (length), measured between the polygons' vertices: the inner radius
    /// is `radius - wall`.
    pub wall: f64,
    /// Bottom thickness b (length): the cavity's floor is `bottom` above the cup's base.
    pub bottom: f64,
    /// Sides of the polygons that stand for the circles (at least 8).
    pub segments: u32,
}

impl Default for CupParams {
    /// The cup of the paper's Fig. 10 scene in a box about 1 unit wide: R = 0.1, H = 0.2,
    /// t = 0.025 (3.2 cells at 128 cells per unit, 1.6 at 64), b = 0.03, 64 segments.
    fn default() -> Self {
        CupParams {
            radius: 0.1,
            height: 0.2,
            wall: 0.025,
            bottom: 0.03,
            segments: 64,
        }
    }
}

/// Area of the regular `n`-gon inscribed in the circle of radius `r`.
fn polygon_area(n: u32, r: f64) -> f64 {
    0.5 * n as f64 * r * r * (2.0 * PI / n as f64).sin()
}

impl CupParams {
    /// The smallest number of segments accepted.
    pub const MIN_SEGMENTS: u32 = 8;

    /// Checks the numbers: finite positive lengths, `wall < radius`, `bottom < height`,
    /// `segments >= 8`. The message names the offending parameter.
    pub fn validate(&self) -> Result<(), String> {
        for (name, v) in [
            ("radius", self.radius),
            ("height", self.height),
            ("wall", self.wall),
            ("bottom", self.bottom),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(format!(
                    "cup {name} must be a positive finite length, got {v}"
                ));
            }
        }
        if self.wall >= self.radius {
            return Err(format!(
                "cup wall ({}) must be thinner than the radius ({}): the cup would have no cavity",
                self.wall, self.radius
            ));
        }
        if self.bottom >= self.height {
            return Err(format!(
                "cup bottom ({}) must be thinner than the height ({}): the cup would have no cavity",
                self.bottom, self.height
            ));
        }
        if self.segments < Self::MIN_SEGMENTS {
            return Err(format!(
                "cup segments must be at least {}, got {}",
                Self::MIN_SEGMENTS,
                self.segments
            ));
        }
        Ok(())
    }

    /// Inner radius `radius - wall` (length).
    pub fn inner_radius(&self) -> f64 {
        self.radius - self.wall
    }

    /// Volume of the polygonal solid (exact for the mesh [`CupParams::mesh`] makes): the outer
    /// prism minus the cavity's.
    pub fn volume(&self) -> f64 {
        polygon_area(self.segments, self.radius) * self.height
            - polygon_area(self.segments, self.inner_radius()) * (self.height - self.bottom)
    }

    /// Height of the cup's base above the centroid (negative: the base is below it), such
    /// that the polygonal solid's centre of volume is at the origin. From the two prisms:
    /// the outer one (`radius`, `height`) minus the cavity (`radius - wall`,
    /// `height - bottom`, standing on the floor at `bottom`).
    pub fn base_z(&self) -> f64 {
        let (h, b) = (self.height, self.bottom);
        let a_out = polygon_area(self.segments, self.radius);
        let a_in = polygon_area(self.segments, self.inner_radius());
        // first moment about the base: prisms' volumes times their mid-heights
        let m1 = a_out * h * h / 2.0 - a_in * (h - b) * (h + b) / 2.0;
        -m1 / self.volume()
    }

    /// The cup's closed surface, axis along z, centre of volume at the origin (see
    /// [`CupParams::base_z`]). `segments` vertices on each of the four rings (base rim, outer
    /// rim, inner rim, floor rim) plus the two centres of the base and the floor:
    /// `4 segments + 2` vertices and `8 segments` triangles.
    pub fn mesh(&self) -> Result<TriangleMesh, String> {
        self.validate()?;
        let z0 = self.base_z();
        let (r, ri) = (self.radius, self.inner_radius());
        let (z1, zb) = (z0 + self.height, z0 + self.bottom);
        // Profile in the (r, z) half-plane, counter-clockwise (the solid on its left), from the
        // axis to the axis: base centre, base rim, outer rim, inner rim, floor rim, floor centre.
        let profile = [(0.0, z0), (r, z0), (r, z1), (ri, z1), (ri, zb), (0.0, zb)];
        Ok(revolve(&profile, self.segments))
    }
}

/// The closed surface of revolution about z of a polygonal profile `(r, z)` that starts and
/// ends on the axis (`r == 0` there, `r > 0` elsewhere) and runs counter-clockwise around the
/// solid in the (r, z) half-plane. Each axis end is one vertex (a fan of triangles); each
/// interior profile point is a ring of `segments` vertices at angles `2 pi k / segments`.
fn revolve(profile: &[(f64, f64)], segments: u32) -> TriangleMesh {
    let n = segments;
    let last = profile.len() - 1;
    let mut vertices = Vec::new();
    // index of the first vertex of profile point p (a pole is one vertex)
    let mut first = Vec::with_capacity(profile.len());
    for (p, &(r, z)) in profile.iter().enumerate() {
        first.push(vertices.len() as u32);
        if p == 0 || p == last {
            vertices.push(DVec3::new(0.0, 0.0, z));
        } else {
            for k in 0..n {
                let a = 2.0 * PI * k as f64 / n as f64;
                vertices.push(DVec3::new(r * a.cos(), r * a.sin(), z));
            }
        }
    }
    let mut triangles = Vec::new();
    for p in 0..last {
        let (a, b) = (first[p], first[p + 1]);
        for k in 0..n {
            let k1 = (k + 1) % n;
            // With the profile direction d and the angular direction e, d x e points into the
            // solid: the triangles (a_k, b_k+1, b_k) and (a_k, a_k+1, b_k+1) face outwards.
            if p == 0 {
                triangles.push([a, b + k1, b + k]);
            } else if p + 1 == last {
                triangles.push([a + k, a + k1, b]);
            } else {
                triangles.push([a + k, b + k1, b + k]);
                triangles.push([a + k, a + k1, b + k1]);
            }
        }
    }
    TriangleMesh {
        vertices,
        triangles,
    }
}

impl TriangleMesh {
    /// The mesh as Wavefront OBJ text: the `header` lines as `#` comments, then `v x y z`
    /// (shortest decimal that reads back to the same f64) and `f a b c` (1-based).
    pub fn to_obj(&self, header: &str) -> String {
        let mut s = String::new();
        for line in header.lines() {
            let _ = writeln!(s, "# {line}");
        }
        for v in &self.vertices {
            let _ = writeln!(s, "v {} {} {}", v.x, v.y, v.z);
        }
        for t in &self.triangles {
            let _ = writeln!(s, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1);
        }
        s
    }

    /// The mesh as binary STL, written by `stl_io`: an 80-byte header (`header`, cut or padded
    /// with spaces; it must not start with `solid`, which would read as ASCII STL), the
    /// triangle count, then per triangle its unit normal and corners as f32 (coordinates
    /// rounded to f32).
    pub fn to_binary_stl(&self, header: &str) -> Vec<u8> {
        let f32s = |v: DVec3| stl_io::Vector::new(v.to_array().map(|x| x as f32));
        let triangles = self.triangles.iter().map(|t| {
            let [a, b, c] = t.map(|i| self.vertices[i as usize]);
            stl_io::Triangle {
                normal: f32s((b - a).cross(c - a).normalize_or_zero()),
                vertices: [a, b, c].map(f32s),
            }
        });
        let mut out = Vec::with_capacity(84 + 50 * self.triangles.len());
        stl_io::write_stl(&mut out, triangles).expect("writing to memory does not fail");
        // stl_io leaves the header zero: ours says what wrote the file.
        let text = header.as_bytes();
        let n = text.len().min(80);
        out[..n].copy_from_slice(&text[..n]);
        out[n..80].fill(b' ');
        out
    }
}
