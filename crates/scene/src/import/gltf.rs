//! glTF 2.0 import: every mesh of the default scene through the whole node hierarchy,
//! perspective cameras, metallic-roughness materials (factors; texture indices recorded
//! but not decoded), `KHR_materials_emissive_strength`, `KHR_materials_ior` and
//! `KHR_materials_transmission`.

use std::path::Path;

use glam::{Mat4, Vec3};

use super::ImportedMesh;
use crate::error::SceneError;
use crate::scene::{
    Camera, Material, MaterialTextures, NO_TEXTURE, Triangle, push_triangle, transform_triangle,
};

/// Imports a `.gltf` (with embedded or external buffers) or `.glb` file.
///
/// # Errors
/// When the file or its buffers cannot be read or are not valid glTF.
pub fn import_gltf(path: &Path, transform: Mat4) -> Result<ImportedMesh, SceneError> {
    let file = ::gltf::Gltf::open(path)?;
    let buffers = ::gltf::import_buffers(&file.document, path.parent(), file.blob.clone())?;
    let doc = &file.document;
    let mut out = ImportedMesh {
        materials: doc.materials().map(|m| material(&m)).collect(),
        ..ImportedMesh::default()
    };
    let mut default_material = None;

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
        if let Some(mesh) = node.mesh() {
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
                read_primitive(&prim, &buffers, &world, material as u32, &mut out);
            }
        }
        let children: Vec<_> = node.children().collect();
        stack.extend(children.into_iter().rev().map(|c| (c, world)));
    }
    Ok(out)
}

fn read_primitive(
    prim: &::gltf::Primitive<'_>,
    buffers: &[::gltf::buffer::Data],
    world: &Mat4,
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
            material,
        };
        push_triangle(
            &mut out.triangles,
            &mut out.report,
            transform_triangle(world, &tri),
        );
    }
    if bad_indices > 0 {
        out.report.warnings.push(format!(
            "primitive {}: {bad_indices} triangles with out-of-range indices dropped",
            prim.index()
        ));
    }
}

fn material(m: &::gltf::Material<'_>) -> Material {
    let pbr = m.pbr_metallic_roughness();
    let [r, g, b, _] = pbr.base_color_factor();
    let strength = m.emissive_strength().unwrap_or(1.0);
    let tex = |t: Option<::gltf::texture::Texture<'_>>| t.map_or(NO_TEXTURE, |t| t.index() as u32);
    Material {
        name: m.name().map_or_else(
            || format!("material{}", m.index().unwrap_or(usize::MAX)),
            str::to_owned,
        ),
        base_color: Vec3::new(r, g, b),
        emission: Vec3::from(m.emissive_factor()) * strength,
        roughness: pbr.roughness_factor(),
        metallic: pbr.metallic_factor(),
        specular: 0.5,
        specular_tint: 0.0,
        transmission: m.transmission().map_or(0.0, |t| t.transmission_factor()),
        ior: m.ior().unwrap_or(1.5),
        two_sided: m.double_sided(),
        textures: MaterialTextures {
            base_color: tex(pbr.base_color_texture().map(|i| i.texture())),
            metallic_roughness: tex(pbr.metallic_roughness_texture().map(|i| i.texture())),
            emissive: tex(m.emissive_texture().map(|i| i.texture())),
            normal: tex(m.normal_texture().map(|i| i.texture())),
        },
    }
}
