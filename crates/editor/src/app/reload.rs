//! Live reload: the files the graph's kinds come from (a declared kind's `.wgsl`, a group
//! file and the files it names) are checked for changes twice a second. A change reads the
//! kinds again; when they load, the preview rebuilds with them. When they do not, the
//! editor keeps the kinds (and the preview its pipelines) it had, and shows the errors on
//! the nodes of the failing kind until the file is fixed.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::SystemTime;

use lumagraph_graph::{Graph, GraphErrors, Registry};

use super::Editor;

/// How often files are checked, in seconds.
const POLL_SECONDS: f64 = 0.5;

/// The files the kinds come from, with their modification times when last read.
#[derive(Debug, Default)]
pub struct Watch {
    /// The document the list is for (its file and what it declares).
    key: Option<(Option<PathBuf>, Graph)>,
    files: Vec<(PathBuf, Option<SystemTime>)>,
    last_poll: f64,
    /// Why the last reload failed: each message with the kind it is about, if known.
    pub errors: Vec<(Option<String>, String)>,
}

fn modified(path: &Path) -> Option<SystemTime> {
    std::fs::metadata(path).and_then(|m| m.modified()).ok()
}

/// The files `graph`'s declared kinds and groups are read from, through `registry`'s
/// groups (whose own kinds and groups are listed too).
fn sources(graph: &Graph, registry: &Registry, base: &Path, out: &mut Vec<PathBuf>) {
    for decl in &graph.kinds {
        if !decl.wgsl.is_empty() {
            out.push(base.join(&decl.wgsl));
        }
    }
    for decl in &graph.groups {
        out.push(base.join(&decl.file));
        if let Some(group) = registry.group(&decl.name)
            && !out.contains(&group.file())
        {
            sources(&group.graph, &group.registry, &group.graph.base_dir(), out);
        }
    }
}

/// The declared kind an error is about (`kind "Posterize"` in its message).
fn kind_of_error(message: &str) -> Option<String> {
    let rest = message.split_once("kind \"")?.1;
    Some(rest.split_once('"')?.0.to_owned())
}

impl Editor {
    /// What the watch list depends on: the document's file, kinds and groups.
    fn watch_key(&self) -> (Option<PathBuf>, Graph) {
        let mut g = Graph::new();
        g.kinds.clone_from(&self.doc.graph.kinds);
        g.groups.clone_from(&self.doc.graph.groups);
        (self.doc.path.clone(), g)
    }

    /// Whether the watch list was made for the document as it is (checked every frame,
    /// so without copying anything).
    fn watching_current(&self) -> bool {
        self.watch.key.as_ref().is_some_and(|(path, g)| {
            *path == self.doc.path
                && g.kinds == self.doc.graph.kinds
                && g.groups == self.doc.graph.groups
        })
    }

    /// Checks the watched files (at most every half second of `now`, egui's clock) and
    /// reloads the kinds when one changed. Returns whether it reloaded.
    pub fn poll_files(&mut self, now: f64) -> bool {
        if !self.watching_current() {
            // Another document, or its declarations were edited: watch what it names now.
            self.watch.key = Some(self.watch_key());
            self.rewatch();
            return false;
        }
        if now - self.watch.last_poll < POLL_SECONDS {
            return false;
        }
        self.watch.last_poll = now;
        let changed = self
            .watch
            .files
            .iter()
            .any(|(path, time)| modified(path) != *time);
        if changed {
            self.reload_kinds();
        }
        changed
    }

    /// Lists the files to watch with their times now.
    fn rewatch(&mut self) {
        let mut files = Vec::new();
        sources(
            &self.doc.graph,
            self.doc.registry(),
            &self.doc.base_dir(),
            &mut files,
        );
        self.watch.files = files
            .into_iter()
            .map(|f| {
                let t = modified(&f);
                (f, t)
            })
            .collect();
    }

    /// Reads the graph's declared kinds and groups again. When they load, they replace
    /// the current ones and the preview rebuilds its pipelines; when they do not, the
    /// current ones stay in use and the errors show on the nodes of the failing kinds.
    pub fn reload_kinds(&mut self) {
        let result: Result<Registry, GraphErrors> = self
            .doc
            .library()
            .registry_for(&self.doc.with_origin(&self.doc.graph));
        match result {
            Ok(registry) => {
                let had_errors = !self.watch.errors.is_empty();
                self.watch.errors.clear();
                self.doc.set_registry(Arc::new(registry));
                self.preview.rebuild();
                self.say(
                    if had_errors {
                        "reloaded: the kinds compile again"
                    } else {
                        "reloaded the changed kinds"
                    },
                    false,
                );
            }
            Err(errors) => {
                self.watch.errors = errors
                    .0
                    .iter()
                    .map(|e| (kind_of_error(&e.to_string()), e.to_string()))
                    .collect();
                self.say(
                    "a changed kind does not compile: the last good one stays in use",
                    true,
                );
            }
        }
        self.rewatch();
        self.errors_for = None;
    }

    /// Adds the last reload's errors to the error marks: on the nodes of the kind each is
    /// about, else to the graph's.
    pub(super) fn add_reload_errors(&mut self) {
        for (kind, message) in &self.watch.errors {
            let nodes: Vec<String> = self
                .doc
                .graph
                .nodes
                .iter()
                .filter(|n| Some(&n.kind) == kind.as_ref())
                .map(|n| n.id.clone())
                .collect();
            if nodes.is_empty() {
                self.graph_errors.push(message.clone());
            }
            for n in nodes {
                self.errors.entry(n).or_default().push(message.clone());
            }
        }
    }
}
