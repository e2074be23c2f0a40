//! Text descriptions of the registry: the CLI's `nodes` listing and the node reference
//! in `docs/graph-format.md` are both generated here, so they cannot drift apart.

use std::fmt::Write as _;

use crate::registry::{InputDef, NodeKind, OutputDef, Registry};
use crate::types::{ParamType, PortType};

fn param_range(ty: &ParamType) -> String {
    match ty {
        ParamType::Float { min, max, .. } => format!("[{min}, {max}]"),
        ParamType::Int { min, max, .. } => format!("[{min}, {max}]"),
        ParamType::Bool { .. } => "true / false".to_owned(),
        ParamType::Enum { options, .. } => options
            .iter()
            .map(|(n, _)| format!("\"{n}\""))
            .collect::<Vec<_>>()
            .join(", "),
        ParamType::Path { extensions, .. } => extensions
            .iter()
            .map(|e| format!(".{e}"))
            .collect::<Vec<_>>()
            .join(" "),
        ParamType::Text { .. } => "any text".to_owned(),
    }
}

fn accepts(types: &[PortType]) -> String {
    types
        .iter()
        .map(|t| t.name())
        .collect::<Vec<_>>()
        .join(" | ")
}

/// An input's description, marked when it is optional.
fn input_doc(p: &InputDef) -> String {
    if p.optional {
        format!("(optional) {}", p.doc)
    } else {
        p.doc.to_owned()
    }
}

/// An output's description, with its size rule when it is not the pass's size.
fn output_doc(p: &OutputDef) -> String {
    match p.size.describe() {
        Some(size) => format!("{}; size: {size}", p.doc),
        None => p.doc.to_owned(),
    }
}

/// A plain-text listing of every kind, for the terminal.
pub fn text(registry: &Registry) -> String {
    let mut s = String::new();
    for kind in registry.kinds() {
        let _ = writeln!(s, "{} [{}]", kind.name, kind.category.name());
        let _ = writeln!(s, "    {}", kind.doc);
        for p in &kind.inputs {
            let _ = writeln!(
                s,
                "    in   {:<10} {:<24} {}",
                p.name,
                accepts(p.accepts),
                input_doc(p)
            );
        }
        for p in &kind.outputs {
            let _ = writeln!(
                s,
                "    out  {:<10} {:<24} {}",
                p.name,
                p.ty.name(),
                output_doc(p)
            );
        }
        for p in &kind.params {
            let _ = writeln!(
                s,
                "    param {:<9} {:<6} default {} in {}: {}",
                p.name,
                p.ty.name(),
                p.ty.default_value(),
                param_range(&p.ty),
                p.doc
            );
        }
        s.push('\n');
    }
    s
}

fn kind_markdown(s: &mut String, kind: &NodeKind) {
    let _ = writeln!(s, "### {}\n\n{}\n", kind.name, kind.doc);
    if !kind.inputs.is_empty() || !kind.outputs.is_empty() {
        let _ = writeln!(
            s,
            "| port | direction | type | description |\n|---|---|---|---|"
        );
        for p in &kind.inputs {
            let _ = writeln!(
                s,
                "| `{}` | in | {} | {} |",
                p.name,
                accepts(p.accepts),
                input_doc(p)
            );
        }
        for p in &kind.outputs {
            let _ = writeln!(
                s,
                "| `{}` | out | {} | {} |",
                p.name,
                p.ty.name(),
                output_doc(p)
            );
        }
        s.push('\n');
    }
    if !kind.params.is_empty() {
        let _ = writeln!(
            s,
            "| param | type | default | range | description |\n|---|---|---|---|---|"
        );
        for p in &kind.params {
            let _ = writeln!(
                s,
                "| `{}` | {} | `{}` | {} | {} |",
                p.name,
                p.ty.name(),
                p.ty.default_value(),
                param_range(&p.ty),
                p.doc
            );
        }
        s.push('\n');
    }
    for p in &kind.params {
        if let ParamType::Enum { options, .. } = &p.ty {
            let _ = writeln!(s, "`{}` values:\n", p.name);
            for (name, doc) in *options {
                let _ = writeln!(s, "- `\"{name}\"`: {doc}");
            }
            s.push('\n');
        }
    }
}

/// The Markdown node reference: port types, then every kind by category.
pub fn markdown(registry: &Registry) -> String {
    let mut s = String::from("## Port types\n\n| type | holds |\n|---|---|\n");
    for t in PortType::ALL {
        let _ = writeln!(s, "| `{}` | {} |", t.name(), t.doc());
    }
    s.push('\n');
    let mut categories: Vec<_> = registry.kinds().iter().map(|k| k.category).collect();
    categories.dedup();
    for c in categories {
        let _ = writeln!(s, "## {} nodes\n", c.name());
        for kind in registry.kinds().iter().filter(|k| k.category == c) {
            kind_markdown(&mut s, kind);
        }
    }
    s
}
