//! glTF 2.0 import: every mesh of the default scene through the whole node hierarchy,
//! perspective cameras, metallic-roughness materials with their base color,
//! metallic-roughness, normal and emissive textures, `KHR_materials_emissive_strength`,
//! `KHR_materials_ior`, `KHR_materials_transmission` and `KHR_materials_specular` (factors
//! and textures), `KHR_materials_clearcoat` and `KHR_materials_sheen` (factors and textures,
//! the coat's own normal texture included), `KHR_materials_diffuse_roughness` (its factor),
//! `alphaMode`, `alphaCutoff`
//! and the base colour factor's alpha (with the base colour texture's alpha: masks and
//! blending, [`crate::scene::AlphaMode`]). Textures read `TEXCOORD_0` or `TEXCOORD_1` (their
//! `texCoord`), through their `KHR_texture_transform` (offset, rotation, scale, `texCoord`
//! override); `COLOR_0` multiplies the base colour and the opacity. Tangents are the file's
//! `TANGENT` when present (else generated when the scene is flattened, along the normal
//! texture's own coordinates).
//!
//! `EXT_mesh_gpu_instancing` places a node's mesh at each of its instances (translation,
//! rotation, scale from float accessors). A mesh placed more than once (by instancing, or by
//! several nodes) is returned once, in its own space, with a transform per placement
//! ([`ImportedMesh::instanced`]); the scene's `instancing` decides whether it stays so or is
//! copied.
//!
//! `KHR_lights_punctual` lights become [`PunctualLight`]s, converted as Blender's importer
//! does in its default ("Standard") mode: a point or spot light's intensity in candela
//! (lm/sr) over 683 lm/W is its radiant intensity in W/sr, a directional light's lux over
//! 683 its irradiance in W/m². A spot's outer cone angle is the cutoff and its inner one
//! the beam width, with the falloff linear in angle between them (Mitsuba's; glTF only
//! recommends a curve). `range` is not read (lights are physical: no cut-off distance).
//!
//! Only the textures some material uses are decoded (PNG or JPEG: embedded in a buffer view,
//! a data URI or an external file); a missing or broken image is an error naming the
//! material, the texture and the image.

use std::collections::HashMap;
use std::path::Path;

use glam::{Mat4, Vec2, Vec3, Vec4};

use super::ImportedMesh;
use crate::error::{ErrorKind, SceneError};
use crate::scene::{
    Camera, Material, MaterialTextures, NO_TEXTURE, PunctualLight, Triangle, push_triangle,
    transform_triangle,
};
use crate::texture::{Texture, UvTransform, Wrap};

/// Imports a `.gltf` (with embedded or external buffers) or `.glb` file.
///
/// # Errors
/// When the file or its buffers cannot be read or are not valid glTF.
pub fn import_gltf(path: &Path, transform: Mat4) -> Result<ImportedMesh, SceneError> {
    import_gltf_with(path, transform, false)
}

/// [`import_gltf`], with the materials reduced to [`Material::as_diffuse`] before the
/// images are decoded where `diffuse`, so that only the images they still read are.
///
/// # Errors
/// As [`import_gltf`].
pub fn import_gltf_with(
    path: &Path,
    transform: Mat4,
    diffuse: bool,
) -> Result<ImportedMesh, SceneError> {
    let (file, unread) = open(path)?;
    check_images(&file.document)?;
    check_uris(&file.document, path.parent())?;
    let buffers = ::gltf::import_buffers(&file.document, path.parent(), file.blob.clone())
        .map_err(ErrorKind::from)?;
    let doc = &file.document;
    check_views(doc, &buffers)?;
    check_tree(doc)?;
    let mut out = ImportedMesh::default();
    out.report.warnings.extend(unread);
    let mut decoder = Decoder {
        base: path.parent(),
        file: path
            .file_name()
            .map_or_else(String::new, |f| f.to_string_lossy().into_owned()),
        buffers: &buffers,
        material: String::new(),
        decoded: HashMap::new(),
        used: HashMap::new(),
        textures: Vec::new(),
        users: Vec::new(),
    };
    for m in doc.materials() {
        decoder.material = material_name(&m);
        let mat = material(doc, &m, &mut decoder, &mut out.report.warnings)
            .map_err(|e| e.about(format!("material \"{}\"", material_name(&m))))?;
        out.materials.push(mat);
    }
    if diffuse {
        for m in &mut out.materials {
            *m = m.as_diffuse();
        }
        decoder.keep_only(&mut out.materials);
    }
    let started = std::time::Instant::now();
    let threads = decoder.threads();
    out.textures = decoder.decode_all()?;
    let (images, bytes) = image_stats(&out.textures);
    out.decode = super::DecodeStats {
        time: started.elapsed(),
        images,
        bytes,
        threads,
    };
    let mut default_material = None;
    let mut placed: Vec<(::gltf::Mesh<'_>, Vec<Mat4>)> = Vec::new();

    let Some(scene) = doc.default_scene().or_else(|| doc.scenes().next()) else {
        out.report
            .warnings
            .push("the glTF file has no scene".to_owned());
        return Ok(out);
    };
    let mut stack: Vec<(::gltf::Node<'_>, Mat4)> = scene.nodes().map(|n| (n, transform)).collect();
    stack.reverse();
    while let Some((node, parent)) = stack.pop() {
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        if let Some(camera) = node.camera() {
            if let ::gltf::camera::Projection::Perspective(p) = camera.projection() {
                out.cameras.push(Camera {
                    position: world.transform_point3(Vec3::ZERO),
                    forward: world.transform_vector3(Vec3::NEG_Z).normalize(),
                    up: world.transform_vector3(Vec3::Y),
                    fov_y_deg: p.yfov().to_degrees(),
                    aperture_radius: 0.0,
                    focus_distance: 1.0,
                    autofocus: false,
                });
            } else {
                out.report.warnings.push(format!(
                    "camera {} is orthographic; skipped",
                    camera.index()
                ));
            }
        }
        if let Some(light) = node.light() {
            match punctual_light(&light, &world) {
                Ok(l) => out.lights.push(l),
                Err(why) => out.report.warnings.push(format!(
                    "light {} ({}): {why}; skipped",
                    light.index(),
                    light.name().unwrap_or("unnamed")
                )),
            }
        }
        if let Some(mesh) = node.mesh() {
            let worlds: Vec<Mat4> = match instances(doc, &node, &buffers)? {
                Some(locals) => locals.iter().map(|l| world * *l).collect(),
                None => vec![world],
            };
            placed.push((mesh, worlds));
        }
        let children: Vec<_> = node.children().collect();
        stack.extend(children.into_iter().rev().map(|c| (c, world)));
    }
    place_meshes(placed, &buffers, &mut default_material, &mut out)?;
    Ok(out)
}

/// Reads the meshes the nodes place (each with its placements, in node order): a mesh placed
/// once in world space, in node order; one placed several times (by several nodes, or by
/// instancing) once, in its own space, as an instanced mesh.
fn place_meshes(
    placed: Vec<(::gltf::Mesh<'_>, Vec<Mat4>)>,
    buffers: &[::gltf::buffer::Data],
    default_material: &mut Option<usize>,
    out: &mut ImportedMesh,
) -> Result<(), SceneError> {
    // A mesh placed once is stored in world space, in node order; one placed several times
    // (by several nodes, or by instancing) is stored once, in its own space.
    let mut uses: HashMap<usize, usize> = HashMap::new();
    for (mesh, worlds) in &placed {
        *uses.entry(mesh.index()).or_default() += worlds.len();
    }
    let mut instanced_at: HashMap<usize, usize> = HashMap::new();
    for (mesh, worlds) in placed {
        if uses[&mesh.index()] <= 1 {
            read_mesh(&mesh, buffers, &worlds, default_material, out)?;
            continue;
        }
        if let Some(&k) = instanced_at.get(&mesh.index()) {
            out.instanced[k].transforms.extend(worlds);
            continue;
        }
        let before = out.triangles.len();
        read_mesh(&mesh, buffers, &[Mat4::IDENTITY], default_material, out)?;
        let triangles = out.triangles.split_off(before);
        instanced_at.insert(mesh.index(), out.instanced.len());
        out.instanced.push(crate::scene::InstancedMesh {
            name: format!(
                "mesh {} ({})",
                mesh.index(),
                mesh.name().unwrap_or("unnamed")
            ),
            triangles,
            transforms: worlds,
        });
    }
    Ok(())
}

/// Reads every triangle primitive of `mesh` placed at each of `worlds` into `out`.
fn read_mesh(
    mesh: &::gltf::Mesh<'_>,
    buffers: &[::gltf::buffer::Data],
    worlds: &[Mat4],
    default_material: &mut Option<usize>,
    out: &mut ImportedMesh,
) -> Result<(), SceneError> {
    for prim in mesh.primitives() {
        if prim.mode() != ::gltf::mesh::Mode::Triangles {
            out.report.warnings.push(format!(
                "mesh {} primitive {}: mode {:?} skipped (only triangles)",
                mesh.index(),
                prim.index(),
                prim.mode()
            ));
            continue;
        }
        let material = if let Some(i) = prim.material().index() {
            i
        } else {
            *default_material.get_or_insert_with(|| {
                out.materials.push(Material::named("default"));
                out.materials.len() - 1
            })
        };
        check_attributes(&prim, buffers).map_err(|e| {
            SceneError::new(ErrorKind::GltfData(format!(
                "mesh {} primitive {}: {e}",
                mesh.index(),
                prim.index()
            )))
        })?;
        read_primitive(&prim, buffers, worlds, material as u32, out);
    }
    Ok(())
}

/// Reads and validates a `.gltf` or `.glb` file, as `gltf::Gltf::open` does, checking first
/// what the gltf crate's validation indexes unchecked (each primitive's `POSITION`
/// accessor) and what lumagraph does not read ([`super::gltf_extensions::check`]: an error
/// for a required extension, the warnings returned for the rest).
fn open(path: &Path) -> Result<(::gltf::Gltf, Vec<String>), SceneError> {
    let bytes = std::fs::read(path)
        .map_err(::gltf::Error::Io)
        .map_err(ErrorKind::from)?;
    let file = path
        .file_name()
        .map_or_else(String::new, |f| f.to_string_lossy().into_owned());
    let unread = super::gltf_extensions::check(&bytes, &file)?;
    if bytes.starts_with(b"glTF") {
        // gltf subtracts the header's 12 bytes from this length unchecked.
        let length = bytes
            .get(8..12)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]));
        if length.is_none_or(|n| n < 12) {
            return Err(SceneError::new(ErrorKind::GltfData(format!(
                "the GLB header's length ({}) is less than the header's own 12 bytes",
                length.map_or_else(|| "missing".to_owned(), |n| n.to_string())
            ))));
        }
    }
    let unchecked = ::gltf::Gltf::from_slice_without_validation(&bytes).map_err(ErrorKind::from)?;
    let json = unchecked.document.as_json();
    for (m, mesh) in json.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            let position = ::gltf::json::validation::Checked::Valid(::gltf::Semantic::Positions);
            if let Some(i) = prim.attributes.get(&position)
                && i.value() >= json.accessors.len()
            {
                return Err(SceneError::new(ErrorKind::GltfData(format!(
                    "mesh {m} primitive {p}: POSITION is accessor {}, but the file has {} accessors",
                    i.value(),
                    json.accessors.len()
                ))));
            }
        }
    }
    let mut root = unchecked.document.into_json();
    // Every extension the file requires is one lumagraph reads (checked above), some of
    // them from the raw JSON where the gltf crate does not know them: its validation would
    // refuse those.
    root.extensions_required.clear();
    let document = ::gltf::Document::from_json(root).map_err(ErrorKind::from)?;
    Ok((
        ::gltf::Gltf {
            document,
            blob: unchecked.blob,
        },
        unread,
    ))
}

/// Every buffer view within its buffer's data (the gltf crate slices them unchecked, for
/// images in buffer views, and adds their offsets and lengths unchecked).
fn check_views(doc: &::gltf::Document, buffers: &[::gltf::buffer::Data]) -> Result<(), SceneError> {
    for view in doc.views() {
        let buffer = view.buffer().index();
        let len = buffers.get(buffer).map_or(0, |d| d.len());
        if view
            .offset()
            .checked_add(view.length())
            .is_none_or(|end| end > len)
        {
            return Err(SceneError::new(ErrorKind::GltfData(format!(
                "buffer view {}: bytes {} to {} + {} are past the end of buffer {buffer} ({len} bytes)",
                view.index(),
                view.offset(),
                view.offset(),
                view.length()
            ))));
        }
    }
    Ok(())
}

/// Every image has a source the gltf crate can give without panicking: a URI, or a buffer
/// view with its MIME type.
fn check_images(doc: &::gltf::Document) -> Result<(), SceneError> {
    for (i, image) in doc.as_json().images.iter().enumerate() {
        let ok = match image.buffer_view {
            Some(_) => image.mime_type.is_some(),
            None => image.uri.is_some(),
        };
        if !ok {
            return Err(SceneError::new(ErrorKind::GltfData(format!(
                "image {i} has neither a \"uri\" nor a \"bufferView\" with a \"mimeType\""
            ))));
        }
    }
    Ok(())
}

/// Every buffer and image URI that names a file names a regular one in UTF-8: gltf unwraps
/// the decoding of `%` escapes, and would read a device such as `/dev/zero` until memory
/// runs out, or wait on a pipe. Run after [`check_images`] (`Image::source` unwraps).
fn check_uris(doc: &::gltf::Document, base: Option<&Path>) -> Result<(), SceneError> {
    let buffers = doc.buffers().filter_map(|b| match b.source() {
        ::gltf::buffer::Source::Uri(uri) => Some((format!("buffer {}", b.index()), uri)),
        ::gltf::buffer::Source::Bin => None,
    });
    let images = doc.images().filter_map(|i| match i.source() {
        ::gltf::image::Source::Uri { uri, .. } => Some((format!("image {}", i.index()), uri)),
        ::gltf::image::Source::View { .. } => None,
    });
    for (what, uri) in buffers.chain(images) {
        let fail = |why: &str| {
            Err(SceneError::new(ErrorKind::GltfData(format!(
                "{what}: URI \"{}\" {why}",
                uri.chars().take(80).collect::<String>()
            ))))
        };
        let path = if uri.contains(':') {
            match uri
                .strip_prefix("file://")
                .or_else(|| uri.strip_prefix("file:"))
            {
                Some(rest) => std::path::PathBuf::from(rest),
                None => continue,
            }
        } else {
            match String::from_utf8(percent_decode(uri)) {
                Ok(decoded) => base.unwrap_or(Path::new("")).join(decoded),
                Err(_) => return fail("is not UTF-8 once its % escapes are decoded"),
            }
        };
        if std::fs::metadata(&path).is_ok_and(|m| !m.is_file()) {
            return fail(&format!("names {}, which is not a file", path.display()));
        }
    }
    Ok(())
}

/// `%XX` escapes decoded (others kept as written), as gltf decodes relative URIs.
fn percent_decode(uri: &str) -> Vec<u8> {
    let bytes = uri.as_bytes();
    let hex = |b: u8| char::from(b).to_digit(16);
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%'
            && let (Some(h), Some(l)) = (
                bytes.get(i + 1).copied().and_then(hex),
                bytes.get(i + 2).copied().and_then(hex),
            )
        {
            out.push((h * 16 + l) as u8);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    out
}

/// The node hierarchy is a forest, as glTF requires: no node has two parents and no node
/// is its own ancestor (which would make the walk through it endless).
fn check_tree(doc: &::gltf::Document) -> Result<(), SceneError> {
    let count = doc.nodes().len();
    let mut parent = vec![None; count];
    for node in doc.nodes() {
        for child in node.children() {
            if let Some(p) = parent[child.index()].replace(node.index()) {
                return Err(SceneError::new(ErrorKind::GltfData(format!(
                    "node {} is a child of both node {p} and node {} (nodes form trees)",
                    child.index(),
                    node.index()
                ))));
            }
        }
    }
    for start in 0..count {
        let mut at = start;
        for _ in 0..count {
            match parent[at] {
                Some(p) if p == start => {
                    return Err(SceneError::new(ErrorKind::GltfData(format!(
                        "node {start} is its own ancestor (nodes form trees)"
                    ))));
                }
                Some(p) => at = p,
                None => break,
            }
        }
    }
    Ok(())
}

/// The accessors the importer reads (positions, normals, tangents, `TEXCOORD_0`,
/// indices) are of the types glTF allows for them and lie within their buffer views: the
/// gltf crate's reader asserts the first and computes the second unchecked.
fn check_attributes(
    prim: &::gltf::Primitive<'_>,
    buffers: &[::gltf::buffer::Data],
) -> Result<(), String> {
    use ::gltf::Semantic;
    use ::gltf::accessor::{DataType, Dimensions};
    for (semantic, accessor) in prim.attributes() {
        let (types, dims): (&[DataType], _) = match semantic {
            Semantic::Positions | Semantic::Normals => (&[DataType::F32], Dimensions::Vec3),
            Semantic::Tangents => (&[DataType::F32], Dimensions::Vec4),
            Semantic::TexCoords(0) => (
                &[DataType::F32, DataType::U8, DataType::U16],
                Dimensions::Vec2,
            ),
            _ => continue,
        };
        check_accessor(&accessor, buffers, types, dims)
            .map_err(|e| format!("{semantic:?} (accessor {}): {e}", accessor.index()))?;
    }
    if let Some(accessor) = prim.indices() {
        let types = [DataType::U8, DataType::U16, DataType::U32];
        check_accessor(&accessor, buffers, &types, Dimensions::Scalar)
            .map_err(|e| format!("indices (accessor {}): {e}", accessor.index()))?;
    }
    Ok(())
}

fn check_accessor(
    accessor: &::gltf::Accessor<'_>,
    buffers: &[::gltf::buffer::Data],
    types: &[::gltf::accessor::DataType],
    dims: ::gltf::accessor::Dimensions,
) -> Result<(), String> {
    if !types.contains(&accessor.data_type()) || accessor.dimensions() != dims {
        return Err(format!(
            "{:?} of {:?}, where glTF allows {dims:?} of {types:?}",
            accessor.dimensions(),
            accessor.data_type()
        ));
    }
    let size = accessor.size();
    if let Some(view) = accessor.view() {
        check_range(&view, buffers, accessor.offset(), accessor.count(), size)?;
    }
    if let Some(sparse) = accessor.sparse() {
        let indices = sparse.indices();
        let values = sparse.values();
        check_range(
            &indices.view(),
            buffers,
            indices.offset(),
            sparse.count(),
            indices.index_type().size(),
        )
        .map_err(|e| format!("sparse indices: {e}"))?;
        check_range(
            &values.view(),
            buffers,
            values.offset(),
            sparse.count(),
            size,
        )
        .map_err(|e| format!("sparse values: {e}"))?;
    }
    Ok(())
}

/// `count` elements of `size` bytes from `offset` in `view`, within the view and with a
/// stride no smaller than an element.
fn check_range(
    view: &::gltf::buffer::View<'_>,
    buffers: &[::gltf::buffer::Data],
    offset: usize,
    count: usize,
    size: usize,
) -> Result<(), String> {
    if count == 0 {
        return Err("count is 0".to_owned());
    }
    let stride = view.stride().unwrap_or(size);
    if stride < size {
        return Err(format!(
            "buffer view {} has a byte stride of {stride}, less than an element's {size} bytes",
            view.index()
        ));
    }
    let len = buffers.get(view.buffer().index()).map_or(0, |d| d.len());
    let end = stride
        .checked_mul(count - 1)
        .and_then(|n| n.checked_add(size))
        .and_then(|n| n.checked_add(offset));
    let view_fits = view
        .offset()
        .checked_add(view.length())
        .is_some_and(|e| e <= len);
    if !view_fits || end.is_none_or(|e| e > view.length()) {
        return Err(format!(
            "{count} elements of {size} bytes from byte {offset} do not fit in buffer view {} ({} bytes)",
            view.index(),
            view.length()
        ));
    }
    Ok(())
}

static DECODE_THREADS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);

/// How many threads decode a glTF file's images from now on (0: the machine's, at most 16),
/// as the application asks (the command line, the editor and the Python module do for
/// `LUMAGRAPH_DECODE_THREADS=N`: `lumagraph::overrides`).
pub fn set_decode_threads(n: usize) {
    DECODE_THREADS.store(n, std::sync::atomic::Ordering::Relaxed);
}

/// Luminous efficacy of 555 nm light, lm/W: photometric glTF units to radiometric ones.
pub const LUMENS_PER_WATT: f32 = 683.0;

/// A `KHR_lights_punctual` light placed by its node's world matrix (it shines along the
/// node's −z).
fn punctual_light(
    light: &::gltf::khr_lights_punctual::Light<'_>,
    world: &Mat4,
) -> Result<PunctualLight, String> {
    use ::gltf::khr_lights_punctual::Kind;
    let power = Vec3::from(light.color()) * (light.intensity() / LUMENS_PER_WATT);
    if !power.is_finite() || power.min_element() < 0.0 {
        return Err(format!("color × intensity {power} is not finite and >= 0"));
    }
    let position = world.transform_point3(Vec3::ZERO);
    let axis = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
    if !position.is_finite() || axis == Vec3::ZERO {
        return Err("its node's transform is singular".to_owned());
    }
    Ok(match light.kind() {
        Kind::Point => crate::lights::point(position, power),
        Kind::Directional => crate::lights::directional(axis, power),
        Kind::Spot {
            inner_cone_angle,
            outer_cone_angle,
        } => {
            let cutoff = outer_cone_angle.clamp(1e-4, std::f32::consts::FRAC_PI_2);
            let beam = inner_cone_angle.clamp(0.0, cutoff);
            crate::lights::spot(position, axis, power, cutoff, beam)
        }
    })
}

/// The instance transforms of a node with `EXT_mesh_gpu_instancing` (relative to the
/// node): translation, rotation (a unit quaternion) and scale per instance, from float
/// accessors; `None` without the extension.
///
/// # Errors
/// [`ErrorKind::GltfData`] naming the node, where an accessor is missing, not of floats, or
/// of another count than the others.
fn instances(
    doc: &::gltf::Document,
    node: &::gltf::Node<'_>,
    buffers: &[::gltf::buffer::Data],
) -> Result<Option<Vec<Mat4>>, SceneError> {
    use ::gltf::accessor::{DataType, Dimensions};
    let Some(ext) = node.extension_value("EXT_mesh_gpu_instancing") else {
        return Ok(None);
    };
    let fail = |why: String| {
        SceneError::new(ErrorKind::GltfData(format!(
            "node {} ({}): EXT_mesh_gpu_instancing: {why}",
            node.index(),
            node.name().unwrap_or("unnamed")
        )))
    };
    let data = |b: ::gltf::Buffer<'_>| buffers.get(b.index()).map(|d| &d.0[..]);
    // The values of attribute `name` (`dims` floats each), or `None` where it is absent.
    let read = |name: &str, dims: Dimensions| -> Result<Option<Vec<Vec4>>, SceneError> {
        let Some(i) = ext.pointer(&format!("/attributes/{name}")) else {
            return Ok(None);
        };
        let a = i
            .as_u64()
            .and_then(|i| doc.accessors().nth(usize::try_from(i).ok()?))
            .ok_or_else(|| fail(format!("{name} names no accessor ({i})")))?;
        if a.data_type() != DataType::F32 || a.dimensions() != dims {
            return Err(fail(format!(
                "{name} is {:?} of {:?}; lumagraph reads {dims:?} of floats",
                a.dimensions(),
                a.data_type()
            )));
        }
        let values: Option<Vec<Vec4>> = match dims {
            Dimensions::Vec4 => ::gltf::accessor::Iter::<[f32; 4]>::new(a, data)
                .map(|it| it.map(Vec4::from).collect()),
            _ => ::gltf::accessor::Iter::<[f32; 3]>::new(a, data)
                .map(|it| it.map(|v| Vec3::from(v).extend(0.0)).collect()),
        };
        values
            .ok_or_else(|| fail(format!("{name}: its buffer data cannot be read")))
            .map(Some)
    };
    let translation = read("TRANSLATION", Dimensions::Vec3)?;
    let rotation = read("ROTATION", Dimensions::Vec4)?;
    let scale = read("SCALE", Dimensions::Vec3)?;
    let counts: Vec<usize> = [&translation, &rotation, &scale]
        .iter()
        .filter_map(|v| v.as_ref().map(Vec::len))
        .collect();
    let n = counts.first().copied().unwrap_or(0);
    if counts.iter().any(|&c| c != n) {
        return Err(fail(format!(
            "its attributes have different counts {counts:?}"
        )));
    }
    Ok(Some(
        (0..n)
            .map(|k| {
                let t = translation.as_ref().map_or(Vec3::ZERO, |v| v[k].truncate());
                let r = rotation.as_ref().map_or(glam::Quat::IDENTITY, |v| {
                    glam::Quat::from_vec4(v[k]).normalize()
                });
                let s = scale.as_ref().map_or(Vec3::ONE, |v| v[k].truncate());
                Mat4::from_scale_rotation_translation(s, r, t)
            })
            .collect(),
    ))
}

fn read_primitive(
    prim: &::gltf::Primitive<'_>,
    buffers: &[::gltf::buffer::Data],
    worlds: &[Mat4],
    material: u32,
    out: &mut ImportedMesh,
) {
    let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
    let Some(positions) = reader.read_positions() else {
        out.report
            .warnings
            .push(format!("primitive {} has no positions", prim.index()));
        return;
    };
    let positions: Vec<Vec3> = positions.map(Vec3::from).collect();
    let normals: Option<Vec<Vec3>> = reader
        .read_normals()
        .map(|n| n.map(Vec3::from).collect())
        .filter(|n: &Vec<Vec3>| n.len() == positions.len());
    let uv_set = |set: u32| -> Option<Vec<Vec2>> {
        reader
            .read_tex_coords(set)
            .map(|t| t.into_f32().map(Vec2::from).collect())
            .filter(|t: &Vec<Vec2>| t.len() == positions.len())
    };
    let (uvs, uvs1) = (uv_set(0), uv_set(1));
    // Vertex colours as texels are stored: RGB sRGB-encoded, alpha linear, 8 bits each.
    let colors: Option<Vec<[u8; 4]>> = reader
        .read_colors(0)
        .map(|c| {
            c.into_rgba_f32()
                .map(|[r, g, b, a]| {
                    let byte = |x: f32| (x.clamp(0.0, 1.0) * 255.0).round() as u8;
                    let e = crate::texture::srgb_encode;
                    [byte(e(r)), byte(e(g)), byte(e(b)), byte(a)]
                })
                .collect()
        })
        .filter(|c: &Vec<[u8; 4]>| c.len() == positions.len());
    // Tangents only mean something with the normals they were made for.
    let tangents: Option<Vec<Vec4>> = reader
        .read_tangents()
        .map(|t| t.map(Vec4::from).collect())
        .filter(|t: &Vec<Vec4>| t.len() == positions.len() && normals.is_some());
    let indices: Vec<u32> = match reader.read_indices() {
        Some(i) => i.into_u32().collect(),
        None => (0..positions.len() as u32).collect(),
    };
    let mut bad_indices = 0usize;
    for t in indices.chunks_exact(3) {
        let idx = [t[0] as usize, t[1] as usize, t[2] as usize];
        if idx.iter().any(|&i| i >= positions.len()) {
            bad_indices += 1;
            continue;
        }
        let tri = Triangle {
            positions: idx.map(|i| positions[i]),
            normals: normals.as_ref().map(|n| idx.map(|i| n[i])),
            uvs: uvs.as_ref().map(|t| idx.map(|i| t[i])),
            uvs1: uvs1.as_ref().map(|t| idx.map(|i| t[i])),
            colors: colors.as_ref().map(|c| idx.map(|i| c[i])),
            tangents: tangents.as_ref().map(|t| {
                idx.map(|i| {
                    let w = if t[i].w < 0.0 { -1.0 } else { 1.0 };
                    t[i].truncate().extend(w)
                })
            }),
            material,
        };
        for world in worlds {
            push_triangle(
                &mut out.triangles,
                &mut out.report,
                transform_triangle(world, &tri),
            );
        }
    }
    if bad_indices > 0 {
        out.report.warnings.push(format!(
            "primitive {}: {bad_indices} triangles with out-of-range indices dropped",
            prim.index()
        ));
    }
}

fn material_name(m: &::gltf::Material<'_>) -> String {
    m.name().map_or_else(
        || format!("material{}", m.index().unwrap_or(usize::MAX)),
        str::to_owned,
    )
}

/// Decodes the textures materials use, each image once, after the materials are read
/// and on several threads ([`Decoder::decode_all`]).
struct Decoder<'a> {
    base: Option<&'a Path>,
    /// The glTF file's name, for texture names.
    file: String,
    buffers: &'a [::gltf::buffer::Data],
    /// The material being read, for errors about its textures.
    material: String,
    /// glTF texture index → index in `users` of its image.
    decoded: HashMap<usize, usize>,
    /// (glTF texture, coordinate set, transform's bits) → index in `textures`.
    used: HashMap<(usize, u32, [u32; 6]), u32>,
    /// The textures as materials read them, their images still to decode (empty texels):
    /// with each, the index in `users` of its image.
    textures: Vec<(Texture, usize)>,
    /// Each glTF texture to decode, with the first material using it.
    users: Vec<(::gltf::texture::Texture<'a>, String)>,
}

/// The distinct images of `textures` (textures read through different transforms or sets
/// share one) and their texels' bytes.
fn image_stats(textures: &[Texture]) -> (usize, u64) {
    let mut seen = HashMap::new();
    for t in textures {
        seen.insert(t.texels.as_ptr(), 4 * t.texels.len() as u64);
    }
    (seen.len(), seen.values().sum())
}

/// How a normal texture reads its texture (the gltf crate has no typed transform for it):
/// the coordinate set (`texCoord`, or the transform's override) and the
/// `KHR_texture_transform`, from the extension's JSON.
fn texture_transform(ext: Option<&::gltf::json::Value>, tex_coord: u32) -> (u32, UvTransform) {
    let Some(t) = ext else {
        return (tex_coord, UvTransform::IDENTITY);
    };
    let pair = |key: &str, default: [f32; 2]| {
        t.get(key)
            .and_then(::gltf::json::Value::as_array)
            .and_then(|a| Some([a.first()?.as_f64()? as f32, a.get(1)?.as_f64()? as f32]))
            .unwrap_or(default)
    };
    let rotation = t
        .get("rotation")
        .and_then(::gltf::json::Value::as_f64)
        .unwrap_or(0.0) as f32;
    let set = t
        .get("texCoord")
        .and_then(::gltf::json::Value::as_u64)
        .map_or(tex_coord, |c| u32::try_from(c).unwrap_or(u32::MAX));
    (
        set,
        UvTransform::khr(pair("offset", [0.0; 2]), rotation, pair("scale", [1.0; 2])),
    )
}

/// How a texture info reads its texture: its coordinate set (the transform's override
/// where it has one) and its `KHR_texture_transform`, from the gltf crate's typed view.
fn info_read(i: &::gltf::texture::Info<'_>) -> (u32, UvTransform) {
    i.texture_transform()
        .map_or((i.tex_coord(), UvTransform::IDENTITY), |t| {
            (
                t.tex_coord().unwrap_or_else(|| i.tex_coord()),
                UvTransform::khr(t.offset(), t.rotation(), t.scale()),
            )
        })
}

fn wrap(mode: ::gltf::texture::WrappingMode) -> Wrap {
    match mode {
        ::gltf::texture::WrappingMode::ClampToEdge => Wrap::ClampToEdge,
        ::gltf::texture::WrappingMode::MirroredRepeat => Wrap::MirroredRepeat,
        ::gltf::texture::WrappingMode::Repeat => Wrap::Repeat,
    }
}

/// RGBA8 texels of decoded image data (16-bit channels keep their high byte; float
/// channels are clamped to [0, 1]).
fn rgba8(data: &::gltf::image::Data) -> Option<Vec<[u8; 4]>> {
    use ::gltf::image::Format;
    let p = &data.pixels;
    let f32_at = |i: usize| {
        let v = f32::from_le_bytes([p[i], p[i + 1], p[i + 2], p[i + 3]]);
        (v.clamp(0.0, 1.0) * 255.0).round() as u8
    };
    let (channels, bytes) = match data.format {
        Format::R8 => (1, 1),
        Format::R8G8 => (2, 1),
        Format::R8G8B8 => (3, 1),
        Format::R8G8B8A8 => (4, 1),
        Format::R16 => (1, 2),
        Format::R16G16 => (2, 2),
        Format::R16G16B16 => (3, 2),
        Format::R16G16B16A16 => (4, 2),
        Format::R32G32B32FLOAT => (3, 4),
        Format::R32G32B32A32FLOAT => (4, 4),
    };
    let n = data.width as usize * data.height as usize;
    if p.len() < n * channels * bytes {
        return None;
    }
    // 8-bit channels, the usual case, a pixel at a time (the same texels as below, without
    // the per-channel indexing).
    if bytes == 1 {
        let p = &p[..n * channels];
        return Some(match channels {
            4 => p
                .chunks_exact(4)
                .map(|c| [c[0], c[1], c[2], c[3]])
                .collect(),
            3 => p.chunks_exact(3).map(|c| [c[0], c[1], c[2], 255]).collect(),
            2 => p
                .chunks_exact(2)
                .map(|c| [c[0], c[0], c[0], c[1]])
                .collect(),
            _ => p.iter().map(|&v| [v, v, v, 255]).collect(),
        });
    }
    let channel = |px: usize, c: usize| -> u8 {
        let i = (px * channels + c) * bytes;
        match bytes {
            1 => p[i],
            // 16-bit channels are little-endian in gltf's decoded data: keep the high byte.
            2 => p[i + 1],
            _ => f32_at(i),
        }
    };
    Some(
        (0..n)
            .map(|px| match channels {
                1 => {
                    let v = channel(px, 0);
                    [v, v, v, 255]
                }
                2 => {
                    let v = channel(px, 0);
                    [v, v, v, channel(px, 1)]
                }
                3 => [channel(px, 0), channel(px, 1), channel(px, 2), 255],
                _ => [
                    channel(px, 0),
                    channel(px, 1),
                    channel(px, 2),
                    channel(px, 3),
                ],
            })
            .collect(),
    )
}

impl<'a> Decoder<'a> {
    /// The index of the texture `info` reads with coordinate set `tex_coord` through
    /// `transform`: each way of reading an image one [`Texture`], sharing the image's
    /// texels once decoded.
    fn texture(
        &mut self,
        info: Option<::gltf::texture::Texture<'a>>,
        (tex_coord, transform): (u32, UvTransform),
        warnings: &mut Vec<String>,
    ) -> Result<u32, SceneError> {
        let Some(t) = info else {
            return Ok(NO_TEXTURE);
        };
        let uv_set = if tex_coord > 1 {
            warnings.push(format!(
                "texture {} uses TEXCOORD_{tex_coord}; lumagraph reads TEXCOORD_0 and \
                 TEXCOORD_1, so TEXCOORD_0 is used instead",
                t.index()
            ));
            0
        } else {
            tex_coord
        };
        let bits = [
            transform.m[0],
            transform.m[1],
            transform.m[2],
            transform.m[3],
            transform.offset[0],
            transform.offset[1],
        ]
        .map(f32::to_bits);
        let key = (t.index(), uv_set, bits);
        if let Some(&i) = self.used.get(&key) {
            return Ok(i);
        }
        let image = *self.decoded.entry(t.index()).or_insert_with(|| {
            self.users.push((t.clone(), self.material.clone()));
            self.users.len() - 1
        });
        let index = self.textures.len() as u32;
        self.textures.push((
            Texture {
                name: String::new(),
                width: 0,
                height: 0,
                texels: Vec::new().into(),
                wrap: [Wrap::Repeat; 2],
                nearest: false,
                uv_set,
                transform,
            },
            image,
        ));
        self.used.insert(key, index);
        Ok(index)
    }

    /// Leaves out the textures none of `materials` reads, and the images only they read,
    /// before anything is decoded; the materials' indices move along (the textures kept
    /// stay in their order).
    fn keep_only(&mut self, materials: &mut [Material]) {
        let textures = std::mem::take(&mut self.textures);
        let kept = crate::scene::keep_read_textures(materials, textures);
        let mut image_index = vec![usize::MAX; self.users.len()];
        let mut users = Vec::new();
        self.textures = kept
            .into_iter()
            .map(|(t, image)| {
                if image_index[image] == usize::MAX {
                    image_index[image] = users.len();
                    users.push(self.users[image].clone());
                }
                (t, image_index[image])
            })
            .collect();
        self.users = users;
        // The maps from glTF textures are for reading materials, which is done.
        self.used.clear();
        self.decoded.clear();
    }

    /// Threads [`Decoder::decode_all`] uses: what [`set_decode_threads`] gave, else the
    /// machine's, at most 16; at most one per image.
    fn threads(&self) -> usize {
        match DECODE_THREADS.load(std::sync::atomic::Ordering::Relaxed) {
            0 => std::thread::available_parallelism()
                .map_or(1, std::num::NonZero::get)
                .min(16),
            n => n,
        }
        .clamp(1, self.users.len().max(1))
    }

    /// Decodes every image the materials use, on [`Decoder::threads`] threads, and returns
    /// the textures with their texels. The first image (in the order materials use them)
    /// that cannot be decoded is the error, naming its material.
    fn decode_all(self) -> Result<Vec<Texture>, SceneError> {
        let n = self.users.len();
        let next = std::sync::atomic::AtomicUsize::new(0);
        let results: Vec<std::sync::Mutex<Option<Result<Texture, SceneError>>>> =
            (0..n).map(|_| std::sync::Mutex::new(None)).collect();
        std::thread::scope(|scope| {
            for _ in 0..self.threads() {
                scope.spawn(|| {
                    loop {
                        let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                        let Some((t, _)) = self.users.get(i) else {
                            break;
                        };
                        let decoded = self.decode(t);
                        *results[i]
                            .lock()
                            .unwrap_or_else(std::sync::PoisonError::into_inner) = Some(decoded);
                    }
                });
            }
        });
        let mut images = Vec::with_capacity(n);
        for (slot, (_, material)) in results.into_iter().zip(&self.users) {
            let decoded = slot
                .into_inner()
                .unwrap_or_else(std::sync::PoisonError::into_inner)
                .unwrap_or_else(|| {
                    Err(SceneError::new(ErrorKind::Texture(
                        "an image was not decoded (a decoding thread stopped)".to_owned(),
                    )))
                });
            images.push(decoded.map_err(|e| e.about(format!("material \"{material}\"")))?);
        }
        Ok(self
            .textures
            .into_iter()
            .map(|(t, i)| Texture {
                uv_set: t.uv_set,
                transform: t.transform,
                ..images[i].clone()
            })
            .collect())
    }

    /// Decodes the image of `t` with its sampler.
    fn decode(&self, t: &::gltf::texture::Texture<'_>) -> Result<Texture, SceneError> {
        let image = t.source();
        let what = match image.source() {
            ::gltf::image::Source::Uri { uri, .. } if !uri.starts_with("data:") => {
                format!("\"{uri}\"")
            }
            ::gltf::image::Source::Uri { .. } => "data URI".to_owned(),
            ::gltf::image::Source::View { .. } => "buffer view".to_owned(),
        };
        let label = format!("texture {} (image {}, {what})", t.index(), image.index());
        let fail =
            |message: String| SceneError::new(ErrorKind::Texture(format!("{label}: {message}")));
        let data = ::gltf::image::Data::from_source(image.source(), self.base, self.buffers)
            .map_err(|e| fail(format!("cannot read the image: {e}")))?;
        if data.width == 0 || data.height == 0 {
            return Err(fail("the image is empty".to_owned()));
        }
        let texels =
            rgba8(&data).ok_or_else(|| fail("the image has fewer pixels than its size".into()))?;
        let sampler = t.sampler();
        let nearest = sampler.mag_filter() == Some(::gltf::texture::MagFilter::Nearest);
        Ok(Texture {
            name: format!("{} image {} ({what})", self.file, image.index()),
            width: data.width,
            height: data.height,
            texels: texels.into(),
            wrap: [wrap(sampler.wrap_s()), wrap(sampler.wrap_t())],
            nearest,
            uv_set: 0,
            transform: UvTransform::IDENTITY,
        })
    }
}

/// `KHR_materials_specular`'s strength (and `KHR_materials_ior`) on the material model's
/// dielectric specular: glTF's F0 is `((ior − 1)/(ior + 1))² · specularColor ·
/// specular` and ours `0.08 · specular · specular_color`, so `specular = 12.5 · ((ior −
/// 1)/(ior + 1))² · specularFactor` and the colour goes to `specular_color` as it is. With
/// neither extension and ior 1.5 this is the default 0.5.
pub fn gltf_specular(ior: f32, specular_factor: f32) -> f32 {
    // Exactly 0.5 at the default ior, as before the extensions were read.
    let layer = if ior == 1.5 {
        0.5
    } else {
        12.5 * ((ior - 1.0) / (ior + 1.0)).powi(2)
    };
    layer * specular_factor
}

/// `KHR_materials_diffuse_roughness` (read from the raw extension JSON):
/// `diffuseRoughnessFactor`, clamped to [0, 1], default 0; its texture is not read (a
/// warning says so).
fn diffuse_roughness(m: &::gltf::Material<'_>, warnings: &mut Vec<String>) -> f32 {
    let Some(ext) = m.extension_value("KHR_materials_diffuse_roughness") else {
        return 0.0;
    };
    if ext.get("diffuseRoughnessTexture").is_some() {
        warnings.push(format!(
            "material {}: diffuseRoughnessTexture is not read (its factor is)",
            material_name(m)
        ));
    }
    #[expect(
        clippy::cast_possible_truncation,
        reason = "a factor in [0, 1] read as JSON f64"
    )]
    ext.get("diffuseRoughnessFactor")
        .and_then(::gltf::json::Value::as_f64)
        .map_or(0.0, |f| f.clamp(0.0, 1.0) as f32)
}

/// A factor of an extension's JSON, or `default`.
#[expect(clippy::cast_possible_truncation, reason = "a factor read as JSON f64")]
fn ext_factor(ext: &::gltf::json::Value, key: &str, default: f32) -> f32 {
    ext.get(key)
        .and_then(::gltf::json::Value::as_f64)
        .map_or(default, |f| f as f32)
}

/// A texture info of an extension's JSON (`{"index", "texCoord", "extensions":
/// {"KHR_texture_transform"}}`), decoded as the typed ones are; none where the key is absent
/// or names no texture (a warning says so).
fn ext_texture<'a>(
    doc: &'a ::gltf::Document,
    material: &str,
    ext: &::gltf::json::Value,
    key: &str,
    dec: &mut Decoder<'a>,
    warnings: &mut Vec<String>,
) -> Result<u32, SceneError> {
    let Some(info) = ext.get(key) else {
        return Ok(NO_TEXTURE);
    };
    let texture = info
        .get("index")
        .and_then(::gltf::json::Value::as_u64)
        .and_then(|i| doc.textures().nth(usize::try_from(i).ok()?));
    let Some(texture) = texture else {
        warnings.push(format!(
            "material {material}: {key} names no texture of the file: not read"
        ));
        return Ok(NO_TEXTURE);
    };
    let tex_coord = info
        .get("texCoord")
        .and_then(::gltf::json::Value::as_u64)
        .map_or(0, |c| u32::try_from(c).unwrap_or(u32::MAX));
    let transform = info
        .get("extensions")
        .and_then(|e| e.get("KHR_texture_transform"));
    dec.texture(
        Some(texture),
        texture_transform(transform, tex_coord),
        warnings,
    )
}

/// `KHR_materials_clearcoat` and `KHR_materials_sheen` (from the raw extension JSON): the
/// factors and their textures, into `out`. The coat takes the base's shading normal: its
/// own normal texture is not read, and over a normal-mapped base it follows the base's
/// bumps where glTF's would be smooth (a warning says either).
fn layers<'a>(
    doc: &'a ::gltf::Document,
    m: &::gltf::Material<'a>,
    out: &mut Material,
    dec: &mut Decoder<'a>,
    warnings: &mut Vec<String>,
) -> Result<(), SceneError> {
    let name = material_name(m);
    if let Some(ext) = m.extension_value("KHR_materials_clearcoat") {
        out.clearcoat = ext_factor(ext, "clearcoatFactor", 0.0).clamp(0.0, 1.0);
        out.clearcoat_roughness = ext_factor(ext, "clearcoatRoughnessFactor", 0.0).clamp(0.0, 1.0);
        out.textures.clearcoat = ext_texture(doc, &name, ext, "clearcoatTexture", dec, warnings)?;
        out.textures.clearcoat_roughness =
            ext_texture(doc, &name, ext, "clearcoatRoughnessTexture", dec, warnings)?;
        // The coat's own normal map; without one the coat is smooth (the interpolated
        // normal), whatever the base's normal map does.
        out.textures.clearcoat_normal =
            ext_texture(doc, &name, ext, "clearcoatNormalTexture", dec, warnings)?;
        out.clearcoat_normal_scale = ext
            .get("clearcoatNormalTexture")
            .and_then(|t| t.get("scale"))
            .and_then(::gltf::json::Value::as_f64)
            .map_or(1.0, |s| s as f32);
    }
    if let Some(ext) = m.extension_value("KHR_materials_sheen") {
        let color = ext
            .get("sheenColorFactor")
            .and_then(::gltf::json::Value::as_array)
            .map_or([0.0; 3], |a| {
                [0, 1, 2].map(|i| {
                    #[expect(
                        clippy::cast_possible_truncation,
                        reason = "a colour read as JSON f64"
                    )]
                    a.get(i)
                        .and_then(::gltf::json::Value::as_f64)
                        .map_or(0.0, |c| c.max(0.0) as f32)
                })
            });
        out.sheen_color = Vec3::from(color);
        out.sheen_roughness = ext_factor(ext, "sheenRoughnessFactor", 0.0).clamp(0.0, 1.0);
        out.textures.sheen_color =
            ext_texture(doc, &name, ext, "sheenColorTexture", dec, warnings)?;
        out.textures.sheen_roughness =
            ext_texture(doc, &name, ext, "sheenRoughnessTexture", dec, warnings)?;
    }
    Ok(())
}

fn material<'a>(
    doc: &'a ::gltf::Document,
    m: &::gltf::Material<'a>,
    dec: &mut Decoder<'a>,
    warnings: &mut Vec<String>,
) -> Result<Material, SceneError> {
    let pbr = m.pbr_metallic_roughness();
    let [r, g, b, a] = pbr.base_color_factor();
    let strength = m.emissive_strength().unwrap_or(1.0);
    let mut tex = |i: Option<::gltf::texture::Info<'a>>| {
        let read = i.as_ref().map_or((0, UvTransform::IDENTITY), info_read);
        dec.texture(i.map(|i| i.texture()), read, warnings)
    };
    let base_color = tex(pbr.base_color_texture())?;
    let metallic_roughness = tex(pbr.metallic_roughness_texture())?;
    let emissive = tex(m.emissive_texture())?;
    let transmission_ext = m.transmission();
    let transmission = tex(transmission_ext
        .as_ref()
        .and_then(::gltf::material::Transmission::transmission_texture))?;
    let specular_ext = m.specular();
    let specular_tex = tex(specular_ext
        .as_ref()
        .and_then(::gltf::material::Specular::specular_texture))?;
    let specular_color_tex = tex(specular_ext
        .as_ref()
        .and_then(::gltf::material::Specular::specular_color_texture))?;
    let normal_info = m.normal_texture();
    let normal = match &normal_info {
        Some(n) => {
            let ext = n.extensions().and_then(|e| e.get("KHR_texture_transform"));
            dec.texture(
                Some(n.texture()),
                texture_transform(ext, n.tex_coord()),
                warnings,
            )?
        }
        None => NO_TEXTURE,
    };
    let ior = m.ior().unwrap_or(1.5);
    let specular = gltf_specular(
        ior,
        specular_ext
            .as_ref()
            .map_or(1.0, ::gltf::material::Specular::specular_factor),
    );
    let specular_color = specular_ext
        .as_ref()
        .map_or(Vec3::ONE, |s| Vec3::from(s.specular_color_factor()));
    let mut out = Material {
        name: material_name(m),
        base_color: Vec3::new(r, g, b),
        emission: Vec3::from(m.emissive_factor()) * strength,
        roughness: pbr.roughness_factor(),
        diffuse_roughness: diffuse_roughness(m, warnings),
        metallic: pbr.metallic_factor(),
        specular,
        specular_tint: 0.0,
        specular_color,
        transmission: transmission_ext.map_or(0.0, |t| t.transmission_factor()),
        ior,
        two_sided: m.double_sided(),
        textures: MaterialTextures {
            base_color,
            metallic_roughness,
            emissive,
            normal,
            transmission,
            specular: specular_tex,
            specular_color: specular_color_tex,
            ..MaterialTextures::default()
        },
        normal_scale: normal_info.map_or(1.0, |n| n.scale()),
        conductor: None,
        multiscatter: true,
        // KHR_materials_volume: absorption inside a thick transmissive volume (a thickness
        // of 0 is thin-walled: no volume).
        medium: m
            .volume()
            .filter(|v| v.thickness_factor() > 0.0)
            .and_then(|v| {
                crate::scene::Medium::attenuation(
                    Vec3::from(v.attenuation_color()),
                    v.attenuation_distance(),
                )
            }),
        index_matched: false,
        opacity: a.clamp(0.0, 1.0),
        alpha_mode: match m.alpha_mode() {
            ::gltf::material::AlphaMode::Opaque => crate::scene::AlphaMode::Opaque,
            ::gltf::material::AlphaMode::Mask => crate::scene::AlphaMode::Mask {
                cutoff: m.alpha_cutoff().unwrap_or(0.5).clamp(0.0, 1.0),
            },
            ::gltf::material::AlphaMode::Blend => crate::scene::AlphaMode::Blend,
        },
        ..Material::named("")
    };
    layers(doc, m, &mut out, dec, warnings)?;
    Ok(out)
}
