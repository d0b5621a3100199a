//! Field snapshots of a run in the scene's formats (`output.formats`): VTK (`fields_NNNNNN.vti`
//! indexed by `fields.pvd`) and, in builds with the `hdf5` feature, HDF5 (`fields_NNNNNN.h5`
//! indexed by `fields.xmf`, plus `series.h5`, the time series of the run, the bodies and the
//! contacts, appended to at every snapshot, at every checkpoint and at the end).
//!
//! With bodies, every snapshot also writes the bodies' surfaces in their current pose
//! (`bodies_NNNNNN.vtp` indexed by `bodies.pvd`, see [`crate::io::surfaces`]), vacuum runs
//! included, and with HDF5 output also `bodies_NNNNNN.h5` indexed by `bodies.xmf` (the same
//! surfaces, computed once, [`SurfaceGeometry`]); a run whose scene asks for no field
//! (`fields: []`) writes no `.vti` (they would be empty) and no `fields.pvd`.
//!
//! With a free surface (the world holds a [`LiquidLevelSet`]), every snapshot's fields also
//! hold `free_surface` (φ_w), the surfaces series also holds its zero level as a part named
//! `free_surface` (world coordinates, identity pose, zero vectors; see
//! [`crate::io::isosurface`]; cut off inside static walls, where φ_w is the fluid's continued
//! and the periodic box's seam makes a second level), and, as in a run with a dynamic body, every snapshot also
//! writes a slice image `slices/slice_NNNNNN.png` ([`crate::io::slices`]).
//!
//! On several processes the split driver writes the VTK snapshots as pieces ([`write_pieces`])
//! and the HDF5 ones as pieces under a file of virtual datasets ([`SplitHdf5`]).
//!
//! A restarted run picks them up with [`Snapshots::resume`] (what the checkpoint's
//! [`RunProgress`] says, and for HDF5 the files kept, read back) and [`Snapshots::cut_back`]
//! (the snapshots written after the checkpoint removed, the indexes and `series.h5` rewritten).

use crate::bodies::free_surface::LiquidLevelSet;
use crate::bodies::{Body, BodySurface, Hydro, RigidState};
use crate::io::checkpoint::RunProgress;
use crate::io::output::{PvdSeries, VtkField, write_vti_compressed};
use crate::io::surfaces::{SurfaceGeometry, SurfacePart, SurfaceSeries};
use crate::scene::{FieldName, OutputFormat};
use crate::schedule::OutputFields;
use crate::sim::engine::Simulation;
use anyhow::Context;
use std::path::{Path, PathBuf};

/// The snapshot writers of one run.
pub struct Snapshots {
    dir: PathBuf,
    pvd: Option<PvdSeries>,
    /// The bodies' surfaces and the free surface's zero level (a run with either).
    surfaces: Option<SurfaceSeries>,
    /// Whether every snapshot writes a slice image (a free surface or a dynamic body).
    slices: bool,
    #[cfg(feature = "hdf5")]
    hdf5: Option<Hdf5Outputs>,
    count: usize,
}

/// The vectors each body's surface cells carry.
const SURFACE_VECTORS: [&str; 3] = ["velocity", "angular_velocity", "force"];

/// Whether `sim`'s snapshots hold VTK field files: the scene asks for VTK and for at least one
/// field that exists in this run.
fn vtk_fields(sim: &Simulation) -> bool {
    sim.scene().output.has_format(OutputFormat::Vtk) && with_fields(sim, |f| !f.is_empty())
}

/// Whether `sim`'s snapshots hold surfaces: it has bodies or a free surface.
fn has_surfaces(sim: &Simulation) -> bool {
    !sim.scene().bodies.is_empty() || sim.world.contains_resource::<LiquidLevelSet>()
}

/// The surface series of `sim`'s run in `dir` (`bodies.pvd`), if it has bodies or a free
/// surface.
fn surface_series(dir: &Path, sim: &Simulation) -> Option<SurfaceSeries> {
    has_surfaces(sim).then(|| SurfaceSeries::new(dir, "bodies", &SURFACE_VECTORS))
}

/// The name of the free surface's part in the surfaces series.
pub const FREE_SURFACE_PART: &str = "free_surface";

/// The time a body-surface snapshot `file` holds (its `TimeValue` field data).
fn vtp_time(file: &Path) -> Result<f64, String> {
    let text = std::fs::read_to_string(file)
        .map_err(|e| format!("cannot read {} ({e})", file.display()))?;
    text.split_once("Name=\"TimeValue\"")
        .and_then(|(_, rest)| rest.split_once('>'))
        .and_then(|(_, rest)| rest.split_once('<'))
        .and_then(|(v, _)| v.trim().parse::<f64>().ok())
        .ok_or_else(|| format!("{} holds no TimeValue", file.display()))
}

impl Snapshots {
    /// The writers for `sim`'s scene, writing into `dir` (nothing is written yet).
    pub fn new(dir: &Path, sim: &Simulation) -> Self {
        Snapshots {
            dir: dir.to_path_buf(),
            pvd: vtk_fields(sim).then(|| PvdSeries::new(dir.join("fields.pvd"))),
            surfaces: surface_series(dir, sim),
            slices: crate::io::slices::wants_slices(sim),
            #[cfg(feature = "hdf5")]
            hdf5: sim
                .scene()
                .output
                .has_format(OutputFormat::Hdf5)
                .then(|| Hdf5Outputs::new(dir, sim, has_surfaces(sim))),
            count: 0,
        }
    }

    /// The writers of a restarted run in `dir`, continuing after the snapshots its checkpoint
    /// (`progress`) counts; `sim` is the restored simulation. The HDF5 side is read back from
    /// the files kept: each snapshot's time for `fields.xmf`, and the lengths of `series.h5`
    /// checked against the checkpoint's steps (it is appended to at every checkpoint, so it
    /// holds them all). Nothing
    /// is written (see [`cut_back`](Snapshots::cut_back)); an error says why the run directory
    /// does not match the checkpoint.
    pub fn resume(dir: &Path, sim: &Simulation, progress: &RunProgress) -> Result<Self, String> {
        let count = progress.snapshots as usize;
        let pvd = if vtk_fields(sim) {
            if progress.pvd.len() != count {
                return Err(format!(
                    "it lists {} VTK snapshots in fields.pvd and counts {count} snapshots",
                    progress.pvd.len()
                ));
            }
            Some(PvdSeries::with_entries(
                dir.join("fields.pvd"),
                progress.pvd.clone(),
            ))
        } else {
            None
        };
        let surfaces = resume_surfaces(dir, sim, count)?;
        #[cfg(feature = "hdf5")]
        let hdf5 = if sim.scene().output.has_format(OutputFormat::Hdf5) {
            Some(Hdf5Outputs::resume(dir, sim, count, has_surfaces(sim))?)
        } else {
            None
        };
        Ok(Snapshots {
            dir: dir.to_path_buf(),
            pvd,
            surfaces,
            slices: crate::io::slices::wants_slices(sim),
            #[cfg(feature = "hdf5")]
            hdf5,
            count,
        })
    }

    /// Make the run directory match a resumed [`Snapshots`]: remove the snapshot files
    /// numbered from [`count`](Snapshots::count) on (written after the checkpoint, slice
    /// images included), rewrite
    /// `fields.pvd`, `bodies.pvd`, `fields.xmf` and `bodies.xmf` with the snapshots kept, and cut
    /// `series.h5` back to the steps up to the checkpoint.
    pub fn cut_back(&mut self) -> anyhow::Result<()> {
        for k in self.count.. {
            let mut found = false;
            for name in [
                "fields_{k}.vti",
                "fields_{k}.h5",
                "bodies_{k}.vtp",
                "bodies_{k}.h5",
                "slices/slice_{k}.png",
            ] {
                let f = self.dir.join(name.replace("{k}", &format!("{k:06}")));
                if f.exists() {
                    std::fs::remove_file(&f)
                        .with_context(|| format!("cannot remove {}", f.display()))?;
                    found = true;
                }
            }
            if !found {
                break;
            }
        }
        if let Some(p) = &self.pvd {
            p.write().context("cannot write fields.pvd")?;
        }
        if let Some(s) = &self.surfaces {
            s.pvd().write().context("cannot write bodies.pvd")?;
        }
        #[cfg(feature = "hdf5")]
        if let Some(h) = self.hdf5.as_mut() {
            h.xmf.write().context("cannot write fields.xmf")?;
            if let Some(b) = &h.bodies {
                b.write().context("cannot write bodies.xmf")?;
            }
            h.cut_back(&self.dir)?;
        }
        Ok(())
    }

    /// Snapshots written so far.
    pub fn count(&self) -> usize {
        self.count
    }

    /// `(time, file)` of the VTK snapshots listed in `fields.pvd` (none without VTK output).
    pub fn pvd_entries(&self) -> &[(f64, String)] {
        self.pvd.as_ref().map_or(&[], |p| p.entries())
    }

    /// `(time, file)` of the body-surface snapshots listed in `bodies.pvd` (none without
    /// bodies).
    pub fn surface_entries(&self) -> &[(f64, String)] {
        self.surfaces.as_ref().map_or(&[], |s| s.pvd().entries())
    }

    /// The index file a viewer opens: `fields.pvd`, else with HDF5 output `fields.xmf`, else
    /// (a run writing no field) `bodies.pvd`.
    pub fn index_file(&self) -> PathBuf {
        match (&self.pvd, &self.surfaces) {
            (Some(p), _) => p.path().to_path_buf(),
            (None, Some(s)) if !self.has_hdf5() => s.pvd().path().to_path_buf(),
            _ => self.dir.join("fields.xmf"),
        }
    }

    fn has_hdf5(&self) -> bool {
        #[cfg(feature = "hdf5")]
        return self.hdf5.is_some();
        #[cfg(not(feature = "hdf5"))]
        false
    }

    /// Record the state after a step for `series.h5` (a no-op without HDF5 output).
    pub fn record(&mut self, sim: &mut Simulation) {
        #[cfg(feature = "hdf5")]
        if let Some(h) = self.hdf5.as_mut() {
            h.record(sim);
        }
        #[cfg(not(feature = "hdf5"))]
        let _ = sim;
    }

    /// Write a snapshot of the current state in every format, then the indexes; returns the
    /// files written.
    pub fn write(&mut self, sim: &Simulation) -> anyhow::Result<Vec<String>> {
        with_fields(sim, |vtk| self.write_fields(sim, vtk))
    }

    fn write_fields(&mut self, sim: &Simulation, vtk: &[VtkField]) -> anyhow::Result<Vec<String>> {
        let mut written = Vec::new();
        if let Some(pvd) = self.pvd.as_mut() {
            let file = format!("fields_{:06}.vti", self.count);
            let precision = sim.scene().output.precision;
            write_vti_compressed(
                &self.dir.join(&file),
                sim.grid(),
                sim.time(),
                vtk,
                precision,
            )
            .with_context(|| format!("cannot write {file}"))?;
            pvd.push(sim.time(), &file)
                .context("cannot write fields.pvd")?;
            written.push(file);
        }
        let mut surfaces = None;
        if let Some(series) = self.surfaces.as_mut() {
            let (file, g) = write_surfaces(series, self.count, sim, None)?;
            written.push(file);
            surfaces = Some(g);
        }
        if self.slices {
            written.push(crate::io::slices::write_slice(&self.dir, self.count, sim)?);
        }
        #[cfg(feature = "hdf5")]
        if let Some(h) = self.hdf5.as_mut() {
            written.extend(h.snapshot(&self.dir, self.count, sim, vtk, surfaces.as_ref())?);
        }
        #[cfg(not(feature = "hdf5"))]
        let _ = surfaces;
        self.count += 1;
        Ok(written)
    }

    /// Write what is kept in memory (the rows of `series.h5` since it was last appended to):
    /// at a checkpoint and at the end.
    pub fn finish(&mut self) -> anyhow::Result<()> {
        #[cfg(feature = "hdf5")]
        if let Some(h) = self.hdf5.as_mut() {
            h.write_series(&self.dir)?;
        }
        Ok(())
    }
}

/// The surfaces series of `sim`'s run in `dir` at a checkpoint after `count` snapshots (none
/// without bodies or free surface): the body surfaces kept, each snapshot's time read back
/// from its file. Nothing is written; an error says why the run directory does not match.
pub fn resume_surfaces(
    dir: &Path,
    sim: &Simulation,
    count: usize,
) -> Result<Option<SurfaceSeries>, String> {
    let Some(series) = surface_series(dir, sim) else {
        return Ok(None);
    };
    let mut entries = Vec::with_capacity(count);
    for k in 0..count {
        let file = format!("bodies_{k:06}.vtp");
        let time = vtp_time(&dir.join(&file))
            .map_err(|e| format!("{e}: the run directory does not match the checkpoint"))?;
        if time > sim.time() {
            return Err(format!(
                "{} is a snapshot at t = {time}, after the checkpoint: the run directory does \
                 not match the checkpoint",
                dir.join(&file).display()
            ));
        }
        entries.push((time, file));
    }
    Ok(Some(series.with_entries(entries)))
}

/// The body surfaces' series of a split run, which rank 0 writes (the bodies are whole on
/// every process): `bodies_NNNNNN.vtp` indexed by `bodies.pvd`, as on one process.
pub fn split_surfaces(dir: &Path, sim: &Simulation) -> Option<SurfaceSeries> {
    surface_series(dir, sim)
}

/// Writes snapshot `index` of the body surfaces of a split run into `dir` (rank 0 alone, no
/// collective call): `bodies_NNNNNN.vtp` and `bodies.pvd`, and with HDF5 output (`hdf5`,
/// rank 0's) `bodies_NNNNNN.h5` and `bodies.xmf`, from the same surfaces and by the same
/// code as on one process; with a free surface its zero level from `whole` (gathered by
/// [`WholeLevelSet::gather`]); returns the files written.
pub fn write_split_surfaces(
    dir: &Path,
    series: &mut SurfaceSeries,
    index: usize,
    sim: &Simulation,
    hdf5: Option<&mut SplitHdf5>,
    whole: Option<&WholeLevelSet>,
) -> anyhow::Result<Vec<String>> {
    let (file, g) = write_surfaces(series, index, sim, whole)?;
    #[cfg(feature = "hdf5")]
    if let Some(h) = hdf5.and_then(|h| h.root.as_mut()) {
        let mut written = vec![file];
        written.extend(h.surfaces(dir, index, sim, &g)?);
        return Ok(written);
    }
    #[cfg(not(feature = "hdf5"))]
    let _ = (dir, hdf5, g);
    Ok(vec![file])
}

/// The whole grid's liquid level set and walls' mask on rank 0 of a split run with a free
/// surface, for the zero level in the body surfaces: every process sends its planes of the
/// level set at each snapshot, and of the (static) walls' mask once (rank 0 alone holds the
/// whole grid's).
pub struct WholeLevelSet {
    gather: crate::parallel::Gather,
    phi: Vec<f64>,
    /// 1 inside a wall, 0 elsewhere (empty without walls).
    in_wall: Vec<f64>,
}

impl WholeLevelSet {
    /// For a split run of `sim` with a free surface (`None` otherwise), with the walls' mask
    /// gathered (every process together).
    pub fn new(sim: &Simulation) -> Option<Self> {
        let d = sim.world.get_resource::<crate::parallel::Decomposition>()?;
        sim.world.get_resource::<LiquidLevelSet>()?;
        let grid = sim.grid();
        let whole = if d.comm.is_root() {
            grid.whole().len()
        } else {
            0
        };
        let gather = crate::parallel::Gather::new(d, grid.plane());
        let walls = sim
            .world
            .get_resource::<crate::systems::free_surface::FreeSurfaceScratch>();
        let mine: Vec<f64> = walls
            .map_or(&[][..], |w| w.in_wall())
            .iter()
            .map(|&w| w as u8 as f64)
            .collect();
        // Every process has walls or none (the same static bodies).
        let mut in_wall = Vec::new();
        if !mine.is_empty() {
            in_wall.resize(whole, 0.0);
            gather.to_root(&mine, &mut in_wall);
        }
        Some(WholeLevelSet {
            gather,
            phi: vec![0.0; whole],
            in_wall,
        })
    }

    /// Gathers the level set now onto rank 0 (every process together).
    pub fn gather(&mut self, sim: &Simulation) {
        if let Some(l) = sim.world.get_resource::<LiquidLevelSet>() {
            self.gather.to_root(&l.phi, &mut self.phi);
        }
    }
}

/// Snapshot `index` of the bodies' surfaces, each at its pose with its velocity, angular
/// velocity and hydrodynamic force, in body-id order, then with a free surface its zero level
/// (part [`FREE_SURFACE_PART`], zero vectors); returns the file name and the surfaces (in
/// world space, for the other formats).
fn write_surfaces(
    series: &mut SurfaceSeries,
    index: usize,
    sim: &Simulation,
    whole: Option<&WholeLevelSet>,
) -> anyhow::Result<(String, SurfaceGeometry)> {
    let world = &sim.world;
    let mut bodies: Vec<_> = world
        .try_query::<(&Body, &RigidState, &Hydro, &BodySurface)>()
        .map(|mut q| q.iter(world).collect())
        .unwrap_or_default();
    bodies.sort_by_key(|(b, ..)| b.id);
    let mut parts: Vec<SurfacePart> = bodies
        .iter()
        .map(|(b, st, h, surf)| SurfacePart {
            name: &b.name,
            mesh: &surf.0,
            center: st.center,
            orientation: st.orientation,
            vectors: vec![st.velocity, st.angular_velocity, h.force],
        })
        .collect();
    // The zero level, without its part inside the static walls (the seam of the periodic
    // box runs there).
    let free = world.get_resource::<LiquidLevelSet>().map(|l| {
        let grid = sim.grid().whole();
        let mut mesh;
        match whole {
            // On several processes the whole grid's level set, gathered for this snapshot.
            Some(w) => {
                mesh = crate::io::isosurface::zero_level(&grid, &w.phi);
                if w.in_wall.len() == w.phi.len() {
                    crate::io::isosurface::clip(&grid, &mut mesh, |c| w.in_wall[c] > 0.5);
                }
            }
            None => {
                let scratch =
                    world.get_resource::<crate::systems::free_surface::FreeSurfaceScratch>();
                let in_wall = scratch.map_or(&[][..], |s| s.in_wall());
                mesh = crate::io::isosurface::zero_level(&grid, &l.phi);
                if in_wall.len() == l.phi.len() {
                    crate::io::isosurface::clip(&grid, &mut mesh, |c| in_wall[c]);
                }
            }
        }
        mesh
    });
    if let Some(mesh) = &free {
        parts.push(SurfacePart {
            name: FREE_SURFACE_PART,
            mesh,
            center: glam::DVec3::ZERO,
            orientation: glam::DQuat::IDENTITY,
            vectors: vec![glam::DVec3::ZERO; SURFACE_VECTORS.len()],
        });
    }
    let g = SurfaceGeometry::new(&parts, series.vector_names()).context("body surfaces")?;
    let file = series
        .write_geometry(index, sim.time(), &g)
        .with_context(|| format!("cannot write bodies_{index:06}.vtp or bodies.pvd"))?;
    Ok((file, g))
}

/// Call `f` with the fields of a snapshot of `sim`, in the scene's `output.fields` order:
/// `omega`, `velocity`, and with bodies `density`, `chi`, `phi` (φ clamped below at minus the
/// band kept around each body, [`crate::bodies::band`]: where no body's band reaches, φ is
/// -∞ in memory and readers choke on infinities and sentinels); then, with a free surface
/// whose φ_w has one value per node and a scene asking for some field, `free_surface`
/// (φ_w, > 0 in the liquid); then, likewise, the plugins' fields ([`OutputFields`]).
fn with_fields<R>(sim: &Simulation, f: impl FnOnce(&[VtkField]) -> R) -> R {
    let fl = sim.fields();
    let omega: Vec<&[f64]> = fl.omega().iter().map(|c| c.as_slice()).collect();
    let u: Vec<&[f64]> = fl.u.iter().map(|c| c.as_slice()).collect();
    let bf = sim.world.get_resource::<crate::bodies::BodyFields>();
    let phi_min = -crate::bodies::band(sim.grid());
    let phi: Vec<f64> = bf
        .map(|b| b.phi.iter().map(|p| p.max(phi_min)).collect())
        .unwrap_or_default();
    type Comps<'a> = Vec<&'a [f64]>;
    let (rho, chi, phi): (Comps, Comps, Comps) = match bf {
        Some(b) => (vec![&b.rho], vec![&b.chi], vec![&phi]),
        None => Default::default(),
    };
    let mut vtk = Vec::new();
    for name in &sim.scene().output.fields {
        let mut add = |name, components| vtk.push(VtkField { name, components });
        match name {
            FieldName::Omega => add("omega", &omega),
            FieldName::Velocity => add("velocity", &u),
            FieldName::Density => {
                if bf.is_some() {
                    add("density", &rho);
                    add("chi", &chi);
                    add("phi", &phi);
                }
            }
        }
    }
    let liquid: Vec<&[f64]> = sim
        .world
        .get_resource::<LiquidLevelSet>()
        .filter(|l| l.phi.len() == sim.grid().len())
        .map(|l| vec![l.phi.as_slice()])
        .unwrap_or_default();
    if !liquid.is_empty() && !sim.scene().output.fields.is_empty() {
        vtk.push(VtkField {
            name: "free_surface",
            components: &liquid,
        });
    }
    let plugin_fields: Vec<(&str, Vec<&[f64]>)> = match sim.world.get_resource::<OutputFields>() {
        Some(o) if !sim.scene().output.fields.is_empty() => {
            o.0.iter().map(|f| (f.name, (f.read)(&sim.world))).collect()
        }
        _ => Vec::new(),
    };
    for (name, components) in &plugin_fields {
        vtk.push(VtkField { name, components });
    }
    f(&vtk)
}

#[cfg(feature = "hdf5")]
struct Hdf5Outputs {
    xmf: crate::io::xdmf::XdmfSeries,
    /// The index of the body surfaces' HDF5 files, `bodies.xmf` (a run with bodies).
    bodies: Option<crate::io::xdmf::SurfaceXdmf>,
    /// The rows recorded since `series.h5` was last appended to.
    series: crate::io::hdf5_out::Series,
    /// The step last recorded (a step is recorded once).
    steps_recorded: u64,
    /// What `series.h5` is: not created yet, to be cut back (a restart), or ready.
    file: SeriesFile,
}

/// The state of `series.h5` in the run directory.
#[cfg(feature = "hdf5")]
enum SeriesFile {
    /// Not created yet (a new run).
    Missing,
    /// Written by the run a restart continues: cut back to this before appending.
    CutTo(crate::io::hdf5_out::SeriesCut),
    /// Ready for rows.
    Ready,
}

#[cfg(feature = "hdf5")]
impl Hdf5Outputs {
    /// The outputs of `sim`'s run in `dir`; `surfaces`: whether snapshots write the body
    /// surfaces (`bodies.xmf`).
    fn new(dir: &Path, sim: &Simulation, surfaces: bool) -> Self {
        use crate::io::hdf5_out::{BodySeries, ContactSeries, Series};
        use crate::scene::BodyKind;
        let scene = sim.scene();
        let global = ["t", "dt", "energy", "enstrophy", "circulation", "max_omega"]
            .iter()
            .map(|&n| (n, Vec::new()))
            .collect();
        let bodies = scene
            .bodies
            .iter()
            .enumerate()
            .filter(|(_, b)| !matches!(b.kind, BodyKind::Static))
            .map(|(id, b)| BodySeries {
                name: b.name.clone(),
                id,
                ..Default::default()
            })
            .collect();
        let contacts = scene
            .bodies
            .iter()
            .any(|b| matches!(b.kind, BodyKind::Dynamic))
            .then(ContactSeries::default);
        Hdf5Outputs {
            xmf: crate::io::xdmf::XdmfSeries::new(dir.join("fields.xmf"), &sim.grid().whole())
                .with_precision(sim.scene().output.precision),
            bodies: surfaces.then(|| {
                crate::io::xdmf::SurfaceXdmf::new(
                    dir.join("bodies.xmf"),
                    &SURFACE_VECTORS,
                    Vec::new(),
                )
            }),
            series: Series {
                global,
                bodies,
                contacts,
                body_names: scene.bodies.iter().map(|b| b.name.clone()).collect(),
            },
            steps_recorded: u64::MAX,
            file: SeriesFile::Missing,
        }
    }

    /// The outputs of a restarted run after `count` snapshots (see [`Snapshots::resume`]).
    fn resume(dir: &Path, sim: &Simulation, count: usize, surfaces: bool) -> Result<Self, String> {
        use crate::io::xdmf::XdmfEntry;
        let mut h = Hdf5Outputs::new(dir, sim, surfaces);
        let (t0, step0) = (sim.time(), sim.steps());
        // A snapshot's fields depend on the scene only: the same for every snapshot.
        let attributes = with_fields(sim, xdmf_attributes);
        let mut entries = Vec::with_capacity(count);
        for k in 0..count {
            let file = format!("fields_{k:06}.h5");
            let time = crate::io::hdf5_out::read_time(&dir.join(&file))
                .map_err(|e| format!("{e}: the run directory does not match the checkpoint"))?;
            if time > t0 {
                return Err(format!(
                    "{} is a snapshot at t = {time}, after the checkpoint: the run directory \
                     does not match the checkpoint",
                    dir.join(&file).display()
                ));
            }
            entries.push(XdmfEntry {
                time,
                file,
                attributes: attributes.clone(),
            });
        }
        h.xmf = crate::io::xdmf::XdmfSeries::with_entries(
            dir.join("fields.xmf"),
            &sim.grid().whole(),
            entries,
        )
        .with_precision(sim.scene().output.precision);
        if h.bodies.is_some() {
            let mut entries = Vec::with_capacity(count);
            for k in 0..count {
                let file = format!("bodies_{k:06}.h5");
                let (time, points, cells, nodes) =
                    crate::io::hdf5_out::read_surface_layout(&dir.join(&file)).map_err(|e| {
                        format!("{e}: the run directory does not match the checkpoint")
                    })?;
                if time > t0 {
                    return Err(format!(
                        "{} is a snapshot at t = {time}, after the checkpoint: the run \
                         directory does not match the checkpoint",
                        dir.join(&file).display()
                    ));
                }
                entries.push(crate::io::xdmf::SurfaceEntry {
                    time,
                    file,
                    points,
                    cells,
                    nodes,
                });
            }
            h.bodies = Some(crate::io::xdmf::SurfaceXdmf::new(
                dir.join("bodies.xmf"),
                &SURFACE_VECTORS,
                entries,
            ));
        }
        let path = dir.join("series.h5");
        let cut = crate::io::hdf5_out::check_series(&path, &h.series, step0 as usize + 1, t0)
            .map_err(|e| format!("{e}: the run directory does not match the checkpoint"))?
            .map_err(|e| {
                format!(
                    "{} {e}: the run directory does not match the checkpoint",
                    path.display()
                )
            })?;
        h.file = SeriesFile::CutTo(cut);
        h.steps_recorded = step0;
        Ok(h)
    }

    fn record(&mut self, sim: &mut Simulation) {
        use crate::bodies::{Body, Hydro, RigidState};
        if self.steps_recorded == sim.steps() {
            return;
        }
        self.steps_recorded = sim.steps();
        let s = sim.sample();
        let t = sim.time();
        for (name, v) in &mut self.series.global {
            v.push(match *name {
                "t" => s.t,
                "dt" => s.dt,
                "energy" => s.energy,
                "enstrophy" => s.enstrophy,
                "circulation" => s.circulation,
                _ => s.max_omega,
            });
        }
        if !self.series.bodies.is_empty() {
            let mut q = sim.world.query::<(&Body, &RigidState, &Hydro)>();
            for (b, st, h) in q.iter(&sim.world) {
                let Some(rec) = self.series.bodies.iter_mut().find(|r| r.id == b.id) else {
                    continue;
                };
                rec.t.push(t);
                rec.center.extend(st.center.to_array());
                rec.velocity.extend(st.velocity.to_array());
                rec.angular_velocity.extend(st.angular_velocity.to_array());
                let o = st.orientation;
                rec.orientation.extend([o.w, o.x, o.y, o.z]);
                rec.force.extend(h.force.to_array());
                rec.torque.extend(h.torque.to_array());
            }
        }
        if let Some(c) = self.series.contacts.as_mut()
            && let Some(rec) = sim
                .world
                .get_resource::<crate::systems::collision::Contacts>()
        {
            for r in &rec.records {
                c.t.push(t);
                c.body_a.push(r.a as u64);
                c.body_b.push(r.b as u64);
                c.gap.push(r.gap);
                c.normal_force.push(r.force);
            }
        }
    }

    fn snapshot(
        &mut self,
        dir: &Path,
        k: usize,
        sim: &Simulation,
        fields: &[VtkField],
        surfaces: Option<&SurfaceGeometry>,
    ) -> anyhow::Result<Vec<String>> {
        use crate::io::xdmf::XdmfEntry;
        let mut written = Vec::new();
        if let Some(g) = surfaces {
            written.extend(self.surfaces(dir, k, sim, g)?);
        }
        let file = format!("fields_{k:06}.h5");
        crate::io::hdf5_out::write_fields(
            &dir.join(&file),
            sim.grid(),
            sim.time(),
            sim.steps(),
            fields,
            sim.scene().output.precision,
        )
        .with_context(|| format!("cannot write {file}"))?;
        self.xmf
            .push(XdmfEntry {
                time: sim.time(),
                file: file.clone(),
                attributes: xdmf_attributes(fields),
            })
            .context("cannot write fields.xmf")?;
        self.write_series(dir)?;
        written.extend([file, "fields.xmf".into(), "series.h5".into()]);
        Ok(written)
    }

    /// Snapshot `k` of the body surfaces `g` in HDF5 (a run with surfaces; nothing
    /// otherwise): `bodies_NNNNNN.h5`, then listed in `bodies.xmf`; returns the files written.
    /// One process's snapshots and rank 0's in a split run both write them here.
    fn surfaces(
        &mut self,
        dir: &Path,
        k: usize,
        sim: &Simulation,
        g: &SurfaceGeometry,
    ) -> anyhow::Result<Vec<String>> {
        let Some(index) = self.bodies.as_mut() else {
            return Ok(Vec::new());
        };
        let file = format!("bodies_{k:06}.h5");
        crate::io::hdf5_out::write_surfaces(&dir.join(&file), sim.time(), sim.steps(), g)
            .with_context(|| format!("cannot write {file}"))?;
        index
            .push(crate::io::xdmf::SurfaceEntry {
                time: sim.time(),
                file: file.clone(),
                points: g.points.len(),
                cells: g.n_cells(),
                nodes: if g.triangles.is_empty() { 2 } else { 3 },
            })
            .context("cannot write bodies.xmf")?;
        Ok(vec![file, "bodies.xmf".to_string()])
    }

    /// Cut `series.h5` back to the checkpoint a restart continues from (see
    /// [`Snapshots::cut_back`]).
    fn cut_back(&mut self, dir: &Path) -> anyhow::Result<()> {
        if let SeriesFile::CutTo(cut) = self.file {
            crate::io::hdf5_out::cut_series(&dir.join("series.h5"), &self.series, cut)
                .context("cannot cut series.h5 back to the checkpoint")?;
            self.file = SeriesFile::Ready;
        }
        Ok(())
    }

    /// Append the rows recorded since the last call to `series.h5` (created first in a new
    /// run) and drop them from memory.
    fn write_series(&mut self, dir: &Path) -> anyhow::Result<()> {
        use crate::io::hdf5_out::{append_series, create_series};
        let path = dir.join("series.h5");
        match self.file {
            SeriesFile::Ready => {}
            SeriesFile::Missing => {
                create_series(&path, &self.series).context("cannot write series.h5")?;
                self.file = SeriesFile::Ready;
            }
            SeriesFile::CutTo(_) => self.cut_back(dir)?,
        }
        append_series(&path, &self.series).context("cannot write series.h5")?;
        self.series.clear_values();
        Ok(())
    }
}

/// The XDMF attributes of a snapshot's fields.
#[cfg(feature = "hdf5")]
fn xdmf_attributes(fields: &[VtkField]) -> Vec<crate::io::xdmf::XdmfAttribute> {
    fields
        .iter()
        .map(|f| crate::io::xdmf::XdmfAttribute {
            name: f.name.to_string(),
            components: if f.components.len() == 1 { 1 } else { 3 },
        })
        .collect()
}

/// Snapshot `count` of a run split over processes ([`crate::parallel::Decomposition`]): every
/// process writes its slab as a piece, `fields_NNNNNN_R.vti` (R its rank), one plane deeper
/// than its slab (the first plane of the process above, so the pieces meet without a gap of a
/// cell; the last process's piece ends with the grid), and rank 0 writes their index,
/// `fields_NNNNNN.pvti`, the file the run's `fields.pvd` names: ParaView and VTK's
/// `vtkXMLPImageDataReader` read it as one dataset with the arrays of a one-process run.
/// Collective: every process calls it at the same snapshot. Returns the index's name (on every
/// process) and whether this process wrote anything.
pub fn write_pieces(dir: &Path, count: usize, sim: &Simulation) -> anyhow::Result<String> {
    use crate::parallel::Decomposition;
    let d = sim
        .world
        .get_resource::<Decomposition>()
        .expect("pieces: a split run");
    let grid = sim.grid();
    let (rank, ranks) = (d.slabs.rank, d.slabs.ranks);
    let plane = grid.plane();
    let last = rank + 1 == ranks;
    let planes = d.slabs.my_planes();
    let piece_planes = planes.start..planes.end + usize::from(!last);
    let piece_grid = grid.whole().slab(piece_planes);
    let index = format!("fields_{count:06}.pvti");
    let piece_name = |r: usize| format!("fields_{count:06}_{r}.vti");
    let precision = sim.scene().output.precision;
    with_fields(sim, |vtk| -> anyhow::Result<()> {
        // Each component with the plane above appended (exchanged by every process, in the
        // same order everywhere).
        let mut deep: Vec<Vec<Vec<f64>>> = Vec::with_capacity(vtk.len());
        for f in vtk {
            let mut comps = Vec::with_capacity(f.components.len());
            for c in f.components.iter() {
                let (mut below, mut above) = (vec![0.0; plane], vec![0.0; plane]);
                let (first, top) = (&c[..plane], &c[c.len() - plane..]);
                d.comm
                    .exchange(&d.slabs, first, top, &mut below, &mut above);
                let mut v = Vec::with_capacity(c.len() + plane);
                v.extend_from_slice(c);
                if !last {
                    v.extend_from_slice(&above);
                }
                comps.push(v);
            }
            deep.push(comps);
        }
        let slices: Vec<Vec<&[f64]>> = deep
            .iter()
            .map(|comps| comps.iter().map(|v| v.as_slice()).collect())
            .collect();
        let fields: Vec<VtkField> = vtk
            .iter()
            .zip(&slices)
            .map(|(f, c)| VtkField {
                name: f.name,
                components: c,
            })
            .collect();
        let file = piece_name(rank);
        write_vti_compressed(
            &dir.join(&file),
            &piece_grid,
            sim.time(),
            &fields,
            precision,
        )
        .with_context(|| format!("cannot write {file}"))?;
        if rank == 0 {
            let pieces: Vec<(String, String)> = (0..ranks)
                .map(|r| {
                    let p = d.slabs.planes(r);
                    let end = if r + 1 == ranks { p.end } else { p.end + 1 };
                    let g = grid.whole().slab(p.start..end);
                    (crate::io::output::extents(&g).1, piece_name(r))
                })
                .collect();
            crate::io::output::write_pvti(
                &dir.join(&index),
                &grid.whole(),
                &fields,
                precision,
                &pieces,
            )
            .with_context(|| format!("cannot write {index}"))?;
        }
        Ok(())
    })?;
    // The index names every piece: it is complete once they all are.
    d.comm.barrier();
    Ok(index)
}

/// The HDF5 snapshots of a run split over processes (a scene asking for `Hdf5`; see
/// [`write_pieces`] for VTK). Every process writes its slab of each snapshot as a file of its
/// own, `fields_NNNNNN_R.h5` (R its rank; the datasets of a one-process snapshot on the slab's
/// planes, its attributes those of the slab as a grid of its own), and rank 0 writes
/// `fields_NNNNNN.h5`, whose datasets are HDF5 virtual datasets of the whole grid made of the
/// pieces ([`crate::io::hdf5_out::write_virtual_fields`]): h5py, ParaView and the HDF5 library
/// read it as the one-process file, names, shapes and values. Rank 0 alone keeps `fields.xmf`
/// and `series.h5`, as on one process (the time series are global, the same on every
/// process). Nothing is gathered: each process writes only its slab. With bodies or a free
/// surface rank 0 also keeps `bodies.xmf` and writes `bodies_NNNNNN.h5`, from its whole copy
/// of the bodies (and the whole level set), along with their VTK form
/// ([`write_split_surfaces`]): the one-process files.
pub struct SplitHdf5 {
    /// Rank 0's outputs: the index and `series.h5`.
    #[cfg(feature = "hdf5")]
    root: Option<Hdf5Outputs>,
}

impl SplitHdf5 {
    /// The HDF5 outputs of `sim`'s split run in `dir`, if its scene asks for them (`root`:
    /// whether this is rank 0). Nothing is written yet.
    pub fn new(dir: &Path, sim: &Simulation, root: bool) -> Option<Self> {
        if !sim.scene().output.has_format(OutputFormat::Hdf5) {
            return None;
        }
        #[cfg(feature = "hdf5")]
        return Some(SplitHdf5 {
            root: root.then(|| Hdf5Outputs::new(dir, sim, has_surfaces(sim))),
        });
        #[cfg(not(feature = "hdf5"))]
        {
            // A scene asking for HDF5 is refused by a build without it.
            let _ = (dir, root);
            None
        }
    }

    /// The outputs of a restarted split run after `count` snapshots, read back on rank 0 as
    /// [`Snapshots::resume`] does (the snapshot files' times, `series.h5`'s lengths). Nothing
    /// is changed (see [`cut_back`](SplitHdf5::cut_back)).
    pub fn resume(
        dir: &Path,
        sim: &Simulation,
        count: usize,
        root: bool,
    ) -> Result<Option<Self>, String> {
        #[cfg(feature = "hdf5")]
        if sim.scene().output.has_format(OutputFormat::Hdf5) {
            let root = if root {
                Some(Hdf5Outputs::resume(dir, sim, count, has_surfaces(sim))?)
            } else {
                None
            };
            return Ok(Some(SplitHdf5 { root }));
        }
        let _ = (dir, sim, count, root);
        Ok(None)
    }

    /// Make the run directory match a resumed run of `count` snapshots: each process removes
    /// its pieces of the later snapshots, rank 0 their files and their body surfaces'
    /// `bodies_NNNNNN.h5`, rewrites `fields.xmf` and `bodies.xmf` and cuts `series.h5` back
    /// to the checkpoint.
    pub fn cut_back(&mut self, dir: &Path, count: usize, rank: usize) -> anyhow::Result<()> {
        for k in count.. {
            let piece = dir.join(format!("fields_{k:06}_{rank}.h5"));
            let index = dir.join(format!("fields_{k:06}.h5"));
            if !piece.is_file() && !index.is_file() {
                break;
            }
            let mine = [Some(piece), (rank == 0).then_some(index)];
            for f in mine.iter().flatten().filter(|f| f.is_file()) {
                std::fs::remove_file(f)
                    .with_context(|| format!("cannot remove {}", f.display()))?;
            }
        }
        #[cfg(feature = "hdf5")]
        if let Some(h) = self.root.as_mut() {
            if let Some(b) = &h.bodies {
                for k in count.. {
                    let f = dir.join(format!("bodies_{k:06}.h5"));
                    if !f.is_file() {
                        break;
                    }
                    std::fs::remove_file(&f)
                        .with_context(|| format!("cannot remove {}", f.display()))?;
                }
                b.write().context("cannot write bodies.xmf")?;
            }
            h.xmf.write().context("cannot write fields.xmf")?;
            h.cut_back(dir)?;
        }
        Ok(())
    }

    /// Record the state after a step for `series.h5` (rank 0).
    pub fn record(&mut self, sim: &mut Simulation) {
        #[cfg(feature = "hdf5")]
        if let Some(h) = self.root.as_mut() {
            h.record(sim);
        }
        #[cfg(not(feature = "hdf5"))]
        let _ = sim;
    }

    /// Snapshot `count`: every process writes its piece, rank 0 the whole snapshot's file;
    /// once every process has written, rank 0 lists it in `fields.xmf` and appends the rows
    /// recorded since the last snapshot to `series.h5`. Collective: every process calls it at
    /// the same snapshot, and all fail if one does.
    pub fn snapshot(&mut self, dir: &Path, count: usize, sim: &Simulation) -> anyhow::Result<()> {
        #[cfg(feature = "hdf5")]
        {
            use crate::io::hdf5_out::{Piece, write_fields, write_virtual_fields};
            use crate::parallel::Decomposition;
            let d = sim
                .world
                .get_resource::<Decomposition>()
                .expect("split HDF5 snapshots: a split run");
            let (rank, ranks) = (d.slabs.rank, d.slabs.ranks);
            let slab = sim.grid();
            let whole = slab.whole();
            let precision = sim.scene().output.precision;
            let file = format!("fields_{count:06}.h5");
            let piece = |r: usize| format!("fields_{count:06}_{r}.h5");
            let written = with_fields(sim, |fields| -> anyhow::Result<Vec<_>> {
                // The slab as a grid of its own: its first plane's position, its planes.
                let mut origin = slab.origin;
                origin[2] += slab.k0 as f64 * slab.h;
                let own = crate::base::grid::Grid::new(slab.n, slab.h, origin);
                write_fields(
                    &dir.join(piece(rank)),
                    &own,
                    sim.time(),
                    sim.steps(),
                    fields,
                    precision,
                )
                .with_context(|| format!("cannot write {}", piece(rank)))?;
                let names: Vec<(&str, usize)> = fields
                    .iter()
                    .map(|f| (f.name, if f.components.len() == 1 { 1 } else { 3 }))
                    .collect();
                if rank == 0 {
                    let pieces: Vec<Piece> = (0..ranks)
                        .map(|r| Piece {
                            file: piece(r),
                            planes: d.slabs.planes(r),
                        })
                        .collect();
                    write_virtual_fields(
                        &dir.join(&file),
                        &whole,
                        sim.time(),
                        sim.steps(),
                        &names,
                        precision,
                        &pieces,
                    )
                    .with_context(|| format!("cannot write {file}"))?;
                }
                Ok(xdmf_attributes(fields))
            });
            // The snapshot is complete once every process has written its part.
            let failed = d.comm.max_one(f64::from(u8::from(written.is_err())));
            let attributes = written?;
            if failed > 0.0 {
                anyhow::bail!("another process could not write its piece of {file}");
            }
            if let Some(h) = self.root.as_mut() {
                h.xmf
                    .push(crate::io::xdmf::XdmfEntry {
                        time: sim.time(),
                        file,
                        attributes,
                    })
                    .context("cannot write fields.xmf")?;
                h.write_series(dir)?;
            }
        }
        #[cfg(not(feature = "hdf5"))]
        let _ = (dir, count, sim);
        Ok(())
    }

    /// Append the rows kept in memory to `series.h5` (rank 0): at a checkpoint and at the end.
    pub fn finish(&mut self, dir: &Path) -> anyhow::Result<()> {
        #[cfg(feature = "hdf5")]
        if let Some(h) = self.root.as_mut() {
            h.write_series(dir)?;
        }
        #[cfg(not(feature = "hdf5"))]
        let _ = dir;
        Ok(())
    }
}
