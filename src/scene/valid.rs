//! [`ValidScene`]: a scene that passed every check. Reading a file ([`Scene::load`]), parsing
//! text ([`Scene::parse`]) and changing a valid scene ([`ValidScene::edit`]) all end in the one
//! check (`check_scene` in `check.rs`), and nothing else makes a `ValidScene`. It carries the
//! scene's defaults resolved ([`Resolved`]), so nothing downstream works them out again.

use super::check::check_scene;
use super::error::{SceneError, offset_of, path_at};
use super::format::Scene;
use super::resolved::Resolved;
use crate::base::grid::Grid;
use crate::bodies::contact::KappaDefault;
use crate::bodies::shapes::ShapeGeometry;
use crate::schedule::{PluginSections, SceneSection};
use std::path::Path;

/// The largest liquid/gas density ratio at which the free-surface validation cases were run
/// and pass: air and water (issue 44, the momentum form: still pool, collapsing column,
/// spheres dropped onto a pool, standing wave at h = 1/128).
pub const MAX_TESTED_RATIO: f64 = 1000.0;

/// A scene whose values, meshes and initial placement have been checked, with its grid, its
/// bodies' shapes and its resolved defaults. Read it as a [`Scene`] (it dereferences to one);
/// change it with [`ValidScene::edit`].
#[derive(Debug, Clone)]
pub struct ValidScene {
    scene: Scene,
    grid: Grid,
    geoms: Vec<ShapeGeometry>,
    resolved: Resolved,
    file: String,
    /// The line of `free_surface.gas_density` in the text read, for the warnings.
    gas_line: Option<usize>,
    /// Where each plugin section starts in the text read (1-based line and column).
    plugin_at: Vec<(String, (usize, usize))>,
}

impl std::ops::Deref for ValidScene {
    type Target = Scene;
    fn deref(&self) -> &Scene {
        &self.scene
    }
}

impl ValidScene {
    /// The grid this scene runs on.
    pub fn grid(&self) -> Grid {
        self.grid.clone()
    }

    /// The bodies' shapes (meshes read), in the order of `bodies`.
    pub fn geometries(&self) -> &[ShapeGeometry] {
        &self.geoms
    }

    /// Its defaults, resolved when it was checked: the bodies' densities, the contact model,
    /// the engine's parameters (see [`Resolved`]).
    pub fn resolved(&self) -> &Resolved {
        &self.resolved
    }

    /// The default κ of its pairs (used where neither `contact.kappa` nor the bodies give
    /// one), see [`crate::scene::kappa`].
    pub fn kappa_default(&self) -> &KappaDefault {
        &self.resolved.contact.default
    }

    /// The warnings of its values (bodies much lighter or heavier than the fluid for their
    /// coupling, baroclinic options that do not act; see `Scene::warnings` in `check.rs`), and
    /// a free surface whose density ratio is beyond [`MAX_TESTED_RATIO`], the largest at which
    /// the free-surface gates were run and pass (naming the scene's line).
    pub fn warnings(&self) -> Vec<String> {
        let mut out = self.scene.warnings(&self.resolved.densities);
        if let Some(fs) = &self.scene.free_surface {
            let ratio = self.scene.fluid.density / fs.gas_density;
            if ratio > MAX_TESTED_RATIO * (1.0 + 1e-9) {
                let at = match self.gas_line {
                    Some(l) => format!("{}, line {l}", self.file),
                    None => self.file.clone(),
                };
                out.push(format!(
                    "{at}: `free_surface.gas_density` makes a liquid/gas density ratio of 1:{ratio:.0}, beyond 1:{MAX_TESTED_RATIO:.0}, the largest at which the free-surface validation cases were run and pass (air and water: still pool, collapsing column, spheres dropped onto a pool); expect a noisy surface or a blow-up"
                ));
            }
        }
        out
    }

    /// The file the scene was read from (as named in errors).
    pub fn file(&self) -> &str {
        &self.file
    }

    /// The scene with `change` applied, checked again as a whole (e.g. another end time or
    /// grid). Errors name the field but no line: the text is no longer the scene.
    pub fn edit(self, change: impl FnOnce(&mut Scene)) -> Result<ValidScene, SceneError> {
        let ValidScene {
            mut scene, file, ..
        } = self;
        change(&mut scene);
        validate(scene, &file, None)
    }

    /// The plugins' sections, for the plugins to check and read (see
    /// [`crate::schedule::Plugin::section`]), located in the file read.
    pub fn plugin_sections(&self) -> PluginSections {
        PluginSections {
            file: self.file.clone(),
            sections: self
                .scene
                .plugins
                .iter()
                .map(|(k, v)| SceneSection {
                    key: k.clone(),
                    text: v.text().to_string(),
                    at: self.plugin_at.iter().find(|a| &a.0 == k).map(|a| a.1),
                })
                .collect(),
        }
    }

    /// The scene itself, for a caller that only reads or serialises it.
    pub fn into_inner(self) -> Scene {
        self.scene
    }
}

/// The one path to a [`ValidScene`]: every check, errors located in `text` when given.
fn validate(mut scene: Scene, file: &str, text: Option<&str>) -> Result<ValidScene, SceneError> {
    let (grid, geoms, resolved) = check_scene(&mut scene).map_err(|i| i.into_error(file, text))?;
    let gas_line = text.and_then(|t| {
        super::error::locate(
            t,
            &[
                super::error::Seg::Key("free_surface"),
                super::error::Seg::Key("gas_density"),
            ],
        )
    });
    Ok(ValidScene {
        plugin_at: text.map(plugin_starts).unwrap_or_default(),
        scene,
        grid,
        geoms,
        resolved,
        file: file.to_string(),
        gas_line,
    })
}

/// Where each section of `plugins` starts in `text` (1-based line and column): the sections
/// read again, borrowed from the text, so that their addresses give their offsets.
fn plugin_starts(text: &str) -> Vec<(String, (usize, usize))> {
    #[derive(serde::Deserialize)]
    #[serde(rename = "Scene")]
    struct Sections<'a> {
        #[serde(borrow, default)]
        plugins: std::collections::BTreeMap<String, &'a ron::value::RawValue>,
    }
    let opts =
        ron::Options::default().with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME);
    let Ok(s) = opts.from_str::<Sections>(text) else {
        return Vec::new();
    };
    s.plugins
        .into_iter()
        .filter_map(|(k, raw)| {
            let ron = raw.get_ron();
            let skip = ron.len() - ron.trim_start().len();
            let off = (ron.as_ptr() as usize).checked_sub(text.as_ptr() as usize)? + skip;
            let before = text.get(..off)?;
            let line = before.matches('\n').count() + 1;
            let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
            Some((k, (line, col)))
        })
        .collect()
}

impl Scene {
    /// Read and check a scene file; relative mesh paths are resolved against its directory.
    pub fn load(path: &Path) -> Result<ValidScene, SceneError> {
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| SceneError {
            file: file.clone(),
            line: None,
            field: None,
            message: format!("cannot read the file: {e}"),
        })?;
        let stem = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        let dir = path.parent().map(|p| p.to_path_buf()).unwrap_or_default();
        Scene::parse_in(&text, &file, &stem, &dir)
    }

    /// Parse and check scene text; `file` names it in errors, `default_name` is used when the
    /// scene has no `name`; relative mesh paths are resolved against the working directory.
    pub fn parse(text: &str, file: &str, default_name: &str) -> Result<ValidScene, SceneError> {
        Scene::parse_in(text, file, default_name, Path::new(""))
    }

    /// [`Scene::parse`] with relative mesh paths resolved against `base_dir`.
    pub fn parse_in(
        text: &str,
        file: &str,
        default_name: &str,
        base_dir: &Path,
    ) -> Result<ValidScene, SceneError> {
        let opts = ron::Options::default()
            .with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME);
        let mut scene: Scene = opts.from_str(text).map_err(|e| {
            let (line, col) = (e.span.start.line, e.span.start.col);
            SceneError {
                file: file.to_string(),
                line: Some(line),
                field: path_at(text, offset_of(text, line, col)),
                message: format!("{} (column {col})", e.code),
            }
        })?;
        if scene.name.is_empty() {
            scene.name = default_name.to_string();
        }
        scene.base_dir = base_dir.to_path_buf();
        validate(scene, file, Some(text))
    }
}
