//! Node kinds declared in graph files: the shader written around the declared function,
//! validated with naga when the graph loads, errors located in the file that holds the
//! WGSL.
//!
//! The function is `fn node(pixel: vec2u, size: vec2u) -> vec4f` (one output) or
//! `-> Outputs` (several: a generated struct with one `vec4f` member per output, in
//! declaration order). Around it the kind's inputs are textures named as the ports, with
//! `load_<input>(p: vec2i) -> vec4f` reading one clamped to the image; the params are
//! `params.<name>` (f32, i32, u32 for bools and enum option indices) and an optional input
//! adds `params.has_<input>` (1 when connected). `#import "common/color.wgsl"` lines bring
//! in the shared WGSL helpers. The module then runs on the generic post filter
//! ([`crate::nodes::post_filter`]).

use std::fmt::Write as _;
use std::path::PathBuf;
use std::sync::Arc;

use lumagraph_graph::custom::{GeneratedShader, KindDecl, Shader};
use lumagraph_graph::group::{Group, GroupDecl};
use lumagraph_graph::{
    ErrorKind, Graph, GraphError, GraphErrors, NodeKind, ParamType, Pos, Registry,
};

/// Where the declared function's text comes from, for locating errors.
struct Code {
    text: String,
    /// The file holding it.
    file: PathBuf,
    /// The file line of the code's line 1, when known.
    first_line: Option<usize>,
}

/// `base` with the kinds `graph` declares added, each with its shader generated and
/// validated (see the module docs), and its group kinds (graph files used as nodes, see
/// [`lumagraph_graph::group`]) loaded, each with the kinds it declares and its own groups.
///
/// # Errors
/// Every declaration that fails: a bad declaration located at the kind in the graph file,
/// a missing `.wgsl` file, WGSL that does not compile located at its file, line and column
/// and naming the nodes of that kind, a name a kind of `base` already has; a group file
/// that cannot be loaded or whose interface is wrong, or a group that contains itself
/// (named with the chain of files).
pub fn registry_for(graph: &Graph, base: &Registry) -> Result<Registry, GraphErrors> {
    let mut chain = Vec::new();
    if let Some(o) = &graph.origin {
        chain.push(std::fs::canonicalize(&o.path).unwrap_or_else(|_| o.path.clone()));
    }
    registry_in(graph, base, &mut chain)
}

/// [`registry_for`] a graph reached through the group files in `chain` (the outermost
/// first, this graph's file last).
fn registry_in(
    graph: &Graph,
    base: &Registry,
    chain: &mut Vec<PathBuf>,
) -> Result<Registry, GraphErrors> {
    let mut registry = base.clone();
    let mut errors = Vec::new();
    for decl in &graph.kinds {
        match declared_kind(graph, decl) {
            Ok(kind) => {
                if let Err(m) = registry.add(kind) {
                    errors.push(at_decl(graph, decl, m));
                }
            }
            Err(e) => errors.push(e),
        }
    }
    for decl in &graph.groups {
        match load_group(graph, decl, base, chain) {
            Ok(group) => {
                if let Err(m) = registry.add_group(group) {
                    errors.push(at_group(graph, decl, m));
                }
            }
            Err(mut e) => errors.append(&mut e.0),
        }
    }
    if errors.is_empty() {
        Ok(registry)
    } else {
        Err(GraphErrors(errors))
    }
}

/// The group `decl` of `graph` declares, loaded with the kinds its nodes use.
fn load_group(
    graph: &Graph,
    decl: &GroupDecl,
    base: &Registry,
    chain: &mut Vec<PathBuf>,
) -> Result<Group, GraphErrors> {
    let path = graph.base_dir().join(&decl.file);
    let canonical = std::fs::canonicalize(&path).map_err(|e| {
        GraphErrors(vec![at_group(
            graph,
            decl,
            format!("cannot read {}: {e}", path.display()),
        )])
    })?;
    if chain.contains(&canonical) || chain.len() > lumagraph_graph::group::MAX_DEPTH {
        let files: Vec<String> = chain
            .iter()
            .chain([&canonical])
            .map(|p| p.display().to_string())
            .collect();
        let why = if chain.contains(&canonical) {
            "contains itself"
        } else {
            "nests too deep"
        };
        return Err(GraphErrors(vec![at_group(
            graph,
            decl,
            format!("the group {why}: {}", files.join(" -> ")),
        )]));
    }
    let inner = Graph::load(&canonical).map_err(|e| GraphErrors(vec![e]))?;
    chain.push(canonical);
    let registry = registry_in(&inner, base, chain);
    chain.pop();
    Ok(Group {
        name: lumagraph_graph::custom::intern(&decl.name),
        graph: inner,
        registry: registry?,
    })
}

/// An error about group declaration `decl`, located at it in the graph file.
fn at_group(graph: &Graph, decl: &GroupDecl, message: impl std::fmt::Display) -> GraphError {
    GraphError {
        file: graph.origin.as_ref().map(|o| o.path.clone()),
        pos: graph.origin.as_ref().and_then(|o| o.kind_pos(&decl.name)),
        ..GraphError::new(ErrorKind::Source(format!(
            "group \"{}\" ({}): {message}",
            decl.name, decl.file
        )))
    }
}

/// An error about declaration `decl`, located at it in the graph file.
fn at_decl(graph: &Graph, decl: &KindDecl, message: impl std::fmt::Display) -> GraphError {
    GraphError {
        file: graph.origin.as_ref().map(|o| o.path.clone()),
        pos: graph.origin.as_ref().and_then(|o| o.kind_pos(&decl.name)),
        ..GraphError::new(ErrorKind::Source(format!(
            "kind \"{}\": {message}",
            decl.name
        )))
    }
}

fn declared_kind(graph: &Graph, decl: &KindDecl) -> Result<NodeKind, GraphError> {
    let placeholder = Shader::File("");
    let mut kind = decl
        .to_kind(placeholder)
        .map_err(|m| at_decl(graph, decl, m))?;
    let graph_file = graph
        .origin
        .as_ref()
        .map_or_else(|| PathBuf::from("(graph)"), |o| o.path.clone());
    let code = if decl.code.trim().is_empty() {
        {
            let file = graph.base_dir().join(&decl.wgsl);
            let text = lumagraph_graph::read_text(&file).map_err(|e| {
                at_decl(graph, decl, format!("cannot read {}: {e}", file.display()))
            })?;
            Code {
                text,
                file,
                first_line: Some(1),
            }
        }
    } else {
        Code {
            text: decl.code.clone(),
            first_line: graph
                .origin
                .as_ref()
                .and_then(|o| o.code_first_line(&decl.code)),
            file: graph_file,
        }
    };
    let nodes: Vec<&str> = graph
        .nodes
        .iter()
        .filter(|n| n.kind == decl.name)
        .map(|n| n.id.as_str())
        .collect();
    let generated = generate(&kind, &code).map_err(|(message, pos)| {
        let used_by = match nodes.as_slice() {
            [] => String::new(),
            ids => format!(" (used by node {})", ids.join(", ")),
        };
        GraphError {
            file: Some(code.file.clone()),
            pos,
            ..GraphError::new(ErrorKind::Source(format!(
                "kind \"{}\"{used_by}: {message}",
                decl.name
            )))
        }
    })?;
    kind.shader = Some(Shader::Generated(Arc::new(generated)));
    // The generic filter's contract holds by construction; checked all the same.
    crate::nodes::post_filter::check(&kind).map_err(|m| at_decl(graph, decl, m))?;
    Ok(kind)
}

fn wgsl_format(ty: lumagraph_graph::PortType) -> &'static str {
    match ty.format() {
        lumagraph_graph::TexFormat::Rgba32Float => "rgba32float",
        lumagraph_graph::TexFormat::Rgba8Unorm => "rgba8unorm",
        lumagraph_graph::TexFormat::R32Float => "r32float",
    }
}

/// The module for `kind` around `code`, validated; or the first error and where it is in
/// the code's file.
/// The bindings, params, helpers and entry point generated around a declared function.
fn generated_head(kind: &NodeKind) -> String {
    let mut head = format!(
        "// Generated by lumagraph for the node kind \"{}\" declared in a graph file.\n",
        kind.name
    );
    let members: Vec<String> = kind
        .params
        .iter()
        .map(|p| {
            let ty = match p.ty {
                ParamType::Float { .. } => "f32",
                ParamType::Int { .. } => "i32",
                _ => "u32",
            };
            format!("    {}: {ty},\n", p.name)
        })
        .chain(
            kind.inputs
                .iter()
                .filter(|i| i.optional)
                .map(|i| format!("    has_{}: u32,\n", i.name)),
        )
        .collect();
    let mut binding = 0;
    for i in &kind.inputs {
        let _ = writeln!(
            head,
            "@group(0) @binding({binding}) var {}: texture_2d<f32>;",
            i.name
        );
        binding += 1;
    }
    for o in &kind.outputs {
        let _ = writeln!(
            head,
            "@group(0) @binding({binding}) var out_{}: texture_storage_2d<{}, write>;",
            o.name,
            wgsl_format(o.ty)
        );
        binding += 1;
    }
    if !members.is_empty() {
        let _ = writeln!(head, "struct Params {{\n{}}}", members.concat());
        let _ = writeln!(
            head,
            "@group(0) @binding({binding}) var<uniform> params: Params;"
        );
    }
    for i in &kind.inputs {
        let _ = writeln!(
            head,
            "fn load_{0}(p: vec2i) -> vec4f {{\n    let last = vec2i(textureDimensions({0})) - 1;\n    return textureLoad({0}, clamp(p, vec2i(0), last), 0);\n}}",
            i.name
        );
    }
    let several = kind.outputs.len() > 1;
    if several {
        let fields: String = kind
            .outputs
            .iter()
            .map(|o| format!("    {}: vec4f,\n", o.name))
            .collect();
        let _ = writeln!(head, "struct Outputs {{\n{fields}}}");
    }
    let first = kind.outputs[0].name;
    let stores: String = if several {
        kind.outputs
            .iter()
            .map(|o| format!("    textureStore(out_{0}, id.xy, r.{0});\n", o.name))
            .collect()
    } else {
        format!("    textureStore(out_{first}, id.xy, r);\n")
    };
    let _ = writeln!(
        head,
        "@compute @workgroup_size(8, 8)\nfn main(@builtin(global_invocation_id) id: vec3u) {{\n    let size = textureDimensions(out_{first});\n    if id.x >= size.x || id.y >= size.y {{\n        return;\n    }}\n    let r = node(id.xy, size);\n{stores}}}"
    );
    head
}

/// Parses and validates `text` with naga; an error is located in the code's file when it
/// falls in the code (which starts at line `code_start + 1`).
fn validate(
    text: &str,
    code_start: usize,
    code: &Code,
    several: bool,
) -> Result<(), (String, Option<Pos>)> {
    let located = |loc: Option<naga::SourceLocation>, message: String| {
        let Some(loc) = loc else {
            return (message, None);
        };
        let line = loc.line_number as usize;
        if line > code_start {
            let code_line = line - code_start;
            match code.first_line {
                Some(first) => (
                    message,
                    Some(Pos {
                        line: first + code_line - 1,
                        col: loc.line_position as usize,
                    }),
                ),
                None => (format!("line {code_line} of its code: {message}"), None),
            }
        } else {
            (
                format!(
                    "{message} (in the code generated around the function: it must define \
                     `fn node(pixel: vec2u, size: vec2u) -> {}`)",
                    if several { "Outputs" } else { "vec4f" }
                ),
                None,
            )
        }
    };
    let module = naga::front::wgsl::parse_str(text)
        .map_err(|e| located(e.location(text), e.message().to_owned()))?;
    naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::all(),
    )
    .validate(&module)
    .map_err(|e| {
        let mut message = e.as_inner().to_string();
        let mut source = std::error::Error::source(e.as_inner());
        while let Some(s) = source {
            let _ = write!(message, ": {s}");
            source = s.source();
        }
        // The innermost span (the expression, not the whole function) says most.
        let loc = e
            .spans()
            .filter(|(span, _)| span.is_defined())
            .last()
            .map(|(span, _)| span.location(text));
        located(loc, message)
    })?;
    Ok(())
}

fn generate(kind: &NodeKind, code: &Code) -> Result<GeneratedShader, (String, Option<Pos>)> {
    let several = kind.outputs.len() > 1;
    let head = generated_head(kind);
    // The code's #import lines are resolved ahead of it and blanked in place, so its lines
    // keep their numbers.
    let mut imports = String::new();
    let mut body = String::new();
    for line in code.text.lines() {
        if line.trim_start().starts_with("#import") {
            imports.push_str(line.trim());
            imports.push('\n');
            body.push('\n');
        } else {
            body.push_str(line);
            body.push('\n');
        }
    }
    let imported = if imports.is_empty() {
        String::new()
    } else {
        const NAME: &str = "(imports of a declared kind)";
        crate::shader::resolve_with(NAME, &[(NAME, imports)]).map_err(|e| (e.to_string(), None))?
    };
    let mut text = head;
    text.push_str(&imported);
    if !text.ends_with('\n') {
        text.push('\n');
    }
    let code_start = text.lines().count();
    text.push_str(&body);

    validate(&text, code_start, code, several)?;
    Ok(GeneratedShader {
        label: format!("{} ({})", kind.name, code.file.display()),
        text,
    })
}

/// [`registry_for`] the graph over the built-in kinds (a program with kinds of its own
/// uses [`NodeLibrary::registry_for`](crate::NodeLibrary::registry_for)); the folder
/// relative `.wgsl` paths are read from is the graph's.
///
/// # Errors
/// As [`registry_for`].
pub fn registry(graph: &Graph) -> Result<Registry, GraphErrors> {
    registry_for(graph, &Registry::with_builtins())
}

/// Checks a graph file meant as a node group on its own (it has an `interface` and no
/// sink, so it cannot be compiled without a graph around it): its interface, and every
/// node's kind and params against `registry` (the graph's, with its declared kinds and
/// groups). Returns the kind a node of it would be.
///
/// # Errors
/// Everything found, located in the file.
pub fn check_group(graph: &Graph, registry: Registry) -> Result<NodeKind, GraphErrors> {
    let file = graph.origin.as_ref().map(|o| o.path.clone());
    let mut errors = Vec::new();
    for node in &graph.nodes {
        let Some(kind) = registry.get(&node.kind) else {
            let e = GraphError::new(ErrorKind::Source(format!(
                "unknown node kind \"{}\"",
                node.kind
            )))
            .now_about(&node.id);
            errors.push(graph.locate(e, None, None));
            continue;
        };
        if registry.group(&node.kind).is_some() {
            continue;
        }
        if let Err(found) = lumagraph_graph::resolve_params(node, kind) {
            for (param, kind) in found {
                let e = GraphError::new(kind).now_about(&node.id);
                errors.push(graph.locate(e, None, Some(&param)));
            }
        }
    }
    let name = graph
        .origin
        .as_ref()
        .and_then(|o| o.path.file_stem())
        .map_or_else(|| "Group".to_owned(), |s| s.to_string_lossy().into_owned());
    let group = Group {
        name: lumagraph_graph::custom::intern(&name),
        graph: graph.clone(),
        registry,
    };
    match group.kind() {
        Ok(kind) if errors.is_empty() => return Ok(kind),
        Ok(_) => {}
        Err(m) => errors.push(GraphError {
            file,
            ..GraphError::new(ErrorKind::Source(format!("interface: {m}")))
        }),
    }
    Err(GraphErrors(errors))
}
