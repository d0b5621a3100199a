//! The run directory: where a run writes, and when `--force` may replace what is there.
//!
//! tumble writes a marker file, [`MARKER`], into every run directory it creates, and `--force`
//! only ever replaces a directory that carries it. Anything else (a directory of the user's
//! files, the current directory or one holding it, the home directory, a symbolic link) is
//! refused with a [`BadOutputDir`] and nothing is touched. A scene file may name its run
//! directory (`output.dir`) only below the directory tumble runs in: a scene someone sends
//! cannot point a run, let alone `--force`, at `/` or `../..`.

use super::{BadOutputDir, RunOptions};
use crate::scene::Scene;
use std::path::{Component, Path, PathBuf};

/// The marker file in every run directory tumble creates.
pub const MARKER: &str = ".tumble-run";

/// What the marker file says to someone who finds it.
const MARKER_TEXT: &str = "This directory was made by `tumble run` and holds the outputs of one run.\n\
`tumble run --force` deletes and rewrites a directory only if it holds this file\n\
(.tumble-run); delete this file to keep tumble from ever replacing the directory.\n";

fn bad(m: String) -> anyhow::Error {
    anyhow::Error::new(BadOutputDir(m))
}

/// The run directory of `scene` under `opts`: `--out` as given, else the scene's `output.dir`
/// (which must be a relative path below the current directory, without `..`), else
/// `runs/<name>`.
pub fn resolve(scene: &Scene, opts: &RunOptions) -> anyhow::Result<PathBuf> {
    match (&opts.out, &scene.output.dir) {
        (Some(d), _) => Ok(d.clone()),
        (None, Some(d)) => {
            let p = PathBuf::from(d);
            let comps: Vec<Component> = p.components().collect();
            let why = if p.is_absolute() || p.has_root() {
                Some("is an absolute path")
            } else if comps.iter().any(|c| matches!(c, Component::ParentDir)) {
                Some("contains `..`")
            } else if !comps.iter().any(|c| matches!(c, Component::Normal(_))) {
                Some("names the current directory")
            } else {
                None
            };
            match why {
                Some(why) => Err(bad(format!(
                    "the scene's output.dir \"{d}\" {why}; a scene may only name a directory \
                     below the current one, so that a scene file cannot make tumble write \
                     elsewhere; to write there on purpose, give it on the command line with \
                     --out"
                ))),
                None => Ok(p),
            }
        }
        (None, None) => Ok(Path::new("runs").join(&scene.name)),
    }
}

/// Whether `dir` holds the marker of a run directory (a regular file, not a link).
pub fn is_run_dir(dir: &Path) -> bool {
    std::fs::symlink_metadata(dir.join(MARKER)).is_ok_and(|m| m.is_file())
}

/// Why `--force` must not replace the existing directory `dir`, if it must not.
fn refuse_replace(dir: &Path) -> Option<String> {
    let shown = dir.display();
    if std::fs::symlink_metadata(dir).is_ok_and(|m| m.file_type().is_symlink()) {
        return Some(format!(
            "the output directory {shown} is a symbolic link; --force replaces only a run \
             directory tumble made itself, so it is left alone; choose another --out"
        ));
    }
    let canon = std::fs::canonicalize(dir).ok();
    let cwd = std::env::current_dir()
        .ok()
        .and_then(|d| std::fs::canonicalize(d).ok());
    let home = std::env::var_os("HOME")
        .filter(|h| !h.is_empty())
        .and_then(|h| std::fs::canonicalize(h).ok());
    if let Some(c) = &canon {
        if c.parent().is_none() {
            return Some(format!(
                "the output directory {shown} is the root directory; --force will not replace \
                 it; choose another --out"
            ));
        }
        if cwd.as_ref().is_some_and(|w| w.starts_with(c)) {
            return Some(format!(
                "the output directory {shown} is the current directory or holds it; --force \
                 will not replace it; choose another --out (for example runs/<name>)"
            ));
        }
        if home.as_ref().is_some_and(|h| h == c) {
            return Some(format!(
                "the output directory {shown} is the home directory; --force will not replace \
                 it; choose another --out"
            ));
        }
    }
    if !is_run_dir(dir) {
        return Some(format!(
            "the output directory {shown} was not made by tumble (it has no {MARKER} marker \
             file), so --force will not delete it; choose another --out, or move or delete \
             the directory yourself if its contents can go"
        ));
    }
    None
}

/// Resolve the run directory and make it, with its marker. An existing directory is
/// replaced only with `force` and only if it is a run directory tumble made (see the module
/// notes); otherwise nothing is touched and the error is a [`BadOutputDir`].
pub fn prepare_dir(scene: &Scene, opts: &RunOptions) -> anyhow::Result<PathBuf> {
    let dir = resolve(scene, opts)?;
    let shown = dir.display();
    if std::fs::symlink_metadata(&dir).is_ok() {
        if !dir.is_dir() {
            return Err(bad(format!(
                "the output directory {shown} is a file, not a directory; choose another --out"
            )));
        }
        if !opts.force {
            return Err(bad(if is_run_dir(&dir) {
                format!(
                    "the output directory {shown} exists (an earlier run); pass --force to \
                     replace it or --out to choose another"
                )
            } else {
                format!(
                    "the output directory {shown} exists and was not made by tumble (it has \
                     no {MARKER} marker file); choose another --out"
                )
            }));
        }
        if let Some(why) = refuse_replace(&dir) {
            return Err(bad(why));
        }
        std::fs::remove_dir_all(&dir).map_err(|e| {
            bad(format!(
                "cannot remove the old output directory {shown}: {e}"
            ))
        })?;
    }
    std::fs::create_dir_all(&dir).map_err(|e| {
        bad(format!(
            "cannot create the output directory {shown}: {}",
            crate::io::output::disk_full(&dir, e)
        ))
    })?;
    let marker = dir.join(MARKER);
    std::fs::write(&marker, MARKER_TEXT).map_err(|e| {
        bad(format!(
            "cannot write {}: {}",
            marker.display(),
            crate::io::output::disk_full(&marker, e)
        ))
    })?;
    Ok(dir)
}
