//! The crate's modules are layers and dependencies point one way (README, "The code"): a file
//! may name `crate::m` only for a module `m` of its own layer or a lower one. This test reads
//! every source file and fails on any reference that points up, so a cycle cannot come back;
//! and no file in `systems/` names another system.

use std::fs;
use std::path::{Path, PathBuf};

/// The layers, lowest first. A module may use its own layer and every layer before it.
const LAYERS: &[&[&str]] = &[
    &["base"],
    &["parallel"],
    &["solvers"],
    &["bodies"],
    &["schedule"],
    &["systems"],
    &["scene"],
    &["sim"],
    &["io"],
    &["run"],
    &["validate"],
    &["cli"],
];

fn rank(module: &str) -> Option<usize> {
    LAYERS.iter().position(|l| l.contains(&module))
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// The layer a file belongs to: `systems/x.rs` is `systems`, `src/m/x.rs` and `src/m.rs` are `m`.
fn module_of(root: &Path, file: &Path) -> Option<String> {
    let rel = file.strip_prefix(root).ok()?;
    let parts: Vec<_> = rel
        .iter()
        .map(|s| s.to_string_lossy().into_owned())
        .collect();
    match parts.as_slice() {
        [top, ..] if top == "systems" => Some("systems".into()),
        [src, name] if src == "src" => Some(name.trim_end_matches(".rs").to_string()),
        [src, dir, ..] if src == "src" => Some(dir.clone()),
        _ => None,
    }
}

#[test]
fn dependencies_point_down_the_layers() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = Vec::new();
    rust_files(&root.join("src"), &mut files);
    rust_files(&root.join("systems"), &mut files);
    let mut bad = Vec::new();
    let mut checked = 0;
    for f in &files {
        let Some(own) = module_of(root, f) else {
            continue;
        };
        let Some(own_rank) = rank(&own) else {
            // lib.rs and main.rs sit on top of every layer.
            assert!(
                own == "lib" || own == "main",
                "{} belongs to no layer: add its module to LAYERS",
                f.display()
            );
            continue;
        };
        checked += 1;
        let text = fs::read_to_string(f).unwrap();
        for (ln, line) in text.lines().enumerate() {
            let mut rest = line;
            while let Some(i) = rest.find("crate::") {
                let after = &rest[i + "crate::".len()..];
                let name: String = after
                    .chars()
                    .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                    .collect();
                if let Some(r) = rank(&name)
                    && r > own_rank
                {
                    bad.push(format!(
                        "{}:{}: `{own}` uses `crate::{name}` (a higher layer)",
                        f.strip_prefix(root).unwrap().display(),
                        ln + 1
                    ));
                }
                rest = after;
            }
        }
    }
    assert!(checked > 30, "only {checked} files were checked");
    assert!(
        bad.is_empty(),
        "dependencies pointing up:\n{}",
        bad.join("\n")
    );
}

/// The systems share no code with each other: a file in `systems/` names no sibling
/// (`crate::systems::x`, or `super::x` from the top of the file); what two systems share lives
/// in a lower layer (the curl and the line sweeps in `solvers`, the body integrals and the
/// pressure coupling's state in `bodies`, the run's failure in `base::fields`). Only
/// `systems/mod.rs`, which lists them, names them.
#[test]
fn systems_do_not_import_each_other() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("systems");
    let mut files = Vec::new();
    rust_files(&dir, &mut files);
    let siblings: Vec<String> = files
        .iter()
        .filter_map(|f| f.file_stem())
        .map(|s| s.to_string_lossy().into_owned())
        .filter(|s| s != "mod")
        .collect();
    assert!(siblings.len() > 10, "only {} systems found", siblings.len());
    let mut bad = Vec::new();
    for f in files.iter().filter(|f| !f.ends_with("mod.rs")) {
        let text = fs::read_to_string(f).unwrap();
        for (ln, line) in text.lines().enumerate() {
            let names_parent = line.contains("crate::systems::")
                || line.starts_with("use super::")
                || line.starts_with("pub use super::")
                || line.match_indices("super::").any(|(i, _)| {
                    let after = &line[i + "super::".len()..];
                    let name: String = after
                        .chars()
                        .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                        .collect();
                    name == "super" || siblings.contains(&name)
                });
            if names_parent {
                bad.push(format!(
                    "systems/{}:{}: {}",
                    f.file_name().unwrap().to_string_lossy(),
                    ln + 1,
                    line.trim()
                ));
            }
        }
    }
    assert!(
        bad.is_empty(),
        "a system names another system (move what they share to a lower layer):\n{}",
        bad.join("\n")
    );
}
