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
use numpy::{IntoPyArray as _, PyArray3, PyReadonlyArray3, PyUntypedArrayMethods as _};
use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyList, PyTuple};

use lumagraph::render::cpu::Image;
use lumagraph::scene::edit::{self, SceneText};
use lumagraph::session::{SceneChange, SessionOptions};

create_exception!(
    lumagraph,
    LumagraphError,
    PyException,
    "An error of lumagraph's: the message names the file, line, node or limit, as the command line's does."
);

fn error(e: &anyhow::Error) -> PyErr {
    LumagraphError::new_err(format!("{e:#}"))
}

fn scene_error(e: &lumagraph::scene::SceneError) -> PyErr {
    LumagraphError::new_err(e.to_string())
}

/// An `(h, w, 4)` or `(h, w, 3)` float array as an image (alpha 1 where there is none).
fn image_of(a: &Bound<'_, PyAny>) -> PyResult<Image> {
    let a: PyReadonlyArray3<'_, f32> =
        a.call_method1("astype", ("float32",))?
            .extract()
            .map_err(|_| {
                LumagraphError::new_err("an image is an array of shape (height, width, 3 or 4)")
            })?;
    let shape = a.shape();
    let (h, w, c) = (shape[0], shape[1], shape[2]);
    if !(c == 3 || c == 4) || h == 0 || w == 0 {
        return Err(LumagraphError::new_err(format!(
            "an image is an array of shape (height, width, 3 or 4), not {shape:?}"
        )));
    }
    let view = a.as_array();
    let pixels = (0..h)
        .flat_map(|y| (0..w).map(move |x| (y, x)))
        .map(|(y, x)| {
            [
                view[[y, x, 0]],
                view[[y, x, 1]],
                view[[y, x, 2]],
                if c == 4 { view[[y, x, 3]] } else { 1.0 },
            ]
        })
        .collect();
    let size = |n: usize| u32::try_from(n).map_err(|_| LumagraphError::new_err("image too large"));
    Ok(Image {
        width: size(w)?,
        height: size(h)?,
        pixels,
    })
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

    /// The colour space of its colour images: `"Linear Rec.709"` (the default) or
    /// `"ACEScg"`.
    #[getter]
    fn working_space(&self) -> &'static str {
        self.inner.working_space.name()
    }

    #[setter]
    fn set_working_space(&mut self, name: &str) -> PyResult<()> {
        self.inner.working_space = lumagraph::graph::WorkingSpace::parse(name)
            .map_err(pyo3::exceptions::PyValueError::new_err)?;
        Ok(())
    }
}

/// A Python value as RON text: `None`, a bool, an int, a float, a tuple or list of them
/// (a vector), or a str as written (RON text such as `Constant((1, 1, 1))`).
fn ron_text(v: &Bound<'_, PyAny>, quote_str: bool) -> PyResult<String> {
    if v.is_none() {
        return Ok("None".to_owned());
    }
    if let Ok(b) = v.extract::<bool>() {
        return Ok(b.to_string());
    }
    if let Ok(i) = v.extract::<i64>() {
        return Ok(i.to_string());
    }
    if let Ok(f) = v.extract::<f64>() {
        return Ok(format!("{f:?}"));
    }
    if let Ok(text) = v.extract::<String>() {
        return Ok(if quote_str {
            ron::to_string(&text).unwrap_or(text)
        } else {
            text
        });
    }
    if v.is_instance_of::<PyTuple>() || v.is_instance_of::<PyList>() || v.hasattr("tolist")? {
        let items: Vec<Bound<'_, PyAny>> = if v.hasattr("tolist")? {
            v.call_method0("tolist")?.extract()?
        } else {
            v.extract()?
        };
        let parts = items
            .iter()
            .map(|i| ron_text(i, true))
            .collect::<PyResult<Vec<_>>>()?;
        return Ok(format!("({})", parts.join(", ")));
    }
    Err(LumagraphError::new_err(format!(
        "a scene value is None, a bool, a number, a str or a tuple of them, not {}",
        v.get_type().name()?
    )))
}

/// RON text as a Python value: numbers, bools, strings, `None` and vectors (tuples) as
/// themselves; a struct or a variant (a camera, an environment) as its RON text.
fn py_value<'py>(py: Python<'py>, text: &str) -> PyResult<Bound<'py, PyAny>> {
    fn convert<'py>(py: Python<'py>, v: &ron::Value) -> Option<PyResult<Bound<'py, PyAny>>> {
        use pyo3::types::{PyBool, PyFloat, PyInt, PyString};
        use ron::Value;
        let value = match v {
            Value::Bool(b) => PyBool::new(py, *b).to_owned().into_any(),
            Value::Number(n) => {
                let f = n.into_f64();
                let whole = !matches!(n, ron::Number::F32(_) | ron::Number::F64(_));
                if whole && f.fract() == 0.0 && f.abs() < 9.0e15 {
                    #[expect(clippy::cast_possible_truncation, reason = "checked whole")]
                    PyInt::new(py, f as i64).into_any()
                } else {
                    PyFloat::new(py, f).into_any()
                }
            }
            Value::String(s) => PyString::new(py, s).into_any(),
            Value::Option(None) => py.None().into_bound(py),
            Value::Option(Some(inner)) => return convert(py, inner),
            Value::Seq(items) => {
                let items: Option<PyResult<Vec<_>>> =
                    items.iter().map(|i| convert(py, i)).collect();
                return Some(items?.and_then(|items| PyTuple::new(py, items).map(Bound::into_any)));
            }
            _ => return None,
        };
        Some(Ok(value))
    }
    let parsed: Option<ron::Value> = ron::from_str(text).ok();
    match parsed.as_ref().and_then(|v| convert(py, v)) {
        Some(v) => v,
        None => Ok(text.into_pyobject(py)?.into_any()),
    }
}

/// A scene file, loaded to be edited: its camera, materials, environment and render
/// settings, by path (`"camera.fov_y"`, `"materials.red.base_color"`, `"render.width"`).
#[pyclass(module = "lumagraph")]
#[derive(Clone)]
struct Scene {
    inner: SceneText,
}

#[pymethods]
impl Scene {
    /// Loads a scene file.
    #[staticmethod]
    #[expect(
        clippy::needless_pass_by_value,
        reason = "Python arguments arrive by value"
    )]
    fn load(path: PathBuf) -> PyResult<Self> {
        let inner = SceneText::load(&path).map_err(|e| scene_error(&e))?;
        Ok(Self { inner })
    }

    /// The value at `path`: a number, bool, str, `None` or tuple; a camera or an
    /// environment as its RON text.
    fn get<'py>(&self, py: Python<'py>, path: &str) -> PyResult<Bound<'py, PyAny>> {
        let text = edit::get(&self.inner.file, path).map_err(|e| scene_error(&e))?;
        py_value(py, &text)
    }

    /// Sets the value at `path`: a number, bool, `None`, a tuple (a vector or colour), or a
    /// str (RON text such as `"Constant((1, 1, 1))"`, else a string value).
    fn set(&mut self, path: &str, value: &Bound<'_, PyAny>) -> PyResult<()> {
        let text = ron_text(value, false)?;
        let first = edit::set(&mut self.inner.file, path, &text);
        match first {
            Ok(()) => Ok(()),
            Err(e) if value.extract::<String>().is_ok() => {
                // A plain string value (`"Au"`): quoted.
                edit::set(&mut self.inner.file, path, &ron_text(value, true)?)
                    .map_err(|_| scene_error(&e))
            }
            Err(e) => Err(scene_error(&e)),
        }
    }

    /// The names under `path`: the parts for `""`, the materials for `"materials"`, a
    /// camera's or a material's fields.
    #[pyo3(signature = (path=""))]
    fn fields(&self, path: &str) -> PyResult<Vec<String>> {
        edit::fields(&self.inner.file, path).map_err(|e| scene_error(&e))
    }

    /// The names of the scene file's materials.
    #[getter]
    fn materials(&self) -> Vec<String> {
        self.inner.file.materials.keys().cloned().collect()
    }

    /// The file it was loaded from.
    #[getter]
    fn path(&self) -> PathBuf {
        self.inner.path.clone()
    }

    /// The file's text with the edited values written in; comments and layout kept.
    fn to_ron(&self) -> PyResult<String> {
        self.inner.to_ron().map_err(|e| scene_error(&e))
    }

    /// Writes [`to_ron`] (atomically) over the file it was loaded from, or to `path`.
    #[pyo3(signature = (path=None))]
    #[expect(
        clippy::needless_pass_by_value,
        reason = "Python arguments arrive by value"
    )]
    fn save(&mut self, path: Option<PathBuf>) -> PyResult<()> {
        self.inner
            .save(path.as_deref())
            .map_err(|e| scene_error(&e))
    }

    fn __repr__(&self) -> String {
        format!("Scene.load({:?})", self.inner.path.display().to_string())
    }
}

/// A scene given as a path or a `Scene`.
fn scene_arg(scene: Option<&Bound<'_, PyAny>>) -> PyResult<Option<SceneText>> {
    let Some(scene) = scene.filter(|s| !s.is_none()) else {
        return Ok(None);
    };
    if let Ok(s) = scene.cast::<Scene>() {
        return Ok(Some(s.borrow().inner.clone()));
    }
    let path: PathBuf = scene.extract()?;
    SceneText::load(&path)
        .map(Some)
        .map_err(|e| scene_error(&e))
}

/// A graph given as a path or a `Graph`.
fn graph_arg(graph: &Bound<'_, PyAny>) -> PyResult<lumagraph::graph::Graph> {
    if let Ok(g) = graph.cast::<Graph>() {
        return Ok(g.borrow().inner.clone());
    }
    let path: PathBuf = graph.extract()?;
    lumagraph::graph::Graph::load(&path).map_err(|e| LumagraphError::new_err(e.to_string()))
}

/// An image shown in Jupyter: `lg.Image(array)` of a linear `(h, w, 3 or 4)` array, or a
/// session's output (`Session.image()`). Shown sRGB-encoded and clipped to [0, 1] (a
/// tone-mapped output as it is); `array` is the data, unchanged.
#[pyclass(name = "Image", module = "lumagraph")]
struct PyImage {
    png: Vec<u8>,
    image: Image,
}

#[pymethods]
impl PyImage {
    #[new]
    fn new(array: &Bound<'_, PyAny>) -> PyResult<Self> {
        use lumagraph::render::image_io::{encode_png, to_rgba8};
        let image = image_of(array)?;
        let png = encode_png(image.width, image.height, &to_rgba8(&image, true))
            .map_err(|e| LumagraphError::new_err(e.to_string()))?;
        Ok(Self { png, image })
    }

    /// The pixels: float32, `(height, width, 4)`.
    #[getter]
    fn array<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray3<f32>>> {
        array(py, &self.image)
    }

    /// The PNG Jupyter shows.
    fn _repr_png_<'py>(&self, py: Python<'py>) -> Bound<'py, PyBytes> {
        PyBytes::new(py, &self.png)
    }

    /// Writes the PNG shown to `path`.
    #[expect(
        clippy::needless_pass_by_value,
        reason = "Python arguments arrive by value"
    )]
    fn save_png(&self, path: PathBuf) -> PyResult<()> {
        lumagraph::graph::write_atomic(&path, &self.png)
            .map_err(|e| LumagraphError::new_err(format!("{}: {e}", path.display())))
    }

    fn __repr__(&self) -> String {
        format!(
            "<lumagraph.Image {}x{}>",
            self.image.width, self.image.height
        )
    }
}

/// A graph and its scene on a device, rendered progressively.
#[pyclass(unsendable, module = "lumagraph")]
struct Session {
    inner: lumagraph::session::Session,
}

impl Session {
    /// Each `Output` node's image (what its input port holds), by the node's id.
    fn output_images<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let out = PyDict::new(py);
        for (node, port) in self.inner.outputs() {
            let img = self.inner.read(&port).map_err(|e| error(&e))?;
            out.set_item(node, array(py, &img)?)?;
        }
        Ok(out)
    }
}

/// The iterator `Session.render_frames` gives: `(frame, images)` a frame.
#[pyclass(unsendable, module = "lumagraph")]
struct FrameIter {
    session: Py<Session>,
    frames: Vec<i64>,
    next: usize,
}

#[pymethods]
impl FrameIter {
    fn __iter__(slf: PyRef<'_, Self>) -> PyRef<'_, Self> {
        slf
    }

    fn __next__<'py>(&mut self, py: Python<'py>) -> PyResult<Option<(i64, Bound<'py, PyDict>)>> {
        let Some(&frame) = self.frames.get(self.next) else {
            return Ok(None);
        };
        self.next += 1;
        let mut session = self.session.borrow_mut(py);
        let images = session.set_frame(py, frame)?;
        Ok(Some((frame, images)))
    }

    fn __len__(&self) -> usize {
        self.frames.len() - self.next
    }
}

#[pymethods]
impl Session {
    /// `Session(graph, scene=None, out="out", write_outputs=False, keep=[], frame=None)`
    ///
    /// Loads the graph (a file, or a `Graph`) and the scene (a file, or a `Scene`) and
    /// sets them up on the default adapter.
    /// `Output` nodes write their files under `out` only with `write_outputs`; `keep` names
    /// more ports ("node.port") to read back with `read`. A graph whose params hold a
    /// frame pattern (`####`, `%04d`, `$F4`) opens at `frame` (see `render_frames`).
    /// `intersector` (`"auto"`, `"inline"`, `"host"`, `"binary"`, `"wide"`, `"rays"`) and
    /// `schedule` (`"auto"`, `"megakernel"`, `"wavefront"`) ask the path tracer for one, as
    /// `lumagraph render --intersector` and `--schedule` do.
    #[new]
    #[pyo3(signature = (graph, scene=None, out="out", write_outputs=false, keep=Vec::new(), frame=None, intersector="auto", schedule="auto"))]
    #[expect(clippy::too_many_arguments, reason = "Python keyword arguments")]
    fn new(
        graph: &Bound<'_, PyAny>,
        scene: Option<&Bound<'_, PyAny>>,
        out: &str,
        write_outputs: bool,
        keep: Vec<String>,
        frame: Option<i64>,
        intersector: &str,
        schedule: &str,
    ) -> PyResult<Self> {
        use lumagraph::pathtrace::specialize::{Intersector, Schedule};
        let options = SessionOptions {
            out: PathBuf::from(out),
            write_outputs,
            keep,
            frame,
            intersector: Intersector::from_name(intersector)
                .map_err(pyo3::exceptions::PyValueError::new_err)?,
            schedule: Schedule::from_name(schedule)
                .map_err(pyo3::exceptions::PyValueError::new_err)?,
            ..SessionOptions::default()
        };
        let graph = graph_arg(graph)?;
        let scene = scene_arg(scene)?;
        let inner = lumagraph::session::Session::open_scene(graph, scene, options)
            .map_err(|e| error(&e))?;
        Ok(Self { inner })
    }

    /// A copy of the scene as the session renders it (`None` without one); edit it and
    /// give it to `set_scene`.
    #[getter]
    fn scene(&self) -> Option<Scene> {
        self.inner.scene().map(|s| Scene { inner: s.clone() })
    }

    /// Renders `scene` (edited) from now on; the accumulation restarts. Returns what
    /// changed: `"camera"` (only the camera moved: nothing rebuilt), `"scene"` (built
    /// again), or `None` (nothing).
    fn set_scene(&mut self, scene: &Scene) -> PyResult<Option<&'static str>> {
        let change = self
            .inner
            .set_scene(scene.inner.file.clone())
            .map_err(|e| error(&e))?;
        Ok(match change {
            SceneChange::Nothing => None,
            SceneChange::Camera => Some("camera"),
            SceneChange::Scene => Some("scene"),
        })
    }

    /// Writes where the render stands to `path` (as `lumagraph render --checkpoint` does).
    #[expect(
        clippy::needless_pass_by_value,
        reason = "Python arguments arrive by value"
    )]
    fn checkpoint(&mut self, path: PathBuf) -> PyResult<()> {
        self.inner.checkpoint(&path).map_err(|e| error(&e))
    }

    /// Goes on from the checkpoint at `path` (of the same graph and scene): the next
    /// `render` renders on from its samples.
    #[expect(
        clippy::needless_pass_by_value,
        reason = "Python arguments arrive by value"
    )]
    fn resume(&mut self, path: PathBuf) -> PyResult<()> {
        self.inner.resume(&path).map_err(|e| error(&e))
    }

    /// An output's image for display (the first `Output` node's unless `output` names
    /// one, or a port "node.port"), as the last render left it.
    #[pyo3(signature = (output=None))]
    fn image(&mut self, output: Option<&str>) -> PyResult<PyImage> {
        let outputs = self.inner.outputs();
        let port = match output {
            None => outputs
                .first()
                .map(|(_, port)| port.clone())
                .ok_or_else(|| LumagraphError::new_err("the graph has no Output node"))?,
            Some(name) => outputs
                .iter()
                .find(|(node, _)| node == name)
                .map_or_else(|| name.to_owned(), |(_, port)| port.clone()),
        };
        let png = self.inner.png(&port).map_err(|e| error(&e))?;
        let image = self.inner.read(&port).map_err(|e| error(&e))?;
        Ok(PyImage { png, image })
    }

    /// The first output's image, shown by Jupyter when a session is a cell's value.
    fn _repr_png_<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyBytes>> {
        Ok(PyBytes::new(py, &self.image(None)?.png))
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
            .render_with(spp, |_, done, all| {
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
        self.output_images(py)
    }

    /// The frame a graph with frame patterns is at (`None` for other graphs).
    #[getter]
    fn frame(&self) -> Option<i64> {
        self.inner.frame()
    }

    /// Moves a graph with frame patterns to `frame` and runs it: each param with a
    /// pattern takes the frame's number, only what changed reloads, nodes with history see
    /// the frame before. Returns each `Output` node's image, by the node's id.
    fn set_frame<'py>(&mut self, py: Python<'py>, frame: i64) -> PyResult<Bound<'py, PyDict>> {
        self.inner.set_frame(frame).map_err(|e| error(&e))?;
        self.output_images(py)
    }

    /// `render_frames(frames)`: an iterator over `(frame, images)` for each frame of
    /// `frames` (`"1-100x2"` as `lumagraph render --frames` takes it, or a list of
    /// numbers), `images` each `Output` node's image by the node's id, as `set_frame`
    /// gives them. A missing input frame raises `LumagraphError` naming it.
    fn render_frames(slf: Py<Self>, frames: &Bound<'_, PyAny>) -> PyResult<FrameIter> {
        let frames: Vec<i64> = match frames.extract::<String>() {
            Ok(spec) => lumagraph::footage::sequence::parse_frames(&spec)
                .map_err(LumagraphError::new_err)?,
            Err(_) => frames.extract().map_err(|_| {
                LumagraphError::new_err(
                    "frames: a range such as \"1-100x2\", or a list of frame numbers",
                )
            })?,
        };
        Ok(FrameIter {
            session: slf,
            frames,
            next: 0,
        })
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

/// Error against time, as `lumagraph converge` measures it: the graph (a file or a
/// `Graph`, its `Output` nodes dropped) on the scene (a file or a `Scene`) at 1, 2, 4… spp
/// until `seconds`, each `Accumulate` and `Denoise` output scored against `reference` (an
/// EXR file or a linear array) or a render of `reference_spp` samples with another seed.
/// Returns the rows of `converge.csv`, as dicts (output, spp, seconds, rmse, relmse,
/// ssim, `gpu_ms`); with `out`, writes `converge.csv` and `converge.png` there.
#[pyfunction]
#[pyo3(signature = (graph, scene, reference=None, reference_spp=None, seconds=10.0, variants=Vec::new(), out=None))]
#[expect(clippy::too_many_arguments, reason = "the command line's options")]
#[expect(
    clippy::needless_pass_by_value,
    reason = "Python arguments arrive by value"
)]
fn converge<'py>(
    py: Python<'py>,
    graph: &Bound<'py, PyAny>,
    scene: &Bound<'py, PyAny>,
    reference: Option<&Bound<'py, PyAny>>,
    reference_spp: Option<u32>,
    seconds: f64,
    variants: Vec<String>,
    out: Option<PathBuf>,
) -> PyResult<Vec<Bound<'py, PyDict>>> {
    use lumagraph::converge::{Options, Reference};
    let graph = graph_arg(graph)?;
    let scene =
        scene_arg(Some(scene))?.ok_or_else(|| LumagraphError::new_err("converge needs a scene"))?;
    let reference = match (reference.filter(|r| !r.is_none()), reference_spp) {
        (Some(r), None) => match r.extract::<PathBuf>() {
            Ok(path) => Reference::File(path),
            Err(_) => Reference::Image(image_of(r)?),
        },
        (None, Some(spp)) => Reference::Spp(spp),
        _ => {
            return Err(LumagraphError::new_err(
                "give reference (an EXR file or an array) or reference_spp, not both",
            ));
        }
    };
    let built = scene.build().map_err(|e| scene_error(&e))?;
    let gpu = std::sync::Arc::new(
        lumagraph::scene::GpuScene::build(&built).map_err(|e| scene_error(&e))?,
    );
    let ctx = lumagraph::render::GpuContext::headless()
        .map_err(|e| LumagraphError::new_err(e.to_string()))?;
    let library = lumagraph::pathtrace::library::with_builtins();
    let measured = lumagraph::converge::measure(
        &ctx,
        graph,
        &gpu,
        &Options {
            reference,
            seconds,
            variants: &variants,
            library: &library,
        },
    )
    .map_err(|e| error(&e))?;
    if let Some(out) = out {
        let (_, no_plot) =
            lumagraph::converge::write(&out, &measured.rows, None).map_err(|e| error(&e))?;
        if let Some(why) = no_plot {
            eprintln!("lumagraph: converge.png not written: {why}");
        }
    }
    measured
        .rows
        .iter()
        .map(|r| {
            let d = PyDict::new(py);
            d.set_item("output", &r.output)?;
            d.set_item("spp", r.spp)?;
            d.set_item("seconds", r.seconds)?;
            d.set_item("rmse", r.rmse)?;
            d.set_item("relmse", r.relmse)?;
            d.set_item("ssim", r.ssim)?;
            d.set_item("gpu_ms", r.gpu_ms)?;
            Ok(d)
        })
        .collect()
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
    lumagraph::overrides::apply();
    // At import, before any session opens a Vulkan instance: no bogus libwayland error
    // where the machine has no XDG_RUNTIME_DIR.
    lumagraph::render::GpuContext::quiet_device_select();
    m.add_class::<Graph>()?;
    m.add_function(wrap_pyfunction!(nodes, m)?)?;
    m.add_class::<Session>()?;
    m.add_class::<FrameIter>()?;
    m.add_class::<Scene>()?;
    m.add_class::<PyImage>()?;
    m.add_function(wrap_pyfunction!(converge, m)?)?;
    m.add("LumagraphError", m.py().get_type::<LumagraphError>())?;
    Ok(())
}
