//! Validation, pruning and texture assignment, and the RON round trip.

use lumagraph_graph::{
    CompileOptions, Edge, ErrorKind, Extent, Graph, GraphErrors, Node, NodeKind, ParamValue, Plan,
    Registry, compile,
};

fn extent(_: &NodeKind, _: &lumagraph_graph::Params) -> Result<Extent, String> {
    Ok(Extent::new(64, 32))
}

fn compile_graph(g: &Graph) -> Result<Plan, GraphErrors> {
    compile(
        g,
        &Registry::with_builtins(),
        &CompileOptions {
            source_extent: &extent,
            keep: &[],
        },
    )
}

fn chain() -> Graph {
    Graph {
        nodes: vec![
            Node::new("input", "ImageInput").with("path", ParamValue::Str("in.exr".into())),
            Node::new("exposure", "Exposure").with("ev", ParamValue::Float(1.0)),
            Node::new("tonemap", "Tonemap").with("operator", ParamValue::Str("agx".into())),
            Node::new("out", "Output").with("path", ParamValue::Str("out.png".into())),
        ],
        edges: vec![
            Edge::new("input.color", "exposure.color"),
            Edge::new("exposure.color", "tonemap.color"),
            Edge::new("tonemap.color", "out.color"),
        ],
        ..Graph::default()
    }
}

fn load_str(text: &str) -> Result<Graph, lumagraph_graph::GraphError> {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("g.ron");
    std::fs::write(&path, text).unwrap();
    Graph::load(&path)
}

/// Loads `text` and compiles it, returning the one error message expected.
fn single_error(text: &str) -> (ErrorKind, String) {
    let g = load_str(text).unwrap();
    let errors = compile_graph(&g).expect_err("graph should be rejected");
    let message = errors.to_string();
    assert_eq!(errors.0.len(), 1, "expected one error, got: {message}");
    let e = errors.0.into_iter().next().unwrap();
    assert!(e.file.is_some(), "error names no file: {message}");
    (*e.kind, message)
}

#[test]
fn chain_compiles_in_order() {
    let plan = compile_graph(&chain()).unwrap();
    let order: Vec<_> = plan.passes.iter().map(|p| p.node.as_str()).collect();
    assert_eq!(order, ["input", "exposure", "tonemap", "out"]);
    // ImageInput's layer ports that nothing reads.
    let left: Vec<&str> = plan.left_out.iter().map(|l| l.what.as_str()).collect();
    assert_eq!(left, ["texture input.scalar", "texture input.vector"]);
    assert!((plan.pass("exposure").unwrap().params.float("ev") - 1.0).abs() < 1e-12);
    // defaults filled in
    assert!((plan.pass("tonemap").unwrap().params.float("white") - 4.0).abs() < 1e-12);
}

#[test]
fn textures_share_memory_when_lifetimes_do_not_overlap() {
    // input -> e1 -> e2 -> e3 -> out: input.color dies at pass 2, e2.color is written at 3.
    let mut g = chain();
    g.nodes = vec![
        Node::new("input", "ImageInput"),
        Node::new("e1", "Exposure"),
        Node::new("e2", "Exposure"),
        Node::new("e3", "Exposure"),
        Node::new("out", "Output"),
    ];
    g.edges = vec![
        Edge::new("input.color", "e1.color"),
        Edge::new("e1.color", "e2.color"),
        Edge::new("e2.color", "e3.color"),
        Edge::new("e3.color", "out.color"),
    ];
    let plan = compile_graph(&g).unwrap();
    assert_eq!(plan.textures.len(), 4);
    assert_eq!(plan.slots.len(), 2, "{plan}");
    // no two textures in one slot overlap in time
    for slot in &plan.slots {
        for w in slot.textures.windows(2) {
            assert!(
                plan.textures[w[0].0].last < plan.textures[w[1].0].first,
                "{plan}"
            );
        }
    }
    assert_eq!(plan.texture_bytes() * 2, plan.unshared_texture_bytes());
}

#[test]
fn dead_branch_is_left_out() {
    let mut g = chain();
    g.nodes.push(Node::new("debug", "Tonemap"));
    g.edges.push(Edge::new("exposure.color", "debug.color"));
    let plan = compile_graph(&g).unwrap();
    assert!(plan.pass("debug").is_none());
    assert!(
        plan.left_out
            .iter()
            .any(|l| l.what.contains("\"debug\"") && l.reason.contains("no output"))
    );
    assert!(
        plan.to_string()
            .contains("node \"debug\" (Tonemap): feeds no output")
    );
}

#[test]
fn kept_port_stays_alive_to_the_end() {
    let keep = ["exposure.color".to_owned()];
    let plan = compile(
        &chain(),
        &Registry::with_builtins(),
        &CompileOptions {
            source_extent: &extent,
            keep: &keep,
        },
    )
    .unwrap();
    let t = plan
        .textures
        .iter()
        .find(|t| t.name == "exposure.color")
        .unwrap();
    assert_eq!(t.last, plan.passes.len());
}

#[test]
fn ron_round_trip_is_identical() {
    let mut g = chain();
    g.nodes[0].pos = Some((10.0, -20.5));
    let text = g.to_ron();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("chain.ron");
    g.save(&path).unwrap();
    let loaded = Graph::load(&path).unwrap();
    assert_eq!(loaded, g);
    loaded.save(&path).unwrap();
    assert_eq!(std::fs::read_to_string(&path).unwrap(), text);
    // no temporary files left behind
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
}

#[test]
fn shipped_graphs_round_trip_and_compile() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../graphs");
    let mut n = 0;
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "ron") {
            let g = Graph::load(&path).unwrap();
            let again = Graph::from_ron(&g.to_ron()).unwrap();
            assert_eq!(g, again, "{}", path.display());
            // Declared kinds get their shaders in the render crate; here a placeholder.
            let mut registry = Registry::with_builtins();
            for decl in &g.kinds {
                let kind = decl
                    .to_kind(lumagraph_graph::custom::Shader::File("(declared)"))
                    .unwrap();
                registry.add(kind).unwrap();
            }
            // Group files (of built-in kinds only here), loaded as the render crate does.
            for decl in &g.groups {
                let inner = Graph::load(&g.base_dir().join(&decl.file)).unwrap();
                let group = lumagraph_graph::group::Group {
                    name: lumagraph_graph::custom::intern(&decl.name),
                    graph: inner,
                    registry: Registry::with_builtins(),
                };
                registry.add_group(group).unwrap();
            }
            let options = CompileOptions {
                source_extent: &extent,
                keep: &[],
            };
            compile(&g, &registry, &options).unwrap_or_else(|e| panic!("{e}"));
            n += 1;
        }
    }
    assert!(n > 0);
}

#[test]
fn save_to_unwritable_place_keeps_old_file() {
    let dir = tempfile::tempdir().unwrap();
    let err = chain()
        .save(&dir.path().join("missing-dir/g.ron"))
        .unwrap_err();
    assert!(err.to_string().contains("cannot write graph file"), "{err}");
}

const HEAD: &str = "(\n    version: 1,\n    nodes: [\n";

fn graph_text(nodes: &str, edges: &str) -> String {
    format!("{HEAD}{nodes}    ],\n    edges: [\n{edges}    ],\n)\n")
}

const GOOD_NODES: &str = r#"        (id: "input", kind: "ImageInput", params: {"path": "in.exr"}),
        (id: "tonemap", kind: "Tonemap"),
        (id: "out", kind: "Output"),
"#;
const GOOD_EDGES: &str = r#"        (from: "input.color", to: "tonemap.color"),
        (from: "tonemap.color", to: "out.color"),
"#;

#[test]
fn good_text_compiles() {
    compile_graph(&load_str(&graph_text(GOOD_NODES, GOOD_EDGES)).unwrap()).unwrap();
}

#[test]
fn malformed_ron_names_line_and_column() {
    let text = graph_text(GOOD_NODES, GOOD_EDGES).replace(
        "(id: \"tonemap\", kind: \"Tonemap\"),",
        "(id: \"tonemap\" kind: \"Tonemap\"),",
    );
    let e = load_str(&text).unwrap_err();
    assert!(matches!(*e.kind, ErrorKind::Syntax(_)), "{e}");
    let pos = e.pos.unwrap();
    assert_eq!(pos.line, 5, "{e}");
    assert!(e.to_string().contains("g.ron:5:"), "{e}");
}

#[test]
fn unsupported_version() {
    let e = load_str("(version: 7, nodes: [])").unwrap_err();
    assert!(
        matches!(*e.kind, ErrorKind::Version { found: 7, .. }),
        "{e}"
    );
}

#[test]
fn unknown_kind() {
    let (k, m) = single_error(&graph_text(
        &GOOD_NODES.replace("\"Tonemap\"", "\"Tonemapp\""),
        GOOD_EDGES,
    ));
    assert!(matches!(k, ErrorKind::UnknownKind { .. }), "{m}");
    assert!(
        m.contains("g.ron:5:") && m.contains("node \"tonemap\"") && m.contains("Tonemapp"),
        "{m}"
    );
}

#[test]
fn unknown_param() {
    let nodes = GOOD_NODES.replace(
        "kind: \"Tonemap\")",
        "kind: \"Tonemap\", params: {\"whit\": 2.0})",
    );
    let (k, m) = single_error(&graph_text(&nodes, GOOD_EDGES));
    assert!(matches!(k, ErrorKind::UnknownParam { .. }), "{m}");
    assert!(
        m.contains("\"whit\"") && m.contains("operator, white") && m.contains("g.ron:5:"),
        "{m}"
    );
}

#[test]
fn param_of_wrong_type() {
    let nodes = GOOD_NODES.replace(
        "kind: \"Tonemap\")",
        "kind: \"Tonemap\", params: {\"white\": \"bright\"})",
    );
    let (k, m) = single_error(&graph_text(&nodes, GOOD_EDGES));
    assert!(matches!(k, ErrorKind::BadParam { .. }), "{m}");
    assert!(
        m.contains("expected float or a frame expression") && m.contains("\"bright\""),
        "{m}"
    );
}

#[test]
fn param_out_of_range() {
    let nodes = GOOD_NODES.replace(
        "kind: \"Tonemap\")",
        "kind: \"Tonemap\", params: {\"white\": -1.0})",
    );
    let (_, m) = single_error(&graph_text(&nodes, GOOD_EDGES));
    assert!(m.contains("out of range"), "{m}");
}

#[test]
fn enum_value_not_an_option() {
    let nodes = GOOD_NODES.replace(
        "kind: \"Tonemap\")",
        "kind: \"Tonemap\", params: {\"operator\": \"filmic\"})",
    );
    let (_, m) = single_error(&graph_text(&nodes, GOOD_EDGES));
    assert!(
        m.contains("\"filmic\" is not one of") && m.contains("\"agx\""),
        "{m}"
    );
}

#[test]
fn edge_to_missing_node() {
    let edges = GOOD_EDGES.replace("to: \"out.color\"", "to: \"outt.color\"");
    let (k, m) = single_error(&graph_text(GOOD_NODES, &edges));
    assert!(matches!(k, ErrorKind::MissingNode { .. }), "{m}");
    assert!(
        m.contains("g.ron:10:") && m.contains("no node \"outt\""),
        "{m}"
    );
}

#[test]
fn edge_to_missing_port() {
    let edges = GOOD_EDGES.replace("to: \"out.color\"", "to: \"out.colour\"");
    let (k, m) = single_error(&graph_text(GOOD_NODES, &edges));
    assert!(matches!(k, ErrorKind::MissingPort { .. }), "{m}");
    assert!(
        m.contains("no input port \"colour\"") && m.contains("its input ports: color"),
        "{m}"
    );
}

#[test]
fn edge_not_node_dot_port() {
    let edges = GOOD_EDGES.replace("from: \"tonemap.color\"", "from: \"tonemap\"");
    let (k, m) = single_error(&graph_text(GOOD_NODES, &edges));
    assert!(matches!(k, ErrorKind::BadPortRef(_)), "{m}");
}

#[test]
fn incompatible_port_types() {
    // Tonemap makes LDR color; Exposure takes only HDR.
    let nodes = format!("{GOOD_NODES}        (id: \"exp\", kind: \"Exposure\"),\n");
    let edges = format!("{GOOD_EDGES}        (from: \"tonemap.color\", to: \"exp.color\"),\n");
    let (k, m) = single_error(&graph_text(&nodes, &edges));
    assert!(matches!(k, ErrorKind::IncompatibleTypes { .. }), "{m}");
    assert!(
        m.contains("tonemap.color produces ldr_color, but exp.color accepts hdr_color"),
        "{m}"
    );
}

#[test]
fn cycle_is_refused() {
    let nodes = r#"        (id: "input", kind: "ImageInput"),
        (id: "a", kind: "Exposure"),
        (id: "b", kind: "Exposure"),
        (id: "out", kind: "Output"),
"#;
    let edges = r#"        (from: "a.color", to: "b.color"),
        (from: "b.color", to: "a.color"),
        (from: "b.color", to: "out.color"),
"#;
    let (k, m) = single_error(&graph_text(nodes, edges));
    assert!(matches!(k, ErrorKind::Cycle(_)), "{m}");
    assert!(m.contains("\"a\", \"b\""), "{m}");
}

#[test]
fn duplicate_node_ids() {
    let nodes = format!("{GOOD_NODES}        (id: \"tonemap\", kind: \"Exposure\"),\n");
    let g = load_str(&graph_text(&nodes, GOOD_EDGES)).unwrap();
    let errors = compile_graph(&g).unwrap_err();
    assert!(
        errors
            .0
            .iter()
            .any(|e| matches!(*e.kind, ErrorKind::DuplicateId(_))),
        "{errors}"
    );
}

#[test]
fn graph_without_output() {
    let nodes = r#"        (id: "input", kind: "ImageInput"),
        (id: "tonemap", kind: "Tonemap"),
"#;
    let (k, m) = single_error(&graph_text(
        nodes,
        "        (from: \"input.color\", to: \"tonemap.color\"),\n",
    ));
    assert!(matches!(k, ErrorKind::NoOutput), "{m}");
}

#[test]
fn two_edges_into_one_input() {
    let nodes = format!("{GOOD_NODES}        (id: \"input2\", kind: \"ImageInput\"),\n");
    let edges = format!("{GOOD_EDGES}        (from: \"input2.color\", to: \"tonemap.color\"),\n");
    let (k, m) = single_error(&graph_text(&nodes, &edges));
    assert!(matches!(k, ErrorKind::TwoEdgesIntoInput { .. }), "{m}");
    assert!(m.contains("from input.color and input2.color"), "{m}");
}

#[test]
fn unconnected_input_of_needed_node() {
    let (k, m) = single_error(&graph_text(
        GOOD_NODES,
        "        (from: \"tonemap.color\", to: \"out.color\"),\n",
    ));
    assert!(matches!(k, ErrorKind::UnconnectedInput { .. }), "{m}");
    assert!(
        m.contains("node \"tonemap\"") && m.contains("\"color\" is not connected"),
        "{m}"
    );
}

#[test]
fn source_that_cannot_tell_its_size() {
    let g = load_str(&graph_text(GOOD_NODES, GOOD_EDGES)).unwrap();
    let fail = |_: &NodeKind, _: &lumagraph_graph::Params| Err("cannot open in.exr".to_owned());
    let e = compile(
        &g,
        &Registry::with_builtins(),
        &CompileOptions {
            source_extent: &fail,
            keep: &[],
        },
    )
    .unwrap_err();
    let m = e.to_string();
    assert!(
        m.contains("node \"input\"") && m.contains("cannot open in.exr") && m.contains("g.ron:4:"),
        "{m}"
    );
}

#[test]
fn overrides_set_params() {
    let mut g = chain();
    g.apply_override("tonemap.operator=reinhard").unwrap();
    g.apply_override("exposure.ev=-2").unwrap();
    let plan = compile_graph(&g).unwrap();
    assert_eq!(
        plan.pass("tonemap").unwrap().params.str("operator"),
        "reinhard"
    );
    assert!((plan.pass("exposure").unwrap().params.float("ev") + 2.0).abs() < 1e-12);
    assert!(g.apply_override("nope.ev=1").is_err());
    assert!(g.apply_override("exposure.ev").is_err());
}

#[cfg(unix)]
#[test]
fn saved_files_are_readable_by_others_and_keep_permissions() {
    use std::os::unix::fs::PermissionsExt as _;
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("g.ron");
    chain().save(&path).unwrap();
    assert_eq!(
        std::fs::metadata(&path).unwrap().permissions().mode() & 0o777,
        0o644
    );
    std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o600)).unwrap();
    chain().save(&path).unwrap();
    assert_eq!(
        std::fs::metadata(&path).unwrap().permissions().mode() & 0o777,
        0o600
    );
}

fn compile_with(g: &Graph, registry: &Registry) -> Result<Plan, GraphErrors> {
    compile(
        g,
        registry,
        &CompileOptions {
            source_extent: &extent,
            keep: &[],
        },
    )
}

/// A Denoise without its optional `variance` compiles; the plan says it was left out.
/// Its required inputs still are required.
#[test]
fn optional_input_may_stay_unconnected() {
    let mut g = Graph::new();
    g.nodes = vec![
        Node::new("img", "ImageInput"),
        Node::new("dn", "Denoise"),
        Node::new("out", "Output"),
    ];
    g.edges = vec![
        Edge::new("img.color", "dn.color"),
        Edge::new("dn.color", "out.color"),
    ];
    // albedo and normal are required: two errors, none for depth or variance.
    let e = compile_graph(&g).unwrap_err();
    let m = e.to_string();
    assert_eq!(e.0.len(), 2, "{m}");
    assert!(!m.contains("variance") && !m.contains("depth"), "{m}");

    g.nodes.insert(0, Node::new("gb", "GBuffer"));
    g.edges = vec![
        Edge::new("img.color", "dn.color"),
        Edge::new("gb.albedo", "dn.albedo"),
        Edge::new("gb.normal", "dn.normal"),
        Edge::new("gb.depth", "dn.depth"),
        Edge::new("dn.color", "out.color"),
    ];
    let plan = compile_graph(&g).unwrap();
    let dn = plan.pass("dn").unwrap();
    assert_eq!(dn.inputs.len(), 4);
    assert!(dn.input("variance").is_none());
    assert!(
        plan.left_out
            .iter()
            .any(|l| l.what == "input dn.variance" && l.reason.contains("optional")),
        "{plan}"
    );
}

/// A test kind with a half-size output and one sized from a param, on an owned registry
/// that also holds the built-ins.
fn sized_registry() -> Registry {
    use lumagraph_graph::registry::{InputDef, OutputDef, OutputSize, ParamDef};
    use lumagraph_graph::{Category, ParamType, PortType};
    fn from_width(input: Extent, params: &lumagraph_graph::Params) -> Result<Extent, String> {
        let w = params.int("width");
        if w > 4096 {
            return Err(format!("width {w} is more than 4096"));
        }
        let w = u32::try_from(w).map_err(|e| e.to_string())?;
        // keep the aspect ratio
        let h = (u64::from(input.height) * u64::from(w)).div_ceil(u64::from(input.width));
        Ok(Extent::new(w, u32::try_from(h).map_err(|e| e.to_string())?))
    }
    let mut r = Registry::with_builtins();
    r.add(NodeKind {
        name: "Pyramid",
        category: Category::Color,
        doc: "test kind",
        inputs: vec![InputDef::new("color", &[PortType::HdrColor], "in")],
        outputs: vec![
            OutputDef::new("half", PortType::HdrColor, "half size")
                .sized(OutputSize::Scaled { num: 1, den: 2 }),
            OutputDef::new("wide", PortType::HdrColor, "sized by a param").sized(OutputSize::Rule(
                from_width,
                "`width` wide, the input's aspect ratio",
            )),
            OutputDef::new("same", PortType::HdrColor, "same size"),
        ],
        params: vec![ParamDef {
            name: "width",
            ty: ParamType::Int {
                default: 100,
                min: 1,
                max: 100_000,
            },
            doc: "width of `wide`",
        }],
        sink: false,
        history: false,
        renders_scene: false,
        shader: None,
        example: Vec::new(),
        reach: lumagraph_graph::registry::Reach::Pixel,
    })
    .unwrap();
    r
}

/// Each output has the size its rule gives; passes downstream run at their input's size;
/// textures of different sizes never share an allocation.
#[test]
fn outputs_have_their_own_sizes() {
    let registry = sized_registry();
    let mut g = Graph::new();
    g.nodes = vec![
        Node::new("img", "ImageInput"), // 64x32
        Node::new("p", "Pyramid").with("width", ParamValue::Int(16)),
        Node::new("e_half", "Exposure"),
        Node::new("e_wide", "Exposure"),
        Node::new("e_same", "Exposure"),
        Node::new("o1", "Output"),
        Node::new("o2", "Output"),
        Node::new("o3", "Output"),
    ];
    g.edges = vec![
        Edge::new("img.color", "p.color"),
        Edge::new("p.half", "e_half.color"),
        Edge::new("p.wide", "e_wide.color"),
        Edge::new("p.same", "e_same.color"),
        Edge::new("e_half.color", "o1.color"),
        Edge::new("e_wide.color", "o2.color"),
        Edge::new("e_same.color", "o3.color"),
    ];
    let plan = compile_with(&g, &registry).unwrap();
    let size = |port: &str| {
        plan.textures
            .iter()
            .find(|t| t.name == port)
            .unwrap()
            .extent
    };
    assert_eq!(size("p.half"), Extent::new(32, 16));
    assert_eq!(size("p.wide"), Extent::new(16, 8));
    assert_eq!(size("p.same"), Extent::new(64, 32));
    assert_eq!(plan.pass("p").unwrap().extent, Extent::new(64, 32));
    assert_eq!(plan.pass("e_half").unwrap().extent, Extent::new(32, 16));
    assert_eq!(plan.pass("e_wide").unwrap().extent, Extent::new(16, 8));
    assert_eq!(size("e_half.color"), Extent::new(32, 16));
    for slot in &plan.slots {
        for t in &slot.textures {
            assert_eq!(plan.texture(*t).extent, slot.extent, "{plan}");
        }
    }
    // The docs state the rules.
    let md = lumagraph_graph::docs::markdown(&registry);
    assert!(md.contains("size: 1/2 of the input size"), "{md}");
    assert!(md.contains("size: `width` wide"), "{md}");
    assert!(
        md.contains("(optional) variance of the color's mean"),
        "{md}"
    );

    // A rule that refuses its params is an error located at the node.
    g.nodes[1] = Node::new("p", "Pyramid").with("width", ParamValue::Int(5000));
    let m = compile_with(&g, &registry).unwrap_err().to_string();
    assert!(
        m.contains("node \"p\"") && m.contains("output \"wide\": width 5000 is more than 4096"),
        "{m}"
    );
}

/// A node whose inputs arrive at different sizes is refused, naming both sizes.
#[test]
fn inputs_of_different_sizes_are_refused() {
    let registry = sized_registry();
    let mut g = Graph::new();
    g.nodes = vec![
        Node::new("img", "ImageInput"),
        Node::new("p", "Pyramid"),
        Node::new("gb", "GBuffer"),
        Node::new("dn", "Denoise"),
        Node::new("out", "Output"),
    ];
    g.edges = vec![
        Edge::new("img.color", "p.color"),
        Edge::new("p.half", "dn.color"),
        Edge::new("img.color", "dn.albedo"),
        Edge::new("gb.normal", "dn.normal"),
        Edge::new("gb.depth", "dn.depth"),
        Edge::new("dn.color", "out.color"),
    ];
    // albedo is an Albedo port; feed it from the GBuffer instead of the image
    g.edges[2] = Edge::new("gb.albedo", "dn.albedo");
    let m = compile_with(&g, &registry).unwrap_err().to_string();
    assert!(
        m.contains("node \"dn\"") && m.contains("inputs differ in size: 32x16 and 64x32"),
        "{m}"
    );
}

/// The registry is a value: kinds are added at run time, a second kind of the same name
/// or a kind repeating a port name is refused, and a graph using an added kind compiles
/// only against the registry that has it.
#[test]
fn registry_is_an_owned_value() {
    let mut registry = sized_registry();
    let exposure = NodeKind::clone(registry.get("Exposure").unwrap());
    let e = registry.add(exposure.clone()).unwrap_err();
    assert!(e.contains("\"Exposure\" is already registered"), "{e}");
    let mut twice = exposure;
    twice.name = "Twice";
    twice.params.push(twice.params[0].clone());
    let e = registry.add(twice).unwrap_err();
    assert!(e.contains("declares param \"ev\" twice"), "{e}");

    let mut g = Graph::new();
    g.nodes = vec![
        Node::new("img", "ImageInput"),
        Node::new("p", "Pyramid"),
        Node::new("out", "Output"),
    ];
    g.edges = vec![
        Edge::new("img.color", "p.color"),
        Edge::new("p.same", "out.color"),
    ];
    assert!(compile_with(&g, &registry).is_ok());
    let m = compile_graph(&g).unwrap_err().to_string();
    assert!(m.contains("unknown node kind \"Pyramid\""), "{m}");
}

/// Every kind's gallery example is a valid set of its params.
#[test]
fn gallery_examples_are_valid_params() {
    let registry = Registry::with_builtins();
    for kind in registry.kinds() {
        let node = kind
            .example
            .iter()
            .fold(Node::new("n", kind.name), |n, (k, v)| n.with(k, v.clone()));
        if let Err(e) = lumagraph_graph::resolve_params(&node, kind) {
            panic!("{}: {e:?}", kind.name);
        }
    }
}

/// A source that cannot tell its size gives one error: nodes computed from it are not
/// also reported for inputs of different sizes.
#[test]
fn an_unsized_source_is_reported_once() {
    let graph = Graph::from_ron(
        r#"(
            version: 1,
            nodes: [
                (id: "a", kind: "ImageInput", params: {"path": "missing.exr"}),
                (id: "b", kind: "ImageInput", params: {"path": "chart.exr"}),
                (id: "mix", kind: "Mix"),
                (id: "out", kind: "Output"),
            ],
            edges: [
                (from: "a.color", to: "mix.a"),
                (from: "b.color", to: "mix.b"),
                (from: "mix.color", to: "out.color"),
            ],
        )"#,
    )
    .unwrap();
    let registry = Registry::with_builtins();
    let sized = |kind: &NodeKind, params: &lumagraph_graph::Params| -> Result<Extent, String> {
        if params.str("path").contains("missing") {
            Err(format!("{}: cannot read {}", kind.name, params.str("path")))
        } else {
            Ok(Extent::new(8, 8))
        }
    };
    let errors = compile(
        &graph,
        &registry,
        &CompileOptions {
            source_extent: &sized,
            keep: &[],
        },
    )
    .unwrap_err();
    let messages: Vec<String> = errors.0.iter().map(ToString::to_string).collect();
    assert_eq!(messages.len(), 1, "{messages:#?}");
    assert!(
        messages.iter().all(|m| m.contains("cannot read")),
        "{messages:#?}"
    );
}

/// Every shipped graph is in the layout `save` writes, comments included: loading and
/// saving one gives its text back byte for byte.
#[test]
fn shipped_graphs_save_as_they_are_written() {
    let mut n = 0;
    for dir in ["graphs", "graphs/groups"] {
        for entry in std::fs::read_dir(repo_root().join(dir)).unwrap() {
            let path = entry.unwrap().path();
            if path.extension().is_some_and(|e| e == "ron") {
                let text = std::fs::read_to_string(&path).unwrap();
                let g = Graph::load(&path).unwrap();
                let again = g.to_ron();
                if again != text {
                    let _ = std::fs::write(
                        std::env::temp_dir().join(path.file_name().unwrap()),
                        &again,
                    );
                }
                assert_eq!(again, text, "{}", path.display());
                n += 1;
            }
        }
    }
    assert!(n >= 8, "{n} graphs");
}

fn repo_root() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Comments survive load → edit → save where they belong: the header, lines above a node
/// or an edge, and a comment after one on its line; a deleted node's comments go with it.
#[test]
fn comments_survive_an_edit_and_a_save() {
    let text = r#"// Header: what this graph is for.
// Second line.

(
    version: 1,
    nodes: [
        // The source image.
        (id: "input", kind: "ImageInput", params: {"path": "a.exr"}),
        (id: "exposure", kind: "Exposure", params: {"ev": 1.0}), // brighter
        // Dropped below.
        (id: "blur", kind: "Blur"),
        (id: "out", kind: "Output"),
    ],
    edges: [
        // Straight through.
        (from: "input.color", to: "exposure.color"),
        (from: "exposure.color", to: "out.color"),
    ],
)
"#;
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("c.ron");
    std::fs::write(&path, text).unwrap();
    let mut g = Graph::load(&path).unwrap();
    // Unchanged: the same bytes.
    assert_eq!(g.to_ron(), text);
    g.node_mut("exposure")
        .unwrap()
        .params
        .insert("ev".into(), ParamValue::Float(2.0));
    g.nodes.retain(|n| n.id != "blur");
    g.nodes.swap(0, 1);
    let saved = g.to_ron();
    assert!(
        saved.starts_with("// Header: what this graph is for.\n// Second line.\n\n(\n"),
        "{saved}"
    );
    assert!(
        saved.contains("        // The source image.\n        (id: \"input\""),
        "{saved}"
    );
    assert!(
        saved.contains("params: {\"ev\": 2.0}), // brighter\n"),
        "{saved}"
    );
    assert!(!saved.contains("Dropped below"), "{saved}");
    assert!(
        saved.contains("        // Straight through.\n        (from: \"input.color\""),
        "{saved}"
    );
    assert_eq!(Graph::from_ron(&saved).unwrap(), g);
}

/// The same graph compiles to the same pass order every time (edges are not taken in a
/// hash map's order): Output nodes at the same depth used to swap between runs.
#[test]
fn the_pass_order_does_not_change_between_compiles() {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../graphs/pathtrace_denoise.ron"
    ))
    .unwrap();
    let order = || {
        let g = Graph::from_ron(&text).unwrap();
        let plan = compile_graph(&g).unwrap();
        plan.passes
            .iter()
            .map(|p| p.node.clone())
            .collect::<Vec<_>>()
    };
    let first = order();
    for _ in 0..20 {
        assert_eq!(order(), first);
    }
}

/// Frames (version 4) keep the comments above them and after them on their line, found by
/// their label; an unchanged file is written back byte for byte.
#[test]
fn frame_comments_survive_an_edit_and_a_save() {
    let text = r#"(
    version: 4,
    nodes: [
        (id: "input", kind: "ImageInput", params: {"path": "a.exr"}),
        (id: "out", kind: "Output"),
    ],
    edges: [
        (from: "input.color", to: "out.color", via: [(100.0, 20.0)]),
    ],
    frames: [
        // What comes in.
        (label: "sources", nodes: ["input"]), // one for now
    ],
)
"#;
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("f.ron");
    std::fs::write(&path, text).unwrap();
    let mut g = Graph::load(&path).unwrap();
    assert_eq!(g.to_ron(), text);
    g.frames[0].nodes.push("out".into());
    let saved = g.to_ron();
    assert!(
        saved.contains(
            "        // What comes in.\n        (label: \"sources\", nodes: [\"input\", \"out\"]), // one for now\n"
        ),
        "{saved}"
    );
}
