//! The layout `Graph::save` writes, and the comments it keeps.
//!
//! A graph file is written the way people write one by hand: one node per line and one
//! edge per line, declarations indented below their list. Comments survive a load → edit →
//! save when they are where a reader expects them to belong:
//! - the **header**: comment lines before the graph's opening `(`;
//! - comment lines directly above a **node**, an **edge** or a **frame** (each on its own
//!   line), and a comment after one on the same line (`(id: "x", ...), // why`); they stay
//!   with that node, edge or frame (found by its id, its two ends, or its label), wherever
//!   it moves, and go when it is deleted.
//!
//! Comments elsewhere (inside a declared kind, between fields) are not kept.

use std::collections::HashMap;
use std::fmt::Write as _;

use serde::Serialize;

use crate::graph::{Edge, Graph, Node};

/// Comments read from a graph file's text.
#[derive(Debug, Default)]
struct Comments {
    header: Vec<String>,
    /// Node id → (lines above, comment after on its line).
    nodes: HashMap<String, (Vec<String>, Option<String>)>,
    /// (from, to) → (lines above, comment after on its line).
    edges: HashMap<(String, String), (Vec<String>, Option<String>)>,
    /// Frame label → (lines above, comment after on its line).
    frames: HashMap<String, (Vec<String>, Option<String>)>,
}

/// The first string value after `key:` on `line`.
fn field<'a>(line: &'a str, key: &str) -> Option<&'a str> {
    let at = line.find(&format!("{key}:"))?;
    let rest = &line[at + key.len() + 1..];
    let start = rest.find('"')? + 1;
    let len = rest[start..].find('"')?;
    Some(&rest[start..start + len])
}

/// The comment after an entry that ends its line: `(...), // text` gives `// text`.
fn trailing(line: &str) -> Option<String> {
    let end = line.rfind("),")?;
    let rest = line[end + 2..].trim();
    rest.starts_with("//").then(|| rest.to_owned())
}

impl Comments {
    fn of(text: &str) -> Self {
        let mut out = Self::default();
        let mut lines = text.lines();
        for line in lines.by_ref() {
            let t = line.trim();
            if t.starts_with('(') {
                break;
            }
            if t.starts_with("//") || (t.is_empty() && !out.header.is_empty()) {
                out.header.push(line.trim_end().to_owned());
            }
        }
        let mut above: Vec<String> = Vec::new();
        for line in lines {
            let t = line.trim();
            if t.starts_with("//") {
                above.push(t.to_owned());
                continue;
            }
            if t.is_empty() || t == "(" {
                continue;
            }
            let comments = (std::mem::take(&mut above), trailing(t));
            if let Some(id) = field(t, "id") {
                out.nodes.insert(id.to_owned(), comments);
            } else if let (Some(from), Some(to)) = (field(t, "from"), field(t, "to")) {
                out.edges.insert((from.to_owned(), to.to_owned()), comments);
            } else if let Some(label) = field(t, "label") {
                out.frames.insert(label.to_owned(), comments);
            }
        }
        out
    }
}

/// Where the value of each field of the file's top-level struct is in `text`: name →
/// byte range of the value (strings, raw strings and comments skipped while matching
/// brackets).
fn top_level_fields(text: &str) -> HashMap<String, std::ops::Range<usize>> {
    let b = text.as_bytes();
    let mut fields = HashMap::new();
    let mut depth = 0usize;
    let mut i = 0;
    let mut value: Option<(String, usize)> = None;
    let mut ident_start: Option<usize> = None;
    while i < b.len() {
        let c = b[i];
        // Comments.
        if c == b'/' && b.get(i + 1) == Some(&b'/') {
            i = text[i..].find('\n').map_or(b.len(), |n| i + n);
            continue;
        }
        // Raw strings r"..." and r#"..."#.
        if c == b'r' && matches!(b.get(i + 1), Some(b'"' | b'#')) {
            let hashes = b[i + 1..].iter().take_while(|&&x| x == b'#').count();
            if b.get(i + 1 + hashes) == Some(&b'"') {
                let close = format!("\"{}", "#".repeat(hashes));
                let from = i + 2 + hashes;
                i = text[from..]
                    .find(&close)
                    .map_or(b.len(), |n| from + n + close.len());
                ident_start = None;
                continue;
            }
        }
        if c == b'"' {
            i += 1;
            while i < b.len() && b[i] != b'"' {
                i += if b[i] == b'\\' { 2 } else { 1 };
            }
            i += 1;
            ident_start = None;
            continue;
        }
        match c {
            b'(' | b'[' | b'{' => depth += 1,
            b')' | b']' | b'}' => {
                if depth == 1
                    && let Some((name, start)) = value.take()
                {
                    fields.insert(name, start..i);
                }
                depth = depth.saturating_sub(1);
            }
            b',' if depth == 1 => {
                if let Some((name, start)) = value.take() {
                    fields.insert(name, start..i);
                }
                ident_start = None;
            }
            b':' if depth == 1 && value.is_none() => {
                if let Some(s) = ident_start.take() {
                    value = Some((text[s..i].trim().to_owned(), i + 1));
                }
            }
            _ if depth == 1 && value.is_none() && (c.is_ascii_alphanumeric() || c == b'_') => {
                ident_start.get_or_insert(i);
            }
            _ if depth == 1 && value.is_none() && !c.is_ascii_whitespace() => ident_start = None,
            _ => {}
        }
        i += 1;
    }
    fields
}

/// The text of field `name` as written in `text` (trimmed), when the graph read from it
/// holds the same value there: kept as the user wrote it (raw strings, layout, comments).
fn as_written<'t>(text: &'t str, name: &str, same: impl FnOnce(&Graph) -> bool) -> Option<&'t str> {
    let parsed = Graph::from_ron(text).ok()?;
    if !same(&parsed) {
        return None;
    }
    let range = top_level_fields(text).remove(name)?;
    Some(text[range].trim())
}

/// One value on one line: `(id: "a", kind: "B", params: {"x": 1.0})`.
fn compact<T: Serialize>(value: &T) -> String {
    let config = ron::ser::PrettyConfig::new()
        .struct_names(false)
        .compact_structs(true)
        .compact_maps(true)
        .compact_arrays(true);
    ron::ser::to_string_pretty(value, config)
        .expect("graph values always serialize: strings, numbers and maps")
}

/// A value over several lines down to `depth`, its lines after the first indented by
/// `indent`.
fn pretty<T: Serialize>(value: &T, depth: usize, indent: &str) -> String {
    let config = ron::ser::PrettyConfig::new()
        .depth_limit(depth)
        .struct_names(false)
        .indentor("    ");
    ron::ser::to_string_pretty(value, config)
        .expect("graph values always serialize: strings, numbers and maps")
        .replace('\n', &format!("\n{indent}"))
}

/// Writes one list entry with its comments.
fn entry(out: &mut String, text: &str, comments: Option<&(Vec<String>, Option<String>)>) {
    if let Some((above, _)) = comments {
        for c in above {
            let _ = writeln!(out, "        {c}");
        }
    }
    let _ = write!(out, "        {text},");
    if let Some((_, Some(after))) = comments {
        let _ = write!(out, " {after}");
    }
    out.push('\n');
}

/// `graph` in the canonical layout, as version `version`, with the comments of the text it
/// was loaded from.
pub(crate) fn write(graph: &Graph, version: u32) -> String {
    let comments = graph
        .origin
        .as_ref()
        .map(|o| Comments::of(o.text()))
        .unwrap_or_default();
    let mut out = String::new();
    for line in &comments.header {
        let _ = writeln!(out, "{line}");
    }
    let _ = writeln!(out, "(\n    version: {version},");
    if graph.working_space != crate::WorkingSpace::default() {
        let _ = writeln!(out, "    working_space: {:?},", graph.working_space.name());
    }
    if !graph.interface.is_empty() {
        let _ = writeln!(
            out,
            "    interface: {},",
            pretty(&graph.interface, 2, "    ")
        );
    }
    if !graph.groups.is_empty() {
        out.push_str("    groups: [\n");
        for g in &graph.groups {
            entry(&mut out, &compact(g), None);
        }
        out.push_str("    ],\n");
    }
    if !graph.kinds.is_empty() {
        // Declared kinds hold WGSL: written as they were when unchanged.
        let kept = graph
            .origin
            .as_ref()
            .and_then(|o| as_written(o.text(), "kinds", |parsed| parsed.kinds == graph.kinds));
        match kept {
            Some(text) => {
                let _ = writeln!(out, "    kinds: {text},");
            }
            None => {
                let _ = writeln!(out, "    kinds: {},", pretty(&graph.kinds, 2, "    "));
            }
        }
    }
    out.push_str("    nodes: [\n");
    for n in &graph.nodes {
        entry(&mut out, &compact::<Node>(n), comments.nodes.get(&n.id));
    }
    out.push_str("    ],\n");
    out.push_str("    edges: [\n");
    for e in &graph.edges {
        let key = (e.from.clone(), e.to.clone());
        entry(&mut out, &compact::<Edge>(e), comments.edges.get(&key));
    }
    out.push_str("    ],\n");
    if !graph.frames.is_empty() {
        out.push_str("    frames: [\n");
        for f in &graph.frames {
            entry(&mut out, &compact(f), comments.frames.get(&f.label));
        }
        out.push_str("    ],\n");
    }
    out.push_str(")\n");
    out
}
