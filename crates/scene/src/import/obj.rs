//! OBJ + MTL import ([`tobj`]): polygons triangulated, `Kd` → base color, `Ke` →
//! emission, `Ks` black or absent → specular 0 (else 0.5), `Ni` → IOR, roughness 1.
//! Vertex normals are kept when every corner has one.

use std::cell::RefCell;
use std::path::Path;

use glam::{Mat4, Vec3};

use super::ImportedMesh;
use crate::error::{ErrorKind, SceneError};
use crate::scene::{Material, Triangle, push_triangle, transform_triangle};

/// Imports an `.obj` file and the `.mtl` files it names.
///
/// # Errors
/// When the OBJ cannot be read or parsed. A missing or broken MTL is a warning: the
/// triangles get a default material.
pub fn import_obj(path: &Path, transform: Mat4) -> Result<ImportedMesh, SceneError> {
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ..tobj::LoadOptions::default()
    };
    let text = std::fs::read(path).map_err(|_| tobj::LoadError::OpenFileFailed)?;
    if let Some(problem) = check_obj(&String::from_utf8_lossy(&text)) {
        return Err(SceneError::new(ErrorKind::ObjData(problem)));
    }
    let base = path.parent().unwrap_or(Path::new(""));
    // What tobj's own MTL loader would say, and which line it could not read (it says
    // only that something failed).
    let mtl_problem = RefCell::new(None);
    let (models, materials) = tobj::load_obj_buf(&mut text.as_slice(), &options, |mtl: &Path| {
        let mtl_path = base.join(mtl);
        // `mtllib` may name a device or a pipe, which would be read without end.
        if std::fs::metadata(&mtl_path).is_ok_and(|m| !m.is_file()) {
            *mtl_problem.borrow_mut() = Some(format!("{} is not a file", mtl_path.display()));
            return Err(tobj::LoadError::OpenFileFailed);
        }
        let text = std::fs::read(&mtl_path).map_err(|_| tobj::LoadError::OpenFileFailed)?;
        if let Some(problem) = check_mtl(&text) {
            *mtl_problem.borrow_mut() = Some(format!("{}: {problem}", mtl_path.display()));
            return Err(tobj::LoadError::MaterialParseError);
        }
        tobj::load_mtl_buf(&mut text.as_slice())
    })?;
    let mut out = ImportedMesh::default();
    match materials {
        Ok(mats) => out.materials = mats.iter().map(material).collect(),
        Err(e) => out.report.warnings.push(match mtl_problem.into_inner() {
            Some(problem) => format!("materials not loaded: {problem}"),
            None => format!("materials not loaded: {e}"),
        }),
    }
    let mut default_material = None;
    for model in &models {
        let mesh = &model.mesh;
        let material = match mesh.material_id.filter(|&i| i < out.materials.len()) {
            Some(i) => i,
            None => *default_material.get_or_insert_with(|| {
                out.materials.push(Material::named("default"));
                out.materials.len() - 1
            }),
        } as u32;
        let vertex = |i: u32, data: &[f32]| {
            let i = i as usize * 3;
            data.get(i..i + 3).map(Vec3::from_slice)
        };
        let has_normals = mesh.normals.len() == mesh.positions.len();
        for t in mesh.indices.chunks_exact(3) {
            let p = [t[0], t[1], t[2]].map(|i| vertex(i, &mesh.positions));
            let [Some(p0), Some(p1), Some(p2)] = p else {
                out.report.warnings.push(format!(
                    "object \"{}\": a face with out-of-range indices dropped",
                    model.name
                ));
                continue;
            };
            let normals = if has_normals {
                let n = [t[0], t[1], t[2]].map(|i| vertex(i, &mesh.normals));
                match n {
                    [Some(a), Some(b), Some(c)] => Some([a, b, c]),
                    _ => None,
                }
            } else {
                None
            };
            let tri = Triangle {
                positions: [p0, p1, p2],
                normals,
                uvs: None,
                uvs1: None,
                colors: None,
                tangents: None,
                material,
            };
            push_triangle(
                &mut out.triangles,
                &mut out.report,
                transform_triangle(&transform, &tri),
            );
        }
    }
    Ok(out)
}

/// The first face corner of an OBJ file that refers to an element the file does not have:
/// index 0, a relative (negative) index before the first element, or an index past the
/// last. tobj computes with such indices unchecked (an overflow) or reads past its arrays.
fn check_obj(text: &str) -> Option<String> {
    const KEYS: [&str; 3] = ["v", "vt", "vn"];
    const WHAT: [&str; 3] = ["vertex", "texture coordinate", "normal"];
    let count = |key: &str| {
        text.lines()
            .filter(|l| l.split_whitespace().next() == Some(key))
            .count()
    };
    let totals = KEYS.map(count);
    let mut seen = [0usize; 3];
    for (i, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("f" | "l") => {}
            Some(key) => {
                if let Some(k) = KEYS.iter().position(|&x| x == key) {
                    seen[k] += 1;
                }
                continue;
            }
            None => continue,
        }
        for corner in words {
            for (k, part) in corner.split('/').take(3).enumerate() {
                let Ok(x) = part.parse::<i64>() else { continue };
                let in_range = match usize::try_from(x.unsigned_abs()) {
                    Ok(n) if x < 0 => n <= seen[k],
                    Ok(n) => n >= 1 && n <= totals[k],
                    Err(_) => false,
                };
                if !in_range {
                    return Some(format!(
                        "line {}: {} index {x} refers to no {} (the file has {} before this \
                         line, {} in all; indices start at 1, negative ones count back)",
                        i + 1,
                        WHAT[k],
                        WHAT[k],
                        seen[k],
                        totals[k]
                    ));
                }
            }
        }
    }
    None
}

/// The first line of an MTL file that tobj cannot be given: a colour (`Ka`, `Kd`, `Ks`,
/// `Ke`) with fewer than three numbers, on which tobj 4.0 panics.
fn check_mtl(text: &[u8]) -> Option<String> {
    let text = String::from_utf8_lossy(text);
    text.lines().enumerate().find_map(|(i, line)| {
        let mut words = line.split_whitespace();
        let key = words.next()?;
        let numbers = words.count();
        (matches!(key, "Ka" | "Kd" | "Ks" | "Ke") && numbers < 3).then(|| {
            format!(
                "line {}: `{key}` needs three numbers (red, green, blue), found {numbers}",
                i + 1
            )
        })
    })
}

fn material(m: &tobj::Material) -> Material {
    let specular = match m.specular {
        Some(ks) if ks.iter().any(|&c| c > 0.0) => 0.5,
        _ => 0.0,
    };
    Material {
        base_color: m.diffuse.map_or(Vec3::splat(0.8), Vec3::from),
        emission: m.emissive.map_or(Vec3::ZERO, Vec3::from),
        roughness: 1.0,
        specular,
        ior: m.optical_density.unwrap_or(1.5),
        ..Material::named(m.name.clone())
    }
}
