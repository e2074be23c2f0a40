//! Node groups in the editor: make one from the selection (Ctrl+G), open a group node's
//! file to edit it (Tab) and leave it again (Tab), the graph around it kept meanwhile.

use std::path::{Path, PathBuf};

use super::{Editor, Pick};
use crate::document::Document;

/// The graph a group was opened from, restored when the group is left.
#[derive(Debug)]
pub struct Outer {
    /// The graph around the group.
    pub doc: Document,
    /// The group node it was opened through.
    pub node: String,
    selected: Vec<String>,
    preview_port: Option<String>,
}

/// The group kind name a file suggests: its stem, capitalized, with anything but letters,
/// digits and `_` made `_`.
pub fn group_name(file: &Path) -> String {
    let stem = file
        .file_stem()
        .map_or_else(|| "Group".to_owned(), |s| s.to_string_lossy().into_owned());
    let mut name: String = stem
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    if let Some(first) = name.get_mut(0..1) {
        first.make_ascii_uppercase();
    }
    if name.starts_with(|c: char| c.is_ascii_digit()) || name.is_empty() {
        name.insert_str(0, "Group");
    }
    name
}

impl Editor {
    /// Moves the selected nodes into a new group file `file` and puts a node of the group
    /// in their place (selected). The kind is named after the file ([`group_name`]).
    pub fn group_selection(&mut self, file: &Path) {
        let name = group_name(file);
        let selected = self.selected.clone();
        match self.doc.group_nodes(&selected, &name, file) {
            Ok(id) => {
                self.select(vec![id]);
                self.say(
                    format!(
                        "grouped {} nodes as {name} in {}",
                        selected.len(),
                        file.display()
                    ),
                    false,
                );
            }
            Err(e) => self.say(e, true),
        }
    }

    /// Asks where to write the group made from the selection.
    pub fn ask_group_selection(&mut self) {
        if self.selected.is_empty() {
            self.say("select the nodes to group first", true);
        } else if self.doc.path.is_none() {
            self.say(
                "save the graph first: its group's file is named relative to it",
                true,
            );
        } else {
            self.open_file_dialog(Pick::GroupFile);
        }
    }

    /// The group file of node `id`, when it is a group node.
    pub fn group_file(&self, id: &str) -> Option<PathBuf> {
        let node = self.doc.graph.node(id)?;
        self.doc.registry().group(&node.kind).map(|g| g.file())
    }

    /// Opens the file of group node `id` for editing; the graph around it waits in
    /// [`Editor::outer`] until [`Editor::leave_group`].
    pub fn open_group(&mut self, id: &str) {
        let Some(file) = self.group_file(id) else {
            self.say(format!("\"{id}\" is not a group node"), true);
            return;
        };
        let graph = match crate::files::open(&file) {
            Ok(g) => g,
            Err(e) => {
                self.say(format!("cannot open the group: {e}"), true);
                return;
            }
        };
        let library = std::sync::Arc::clone(self.doc.library());
        let doc = std::mem::replace(
            &mut self.doc,
            Document::with_library(graph, Some(file.clone()), library),
        );
        self.errors_for = None;
        self.canvas.request_frame(crate::canvas::Frame::All);
        self.outer.push(Outer {
            doc,
            node: id.to_owned(),
            selected: std::mem::take(&mut self.selected),
            preview_port: self.preview_port.take(),
        });
        self.say(
            format!("editing group {} (Tab leaves it)", file.display()),
            false,
        );
    }

    /// Leaves the open group: saves it when it changed, then returns to the graph around
    /// it, whose group kinds are read again. Returns whether a group was left.
    pub fn leave_group(&mut self) -> bool {
        if self.outer.is_empty() {
            return false;
        }
        if self.doc.is_dirty()
            && let Err(e) = self.save()
        {
            self.say(format!("the group was not left: {e}"), true);
            return false;
        }
        let Some(outer) = self.outer.pop() else {
            return false;
        };
        self.doc = outer.doc;
        self.errors_for = None;
        self.canvas
            .request_frame(crate::canvas::Frame::Nodes(vec![outer.node.clone()]));
        self.selected = outer.selected;
        self.preview_port = outer.preview_port;
        match self.doc.reload_registry() {
            Ok(()) => self.say(format!("back in the graph around {}", outer.node), false),
            Err(e) => self.say(format!("the group does not load: {e}"), true),
        }
        true
    }

    /// Tab: opens the selected group node, or else leaves the open group.
    pub fn toggle_group(&mut self) {
        match self.selected.as_slice() {
            [one] if self.group_file(one).is_some() => {
                let one = one.clone();
                self.open_group(&one);
            }
            _ => {
                if !self.leave_group() {
                    self.say("select a group node to open it", true);
                }
            }
        }
    }
}

/// The graph to compile for a group being edited: the outermost graph with the edited
/// group in place, so the preview and the error marks see it where it is used.
#[derive(Debug)]
pub struct Context {
    /// Kinds of the outermost graph, the edited group's replaced by the document.
    pub registry: lumagraph_graph::Registry,
    /// The outermost graph.
    pub graph: lumagraph_graph::Graph,
    /// Its folder.
    pub base: PathBuf,
    /// What the edited group's node ids are prefixed with there (`lens/`).
    pub prefix: String,
}

impl Editor {
    /// The edited group in the graphs around it ([`Context`]); `None` when no group is
    /// open, or when the edited group cannot be used as it is (why, then, as `Err`).
    pub fn group_context(&self) -> Option<Result<Context, String>> {
        if self.outer.is_empty() {
            return None;
        }
        let mut graph = self.doc.with_origin(&self.doc.graph);
        let mut registry = self.doc.registry().clone();
        let mut prefix = String::new();
        for outer in self.outer.iter().rev() {
            let kind = outer.doc.graph.node(&outer.node)?.kind.clone();
            let mut around = outer.doc.registry().clone();
            let group = lumagraph_graph::group::Group {
                name: lumagraph_graph::custom::intern(&kind),
                graph,
                registry,
            };
            if let Err(e) = around.set_group(group) {
                return Some(Err(format!("as a group: {e}")));
            }
            registry = around;
            graph = outer.doc.graph.clone();
            prefix = format!("{}/{prefix}", outer.node);
        }
        let base = self.outer.first().map(|o| o.doc.base_dir())?;
        Some(Ok(Context {
            registry,
            graph,
            base,
            prefix,
        }))
    }
}
