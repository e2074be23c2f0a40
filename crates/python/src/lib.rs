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

/// A graph and its scene on a device, rendered progressively.
#[pyclass(unsendable, module = "lumagraph")]
struct Session {
    inner: lumagraph::session::Session,
}

#[pymethods]
impl Session {
    /// `Session(graph, scene=None, out="out", write_outputs=False, keep=[])`
    ///
    /// Loads the graph file and the scene file and sets them up on the default adapter.
    /// `Output` nodes write their files under `out` only with `write_outputs`; `keep` names
    /// more ports ("node.port") to read back with `read`.
    #[new]
    #[expect(
        clippy::needless_pass_by_value,
        reason = "Python arguments arrive by value"
    )]
    #[pyo3(signature = (graph, scene=None, out="out", write_outputs=false, keep=Vec::new()))]
    fn new(
        graph: PathBuf,
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
        let inner = lumagraph::session::Session::open(&graph, scene.as_deref(), options)
            .map_err(|e| error(&e))?;
        Ok(Self { inner })
    }

    /// Renders on to `spp` samples per pixel in all; returns each `Output` node's image
    /// (what its input port holds), by the node's id.
    fn render<'py>(&mut self, py: Python<'py>, spp: u32) -> PyResult<Bound<'py, PyDict>> {
        self.inner.render(spp).map_err(|e| error(&e))?;
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

    /// Samples per pixel rendered so far.
    #[getter]
    fn spp(&self) -> u32 {
        self.inner.spp()
    }
}

/// Render graphs from Python.
#[pymodule(name = "lumagraph")]
fn lumagraph_module(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Session>()?;
    m.add("LumagraphError", m.py().get_type::<LumagraphError>())?;
    Ok(())
}
