//! HDF5 files (feature `hdf5`): one file per field snapshot and `series.h5` for the time
//! series.
//!
//! A snapshot file `fields_NNNNNN.h5` holds one dataset per field at its root (`/omega`,
//! `/velocity`, `/density`, `/chi`, `/phi`), C order, shape `(nz, ny, nx)` in 3D and
//! `(ny, nx)` in 2D with a trailing axis of 3 for vectors (z = 0 in 2D), see
//! [`crate::io::xdmf::dataset_shape`]; and root attributes `time`, `step`, `origin`, `spacing`
//! (x, y, z) and `dims` (nx, ny, nz). `series.h5` is described at [`write_series`].
//!
//! Both are written to a temporary name next to the target, closed, fsynced and renamed over
//! it, so a killed run leaves only complete files.

use crate::base::grid::Grid;
use crate::io::output::{VtkField, disk_full, temp_path};
use crate::io::xdmf::dataset_shape;
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

fn dataset(group: &hdf5::Group, name: &str, shape: &[usize], v: &[f64]) -> hdf5::Result<()> {
    group
        .new_dataset::<f64>()
        .shape(shape)
        .create(name)?
        .write_raw(v)
}

/// Write one snapshot: `fields` (as for [`crate::io::output::write_vti`]) on `grid` at `time`.
pub fn write_fields(
    path: &Path,
    grid: &Grid,
    time: f64,
    step: u64,
    fields: &[VtkField],
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
        scalar_f64(file, "time", time)?;
        file.new_attr::<u64>().create("step")?.write_scalar(&step)?;
        attr_f64(file, "origin", &grid.origin)?;
        attr_f64(file, "spacing", &[grid.h; 3])?;
        file.new_attr::<u64>()
            .shape([3])
            .create("dims")?
            .write_raw(&grid.n.map(|n| n as u64)[..])?;
        let mut buf: Vec<f64> = Vec::new();
        for f in fields {
            let nc = f.components.len();
            let shape = dataset_shape(grid, nc);
            if nc == 1 {
                dataset(file, f.name, &shape, f.components[0])?;
            } else {
                buf.clear();
                buf.reserve(3 * npts);
                for p in 0..npts {
                    for c in 0..3 {
                        buf.push(f.components.get(c).map_or(0.0, |v| v[p]));
                    }
                }
                dataset(file, f.name, &shape, &buf)?;
            }
        }
        Ok(())
    })
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

/// Write `series.h5`: `/series/<column>` (t, dt, energy, enstrophy, circulation, max_omega)
/// per step; `/bodies/<name>/` per moving body with `t` (n), `center`, `velocity`,
/// `angular_velocity`, `force`, `torque` (n, 3) and `orientation` (n, 4: w, x, y, z), and
/// attributes `id` and `name`; `/contacts/` with `t`, `body_a`, `body_b` (indices into the
/// root attribute `body_names`), `gap` and `normal_force`, one entry per close pair per step.
pub fn write_series(path: &Path, s: &Series) -> io::Result<()> {
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
        for (name, v) in &s.global {
            dataset(&g, name, &[v.len()], v)?;
        }
        let bodies = file.create_group("bodies")?;
        let mut used = Vec::new();
        for b in &s.bodies {
            let gname = group_name(b, &used);
            let bg = bodies.create_group(&gname)?;
            used.push(gname);
            bg.new_attr::<u64>()
                .create("id")?
                .write_scalar(&(b.id as u64))?;
            let name: hdf5::types::VarLenUnicode = b.name.parse().unwrap_or_default();
            bg.new_attr::<hdf5::types::VarLenUnicode>()
                .create("name")?
                .write_scalar(&name)?;
            let n = b.t.len();
            dataset(&bg, "t", &[n], &b.t)?;
            for (k, v) in [
                ("center", &b.center),
                ("velocity", &b.velocity),
                ("angular_velocity", &b.angular_velocity),
                ("force", &b.force),
                ("torque", &b.torque),
            ] {
                dataset(&bg, k, &[n, 3], v)?;
            }
            dataset(&bg, "orientation", &[n, 4], &b.orientation)?;
        }
        if let Some(c) = &s.contacts {
            let cg = file.create_group("contacts")?;
            let m = c.t.len();
            dataset(&cg, "t", &[m], &c.t)?;
            for (k, v) in [("body_a", &c.body_a), ("body_b", &c.body_b)] {
                cg.new_dataset::<u64>()
                    .shape([m])
                    .create(k)?
                    .write_raw(&v[..])?;
            }
            dataset(&cg, "gap", &[m], &c.gap)?;
            dataset(&cg, "normal_force", &[m], &c.normal_force)?;
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
