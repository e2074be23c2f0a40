//! PLY import ([`ply_rs_bw`]): ASCII and binary (little and big endian) files of a `vertex`
//! element (`x`, `y`, `z`; optional normals `nx`, `ny`, `nz`, texture coordinates `u`/`v`,
//! `s`/`t` or `texture_u`/`texture_v`, and colours `red`, `green`, `blue`, `alpha` as bytes
//! or as floats in [0, 1]) and a `face` element (`vertex_indices` or `vertex_index`, a list
//! of any integer type; polygons are fanned into triangles). Other elements (`edge`,
//! `material`, …) are read past and named in a warning, as are vertex properties this
//! importer does not use. PLY has no materials: every triangle gets one default material.

use std::io::BufReader;
use std::path::Path;

use glam::{Mat4, Vec2, Vec3};
use ply_rs_bw::parser::Parser;
use ply_rs_bw::ply::{Property, PropertyAccess};

use super::ImportedMesh;
use crate::error::{ErrorKind, SceneError};
use crate::scene::{Material, Triangle, push_triangle, transform_triangle};

/// One `vertex` element: what a triangle corner can take from it.
#[derive(Clone, Debug, Default)]
struct Vertex {
    position: [f64; 3],
    /// Which of x, y, z were given.
    has_position: [bool; 3],
    normal: [f32; 3],
    has_normal: u8,
    uv: [f32; 2],
    has_uv: u8,
    /// RGBA, 0-255 (floats in [0, 1] are scaled).
    color: [u8; 4],
    has_color: u8,
}

/// The vertex properties [`Vertex`] reads.
const VERTEX_PROPERTIES: [&str; 17] = [
    "x",
    "y",
    "z",
    "nx",
    "ny",
    "nz",
    "u",
    "v",
    "s",
    "t",
    "texture_u",
    "texture_v",
    "texture_s",
    "texture_t",
    "red",
    "green",
    "blue",
];

/// A property's value as a number, if it is a scalar.
fn scalar(p: &Property) -> Option<f64> {
    Some(match *p {
        Property::Char(v) => f64::from(v),
        Property::UChar(v) => f64::from(v),
        Property::Short(v) => f64::from(v),
        Property::UShort(v) => f64::from(v),
        Property::Int(v) => f64::from(v),
        Property::UInt(v) => f64::from(v),
        Property::Float(v) => f64::from(v),
        Property::Double(v) => v,
        _ => return None,
    })
}

/// A colour channel: bytes as they are, floats in [0, 1] scaled to bytes.
fn channel(p: &Property) -> Option<u8> {
    match *p {
        Property::Float(_) | Property::Double(_) => {
            let v = scalar(p)?;
            #[expect(clippy::cast_possible_truncation, reason = "clamped to a byte")]
            #[expect(clippy::cast_sign_loss, reason = "clamped to a byte")]
            Some((v.clamp(0.0, 1.0) * 255.0).round() as u8)
        }
        _ => {
            let v = scalar(p)?;
            #[expect(clippy::cast_possible_truncation, reason = "clamped to a byte")]
            #[expect(clippy::cast_sign_loss, reason = "clamped to a byte")]
            Some(v.clamp(0.0, 255.0) as u8)
        }
    }
}

impl PropertyAccess for Vertex {
    fn new() -> Self {
        Self {
            color: [255; 4],
            ..Self::default()
        }
    }

    #[expect(
        clippy::cast_possible_truncation,
        reason = "f32 is what the renderer keeps"
    )]
    fn set_property(&mut self, key: &str, property: Property) {
        let axis = |k: &str| match k {
            "x" | "nx" | "red" | "u" | "s" | "texture_u" | "texture_s" => Some(0),
            "y" | "ny" | "green" | "v" | "t" | "texture_v" | "texture_t" => Some(1),
            "z" | "nz" | "blue" => Some(2),
            "alpha" => Some(3),
            _ => None,
        };
        match (key, axis(key), scalar(&property)) {
            ("x" | "y" | "z", Some(a), Some(v)) => {
                self.position[a] = v;
                self.has_position[a] = true;
            }
            ("nx" | "ny" | "nz", Some(a), Some(v)) => {
                self.normal[a] = v as f32;
                self.has_normal |= 1 << a;
            }
            (
                "u" | "v" | "s" | "t" | "texture_u" | "texture_v" | "texture_s" | "texture_t",
                Some(a),
                Some(v),
            ) => {
                self.uv[a] = v as f32;
                self.has_uv |= 1 << a;
            }
            ("red" | "green" | "blue" | "alpha", Some(a), Some(_)) => {
                if let Some(c) = channel(&property) {
                    self.color[a] = c;
                    self.has_color |= 1 << a;
                }
            }
            _ => {}
        }
    }
}

/// One `face` element: its corners' vertex indices (`None`: a negative index, or the list
/// missing or of floats).
#[derive(Clone, Debug, Default)]
struct Face {
    corners: Option<Vec<i64>>,
}

impl PropertyAccess for Face {
    fn new() -> Self {
        Self::default()
    }

    fn set_property(&mut self, key: &str, property: Property) {
        if !matches!(key, "vertex_indices" | "vertex_index") {
            return;
        }
        self.corners = match property {
            Property::ListChar(v) => Some(v.into_iter().map(i64::from).collect()),
            Property::ListUChar(v) => Some(v.into_iter().map(i64::from).collect()),
            Property::ListShort(v) => Some(v.into_iter().map(i64::from).collect()),
            Property::ListUShort(v) => Some(v.into_iter().map(i64::from).collect()),
            Property::ListInt(v) => Some(v.into_iter().map(i64::from).collect()),
            Property::ListUInt(v) => Some(v.into_iter().map(i64::from).collect()),
            _ => None,
        };
    }
}

/// An element this importer does not use: read past.
struct Ignored;

impl PropertyAccess for Ignored {
    fn new() -> Self {
        Self
    }
}

fn ply_error(message: impl Into<String>) -> SceneError {
    SceneError::new(ErrorKind::PlyData(message.into()))
}

/// A PLY file's vertices and faces, and warnings for what is not read.
struct Elements {
    vertices: Vec<Vertex>,
    faces: Vec<Face>,
    warnings: Vec<String>,
}

/// The file's vertices and faces, with warnings for what is not read.
fn read_elements(path: &Path) -> Result<Elements, SceneError> {
    let file =
        std::fs::File::open(path).map_err(|e| ply_error(format!("cannot read the file: {e}")))?;
    if !file.metadata().is_ok_and(|m| m.is_file()) {
        return Err(ply_error("not a file"));
    }
    let mut reader = BufReader::new(file);
    let vertex_parser = Parser::<Vertex>::new();
    let header = vertex_parser
        .read_header(&mut reader)
        .map_err(|e| ply_error(format!("header: {e}")))?;
    let mut vertices: Option<Vec<Vertex>> = None;
    let mut faces: Vec<Face> = Vec::new();
    let mut warnings = Vec::new();
    for element in header.elements.values() {
        let what = |e: std::io::Error| ply_error(format!("element \"{}\": {e}", element.name));
        match element.name.as_str() {
            "vertex" => {
                let unused: Vec<&str> = element
                    .properties
                    .keys()
                    .map(String::as_str)
                    .filter(|k| !VERTEX_PROPERTIES.contains(k) && *k != "alpha")
                    .collect();
                if !unused.is_empty() {
                    warnings.push(format!("vertex properties not read: {}", unused.join(", ")));
                }
                vertices = Some(
                    vertex_parser
                        .read_payload_for_element(&mut reader, element, &header)
                        .map_err(what)?,
                );
            }
            "face" => {
                faces = Parser::<Face>::new()
                    .read_payload_for_element(&mut reader, element, &header)
                    .map_err(what)?;
            }
            other => {
                Parser::<Ignored>::new()
                    .read_payload_for_element(&mut reader, element, &header)
                    .map_err(what)?;
                warnings.push(format!(
                    "element \"{other}\" ({} entries) not read: only vertices and faces are",
                    element.count
                ));
            }
        }
    }
    let vertices = vertices.ok_or_else(|| ply_error("no \"vertex\" element"))?;
    // Every vertex has the element's properties: the first says for all.
    if vertices
        .first()
        .is_some_and(|v| v.has_position != [true; 3])
    {
        return Err(ply_error("the vertices have no x, y and z"));
    }
    if faces.is_empty() {
        warnings.push("no faces: a point cloud has no surface to render".to_owned());
    }
    Ok(Elements {
        vertices,
        faces,
        warnings,
    })
}

/// Imports a `.ply` file, placed by `transform`.
///
/// # Errors
/// When the file cannot be read or parsed, has no `vertex` element with x, y and z, or a
/// face refers to a vertex it does not have (the face is named).
pub fn import_ply(path: &Path, transform: Mat4) -> Result<ImportedMesh, SceneError> {
    let Elements {
        vertices,
        faces,
        warnings,
    } = read_elements(path)?;
    let mut out = ImportedMesh::default();
    out.report.warnings = warnings;
    out.materials.push(Material::named("default"));
    let position = |v: &Vertex| {
        #[expect(
            clippy::cast_possible_truncation,
            reason = "f32 is what the renderer keeps"
        )]
        Vec3::new(
            v.position[0] as f32,
            v.position[1] as f32,
            v.position[2] as f32,
        )
    };
    let mut skipped = 0usize;
    for (f, face) in faces.iter().enumerate() {
        let Some(corners) = &face.corners else {
            return Err(ply_error(format!(
                "face {f}: no integer list \"vertex_indices\" or \"vertex_index\""
            )));
        };
        let mut at = Vec::with_capacity(corners.len());
        for &i in corners {
            match usize::try_from(i).ok().filter(|&i| i < vertices.len()) {
                Some(i) => at.push(&vertices[i]),
                None => {
                    return Err(ply_error(format!(
                        "face {f}: vertex index {i} refers to no vertex (the file has {})",
                        vertices.len()
                    )));
                }
            }
        }
        if at.len() < 3 {
            skipped += 1;
            continue;
        }
        // A polygon as a fan about its first corner.
        for k in 1..at.len() - 1 {
            let c = [at[0], at[k], at[k + 1]];
            let all = |bits: fn(&Vertex) -> u8, full: u8| c.iter().all(|v| bits(v) == full);
            let tri = Triangle {
                positions: c.map(position),
                normals: all(|v| v.has_normal, 0b111).then(|| c.map(|v| Vec3::from(v.normal))),
                uvs: all(|v| v.has_uv, 0b11).then(|| c.map(|v| Vec2::from(v.uv))),
                uvs1: None,
                colors: c
                    .iter()
                    .all(|v| v.has_color & 0b111 == 0b111)
                    .then(|| c.map(|v| v.color)),
                tangents: None,
                material: 0,
            };
            push_triangle(
                &mut out.triangles,
                &mut out.report,
                transform_triangle(&transform, &tri),
            );
        }
    }
    if skipped > 0 {
        out.report
            .warnings
            .push(format!("{skipped} faces of fewer than 3 corners dropped"));
    }
    Ok(out)
}
