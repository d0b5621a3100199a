//! Body surfaces for viewing: each shape's boundary as triangles (3D) or line segments (2D), in
//! the body's own frame, tessellated once; the output layer places them at the body's pose.
//!
//! Analytic solids come from parry's `to_trimesh`, meshes are their own triangles, 2D shapes
//! are closed polylines. A half-space is a square patch of its plane, `2 * half_size` wide,
//! centred on the point of the plane nearest the body origin. A complement has the surface
//! of the shape it is the complement of.

use glam::DVec3;

/// A surface in body coordinates: triangles in 3D, line segments in 2D.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SurfaceMesh {
    /// Vertex positions (body frame).
    pub points: Vec<DVec3>,
    /// Triangles, as indices into `points` (3D shapes).
    pub triangles: Vec<[u32; 3]>,
    /// Line segments, as indices into `points` (2D shapes).
    pub lines: Vec<[u32; 2]>,
}

impl SurfaceMesh {
    /// Whether it has no cell at all.
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty() && self.lines.is_empty()
    }

    /// A closed polyline through `points` (2D outlines).
    pub fn closed_polyline(points: Vec<DVec3>) -> Self {
        let n = points.len() as u32;
        let lines = (0..n).map(|i| [i, (i + 1) % n]).collect();
        SurfaceMesh {
            points,
            triangles: Vec::new(),
            lines,
        }
    }

    /// Triangles from parry's `(vertices, indices)`.
    pub fn from_parry(v: Vec<parry3d_f64::math::Vector>, t: Vec<[u32; 3]>) -> Self {
        SurfaceMesh {
            points: v.iter().map(|p| DVec3::new(p.x, p.y, p.z)).collect(),
            triangles: t,
            lines: Vec::new(),
        }
    }

    /// The same surface with every point mapped by `f`.
    pub fn map(mut self, f: impl Fn(DVec3) -> DVec3) -> Self {
        for p in &mut self.points {
            *p = f(*p);
        }
        self
    }

    /// Area (3D: sum of the triangles' areas) or length (2D: sum of the segments' lengths).
    pub fn measure(&self) -> f64 {
        let p = |i: u32| self.points[i as usize];
        let tri: f64 = self
            .triangles
            .iter()
            .map(|t| 0.5 * (p(t[1]) - p(t[0])).cross(p(t[2]) - p(t[0])).length())
            .sum();
        let len: f64 = self
            .lines
            .iter()
            .map(|l| (p(l[1]) - p(l[0])).length())
            .sum();
        tri + len
    }
}
