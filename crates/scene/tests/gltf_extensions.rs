//! What a glTF file uses and lumagraph does not read is said, never ignored in silence: a
//! required extension it does not read is an error naming the file, the extension and
//! where the file requires it; the rest are warnings naming the file, the materials,
//! meshes or nodes, and what the render lacks. GPU-free.

use glam::Mat4;
use lumagraph_scene::import::import_mesh;

/// One triangle (its buffer as a data URI), one material with `material` as its JSON
/// body, the primitive's `attributes` and the root's `extra` members.
fn gltf(material: &str, attributes: &str, extra: &str) -> String {
    // Three corners (36 bytes of f32), then three u8 colours' worth of padding: the
    // buffer holds the positions only.
    let floats: [f32; 9] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];
    let bytes: Vec<u8> = floats.iter().flat_map(|f| f.to_le_bytes()).collect();
    let b64 = base64(&bytes);
    format!(
        r#"{{
  "asset": {{"version": "2.0"}},
  {extra}
  "scene": 0,
  "scenes": [{{"nodes": [0]}}],
  "nodes": [{{"mesh": 0}}],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0{attributes}}}, "material": 0}}]}}],
  "materials": [{material}],
  "accessors": [{{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}}],
  "bufferViews": [{{"buffer": 0, "byteLength": 36}}],
  "buffers": [{{"byteLength": 36, "uri": "data:application/octet-stream;base64,{b64}"}}]
}}"#
    )
}

fn base64(bytes: &[u8]) -> String {
    const A: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for c in bytes.chunks(3) {
        let n = (u32::from(c[0]) << 16)
            | (u32::from(*c.get(1).unwrap_or(&0)) << 8)
            | u32::from(*c.get(2).unwrap_or(&0));
        for k in 0..4 {
            if k <= c.len() {
                out.push(A[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

fn write(name: &str, text: &str) -> (tempfile::TempDir, std::path::PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(name);
    std::fs::write(&path, text).unwrap();
    (dir, path)
}

#[test]
fn a_required_extension_not_read_is_an_error_located_in_the_gltf_file() {
    let text = gltf(
        r#"{"name": "paint"}"#,
        "",
        r#""extensionsUsed": ["KHR_materials_iridescence"],
  "extensionsRequired": ["KHR_materials_iridescence"],"#,
    );
    let (_dir, path) = write("Car.gltf", &text);
    let e = import_mesh(&path, Mat4::IDENTITY).unwrap_err().to_string();
    println!("{e}");
    assert!(
        e.contains("Car.gltf requires the extension KHR_materials_iridescence")
            && e.contains("extensionsRequired[0] (line 4, column 26 of its JSON)")
            && e.contains("without their thin-film iridescence"),
        "{e}"
    );
}

#[test]
fn a_required_extension_that_is_read_loads() {
    let text = gltf(
        r#"{"name": "glass", "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1.0}}}"#,
        "",
        r#""extensionsUsed": ["KHR_materials_transmission"],
  "extensionsRequired": ["KHR_materials_transmission"],"#,
    );
    let (_dir, path) = write("Glass.gltf", &text);
    let m = import_mesh(&path, Mat4::IDENTITY).unwrap();
    assert_eq!(m.materials[0].transmission, 1.0);
    assert!(m.report.warnings.is_empty(), "{:?}", m.report.warnings);
    // SheenChair's case: a file requiring KHR_texture_transform loads (the extension is
    // read; its use on textures is tested in tests/pathtrace/textures.rs).
    let text = gltf(
        r#"{"name": "cloth"}"#,
        "",
        r#""extensionsUsed": ["KHR_texture_transform"],
  "extensionsRequired": ["KHR_texture_transform"],"#,
    );
    let (_dir, path) = write("Chair.gltf", &text);
    let m = import_mesh(&path, Mat4::IDENTITY).unwrap();
    assert!(m.report.warnings.is_empty(), "{:?}", m.report.warnings);
}

#[test]
fn extensions_and_attributes_not_read_are_warnings_naming_their_users() {
    let text = gltf(
        r#"{"name": "velvet",
            "pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 1]},
            "extensions": {
              "KHR_materials_sheen": {"sheenColorFactor": [1, 0, 0], "sheenRoughnessFactor": 0.25},
              "KHR_materials_clearcoat": {"clearcoatFactor": 0.75, "clearcoatRoughnessFactor": 0.5,
                                          "clearcoatNormalTexture": {"index": 0}},
              "KHR_materials_specular": {"specularColorFactor": [1, 0.5, 0]},
              "KHR_materials_volume": {"thicknessFactor": 0.1}
            }}"#,
        r#", "COLOR_0": 0, "COLOR_1": 0"#,
        r#""extensionsUsed": ["KHR_materials_sheen", "KHR_materials_clearcoat", "KHR_materials_specular", "KHR_materials_volume", "KHR_materials_anisotropy"],"#,
    );
    let (_dir, path) = write("Velvet.gltf", &text);
    let m = import_mesh(&path, Mat4::IDENTITY).unwrap();
    let w = m.report.warnings.join("\n");
    println!("{w}");
    // Clear coat, sheen and specular colour are read (the coat's normal texture too: here it
    // names no texture of the file, which is said).
    let v = &m.materials[0];
    assert_eq!(
        (
            v.clearcoat,
            v.clearcoat_roughness,
            v.sheen_color,
            v.sheen_roughness
        ),
        (0.75, 0.5, glam::Vec3::X, 0.25)
    );
    // The specular colour is read as it is.
    assert_eq!(v.specular_color, glam::Vec3::new(1.0, 0.5, 0.0));
    assert!(!w.contains("KHR_materials_specular"), "{w}");
    assert!(!w.contains("KHR_materials_sheen"), "{w}");
    assert!(!w.contains("KHR_materials_clearcoat"), "{w}");
    for want in [
        "material velvet: clearcoatNormalTexture names no texture of the file: not read",
        "Velvet.gltf: KHR_materials_volume is read in part (used by \"velvet\"): the thickness is not used",
        "Velvet.gltf: KHR_materials_anisotropy is not read: materials render with isotropic roughness",
        "Velvet.gltf: the vertex attribute COLOR_1 is not read (1 primitives): only COLOR_0",
    ] {
        assert!(w.contains(want), "missing «{want}» in:\n{w}");
    }
    assert!(!w.contains("attribute COLOR_0"), "COLOR_0 is read:\n{w}");
}

/// `EXT_mesh_gpu_instancing`: a node's mesh at each instance, the instance's translation,
/// rotation and scale applied before the node's own transform (glTF's order); the file
/// requires the extension, and it loads.
#[test]
fn gpu_instancing_places_the_mesh_at_each_instance() {
    let corners: [f32; 9] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];
    let translations: [f32; 9] = [10.0, 0.0, 0.0, 0.0, 5.0, 0.0, 0.0, 0.0, 0.0];
    let h = std::f32::consts::FRAC_1_SQRT_2;
    // Identity, 90° about +z, identity.
    let rotations: [f32; 12] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, h, h, 0.0, 0.0, 0.0, 1.0];
    let scales: [f32; 9] = [1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 2.0, 2.0, 2.0];
    let bytes: Vec<u8> = [&corners[..], &translations, &rotations, &scales]
        .concat()
        .iter()
        .flat_map(|f| f.to_le_bytes())
        .collect();
    let text = format!(
        r#"{{
  "asset": {{"version": "2.0"}},
  "extensionsUsed": ["EXT_mesh_gpu_instancing"],
  "extensionsRequired": ["EXT_mesh_gpu_instancing"],
  "scene": 0,
  "scenes": [{{"nodes": [0]}}],
  "nodes": [{{"mesh": 0, "translation": [0, 0, 1],
    "extensions": {{"EXT_mesh_gpu_instancing": {{"attributes": {{"TRANSLATION": 1, "ROTATION": 2, "SCALE": 3}}}}}}}}],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}}}]}}],
  "accessors": [
    {{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}},
    {{"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC3"}},
    {{"bufferView": 2, "componentType": 5126, "count": 3, "type": "VEC4"}},
    {{"bufferView": 3, "componentType": 5126, "count": 3, "type": "VEC3"}}
  ],
  "bufferViews": [
    {{"buffer": 0, "byteLength": 36}},
    {{"buffer": 0, "byteOffset": 36, "byteLength": 36}},
    {{"buffer": 0, "byteOffset": 72, "byteLength": 48}},
    {{"buffer": 0, "byteOffset": 120, "byteLength": 36}}
  ],
  "buffers": [{{"byteLength": 156, "uri": "data:application/octet-stream;base64,{}"}}]
}}"#,
        base64(&bytes)
    );
    let (_dir, path) = write("Instanced.gltf", &text);
    let m = import_mesh(&path, Mat4::IDENTITY).unwrap();
    assert!(m.report.warnings.is_empty(), "{:?}", m.report.warnings);
    // The mesh is stored once, with a transform per instance.
    assert!(m.triangles.is_empty());
    assert_eq!(m.instanced.len(), 1);
    assert_eq!(m.instanced[0].triangles.len(), 1);
    let got: Vec<[glam::Vec3; 3]> = m.instanced[0]
        .transforms
        .iter()
        .map(|t| lumagraph_scene::transform_triangle(t, &m.instanced[0].triangles[0]).positions)
        .collect();
    let v = |x: f32, y: f32, z: f32| glam::Vec3::new(x, y, z);
    let want = [
        [v(10.0, 0.0, 1.0), v(11.0, 0.0, 1.0), v(10.0, 1.0, 1.0)],
        [v(0.0, 5.0, 1.0), v(0.0, 6.0, 1.0), v(-1.0, 5.0, 1.0)],
        [v(0.0, 0.0, 1.0), v(2.0, 0.0, 1.0), v(0.0, 2.0, 1.0)],
    ];
    assert_eq!(got.len(), 3, "{got:?}");
    for (g, w) in got.iter().zip(&want) {
        for (a, b) in g.iter().zip(w) {
            assert!((*a - *b).length() < 1e-5, "{got:?} against {want:?}");
        }
    }
    // An attribute of another count than the rest is an error naming the node.
    let broken = text.replace(
        r#"{"bufferView": 3, "componentType": 5126, "count": 3, "type": "VEC3"}"#,
        r#"{"bufferView": 3, "componentType": 5126, "count": 2, "type": "VEC3"}"#,
    );
    assert_ne!(broken, text);
    let (_dir, path) = write("Broken.gltf", &broken);
    let e = import_mesh(&path, Mat4::IDENTITY).unwrap_err().to_string();
    assert!(
        e.contains(
            "node 0 (unnamed): EXT_mesh_gpu_instancing: its attributes have different counts"
        ),
        "{e}"
    );
}
