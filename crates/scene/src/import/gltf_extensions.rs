//! What of a glTF file is not read, said out loud: an extension the file requires and
//! lumagraph does not read is an error located in the glTF file; every extension, attribute
//! or material feature it uses and lumagraph ignores (or reads only in part) is one warning
//! naming the file, the materials, meshes or nodes, and what is lost.
//!
//! The checks read the file's JSON as it is (not the gltf crate's typed view, which drops
//! extensions it does not know).

use std::collections::BTreeMap;
use std::fmt::Write as _;

use serde_json::Value;

use crate::error::{ErrorKind, SceneError};

/// Extensions read (in full, or with what is not read said where it is met: a light's
/// `range`, which physical lights do not have, and `KHR_materials_diffuse_roughness`'s
/// texture, warned about by the material reader).
const READ: &[&str] = &[
    "KHR_materials_emissive_strength",
    "KHR_materials_clearcoat",
    "KHR_materials_sheen",
    "KHR_materials_specular",
    "KHR_materials_ior",
    "KHR_materials_transmission",
    "KHR_materials_diffuse_roughness",
    "KHR_lights_punctual",
    "KHR_texture_transform",
    "EXT_mesh_gpu_instancing",
];

/// Extensions that carry nothing a render shows (metadata): neither read nor warned about.
const NOTHING_TO_RENDER: &[&str] = &["KHR_xmp", "KHR_xmp_json_ld"];

/// Extensions read in part, with what is not read.
const PARTLY_READ: &[(&str, &str)] = &[(
    "KHR_materials_volume",
    "the thickness is not used: the mesh itself is the volume",
)];

/// Extensions not read, with what a render of a file that uses them lacks.
const NOT_READ: &[(&str, &str)] = &[
    (
        "KHR_materials_iridescence",
        "materials render without their thin-film iridescence",
    ),
    (
        "KHR_materials_anisotropy",
        "materials render with isotropic roughness",
    ),
    (
        "KHR_materials_dispersion",
        "glass renders without dispersion",
    ),
    (
        "KHR_materials_variants",
        "only the default materials are used",
    ),
    (
        "KHR_materials_unlit",
        "unlit materials are shaded as lit ones",
    ),
    (
        "KHR_materials_pbrSpecularGlossiness",
        "specular-glossiness materials are not read: their metallic-roughness fallback (or the defaults) is used",
    ),
    (
        "KHR_mesh_quantization",
        "quantized attributes may be read wrongly",
    ),
    (
        "KHR_draco_mesh_compression",
        "compressed meshes cannot be read",
    ),
    (
        "EXT_meshopt_compression",
        "compressed buffers cannot be read",
    ),
    ("KHR_texture_basisu", "KTX2 textures cannot be read"),
    ("EXT_texture_webp", "WebP textures cannot be read"),
];

/// The file's JSON: the whole text of a `.gltf`, the JSON chunk of a `.glb`.
fn json_text(bytes: &[u8]) -> Option<&[u8]> {
    if bytes.starts_with(b"glTF") {
        let len = u32::from_le_bytes(bytes.get(12..16)?.try_into().ok()?) as usize;
        if bytes.get(16..20)? != b"JSON" {
            return None;
        }
        bytes.get(20..20 + len)
    } else {
        Some(bytes)
    }
}

/// Line and column (1-based) of byte `at` of `text`.
fn line_col(text: &[u8], at: usize) -> (usize, usize) {
    let before = &text[..at.min(text.len())];
    let line = before.iter().filter(|&&b| b == b'\n').count() + 1;
    let col = at
        - before
            .iter()
            .rposition(|&b| b == b'\n')
            .map_or(0, |p| p + 1)
        + 1;
    (line, col)
}

/// Every material's name by index, for messages.
fn material_names(root: &Value) -> Vec<String> {
    root.get("materials")
        .and_then(Value::as_array)
        .map(|ms| {
            ms.iter()
                .enumerate()
                .map(|(i, m)| {
                    m.get("name")
                        .and_then(Value::as_str)
                        .map_or_else(|| format!("material {i}"), |n| format!("\"{n}\""))
                })
                .collect()
        })
        .unwrap_or_default()
}

/// Up to four names, then how many more.
fn some(names: &[String]) -> String {
    let mut out = names.iter().take(4).cloned().collect::<Vec<_>>().join(", ");
    if names.len() > 4 {
        let _ = write!(out, " and {} more", names.len() - 4);
    }
    out
}

/// Every texture info (`{"index": …}`) of a material, anywhere in it.
fn texture_infos<'a>(v: &'a Value, out: &mut Vec<&'a Value>) {
    match v {
        Value::Object(map) => {
            if map.contains_key("index") && map.get("index").is_some_and(Value::is_u64) {
                out.push(v);
            }
            for x in map.values() {
                texture_infos(x, out);
            }
        }
        Value::Array(xs) => {
            for x in xs {
                texture_infos(x, out);
            }
        }
        _ => {}
    }
}

/// Checks what a glTF file uses against what lumagraph reads: an error for a required
/// extension it does not read, warnings (with `file`, the file's name) for the rest.
///
/// # Errors
/// [`ErrorKind::GltfData`] naming the required extension, where the file requires it
/// (`extensionsRequired[i]`, with its line and column in the JSON) and what is read.
pub fn check(bytes: &[u8], file: &str) -> Result<Vec<String>, SceneError> {
    let Some(text) = json_text(bytes) else {
        return Ok(Vec::new());
    };
    let Ok(root) = serde_json::from_slice::<Value>(text) else {
        // The gltf crate reports the syntax error.
        return Ok(Vec::new());
    };
    check_required(&root, text, file)?;
    let (users, unread) = users(&root);
    let mut warnings = Vec::new();
    for (ext, who) in &users {
        let whom = if who.is_empty() {
            String::new()
        } else {
            format!(" (used by {})", some(who))
        };
        if READ.contains(&ext.as_str()) || NOTHING_TO_RENDER.contains(&ext.as_str()) {
            continue;
        }
        if let Some((_, lost)) = PARTLY_READ.iter().find(|(n, _)| n == ext) {
            warnings.push(format!("{file}: {ext} is read in part{whom}: {lost}"));
        } else if let Some((_, lost)) = NOT_READ.iter().find(|(n, _)| n == ext) {
            warnings.push(format!("{file}: {ext} is not read{whom}: {lost}"));
        } else {
            warnings.push(format!("{file}: {ext} is not read{whom}"));
        }
    }
    for (attribute, prims) in &unread {
        let lost = if attribute.starts_with("TEXCOORD_") {
            "textures that name it read TEXCOORD_0"
        } else if attribute.starts_with("COLOR_") {
            "only COLOR_0 multiplies the base colour"
        } else if attribute.starts_with("JOINTS_") || attribute.starts_with("WEIGHTS_") {
            "meshes are drawn in their bind pose (skins are not read)"
        } else if attribute == "targets" {
            "meshes are drawn without their morph targets"
        } else {
            "it is not used"
        };
        warnings.push(format!(
            "{file}: the vertex attribute {attribute} is not read ({prims} primitives): {lost}"
        ));
    }
    Ok(warnings)
}

/// Every extension the file requires and lumagraph does not read is an error.
fn check_required(root: &Value, text: &[u8], file: &str) -> Result<(), SceneError> {
    let known = |name: &str| {
        READ.contains(&name)
            || NOTHING_TO_RENDER.contains(&name)
            || PARTLY_READ.iter().any(|(n, _)| *n == name)
    };
    if let Some(required) = root.get("extensionsRequired").and_then(Value::as_array) {
        for (i, ext) in required.iter().enumerate() {
            let name = ext.as_str().unwrap_or("?");
            if !known(name) {
                let json = String::from_utf8_lossy(text);
                let quoted = format!("\"{name}\"");
                let at = json
                    .find("\"extensionsRequired\"")
                    .and_then(|k| json[k..].find(&quoted).map(|p| k + p));
                let place = at.map_or_else(String::new, |at| {
                    let (l, c) = line_col(text, at);
                    format!(" (line {l}, column {c} of its JSON)")
                });
                let why = NOT_READ
                    .iter()
                    .find(|(n, _)| *n == name)
                    .map_or_else(String::new, |(_, w)| format!(": without it {w}"));
                return Err(SceneError::new(ErrorKind::GltfData(format!(
                    "{file} requires the extension {name} (extensionsRequired[{i}]{place}), \
                     which lumagraph does not read{why}; it reads {}, and in part {}",
                    READ.join(", "),
                    PARTLY_READ
                        .iter()
                        .map(|(n, _)| *n)
                        .collect::<Vec<_>>()
                        .join(", ")
                ))));
            }
        }
    }
    Ok(())
}

/// Whether lumagraph reads a primitive's vertex attribute.
fn attribute_read(name: &str) -> bool {
    matches!(
        name,
        "POSITION" | "NORMAL" | "TANGENT" | "TEXCOORD_0" | "TEXCOORD_1" | "COLOR_0"
    ) || name.starts_with('_')
}

/// Extension → the materials, meshes or nodes that use it (every extension the file lists
/// as used, with no user where none was found), and each vertex attribute not read (and
/// `targets`, morph targets) → how many primitives have it.
fn users(root: &Value) -> (BTreeMap<String, Vec<String>>, BTreeMap<String, usize>) {
    let names = material_names(root);
    // Extension → the materials, meshes or nodes that use it.
    let mut users: BTreeMap<String, Vec<String>> = BTreeMap::new();
    let materials = root.get("materials").and_then(Value::as_array);
    for (i, m) in materials.into_iter().flatten().enumerate() {
        let who = names.get(i).cloned().unwrap_or_default();
        if let Some(exts) = m.get("extensions").and_then(Value::as_object) {
            for ext in exts.keys() {
                users.entry(ext.clone()).or_default().push(who.clone());
            }
        }
        let mut infos = Vec::new();
        texture_infos(m, &mut infos);
        for info in infos {
            if let Some(exts) = info.get("extensions").and_then(Value::as_object) {
                for ext in exts.keys() {
                    let list = users.entry(ext.clone()).or_default();
                    if !list.contains(&who) {
                        list.push(who.clone());
                    }
                }
            }
        }
    }
    let mut unread: BTreeMap<String, usize> = BTreeMap::new();
    let meshes = root.get("meshes").and_then(Value::as_array);
    for (mi, mesh) in meshes.into_iter().flatten().enumerate() {
        let prims = mesh.get("primitives").and_then(Value::as_array);
        for (pi, p) in prims.into_iter().flatten().enumerate() {
            if let Some(attributes) = p.get("attributes").and_then(Value::as_object) {
                for name in attributes.keys().filter(|n| !attribute_read(n)) {
                    *unread.entry(name.clone()).or_default() += 1;
                }
            }
            if p.get("targets").is_some() {
                *unread.entry("targets".to_owned()).or_default() += 1;
            }
            if let Some(exts) = p.get("extensions").and_then(Value::as_object) {
                for ext in exts.keys() {
                    users
                        .entry(ext.clone())
                        .or_default()
                        .push(format!("mesh {mi} primitive {pi}"));
                }
            }
        }
    }
    let nodes = root.get("nodes").and_then(Value::as_array);
    for (ni, n) in nodes.into_iter().flatten().enumerate() {
        if let Some(exts) = n.get("extensions").and_then(Value::as_object) {
            for ext in exts.keys() {
                users
                    .entry(ext.clone())
                    .or_default()
                    .push(format!("node {ni}"));
            }
        }
    }
    // Extensions declared used but found nowhere above (file-level ones, or unusual places).
    for ext in root
        .get("extensionsUsed")
        .and_then(Value::as_array)
        .into_iter()
        .flatten()
        .filter_map(Value::as_str)
    {
        users.entry(ext.to_owned()).or_default();
    }
    (users, unread)
}
