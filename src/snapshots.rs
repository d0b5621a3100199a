//! Field snapshots of a run in the scene's formats (`output.formats`): VTK (`fields_NNNNNN.vti`
//! indexed by `fields.pvd`) and, in builds with the `hdf5` feature, HDF5 (`fields_NNNNNN.h5`
//! indexed by `fields.xmf`, plus `series.h5`, the time series of the run, the bodies and the
//! contacts, rewritten at every snapshot and at the end).

use crate::engine::Simulation;
use crate::output::{PvdSeries, VtkField, write_vti};
use crate::scene::{FieldName, OutputFormat};
use anyhow::Context;
use std::path::{Path, PathBuf};

/// The snapshot writers of one run.
pub struct Snapshots {
    dir: PathBuf,
    pvd: Option<PvdSeries>,
    #[cfg(feature = "hdf5")]
    hdf5: Option<Hdf5Outputs>,
    count: usize,
}

impl Snapshots {
    /// The writers for `sim`'s scene, writing into `dir` (nothing is written yet).
    pub fn new(dir: &Path, sim: &Simulation) -> Self {
        let out = &sim.scene().output;
        Snapshots {
            dir: dir.to_path_buf(),
            pvd: out
                .has_format(OutputFormat::Vtk)
                .then(|| PvdSeries::new(dir.join("fields.pvd"))),
            #[cfg(feature = "hdf5")]
            hdf5: out
                .has_format(OutputFormat::Hdf5)
                .then(|| Hdf5Outputs::new(dir, sim)),
            count: 0,
        }
    }

    /// Snapshots written so far.
    pub fn count(&self) -> usize {
        self.count
    }

    /// The index file a viewer opens: `fields.pvd`, else `fields.xmf`.
    pub fn index_file(&self) -> PathBuf {
        match &self.pvd {
            Some(p) => p.path().to_path_buf(),
            None => self.dir.join("fields.xmf"),
        }
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
        let f = sim.fields();
        let omega: Vec<&[f64]> = f.omega().iter().map(|c| c.as_slice()).collect();
        let u: Vec<&[f64]> = f.u.iter().map(|c| c.as_slice()).collect();
        let bf = sim.world.get_resource::<crate::bodies::BodyFields>();
        // φ is -∞ far from every body: clamped, as readers choke on infinities.
        let phi: Vec<f64> = bf
            .map(|b| b.phi.iter().map(|p| p.max(-1e30)).collect())
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
        let mut written = Vec::new();
        if let Some(pvd) = self.pvd.as_mut() {
            let file = format!("fields_{:06}.vti", self.count);
            write_vti(&self.dir.join(&file), sim.grid(), sim.time(), &vtk)
                .with_context(|| format!("cannot write {file}"))?;
            pvd.push(sim.time(), &file)
                .context("cannot write fields.pvd")?;
            written.push(file);
        }
        #[cfg(feature = "hdf5")]
        if let Some(h) = self.hdf5.as_mut() {
            written.extend(h.snapshot(&self.dir, self.count, sim, &vtk)?);
        }
        self.count += 1;
        Ok(written)
    }

    /// Write what is kept in memory until the end (`series.h5`).
    pub fn finish(&mut self) -> anyhow::Result<()> {
        #[cfg(feature = "hdf5")]
        if let Some(h) = self.hdf5.as_ref() {
            h.write_series(&self.dir)?;
        }
        Ok(())
    }
}

#[cfg(feature = "hdf5")]
struct Hdf5Outputs {
    xmf: crate::xdmf::XdmfSeries,
    series: crate::hdf5_out::Series,
    /// The step last recorded (a step is recorded once).
    steps_recorded: u64,
}

#[cfg(feature = "hdf5")]
impl Hdf5Outputs {
    fn new(dir: &Path, sim: &Simulation) -> Self {
        use crate::hdf5_out::{BodySeries, ContactSeries, Series};
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
            xmf: crate::xdmf::XdmfSeries::new(dir.join("fields.xmf"), sim.grid()),
            series: Series {
                global,
                bodies,
                contacts,
                body_names: scene.bodies.iter().map(|b| b.name.clone()).collect(),
            },
            steps_recorded: u64::MAX,
        }
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
    ) -> anyhow::Result<Vec<String>> {
        use crate::xdmf::{XdmfAttribute, XdmfEntry};
        let file = format!("fields_{k:06}.h5");
        crate::hdf5_out::write_fields(
            &dir.join(&file),
            sim.grid(),
            sim.time(),
            sim.steps(),
            fields,
        )
        .with_context(|| format!("cannot write {file}"))?;
        self.xmf
            .push(XdmfEntry {
                time: sim.time(),
                file: file.clone(),
                attributes: fields
                    .iter()
                    .map(|f| XdmfAttribute {
                        name: f.name.to_string(),
                        components: if f.components.len() == 1 { 1 } else { 3 },
                    })
                    .collect(),
            })
            .context("cannot write fields.xmf")?;
        self.write_series(dir)?;
        Ok(vec![file, "fields.xmf".into(), "series.h5".into()])
    }

    fn write_series(&self, dir: &Path) -> anyhow::Result<()> {
        crate::hdf5_out::write_series(&dir.join("series.h5"), &self.series)
            .context("cannot write series.h5")
    }
}
