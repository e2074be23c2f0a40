//! The generator of `tests/graph/fuzz_graphs.rs`: a graph file (and the group files it uses)
//! made from a list of random choices.

use std::fmt;
use std::sync::{Arc, LazyLock};

use lumagraph::graph::{NodeKind, ParamType, PortType};
use lumagraph::render::NodeLibrary;

/// The built-in kinds, and their implementations for the runner.
pub static LIBRARY: LazyLock<NodeLibrary> =
    LazyLock::new(lumagraph::pathtrace::library::with_builtins);
/// Cases in a hundred that have a scene (each compiles the path tracer: slower).
const SCENE_PERCENT: usize = 4;

/// One generated graph: files written into the case's `in/` folder, `graph.ron` the graph.
#[derive(Clone)]
pub struct Case {
    pub files: Vec<(String, String)>,
    /// Rendered with a scene (the Cornell box at 8×8), so the kinds that render it may be
    /// used.
    pub scene: bool,
}

impl fmt::Debug for Case {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.scene {
            writeln!(f, "(with assets/cornell.ron at 8×8)")?;
        }
        for (name, text) in &self.files {
            writeln!(f, "--- {name} ---\n{text}")?;
        }
        Ok(())
    }
}

/// The generator's random choices, read in turn; past the end every choice is the first
/// option, so a shrunk list still makes a graph.
struct Choices<'a> {
    values: &'a [u32],
    at: usize,
}

impl Choices<'_> {
    fn below(&mut self, n: usize) -> usize {
        let v = self.values.get(self.at).copied().unwrap_or(0);
        self.at += 1;
        if n == 0 { 0 } else { v as usize % n }
    }

    /// Something unusual, `percent` times in 100 (never past the end of the choices).
    fn rarely(&mut self, percent: usize) -> bool {
        self.below(100) + percent >= 100
    }

    fn pick<'b, T>(&mut self, items: &'b [T]) -> &'b T {
        &items[self.below(items.len())]
    }

    fn word(&mut self, items: &[&'static str]) -> &'static str {
        items[self.below(items.len())]
    }
}

/// Output paths: inside the folder, and every way out of it (`@ABS@` is the case's
/// temporary folder; `link` a symbolic link in the output folder to a folder outside).
const OUT_PATHS: &[&str] = &[
    "o.png",
    "o.exr",
    "sub/o.exr",
    "sub/../p.png",
    "link/../q.png",
];
const ESCAPING_PATHS: &[&str] = &[
    "../escape.png",
    "../../escape.exr",
    "../../../escape.png",
    "@ABS@/abs.png",
    "link/x.png",
    "link/new/y.exr",
    "a/..",
    ".",
];

/// A value for a param of type `ty` of kind `kind`: mostly valid (its default, the ends
/// of its range, inside it), now and then past its range, NaN, infinite or of another type.
fn value(c: &mut Choices<'_>, kind: &str, ty: &ParamType) -> String {
    let bad = c.rarely(4);
    match ty {
        ParamType::Float { default, min, max } => {
            let frac = c.below(1001) as f64 / 1000.0;
            let v = if bad {
                *c.pick(&[
                    min - 1.0,
                    max + 1.0,
                    f64::NAN,
                    f64::INFINITY,
                    f64::NEG_INFINITY,
                ])
            } else {
                *c.pick(&[*default, *min, *max, min + (max - min) * frac])
            };
            format!("{v:?}")
        }
        ParamType::Int { default, min, max } => {
            let span = u64::try_from(max.saturating_sub(*min))
                .unwrap_or(0)
                .min(1 << 20);
            let inside = min.saturating_add(i64::try_from(c.below(span as usize + 1)).unwrap_or(0));
            let v = if bad {
                *c.pick(&[min.saturating_sub(1), max.saturating_add(1)])
            } else {
                *c.pick(&[*default, *min, *max, inside])
            };
            v.to_string()
        }
        ParamType::Bool { .. } if bad => "1".into(),
        ParamType::Bool { .. } => c.word(&["true", "false"]).into(),
        ParamType::Enum { .. } if bad => "\"bogus\"".into(),
        ParamType::Enum { options, .. } => format!("{:?}", c.pick(options).0),
        // A layer, view or channel name: the default (empty) but now and then one the
        // file or the image has not.
        ParamType::Text { .. } if bad => "\"no such\"".into(),
        ParamType::Text { .. } => "\"\"".into(),
        _ => {
            let paths = match kind {
                "Output" if bad || c.rarely(12) => ESCAPING_PATHS,
                "Output" => OUT_PATHS,
                "LUT" if bad => &["missing.cube", "in.exr"],
                "LUT" => &["look.cube"],
                _ if bad => &["missing.exr", "look.cube"],
                _ => &["in.exr", "in.png"],
            };
            format!("{:?}", c.pick(paths))
        }
    }
}

/// Statements for a declared kind's `node` function, over `acc` (a `vec4f`), its input
/// `color` and its params `n` (int) and `f` (float); `{a}` and `{b}` are replaced by odd
/// offsets. The last ones do not compile.
const SNIPPETS: &[&str] = &[
    "acc += load_color(vec2i(pixel) + vec2i({a}, {b}));",
    "acc += textureLoad(color, vec2i({a}, {b}), 0);",
    "{ var t = array<f32, 4>(1.0, 2.0, 3.0, 4.0); acc.x += t[pixel.x * 1000u + u32(params.n)]; }",
    "{ var t = array<vec4f, 2>(acc, acc); acc = t[i32(pixel.y) - {b}]; }",
    "acc = acc / vec4f(f32(params.n) - 2.0);",
    "acc.y += f32(i32(pixel.x) / (i32(pixel.y) - 1) % (params.n - 1));",
    "for (var i = 0; i < params.n * 100; i++) { acc.z += 0.001 * params.f; }",
    "loop { if acc.w > 1e30 || acc.w != acc.w { break; } acc.w = abs(acc.w) * 2.0 + 1.0; }",
    "acc = vec4f(params.f) * acc + vec4f(f32(size.x), f32(size.y), 0.0, 1.0);",
    "textureStore(out_color, vec2i({a}, {b}), acc);",
    "acc = vec4f(sqrt(-1.0 + acc.x), log(acc.y - 1.0), exp(acc.z * 1e6), acc.w);",
    "acc += ;",
    "let = 3;",
    "acc += undefined_function(1.0);",
    "return 1.0;",
    "}",
];
const OFFSETS: &[&str] = &["0", "-1", "1", "7", "1000000", "-1000000", "-2147483647"];

fn snippet_code(c: &mut Choices<'_>) -> String {
    let mut code = String::new();
    if c.rarely(15) {
        code += c.word(&[
            "#import \"common/color.wgsl\"\n",
            "#import \"common/color.wgsl\"\n",
            "#import \"../Cargo.toml\"\n",
            "#import \"no/such.wgsl\"\n",
        ]);
    }
    code +=
        "fn node(pixel: vec2u, size: vec2u) -> vec4f {\n    var acc = load_color(vec2i(pixel));\n";
    for _ in 0..1 + c.below(4) {
        // Broken snippets (the last five) one time in six.
        let n = if c.rarely(17) {
            SNIPPETS.len()
        } else {
            SNIPPETS.len() - 5
        };
        let s = SNIPPETS[c.below(n)]
            .replace("{a}", c.word(OFFSETS))
            .replace("{b}", c.word(OFFSETS));
        code += &format!("    {s}\n");
    }
    code + "    return acc;\n}\n"
}

/// Kinds a generated graph may use: the built-in ones that render no scene.
fn pool(scene: bool) -> Vec<&'static Arc<NodeKind>> {
    LIBRARY
        .registry()
        .kinds()
        .iter()
        .filter(|k| scene || !k.renders_scene)
        .collect()
}

/// A node to write: id, kind, inputs (name, accepted types, optional), outputs (name,
/// type), params as RON.
struct NodeSpec {
    id: String,
    kind: String,
    inputs: Vec<(String, Vec<PortType>, bool)>,
    outputs: Vec<(String, PortType)>,
    params: Vec<(String, String)>,
}

impl NodeSpec {
    /// A node of `kind`: each param set half the time, the path of a node that reads a
    /// file always.
    fn of(c: &mut Choices<'_>, id: String, kind: &NodeKind) -> Self {
        let mut params = Vec::new();
        for def in &kind.params {
            if c.rarely(50) || matches!(def.ty, ParamType::Path { .. }) {
                params.push((def.name.to_owned(), value(c, kind.name, &def.ty)));
            }
        }
        if c.rarely(1) {
            params.push(("bogus".into(), "1".into()));
        }
        Self {
            id,
            kind: kind.name.to_owned(),
            inputs: kind
                .inputs
                .iter()
                .map(|i| (i.name.to_owned(), i.accepts.to_vec(), i.optional))
                .collect(),
            // The input files are colour: ImageInput's `scalar` and `vector` ports are
            // refused with them (a case now and then checks that).
            outputs: kind
                .outputs
                .iter()
                .filter(|o| kind.name != "ImageInput" || o.name == "color" || c.rarely(20))
                .map(|o| (o.name.to_owned(), o.ty))
                .collect(),
            params,
        }
    }

    /// A node of a declared kind or a group: one `color` input and output.
    fn color(id: String, kind: &str, params: Vec<(String, String)>) -> Self {
        Self {
            id,
            kind: kind.to_owned(),
            inputs: vec![("color".into(), vec![PortType::HdrColor], false)],
            outputs: vec![("color".into(), PortType::HdrColor)],
            params,
        }
    }

    fn ron(&self) -> String {
        let params: Vec<String> = self
            .params
            .iter()
            .map(|(k, v)| format!("{k:?}: {v}"))
            .collect();
        format!(
            "        (id: {:?}, kind: {:?}, params: {{{}}}),\n",
            self.id,
            self.kind,
            params.join(", ")
        )
    }
}

/// The ports of `nodes` that produce a type `accepts` takes.
fn sources<'a>(nodes: &'a [NodeSpec], accepts: &[PortType]) -> Vec<(&'a str, &'a str)> {
    nodes
        .iter()
        .flat_map(|n| n.outputs.iter().map(move |(p, ty)| (n, p, ty)))
        .filter(|(_, _, ty)| accepts.contains(ty))
        .map(|(n, p, _)| (n.id.as_str(), p.as_str()))
        .collect()
}

/// Edges into every input of `nodes[1..]`: mostly from an earlier node's port of a type it
/// takes (an optional input is left out now and then), rarely from a port of another type,
/// from a later node (cycles) or from a port that does not exist.
fn edges(c: &mut Choices<'_>, nodes: &[NodeSpec]) -> String {
    let mut out = String::new();
    for j in 1..nodes.len() {
        for (input, accepts, optional) in &nodes[j].inputs {
            let to = format!("{}.{input}", nodes[j].id);
            let fitting = sources(&nodes[..j], accepts);
            let (from, port) = if c.rarely(3) {
                let n = &nodes[c.below(nodes.len())];
                (
                    n.id.as_str(),
                    n.outputs.first().map_or("color", |(p, _)| p.as_str()),
                )
            } else if c.rarely(2) {
                (nodes[0].id.as_str(), "nope")
            } else if (*optional && c.rarely(30)) || fitting.is_empty() {
                continue;
            } else {
                *c.pick(&fitting)
            };
            out += &format!("        (from: \"{from}.{port}\", to: \"{to}\"),\n");
        }
    }
    out
}

/// Group files `g{depth}.ron`…: each a chain of two nodes (a filter, then a filter or the
/// next group), sometimes with an Output inside, sometimes using itself.
fn groups(c: &mut Choices<'_>, depth: usize, files: &mut Vec<(String, String)>) {
    let filters: Vec<_> = pool(false)
        .into_iter()
        .filter(|k| {
            k.input("color").is_some() && k.output("color").is_some() && k.inputs.len() == 1
        })
        .collect();
    for d in 0..depth {
        let own = d + 1 < depth || c.rarely(10);
        let inner = if d + 1 < depth { d + 1 } else { d };
        let kind = *c.pick(&filters);
        let a = NodeSpec::of(c, "a".into(), kind);
        let b = if own {
            NodeSpec::color("b".into(), "H", Vec::new())
        } else {
            let kind = *c.pick(&filters);
            NodeSpec::of(c, "b".into(), kind)
        };
        let mut nodes = a.ron() + &b.ron();
        let mut edges = String::from("        (from: \"a.color\", to: \"b.color\"),\n");
        if c.rarely(30) {
            let path = value(
                c,
                "Output",
                &ParamType::Path {
                    default: "",
                    extensions: &[],
                },
            );
            nodes +=
                &format!("        (id: \"o\", kind: \"Output\", params: {{\"path\": {path}}}),\n");
            edges += "        (from: \"b.color\", to: \"o.color\"),\n";
        }
        let uses = if own {
            format!("    groups: [(name: \"H\", file: \"g{inner}.ron\")],\n")
        } else {
            String::new()
        };
        files.push((
            format!("g{d}.ron"),
            format!(
                "(\n    version: 3,\n{uses}    interface: (\n        inputs: [(name: \"color\", to: [\"a.color\"])],\n        outputs: [(name: \"color\", from: \"b.color\")],\n    ),\n    nodes: [\n{nodes}    ],\n    edges: [\n{edges}    ],\n)\n"
            ),
        ));
    }
}

/// The case the choices `values` make.
pub fn build(values: &[u32]) -> Case {
    let mut c = Choices { values, at: 0 };
    let mut files = Vec::new();
    let scene = c.rarely(SCENE_PERCENT);
    let pool = pool(scene);
    let mut kinds = String::new();
    let declared = if c.rarely(40) { 1 + c.below(2) } else { 0 };
    for k in 0..declared {
        let code = snippet_code(&mut c);
        kinds += &format!(
            "        (name: \"K{k}\", inputs: [(name: \"color\")], outputs: [(name: \"color\")], params: [(name: \"n\", type: Int(default: 2, min: 0, max: 64)), (name: \"f\", type: Float(default: 0.5, min: -1.0, max: 1.0))], code: {code:?}),\n"
        );
    }
    let depth = if c.rarely(25) { 1 + c.below(3) } else { 0 };
    groups(&mut c, depth, &mut files);
    let input = LIBRARY.registry().get("ImageInput").expect("ImageInput");
    let mut nodes = vec![NodeSpec::of(&mut c, "n0".into(), input)];
    for i in 1..=c.below(8) {
        let id = format!("n{i}");
        let r = c.below(100);
        nodes.push(if r >= 88 && declared > 0 {
            let params = vec![(
                "n".to_owned(),
                value(
                    &mut c,
                    "",
                    &ParamType::Int {
                        default: 0,
                        min: 0,
                        max: 64,
                    },
                ),
            )];
            NodeSpec::color(id, &format!("K{}", c.below(declared)), params)
        } else if r >= 80 && depth > 0 {
            NodeSpec::color(id, "G", Vec::new())
        } else if r == 79 {
            NodeSpec::color(id, "Nope", Vec::new())
        } else {
            // A kind whose required inputs the nodes so far can feed, if one of three
            // picks is (kinds reading G-buffer images need a scene, which these graphs
            // have not).
            let mut kind = *c.pick(&pool);
            for _ in 0..2 {
                let fed = kind
                    .inputs
                    .iter()
                    .all(|i| i.optional || !sources(&nodes, i.accepts).is_empty());
                if fed {
                    break;
                }
                kind = *c.pick(&pool);
            }
            NodeSpec::of(&mut c, id, kind)
        });
    }
    let output = LIBRARY.registry().get("Output").expect("Output");
    let first_output = nodes.len();
    for i in 0..c.below(3) + usize::from(!c.rarely(5)) {
        let mut o = NodeSpec::of(&mut c, format!("out{i}"), output);
        if !o.params.iter().any(|(k, _)| k == "path") {
            o.params
                .push(("path".into(), value(&mut c, "Output", &output.params[0].ty)));
        }
        nodes.push(o);
    }
    let mut edges = edges(&mut c, &nodes[..first_output]);
    // Outputs read a random port of the nodes before them, most often the last node's.
    for o in &nodes[first_output..] {
        let ports = sources(&nodes[..first_output], &o.inputs[0].1);
        let last = ports
            .iter()
            .rposition(|(n, _)| *n == nodes[first_output - 1].id);
        let (from, port) = match last {
            Some(i) if !c.rarely(40) => ports[i],
            _ if ports.is_empty() => ("n0", "color"),
            _ => *c.pick(&ports),
        };
        edges += &format!(
            "        (from: \"{from}.{port}\", to: \"{}.color\"),\n",
            o.id
        );
    }
    let groups_line = if depth > 0 {
        "    groups: [(name: \"G\", file: \"g0.ron\")],\n"
    } else {
        ""
    };
    let kinds_line = if kinds.is_empty() {
        String::new()
    } else {
        format!("    kinds: [\n{kinds}    ],\n")
    };
    let nodes: String = nodes.iter().map(NodeSpec::ron).collect();
    files.insert(
        0,
        (
            "graph.ron".into(),
            format!("(\n    version: 3,\n{kinds_line}{groups_line}    nodes: [\n{nodes}    ],\n    edges: [\n{edges}    ],\n)\n"),
        ),
    );
    Case { files, scene }
}
