//! Surfaces for ParaView: a `.vtp` (VTK XML PolyData) per snapshot holding every part's surface
//! in its current pose, indexed by a `.pvd` time series that opens beside the fields.
//!
//! A part is anything with a surface: a rigid body (its shape's tessellation in the body frame,
//! placed at the body's pose) or a free surface (its zero level set, in world
//! coordinates with the identity pose). Each cell carries the part's index (`part_id`, into
//! the field-data array `part_names`) and the part's vectors (velocity, force, ...), so
//! ParaView can colour the surfaces by any of them.

use std::fmt::Write as _;
use std::io;
use std::path::{Path, PathBuf};

use glam::{DQuat, DVec3};

use crate::bodies::surface::SurfaceMesh;
use crate::io::output::{PvdSeries, atomic_write, fmt_f64};

/// One part of a snapshot: a surface at a pose, with per-part vectors as cell data.
pub struct SurfacePart<'a> {
    /// Name shown in ParaView's field data.
    pub name: &'a str,
    /// The surface in the part's own frame.
    pub mesh: &'a SurfaceMesh,
    /// Where the part's frame origin is (world).
    pub center: DVec3,
    /// The part's orientation (world from part frame).
    pub orientation: DQuat,
    /// Vectors carried by every cell of the part, one per name in [`SurfaceSeries::new`].
    pub vectors: Vec<DVec3>,
}

/// A time series of surface snapshots, `<stem>_NNNNNN.vtp` + `<stem>.pvd`.
pub struct SurfaceSeries {
    dir: PathBuf,
    stem: String,
    vector_names: Vec<&'static str>,
    pvd: PvdSeries,
}

impl SurfaceSeries {
    /// A series in `dir` named `stem`, whose parts carry the vectors `vector_names`.
    pub fn new(dir: &Path, stem: &str, vector_names: &[&'static str]) -> Self {
        SurfaceSeries {
            dir: dir.to_path_buf(),
            stem: stem.to_string(),
            vector_names: vector_names.to_vec(),
            pvd: PvdSeries::new(dir.join(format!("{stem}.pvd"))),
        }
    }

    /// The same series continuing after a restart: the `.pvd` lists `entries`.
    pub fn with_entries(mut self, entries: Vec<(f64, String)>) -> Self {
        self.pvd = PvdSeries::with_entries(self.pvd.path().to_path_buf(), entries);
        self
    }

    /// The `.pvd` index.
    pub fn pvd(&self) -> &PvdSeries {
        &self.pvd
    }

    /// Writes snapshot `index` at time `t` and lists it in the `.pvd`; returns the file name.
    pub fn write(&mut self, index: usize, t: f64, parts: &[SurfacePart]) -> io::Result<String> {
        let g = SurfaceGeometry::new(parts, &self.vector_names)?;
        self.write_geometry(index, t, &g)
    }

    /// Writes snapshot `index` at time `t` from its computed surfaces (with the series'
    /// vectors) and lists it in the `.pvd`; returns the file name.
    pub fn write_geometry(
        &mut self,
        index: usize,
        t: f64,
        g: &SurfaceGeometry,
    ) -> io::Result<String> {
        if g.vector_names != self.vector_names {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!(
                    "surfaces carry the vectors {:?}, the series {:?}",
                    g.vector_names, self.vector_names
                ),
            ));
        }
        let name = format!("{}_{index:06}.vtp", self.stem);
        let xml = vtp(t, g);
        atomic_write(&self.dir.join(&name), xml.as_bytes())?;
        self.pvd.push(t, &name)?;
        Ok(name)
    }

    /// The names of the vectors the parts carry.
    pub fn vector_names(&self) -> &[&'static str] {
        &self.vector_names
    }
}

/// The surfaces of one snapshot in world space, computed once for every writer (`.vtp`, and
/// with the `hdf5` feature `bodies_NNNNNN.h5`): the parts' points one after the other, their
/// cells with global point indices, and per cell the part's index and vectors. Cells are in
/// VTK's PolyData order: every part's lines, then every part's triangles (a 2D scene has only
/// lines, a 3D one only triangles).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SurfaceGeometry {
    /// Part names, indexed by [`cell_part`](SurfaceGeometry::cell_part).
    pub part_names: Vec<String>,
    /// Points in world coordinates.
    pub points: Vec<DVec3>,
    /// Line segments (2D surfaces), global point indices.
    pub lines: Vec<[usize; 2]>,
    /// Triangles (3D surfaces), global point indices.
    pub triangles: Vec<[usize; 3]>,
    /// The part of each cell, lines first then triangles.
    pub cell_part: Vec<u32>,
    /// Names of the per-cell vectors.
    pub vector_names: Vec<String>,
    /// Per vector name, its value on each cell (same order as `cell_part`).
    pub cell_vectors: Vec<Vec<DVec3>>,
}

impl SurfaceGeometry {
    /// The world-space surfaces of `parts`, whose vectors are named `vector_names`; an error if
    /// a part has not one vector per name.
    pub fn new(parts: &[SurfacePart], vector_names: &[&str]) -> io::Result<Self> {
        for p in parts {
            if p.vectors.len() != vector_names.len() {
                return Err(io::Error::new(
                    io::ErrorKind::InvalidInput,
                    format!(
                        "surface part `{}` has {} vectors, the series {}",
                        p.name,
                        p.vectors.len(),
                        vector_names.len()
                    ),
                ));
            }
        }
        let mut g = SurfaceGeometry {
            part_names: parts.iter().map(|p| p.name.to_string()).collect(),
            vector_names: vector_names.iter().map(|n| n.to_string()).collect(),
            cell_vectors: vec![Vec::new(); vector_names.len()],
            ..Default::default()
        };
        let mut base = 0usize;
        let mut bases = Vec::with_capacity(parts.len());
        for p in parts {
            bases.push(base);
            g.points
                .extend(p.mesh.points.iter().map(|q| p.center + p.orientation * *q));
            base += p.mesh.points.len();
        }
        for (i, (p, &b)) in parts.iter().zip(&bases).enumerate() {
            for l in &p.mesh.lines {
                g.lines.push(l.map(|k| b + k as usize));
                g.push_cell(i, p);
            }
        }
        for (i, (p, &b)) in parts.iter().zip(&bases).enumerate() {
            for t in &p.mesh.triangles {
                g.triangles.push(t.map(|k| b + k as usize));
                g.push_cell(i, p);
            }
        }
        Ok(g)
    }

    fn push_cell(&mut self, part: usize, p: &SurfacePart) {
        self.cell_part.push(part as u32);
        for (c, v) in self.cell_vectors.iter_mut().zip(&p.vectors) {
            c.push(*v);
        }
    }

    /// Number of cells (lines and triangles).
    pub fn n_cells(&self) -> usize {
        self.cell_part.len()
    }
}

/// The `.vtp` text of one snapshot.
fn vtp(t: f64, g: &SurfaceGeometry) -> String {
    let n_points = g.points.len();
    let n_lines = g.lines.len();
    let n_polys = g.triangles.len();
    let mut s = String::with_capacity(64 * (n_points + n_lines + n_polys) + 1024);
    s.push_str("<?xml version=\"1.0\"?>\n");
    s.push_str(
        "<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" \
         header_type=\"UInt64\">\n<PolyData>\n<FieldData>\n",
    );
    let _ = writeln!(
        s,
        "<DataArray type=\"Float64\" Name=\"TimeValue\" NumberOfTuples=\"1\" format=\"ascii\">{}</DataArray>",
        fmt_f64(t)
    );
    // A string array in VTK's XML ascii form: each string's bytes as numbers, then a 0.
    let _ = write!(
        s,
        "<Array type=\"String\" Name=\"part_names\" NumberOfTuples=\"{}\" format=\"ascii\">",
        g.part_names.len()
    );
    for name in &g.part_names {
        for b in name.bytes() {
            let _ = write!(s, "{b} ");
        }
        s.push_str("0 ");
    }
    s.push_str("</Array>\n</FieldData>\n");
    let _ = writeln!(
        s,
        "<Piece NumberOfPoints=\"{n_points}\" NumberOfVerts=\"0\" NumberOfLines=\"{n_lines}\" \
         NumberOfStrips=\"0\" NumberOfPolys=\"{n_polys}\">"
    );
    s.push_str("<Points>\n<DataArray type=\"Float32\" Name=\"Points\" NumberOfComponents=\"3\" format=\"ascii\">\n");
    for w in &g.points {
        let _ = writeln!(s, "{} {} {}", w.x as f32, w.y as f32, w.z as f32);
    }
    s.push_str("</DataArray>\n</Points>\n");
    // Cell data: VTK orders the cells of a PolyData as verts, lines, polys, strips.
    s.push_str("<CellData Scalars=\"part_id\">\n");
    s.push_str("<DataArray type=\"Int32\" Name=\"part_id\" format=\"ascii\">\n");
    for i in &g.cell_part {
        let _ = write!(s, "{i} ");
    }
    s.push_str("\n</DataArray>\n");
    for (vn, vs) in g.vector_names.iter().zip(&g.cell_vectors) {
        let _ = writeln!(
            s,
            "<DataArray type=\"Float32\" Name=\"{vn}\" NumberOfComponents=\"3\" format=\"ascii\">"
        );
        for v in vs {
            let _ = writeln!(s, "{} {} {}", v.x as f32, v.y as f32, v.z as f32);
        }
        s.push_str("</DataArray>\n");
    }
    s.push_str("</CellData>\n");
    cells(&mut s, "Lines", g.lines.iter().map(|c| &c[..]));
    cells(&mut s, "Polys", g.triangles.iter().map(|c| &c[..]));
    s.push_str("</Piece>\n</PolyData>\n</VTKFile>\n");
    s
}

/// A `<Lines>` or `<Polys>` block: connectivity (global point indices) and offsets.
fn cells<'a>(s: &mut String, tag: &str, of: impl Iterator<Item = &'a [usize]>) {
    let _ = writeln!(
        s,
        "<{tag}>\n<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">"
    );
    let mut offsets = Vec::new();
    let mut end = 0usize;
    for c in of {
        for i in c {
            let _ = write!(s, "{i} ");
        }
        end += c.len();
        offsets.push(end);
    }
    s.push_str("\n</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n");
    for o in offsets {
        let _ = write!(s, "{o} ");
    }
    let _ = writeln!(s, "\n</DataArray>\n</{tag}>");
}
