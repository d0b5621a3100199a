//! The XDMF index (`fields.xmf`) of HDF5 snapshots: an XDMF 2 temporal collection of uniform
//! grids that ParaView (*XDMF Reader*) and VisIt open as one time series.
//!
//! Each snapshot is a `3DCoRectMesh` (`2DCoRectMesh` in 2D) with node-centred attributes
//! pointing at datasets of its HDF5 file (`fields_NNNNNN.h5:/omega`). XDMF lists dimensions,
//! origins and spacings slowest axis first (z y x), which is how the datasets are stored: the
//! grid's flat order is x fastest, so a field is a C-order array of shape `(nz, ny, nx)` (or
//! `(ny, nx)` in 2D), vectors with a trailing axis of 3 components (z = 0 in 2D, as ParaView
//! wants 3-vectors).
//!
//! [`XdmfSeries::push`] rewrites the whole file atomically after each snapshot, so it only
//! lists complete snapshots.

use crate::base::grid::Grid;
use crate::io::output::{atomic_write, fmt_f64};
use std::fmt::Write as _;
use std::io;
use std::path::{Path, PathBuf};

/// One attribute of a snapshot: a dataset at the root of the snapshot's HDF5 file.
#[derive(Clone, Debug, PartialEq)]
pub struct XdmfAttribute {
    /// Attribute and dataset name.
    pub name: String,
    /// 1 (scalar) or 3 (vector).
    pub components: usize,
}

/// One snapshot in the index.
#[derive(Clone, Debug, PartialEq)]
pub struct XdmfEntry {
    /// Simulated time.
    pub time: f64,
    /// The HDF5 file, relative to the index's directory.
    pub file: String,
    /// Its fields.
    pub attributes: Vec<XdmfAttribute>,
}

/// The dataset shape of a field on `grid` with `components` components, slowest axis first:
/// `[nz, ny, nx]` or `[ny, nx]`, with a trailing `3` for vectors.
pub fn dataset_shape(grid: &Grid, components: usize) -> Vec<usize> {
    let [nx, ny, nz] = grid.n;
    let mut s = if grid.dim == 3 {
        vec![nz, ny, nx]
    } else {
        vec![ny, nx]
    };
    if components > 1 {
        s.push(3);
    }
    s
}

/// An XDMF temporal collection, rewritten on every [`push`](XdmfSeries::push).
#[derive(Clone, Debug)]
pub struct XdmfSeries {
    path: PathBuf,
    grid: Grid,
    entries: Vec<XdmfEntry>,
    /// Bytes per value of the snapshots' datasets (4 or 8).
    precision: usize,
}

impl XdmfSeries {
    /// The same series with datasets of `precision` (Double unless set).
    pub fn with_precision(mut self, precision: crate::scene::format::Precision) -> Self {
        self.precision = precision.bytes();
        self
    }

    /// A series of snapshots on `grid`, indexed in `path` (nothing written until a push).
    pub fn new(path: impl Into<PathBuf>, grid: &Grid) -> Self {
        XdmfSeries {
            path: path.into(),
            grid: grid.clone(),
            entries: Vec::new(),
            precision: 8,
        }
    }

    /// A series on `grid` indexed in `path` that already lists `entries` (a restarted run's;
    /// nothing is written until [`write`](XdmfSeries::write) or the next push).
    pub fn with_entries(path: impl Into<PathBuf>, grid: &Grid, entries: Vec<XdmfEntry>) -> Self {
        XdmfSeries {
            path: path.into(),
            grid: grid.clone(),
            entries,
            precision: 8,
        }
    }

    /// The index file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The listed snapshots, in push order.
    pub fn entries(&self) -> &[XdmfEntry] {
        &self.entries
    }

    /// Add a snapshot (its HDF5 file complete) and rewrite the index atomically. On failure
    /// the entry is not kept.
    pub fn push(&mut self, entry: XdmfEntry) -> io::Result<()> {
        crate::io::output::push_and_write(self, |s| &mut s.entries, entry, Self::write)
    }

    /// Rewrite the index atomically with the listed snapshots.
    pub fn write(&self) -> io::Result<()> {
        atomic_write(&self.path, self.text().as_bytes())
    }

    /// The XML text of the index.
    pub fn text(&self) -> String {
        let g = &self.grid;
        let h = fmt_f64(g.h);
        let (topology, geometry, dims, origin, spacing) = if g.dim == 3 {
            (
                "3DCoRectMesh",
                "ORIGIN_DXDYDZ",
                format!("{} {} {}", g.n[2], g.n[1], g.n[0]),
                format!(
                    "{} {} {}",
                    fmt_f64(g.origin[2]),
                    fmt_f64(g.origin[1]),
                    fmt_f64(g.origin[0])
                ),
                format!("{h} {h} {h}"),
            )
        } else {
            (
                "2DCoRectMesh",
                "ORIGIN_DXDY",
                format!("{} {}", g.n[1], g.n[0]),
                format!("{} {}", fmt_f64(g.origin[1]), fmt_f64(g.origin[0])),
                format!("{h} {h}"),
            )
        };
        let nd = g.dim;
        let mut s = String::new();
        s.push_str("<?xml version=\"1.0\" ?>\n");
        s.push_str("<!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>\n");
        s.push_str("<Xdmf Version=\"2.0\">\n  <Domain>\n");
        s.push_str(
            "    <Grid Name=\"fields\" GridType=\"Collection\" CollectionType=\"Temporal\">\n",
        );
        for (k, e) in self.entries.iter().enumerate() {
            let _ = writeln!(
                s,
                "      <Grid Name=\"snapshot{k:06}\" GridType=\"Uniform\">"
            );
            let _ = writeln!(s, "        <Time Value=\"{}\"/>", fmt_f64(e.time));
            let _ = writeln!(
                s,
                "        <Topology TopologyType=\"{topology}\" Dimensions=\"{dims}\"/>"
            );
            let _ = writeln!(s, "        <Geometry GeometryType=\"{geometry}\">");
            for (name, v) in [("Origin", &origin), ("Spacing", &spacing)] {
                let _ = writeln!(
                    s,
                    "          <DataItem Name=\"{name}\" Dimensions=\"{nd}\" NumberType=\"Float\" \
                     Precision=\"8\" Format=\"XML\">{v}</DataItem>"
                );
            }
            s.push_str("        </Geometry>\n");
            for a in &e.attributes {
                let shape = dataset_shape(g, a.components)
                    .iter()
                    .map(|n| n.to_string())
                    .collect::<Vec<_>>()
                    .join(" ");
                let kind = if a.components == 1 {
                    "Scalar"
                } else {
                    "Vector"
                };
                let _ = writeln!(
                    s,
                    "        <Attribute Name=\"{}\" AttributeType=\"{kind}\" Center=\"Node\">",
                    a.name
                );
                let _ = writeln!(
                    s,
                    "          <DataItem Dimensions=\"{shape}\" NumberType=\"Float\" \
                     Precision=\"{}\" Format=\"HDF\">{}:/{}</DataItem>",
                    self.precision, e.file, a.name
                );
                s.push_str("        </Attribute>\n");
            }
            s.push_str("      </Grid>\n");
        }
        s.push_str("    </Grid>\n  </Domain>\n</Xdmf>\n");
        s
    }
}

/// One body-surface snapshot in `bodies.xmf`.
#[derive(Clone, Debug, PartialEq)]
pub struct SurfaceEntry {
    /// Simulated time.
    pub time: f64,
    /// The HDF5 file (see [`crate::io::hdf5_out::write_surfaces`]), relative to the index.
    pub file: String,
    /// Number of points.
    pub points: usize,
    /// Number of cells.
    pub cells: usize,
    /// Nodes per cell: 3 (triangles, dataset `triangles`) or 2 (segments, dataset `lines`).
    pub nodes: usize,
}

/// The XDMF index of the body-surface snapshots (`bodies.xmf`): a temporal collection of
/// unstructured grids, `Triangle` (3D) or `Polyline` of 2 nodes (2D) topology, `XYZ`
/// geometry, and cell-centred `part_id` and vectors; rewritten atomically on every push.
#[derive(Clone, Debug)]
pub struct SurfaceXdmf {
    path: PathBuf,
    vectors: Vec<String>,
    entries: Vec<SurfaceEntry>,
}

impl SurfaceXdmf {
    /// An index in `path` of snapshots whose cells carry `part_id` and `vectors`, listing
    /// `entries` (nothing written until [`write`](SurfaceXdmf::write) or a push).
    pub fn new(path: impl Into<PathBuf>, vectors: &[&str], entries: Vec<SurfaceEntry>) -> Self {
        SurfaceXdmf {
            path: path.into(),
            vectors: vectors.iter().map(|v| v.to_string()).collect(),
            entries,
        }
    }

    /// The listed snapshots.
    pub fn entries(&self) -> &[SurfaceEntry] {
        &self.entries
    }

    /// Add a snapshot (its HDF5 file complete) and rewrite the index; on failure the entry is
    /// not kept.
    pub fn push(&mut self, entry: SurfaceEntry) -> io::Result<()> {
        crate::io::output::push_and_write(self, |s| &mut s.entries, entry, Self::write)
    }

    /// Rewrite the index atomically.
    pub fn write(&self) -> io::Result<()> {
        atomic_write(&self.path, self.text().as_bytes())
    }

    /// The XML text of the index.
    pub fn text(&self) -> String {
        let mut s = String::new();
        s.push_str("<?xml version=\"1.0\" ?>\n");
        s.push_str("<!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>\n");
        s.push_str("<Xdmf Version=\"2.0\">\n  <Domain>\n");
        s.push_str(
            "    <Grid Name=\"bodies\" GridType=\"Collection\" CollectionType=\"Temporal\">\n",
        );
        for (k, e) in self.entries.iter().enumerate() {
            let (topology, dataset) = if e.nodes == 3 {
                ("TopologyType=\"Triangle\"", "triangles")
            } else {
                ("TopologyType=\"Polyline\" NodesPerElement=\"2\"", "lines")
            };
            let (m, n, nodes, f) = (e.cells, e.points, e.nodes, &e.file);
            let _ = writeln!(
                s,
                "      <Grid Name=\"bodies{k:06}\" GridType=\"Uniform\">\n        \
                 <Time Value=\"{}\"/>\n        \
                 <Topology {topology} NumberOfElements=\"{m}\">\n          \
                 <DataItem Dimensions=\"{m} {nodes}\" NumberType=\"Int\" Precision=\"8\" \
                 Format=\"HDF\">{f}:/{dataset}</DataItem>\n        </Topology>\n        \
                 <Geometry GeometryType=\"XYZ\">\n          \
                 <DataItem Dimensions=\"{n} 3\" NumberType=\"Float\" Precision=\"8\" \
                 Format=\"HDF\">{f}:/points</DataItem>\n        </Geometry>\n        \
                 <Attribute Name=\"part_id\" AttributeType=\"Scalar\" Center=\"Cell\">\n          \
                 <DataItem Dimensions=\"{m}\" NumberType=\"Int\" Precision=\"4\" \
                 Format=\"HDF\">{f}:/part_id</DataItem>\n        </Attribute>",
                fmt_f64(e.time)
            );
            for v in &self.vectors {
                let _ = writeln!(
                    s,
                    "        <Attribute Name=\"{v}\" AttributeType=\"Vector\" Center=\"Cell\">\n          \
                     <DataItem Dimensions=\"{m} 3\" NumberType=\"Float\" Precision=\"8\" \
                     Format=\"HDF\">{f}:/{v}</DataItem>\n        </Attribute>"
                );
            }
            s.push_str("      </Grid>\n");
        }
        s.push_str("    </Grid>\n  </Domain>\n</Xdmf>\n");
        s
    }
}
