//! Scene errors: each names the file, the line and column when known, and the shape or
//! material it concerns.

pub use lumagraph_files::Pos;

/// What went wrong.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ErrorKind {
    /// A file could not be read.
    #[error("cannot read {what}: {source}")]
    Io {
        /// What was being read ("scene file", "OBJ file").
        what: &'static str,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
    /// The file is not valid RON for a scene.
    #[error("syntax error: {0}")]
    Syntax(String),
    /// The file's version is not one this build reads.
    #[error("unsupported scene version {found} (this build reads versions 1 to {supported})")]
    Version {
        /// Version in the file.
        found: u32,
        /// Version this build reads.
        supported: u32,
    },
    /// A shape names a material that is not defined.
    #[error("unknown material \"{material}\" (defined materials: {known})")]
    UnknownMaterial {
        /// The name used.
        material: String,
        /// The names defined, comma-separated.
        known: String,
    },
    /// A value is out of its range or not finite.
    #[error("{field}: {message}")]
    BadValue {
        /// The field (`radius`, `fov_y`).
        field: &'static str,
        /// What is wrong.
        message: String,
    },
    /// The camera asks for a glTF camera that cannot be found.
    #[error("{0}")]
    Camera(String),
    /// A glTF file could not be loaded.
    #[error("glTF: {0}")]
    Gltf(#[source] Box<gltf::Error>),
    /// A glTF file that parses but whose parts do not fit together: a buffer view or
    /// accessor past the end of its data, an attribute of the wrong type, a node hierarchy
    /// that is not a tree.
    #[error("glTF: {0}")]
    GltfData(String),
    /// An OBJ or MTL file could not be loaded.
    #[error("OBJ: {0}")]
    Obj(#[from] tobj::LoadError),
    /// An OBJ face refers to an element the file does not have: the line and what.
    #[error("OBJ: {0}")]
    ObjData(String),
    /// A PLY file could not be read, or refers to what it does not have: what, and where
    /// (the element, the face).
    #[error("PLY: {0}")]
    PlyData(String),
    /// A texture's image could not be read or decoded: the texture
    /// (`texture 0 (image 1, "wood.png")`) and what went wrong.
    #[error("{0}")]
    Texture(String),
    /// A mesh file has an extension this build does not import.
    #[error("unsupported mesh file type \"{0}\" (use .gltf, .glb, .obj or .ply)")]
    MeshType(String),
    /// The BVH is deeper than the flattening accepts.
    #[error("BVH depth {depth} exceeds the most accepted, {max}")]
    BvhTooDeep {
        /// Depth of the built tree.
        depth: usize,
        /// The most accepted ([`crate::bvh::BVH_MAX_DEPTH`]).
        max: usize,
    },
    /// More primitives than the GPU layout can index.
    #[error("too many primitives ({0}); the GPU layout indexes at most 2^28")]
    TooManyPrimitives(usize),
    /// Copies of instanced meshes over [`crate::scene::MAX_INSTANCED_TRIANGLES`].
    #[error(
        "copying instanced meshes would store {} triangles, over lumagraph's {} (the largest: \
         \"{}\", {} instances of {} triangles); keep them instances (`instancing: On` in the \
         scene file, or `Auto`) or place fewer",
        .0.total, .0.max, .0.mesh, .0.instances, .0.triangles
    )]
    TooManyInstancedTriangles(Box<InstancedCopies>),
    /// A scene file could not be written.
    #[error("cannot write scene file: {source}")]
    Write {
        /// The cause.
        #[source]
        source: std::io::Error,
    },
    /// An edit changes a part of a scene file that the editor does not write: `"version"`,
    /// `"shapes"` or `"lights"`.
    #[error("the editor cannot change the {0} of a scene file")]
    NotEditable(&'static str),
    /// An edited scene could not be written over the text it was read from.
    #[error("cannot write the edited scene: {0}")]
    Unwritable(String),
    /// An edit by path ([`crate::edit`]) names nothing editable, or its value does not fit:
    /// the path edited (`camera.fov_y`), then what is wrong.
    #[error("scene edit {0}")]
    Edit(String),
}

impl From<gltf::Error> for ErrorKind {
    fn from(e: gltf::Error) -> Self {
        Self::Gltf(Box::new(e))
    }
}

/// One scene error with its location: the file (the scene file, or the mesh file it
/// references), the line and column, and the shape or material concerned (e.g.
/// `shape "floor"`, `material "white"`).
pub type SceneError = lumagraph_files::Located<ErrorKind>;

/// What [`ErrorKind::TooManyInstancedTriangles`] names.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct InstancedCopies {
    /// The mesh with the most copied triangles.
    pub mesh: String,
    /// Its instances.
    pub instances: usize,
    /// Its triangles.
    pub triangles: usize,
    /// Triangles all copies would store.
    pub total: u64,
    /// The limit.
    pub max: u64,
}

impl From<ErrorKind> for SceneError {
    fn from(kind: ErrorKind) -> Self {
        Self::new(kind)
    }
}
