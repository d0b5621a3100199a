//! `tumble mesh`: closed triangle meshes for `Mesh` bodies.

use crate::bodies::meshgen::CupParams;
use clap::Subcommand;
use std::path::PathBuf;

#[derive(Subcommand)]
pub enum MeshShape {
    /// A cup: a solid of revolution about z (outer wall, flat bottom, open top with a flat
    /// rim), its centre of volume at the origin. Lengths in scene units.
    Cup {
        /// Outer radius R.
        #[arg(long, default_value_t = CupParams::default().radius)]
        radius: f64,
        /// Total height H, base to rim.
        #[arg(long, default_value_t = CupParams::default().height)]
        height: f64,
        /// Wall thickness t (inner radius R - t).
        #[arg(long, default_value_t = CupParams::default().wall)]
        wall: f64,
        /// Bottom thickness b.
        #[arg(long, default_value_t = CupParams::default().bottom)]
        bottom: f64,
        /// Sides of the polygons standing for the circles (at least 8).
        #[arg(long, default_value_t = CupParams::default().segments)]
        segments: u32,
        /// The file to write: .obj (Wavefront OBJ) or .stl (binary STL), by its extension.
        #[arg(long, value_name = "FILE")]
        out: PathBuf,
        /// Replace FILE if it exists and tumble wrote it (its header says so).
        #[arg(long)]
        force: bool,
    },
}

/// `tumble mesh`: write the mesh asked for.
pub fn mesh(shape: MeshShape) -> u8 {
    let MeshShape::Cup {
        radius,
        height,
        wall,
        bottom,
        segments,
        out,
        force,
    } = shape;
    let params = CupParams {
        radius,
        height,
        wall,
        bottom,
        segments,
    };
    match write_cup(&params, &out, force) {
        Ok(summary) => {
            println!("{summary}");
            0
        }
        Err(e) => {
            eprintln!("error: {e:#}");
            2
        }
    }
}

const MESH_MARK: &str = "tumble mesh ";

/// Writes the cup `params` to `out` (.obj or .stl by extension); refuses to replace an existing
/// file unless `force` is set and the file starts with [`MESH_MARK`] (tumble wrote it).
fn write_cup(params: &CupParams, out: &std::path::Path, force: bool) -> anyhow::Result<String> {
    use anyhow::{Context, bail};
    use std::io::{Read, Write};
    let ext = out
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase());
    let obj = match ext.as_deref() {
        Some("obj") => true,
        Some("stl") => false,
        _ => bail!(
            "{}: unsupported mesh format (the file name must end in .obj or .stl)",
            out.display()
        ),
    };
    let mesh = params.mesh().map_err(anyhow::Error::msg)?;
    let command = format!(
        "{MESH_MARK}cup --radius {} --height {} --wall {} --bottom {} --segments {}",
        params.radius, params.height, params.wall, params.bottom, params.segments
    );
    let bytes = if obj {
        let header = format!(
            "{command}\nclosed, outward oriented; axis z, centre of volume at the origin; {} vertices, {} triangles",
            mesh.vertices.len(),
            mesh.triangles.len()
        );
        mesh.to_obj(&header).into_bytes()
    } else {
        mesh.to_binary_stl(&command)
    };
    let mut file = match std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(out)
    {
        Ok(f) => f,
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
            if !force {
                bail!(
                    "{} exists; pass --force to replace it (only a file tumble mesh wrote)",
                    out.display()
                );
            }
            let mut head = vec![0u8; MESH_MARK.len() + 2];
            let n = std::fs::File::open(out)
                .and_then(|mut f| f.read(&mut head))
                .with_context(|| format!("cannot read {}", out.display()))?;
            let head = &head[..n];
            let ours = head.starts_with(MESH_MARK.as_bytes())
                || head
                    .strip_prefix(b"# ")
                    .is_some_and(|h| h.starts_with(MESH_MARK.as_bytes()));
            if !ours {
                bail!(
                    "{} exists and tumble did not write it (it does not start with `{MESH_MARK}`); not replacing it",
                    out.display()
                );
            }
            std::fs::File::create(out).with_context(|| format!("cannot write {}", out.display()))?
        }
        Err(e) => return Err(e).with_context(|| format!("cannot create {}", out.display())),
    };
    file.write_all(&bytes)
        .and_then(|()| file.sync_all())
        .with_context(|| format!("cannot write {}", out.display()))?;
    Ok(format!(
        "wrote {} ({} vertices, {} triangles, volume {:.6e})",
        out.display(),
        mesh.vertices.len(),
        mesh.triangles.len(),
        params.volume()
    ))
}
