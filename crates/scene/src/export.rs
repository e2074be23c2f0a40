//! The resolved scene written out for other renderers: one JSON file with every number
//! explicit (camera, materials, analytic shapes, lights, environment, render settings), OBJ files
//! of its world-space triangles, one per material and shading (flat or with vertex
//! normals; with the base colour texture's coordinates, its transform applied, where the
//! material has one), and PNG files of the base colour textures and of the opacity the path
//! tracer uses. What is written is what the path tracer renders: glTF files loaded, version 1
//! environments converted, conductor presets resolved, autofocus applied.
//!
//! `scripts/references/` builds Mitsuba 3 scenes from it, so the references the tests
//! compare with are made from the same description as the renders.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::GpuScene;
use crate::error::{ErrorKind, SceneError};
use crate::file::Environment;
use crate::scene::{AlphaMode, MaterialTextures, NO_TEXTURE, PunctualLight, Scene};

/// Format name and version of the JSON file.
pub const FORMAT: &str = "lumagraph-scene-export";
/// Its version.
pub const FORMAT_VERSION: u32 = 1;

#[derive(Serialize)]
struct Export {
    format: &'static str,
    format_version: u32,
    camera: CameraOut,
    render: RenderOut,
    materials: Vec<MaterialOut>,
    meshes: Vec<MeshOut>,
    shapes: Vec<ShapeOut>,
    lights: Vec<LightOut>,
    environment: EnvironmentOut,
}

#[derive(Serialize)]
struct CameraOut {
    position: [f32; 3],
    target: [f32; 3],
    up: [f32; 3],
    /// Full vertical field of view, degrees.
    fov_y: f32,
    aperture_radius: f32,
    /// Along the view direction (a plane).
    focus_distance: f32,
}

#[derive(Serialize)]
struct RenderOut {
    width: u32,
    height: u32,
    max_bounces: u32,
    spp: u32,
    seed: u32,
}

#[derive(Serialize)]
struct MaterialOut {
    name: String,
    base_color: [f32; 3],
    emission: [f32; 3],
    metallic: f32,
    /// Every lobe parameter ([`crate::lobes::PARAMS`]) by its name.
    #[serde(flatten)]
    lobes: serde_json::Map<String, serde_json::Value>,
    ior: f32,
    two_sided: bool,
    eta: Option<[f32; 3]>,
    k: Option<[f32; 3]>,
    multiscatter: bool,
    /// Any texture is used.
    textured: bool,
    /// The texture slots used besides the base colour's and the emission's, by name.
    other_textures: Vec<&'static str>,
    /// The base colour texture, multiplying `base_color`: its RGB as an sRGB PNG.
    base_color_texture: Option<TextureOut>,
    /// The emission texture, multiplying `emission`, if any (not written out).
    emission_textured: bool,
    /// `"opaque"`, `"mask"` or `"blend"` (glTF's `alphaMode`).
    alpha_mode: &'static str,
    /// The opacity factor (times the base colour texture's alpha).
    opacity: f32,
    /// Below it a `mask` surface is cut out.
    alpha_cutoff: f32,
    /// Where the opacity varies over the surface (`mask` or `blend` with a base colour
    /// texture): a linear grey PNG of it, alpha × opacity, and for `mask` 0 or 255 per texel
    /// (cut out or not; the path tracer compares the filtered opacity with the cut-off).
    opacity_texture: Option<TextureOut>,
    /// The homogeneous medium inside, if any.
    medium: Option<MediumOut>,
    /// No surface (an index-matched medium boundary).
    index_matched: bool,
}

#[derive(Serialize)]
struct TextureOut {
    /// The PNG file, beside the JSON file.
    file: String,
    /// Along U and V: `"repeat"`, `"clamp"` or `"mirror"`.
    wrap: [&'static str; 2],
    /// `"bilinear"` or `"nearest"`.
    filter: &'static str,
    /// Texels across and down.
    width: u32,
    height: u32,
}

#[derive(Serialize)]
struct MediumOut {
    sigma_a: [f32; 3],
    sigma_s: [f32; 3],
    /// Henyey–Greenstein asymmetry.
    g: f32,
}

#[derive(Serialize)]
struct MeshOut {
    /// The OBJ file, beside the JSON file.
    file: String,
    material: u32,
    triangles: usize,
    /// Vertex normals are given (else the triangles are flat).
    smooth: bool,
    /// Texture coordinates are given (`vt`, OBJ's convention: V up): those the base colour
    /// texture reads, through its transform.
    uvs: bool,
    /// Some triangles have vertex colours (multiplying the base colour and the opacity),
    /// which OBJ cannot hold.
    vertex_colors: bool,
}

/// An analytic shape: its kind's Mitsuba 3 dictionary (`ShapeKind::mitsuba`) and its
/// material.
#[derive(Serialize)]
struct ShapeOut {
    kind: &'static str,
    mitsuba: serde_json::Value,
    material: u32,
}

/// A light without area: its kind (`point`, `spot`, …) and its Mitsuba 3 emitter.
#[derive(Serialize)]
struct LightOut {
    #[serde(rename = "type")]
    kind: String,
    mitsuba: serde_json::Value,
}

#[derive(Serialize)]
#[serde(tag = "type", rename_all = "lowercase")]
enum EnvironmentOut {
    None,
    Constant {
        radiance: [f32; 3],
    },
    Map {
        path: String,
        intensity: f32,
        /// Degrees, Mitsuba's orientation: `to_world = rotate(y, azimuth) · rotate(x,
        /// elevation)`.
        azimuth: f32,
        elevation: f32,
        show_background: bool,
    },
}

/// `bytes` to `path` atomically (the repository's one writer, [`lumagraph_files::write_atomic`]).
fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), SceneError> {
    lumagraph_files::write_atomic(path, bytes).map_err(|source| {
        SceneError::new(ErrorKind::Io {
            what: "export file",
            source,
        })
        .in_file(path)
    })
}

/// The texture coordinates the base colour texture of `t`'s material reads at its corners,
/// through the texture's transform, if the material has one and `t` has those coordinates.
fn base_color_uvs(scene: &Scene, t: &crate::scene::Triangle) -> Option<[glam::Vec2; 3]> {
    let m = &scene.materials[t.material as usize];
    let tex = scene.textures.get(m.textures.base_color as usize)?;
    let uvs = if tex.uv_set == 1 { t.uvs1 } else { t.uvs }?;
    Some(uvs.map(|uv| tex.transform.apply(uv)))
}

/// One OBJ file's worth of triangles: those of one material, shading and texturing.
struct MeshGroup {
    key: (u32, bool, bool),
    obj: String,
    triangles: usize,
    vertex_colors: bool,
}

/// Writes the triangles of `scene` into `dir` as OBJ files, one per material, shading and
/// texturing, in file order; returns their descriptions and paths.
fn write_meshes(
    scene: &Scene,
    triangles: &[&crate::scene::Triangle],
    dir: &Path,
) -> Result<(Vec<MeshOut>, Vec<PathBuf>), SceneError> {
    let mut groups: Vec<MeshGroup> = Vec::new();
    for t in triangles {
        let uvs = base_color_uvs(scene, t);
        let key = (t.material, t.normals.is_some(), uvs.is_some());
        let i = if let Some(i) = groups.iter().position(|g| g.key == key) {
            i
        } else {
            groups.push(MeshGroup {
                key,
                obj: String::new(),
                triangles: 0,
                vertex_colors: false,
            });
            groups.len() - 1
        };
        let g = &mut groups[i];
        g.vertex_colors |= t.colors.is_some();
        let obj = &mut g.obj;
        let base = g.triangles * 3 + 1;
        for p in t.positions {
            let _ = writeln!(obj, "v {:?} {:?} {:?}", p.x, p.y, p.z);
        }
        if let Some(uvs) = uvs {
            // OBJ's V runs up, glTF's (and the path tracer's) down.
            for uv in uvs {
                let _ = writeln!(obj, "vt {:?} {:?}", uv.x, 1.0 - uv.y);
            }
        }
        let corner = |k: usize| match (uvs.is_some(), t.normals.is_some()) {
            (false, false) => format!("{k}"),
            (true, false) => format!("{k}/{k}"),
            (false, true) => format!("{k}//{k}"),
            (true, true) => format!("{k}/{k}/{k}"),
        };
        if let Some(ns) = t.normals {
            for n in ns {
                let _ = writeln!(obj, "vn {:?} {:?} {:?}", n.x, n.y, n.z);
            }
        }
        let _ = writeln!(
            obj,
            "f {} {} {}",
            corner(base),
            corner(base + 1),
            corner(base + 2)
        );
        g.triangles += 1;
    }
    let mut meshes = Vec::new();
    let mut written = Vec::new();
    for g in groups {
        let (material, smooth, uvs) = g.key;
        let file = format!(
            "mesh_{material}{}{}.obj",
            if smooth { "_smooth" } else { "" },
            if uvs { "_uv" } else { "" }
        );
        let path = dir.join(&file);
        write_atomic(&path, g.obj.as_bytes())?;
        written.push(path);
        meshes.push(MeshOut {
            file,
            material,
            triangles: g.triangles,
            smooth,
            uvs,
            vertex_colors: g.vertex_colors,
        });
    }
    Ok((meshes, written))
}

/// `texels` (`channels` bytes each, row by row) as a PNG, atomically.
fn write_png(
    path: &Path,
    width: u32,
    height: u32,
    texels: &[u8],
    color: image::ExtendedColorType,
) -> Result<(), SceneError> {
    use image::ImageEncoder as _;
    let mut bytes = Vec::new();
    image::codecs::png::PngEncoder::new(&mut bytes)
        .write_image(texels, width, height, color)
        .map_err(|e| {
            SceneError::new(ErrorKind::BadValue {
                field: "export",
                message: format!("encoding {}: {e}", path.display()),
            })
        })?;
    write_atomic(path, &bytes)
}

fn texture_out(t: &crate::texture::Texture, file: String) -> TextureOut {
    let wrap = |w: crate::texture::Wrap| match w {
        crate::texture::Wrap::Repeat => "repeat",
        crate::texture::Wrap::ClampToEdge => "clamp",
        crate::texture::Wrap::MirroredRepeat => "mirror",
    };
    TextureOut {
        file,
        wrap: [wrap(t.wrap[0]), wrap(t.wrap[1])],
        filter: if t.nearest { "nearest" } else { "bilinear" },
        width: t.width,
        height: t.height,
    }
}

/// Writes material `i`'s base colour texture (once per texture, shared by the materials that
/// use it) and its opacity texture into `dir`, and records them in `out`.
fn write_material_textures(
    scene: &Scene,
    i: usize,
    out: &mut MaterialOut,
    dir: &Path,
    written: &mut Vec<PathBuf>,
) -> Result<(), SceneError> {
    let m = &scene.materials[i];
    let Some(t) = scene.textures.get(m.textures.base_color as usize) else {
        return Ok(());
    };
    let file = format!("texture_{}.png", m.textures.base_color);
    let path = dir.join(&file);
    if !written.contains(&path) {
        let rgb: Vec<u8> = t.texels.iter().flat_map(|p| [p[0], p[1], p[2]]).collect();
        write_png(
            &path,
            t.width,
            t.height,
            &rgb,
            image::ExtendedColorType::Rgb8,
        )?;
        written.push(path);
    }
    out.base_color_texture = Some(texture_out(t, file));
    let opacity: Vec<u8> = match m.alpha_mode {
        AlphaMode::Opaque => return Ok(()),
        // The path tracer's test, texel by texel: alpha × opacity against the cut-off.
        AlphaMode::Mask { cutoff } => t
            .texels
            .iter()
            .map(|p| {
                if f32::from(p[3]) / 255.0 * m.opacity >= cutoff {
                    255
                } else {
                    0
                }
            })
            .collect(),
        AlphaMode::Blend => t
            .texels
            .iter()
            .map(|p| (f32::from(p[3]) * m.opacity).round().clamp(0.0, 255.0) as u8)
            .collect(),
    };
    let file = format!("opacity_{i}.png");
    let path = dir.join(&file);
    write_png(
        &path,
        t.width,
        t.height,
        &opacity,
        image::ExtendedColorType::L8,
    )?;
    written.push(path);
    out.opacity_texture = Some(texture_out(t, file));
    Ok(())
}

fn material_out(m: &crate::scene::Material) -> MaterialOut {
    MaterialOut {
        name: m.name.clone(),
        base_color: m.base_color.to_array(),
        emission: m.emission.to_array(),
        metallic: m.metallic,
        lobes: crate::lobes::PARAMS
            .iter()
            .map(|p| (p.name.to_owned(), (p.export)(m)))
            .collect(),
        ior: m.ior,
        two_sided: m.two_sided,
        eta: m.conductor.map(|c| c.eta.to_array()),
        k: m.conductor.map(|c| c.k.to_array()),
        multiscatter: m.multiscatter,
        textured: m.textures.any(),
        other_textures: MaterialTextures::NAMES
            .iter()
            .zip(m.textures.all())
            .skip(1)
            .filter(|&(&name, t)| t != NO_TEXTURE && name != "emissive")
            .map(|(&name, _)| name)
            .collect(),
        base_color_texture: None,
        emission_textured: m.textures.emissive != NO_TEXTURE,
        alpha_mode: match m.alpha_mode {
            AlphaMode::Opaque => "opaque",
            AlphaMode::Mask { .. } => "mask",
            AlphaMode::Blend => "blend",
        },
        opacity: m.opacity,
        alpha_cutoff: match m.alpha_mode {
            AlphaMode::Mask { cutoff } => cutoff,
            _ => 0.5,
        },
        opacity_texture: None,
        medium: m.medium.map(|x| MediumOut {
            sigma_a: x.sigma_a.to_array(),
            sigma_s: x.sigma_s.to_array(),
            g: x.g,
        }),
        index_matched: m.index_matched,
    }
}

fn light_out(l: &PunctualLight) -> LightOut {
    let kind = crate::lights::kind_of(l).expect("a light without area has a kind");
    LightOut {
        kind: kind.name().to_lowercase(),
        mitsuba: kind.mitsuba(l),
    }
}

fn environment_out(env: &Environment) -> EnvironmentOut {
    match env {
        Environment::Constant(c) => EnvironmentOut::Constant { radiance: *c },
        Environment::Map {
            path,
            intensity,
            azimuth,
            elevation,
            show_background,
        } => EnvironmentOut::Map {
            path: path.clone(),
            intensity: *intensity,
            azimuth: *azimuth,
            elevation: *elevation,
            show_background: *show_background,
        },
        _ => EnvironmentOut::None,
    }
}

/// Writes `scene` (flattened as `gpu`, for the resolved camera) into `dir`: `scene.json`,
/// `mesh_<material>[_smooth][_uv].obj`, `texture_<texture>.png` and `opacity_<material>.png`
/// files. Returns the files written. Instanced meshes are written as copies.
///
/// # Errors
/// When `dir` cannot be created or a file cannot be written, or the copies of instanced
/// meshes would exceed [`crate::MAX_INSTANCED_TRIANGLES`].
pub fn export(scene: &Scene, gpu: &GpuScene, dir: &Path) -> Result<Vec<PathBuf>, SceneError> {
    // Instanced meshes as copies, beside the scene's own triangles (the rest of the scene,
    // its textures above all, is not copied).
    let mut copies = Vec::new();
    crate::scene::copy_instances(
        &scene.instanced,
        &mut copies,
        &mut crate::LoadReport::default(),
    )?;
    let triangles: Vec<&crate::scene::Triangle> = scene.triangles.iter().chain(&copies).collect();
    std::fs::create_dir_all(dir).map_err(|source| {
        SceneError::new(ErrorKind::Io {
            what: "export folder",
            source,
        })
        .in_file(dir)
    })?;
    let (meshes, mut written) = write_meshes(scene, &triangles, dir)?;
    let mut materials = Vec::with_capacity(scene.materials.len());
    for (i, m) in scene.materials.iter().enumerate() {
        let mut out = material_out(m);
        write_material_textures(scene, i, &mut out, dir, &mut written)?;
        materials.push(out);
    }
    let c = &scene.camera;
    let (_, up, forward) = c.basis();
    let out = Export {
        format: FORMAT,
        format_version: FORMAT_VERSION,
        camera: CameraOut {
            position: c.position.to_array(),
            target: (c.position + forward).to_array(),
            up: up.to_array(),
            fov_y: c.fov_y_deg,
            aperture_radius: c.aperture_radius,
            focus_distance: gpu.camera.focus_distance,
        },
        render: RenderOut {
            width: scene.settings.width,
            height: scene.settings.height,
            max_bounces: scene.settings.max_bounces,
            spp: scene.settings.spp,
            seed: scene.settings.seed,
        },
        materials,
        meshes,
        shapes: scene
            .shapes
            .iter()
            .map(|s| ShapeOut {
                kind: s.kind().name(),
                mitsuba: s.kind().mitsuba(&s.record()),
                material: s.material,
            })
            .collect(),
        lights: scene.lights.iter().map(light_out).collect(),
        environment: environment_out(&scene.environment),
    };
    let json = serde_json::to_string_pretty(&out).map_err(|e| {
        SceneError::new(ErrorKind::BadValue {
            field: "export",
            message: e.to_string(),
        })
    })?;
    let path = dir.join("scene.json");
    write_atomic(&path, (json + "\n").as_bytes())?;
    written.push(path);
    Ok(written)
}
