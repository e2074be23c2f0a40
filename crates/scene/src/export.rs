//! The resolved scene written out for other renderers: one JSON file with every number
//! explicit (camera, materials, spheres, lights, environment, render settings) and OBJ files
//! of its world-space triangles, one per material and shading (flat or with vertex
//! normals). What is written is what the path tracer renders: glTF files loaded, version 1
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
use crate::scene::{PunctualLight, Scene};

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
    spheres: Vec<SphereOut>,
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
    roughness: f32,
    diffuse_roughness: f32,
    metallic: f32,
    specular: f32,
    specular_tint: f32,
    /// Colour of the dielectric specular at normal incidence (white: none).
    specular_color: [f32; 3],
    transmission: f32,
    /// Clear coat weight and roughness (0: none).
    clearcoat: f32,
    clearcoat_roughness: f32,
    /// Sheen colour (black: none) and roughness.
    sheen_color: [f32; 3],
    sheen_roughness: f32,
    ior: f32,
    two_sided: bool,
    eta: Option<[f32; 3]>,
    k: Option<[f32; 3]>,
    multiscatter: bool,
    textured: bool,
    /// The homogeneous medium inside, if any.
    medium: Option<MediumOut>,
    /// No surface (an index-matched medium boundary).
    index_matched: bool,
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
}

#[derive(Serialize)]
struct SphereOut {
    center: [f32; 3],
    radius: f32,
    material: u32,
}

#[derive(Serialize)]
#[serde(tag = "type", rename_all = "lowercase")]
enum LightOut {
    Point {
        position: [f32; 3],
        intensity: [f32; 3],
    },
    Spot {
        position: [f32; 3],
        /// A point on the axis, one unit from the light.
        target: [f32; 3],
        intensity: [f32; 3],
        cutoff_angle: f32,
        beam_width: f32,
    },
    Directional {
        direction: [f32; 3],
        irradiance: [f32; 3],
    },
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

/// `text` to `path` atomically (the repository's one writer, [`lumagraph_graph::write_atomic`]).
fn write_atomic(path: &Path, text: &str) -> Result<(), SceneError> {
    lumagraph_graph::write_atomic(path, text.as_bytes()).map_err(|source| {
        SceneError::new(ErrorKind::Io {
            what: "export file",
            source,
        })
        .in_file(path)
    })
}

/// Writes the triangles of `scene` into `dir` as OBJ files, one per material and shading,
/// in file order; returns their descriptions and paths.
fn write_meshes(scene: &Scene, dir: &Path) -> Result<(Vec<MeshOut>, Vec<PathBuf>), SceneError> {
    let mut groups: Vec<((u32, bool), String, usize)> = Vec::new();
    for t in &scene.triangles {
        let key = (t.material, t.normals.is_some());
        let i = if let Some(i) = groups.iter().position(|g| g.0 == key) {
            i
        } else {
            groups.push((key, String::new(), 0));
            groups.len() - 1
        };
        let (_, obj, count) = &mut groups[i];
        let base = *count * 3 + 1;
        for p in t.positions {
            let _ = writeln!(obj, "v {:?} {:?} {:?}", p.x, p.y, p.z);
        }
        if let Some(ns) = t.normals {
            for n in ns {
                let _ = writeln!(obj, "vn {:?} {:?} {:?}", n.x, n.y, n.z);
            }
            let _ = writeln!(
                obj,
                "f {0}//{0} {1}//{1} {2}//{2}",
                base,
                base + 1,
                base + 2
            );
        } else {
            let _ = writeln!(obj, "f {} {} {}", base, base + 1, base + 2);
        }
        *count += 1;
    }
    let mut meshes = Vec::new();
    let mut written = Vec::new();
    for ((material, smooth), obj, triangles) in groups {
        let file = format!("mesh_{material}{}.obj", if smooth { "_smooth" } else { "" });
        let path = dir.join(&file);
        write_atomic(&path, &obj)?;
        written.push(path);
        meshes.push(MeshOut {
            file,
            material,
            triangles,
            smooth,
        });
    }
    Ok((meshes, written))
}

fn material_out(m: &crate::scene::Material) -> MaterialOut {
    MaterialOut {
        name: m.name.clone(),
        base_color: m.base_color.to_array(),
        emission: m.emission.to_array(),
        roughness: m.roughness,
        diffuse_roughness: m.diffuse_roughness,
        metallic: m.metallic,
        specular: m.specular,
        specular_tint: m.specular_tint,
        specular_color: m.specular_color.to_array(),
        transmission: m.transmission,
        clearcoat: m.clearcoat,
        clearcoat_roughness: m.clearcoat_roughness,
        sheen_color: m.sheen_color.to_array(),
        sheen_roughness: m.sheen_roughness,
        ior: m.ior,
        two_sided: m.two_sided,
        eta: m.conductor.map(|c| c.eta.to_array()),
        k: m.conductor.map(|c| c.k.to_array()),
        multiscatter: m.multiscatter,
        textured: m.textures.any(),
        medium: m.medium.map(|x| MediumOut {
            sigma_a: x.sigma_a.to_array(),
            sigma_s: x.sigma_s.to_array(),
            g: x.g,
        }),
        index_matched: m.index_matched,
    }
}

fn light_out(l: &PunctualLight) -> LightOut {
    match *l {
        PunctualLight::Point {
            position,
            intensity,
        } => LightOut::Point {
            position: position.to_array(),
            intensity: intensity.to_array(),
        },
        PunctualLight::Spot {
            position,
            axis,
            intensity,
            cutoff,
            beam,
        } => LightOut::Spot {
            position: position.to_array(),
            target: (position + axis).to_array(),
            intensity: intensity.to_array(),
            cutoff_angle: cutoff.to_degrees(),
            beam_width: beam.to_degrees(),
        },
        PunctualLight::Directional {
            direction,
            irradiance,
        } => LightOut::Directional {
            direction: direction.to_array(),
            irradiance: irradiance.to_array(),
        },
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

/// Writes `scene` (flattened as `gpu`, for the resolved camera) into `dir`: `scene.json` and
/// `mesh_<material>[_smooth].obj` files. Returns the files written.
///
/// # Errors
/// When `dir` cannot be created or a file cannot be written.
pub fn export(scene: &Scene, gpu: &GpuScene, dir: &Path) -> Result<Vec<PathBuf>, SceneError> {
    std::fs::create_dir_all(dir).map_err(|source| {
        SceneError::new(ErrorKind::Io {
            what: "export folder",
            source,
        })
        .in_file(dir)
    })?;
    let (meshes, mut written) = write_meshes(scene, dir)?;
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
        materials: scene.materials.iter().map(material_out).collect(),
        meshes,
        spheres: scene
            .spheres
            .iter()
            .map(|s| SphereOut {
                center: s.center.to_array(),
                radius: s.radius,
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
    write_atomic(&path, &(json + "\n"))?;
    written.push(path);
    Ok(written)
}
