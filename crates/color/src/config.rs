//! Configs: where one comes from, what it holds, and processors made from it.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use ocio::{
    Config, DisplayViewTransform, GroupTransform, LookTransform, Transform, TransformDirection,
};

use crate::Processor;

/// An error of colour management: what was asked and what the config has.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct Error(pub String);

/// A result with [`Error`].
pub type Result<T> = std::result::Result<T, Error>;

/// The config used where none is named and `OCIO` is not set: OpenColorIO's CG config
/// with ACES 2.0, named in full (`ocio://default` is another config from one OpenColorIO
/// release to the next: 2.6 made it the v5.0.0 config).
pub const DEFAULT_CONFIG: &str = "ocio://cg-config-v4.0.0_aces-v2.0_ocio-v2.5";

/// Names of lumagraph's default working space (scene-linear Rec. 709) in the configs users
/// bring: OpenColorIO's CG and studio configs (and their aliases), the ACES 1.x configs,
/// Blender's (`lumagraph_graph::WorkingSpace::ocio_names`, where a graph's other working
/// spaces are named too).
pub const WORKING_SPACE_NAMES: &[&str] = lumagraph_graph::WorkingSpace::Rec709.ocio_names();

/// The config name that stands for Blender's own config (AgX, Filmic, Khronos PBR
/// Neutral): the file `LUMAGRAPH_BLENDER_OCIO` names, else the copy of Blender 4.2's that
/// `scripts/setup.sh` unpacks into `~/.cache/lumagraph/blender-ocio/4.2/`.
pub const BLENDER: &str = "blender";

/// Where [`BLENDER`] is.
///
/// # Errors
/// No config there (the message says how to get one).
pub fn blender_config() -> Result<PathBuf> {
    let path = match std::env::var_os("LUMAGRAPH_BLENDER_OCIO") {
        Some(p) if !p.is_empty() => PathBuf::from(p),
        _ => std::env::var_os("XDG_CACHE_HOME")
            .filter(|p| !p.is_empty())
            .map(PathBuf::from)
            .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache")))
            .unwrap_or_default()
            .join("lumagraph/blender-ocio/4.2/config.ocio"),
    };
    if path.is_file() {
        return Ok(path);
    }
    Err(Error(format!(
        "OpenColorIO config {BLENDER}: Blender's config is not at {}: run `bash \
         scripts/setup.sh` (it unpacks Blender 4.2's from the bpy wheel), or set \
         LUMAGRAPH_BLENDER_OCIO to a Blender install's datafiles/colormanagement/config.ocio",
        path.display()
    )))
}

/// A loaded OpenColorIO config.
#[derive(Clone)]
pub struct ColorConfig {
    config: Arc<Config>,
    /// Where it came from, as given: `ocio://…`, a file, or `$OCIO = …`.
    pub source: String,
    working: String,
}

impl std::fmt::Debug for ColorConfig {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ColorConfig")
            .field("source", &self.source)
            .field("working", &self.working)
            .finish_non_exhaustive()
    }
}

impl ColorConfig {
    /// The config `spec` names: empty for the one the `OCIO` environment variable names,
    /// else [`DEFAULT_CONFIG`]; `ocio://NAME` for a built-in one; [`BLENDER`] for Blender's;
    /// anything else a `config.ocio` file, relative to `base`.
    ///
    /// # Errors
    /// An unknown built-in name, a file that is missing or not a config (OpenColorIO's
    /// message), a config without a scene-linear Rec. 709 space.
    pub fn load(spec: &str, base: &Path) -> Result<Self> {
        let (uri, source) = if spec.trim().is_empty() {
            match std::env::var("OCIO") {
                Ok(v) if !v.trim().is_empty() => (v.clone(), format!("$OCIO = {v}")),
                _ => (DEFAULT_CONFIG.to_owned(), DEFAULT_CONFIG.to_owned()),
            }
        } else {
            (spec.to_owned(), spec.to_owned())
        };
        let uri = if uri.trim() == BLENDER {
            blender_config()?.to_string_lossy().into_owned()
        } else {
            uri
        };
        let config = if uri.starts_with("ocio://") {
            Config::create_from_builtin_config(&uri)
                .map_err(|e| Error(format!("OpenColorIO config {source}: {e}")))?
        } else {
            let path: PathBuf = base.join(&uri);
            if !path.is_file() {
                return Err(Error(format!(
                    "OpenColorIO config {source}: no file {}",
                    path.display()
                )));
            }
            Config::create_from_file(&path.to_string_lossy())
                .map_err(|e| Error(format!("OpenColorIO config {}: {e}", path.display())))?
        };
        let working = WORKING_SPACE_NAMES
            .iter()
            .find_map(|n| config.get_color_space(n).map(|cs| cs.name().to_owned()))
            .ok_or_else(|| {
                Error(format!(
                    "OpenColorIO config {source} has no scene-linear Rec. 709 colour space \
                     (lumagraph's working space; looked for {})",
                    WORKING_SPACE_NAMES.join(", ")
                ))
            })?;
        Ok(Self {
            config: Arc::new(config),
            source,
            working,
        })
    }

    /// The config's name for lumagraph's working space: scene-linear Rec. 709, or what
    /// [`ColorConfig::with_working_space`] chose.
    pub fn working_space(&self) -> &str {
        &self.working
    }

    /// The same config with the working space (what an empty colour space name means)
    /// the first of `names` the config has: a graph's working space
    /// (`lumagraph_graph::WorkingSpace::ocio_names`).
    ///
    /// # Errors
    /// A config with none of `names` (the message lists them).
    pub fn with_working_space(mut self, names: &[&str]) -> Result<Self> {
        self.working = names
            .iter()
            .find_map(|n| {
                self.config
                    .get_color_space(n)
                    .map(|cs| cs.name().to_owned())
            })
            .ok_or_else(|| {
                Error(format!(
                    "OpenColorIO config {} has no colour space for the graph's working space \
                     (looked for {})",
                    self.source,
                    names.join(", ")
                ))
            })?;
        Ok(self)
    }

    /// The colour space the config's file rules give a file at `path`.
    pub fn color_space_from_filepath(&self, path: &str) -> String {
        self.config.color_space_from_filepath(path)
    }

    /// The active colour spaces, in the config's order.
    pub fn color_spaces(&self) -> Vec<String> {
        (0..self.config.num_color_spaces())
            .map(|i| self.config.color_space_name_by_index(i).to_owned())
            .collect()
    }

    /// The displays, each with its views, default first.
    pub fn displays(&self) -> Vec<(String, Vec<String>)> {
        (0..self.config.num_displays())
            .map(|i| {
                let d = self.config.display(i);
                let views = (0..self.config.num_views(&d))
                    .map(|j| self.config.view(&d, j))
                    .collect();
                (d, views)
            })
            .collect()
    }

    /// The looks.
    pub fn looks(&self) -> Vec<String> {
        (0..self.config.num_looks())
            .map(|i| self.config.look_name_by_index(i).to_owned())
            .collect()
    }

    /// The default display, and its default view.
    pub fn default_display_view(&self) -> (String, String) {
        let d = self.config.default_display();
        let v = self.config.default_view(&d);
        (d, v)
    }

    /// `name` as the config calls it (a role or an alias resolved); empty: the working
    /// space.
    fn space(&self, name: &str) -> Result<String> {
        if name.trim().is_empty() {
            return Ok(self.working.clone());
        }
        self.config
            .get_color_space(name)
            .map(|cs| cs.name().to_owned())
            .ok_or_else(|| {
                Error(format!(
                    "OpenColorIO config {} has no colour space {name:?}; it has: {}",
                    self.source,
                    self.color_spaces().join(", ")
                ))
            })
    }

    /// From colour space `from` to `to` (empty: the working space).
    ///
    /// # Errors
    /// An unknown space (the message lists the config's), a conversion the config cannot
    /// make.
    pub fn processor(&self, from: &str, to: &str) -> Result<Processor> {
        let (from, to) = (self.space(from)?, self.space(to)?);
        let p = self
            .config
            .get_processor(&from, &to)
            .map_err(|e| Error(format!("{from} → {to}: {e}")))?;
        Ok(Processor::new(p, format!("{from} → {to}")))
    }

    /// From colour space `from` (empty: the working space) to `display` and `view` (empty:
    /// the config's defaults) with `looks` (OpenColorIO's syntax, `+look, -other`; empty:
    /// the view's own).
    ///
    /// # Errors
    /// An unknown space, display, view or look (the message lists what there is).
    pub fn display_processor(
        &self,
        from: &str,
        display: &str,
        view: &str,
        looks: &str,
    ) -> Result<Processor> {
        let from = self.space(from)?;
        let displays = self.displays();
        let display = if display.trim().is_empty() {
            self.config.default_display()
        } else {
            display.to_owned()
        };
        let Some((_, views)) = displays.iter().find(|(d, _)| *d == display) else {
            let names: Vec<&str> = displays.iter().map(|(d, _)| d.as_str()).collect();
            return Err(Error(format!(
                "OpenColorIO config {} has no display {display:?}; its displays: {}",
                self.source,
                names.join(", ")
            )));
        };
        let view = if view.trim().is_empty() {
            self.config.default_view(&display)
        } else {
            view.to_owned()
        };
        if !views.contains(&view) {
            return Err(Error(format!(
                "display {display:?} has no view {view:?}; its views: {}",
                views.join(", ")
            )));
        }
        let dv = DisplayViewTransform {
            src: from.clone(),
            display: display.clone(),
            view: view.clone(),
            looks_bypass: !looks.trim().is_empty(),
            ..DisplayViewTransform::default()
        };
        let transform = if looks.trim().is_empty() {
            Transform::DisplayView(dv)
        } else {
            for name in looks
                .split(',')
                .map(|l| l.trim().trim_start_matches(['+', '-']))
            {
                if !self.looks().iter().any(|l| l == name) {
                    return Err(Error(format!(
                        "OpenColorIO config {} has no look {name:?}; its looks: {}",
                        self.source,
                        self.looks().join(", ")
                    )));
                }
            }
            let look = LookTransform {
                src: from.clone(),
                dst: from.clone(),
                looks: looks.to_owned(),
                ..LookTransform::default()
            };
            Transform::Group(GroupTransform {
                transforms: vec![Transform::Look(look), Transform::DisplayView(dv)],
                ..GroupTransform::default()
            })
        };
        let p = self
            .config
            .get_processor_for_transform(&transform, TransformDirection::Forward)
            .map_err(|e| Error(format!("{from} → {display} / {view}: {e}")))?;
        let looks = if looks.trim().is_empty() {
            String::new()
        } else {
            format!(" (looks {looks})")
        };
        Ok(Processor::new(
            p,
            format!("{from} → {display} / {view}{looks}"),
        ))
    }
}
