//! HDF5 files (feature `hdf5`): one file per field snapshot and `series.h5` for the time
//! series.
//!
//! A snapshot file `fields_NNNNNN.h5` holds one dataset per field at its root (`/omega`,
//! `/velocity`, `/density`, `/chi`, `/phi`), C order, shape `(nz, ny, nx)` in 3D and
//! `(ny, nx)` in 2D with a trailing axis of 3 for vectors (z = 0 in 2D), see
//! [`crate::io::xdmf::dataset_shape`]; and root attributes `time`, `step`, `origin`, `spacing`
//! (x, y, z) and `dims` (nx, ny, nz). `series.h5` is described at [`create_series`].
//! With bodies, `bodies_NNNNNN.h5` holds their surfaces ([`write_surfaces`]). On several
//! processes each writes its slab's `fields_NNNNNN_R.h5` with [`write_fields`] and
//! `fields_NNNNNN.h5` holds virtual datasets made of them ([`write_virtual_fields`]).
//!
//! A snapshot file, and `series.h5` when it is created (with no rows), are written to a
//! temporary name next to the target, closed, fsynced and renamed over it, so a killed run
//! leaves only complete files. Then rows are appended to `series.h5` in place
//! ([`append_series`]): its datasets are chunked and resizable, so the run keeps only the rows
//! since the last append in memory and writes each row once.

use crate::base::grid::Grid;
use crate::io::output::{VtkField, disk_full, temp_path};
use crate::io::xdmf::dataset_shape;
use crate::scene::format::Precision;
use std::io;
use std::path::Path;

/// An I/O error from an HDF5 error; "disk full" is recognised from the library's error stack.
fn h5_err(path: &Path, e: hdf5::Error) -> io::Error {
    let msg = e.to_string().replace('\n', " ");
    let lower = msg.to_lowercase();
    if lower.contains("no space left") || lower.contains("errno = 28") {
        return disk_full(
            path,
            io::Error::new(io::ErrorKind::StorageFull, "no space left on device"),
        );
    }
    io::Error::other(format!("HDF5 error writing {}: {msg}", path.display()))
}

/// Write an HDF5 file atomically: `f` fills a new file at a temporary name, which is then
/// closed, fsynced and renamed over `path`. On failure `path` is untouched.
pub fn atomic_h5(path: &Path, f: impl FnOnce(&hdf5::File) -> hdf5::Result<()>) -> io::Result<()> {
    let tmp = temp_path(path)?;
    let result = (|| {
        let file = hdf5::File::create(&tmp).map_err(|e| h5_err(path, e))?;
        f(&file).map_err(|e| h5_err(path, e))?;
        file.close().map_err(|e| h5_err(path, e))?;
        std::fs::File::open(&tmp)?.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    match result {
        Ok(()) => {
            if let Some(d) = path.parent().and_then(|d| std::fs::File::open(d).ok()) {
                let _ = d.sync_all();
            }
            Ok(())
        }
        Err(e) => {
            let _ = std::fs::remove_file(&tmp);
            Err(disk_full(path, e))
        }
    }
}

fn attr_f64(loc: &hdf5::Location, name: &str, v: &[f64]) -> hdf5::Result<()> {
    loc.new_attr::<f64>()
        .shape([v.len()])
        .create(name)?
        .write_raw(v)
}

fn scalar_f64(loc: &hdf5::Location, name: &str, v: f64) -> hdf5::Result<()> {
    loc.new_attr::<f64>().create(name)?.write_scalar(&v)
}

/// Bytes per chunk of a field dataset, about.
const CHUNK_BYTES: usize = 1 << 20;

/// The chunk shape of a field dataset of `shape` with `size`-byte values: whole planes of the
/// slowest axis, as many as fit in about [`CHUNK_BYTES`] (at least one).
fn chunk_shape(shape: &[usize], size: usize) -> Vec<usize> {
    let plane: usize = shape[1..].iter().product::<usize>().max(1) * size;
    let mut c = shape.to_vec();
    c[0] = (CHUNK_BYTES / plane).clamp(1, shape[0].max(1));
    c
}

/// A field dataset `name` of `shape` holding `v`: chunked, shuffled and deflate-compressed
/// (when the library has the deflate filter), as `T` (`f32` or `f64`).
fn field_dataset<T: hdf5::H5Type>(
    group: &hdf5::Group,
    name: &str,
    shape: &[usize],
    v: &[T],
) -> hdf5::Result<()> {
    let b = group.new_dataset::<T>().shape(shape);
    let b = if hdf5::filters::deflate_available() && shape.iter().all(|&n| n > 0) {
        b.chunk(chunk_shape(shape, std::mem::size_of::<T>()))
            .shuffle()
            .deflate(4)
    } else {
        b
    };
    b.create(name)?.write_raw(v)
}

/// [`field_dataset`] of `v` in `precision`.
fn dataset(
    group: &hdf5::Group,
    name: &str,
    shape: &[usize],
    v: &[f64],
    precision: Precision,
) -> hdf5::Result<()> {
    match precision {
        Precision::Double => field_dataset(group, name, shape, v),
        Precision::Single => {
            let s: Vec<f32> = v.iter().map(|&x| x as f32).collect();
            field_dataset(group, name, shape, &s)
        }
    }
}

/// Write one snapshot: `fields` (as for [`crate::io::output::write_vti`]) on `grid` at `time`,
/// in `precision`, each dataset chunked and compressed.
pub fn write_fields(
    path: &Path,
    grid: &Grid,
    time: f64,
    step: u64,
    fields: &[VtkField],
    precision: Precision,
) -> io::Result<()> {
    let npts = grid.len();
    for f in fields {
        if !(1..=3).contains(&f.components.len()) || f.components.iter().any(|c| c.len() != npts) {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!("field {:?} does not match the grid", f.name),
            ));
        }
    }
    atomic_h5(path, |file| {
        root_attributes(file, grid, time, step)?;
        let mut buf: Vec<f64> = Vec::new();
        for f in fields {
            let nc = f.components.len();
            let shape = dataset_shape(grid, nc);
            if nc == 1 {
                dataset(file, f.name, &shape, f.components[0], precision)?;
            } else {
                buf.clear();
                buf.reserve(3 * npts);
                for p in 0..npts {
                    for c in 0..3 {
                        buf.push(f.components.get(c).map_or(0.0, |v| v[p]));
                    }
                }
                dataset(file, f.name, &shape, &buf, precision)?;
            }
        }
        Ok(())
    })
}

/// One process's piece of a snapshot split over processes: its file (relative to the
/// directory of the snapshot's index file) and the whole grid's z-planes it holds.
#[derive(Clone, Debug, PartialEq)]
pub struct Piece {
    /// The piece's file, written by [`write_fields`] on its slab.
    pub file: String,
    /// The z-planes of the whole grid it holds, in order.
    pub planes: std::ops::Range<usize>,
}

/// Write the snapshot file of a run split over processes: the root attributes of
/// [`write_fields`] for the whole grid `whole`, and for each of `fields` (name and 1 or 3
/// components) a virtual dataset (HDF5 1.10's VDS) of the whole grid's shape whose planes of
/// each of `pieces` are the same dataset of that piece's file. A reader sees the one-process
/// file's datasets (names, shapes, types, values); the library opens the pieces as it reads,
/// found by their names relative to this file's directory, so the run directory may move.
/// Atomic, as [`write_fields`]; a missing piece reads as zeros.
pub fn write_virtual_fields(
    path: &Path,
    whole: &Grid,
    time: f64,
    step: u64,
    fields: &[(&str, usize)],
    precision: Precision,
    pieces: &[Piece],
) -> io::Result<()> {
    atomic_h5(path, |file| {
        root_attributes(file, whole, time, step)?;
        for &(name, components) in fields {
            let shape = dataset_shape(whole, components);
            match precision {
                Precision::Double => virtual_dataset::<f64>(file, name, &shape, pieces)?,
                Precision::Single => virtual_dataset::<f32>(file, name, &shape, pieces)?,
            }
        }
        Ok(())
    })
}

/// A virtual dataset `name` of `shape` (slowest axis the z-planes) in `file`, mapping each
/// piece's planes to its file's dataset `name`, whole.
fn virtual_dataset<T: hdf5::H5Type>(
    file: &hdf5::File,
    name: &str,
    shape: &[usize],
    pieces: &[Piece],
) -> hdf5::Result<()> {
    use hdf5::{Hyperslab, Selection, SliceOrIndex};
    let mut b = file.new_dataset::<T>().shape(shape);
    for p in pieces {
        let mut src = shape.to_vec();
        src[0] = p.planes.len();
        let mut slab: Vec<SliceOrIndex> = shape.iter().map(|&n| (0..n).into()).collect();
        slab[0] = p.planes.clone().into();
        b = b.virtual_map(
            &p.file,
            format!("/{name}"),
            src,
            Selection::All,
            shape.to_vec(),
            Selection::Hyperslab(Hyperslab::from(slab)),
        );
    }
    b.create(name).map(drop)
}

/// The root attributes of a snapshot file on `grid`: `time`, `step`, `origin`, `spacing`,
/// `dims`.
fn root_attributes(file: &hdf5::File, grid: &Grid, time: f64, step: u64) -> hdf5::Result<()> {
    scalar_f64(file, "time", time)?;
    file.new_attr::<u64>().create("step")?.write_scalar(&step)?;
    attr_f64(file, "origin", &grid.origin)?;
    attr_f64(file, "spacing", &[grid.h; 3])?;
    file.new_attr::<u64>()
        .shape([3])
        .create("dims")?
        .write_raw(&grid.n.map(|n| n as u64)[..])
}

/// The time series of one body, one entry per recorded step.
#[derive(Clone, Debug, Default)]
pub struct BodySeries {
    /// Name in the scene.
    pub name: String,
    /// Index in the scene's body list.
    pub id: usize,
    /// Times.
    pub t: Vec<f64>,
    /// Centre (x, y, z) per time, flattened.
    pub center: Vec<f64>,
    /// Velocity per time, flattened.
    pub velocity: Vec<f64>,
    /// Angular velocity per time, flattened.
    pub angular_velocity: Vec<f64>,
    /// Orientation quaternion (w, x, y, z) per time, flattened.
    pub orientation: Vec<f64>,
    /// Hydrodynamic force per time, flattened.
    pub force: Vec<f64>,
    /// Hydrodynamic torque per time, flattened.
    pub torque: Vec<f64>,
}

/// Contact records: one entry per close pair per step.
#[derive(Clone, Debug, Default)]
pub struct ContactSeries {
    /// Times.
    pub t: Vec<f64>,
    /// Index (in the scene's body list) of the first body of the pair.
    pub body_a: Vec<u64>,
    /// Index of the second body.
    pub body_b: Vec<u64>,
    /// Gap between the bodies.
    pub gap: Vec<f64>,
    /// Normal contact force.
    pub normal_force: Vec<f64>,
}

/// Everything `series.h5` holds.
#[derive(Clone, Debug, Default)]
pub struct Series {
    /// Global columns of `series.csv`, by name, one value per step.
    pub global: Vec<(&'static str, Vec<f64>)>,
    /// Moving bodies.
    pub bodies: Vec<BodySeries>,
    /// Contacts (scenes with dynamic bodies).
    pub contacts: Option<ContactSeries>,
    /// Names of all the scene's bodies (what the contact indices refer to).
    pub body_names: Vec<String>,
}

/// A group name for a body: its name with `/` replaced, made unique with its index.
fn group_name(b: &BodySeries, used: &[String]) -> String {
    let mut n = b.name.replace(['/', '.'], "_");
    if n.is_empty() || used.contains(&n) {
        n = format!("{n}_{}", b.id);
    }
    n
}

/// The group names of `s`'s bodies, in order.
fn group_names(s: &Series) -> Vec<String> {
    let mut used = Vec::new();
    for b in &s.bodies {
        let n = group_name(b, &used);
        used.push(n);
    }
    used
}

impl Series {
    /// Drop the values (keep the names): what is left after they are appended to the file.
    pub fn clear_values(&mut self) {
        for (_, v) in &mut self.global {
            v.clear();
        }
        for b in &mut self.bodies {
            for v in [
                &mut b.t,
                &mut b.center,
                &mut b.velocity,
                &mut b.angular_velocity,
                &mut b.orientation,
                &mut b.force,
                &mut b.torque,
            ] {
                v.clear();
            }
        }
        if let Some(c) = self.contacts.as_mut() {
            *c = ContactSeries::default();
        }
    }
}

/// Rows of a chunk of the resizable datasets of `series.h5`.
const CHUNK_ROWS: usize = 1024;

/// A resizable dataset `name` in `g` with no rows yet, `cols` values per row (`cols` = 1: a
/// one-dimensional dataset).
fn growing<T: hdf5::H5Type>(g: &hdf5::Group, name: &str, cols: usize) -> hdf5::Result<()> {
    let b = g.new_dataset::<T>();
    if cols == 1 {
        b.shape([0..]).chunk([CHUNK_ROWS]).create(name)?;
    } else {
        b.shape([(0, None), (cols, Some(cols))])
            .chunk([CHUNK_ROWS, cols])
            .create(name)?;
    }
    Ok(())
}

/// Append the rows `v` (flattened, as many values per row as the dataset has columns) to the
/// resizable dataset `ds`.
fn append_rows<T: hdf5::H5Type>(ds: &hdf5::Dataset, v: &[T]) -> hdf5::Result<()> {
    let mut shape = ds.shape();
    let cols: usize = shape[1..].iter().product();
    let (old, n) = (shape[0], v.len() / cols.max(1));
    if n == 0 {
        return Ok(());
    }
    shape[0] = old + n;
    ds.resize(shape.clone())?;
    if shape.len() == 1 {
        ds.write_slice(v, old..old + n)
    } else {
        let view = ndarray::ArrayView2::from_shape((n, cols), v)
            .map_err(|e| hdf5::Error::Internal(e.to_string()))?;
        ds.write_slice(view, ndarray::s![old..old + n, ..])
    }
}

/// Create `series.h5` for the layout of `s` (its names; its values are not written, see
/// [`append_series`]): `/series/<column>` (t, dt, energy, enstrophy, circulation, max_omega)
/// per step; `/bodies/<name>/` per moving body with `t` (n), `center`, `velocity`,
/// `angular_velocity`, `force`, `torque` (n, 3) and `orientation` (n, 4: w, x, y, z), and
/// attributes `id` and `name`; `/contacts/` with `t`, `body_a`, `body_b` (indices into the
/// root attribute `body_names`), `gap` and `normal_force`, one entry per close pair per step.
/// The datasets are chunked and grow along their first axis as rows are appended. Written
/// atomically: the file appears complete, with no rows, or not at all.
pub fn create_series(path: &Path, s: &Series) -> io::Result<()> {
    atomic_h5(path, |file| {
        let names: Vec<hdf5::types::VarLenUnicode> = s
            .body_names
            .iter()
            .map(|n| n.parse().unwrap_or_default())
            .collect();
        file.new_attr::<hdf5::types::VarLenUnicode>()
            .shape([names.len()])
            .create("body_names")?
            .write_raw(&names[..])?;
        let g = file.create_group("series")?;
        for (name, _) in &s.global {
            growing::<f64>(&g, name, 1)?;
        }
        let bodies = file.create_group("bodies")?;
        for (b, gname) in s.bodies.iter().zip(group_names(s)) {
            let bg = bodies.create_group(&gname)?;
            bg.new_attr::<u64>()
                .create("id")?
                .write_scalar(&(b.id as u64))?;
            let name: hdf5::types::VarLenUnicode = b.name.parse().unwrap_or_default();
            bg.new_attr::<hdf5::types::VarLenUnicode>()
                .create("name")?
                .write_scalar(&name)?;
            growing::<f64>(&bg, "t", 1)?;
            for k in ["center", "velocity", "angular_velocity", "force", "torque"] {
                growing::<f64>(&bg, k, 3)?;
            }
            growing::<f64>(&bg, "orientation", 4)?;
        }
        if s.contacts.is_some() {
            let cg = file.create_group("contacts")?;
            growing::<f64>(&cg, "t", 1)?;
            growing::<u64>(&cg, "body_a", 1)?;
            growing::<u64>(&cg, "body_b", 1)?;
            growing::<f64>(&cg, "gap", 1)?;
            growing::<f64>(&cg, "normal_force", 1)?;
        }
        Ok(())
    })
}

/// Open `series.h5` to change it, run `f`, close and fsync it.
fn modify_series(path: &Path, f: impl FnOnce(&hdf5::File) -> hdf5::Result<()>) -> io::Result<()> {
    let result = (|| {
        let file = hdf5::File::open_rw(path).map_err(|e| h5_err(path, e))?;
        f(&file).map_err(|e| h5_err(path, e))?;
        file.close().map_err(|e| h5_err(path, e))?;
        std::fs::File::open(path)?.sync_all()
    })();
    result.map_err(|e| disk_full(path, e))
}

/// Append the values of `s` (steps and contacts since the last call) to the `series.h5` at
/// `path`, made by [`create_series`] for the same layout: the writing is proportional to the
/// new rows, not to the whole series.
pub fn append_series(path: &Path, s: &Series) -> io::Result<()> {
    modify_series(path, |file| {
        for (name, v) in &s.global {
            append_rows(&file.dataset(&format!("series/{name}"))?, v)?;
        }
        for (b, gname) in s.bodies.iter().zip(group_names(s)) {
            let g = file.group(&format!("bodies/{gname}"))?;
            append_rows(&g.dataset("t")?, &b.t)?;
            for (k, v) in [
                ("center", &b.center),
                ("velocity", &b.velocity),
                ("angular_velocity", &b.angular_velocity),
                ("orientation", &b.orientation),
                ("force", &b.force),
                ("torque", &b.torque),
            ] {
                append_rows(&g.dataset(k)?, v)?;
            }
        }
        if let Some(c) = &s.contacts {
            let g = file.group("contacts")?;
            append_rows(&g.dataset("t")?, &c.t)?;
            append_rows(&g.dataset("body_a")?, &c.body_a)?;
            append_rows(&g.dataset("body_b")?, &c.body_b)?;
            append_rows(&g.dataset("gap")?, &c.gap)?;
            append_rows(&g.dataset("normal_force")?, &c.normal_force)?;
        }
        Ok(())
    })
}

/// Where a restart cuts `series.h5` back to: the rows of the steps up to its checkpoint and
/// of the contacts up to its time.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SeriesCut {
    /// Steps kept (the initial state and every step up to the checkpoint).
    pub steps: usize,
    /// Contact records kept.
    pub contacts: usize,
}

/// Check that the `series.h5` at `path`, made for the layout of `s`, holds the first `steps`
/// steps (the last at the checkpoint's time `t`) and return where to cut it
/// ([`cut_series`]). Reads only; `Ok(Err(why))` says what the file lacks.
pub fn check_series(
    path: &Path,
    s: &Series,
    steps: usize,
    t: f64,
) -> io::Result<Result<SeriesCut, String>> {
    (|| -> hdf5::Result<Result<SeriesCut, String>> {
        let file = hdf5::File::open(path)?;
        let short = |ds: &hdf5::Dataset, need: usize, what: &str| {
            let have = ds.shape().first().copied().unwrap_or(0);
            (have < need).then(|| {
                format!("has {have} rows of {what}, fewer than the {need} up to the checkpoint")
            })
        };
        for (name, _) in &s.global {
            let what = format!("/series/{name}");
            if let Some(e) = short(&file.dataset(&what)?, steps, &what) {
                return Ok(Err(e));
            }
        }
        for gname in group_names(s) {
            let g = file.group(&format!("bodies/{gname}"))?;
            for k in [
                "t",
                "center",
                "velocity",
                "angular_velocity",
                "orientation",
                "force",
                "torque",
            ] {
                let what = format!("/bodies/{gname}/{k}");
                if let Some(e) = short(&g.dataset(k)?, steps, &what) {
                    return Ok(Err(e));
                }
            }
            let last = g
                .dataset("t")?
                .read_slice_1d::<f64, _>(steps.saturating_sub(1)..steps)?;
            if last.first() != Some(&t) {
                return Ok(Err(format!(
                    "has no entry of /bodies/{gname} at the checkpoint's time t = {t}"
                )));
            }
        }
        let mut contacts = 0;
        if s.contacts.is_some() {
            let g = file.group("contacts")?;
            let ct: Vec<f64> = g.dataset("t")?.read_raw()?;
            contacts = ct.partition_point(|&x| x <= t);
            for k in ["body_a", "body_b", "gap", "normal_force"] {
                let what = format!("/contacts/{k}");
                if let Some(e) = short(&g.dataset(k)?, contacts, &what) {
                    return Ok(Err(e));
                }
            }
        }
        Ok(Ok(SeriesCut { steps, contacts }))
    })()
    .map_err(|e| read_err(path, e))
}

/// Cut the `series.h5` at `path`, made for the layout of `s`, back to `cut` rows (see
/// [`check_series`]).
pub fn cut_series(path: &Path, s: &Series, cut: SeriesCut) -> io::Result<()> {
    let to = |ds: hdf5::Dataset, rows: usize| {
        let mut shape = ds.shape();
        shape[0] = rows;
        ds.resize(shape)
    };
    modify_series(path, |file| {
        for (name, _) in &s.global {
            to(file.dataset(&format!("series/{name}"))?, cut.steps)?;
        }
        for gname in group_names(s) {
            let g = file.group(&format!("bodies/{gname}"))?;
            for ds in g.datasets()? {
                to(ds, cut.steps)?;
            }
        }
        if s.contacts.is_some() {
            for ds in file.group("contacts")?.datasets()? {
                to(ds, cut.contacts)?;
            }
        }
        Ok(())
    })
}

/// An I/O error for an HDF5 file that cannot be read.
fn read_err(path: &Path, e: hdf5::Error) -> io::Error {
    io::Error::other(format!(
        "cannot read {}: {}",
        path.display(),
        e.to_string().replace('\n', " ")
    ))
}

/// The `time` attribute of the snapshot file at `path`.
pub fn read_time(path: &Path) -> io::Result<f64> {
    (|| hdf5::File::open(path)?.attr("time")?.read_scalar::<f64>())().map_err(|e| read_err(path, e))
}

/// Read the data of the `series.h5` at `path` into `s`, a [`Series`] made for the run's scene
/// (its names, ids and body names set; it is what the file was written from): the global
/// columns, each moving body's series (found by its `id` attribute; a body the file lacks is
/// left empty) and the contacts. Values come back exactly as written.
pub fn read_series(path: &Path, s: &mut Series) -> io::Result<()> {
    (|| -> hdf5::Result<()> {
        let file = hdf5::File::open(path)?;
        for (name, v) in &mut s.global {
            *v = file.dataset(&format!("series/{name}"))?.read_raw()?;
        }
        if !s.bodies.is_empty() {
            for g in file.group("bodies")?.groups()? {
                let id: u64 = g.attr("id")?.read_scalar()?;
                let Some(b) = s.bodies.iter_mut().find(|b| b.id as u64 == id) else {
                    continue;
                };
                b.t = g.dataset("t")?.read_raw()?;
                for (k, v) in [
                    ("center", &mut b.center),
                    ("velocity", &mut b.velocity),
                    ("angular_velocity", &mut b.angular_velocity),
                    ("orientation", &mut b.orientation),
                    ("force", &mut b.force),
                    ("torque", &mut b.torque),
                ] {
                    *v = g.dataset(k)?.read_raw()?;
                }
            }
        }
        if let Some(c) = s.contacts.as_mut() {
            let g = file.group("contacts")?;
            c.t = g.dataset("t")?.read_raw()?;
            c.body_a = g.dataset("body_a")?.read_raw()?;
            c.body_b = g.dataset("body_b")?.read_raw()?;
            c.gap = g.dataset("gap")?.read_raw()?;
            c.normal_force = g.dataset("normal_force")?.read_raw()?;
        }
        Ok(())
    })()
    .map_err(|e| read_err(path, e))
}

/// Write one body-surface snapshot `g` at `time` (step `step`) to `path`, atomically: root
/// datasets `points` (n, 3) float64 in world coordinates, `triangles` (m, 3) or, in 2D,
/// `lines` (m, 2) int64 indices into `points`, and per cell `part_id` (m) int32 and each of
/// the vectors (`velocity`, ...) (m, 3) float64; root attributes `time`, `step` and
/// `part_names` (what `part_id` indexes).
pub fn write_surfaces(
    path: &Path,
    time: f64,
    step: u64,
    g: &crate::io::surfaces::SurfaceGeometry,
) -> io::Result<()> {
    atomic_h5(path, |file| {
        scalar_f64(file, "time", time)?;
        file.new_attr::<u64>().create("step")?.write_scalar(&step)?;
        let names: Vec<hdf5::types::VarLenUnicode> = g
            .part_names
            .iter()
            .map(|n| n.parse().unwrap_or_default())
            .collect();
        file.new_attr::<hdf5::types::VarLenUnicode>()
            .shape([names.len()])
            .create("part_names")?
            .write_raw(&names[..])?;
        let pts: Vec<f64> = g.points.iter().flat_map(|p| p.to_array()).collect();
        file.new_dataset::<f64>()
            .shape([g.points.len(), 3])
            .create("points")?
            .write_raw(&pts)?;
        let (name, nodes, conn): (&str, usize, Vec<i64>) = if g.triangles.is_empty() {
            let c = g.lines.iter().flatten().map(|&i| i as i64).collect();
            ("lines", 2, c)
        } else {
            let c = g.triangles.iter().flatten().map(|&i| i as i64).collect();
            ("triangles", 3, c)
        };
        file.new_dataset::<i64>()
            .shape([conn.len() / nodes, nodes])
            .create(name)?
            .write_raw(&conn)?;
        let ids: Vec<i32> = g.cell_part.iter().map(|&i| i as i32).collect();
        file.new_dataset::<i32>()
            .shape([ids.len()])
            .create("part_id")?
            .write_raw(&ids)?;
        for (vn, vs) in g.vector_names.iter().zip(&g.cell_vectors) {
            let v: Vec<f64> = vs.iter().flat_map(|p| p.to_array()).collect();
            file.new_dataset::<f64>()
                .shape([vs.len(), 3])
                .create(vn.as_str())?
                .write_raw(&v)?;
        }
        Ok(())
    })
}

/// What the body-surface index needs of a surface snapshot written by [`write_surfaces`]:
/// its time, points, cells and nodes per cell (3 triangles, 2 lines).
pub fn read_surface_layout(path: &Path) -> io::Result<(f64, usize, usize, usize)> {
    (|| -> hdf5::Result<(f64, usize, usize, usize)> {
        let file = hdf5::File::open(path)?;
        let time = file.attr("time")?.read_scalar::<f64>()?;
        let points = file.dataset("points")?.shape()[0];
        let (cells, nodes) = match file.dataset("triangles") {
            Ok(d) => (d.shape()[0], 3),
            Err(_) => (file.dataset("lines")?.shape()[0], 2),
        };
        Ok((time, points, cells, nodes))
    })()
    .map_err(|e| read_err(path, e))
}
