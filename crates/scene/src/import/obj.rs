//! OBJ + MTL import ([`tobj`]): polygons triangulated, `Kd` → base color, `Ke` →
//! emission, `Ks` black or absent → specular 0 (else 0.5), `Ni` → IOR, roughness 1 (or
//! `Pr`), metallic 0 (or `Pm`), `d` (or 1 − `Tr`) below 1 → alpha blending. Textures:
//! `map_Kd` → base colour (sRGB), `map_d` → its alpha (blended: the plants and chains of
//! OBJ scenes are cut out by it), `map_Ke` → emission, `norm` → tangent-space normal map,
//! and `map_Bump`/`bump` as a normal map where its texels are coloured (a grey height map is
//! not read, and said so). Other maps are named in a warning. Texture coordinates are kept
//! when every corner has them (OBJ's `v` runs up, glTF's down: `v` is flipped). Vertex
//! normals are kept when every corner has one.

use std::cell::RefCell;
use std::path::Path;

use glam::{Mat4, Vec3};

use super::ImportedMesh;
use crate::error::{ErrorKind, SceneError};
use crate::scene::{AlphaMode, Material, NO_TEXTURE, Triangle, push_triangle, transform_triangle};
use crate::texture::{Texture, UvTransform, Wrap};

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
    let text = std::fs::read(path)
        .map_err(|_| tobj::LoadError::OpenFileFailed)
        .map_err(ErrorKind::from)?;
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
    })
    .map_err(ErrorKind::from)?;
    let mut out = ImportedMesh::default();
    match materials {
        Ok(mats) => {
            let start = std::time::Instant::now();
            let mut textures = Textures::new(base);
            out.materials = mats
                .iter()
                .map(|m| material(m, &mut textures, &mut out.report.warnings))
                .collect::<Result<_, _>>()?;
            out.decode.images = textures.loaded.len();
            // Masks merged into a base colour texture are not used on their own.
            compact(&mut textures.textures, &mut out.materials);
            out.decode.bytes = textures
                .textures
                .iter()
                .map(|t| 4 * t.texels.len() as u64)
                .sum();
            out.decode.threads = 1;
            out.decode.time = start.elapsed();
            out.textures = textures.textures;
        }
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
        let has_uvs = mesh.texcoords.len() / 2 == mesh.positions.len() / 3;
        let uv = |i: u32| {
            let i = i as usize * 2;
            mesh.texcoords
                .get(i..i + 2)
                .map(|t| glam::Vec2::new(t[0], 1.0 - t[1]))
        };
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
            let uvs = match [t[0], t[1], t[2]].map(uv) {
                [Some(a), Some(b), Some(c)] if has_uvs => Some([a, b, c]),
                _ => None,
            };
            let tri = Triangle {
                positions: [p0, p1, p2],
                normals,
                uvs,
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
    // The elements of each kind, in one pass over the lines.
    let mut totals = [0usize; 3];
    for line in text.lines() {
        if let Some(k) = line
            .split_whitespace()
            .next()
            .and_then(|key| KEYS.iter().position(|&x| x == key))
        {
            totals[k] += 1;
        }
    }
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

/// The textures an MTL file's materials use, each image decoded once.
struct Textures<'a> {
    /// The folder texture paths are relative to.
    base: &'a Path,
    textures: Vec<Texture>,
    /// File → index.
    loaded: std::collections::HashMap<String, u32>,
    /// (base colour texture or none, alpha texture) → the texture that merges them.
    merged: std::collections::HashMap<(u32, u32), u32>,
}

impl<'a> Textures<'a> {
    fn new(base: &'a Path) -> Self {
        Self {
            base,
            textures: Vec::new(),
            loaded: std::collections::HashMap::new(),
            merged: std::collections::HashMap::new(),
        }
    }

    /// A texture with `base`'s colour (white where `base` is [`NO_TEXTURE`]) and `alpha`'s
    /// opacity: its alpha channel where it has one below 255, else its red channel (a grey
    /// mask). `alpha` is read at `base`'s size, nearest texel.
    fn with_alpha(&mut self, base: u32, alpha: u32) -> u32 {
        if let Some(&i) = self.merged.get(&(base, alpha)) {
            return i;
        }
        let a = &self.textures[alpha as usize];
        let has_alpha = a.texels.iter().any(|p| p[3] < 255);
        let opacity = |x: u32, y: u32, w: u32, h: u32| {
            let ax = (u64::from(x) * u64::from(a.width) / u64::from(w)) as usize;
            let ay = (u64::from(y) * u64::from(a.height) / u64::from(h)) as usize;
            let p = a.texels[ay * a.width as usize + ax];
            if has_alpha { p[3] } else { p[0] }
        };
        let (name, width, height, texels): (String, u32, u32, Vec<[u8; 4]>) = if base == NO_TEXTURE
        {
            let (w, h) = (a.width, a.height);
            let texels = (0..h)
                .flat_map(|y| (0..w).map(move |x| (x, y)))
                .map(|(x, y)| [255, 255, 255, opacity(x, y, w, h)])
                .collect();
            (format!("white with alpha from {}", a.name), w, h, texels)
        } else {
            let b = &self.textures[base as usize];
            let (w, h) = (b.width, b.height);
            let texels = (0..h)
                .flat_map(|y| (0..w).map(move |x| (x, y)))
                .map(|(x, y)| {
                    let c = b.texels[y as usize * w as usize + x as usize];
                    [c[0], c[1], c[2], opacity(x, y, w, h)]
                })
                .collect();
            (
                format!("{} with alpha from {}", b.name, a.name),
                w,
                h,
                texels,
            )
        };
        let index = self.push(name, width, height, texels);
        self.merged.insert((base, alpha), index);
        index
    }

    /// Adds a texture of `texels` (row by row from the top), repeating, bilinear, read
    /// through the first texture coordinates; returns its index.
    fn push(&mut self, name: String, width: u32, height: u32, texels: Vec<[u8; 4]>) -> u32 {
        let index = u32::try_from(self.textures.len()).unwrap_or(u32::MAX);
        self.textures.push(Texture {
            name,
            width,
            height,
            texels: texels.into(),
            wrap: [Wrap::Repeat; 2],
            nearest: false,
            uv_set: 0,
            transform: UvTransform::IDENTITY,
        });
        index
    }

    /// The texture of an MTL map statement's argument (options such as `-bm 1` first, the
    /// file last), decoded; the error names the material and the file.
    fn get(&mut self, material: &str, statement: &str, arg: &str) -> Result<u32, SceneError> {
        let file = arg.split_whitespace().last().unwrap_or(arg).to_owned();
        if let Some(&i) = self.loaded.get(&file) {
            return Ok(i);
        }
        let path = self.base.join(&file);
        let fail = |message: String| {
            SceneError::new(ErrorKind::Texture(format!(
                "material \"{material}\": {statement} \"{file}\": {message}"
            )))
        };
        if std::fs::metadata(&path).is_ok_and(|m| !m.is_file()) {
            return Err(fail("not a file".to_owned()));
        }
        let image = image::ImageReader::open(&path)
            .map_err(|e| fail(format!("cannot read it: {e}")))?
            .with_guessed_format()
            .map_err(|e| fail(format!("cannot read it: {e}")))?
            .decode()
            .map_err(|e| fail(format!("cannot decode it: {e}")))?
            .into_rgba8();
        let (width, height) = image.dimensions();
        if width == 0 || height == 0 {
            return Err(fail("the image is empty".to_owned()));
        }
        let texels: Vec<[u8; 4]> = image.pixels().map(|p| p.0).collect();
        let index = self.push(file.clone(), width, height, texels);
        self.loaded.insert(file, index);
        Ok(index)
    }
}

/// Drops the textures no material uses, renumbering the materials' slots.
fn compact(textures: &mut Vec<Texture>, materials: &mut [Material]) {
    let mut used = vec![false; textures.len()];
    for m in materials.iter() {
        for t in m.textures.all() {
            if let Some(u) = used.get_mut(t as usize) {
                *u = true;
            }
        }
    }
    let mut new_index = vec![NO_TEXTURE; textures.len()];
    let mut next = 0u32;
    for (i, &u) in used.iter().enumerate() {
        if u {
            new_index[i] = next;
            next += 1;
        }
    }
    let mut i = 0;
    textures.retain(|_| {
        i += 1;
        used[i - 1]
    });
    for m in materials.iter_mut() {
        for t in m.textures.all_mut() {
            if let Some(&n) = new_index.get(*t as usize) {
                *t = n;
            }
        }
    }
}

/// Whether every texel of `t` is grey (R = G = B): a height map rather than a normal map.
fn grey(t: &Texture) -> bool {
    t.texels.iter().all(|p| p[0] == p[1] && p[1] == p[2])
}

fn material(
    m: &tobj::Material,
    textures: &mut Textures<'_>,
    warnings: &mut Vec<String>,
) -> Result<Material, SceneError> {
    let specular = match m.specular {
        Some(ks) if ks.iter().any(|&c| c > 0.0) => 0.5,
        _ => 0.0,
    };
    let param = |key: &str| m.unknown_param.get(key).map(String::as_str);
    let number = |key: &str| param(key).and_then(|v| v.trim().parse::<f32>().ok());
    let opacity = m
        .dissolve
        .or_else(|| number("Tr").map(|tr| 1.0 - tr))
        .unwrap_or(1.0)
        .clamp(0.0, 1.0);
    let mut out = Material {
        base_color: m.diffuse.map_or(Vec3::splat(0.8), Vec3::from),
        emission: m.emissive.map_or(Vec3::ZERO, Vec3::from),
        roughness: number("Pr").map_or(1.0, |r| r.clamp(0.0, 1.0)),
        metallic: number("Pm").map_or(0.0, |x| x.clamp(0.0, 1.0)),
        specular,
        ior: m.optical_density.unwrap_or(1.5),
        opacity,
        alpha_mode: if opacity < 1.0 {
            AlphaMode::Blend
        } else {
            AlphaMode::Opaque
        },
        ..Material::named(m.name.clone())
    };
    let name = &m.name;
    if let Some(t) = &m.diffuse_texture {
        out.textures.base_color = textures.get(name, "map_Kd", t)?;
    }
    if let Some(t) = &m.dissolve_texture {
        let alpha = textures.get(name, "map_d", t)?;
        out.textures.base_color = textures.with_alpha(out.textures.base_color, alpha);
        out.alpha_mode = AlphaMode::Blend;
    }
    if let Some(t) = param("map_Ke") {
        out.textures.emissive = textures.get(name, "map_Ke", t)?;
        if out.emission == Vec3::ZERO {
            // The map is the emission (an MTL without `Ke` means it in full).
            out.emission = Vec3::ONE;
        }
    }
    if let Some(t) = param("norm") {
        out.textures.normal = textures.get(name, "norm", t)?;
    } else if let Some(t) = &m.normal_texture {
        let i = textures.get(name, "map_Bump", t)?;
        if grey(&textures.textures[i as usize]) {
            warnings.push(format!(
                "material \"{name}\": bump map \"{t}\" not read: it is a grey height map, and \
                 only normal maps are (`norm`)"
            ));
        } else {
            out.textures.normal = i;
        }
    }
    let unread: Vec<&str> = [
        ("map_Ka", m.ambient_texture.is_some()),
        ("map_Ks", m.specular_texture.is_some()),
        ("map_Ns", m.shininess_texture.is_some()),
        ("map_Pr", param("map_Pr").is_some()),
        ("map_Pm", param("map_Pm").is_some()),
        ("disp", param("disp").is_some()),
        ("refl", param("refl").is_some()),
    ]
    .into_iter()
    .filter(|(_, set)| *set)
    .map(|(key, _)| key)
    .collect();
    if !unread.is_empty() {
        warnings.push(format!(
            "material \"{name}\": {} not read",
            unread.join(", ")
        ));
    }
    Ok(out)
}
