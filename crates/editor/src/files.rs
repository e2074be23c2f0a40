//! Files: opening and saving graphs, and the recent-files list.
//!
//! Saving goes through [`Graph::save`] (a temporary file renamed over the target). Input
//! paths in a graph are relative to the graph file's folder, so "save as" into another
//! folder rewrites them to point at the same files from there. The recent-files list is a
//! small RON file in the user's config folder (`$XDG_CONFIG_HOME/lumagraph/recent.ron`,
//! else `~/.config/lumagraph/recent.ron`).

use std::path::{Component, Path, PathBuf};

use lumagraph_graph::{Graph, ParamType, ParamValue, Registry};
use serde::{Deserialize, Serialize};

use crate::EditorError;

/// How many recent files are remembered.
const RECENT_MAX: usize = 10;

/// The default place of the recent-files list, when the environment tells one.
pub fn default_recent_path() -> Option<PathBuf> {
    let config = std::env::var_os("XDG_CONFIG_HOME")
        .filter(|v| !v.is_empty())
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".config")))?;
    Some(config.join("lumagraph").join("recent.ron"))
}

/// Recently opened or saved graph files, newest first.
#[derive(Debug, Default, Clone, PartialEq, Serialize, Deserialize)]
pub struct Recent {
    /// The files.
    pub files: Vec<PathBuf>,
    #[serde(skip)]
    store: Option<PathBuf>,
}

impl Recent {
    /// Reads the list from `store` (a missing or unreadable file gives an empty list: the
    /// list is a convenience, never a reason to fail).
    pub fn load(store: Option<PathBuf>) -> Self {
        let files = store
            .as_deref()
            .and_then(|p| std::fs::read_to_string(p).ok())
            .and_then(|t| ron::from_str::<Self>(&t).ok())
            .map(|r| r.files)
            .unwrap_or_default();
        Self { files, store }
    }

    /// Puts `path` first and writes the list back.
    ///
    /// # Errors
    /// When the list cannot be written.
    pub fn add(&mut self, path: &Path) -> Result<(), EditorError> {
        let path = std::path::absolute(path).unwrap_or_else(|_| path.to_owned());
        self.files.retain(|p| *p != path);
        self.files.insert(0, path);
        self.files.truncate(RECENT_MAX);
        self.write()
    }

    fn write(&self) -> Result<(), EditorError> {
        let Some(store) = &self.store else {
            return Ok(());
        };
        let text = ron::ser::to_string_pretty(self, ron::ser::PrettyConfig::default())
            .map_err(|e| EditorError::Recent(e.to_string()))?;
        if let Some(dir) = store.parent() {
            std::fs::create_dir_all(dir).map_err(|e| EditorError::Recent(e.to_string()))?;
        }
        lumagraph_graph::write_atomic(store, text.as_bytes())
            .map_err(|e| EditorError::Recent(format!("{}: {e}", store.display())))
    }
}

/// Opens a graph file. A file that cannot be parsed gives the error, never a panic.
///
/// # Errors
/// When the file cannot be read or parsed.
pub fn open(path: &Path) -> Result<Graph, EditorError> {
    Graph::load(path).map_err(|e| EditorError::Graph(e.to_string()))
}

/// Saves `graph` to `path` atomically. When the folder changes (`old_base` differs from
/// the new file's folder), relative input paths are rewritten to stay pointed at the same
/// files. Returns the graph as saved.
///
/// # Errors
/// When the file cannot be written.
pub fn save(
    registry: &Registry,
    graph: &Graph,
    old_base: &Path,
    path: &Path,
) -> Result<Graph, EditorError> {
    let new_base = path.parent().unwrap_or(Path::new(""));
    let mut out = graph.clone();
    if absolute(old_base) != absolute(new_base) {
        rebase_inputs(registry, &mut out, old_base, new_base);
    }
    out.save(path)
        .map_err(|e| EditorError::Graph(e.to_string()))?;
    Ok(out)
}

fn absolute(p: &Path) -> PathBuf {
    let p = if p.as_os_str().is_empty() {
        Path::new(".")
    } else {
        p
    };
    std::path::absolute(p).map_or_else(|_| p.to_owned(), |a| normalize(&a))
}

/// Removes `.` and resolves `..` lexically.
fn normalize(p: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for c in p.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir => {
                out.pop();
            }
            other => out.push(other),
        }
    }
    out
}

/// `target` written relative to the folder `base` (either may be relative to the current
/// folder), with `/` separators: how a graph file names another file.
pub fn relative_path(target: &Path, base: &Path) -> String {
    relative_to(&absolute(target), &absolute(base))
        .to_string_lossy()
        .replace('\\', "/")
}

/// `target` written relative to `base` (both absolute and normalized).
fn relative_to(target: &Path, base: &Path) -> PathBuf {
    let t: Vec<_> = target.components().collect();
    let b: Vec<_> = base.components().collect();
    let common = t.iter().zip(&b).take_while(|(x, y)| x == y).count();
    let mut out = PathBuf::new();
    for _ in common..b.len() {
        out.push("..");
    }
    for c in &t[common..] {
        out.push(c);
    }
    out
}

/// Rewrites the relative paths of a graph from `old_base` to `new_base`: the path params
/// of input nodes (non-sinks; sink paths are relative to the output folder), the `.wgsl`
/// files of declared kinds and the files of group kinds.
pub fn rebase_inputs(registry: &Registry, graph: &mut Graph, old_base: &Path, new_base: &Path) {
    let (old_base, new_base) = (absolute(old_base), absolute(new_base));
    let rebase = |p: &mut String| {
        if p.is_empty() || Path::new(p.as_str()).is_absolute() {
            return;
        }
        let target = normalize(&old_base.join(p.as_str()));
        *p = relative_to(&target, &new_base)
            .to_string_lossy()
            .replace('\\', "/");
    };
    for decl in &mut graph.kinds {
        rebase(&mut decl.wgsl);
    }
    for decl in &mut graph.groups {
        rebase(&mut decl.file);
    }
    for node in &mut graph.nodes {
        let Some(kind) = registry.get(&node.kind) else {
            continue;
        };
        if kind.sink {
            continue;
        }
        for def in &kind.params {
            if matches!(def.ty, ParamType::Path { .. })
                && let Some(ParamValue::Str(p)) = node.params.get_mut(def.name)
            {
                rebase(p);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn relative_paths() {
        assert_eq!(
            relative_to(Path::new("/a/b/c.exr"), Path::new("/a/d")),
            PathBuf::from("../b/c.exr")
        );
        assert_eq!(
            relative_to(Path::new("/a/b/c.exr"), Path::new("/a/b")),
            PathBuf::from("c.exr")
        );
    }
}
