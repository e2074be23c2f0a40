//! The `lumagraph` Python package: a [`lumagraph::session::Session`] from Python, images
//! as `NumPy` `float32` arrays of shape `(height, width, 4)`.
//!
//! ```python
//! import lumagraph as lg
//! s = lg.Session("graphs/pathtrace.ron", "assets/cornell.ron")
//! images = s.render(64)              # {"png": array, "exr": array}: each output's image
//! s.set_param("exposure.ev", "1.5")  # the passes that ran: exposure, tonemap, png
//! ```
//!
//! Built with maturin (`crates/python/pyproject.toml`); `docs/python.md` says how.

use std::path::PathBuf;

use numpy::ndarray::Array3;
use numpy::{IntoPyArray as _, PyArray3};
use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use lumagraph::render::cpu::Image;
use lumagraph::session::SessionOptions;

create_exception!(
    lumagraph,
    LumagraphError,
    PyException,
    "An error of lumagraph's: the message names the file, line, node or limit, as the command line's does."
);

fn error(e: &anyhow::Error) -> PyErr {
    LumagraphError::new_err(format!("{e:#}"))
}

fn array<'py>(py: Python<'py>, img: &Image) -> PyResult<Bound<'py, PyArray3<f32>>> {
    let data: Vec<f32> = img.pixels.iter().flatten().copied().collect();
    let a = Array3::from_shape_vec((img.height as usize, img.width as usize, 4), data)
        .map_err(|e| LumagraphError::new_err(e.to_string()))?;
    Ok(a.into_pyarray(py))
}

/// A render graph: loaded from a file or built in code.
#[pyclass(module = "lumagraph")]
#[derive(Clone)]
struct Graph {
    inner: lumagraph::graph::Graph,
}

#[pymethods]
impl Graph {
    /// An empty graph.
    #[new]
    fn new() -> Self {
        Self {
            inner: lumagraph::graph::Graph::new(),
        }
    }

    /// Loads a graph file.
    #[staticmethod]
    #[expect(
        clippy::needless_pass_by_value,
        reason = "Python arguments arrive by value"
    )]
    fn load(path: PathBuf) -> PyResult<Self> {
        let inner = lumagraph::graph::Graph::load(&path)
            .map_err(|e| LumagraphError::new_err(e.to_string()))?;
        Ok(Self { inner })
    }

    /// Adds a node of `kind` called `name`, its params as keyword arguments
    /// (`add_node("Tonemap", "tonemap", operator="aces")`); returns the name.
    #[pyo3(signature = (kind, name, **params))]
    fn add_node(
        &mut self,
        kind: &str,
        name: &str,
        params: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<String> {
        use lumagraph::graph::ParamValue;
        if self.inner.node(name).is_some() {
            return Err(LumagraphError::new_err(format!(
                "there is already a node \"{name}\""
            )));
        }
        let mut node = lumagraph::graph::Node::new(name, kind);
        if let Some(params) = params {
            for (k, v) in params.iter() {
                let key: String = k.extract()?;
                // bool before int: a Python bool is an int.
                let value = if let Ok(b) = v.extract::<bool>() {
                    ParamValue::Bool(b)
                } else if let Ok(i) = v.extract::<i64>() {
                    ParamValue::Int(i)
                } else if let Ok(f) = v.extract::<f64>() {
                    ParamValue::Float(f)
                } else if let Ok(s) = v.extract::<String>() {
                    ParamValue::Str(s)
                } else {
                    return Err(LumagraphError::new_err(format!(
                        "{name}.{key}: a param is a bool, an int, a float or a str"
                    )));
                };
                node = node.with(&key, value);
            }
        }
        self.inner.nodes.push(node);
        Ok(name.to_owned())
    }

    /// Connects output port `src` ("node.port") to input port `dst`.
    fn connect(&mut self, src: &str, dst: &str) {
        self.inner.edges.push(lumagraph::graph::Edge::new(src, dst));
    }

    /// Writes the graph file (atomically).
    #[expect(
        clippy::needless_pass_by_value,
        reason = "Python arguments arrive by value"
    )]
    fn save(&self, path: PathBuf) -> PyResult<()> {
        self.inner
            .save(&path)
            .map_err(|e| LumagraphError::new_err(e.to_string()))
    }

    /// The graph file's text.
    fn to_ron(&self) -> String {
        self.inner.to_ron()
    }

    /// The ids of its nodes, in order.
    #[getter]
    fn nodes(&self) -> Vec<String> {
        self.inner.nodes.iter().map(|n| n.id.clone()).collect()
    }
}

/// A graph and its scene on a device, rendered progressively.
#[pyclass(unsendable, module = "lumagraph")]
struct Session {
    inner: lumagraph::session::Session,
}

#[pymethods]
impl Session {
    /// `Session(graph, scene=None, out="out", write_outputs=False, keep=[])`
    ///
    /// Loads the graph (a file, or a `Graph`) and the scene file and sets them up on the
    /// default adapter.
    /// `Output` nodes write their files under `out` only with `write_outputs`; `keep` names
    /// more ports ("node.port") to read back with `read`.
    #[new]
    #[expect(
        clippy::needless_pass_by_value,
        reason = "Python arguments arrive by value"
    )]
    #[pyo3(signature = (graph, scene=None, out="out", write_outputs=false, keep=Vec::new()))]
    fn new(
        graph: &Bound<'_, PyAny>,
        scene: Option<PathBuf>,
        out: &str,
        write_outputs: bool,
        keep: Vec<String>,
    ) -> PyResult<Self> {
        let options = SessionOptions {
            out: PathBuf::from(out),
            write_outputs,
            keep,
            ..SessionOptions::default()
        };
        let opened = if let Ok(g) = graph.cast::<Graph>() {
            lumagraph::session::Session::open_graph(
                g.borrow().inner.clone(),
                scene.as_deref(),
                options,
            )
        } else {
            let path: PathBuf = graph.extract()?;
            lumagraph::session::Session::open(&path, scene.as_deref(), options)
        };
        let inner = opened.map_err(|e| error(&e))?;
        Ok(Self { inner })
    }

    /// Renders on to `spp` samples per pixel in all; returns each `Output` node's image
    /// (what its input port holds), by the node's id. With `progress`, prints the frames
    /// done to standard error as it goes. Ctrl-C stops it between batches of frames
    /// (`KeyboardInterrupt`); a later `render` goes on from the frames done.
    #[pyo3(signature = (spp, progress=false))]
    fn render<'py>(
        &mut self,
        py: Python<'py>,
        spp: u32,
        progress: bool,
    ) -> PyResult<Bound<'py, PyDict>> {
        let mut interrupted = None;
        let done = self
            .inner
            .render_with(spp, |done, all| {
                if progress {
                    eprint!("\rlumagraph: {done}/{all} frames");
                }
                match py.check_signals() {
                    Ok(()) => true,
                    Err(e) => {
                        interrupted = Some(e);
                        false
                    }
                }
            })
            .map_err(|e| error(&e))?;
        if progress {
            eprintln!();
        }
        if let Some(e) = interrupted {
            return Err(e);
        }
        if done.is_none() {
            return Err(LumagraphError::new_err("the render stopped"));
        }
        let out = PyDict::new(py);
        for (node, port) in self.inner.outputs() {
            let img = self.inner.read(&port).map_err(|e| error(&e))?;
            out.set_item(node, array(py, &img)?)?;
        }
        Ok(out)
    }

    /// The image on output port "node.port" as the last frame left it.
    fn read<'py>(&self, py: Python<'py>, port: &str) -> PyResult<Bound<'py, PyArray3<f32>>> {
        let img = self.inner.read(port).map_err(|e| error(&e))?;
        array(py, &img)
    }

    /// Sets "node.param" to `value` (as `--set` takes it) and re-runs what it changes;
    /// returns the ids of the passes that ran.
    fn set_param(&mut self, target: &str, value: &str) -> PyResult<Vec<String>> {
        let report = self.inner.set_param(target, value).map_err(|e| error(&e))?;
        Ok(report.executed)
    }

    /// What loading the scene warned of (also printed to standard error), one line each.
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.inner.warnings().to_vec()
    }

    /// Samples per pixel accumulated so far.
    #[getter]
    fn spp(&self) -> u64 {
        self.inner.spp()
    }

    /// What the nodes measured in the last run, by "node.name" (a `Difference` node's
    /// relMSE, the path tracer's paths and rays, …).
    #[getter]
    fn measurements<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let out = PyDict::new(py);
        for (node, name, value) in self.inner.measurements().map_err(|e| error(&e))? {
            out.set_item(format!("{node}.{name}"), value)?;
        }
        Ok(out)
    }

    /// Milliseconds per pass (by node) in the last run's timed frame, or `None` where the
    /// adapter cannot time passes.
    #[getter]
    fn timings<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        let Some(times) = self.inner.timings() else {
            return Ok(None);
        };
        let out = PyDict::new(py);
        for (node, ms) in times {
            out.set_item(node, ms)?;
        }
        Ok(Some(out))
    }
}

fn param_value<'py>(
    py: Python<'py>,
    v: &lumagraph::graph::ParamValue,
) -> PyResult<Bound<'py, PyAny>> {
    use lumagraph::graph::ParamValue;
    Ok(match v {
        ParamValue::Bool(b) => b.into_pyobject(py)?.to_owned().into_any(),
        ParamValue::Int(i) => i.into_pyobject(py)?.into_any(),
        ParamValue::Float(f) => f.into_pyobject(py)?.into_any(),
        ParamValue::Str(s) => s.into_pyobject(py)?.into_any(),
    })
}

/// Every built-in node kind: its name, category, doc, input and output ports (name, type
/// and doc) and params (name, default and doc).
#[pyfunction]
fn nodes(py: Python<'_>) -> PyResult<Vec<Bound<'_, PyDict>>> {
    let registry = lumagraph::graph::Registry::with_builtins();
    let mut out = Vec::new();
    for k in registry.kinds() {
        let d = PyDict::new(py);
        d.set_item("kind", k.name)?;
        d.set_item("category", k.category.name())?;
        d.set_item("doc", k.doc)?;
        let mut inputs = Vec::new();
        for i in &k.inputs {
            let p = PyDict::new(py);
            p.set_item("name", i.name)?;
            let types: Vec<String> = i.accepts.iter().map(ToString::to_string).collect();
            p.set_item("types", types)?;
            p.set_item("doc", i.doc)?;
            inputs.push(p);
        }
        d.set_item("inputs", inputs)?;
        let mut outputs = Vec::new();
        for o in &k.outputs {
            let p = PyDict::new(py);
            p.set_item("name", o.name)?;
            p.set_item("type", o.ty.to_string())?;
            p.set_item("doc", o.doc)?;
            outputs.push(p);
        }
        d.set_item("outputs", outputs)?;
        let mut params = Vec::new();
        for prm in &k.params {
            let p = PyDict::new(py);
            p.set_item("name", prm.name)?;
            p.set_item("default", param_value(py, &prm.ty.default_value())?)?;
            p.set_item("doc", prm.doc)?;
            params.push(p);
        }
        d.set_item("params", params)?;
        out.push(d);
    }
    Ok(out)
}

/// Render graphs from Python.
#[pymodule(name = "lumagraph")]
fn lumagraph_module(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Graph>()?;
    m.add_function(wrap_pyfunction!(nodes, m)?)?;
    m.add_class::<Session>()?;
    m.add("LumagraphError", m.py().get_type::<LumagraphError>())?;
    Ok(())
}
