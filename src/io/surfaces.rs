//! Surfaces for ParaView: a `.vtp` (VTK XML PolyData) per snapshot holding every part's surface
//! in its current pose, indexed by a `.pvd` time series that opens beside the fields.
//!
//! A part is anything with a surface: a rigid body (its shape's tessellation in the body frame,
//! placed at the body's pose) or, later, a free surface (its zero level set, in world
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
        for p in parts {
            if p.vectors.len() != self.vector_names.len() {
                return Err(io::Error::new(
                    io::ErrorKind::InvalidInput,
                    format!(
                        "surface part `{}` has {} vectors, the series {}",
                        p.name,
                        p.vectors.len(),
                        self.vector_names.len()
                    ),
                ));
            }
        }
        let name = format!("{}_{index:06}.vtp", self.stem);
        let xml = vtp(t, parts, &self.vector_names);
        atomic_write(&self.dir.join(&name), xml.as_bytes())?;
        self.pvd.push(t, &name)?;
        Ok(name)
    }
}

/// The `.vtp` text of one snapshot.
fn vtp(t: f64, parts: &[SurfacePart], vector_names: &[&str]) -> String {
    let n_points: usize = parts.iter().map(|p| p.mesh.points.len()).sum();
    let n_lines: usize = parts.iter().map(|p| p.mesh.lines.len()).sum();
    let n_polys: usize = parts.iter().map(|p| p.mesh.triangles.len()).sum();
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
        parts.len()
    );
    for p in parts {
        for b in p.name.bytes() {
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
    for p in parts {
        for q in &p.mesh.points {
            let w = p.center + p.orientation * *q;
            let _ = writeln!(s, "{} {} {}", w.x as f32, w.y as f32, w.z as f32);
        }
    }
    s.push_str("</DataArray>\n</Points>\n");
    // Cell data: VTK orders the cells of a PolyData as verts, lines, polys, strips.
    s.push_str("<CellData Scalars=\"part_id\">\n");
    s.push_str("<DataArray type=\"Int32\" Name=\"part_id\" format=\"ascii\">\n");
    for pass in 0..2 {
        for (i, p) in parts.iter().enumerate() {
            let n = if pass == 0 {
                p.mesh.lines.len()
            } else {
                p.mesh.triangles.len()
            };
            for _ in 0..n {
                let _ = write!(s, "{i} ");
            }
        }
    }
    s.push_str("\n</DataArray>\n");
    for (k, vn) in vector_names.iter().enumerate() {
        let _ = writeln!(
            s,
            "<DataArray type=\"Float32\" Name=\"{vn}\" NumberOfComponents=\"3\" format=\"ascii\">"
        );
        for pass in 0..2 {
            for p in parts {
                let n = if pass == 0 {
                    p.mesh.lines.len()
                } else {
                    p.mesh.triangles.len()
                };
                let v = p.vectors[k];
                for _ in 0..n {
                    let _ = writeln!(s, "{} {} {}", v.x as f32, v.y as f32, v.z as f32);
                }
            }
        }
        s.push_str("</DataArray>\n");
    }
    s.push_str("</CellData>\n");
    cells(&mut s, "Lines", parts, |m| {
        m.lines.iter().map(|l| l.to_vec()).collect()
    });
    cells(&mut s, "Polys", parts, |m| {
        m.triangles.iter().map(|t| t.to_vec()).collect()
    });
    s.push_str("</Piece>\n</PolyData>\n</VTKFile>\n");
    s
}

/// A `<Lines>` or `<Polys>` block: connectivity (global point indices) and offsets.
fn cells(
    s: &mut String,
    tag: &str,
    parts: &[SurfacePart],
    of: impl Fn(&SurfaceMesh) -> Vec<Vec<u32>>,
) {
    let _ = writeln!(
        s,
        "<{tag}>\n<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">"
    );
    let mut base = 0usize;
    let mut offsets = Vec::new();
    let mut end = 0usize;
    for p in parts {
        for c in of(p.mesh) {
            for i in &c {
                let _ = write!(s, "{} ", base + *i as usize);
            }
            end += c.len();
            offsets.push(end);
        }
        base += p.mesh.points.len();
    }
    s.push_str("\n</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n");
    for o in offsets {
        let _ = write!(s, "{o} ");
    }
    let _ = writeln!(s, "\n</DataArray>\n</{tag}>");
}
