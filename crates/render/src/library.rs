//! The node kinds a program knows and how each one runs: a [`NodeLibrary`] holds a
//! [`Registry`] (ports, params, docs) and one [`NodeImpl`] per kind that has GPU code of
//! its own. This crate's built-in kinds are [`NodeLibrary::frame_graph`]'s; the path
//! tracer's crate adds the kinds that render the scene (`lumagraph_pathtrace::library`,
//! the library programs start from), and a program built on lumagraph adds its own kinds with [`NodeLibrary::with_kind`] and hands the library to
//! the compiler, the [`Executor`](crate::Executor), the CLI and the editor.
//!
//! Kinds that name a shader ([`NodeKind::shader`]: the built-in generic post filters and
//! the kinds declared in graph files, [`crate::custom`]) run on the generic post filter and
//! need no entry of their own.

use std::path::Path;

use lumagraph_graph::{
    CompileOptions, Extent, Graph, GraphErrors, NodeKind, Params, Pass, Plan, Registry,
};
use lumagraph_scene::GpuScene;

use crate::context::GpuContext;
use crate::error::{RenderError, Result};
use crate::nodes::{IMPLEMENTATIONS, NodeExec, NodeImpl, Resources, post_filter};

/// Node kinds with their GPU implementations: what a program can compile and run.
///
/// ```no_run
/// # fn kind() -> lumagraph_graph::NodeKind { unimplemented!() }
/// # const IMPL: lumagraph_render::nodes::NodeImpl =
/// #     lumagraph_render::nodes::NodeImpl::new("Mine", |_, _, _| unimplemented!());
/// use lumagraph_render::NodeLibrary;
///
/// let library = NodeLibrary::frame_graph().with_kind(kind(), IMPL)?;
/// # Ok::<(), lumagraph_render::RenderError>(())
/// ```
#[derive(Clone, Debug)]
pub struct NodeLibrary {
    registry: Registry,
    implementations: Vec<NodeImpl>,
}

impl NodeLibrary {
    /// Every built-in kind, with this crate's implementations: the post-processing, image
    /// file and colour nodes. The kinds that render the scene (`PathTrace`, `GBuffer`) are
    /// in the registry but run only once their crate adds them
    /// ([`NodeLibrary::with_implementations`]; `lumagraph_pathtrace::library` does);
    /// until then a graph using one is refused when its node is created, naming the kind.
    pub fn frame_graph() -> Self {
        Self {
            registry: Registry::with_builtins(),
            implementations: IMPLEMENTATIONS.to_vec(),
        }
    }

    /// The library with implementations of built-in kinds it has none of (the kinds that
    /// render the scene, from the crate that defines them).
    ///
    /// # Errors
    /// [`RenderError::Library`], naming the kind, when the registry has no such kind, it
    /// already has an implementation, or the kind names a shader or does not fit.
    pub fn with_implementations(mut self, implementations: &[NodeImpl]) -> Result<Self> {
        for implementation in implementations {
            let err = |m: &str| {
                RenderError::Library(format!("node kind \"{}\": {m}", implementation.kind))
            };
            let kind = self
                .registry
                .get(implementation.kind)
                .ok_or_else(|| err("the registry has no kind of that name"))?;
            if kind.shader.is_some() || self.implementation(kind).is_some() {
                return Err(err("it already has an implementation"));
            }
            check(kind, implementation).map_err(|m| err(&m))?;
            self.implementations.push(*implementation);
        }
        Ok(self)
    }

    /// The library with `kind` added, run by `implementation` (see [`NodeLibrary::add`]).
    ///
    /// # Errors
    /// As [`NodeLibrary::add`].
    pub fn with_kind(mut self, kind: NodeKind, implementation: NodeImpl) -> Result<Self> {
        self.add(kind, implementation)?;
        Ok(self)
    }

    /// Adds `kind`, run by `implementation`.
    ///
    /// # Errors
    /// [`RenderError::Library`], naming the kind, when the library already has a kind of
    /// that name, the implementation is for another kind, the kind names a shader (the
    /// generic post filter runs those), the kind repeats a port or param name, or a source
    /// that does not render the scene gives no way to tell its size (a kind that is not a
    /// source must give none).
    pub fn add(&mut self, kind: NodeKind, implementation: NodeImpl) -> Result<()> {
        let err = |m: String| RenderError::Library(format!("node kind \"{}\": {m}", kind.name));
        if self.registry.get(kind.name).is_some() {
            return Err(err("the library already has a kind of that name".into()));
        }
        if implementation.kind != kind.name {
            return Err(err(format!(
                "its implementation is for \"{}\"",
                implementation.kind
            )));
        }
        if let Some(shader) = &kind.shader {
            return Err(err(format!(
                "it names the shader {shader}, so the generic post filter runs it; \
                 give it no shader to run it with its own implementation"
            )));
        }
        check(&kind, &implementation).map_err(err)?;
        self.registry.add(kind).map_err(RenderError::Library)?;
        self.implementations.push(implementation);
        Ok(())
    }

    /// The node kinds: their ports, params and docs.
    pub fn registry(&self) -> &Registry {
        &self.registry
    }

    /// The implementations of the kinds that have their own, in the order they were added.
    pub fn implementations(&self) -> &[NodeImpl] {
        &self.implementations
    }

    /// How `kind` runs: the generic post filter for a kind that names a shader (built in
    /// or declared in a graph file), else the kind's own implementation.
    pub fn implementation(&self, kind: &NodeKind) -> Option<&NodeImpl> {
        if kind.shader.is_some() {
            return Some(&post_filter::IMPL);
        }
        self.implementations.iter().find(|i| i.kind == kind.name)
    }

    /// Memory a pass's node allocates for itself (see [`NodeImpl::owned_memory`]).
    pub fn owned_memory(&self, pass: &Pass) -> Option<(u64, String)> {
        self.implementation(&pass.kind)
            .and_then(|i| (i.owned_memory)(pass))
    }

    /// Creates the GPU side of the node a pass runs.
    ///
    /// # Errors
    /// When the kind has no implementation here or its setup fails; the error names the
    /// node.
    pub fn create(
        &self,
        ctx: &GpuContext,
        pass: &Pass,
        resources: &Resources,
    ) -> Result<Box<dyn NodeExec>> {
        let node = match self.implementation(&pass.kind) {
            Some(i) => (i.create)(ctx, pass, resources),
            None => Err(RenderError::Unimplemented(pass.kind.name.to_owned())),
        };
        node.map_err(|e| e.in_node(&pass.node))
    }

    /// The image size a source of `kind` produces: the scene's for a kind that renders it,
    /// else what its implementation tells from the params (paths relative to `base_dir`).
    ///
    /// # Errors
    /// A message naming the file when a source cannot tell its size.
    pub fn source_extent(
        &self,
        base_dir: &Path,
        scene: Option<&GpuScene>,
        kind: &NodeKind,
        params: &Params,
    ) -> std::result::Result<Extent, String> {
        if kind.renders_scene {
            return scene
                .map(|s| Extent::new(s.settings.width, s.settings.height))
                .ok_or_else(|| {
                    "renders a scene, but none was given (lumagraph render --scene FILE)".to_owned()
                });
        }
        match self.implementation(kind).and_then(|i| i.source_extent) {
            Some(extent) => extent(base_dir, params),
            None => Err(format!("{} is not a source", kind.name)),
        }
    }

    /// The library's kinds and those `graph` declares ([`crate::custom::registry_for`]).
    ///
    /// # Errors
    /// As [`crate::custom::registry_for`]: every declaration that fails, and a declared
    /// kind whose name the library already has.
    pub fn registry_for(&self, graph: &Graph) -> std::result::Result<Registry, GraphErrors> {
        crate::custom::registry_for(graph, &self.registry)
    }

    /// Compiles `graph` with the library's kinds and those the graph file declares, sizing
    /// sources from their params and files (relative to the graph's folder) and from the
    /// scene.
    ///
    /// # Errors
    /// Every problem found in the graph (first in its declared kinds).
    pub fn compile(
        &self,
        graph: &Graph,
        keep: &[String],
        scene: Option<&GpuScene>,
    ) -> std::result::Result<Plan, GraphErrors> {
        self.compile_with(
            graph,
            &self.registry_for(graph)?,
            &graph.base_dir(),
            keep,
            scene,
        )
    }

    /// Compiles `graph` against `registry` (the library's, or one made from it by
    /// [`NodeLibrary::registry_for`]), sizing sources with the library's implementations
    /// (paths relative to `base_dir`) and from the scene.
    ///
    /// # Errors
    /// Every problem found in the graph.
    pub fn compile_with(
        &self,
        graph: &Graph,
        registry: &Registry,
        base_dir: &Path,
        keep: &[String],
        scene: Option<&GpuScene>,
    ) -> std::result::Result<Plan, GraphErrors> {
        self.compile_sized(graph, registry, base_dir, keep, scene, None)
    }

    /// Compiles `graph` as [`NodeLibrary::compile`] does, with the nodes that render the
    /// scene making `window`-sized images (one tile's window of a tiled render).
    ///
    /// # Errors
    /// Every problem found in the graph (first in its declared kinds).
    pub fn compile_window(
        &self,
        graph: &Graph,
        keep: &[String],
        scene: Option<&GpuScene>,
        window: Extent,
    ) -> std::result::Result<Plan, GraphErrors> {
        self.compile_sized(
            graph,
            &self.registry_for(graph)?,
            &graph.base_dir(),
            keep,
            scene,
            Some(window),
        )
    }

    fn compile_sized(
        &self,
        graph: &Graph,
        registry: &Registry,
        base_dir: &Path,
        keep: &[String],
        scene: Option<&GpuScene>,
        window: Option<Extent>,
    ) -> std::result::Result<Plan, GraphErrors> {
        let extent = |kind: &NodeKind, params: &Params| match window {
            Some(w) if kind.renders_scene => Ok(w),
            _ => self.source_extent(base_dir, scene, kind, params),
        };
        lumagraph_graph::compile(
            graph,
            registry,
            &CompileOptions {
                source_extent: &extent,
                keep,
            },
        )
    }
}

/// Whether `implementation` fits `kind`: a source that does not render the scene tells its
/// size, no other kind does.
fn check(kind: &NodeKind, implementation: &NodeImpl) -> std::result::Result<(), String> {
    let sized_source = kind.is_source() && !kind.renders_scene;
    match (sized_source, implementation.source_extent.is_some()) {
        (true, false) => Err(
            "a source that does not render the scene must tell its image \
             size from its params (NodeImpl::sized_by)"
                .to_owned(),
        ),
        (false, true) => Err(
            "only a source that does not render the scene tells its image \
             size (NodeImpl::sized_by)"
                .to_owned(),
        ),
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The registry's kinds that do not render the scene are the implementation table's
    /// and the generic post filters, each once, and each implementation fits its kind (the
    /// path tracer's crate checks the whole library).
    #[test]
    fn every_builtin_kind_has_one_implementation() {
        let library = NodeLibrary::frame_graph();
        let mut kinds: Vec<&str> = library
            .registry()
            .kinds()
            .iter()
            .filter(|k| k.shader.is_none() && !k.renders_scene)
            .map(|k| k.name)
            .collect();
        let mut implemented: Vec<&str> = library.implementations().iter().map(|i| i.kind).collect();
        kinds.sort_unstable();
        implemented.sort_unstable();
        assert_eq!(kinds, implemented);
        for k in library.registry().kinds() {
            assert!(
                !(k.shader.is_some() && library.implementations().iter().any(|i| i.kind == k.name)),
                "{}: a post filter with an implementation of its own",
                k.name
            );
            let Some(i) = library.implementation(k) else {
                assert!(k.renders_scene, "{}", k.name);
                continue;
            };
            if k.shader.is_none() {
                check(k, i).unwrap_or_else(|e| panic!("{}: {e}", k.name));
            }
        }
    }

    fn source(name: &'static str) -> NodeKind {
        let mut kind = NodeKind::clone(
            NodeLibrary::frame_graph()
                .registry()
                .get("ImageInput")
                .unwrap(),
        );
        kind.name = name;
        kind
    }

    fn sized(name: &'static str) -> NodeImpl {
        NodeImpl::new(name, |_, _, _| Err(RenderError::Gpu("unused".into())))
            .sized_by(|_, _| Ok(Extent::new(1, 1)))
    }

    #[test]
    fn a_kind_is_added_and_found() {
        let library = NodeLibrary::frame_graph()
            .with_kind(source("Mine"), sized("Mine"))
            .unwrap();
        let kind = library.registry().get("Mine").unwrap();
        assert_eq!(library.implementation(kind).unwrap().kind, "Mine");
        assert!(NodeLibrary::frame_graph().implementation(kind).is_none());
    }

    #[test]
    fn a_bad_kind_is_refused_with_its_name() {
        let cases = [
            (source("ImageInput"), sized("ImageInput"), "already has"),
            (source("Mine"), sized("Other"), "is for \"Other\""),
            (
                source("Mine"),
                NodeImpl::new("Mine", |_, _, _| Err(RenderError::Gpu("unused".into()))),
                "must tell its image size",
            ),
        ];
        for (kind, implementation, expected) in cases {
            let e = NodeLibrary::frame_graph()
                .with_kind(kind, implementation)
                .unwrap_err()
                .to_string();
            assert!(e.contains(expected) && e.contains("node kind \""), "{e}");
        }
        let mut exposure = NodeKind::clone(
            NodeLibrary::frame_graph()
                .registry()
                .get("Exposure")
                .unwrap(),
        );
        exposure.name = "MyExposure";
        let e = NodeLibrary::frame_graph()
            .with_kind(
                exposure,
                NodeImpl::new("MyExposure", |_, _, _| {
                    Err(RenderError::Gpu("unused".into()))
                }),
            )
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("MyExposure") && e.contains("generic post filter"),
            "{e}"
        );
    }
}
