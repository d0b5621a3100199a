//! `tumble run` under `mpirun` against the same run on one process.

#[path = "../suite/vti.rs"]
#[allow(dead_code)]
mod vti;

#[cfg(feature = "hdf5")]
use std::f64::consts::{PI, TAU};
use std::path::Path;
use std::process::Command;

/// `mpirun -np N`, oversubscribed (three processes on a two-core machine), with Open MPI's
/// consent to run as root (CI's shell).
pub fn mpirun(np: usize) -> Command {
    let mut cmd = Command::new("mpirun");
    cmd.args(["--oversubscribe", "-np", &np.to_string()]);
    // SAFETY: geteuid has no preconditions.
    if unsafe { libc::geteuid() } == 0 {
        cmd.arg("--allow-run-as-root");
    }
    cmd
}

/// A fresh directory for test `tag` holding the scene `text` as `file`.
fn scratch(tag: &str, file: &str, text: &str) -> Result<std::path::PathBuf, String> {
    let dir = std::env::temp_dir().join(format!("tumble-mpi-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).map_err(|e| e.to_string())?;
    std::fs::write(dir.join(file), text).map_err(|e| e.to_string())?;
    Ok(dir)
}

/// A Taylor-Green vortex at 24 x 20 x 36 with three snapshots, in double precision.
const SCENE: &str = r#"Scene(
    name: "tg",
    domain: (extent: [6.283185307179586, 5.235987755982989, 9.42477796076938], cells: [24, 20, 36]),
    fluid: (viscosity: 0.000625),
    numerics: (dt: Adaptive(c: 0.5, dt_max: 0.1), end_time: 0.6),
    initial: [TaylorGreen3d(amplitude: 1.0, wavenumber: 1.0)],
    output: (every: 0.3, precision: Double),
)"#;

/// `tumble run` on one process and under `mpirun -np 2` and `-np 3`: the same time series,
/// byte for byte, and the same snapshot arrays, bit for bit, read back from the pieces the
/// `.pvti` names (every sum over the grid is taken plane by plane in one order whatever the
/// split, and the fields are computed from the same values).
pub fn run_matches_one_process() -> Result<(), String> {
    let dir = scratch("run", "tg.ron", SCENE)?;
    run_in(&dir, "tg.ron", 1, "one")?;
    for np in [2, 3] {
        let out = format!("np{np}");
        run_in(&dir, "tg.ron", np, &out)?;
        same_files(&dir, "one", &out, &["series.csv"])?;
        same_snapshots(&dir, &out, 3)?;
    }
    let _ = std::fs::remove_dir_all(&dir);
    Ok(())
}

/// `checks::BODIES` (a channel, two spheres and an ellipsoid, two of them in contact within
/// the run) to t = 0.12, with snapshots and checkpoints every 0.06.
fn bodies_scene() -> String {
    super::checks::BODIES
        .replace("end_time: 1.0", "end_time: 0.12")
        .replace(
            "\n)",
            "\n    output: (every: 0.06, fields: [Omega, Velocity, Density], precision: Double, \
             checkpoint_every: 0.06),\n)",
        )
}

/// `tumble run` of `scene` (in `dir`) into `out`, under `mpirun -np np` when `np` > 1.
fn run_in(dir: &Path, scene: &str, np: usize, out: &str) -> Result<(), String> {
    let tumble = env!("CARGO_BIN_EXE_tumble");
    let mut cmd = if np > 1 {
        let mut c = mpirun(np);
        c.arg(tumble);
        c
    } else {
        Command::new(tumble)
    };
    let st = cmd
        .args(["run", "--quiet", "--out", out, scene])
        .current_dir(dir)
        .stdout(std::process::Stdio::null())
        .status()
        .map_err(|e| e.to_string())?;
    st.success()
        .then_some(())
        .ok_or(format!("{out}: tumble run failed ({st})"))
}

/// The files `names` of run directories `a` and `b` (in `dir`) are the same, byte for byte.
fn same_files(dir: &Path, a: &str, b: &str, names: &[&str]) -> Result<(), String> {
    for name in names {
        let x = std::fs::read(dir.join(a).join(name)).map_err(|e| format!("{a}/{name}: {e}"))?;
        let y = std::fs::read(dir.join(b).join(name)).map_err(|e| format!("{b}/{name}: {e}"))?;
        if x != y {
            return Err(format!("{b}/{name} differs from {a}/{name}"));
        }
    }
    Ok(())
}

/// The snapshots `0..count` of run `out` (in `dir`, in pieces) hold the arrays of the
/// one-process run `one`'s bit for bit.
fn same_snapshots(dir: &Path, out: &str, count: usize) -> Result<(), String> {
    for snap in 0..count {
        let whole = vti::read_vti(&dir.join(format!("one/fields_{snap:06}.vti")))
            .map_err(|e| e.to_string())?;
        let pieces = read_pvti(&dir.join(out).join(format!("fields_{snap:06}.pvti")))?;
        compare_exact(&whole, &pieces).map_err(|e| format!("{out} snapshot {snap}: {e}"))?;
    }
    Ok(())
}

/// The first checkpoint of run `out` (in `dir`): rank 0's file.
fn first_checkpoint(dir: &Path, out: &str) -> Result<std::path::PathBuf, String> {
    let ck = std::fs::read_dir(dir.join(out))
        .map_err(|e| e.to_string())?
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| n.starts_with("checkpoint_") && n.ends_with(".bin") && !n.contains("rank"))
        .min()
        .ok_or(format!("{out} wrote no checkpoint"))?;
    Ok(dir.join(out).join(ck))
}

/// The two-process run `np2` (in `dir`) copied to `full`, then restarted from its first
/// checkpoint to its end.
fn restart_np2_from_first_checkpoint(dir: &Path) -> Result<(), String> {
    let ck = first_checkpoint(dir, "np2")?;
    copy_dir(&dir.join("np2"), &dir.join("full"))?;
    restart(dir, ck)
}

/// Bodies on one process and under `mpirun -np 2` and `-np 3`: every sum over the grid is
/// taken plane by plane in the same order whatever the split, so `series.csv`, `bodies.csv`,
/// `contacts.csv` and the body surfaces (rank 0's) are the one-process run's byte for byte and the snapshots' arrays
/// (vorticity, velocity, density, χ, φ) bit for bit. Then the two-process run restarted from
/// its first checkpoint ends with the same files.
pub fn bodies_match_one_process_bit_for_bit() -> Result<(), String> {
    let dir = scratch("bodies", "bodies.ron", &bodies_scene())?;
    run_in(&dir, "bodies.ron", 1, "one")?;
    let csvs = [
        "series.csv",
        "bodies.csv",
        "contacts.csv",
        "bodies.pvd",
        "bodies_000000.vtp",
        "bodies_000002.vtp",
    ];
    let contacts = std::fs::read_to_string(dir.join("one/contacts.csv"))
        .map_err(|e| format!("one/contacts.csv: {e}"))?;
    if contacts.lines().count() < 10 {
        return Err("the bodies did not come into contact: the scene tests too little".into());
    }
    for np in [2, 3] {
        let out = format!("np{np}");
        run_in(&dir, "bodies.ron", np, &out)?;
        same_files(&dir, "one", &out, &csvs)?;
        same_snapshots(&dir, &out, 3)?;
    }
    restart_np2_from_first_checkpoint(&dir)?;
    same_files(&dir, "full", "np2", &csvs).map_err(|e| format!("after the restart: {e}"))?;
    let _ = std::fs::remove_dir_all(&dir);
    Ok(())
}

/// `checks::POOL` (a tank of water at 1:1000 with a light and a heavy sphere dropped into it)
/// to t = 0.6, with snapshots and checkpoints every 0.3: on one process and under
/// `mpirun -np 2` and `-np 3` the same `series.csv` (with the liquid's volume and area),
/// `bodies.csv`, `contacts.csv` and surfaces (the spheres and the free surface's zero level,
/// rank 0's from the whole level set) byte for byte, with the `hdf5` feature their HDF5 form
/// too ([`same_h5_surfaces`]), and the snapshots' arrays bit for bit; then the two-process run
/// restarted from its first checkpoint ends with the same files.
pub fn free_surface_matches_one_process_bit_for_bit() -> Result<(), String> {
    let scene = super::checks::POOL
        .replace("end_time: 1.0", "end_time: 0.6")
        .replace(
            "\n)",
            "\n    output: (every: 0.3, fields: [Velocity, Density], precision: Double, \
         checkpoint_every: 0.3),\n)",
        );
    // With HDF5, the surfaces' HDF5 form too (the free surface's part included).
    let scene = if cfg!(feature = "hdf5") {
        scene.replace(
            "checkpoint_every: 0.3)",
            "checkpoint_every: 0.3, formats: [Vtk, Hdf5])",
        )
    } else {
        scene
    };
    let dir = scratch("pool", "pool.ron", &scene)?;
    run_in(&dir, "pool.ron", 1, "one")?;
    let files = [
        "series.csv",
        "bodies.csv",
        "contacts.csv",
        "bodies.pvd",
        "bodies_000000.vtp",
        "bodies_000002.vtp",
    ];
    for np in [2, 3] {
        let out = format!("np{np}");
        run_in(&dir, "pool.ron", np, &out)?;
        same_files(&dir, "one", &out, &files)?;
        #[cfg(feature = "hdf5")]
        same_h5_surfaces(&dir, "one", &out, 3)?;
        same_snapshots(&dir, &out, 3)?;
    }
    restart_np2_from_first_checkpoint(&dir)?;
    same_files(&dir, "full", "np2", &files).map_err(|e| format!("after the restart: {e}"))?;
    #[cfg(feature = "hdf5")]
    same_h5_surfaces(&dir, "one", "np2", 3).map_err(|e| format!("after the restart: {e}"))?;
    let _ = std::fs::remove_dir_all(&dir);
    Ok(())
}

/// The body surfaces' HDF5 form in run directories `a` and `b` (in `dir`): `bodies.xmf` byte
/// for byte, and `snaps` files `bodies_NNNNNN.h5` (and no more) with the same datasets
/// ([`same_h5_datasets`]).
#[cfg(feature = "hdf5")]
fn same_h5_surfaces(dir: &Path, a: &str, b: &str, snaps: usize) -> Result<(), String> {
    same_files(dir, a, b, &["bodies.xmf"])?;
    for k in 0..snaps {
        let f = format!("bodies_{k:06}.h5");
        same_h5_datasets(&dir.join(a).join(&f), &dir.join(b).join(&f))?;
    }
    for d in [a, b] {
        let extra = dir.join(d).join(format!("bodies_{snaps:06}.h5"));
        if extra.exists() {
            return Err(format!("{} should not exist", extra.display()));
        }
    }
    Ok(())
}

/// `tumble validate` of two quick cases (Taylor-Green 3D, which splits, and a vacuum rebound)
/// under `mpirun -np 2` and on one process: the same report, line for line, but for the wall
/// times and the plots' directory.
pub fn validate_matches_one_process() -> Result<(), String> {
    let tumble = env!("CARGO_BIN_EXE_tumble");
    let dir = scratch("validate", "none.txt", "")?;
    let report = |np: usize| -> Result<Vec<String>, String> {
        let mut cmd = if np > 1 {
            let mut c = mpirun(np);
            c.arg(tumble);
            c
        } else {
            Command::new(tumble)
        };
        let plots = format!("plots{np}");
        let out = cmd
            .args(["validate", "taylor-green-3d", "rebound-vacuum", "--quick"])
            .args(["--threads", "1", "--plots", &plots])
            .current_dir(&dir)
            .output()
            .map_err(|e| e.to_string())?;
        if !out.status.success() {
            return Err(format!(
                "{np} processes: tumble validate failed ({})",
                out.status
            ));
        }
        Ok(String::from_utf8_lossy(&out.stdout)
            .lines()
            .filter(|l| !(l.trim_end().ends_with(" s)") || l.trim_start().starts_with("plot ")))
            .map(without_seconds)
            .collect())
    };
    let (one, two) = (report(1)?, report(2)?);
    let _ = std::fs::remove_dir_all(&dir);
    if one.len() < 4 || !one.iter().any(|l| l.starts_with("PASS taylor-green-3d")) {
        return Err(format!(
            "the one-process report is not the expected one: {one:?}"
        ));
    }
    match one.iter().zip(&two).find(|(a, b)| a != b) {
        Some((a, b)) => Err(format!("one process: `{a}`, two: `{b}`")),
        None if one.len() != two.len() => Err(format!(
            "{} lines on one process, {} on two",
            one.len(),
            two.len()
        )),
        None => Ok(()),
    }
}

/// `line` with every number of seconds (a number followed by the word `s`) replaced by `#`:
/// wall times differ between runs.
fn without_seconds(line: &str) -> String {
    let words: Vec<&str> = line.split(' ').collect();
    let seconds = |w: &str| matches!(w, "s" | "s;" | "s," | "s)" | "s.");
    words
        .iter()
        .enumerate()
        .map(|(i, w)| {
            let next_is_s = words.get(i + 1).is_some_and(|n| seconds(n));
            if next_is_s && w.parse::<f64>().is_ok() {
                "#"
            } else {
                w
            }
        })
        .collect::<Vec<_>>()
        .join(" ")
}

/// `mpirun -np 2 tumble run --restart FROM` (a run directory or rank 0's checkpoint) in `dir`.
fn restart(dir: &Path, from: impl AsRef<std::ffi::OsStr>) -> Result<(), String> {
    let st = mpirun(2)
        .arg(env!("CARGO_BIN_EXE_tumble"))
        .args(["run", "--quiet", "--restart"])
        .arg(from.as_ref())
        .current_dir(dir)
        .stdout(std::process::Stdio::null())
        .status()
        .map_err(|e| e.to_string())?;
    st.success().then_some(()).ok_or(format!(
        "the restart from {:?} failed ({st})",
        from.as_ref()
    ))
}

/// A copy of directory `from` (files only) at `to`.
fn copy_dir(from: &Path, to: &Path) -> Result<(), String> {
    std::fs::create_dir_all(to).map_err(|e| e.to_string())?;
    for e in std::fs::read_dir(from).map_err(|e| e.to_string())? {
        let e = e.map_err(|e| e.to_string())?;
        if e.path().is_file() {
            std::fs::copy(e.path(), to.join(e.file_name())).map_err(|e| e.to_string())?;
        }
    }
    Ok(())
}

/// The one-process snapshot's arrays against the pieces', bit for bit.
fn compare_exact(whole: &vti::VtiData, pieces: &Arrays) -> Result<(), String> {
    let names: Vec<&str> = whole.arrays.iter().map(|a| a.0.as_str()).collect();
    let piece_names: Vec<&str> = pieces.iter().map(|a| a.0.as_str()).collect();
    if names != piece_names {
        return Err(format!("arrays {names:?} against {piece_names:?}"));
    }
    for ((name, _, a), (_, _, b)) in whole.arrays.iter().zip(pieces) {
        let differ = a
            .iter()
            .zip(b)
            .filter(|(x, y)| x.to_bits() != y.to_bits())
            .count();
        if differ > 0 || a.len() != b.len() {
            return Err(format!("{name}: {differ} values differ"));
        }
    }
    Ok(())
}

/// A dataset's point arrays: (name, components, values interleaved per point).
type Arrays = Vec<(String, usize, Vec<f64>)>;

/// The arrays of a `.pvti` dataset, assembled from its pieces.
fn read_pvti(path: &Path) -> Result<Arrays, String> {
    let xml = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let doc = roxmltree::Document::parse(&xml).map_err(|e| e.to_string())?;
    let ext = |s: &str| -> Vec<usize> { s.split(' ').filter_map(|v| v.parse().ok()).collect() };
    let top = doc
        .descendants()
        .find(|n| n.has_tag_name("PImageData"))
        .ok_or("no PImageData")?;
    let w = ext(top.attribute("WholeExtent").ok_or("no WholeExtent")?);
    let (nx, ny, nz) = (w[1] + 1, w[3] + 1, w[5] + 1);
    let mut arrays: Arrays = Vec::new();
    for piece in doc.descendants().filter(|n| n.has_tag_name("Piece")) {
        let e = ext(piece.attribute("Extent").ok_or("no Extent")?);
        let src = path.with_file_name(piece.attribute("Source").ok_or("no Source")?);
        let data = vti::read_vti(&src).map_err(|e| format!("{}: {e}", src.display()))?;
        for (name, nc, values) in data.arrays {
            let at = match arrays.iter().position(|a| a.0 == name) {
                Some(i) => i,
                None => {
                    arrays.push((name, nc, vec![f64::NAN; nx * ny * nz * nc]));
                    arrays.len() - 1
                }
            };
            // The piece's planes e[4]..=e[5], each whole in x and y.
            let plane = nx * ny * nc;
            let dst = &mut arrays[at].2[e[4] * plane..(e[5] + 1) * plane];
            if values.len() != dst.len() {
                return Err(format!(
                    "{}: {} values for extent {e:?}",
                    src.display(),
                    values.len()
                ));
            }
            dst.copy_from_slice(&values);
        }
    }
    Ok(arrays)
}

/// A Taylor-Green vortex at 48³ with a checkpoint every 0.5 (20 steps) to t = 3.
const LONG_SCENE: &str = r#"Scene(
    name: "tg-long",
    domain: (extent: [6.283185307179586, 6.283185307179586, 6.283185307179586], cells: [48, 48, 48]),
    fluid: (viscosity: 0.000625),
    numerics: (dt: Adaptive(c: 0.5, dt_max: 0.025), end_time: 3.0),
    initial: [TaylorGreen3d(amplitude: 1.0, wavenumber: 1.0)],
    output: (every: 1.0, checkpoint_every: 0.5),
)"#;

/// The processes whose parent is `pid` (from /proc).
fn children(pid: u32) -> Vec<u32> {
    let Ok(dir) = std::fs::read_dir("/proc") else {
        return Vec::new();
    };
    dir.filter_map(|e| {
        let e = e.ok()?;
        let child: u32 = e.file_name().to_str()?.parse().ok()?;
        let stat = std::fs::read_to_string(e.path().join("stat")).ok()?;
        // pid (comm) state ppid ...: the fields after the last ')'.
        let ppid: u32 = stat
            .rsplit(')')
            .next()?
            .split_whitespace()
            .nth(1)?
            .parse()
            .ok()?;
        (ppid == pid).then_some(child)
    })
    .collect()
}

/// SIGKILL of one of two processes after the run's second checkpoint, then `--restart` of the
/// run directory on two processes: `series.csv`, the last snapshot's pieces and the last
/// checkpoint's pieces are those of an uninterrupted two-process run, byte for byte.
pub fn killed_and_restarted_is_bit_identical() -> Result<(), String> {
    let tumble = env!("CARGO_BIN_EXE_tumble");
    let dir = scratch("kill", "tg.ron", LONG_SCENE)?;
    let start = |out: &str| {
        let mut c = mpirun(2);
        c.arg(tumble)
            .args(["run", "--quiet", "--out", out, "tg.ron"])
            .current_dir(&dir)
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null());
        c
    };
    let st = start("full").status().map_err(|e| e.to_string())?;
    if !st.success() {
        return Err(format!("the uninterrupted run failed ({st})"));
    }
    let mut job = start("killed").spawn().map_err(|e| e.to_string())?;
    let piece = dir.join("killed/checkpoint_000040.rank1of2.bin");
    let t0 = std::time::Instant::now();
    while !piece.is_file() {
        if t0.elapsed().as_secs() > 120 || job.try_wait().map_err(|e| e.to_string())?.is_some() {
            let _ = job.kill();
            return Err("the run ended or stalled before its second checkpoint".into());
        }
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    let ranks = children(job.id());
    let victim = *ranks.last().ok_or("mpirun started no process to kill")?;
    // SAFETY: kill has no memory preconditions; the pid is a child of our mpirun.
    unsafe { libc::kill(victim as i32, libc::SIGKILL) };
    let st = job.wait().map_err(|e| e.to_string())?;
    if st.success() {
        return Err("the run ended before one of its processes was killed".into());
    }
    restart(&dir, "killed")?;
    for file in [
        "series.csv",
        "fields_000003.pvti",
        "fields_000003_0.vti",
        "fields_000003_1.vti",
        "checkpoint_000120.bin",
        "checkpoint_000120.rank1of2.bin",
    ] {
        let a =
            std::fs::read(dir.join("full").join(file)).map_err(|e| format!("full/{file}: {e}"))?;
        let b = std::fs::read(dir.join("killed").join(file))
            .map_err(|e| format!("killed/{file}: {e}"))?;
        if a != b {
            return Err(format!("{file} differs from the uninterrupted run's"));
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    Ok(())
}

/// A scene that cannot split (bodies coupled by the baroclinic term) under `mpirun -np 2`: exit
/// status 2, no run directory.
pub fn unsplittable_scene_is_refused_and_writes_nothing() -> Result<(), String> {
    let tumble = env!("CARGO_BIN_EXE_tumble");
    let scene = r#"Scene(
    domain: (extent: [1.0, 1.0, 1.0], cells: [16, 16, 16]),
    fluid: (viscosity: 0.01, gravity: [0.0, 0.0, -9.8]),
    numerics: (end_time: 0.01, body_coupling: Baroclinic),
    bodies: [(name: "ball", shape: Sphere(radius: 0.2), density: 2.0, position: [0.5, 0.5, 0.5])],
)"#;
    let dir = scratch("refused", "ball.ron", scene)?;
    let st = mpirun(2)
        .arg(tumble)
        .args(["run", "--quiet", "--out", "out", "ball.ron"])
        .current_dir(&dir)
        .stderr(std::process::Stdio::null())
        .status()
        .map_err(|e| e.to_string())?;
    let written = dir.join("out").exists();
    let _ = std::fs::remove_dir_all(&dir);
    match (st.code(), written) {
        (Some(2), false) => Ok(()),
        (code, written) => Err(format!(
            "exit status {code:?} (2 expected), run directory written: {written}"
        )),
    }
}

/// Under `mpirun -np 2`, `tumble check` (a command that does not split its work) refuses with
/// exit status 2 instead of running once per process.
pub fn other_commands_refuse_several_processes() -> Result<(), String> {
    let tumble = env!("CARGO_BIN_EXE_tumble");
    let dir = scratch("check", "tg.ron", SCENE)?;
    let st = mpirun(2)
        .arg(tumble)
        .args(["check", "tg.ron"])
        .current_dir(&dir)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .status()
        .map_err(|e| e.to_string())?;
    let _ = std::fs::remove_dir_all(&dir);
    match st.code() {
        Some(2) => Ok(()),
        code => Err(format!("exit status {code:?}, 2 expected")),
    }
}

/// A Taylor-Green vortex at 24 x 20 x 37 (slabs of 19 and 18 planes on two processes, 13, 12
/// and 12 on three) with three HDF5 snapshots in double precision, and no VTK.
#[cfg(feature = "hdf5")]
const HDF5_SCENE: &str = r#"Scene(
    name: "tg-h5",
    domain: (extent: [6.283185307179586, 5.235987755982989, 9.686577348568527], cells: [24, 20, 37]),
    fluid: (viscosity: 0.000625),
    numerics: (dt: Adaptive(c: 0.5, dt_max: 0.1), end_time: 0.6),
    initial: [TaylorGreen3d(amplitude: 1.0, wavenumber: 1.0)],
    output: (every: 0.3, checkpoint_every: 0.3, precision: Double, formats: [Hdf5]),
)"#;

/// The box of [`HDF5_SCENE`]'s volume.
#[cfg(feature = "hdf5")]
const H5_VOLUME: f64 = TAU * (5.0 * PI / 3.0) * (37.0 * PI / 12.0);

/// `tumble run` of an HDF5 scene on one process and under `mpirun -np 2` and `-np 3`, each
/// split run then restarted from its first checkpoint (its last snapshot and `series.h5`'s
/// later rows written again) and its directory moved: its `fields_NNNNNN.h5`, read through
/// the HDF5 library, hold virtual datasets with the one-process file's names, shapes, types
/// and root attributes, and values within 1e-12 of the largest; `fields.xmf` is the
/// one-process index, and `series.h5` (rank 0's) the one-process series to 1e-12.
#[cfg(feature = "hdf5")]
pub fn hdf5_matches_one_process() -> Result<(), String> {
    use hdf5::dataset::Layout;
    let tumble = env!("CARGO_BIN_EXE_tumble");
    let dir = scratch("hdf5", "tg.ron", HDF5_SCENE)?;
    let run = |np: usize, args: &[&str]| -> Result<(), String> {
        let mut cmd = if np == 1 {
            Command::new(tumble)
        } else {
            let mut c = mpirun(np);
            c.arg(tumble);
            c
        };
        let st = cmd
            .args(["run", "--quiet"])
            .args(args)
            .current_dir(&dir)
            .stdout(std::process::Stdio::null())
            .status()
            .map_err(|e| e.to_string())?;
        st.success().then_some(()).ok_or(format!(
            "tumble run {args:?} on {np} processes failed ({st})"
        ))
    };
    let h5 = |e: hdf5::Error| e.to_string();
    run(1, &["--out", "one", "tg.ron"])?;
    let one = dir.join("one");
    let xmf = |d: &Path| {
        std::fs::read_to_string(d.join("fields.xmf")).map_err(|e| format!("fields.xmf: {e}"))
    };
    for np in [2, 3] {
        let out = format!("np{np}");
        run(np, &["--out", &out, "tg.ron"])?;
        let first = std::fs::read_dir(dir.join(&out))
            .map_err(|e| e.to_string())?
            .filter_map(|e| e.ok()?.file_name().into_string().ok())
            .filter(|n| n.starts_with("checkpoint_") && !n.contains(".rank"))
            .min()
            .ok_or(format!("{out}: no checkpoint"))?;
        run(np, &["--restart", &format!("{out}/{first}")])?;
        // The run directory moves: the virtual datasets name their pieces relative to it.
        let moved = dir.join(format!("moved{np}"));
        std::fs::rename(dir.join(&out), &moved).map_err(|e| e.to_string())?;
        if xmf(&moved)? != xmf(&one)? {
            return Err(format!(
                "{out}: fields.xmf differs from the one-process index"
            ));
        }
        for snap in 0..3 {
            let name = format!("fields_{snap:06}.h5");
            let a = hdf5::File::open(one.join(&name)).map_err(h5)?;
            let b = hdf5::File::open(moved.join(&name)).map_err(h5)?;
            let what = |s: &str| format!("{out}/{name}: {s}");
            let names = a.member_names().map_err(h5)?;
            if names != b.member_names().map_err(h5)? || names.is_empty() {
                return Err(what(&format!(
                    "datasets {names:?} against {:?}",
                    b.member_names()
                )));
            }
            for attr in ["time", "step", "origin", "spacing", "dims"] {
                let (x, y) = (a.attr(attr).map_err(h5)?, b.attr(attr).map_err(h5)?);
                let same = match attr {
                    "step" | "dims" => x.read_raw::<u64>().ok() == y.read_raw::<u64>().ok(),
                    _ => x.read_raw::<f64>().ok() == y.read_raw::<f64>().ok(),
                };
                if !same {
                    return Err(what(&format!("attribute {attr} differs")));
                }
            }
            for n in &names {
                let (x, y) = (a.dataset(n).map_err(h5)?, b.dataset(n).map_err(h5)?);
                if y.layout() != Layout::Virtual {
                    return Err(what(&format!("{n} is not a virtual dataset")));
                }
                if x.shape() != y.shape() || x.dtype().map_err(h5)? != y.dtype().map_err(h5)? {
                    return Err(what(&format!(
                        "{n}: shape {:?} against {:?}",
                        x.shape(),
                        y.shape()
                    )));
                }
                let (x, y) = (
                    x.read_raw::<f64>().map_err(h5)?,
                    y.read_raw::<f64>().map_err(h5)?,
                );
                let scale = x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                let d = x
                    .iter()
                    .zip(&y)
                    .fold(0.0f64, |m, (p, q)| m.max((p - q).abs()));
                let nan = y.iter().any(|v| v.is_nan());
                if x.len() != y.len() || nan || d > 1e-12 * scale || scale == 0.0 {
                    return Err(what(&format!("{n}: max difference {d:e} of {scale:e}")));
                }
            }
        }
        let series = |d: &Path| -> Result<Vec<Vec<f64>>, String> {
            let f = hdf5::File::open(d.join("series.h5")).map_err(h5)?;
            ["t", "dt", "energy", "enstrophy", "circulation", "max_omega"]
                .iter()
                .map(|c| f.dataset(&format!("series/{c}")).and_then(|s| s.read_raw()))
                .collect::<Result<_, _>>()
                .map_err(h5)
        };
        let (a, b) = (series(&one)?, series(&moved)?);
        for (c, (x, y)) in a.iter().zip(&b).enumerate() {
            if x.len() != y.len() || x.is_empty() {
                return Err(format!(
                    "{out}/series.h5: {} rows, one process {}",
                    y.len(),
                    x.len()
                ));
            }
            for (i, (p, q)) in x.iter().zip(y).enumerate() {
                // The circulation, zero up to round-off, against max|ω| times the volume.
                let scale = if c == 4 {
                    a[5][i] * H5_VOLUME
                } else {
                    p.abs().max(q.abs()).max(1e-300)
                };
                if q.is_nan() || (p - q).abs() > 1e-12 * scale {
                    return Err(format!(
                        "{out}/series.h5 column {c} row {i}: {p} against {q}"
                    ));
                }
            }
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    Ok(())
}

/// The datasets of HDF5 file `b` are those of `a`: the same names (some), and for each the
/// same shape, type and values bit for bit; so are the root attributes `time`, `step` and
/// `part_names` (the files themselves may differ in HDF5's object times).
#[cfg(feature = "hdf5")]
fn same_h5_datasets(a: &Path, b: &Path) -> Result<(), String> {
    use hdf5::types::{TypeDescriptor, VarLenUnicode};
    let h5 = |e: hdf5::Error| format!("{}: {e}", b.display());
    let (x, y) = (
        hdf5::File::open(a).map_err(|e| format!("{}: {e}", a.display()))?,
        hdf5::File::open(b).map_err(h5)?,
    );
    let what = |s: String| format!("{} against {}: {s}", b.display(), a.display());
    let names = x.member_names().map_err(h5)?;
    if names.is_empty() || names != y.member_names().map_err(h5)? {
        return Err(what(format!(
            "datasets {:?} against {names:?}",
            y.member_names()
        )));
    }
    let time = |f: &hdf5::File| f.attr("time").and_then(|t| t.read_scalar::<f64>());
    let step = |f: &hdf5::File| f.attr("step").and_then(|t| t.read_scalar::<u64>());
    let parts = |f: &hdf5::File| {
        f.attr("part_names")
            .and_then(|t| t.read_raw::<VarLenUnicode>())
            .map(|v| v.iter().map(|s| s.as_str().to_string()).collect::<Vec<_>>())
    };
    if time(&x).map_err(h5)?.to_bits() != time(&y).map_err(h5)?.to_bits()
        || step(&x).map_err(h5)? != step(&y).map_err(h5)?
        || parts(&x).map_err(h5)? != parts(&y).map_err(h5)?
    {
        return Err(what("the root attributes differ".into()));
    }
    for n in &names {
        let (p, q) = (x.dataset(n).map_err(h5)?, y.dataset(n).map_err(h5)?);
        let (tp, tq) = (p.dtype().map_err(h5)?, q.dtype().map_err(h5)?);
        if p.shape() != q.shape() || tp != tq {
            return Err(what(format!(
                "{n}: shape {:?} against {:?}",
                q.shape(),
                p.shape()
            )));
        }
        let same = match tp.to_descriptor().map_err(h5)? {
            TypeDescriptor::Float(_) => {
                let bits = |d: &hdf5::Dataset| {
                    d.read_raw::<f64>()
                        .map(|v| v.iter().map(|f| f.to_bits()).collect::<Vec<_>>())
                };
                bits(&p).map_err(h5)? == bits(&q).map_err(h5)?
            }
            TypeDescriptor::Integer(_) => {
                p.read_raw::<i64>().map_err(h5)? == q.read_raw::<i64>().map_err(h5)?
            }
            t => return Err(what(format!("{n}: unexpected type {t:?}"))),
        };
        if !same {
            return Err(what(format!("{n}: the values differ")));
        }
    }
    Ok(())
}

/// [`bodies_scene`] with HDF5 output (and no VTK) on one process and under `mpirun -np 2` and
/// `-np 3`: rank 0 writes the body surfaces' HDF5 form, `bodies_NNNNNN.h5` with the
/// one-process files' datasets and attributes bit for bit and `bodies.xmf` byte for byte (as
/// are `bodies.pvd` and the `.vtp`). Then the two-process run, its third surfaces snapshot
/// spoilt, restarted from its first checkpoint: the later snapshot is written again and
/// `bodies.xmf` lists each snapshot once, the same files again.
#[cfg(feature = "hdf5")]
pub fn hdf5_bodies_match_one_process() -> Result<(), String> {
    let scene = bodies_scene().replace(
        "checkpoint_every: 0.06)",
        "checkpoint_every: 0.06, formats: [Hdf5])",
    );
    if !scene.contains("formats: [Hdf5]") {
        return Err("the bodies scene's output changed: no HDF5 asked for".into());
    }
    let dir = scratch("hdf5-bodies", "bodies.ron", &scene)?;
    run_in(&dir, "bodies.ron", 1, "one")?;
    let snaps: Vec<String> = (0..)
        .map(|k| format!("bodies_{k:06}.h5"))
        .take_while(|f| dir.join("one").join(f).is_file())
        .collect();
    if snaps.len() != 3 {
        return Err(format!(
            "one process wrote {} bodies_*.h5, not 3",
            snaps.len()
        ));
    }
    let check = |out: &str| -> Result<(), String> {
        same_files(&dir, "one", out, &["bodies.pvd", "bodies_000002.vtp"])?;
        same_h5_surfaces(&dir, "one", out, snaps.len())
    };
    for np in [2, 3] {
        let out = format!("np{np}");
        run_in(&dir, "bodies.ron", np, &out)?;
        check(&out)?;
    }
    // The restart from the first of the two-process run's checkpoints.
    let ck = first_checkpoint(&dir, "np2")?;
    let last = dir.join("np2").join(&snaps[2]);
    std::fs::write(&last, b"not a snapshot").map_err(|e| e.to_string())?;
    restart(&dir, ck)?;
    check("np2").map_err(|e| format!("after the restart: {e}"))?;
    let _ = std::fs::remove_dir_all(&dir);
    Ok(())
}
