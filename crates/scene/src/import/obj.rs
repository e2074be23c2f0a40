//! OBJ + MTL import ([`tobj`]): polygons triangulated, `Kd` → base color, `Ke` →
//! emission, `Ks` black or absent → specular 0 (else 0.5), `Ni` → IOR, roughness 1.
//! Vertex normals are kept when every corner has one.

use std::path::Path;

use glam::{Mat4, Vec3};

use super::ImportedMesh;
use crate::error::SceneError;
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
    let (models, materials) = tobj::load_obj(path, &options)?;
    let mut out = ImportedMesh::default();
    match materials {
        Ok(mats) => out.materials = mats.iter().map(material).collect(),
        Err(e) => out
            .report
            .warnings
            .push(format!("materials not loaded: {e}")),
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
