//! A graph's working space: written and read as `working_space` (version 5), and the
//! conversions the compiler adds where a Rec. 709 port meets the working space.

use lumagraph_graph::{
    CompileOptions, Edge, Extent, Graph, Node, NodeKind, ParamValue, Plan, Registry, WorkingSpace,
    compile,
};

fn extent(_: &NodeKind, _: &lumagraph_graph::Params) -> Result<Extent, String> {
    Ok(Extent::new(64, 32))
}

/// Path tracer → Accumulate → Tonemap → Output, and Accumulate → an EXR Output.
fn render_graph(space: WorkingSpace) -> Graph {
    Graph {
        nodes: vec![
            Node::new("pathtrace", "PathTrace"),
            Node::new("accumulate", "Accumulate"),
            Node::new("tonemap", "Tonemap"),
            Node::new("png", "Output").with("path", ParamValue::Str("out.png".into())),
            Node::new("exr", "Output").with("path", ParamValue::Str("out.exr".into())),
        ],
        edges: vec![
            Edge::new("pathtrace.color", "accumulate.color"),
            Edge::new("accumulate.color", "tonemap.color"),
            Edge::new("tonemap.color", "png.color"),
            Edge::new("accumulate.color", "exr.color"),
        ],
        working_space: space,
        ..Graph::default()
    }
}

fn plan(g: &Graph) -> Plan {
    compile(
        g,
        &Registry::with_builtins(),
        &CompileOptions {
            source_extent: &extent,
            keep: &[],
        },
    )
    .unwrap_or_else(|e| panic!("{e}"))
}

fn nodes(plan: &Plan) -> Vec<&str> {
    plan.passes.iter().map(|p| p.node.as_str()).collect()
}

#[test]
fn a_rec709_graph_gets_no_conversion() {
    let p = plan(&render_graph(WorkingSpace::Rec709));
    let mut names = nodes(&p);
    names.sort_unstable();
    assert_eq!(names, ["accumulate", "exr", "pathtrace", "png", "tonemap"]);
    assert_eq!(p.working_space, WorkingSpace::Rec709);
}

/// In ACEScg the path tracer's Rec. 709 colour is converted into the working space after
/// it and back into Rec. 709 before the tone curve; the EXR output takes the working space.
#[test]
fn an_acescg_graph_converts_where_rec709_meets_it() {
    let p = plan(&render_graph(WorkingSpace::AcesCg));
    assert_eq!(p.working_space, WorkingSpace::AcesCg);
    let names = nodes(&p);
    for id in ["pathtrace_color_to_acescg", "accumulate_color_to_rec709"] {
        assert!(names.contains(&id), "{names:?}");
    }
    assert_eq!(names.len(), 7, "{names:?}");
    let to_working = p.pass("pathtrace_color_to_acescg").unwrap();
    assert_eq!(to_working.kind.name, "ColorSpace");
    assert_eq!(to_working.params.str("from"), "Linear Rec.709 (sRGB)");
    assert_eq!(to_working.params.str("to"), "ACEScg");
    let back = p.pass("accumulate_color_to_rec709").unwrap();
    assert_eq!(back.params.str("from"), "ACEScg");
    assert_eq!(back.params.str("to"), "Linear Rec.709 (sRGB)");
    // Accumulate reads the converted colour; the EXR output reads Accumulate's.
    let accumulate = p.pass("accumulate").unwrap();
    let exr = p.pass("exr").unwrap();
    assert_eq!(
        p.textures[accumulate.input("color").unwrap().0].name,
        "pathtrace_color_to_acescg.color"
    );
    assert_eq!(
        p.textures[exr.input("color").unwrap().0].name,
        "accumulate.color"
    );
}

#[test]
fn the_working_space_is_saved_as_version_5_and_read_back() {
    let g = render_graph(WorkingSpace::AcesCg);
    let text = g.to_ron();
    assert!(text.contains("version: 5"), "{text}");
    assert!(text.contains("working_space: \"ACEScg\""), "{text}");
    let back = Graph::from_ron(&text).unwrap();
    assert_eq!(back.working_space, WorkingSpace::AcesCg);
    assert_eq!(back, g);
    // The default is not written, and the version stays the oldest that holds the graph.
    let text = render_graph(WorkingSpace::Rec709).to_ron();
    assert!(
        text.contains("version: 1") && !text.contains("working_space"),
        "{text}"
    );
    // An older version, or an unknown space, is refused.
    let old = text.replace("version: 1,", "version: 4,\n    working_space: \"ACEScg\",");
    let e = Graph::from_ron(&old).unwrap_err().to_string();
    assert!(e.contains("version: 5"), "{e}");
    let bad = text.replace(
        "version: 1,",
        "version: 5,\n    working_space: \"Rec2020\",",
    );
    let e = Graph::from_ron(&bad).unwrap_err().to_string();
    assert!(e.contains("Rec2020") && e.contains("ACEScg"), "{e}");
}
