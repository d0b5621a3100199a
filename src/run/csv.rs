//! The run's CSV time series: `series.csv` (one row per step), `bodies.csv` (one row per
//! moving body per step) and `contacts.csv` (one row per close pair per step).

use crate::base::fields::Sample;
use crate::bodies::free_surface::LiquidLevelSet;
use crate::io::output::{CsvWriter, atomic_write, csv_writer};
use crate::sim::engine::Simulation;
use crate::systems::diffusion::GridScaleDissipation;
use anyhow::Context;
use std::path::Path;

/// The columns of `series.csv` every run has.
pub const SERIES_COLUMNS: [&str; 6] =
    ["t", "dt", "energy", "enstrophy", "circulation", "max_omega"];

/// The columns `series.csv` adds in a run with a free surface: the liquid volume
/// ∫H_ε(φ_w) dV (an area in 2D) and the interface area ∫δ_ε(φ_w) dV (a length in 2D), from
/// the [`LiquidLevelSet`] after each step.
pub const LIQUID_COLUMNS: [&str; 2] = ["liquid_volume", "liquid_area"];

/// The column `series.csv` adds in a 3D fluid run: the kinetic energy per unit volume the
/// grid-scale dissipation has removed since the start ([`GridScaleDissipation`]).
pub const GRID_SCALE_COLUMN: &str = "grid_scale_removed";

/// `series.csv`: one row per step, [`SERIES_COLUMNS`], then [`LIQUID_COLUMNS`] if the run has
/// a free surface (its world holds a [`LiquidLevelSet`] when the file is created or, after a
/// restart, opened: the restored simulation has it if the run had it, so the columns stay the
/// same), then [`GRID_SCALE_COLUMN`] in a 3D fluid run.
pub struct SeriesCsv {
    w: CsvWriter,
    liquid: bool,
    grid_scale: bool,
}

impl SeriesCsv {
    fn has_liquid(sim: &Simulation) -> bool {
        sim.world.contains_resource::<LiquidLevelSet>()
    }

    fn has_grid_scale(sim: &Simulation) -> bool {
        sim.grid().dim == 3 && sim.world.contains_resource::<GridScaleDissipation>()
    }

    /// The header of `sim`'s `series.csv`.
    pub fn header(sim: &Simulation) -> Vec<&'static str> {
        let mut h = SERIES_COLUMNS.to_vec();
        if Self::has_liquid(sim) {
            h.extend(LIQUID_COLUMNS);
        }
        if Self::has_grid_scale(sim) {
            h.push(GRID_SCALE_COLUMN);
        }
        h
    }

    /// Create `path` with `sim`'s header.
    pub fn create(path: &Path, sim: &Simulation) -> anyhow::Result<Self> {
        let header = Self::header(sim);
        Ok(SeriesCsv {
            liquid: Self::has_liquid(sim),
            grid_scale: Self::has_grid_scale(sim),
            w: CsvWriter::create(path, &header).context("cannot create series.csv")?,
        })
    }

    /// Open the `series.csv` of an earlier run of `sim` to append to it (a restart).
    pub fn append(path: &Path, sim: &Simulation) -> anyhow::Result<Self> {
        let header = Self::header(sim);
        Ok(SeriesCsv {
            liquid: Self::has_liquid(sim),
            grid_scale: Self::has_grid_scale(sim),
            w: CsvWriter::append(path, header.len()).context("cannot open series.csv")?,
        })
    }

    /// Append `sim`'s current state.
    pub fn row(&mut self, sim: &Simulation) -> anyhow::Result<()> {
        let s: Sample = sim.sample();
        let mut v = vec![s.t, s.dt, s.energy, s.enstrophy, s.circulation, s.max_omega];
        if self.liquid {
            // A free surface that went away writes NaN: the columns stay the same.
            let l = sim.world.get_resource::<LiquidLevelSet>();
            v.push(l.map_or(f64::NAN, |l| l.volume));
            v.push(l.map_or(f64::NAN, |l| l.area));
        }
        if self.grid_scale {
            let g = sim.world.get_resource::<GridScaleDissipation>();
            v.push(g.map_or(f64::NAN, |g| g.removed));
        }
        self.w.row(&v).context("cannot write series.csv")
    }

    /// Flush to disk.
    pub fn flush(&mut self) -> anyhow::Result<()> {
        self.w.flush().context("cannot write series.csv")
    }
}

/// Create `path` and write its `header` (comma-separated names, none needing quotes).
fn create(path: &Path, header: &str) -> anyhow::Result<CsvWriter> {
    let header: Vec<&str> = header.split(',').collect();
    CsvWriter::create(path, &header).with_context(|| format!("cannot create {}", path.display()))
}

/// Open `path` (a file [`create`] made with `header`) to append rows: a restarted run.
fn append(path: &Path, header: &str) -> anyhow::Result<CsvWriter> {
    CsvWriter::append(path, header.split(',').count())
        .with_context(|| format!("cannot open {}", path.display()))
}

/// `bodies.csv`: one row per moving body per step.
pub struct BodiesCsv(CsvWriter);

/// The header of `bodies.csv`.
pub const BODIES_HEADER: &str = "t,id,name,x,y,z,vx,vy,vz,wx,wy,wz,qw,qx,qy,qz,fx,fy,fz,tx,ty,tz";

impl BodiesCsv {
    /// Create the file if the scene has moving bodies.
    pub fn create(path: &Path, sim: &Simulation) -> anyhow::Result<Option<Self>> {
        if !sim
            .scene()
            .bodies
            .iter()
            .any(|b| !matches!(b.kind, crate::scene::BodyKind::Static))
        {
            return Ok(None);
        }
        Ok(Some(BodiesCsv(create(path, BODIES_HEADER)?)))
    }

    /// Open the file of an earlier run to append to it (a restart).
    pub fn append(path: &Path) -> anyhow::Result<Self> {
        Ok(BodiesCsv(append(path, BODIES_HEADER)?))
    }

    /// Append the current state of every moving body.
    pub fn rows(&mut self, sim: &mut Simulation) -> anyhow::Result<()> {
        use crate::bodies::{Body, Hydro, RigidState};
        let t = sim.time();
        let mut q = sim.world.query::<(&Body, &RigidState, &Hydro)>();
        for (b, s, h) in q.iter(&sim.world) {
            if b.is_static() {
                continue;
            }
            let o = s.orientation;
            let nums = [
                s.center.x,
                s.center.y,
                s.center.z,
                s.velocity.x,
                s.velocity.y,
                s.velocity.z,
                s.angular_velocity.x,
                s.angular_velocity.y,
                s.angular_velocity.z,
                o.w,
                o.x,
                o.y,
                o.z,
                h.force.x,
                h.force.y,
                h.force.z,
                h.torque.x,
                h.torque.y,
                h.torque.z,
            ];
            let record = [t.to_string(), b.id.to_string(), b.name.clone()]
                .into_iter()
                .chain(nums.iter().map(f64::to_string));
            self.0.record(record).context("cannot write bodies.csv")?;
        }
        Ok(())
    }

    /// Flush to disk.
    pub fn flush(&mut self) -> anyhow::Result<()> {
        self.0.flush().context("cannot write bodies.csv")
    }
}

/// `contacts.csv`: one row per close pair of bodies per step.
pub struct ContactsCsv(CsvWriter);

/// The header of `contacts.csv`.
pub const CONTACTS_HEADER: &str = "t,body_a,body_b,gap,normal_force";

impl ContactsCsv {
    /// Create the file if the scene has a dynamic body.
    pub fn create(path: &Path, sim: &Simulation) -> anyhow::Result<Option<Self>> {
        if !sim
            .scene()
            .bodies
            .iter()
            .any(|b| matches!(b.kind, crate::scene::BodyKind::Dynamic))
        {
            return Ok(None);
        }
        Ok(Some(ContactsCsv(create(path, CONTACTS_HEADER)?)))
    }

    /// Open the file of an earlier run to append to it (a restart).
    pub fn append(path: &Path) -> anyhow::Result<Self> {
        Ok(ContactsCsv(append(path, CONTACTS_HEADER)?))
    }

    /// Append this step's close pairs.
    pub fn rows(&mut self, sim: &Simulation) -> anyhow::Result<()> {
        let Some(c) = sim
            .world
            .get_resource::<crate::systems::collision::Contacts>()
        else {
            return Ok(());
        };
        let t = sim.time().to_string();
        let names = &sim.scene().bodies;
        for r in &c.records {
            self.0
                .record([
                    t.as_str(),
                    names[r.a].name.as_str(),
                    names[r.b].name.as_str(),
                    &r.gap.to_string(),
                    &r.force.to_string(),
                ])
                .context("cannot write contacts.csv")?;
        }
        Ok(())
    }

    /// Flush to disk.
    pub fn flush(&mut self) -> anyhow::Result<()> {
        self.0.flush().context("cannot write contacts.csv")
    }
}

/// The header of `timings.csv`.
pub const TIMINGS_HEADER: &str = "system,seconds_total,seconds_per_step";

/// Write `timings.csv` at `path` atomically: per system its total seconds and the seconds per
/// step over `steps` steps (at least 1), both to the microsecond.
pub fn write_timings(path: &Path, seconds: &[(&str, f64)], steps: u64) -> anyhow::Result<()> {
    let mut w = csv_writer(Vec::new());
    let mut write = || -> csv::Result<()> {
        w.write_record(TIMINGS_HEADER.split(','))?;
        for (name, s) in seconds {
            let per_step = s / steps.max(1) as f64;
            w.write_record([*name, &format!("{s:.6}"), &format!("{per_step:.6}")])?;
        }
        Ok(())
    };
    write().context("cannot write timings.csv")?;
    let bytes = w.into_inner().context("cannot write timings.csv")?;
    atomic_write(path, &bytes).context("cannot write timings.csv")
}
