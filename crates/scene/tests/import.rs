//! glTF and OBJ import: counts, bounds, materials, cameras, broken triangles.

mod common;

use glam::{Mat4, Vec3};
use lumagraph_scene::import::{ImportedMesh, import_mesh};

fn bounds(m: &ImportedMesh) -> (Vec3, Vec3) {
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for p in m.triangles.iter().flat_map(|t| t.positions) {
        lo = lo.min(p);
        hi = hi.max(p);
    }
    (lo, hi)
}

fn close(a: Vec3, b: Vec3, eps: f32) -> bool {
    (a - b).abs().max_element() <= eps
}

#[test]
fn gltf_sphere_grid() {
    let path = common::assets().join("SphereGrids/SphereGrid_MetalRough.gltf");
    let m = import_mesh(&path, Mat4::IDENTITY).unwrap();
    // 25 spheres × 6624 indices / 3 = 55 200 triangles, less the zero-area ones at the
    // poles of each UV sphere, which are dropped and counted.
    let dropped = m.report.degenerate_triangles;
    assert_eq!(m.triangles.len() + dropped, 25 * 2208);
    assert_eq!(m.report.non_finite_triangles, 0);
    assert_eq!(dropped % 25, 0, "the same per sphere");
    // Grid: spacing 1.2, radius 0.5, centered.
    let (lo, hi) = bounds(&m);
    assert!(close(lo, Vec3::new(-2.9, -2.9, -0.5), 1e-4), "{lo}");
    assert!(close(hi, Vec3::new(2.9, 2.9, 0.5), 1e-4), "{hi}");
    assert_eq!(m.materials.len(), 25);
    for mat in &m.materials {
        assert!(close(mat.base_color, Vec3::new(0.95, 0.64, 0.54), 1e-6));
    }
    let m00 = m
        .materials
        .iter()
        .find(|x| x.name == "m0.00_r0.00")
        .unwrap();
    assert_eq!((m00.metallic, m00.roughness), (0.0, 0.0));
    let m11 = m
        .materials
        .iter()
        .find(|x| x.name == "m1.00_r1.00")
        .unwrap();
    assert_eq!((m11.metallic, m11.roughness), (1.0, 1.0));
    // Vertex normals are kept, unit, and point away from the sphere centers.
    assert!(m.triangles.iter().all(|t| t.normals.is_some()));
    let t = &m.triangles[100];
    let center = (t.positions[0] + t.positions[1] + t.positions[2]) / 3.0;
    let sphere_center = (center / 1.2).round() * 1.2;
    let n = t.normals.unwrap()[0];
    assert!((n.length() - 1.0).abs() < 1e-5);
    assert!(n.dot(center - sphere_center) > 0.0);
    assert!(m.cameras.is_empty());
}

#[test]
fn gltf_cornell_box() {
    let path = common::assets().join("CornellBox/CornellBox.gltf");
    let m = import_mesh(&path, Mat4::IDENTITY).unwrap();
    assert!(m.report.is_clean(), "{:?}", m.report);
    // 5 walls + light: 2 triangles each; 2 blocks × 5 faces × 2.
    assert_eq!(m.triangles.len(), 32);
    let (lo, hi) = bounds(&m);
    assert!(close(lo, Vec3::new(0.0, 0.0, 0.0), 1e-6), "{lo}");
    assert!(close(hi, Vec3::new(0.556, 0.5488, 0.5592), 1e-6), "{hi}");
    let light = m.materials.iter().find(|x| x.name == "light").unwrap();
    assert!(
        close(light.emission, Vec3::new(17.0, 12.0, 4.0), 1e-4),
        "{}",
        light.emission
    );
    let red = m.materials.iter().find(|x| x.name == "red").unwrap();
    assert!(close(red.base_color, Vec3::new(0.63, 0.065, 0.05), 1e-6));
    assert_eq!(m.cameras.len(), 1);
    let c = m.cameras[0];
    assert!(close(c.position, Vec3::new(0.278, 0.273, -0.8), 1e-6));
    assert!(close(c.forward, Vec3::Z, 1e-6), "{}", c.forward);
    assert!((c.fov_y_deg - 39.3077).abs() < 1e-3);
    // The light faces down.
    let lid = m.materials.iter().position(|x| x.name == "light").unwrap() as u32;
    let lights: Vec<_> = m.triangles.iter().filter(|t| t.material == lid).collect();
    assert_eq!(lights.len(), 2);
    for t in lights {
        assert!(close(t.normal(), Vec3::NEG_Y, 1e-6));
    }
}

#[test]
fn obj_cornell_box() {
    let path = common::assets().join("CornellBox/CornellBox.obj");
    let m = import_mesh(&path, Mat4::from_scale(Vec3::splat(0.001))).unwrap();
    assert!(m.report.is_clean(), "{:?}", m.report);
    assert_eq!(m.triangles.len(), 32);
    let (lo, hi) = bounds(&m);
    assert!(close(lo, Vec3::ZERO, 1e-6), "{lo}");
    assert!(close(hi, Vec3::new(0.556, 0.5488, 0.5592), 1e-6), "{hi}");
    let by_name = |n: &str| m.materials.iter().find(|x| x.name == n).unwrap();
    assert_eq!(by_name("white").base_color, Vec3::new(0.725, 0.71, 0.68));
    assert_eq!(by_name("green").base_color, Vec3::new(0.14, 0.45, 0.091));
    assert_eq!(by_name("light").emission, Vec3::new(17.0, 12.0, 4.0));
    assert_eq!(by_name("white").emission, Vec3::ZERO);
    // No normals in the file: flat normals are generated later.
    assert!(m.triangles.iter().all(|t| t.normals.is_none()));
    // Light faces down, floor faces up.
    let lid = m.materials.iter().position(|x| x.name == "light").unwrap() as u32;
    assert!(
        m.triangles
            .iter()
            .filter(|t| t.material == lid)
            .all(|t| close(t.normal(), Vec3::NEG_Y, 1e-6))
    );
}

#[test]
fn broken_triangles_are_dropped_and_counted() {
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR"));
    let obj = dir.join("broken.obj");
    std::fs::write(
        &obj,
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nv nan 0 0\nv inf 1 1\nv 0 0 0\n\
         vn 0 0 1\nvn 0 0 0\n\
         f 1 2 3\n\
         f 1 2 4\n\
         f 1 7 3\n\
         f 1 2 5\n\
         f 6 2 3\n\
         f 1//1 2//1 3//2\n",
    )
    .unwrap();
    let m = import_mesh(&obj, Mat4::IDENTITY).unwrap();
    // Good: face 1 and face 6 (its zero normal replaced by the flat one).
    assert_eq!(m.triangles.len(), 2, "{:?}", m.report);
    assert_eq!(m.report.degenerate_triangles, 2);
    assert_eq!(m.report.non_finite_triangles, 2);
    assert!(m.report.replaced_normals <= 1);

    let e = import_mesh(&dir.join("missing.obj"), Mat4::IDENTITY).unwrap_err();
    assert!(e.to_string().contains("missing.obj"), "{e}");
    let e = import_mesh(&dir.join("model.fbx"), Mat4::IDENTITY).unwrap_err();
    assert!(e.to_string().contains("fbx"), "{e}");
}

#[test]
fn mirrored_transform_keeps_front_side() {
    let path = common::assets().join("CornellBox/CornellBox.gltf");
    let mirror = Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0));
    let m = import_mesh(&path, mirror).unwrap();
    let lid = m.materials.iter().position(|x| x.name == "light").unwrap() as u32;
    for t in m.triangles.iter().filter(|t| t.material == lid) {
        assert!(close(t.normal(), Vec3::NEG_Y, 1e-6), "{}", t.normal());
    }
}

/// An OBJ whose `mtllib` names a device (which would be read without end) loads without
/// materials, saying why.
#[cfg(unix)]
#[test]
fn an_mtllib_naming_a_device_is_not_read() {
    let obj = std::env::temp_dir().join(format!("lumagraph-mtllib-{}.obj", std::process::id()));
    std::fs::write(
        &obj,
        "mtllib /dev/zero\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    )
    .unwrap();
    let m = import_mesh(&obj, Mat4::IDENTITY);
    let _ = std::fs::remove_file(&obj);
    let m = m.unwrap();
    assert_eq!(m.triangles.len(), 1);
    assert!(
        m.report
            .warnings
            .iter()
            .any(|w| w.contains("/dev/zero is not a file")),
        "{:?}",
        m.report.warnings
    );
}

/// A PNG of `w`×`h` texels, each `f(x, y)`.
fn png(path: &std::path::Path, w: u32, h: u32, f: impl Fn(u32, u32) -> [u8; 3]) {
    image::RgbImage::from_fn(w, h, |x, y| image::Rgb(f(x, y)))
        .save(path)
        .unwrap();
}

/// MTL maps: `map_Kd` is the base colour texture and `map_d` its alpha (blended), `norm` the
/// normal map, a coloured `map_Bump` a normal map too and a grey one (a height map) not read
/// and said so; `map_Ke` the emission (in full where `Ke` is absent); `d` below 1 blends; `Pr`
/// and `Pm` set roughness and metallic; maps not read are named; OBJ's `v` is flipped to
/// glTF's; textures no material uses alone are not kept; an image
/// two materials use is decoded once; a missing image is an error naming its material and
/// file.
#[test]
fn obj_textures_are_read() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    png(&d.join("albedo.png"), 4, 2, |x, _| [x as u8 * 60, 10, 200]);
    png(&d.join("normal.png"), 2, 2, |_, _| [128, 128, 255]);
    png(&d.join("height.png"), 2, 2, |x, y| [(x + y) as u8 * 90; 3]);
    png(&d.join("mask.png"), 2, 1, |x, _| [x as u8 * 255; 3]);
    std::fs::write(
        d.join("m.obj"),
        "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 1 0.25\nvn 0 0 1\n\
         usemtl a\nf 1/1/1 2/2/1 3/3/1\nusemtl b\nf 1/1/1 3/3/1 2/2/1\nusemtl c\nf 2/2/1 1/1/1 3/3/1\n",
    )
    .unwrap();
    std::fs::write(
        d.join("m.mtl"),
        "newmtl a\nKd 1 1 1\nmap_Kd albedo.png\nnorm normal.png\nd 0.5\nPr 0.3\nPm 1\n\
         map_Ks albedo.png\nmap_d mask.png\n\
         newmtl b\nKd 1 1 1\nmap_Kd albedo.png\nmap_Bump -bm 1.0 height.png\nmap_Ke albedo.png\n\
         newmtl c\nKd 1 1 1\nbump normal.png\n",
    )
    .unwrap();
    let m = import_mesh(&d.join("m.obj"), Mat4::IDENTITY).unwrap();
    let names: Vec<&str> = m.textures.iter().map(|t| t.name.as_str()).collect();
    // Each image decoded once; the mask merged into the base colour and the grey bump map
    // not kept on their own.
    assert_eq!(
        names,
        [
            "albedo.png",
            "albedo.png with alpha from mask.png",
            "normal.png"
        ]
    );
    let (a, b, c) = (&m.materials[0], &m.materials[1], &m.materials[2]);
    assert_eq!(a.textures.base_color, 1);
    // The 2x1 mask over the 4x2 albedo, nearest texel: columns 0-1 from 0, 2-3 from 255.
    let alphas: Vec<u8> = m.textures[1].texels.iter().map(|p| p[3]).collect();
    assert_eq!(alphas, [0, 0, 255, 255, 0, 0, 255, 255]);
    assert_eq!(m.textures[1].texels[1][..3], [60, 10, 200]);
    assert_eq!(a.textures.normal, 2);
    assert_eq!(a.opacity, 0.5);
    assert_eq!(a.alpha_mode, lumagraph_scene::AlphaMode::Blend);
    assert_eq!((a.roughness, a.metallic), (0.3, 1.0));
    assert_eq!(b.textures.base_color, 0);
    assert_eq!(
        b.textures.normal,
        lumagraph_scene::NO_TEXTURE,
        "grey bump map read"
    );
    assert_eq!(b.textures.emissive, 0);
    assert_eq!(b.emission, Vec3::ONE);
    assert_eq!(b.alpha_mode, lumagraph_scene::AlphaMode::Opaque);
    assert_eq!(c.textures.normal, 2, "a coloured bump map is a normal map");
    let warnings = m.report.warnings.join("\n");
    assert!(warnings.contains("\"a\": map_Ks not read"), "{warnings}");
    assert!(
        warnings.contains("bump map \"-bm 1.0 height.png\" not read"),
        "{warnings}"
    );
    assert_eq!(m.decode.images, 4);
    // OBJ v = 0.25 is glTF's 0.75.
    let uvs = m.triangles[0].uvs.expect("texture coordinates kept");
    assert_eq!(uvs[2], glam::Vec2::new(1.0, 0.75));
    assert_eq!(m.textures[0].texels[1], [60, 10, 200, 255]);

    std::fs::write(d.join("m.mtl"), "newmtl a\nmap_Kd missing.png\n").unwrap();
    let e = import_mesh(&d.join("m.obj"), Mat4::IDENTITY)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("m.obj") && e.contains("material \"a\"") && e.contains("missing.png"),
        "{e}"
    );
}

/// A `Mesh`'s `diffuse: true` reduces a glTF file's materials before its images are decoded:
/// only the base colour is decoded (the roughness map is not, and a normal map that cannot
/// be decoded is no error), and the textures and materials are those of the whole import
/// reduced afterwards.
#[test]
fn a_diffuse_gltf_decodes_only_its_base_colours() {
    use lumagraph_scene::NO_TEXTURE;
    use lumagraph_scene::import::import_mesh_with;
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    png(&d.join("rough.png"), 2, 2, |x, y| {
        [0, (x * 100) as u8, (y * 100) as u8]
    });
    png(&d.join("base.png"), 4, 2, |x, y| {
        [x as u8 * 60, y as u8 * 90, 200]
    });
    png(&d.join("normal.png"), 2, 2, |_, _| [128, 128, 255]);
    // Positions, then texture coordinates: one triangle.
    let floats: [f32; 15] = [
        0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0,
    ];
    let bytes: Vec<u8> = floats.iter().flat_map(|f| f.to_le_bytes()).collect();
    std::fs::write(d.join("m.bin"), &bytes).unwrap();
    let gltf = r#"{
  "asset": {"version": "2.0"},
  "scene": 0,
  "scenes": [{"nodes": [0]}],
  "nodes": [{"mesh": 0}],
  "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "material": 0}]}],
  "materials": [{"name": "stone", "normalTexture": {"index": 2},
    "pbrMetallicRoughness": {"metallicRoughnessTexture": {"index": 0}, "baseColorTexture": {"index": 1}}}],
  "textures": [{"source": 0}, {"source": 1}, {"source": 2}],
  "images": [{"uri": "rough.png"}, {"uri": "base.png"}, {"uri": "normal.png"}],
  "accessors": [
    {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
    {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC2"}],
  "bufferViews": [{"buffer": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 24}],
  "buffers": [{"byteLength": 60, "uri": "m.bin"}]
}"#;
    std::fs::write(d.join("m.gltf"), gltf).unwrap();
    let path = d.join("m.gltf");
    let whole = import_mesh(&path, Mat4::IDENTITY).unwrap();
    assert_eq!(whole.decode.images, 3);
    let diffuse = import_mesh_with(&path, Mat4::IDENTITY, true).unwrap();
    assert_eq!(diffuse.decode.images, 1);
    assert_eq!(diffuse.textures.len(), 1);
    let (m, full) = (&diffuse.materials[0], &whole.materials[0]);
    let mut expected = full.as_diffuse();
    expected.textures.base_color = 0;
    assert_eq!(m, &expected);
    let (t, base) = (
        &diffuse.textures[0],
        &whole.textures[full.textures.base_color as usize],
    );
    assert_eq!(
        (t.width, t.height, &t.texels, &t.name),
        (base.width, base.height, &base.texels, &base.name)
    );
    assert_eq!(m.textures.normal, NO_TEXTURE);
    // The normal map unreadable: the whole import fails, the diffuse one does not read it.
    std::fs::write(d.join("normal.png"), b"not a PNG").unwrap();
    assert!(import_mesh(&path, Mat4::IDENTITY).is_err());
    let again = import_mesh_with(&path, Mat4::IDENTITY, true).unwrap();
    assert_eq!(again.textures[0].texels, t.texels);
}
