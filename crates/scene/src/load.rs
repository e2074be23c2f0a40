//! Loading a RON scene file into a [`Scene`]: syntax errors come from ron with their line
//! and column; semantic errors (unknown material, bad radius…) name the shape or material
//! and point at it in the file.

use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};

use glam::{Mat4, Quat, Vec3};
use ron::extensions::Extensions;
use serde::Deserialize;

use crate::conductor::Conductor;
use crate::error::{ErrorKind, Pos, SceneError};
use crate::file::{
    CameraDesc, Environment, LightDesc, MaterialDesc, SceneFile, ShapeDesc, TransformDesc, V3,
    VERSION,
};
use crate::import::import_mesh_with;
use crate::scene::{
    Camera, LoadReport, Material, Medium, PunctualLight, Scene, Shape, cube_quads, push_triangle,
    quad_triangles, rectangle_quad, transform_triangle,
};

#[derive(Deserialize)]
struct VersionProbe {
    version: u32,
}

/// Finds things in the file text, to point semantic errors at a line and column.
struct Locator<'a> {
    text: &'a str,
    /// Byte offset where each shape starts, in file order.
    shape_starts: Vec<usize>,
}

impl<'a> Locator<'a> {
    fn new(text: &'a str) -> Self {
        let kinds = ShapeDesc::KINDS;
        let start = text.find("shapes").unwrap_or(0);
        let end = text[start..]
            .find("lights:")
            .map_or(text.len(), |o| start + o);
        let mut shape_starts = Vec::new();
        let bytes = text.as_bytes();
        let mut i = start;
        while i < end {
            let rest = &text[i..];
            let before_ok =
                i == 0 || !(bytes[i - 1].is_ascii_alphanumeric() || bytes[i - 1] == b'_');
            if before_ok
                && let Some(k) = kinds.iter().find(|k| {
                    rest.starts_with(**k) && rest[k.len()..].trim_start().starts_with('(')
                })
            {
                shape_starts.push(i);
                i += k.len();
                continue;
            }
            i += rest.chars().next().map_or(1, char::len_utf8);
        }
        Self { text, shape_starts }
    }

    fn pos(&self, offset: usize) -> Pos {
        let before = &self.text[..offset.min(self.text.len())];
        let line = before.matches('\n').count() + 1;
        let col = before[before.rfind('\n').map_or(0, |nl| nl + 1)..]
            .chars()
            .count()
            + 1;
        Pos { line, col }
    }

    /// Where `needle` first appears in shape `index`, or where the shape starts.
    fn in_shape(&self, index: usize, needle: &str) -> Option<Pos> {
        let start = *self.shape_starts.get(index)?;
        let end = self
            .shape_starts
            .get(index + 1)
            .copied()
            .unwrap_or(self.text.len());
        let found = self.text[start..end]
            .find(needle)
            .map_or(start, |o| start + o);
        Some(self.pos(found))
    }

    /// Where material `name` is defined, then `field` inside it when given.
    fn in_material(&self, name: &str, field: Option<&str>) -> Option<Pos> {
        let m = self.text.find("materials")?;
        let start = m + self.text[m..].find(&format!("\"{name}\""))?;
        let off = field
            .and_then(|f| self.text[start..].find(f))
            .map_or(start, |o| start + o);
        Some(self.pos(off))
    }

    fn find(&self, needle: &str) -> Option<Pos> {
        self.text.find(needle).map(|o| self.pos(o))
    }

    /// Where `needle` first appears in light `index` of the `lights` list (lights are
    /// found by their kind's name followed by `(`), or where that light starts.
    fn in_light(&self, index: usize, needle: &str) -> Option<Pos> {
        let list = self.text.find("lights:")?;
        let kinds: Vec<&str> = crate::lights::KINDS.iter().map(|k| k.name()).collect();
        let mut starts = Vec::new();
        let mut i = list;
        while i < self.text.len() {
            let rest = &self.text[i..];
            if let Some(k) = kinds
                .iter()
                .find(|k| rest.starts_with(**k) && rest[k.len()..].trim_start().starts_with('('))
            {
                starts.push(i);
                i += k.len();
                continue;
            }
            i += rest.chars().next().map_or(1, char::len_utf8);
        }
        let start = *starts.get(index)?;
        let end = starts.get(index + 1).copied().unwrap_or(self.text.len());
        let found = self.text[start..end]
            .find(needle)
            .map_or(start, |o| start + o);
        Some(self.pos(found))
    }
}

fn bad(field: &'static str, message: impl Into<String>) -> SceneError {
    SceneError::new(ErrorKind::BadValue {
        field,
        message: message.into(),
    })
}

fn finite3(field: &'static str, v: V3) -> Result<Vec3, SceneError> {
    let v = Vec3::from(v);
    if v.is_finite() {
        Ok(v)
    } else {
        Err(bad(field, format!("{v} is not finite")))
    }
}

pub(crate) fn non_negative3(field: &'static str, v: V3) -> Result<Vec3, SceneError> {
    let v = finite3(field, v)?;
    if v.min_element() >= 0.0 {
        Ok(v)
    } else {
        Err(bad(field, format!("{v} has a negative component")))
    }
}

pub(crate) fn unit_range(field: &'static str, x: f32) -> Result<f32, SceneError> {
    if (0.0..=1.0).contains(&x) {
        Ok(x)
    } else {
        Err(bad(field, format!("{x} is outside [0, 1]")))
    }
}

/// The matrix of a transform description.
///
/// # Errors
/// When `matrix` is given with other fields, a rotation axis is zero, or the result is
/// singular or not finite.
pub fn transform_matrix(t: &TransformDesc) -> Result<Mat4, SceneError> {
    let m = if let Some(rows) = &t.matrix {
        if t.translate.is_some() || t.scale.is_some() || !t.rotate.is_empty() {
            return Err(bad(
                "transform",
                "give either `matrix` or translate/rotate/scale, not both",
            ));
        }
        if rows.len() != 4 || rows.iter().any(|r| r.len() != 4) {
            return Err(bad("matrix", "give 4 rows of 4 numbers"));
        }
        let mut a = [[0.0; 4]; 4];
        for (dst, src) in a.iter_mut().zip(rows) {
            dst.copy_from_slice(src);
        }
        Mat4::from_cols_array_2d(&a).transpose()
    } else {
        let mut m = Mat4::from_scale(t.scale.map_or(Vec3::ONE, Vec3::from));
        for r in &t.rotate {
            let axis = Vec3::from(r.axis);
            if axis.length_squared() == 0.0 || !axis.is_finite() || !r.degrees.is_finite() {
                return Err(bad(
                    "rotate",
                    format!("bad axis {axis} or angle {}", r.degrees),
                ));
            }
            m = Mat4::from_quat(Quat::from_axis_angle(
                axis.normalize(),
                r.degrees.to_radians(),
            )) * m;
        }
        Mat4::from_translation(t.translate.map_or(Vec3::ZERO, Vec3::from)) * m
    };
    let det = m.determinant();
    if !m.is_finite() || det == 0.0 || !det.is_finite() {
        return Err(bad("transform", "the matrix is singular or not finite"));
    }
    Ok(m)
}

/// A `Mesh`'s `instances`: everything the file holds becomes instances placed at each of
/// `places` (after the file's own transform and node hierarchy): its flat triangles one
/// instanced mesh, its own instanced meshes (a glTF mesh used by several nodes) placed at
/// every combination.
fn place_instances(mesh: &mut crate::import::ImportedMesh, places: &[Mat4], name: &str) {
    for m in &mut mesh.instanced {
        m.transforms = places
            .iter()
            .flat_map(|p| m.transforms.iter().map(move |t| *p * *t))
            .collect();
    }
    if !mesh.triangles.is_empty() {
        mesh.instanced.push(crate::scene::InstancedMesh {
            name: name.to_owned(),
            triangles: std::mem::take(&mut mesh.triangles),
            transforms: places.to_vec(),
        });
    }
}

/// A `Mesh`'s `diffuse: true`: every material of the file as [`Material::as_diffuse`], and
/// the textures none of them reads any more left out (they were decoded with the file, but
/// take no place in the atlas).
fn reduce_to_diffuse(mesh: &mut crate::import::ImportedMesh) {
    for m in &mut mesh.materials {
        *m = m.as_diffuse();
    }
    let textures = std::mem::take(&mut mesh.textures);
    mesh.textures = crate::scene::keep_read_textures(&mut mesh.materials, textures);
}

/// The conductor a material description names or gives, if any.
fn conductor_from_desc(d: &MaterialDesc) -> Result<Option<Conductor>, SceneError> {
    match (&d.conductor, d.eta, d.k) {
        (None, None, None) => Ok(None),
        (Some(name), None, None) => crate::conductor::preset(name).map(Some).ok_or_else(|| {
            let known: Vec<&str> = crate::conductor::PRESETS.iter().map(|p| p.0).collect();
            bad(
                "conductor",
                format!("no conductor \"{name}\" (known: {})", known.join(", ")),
            )
        }),
        (Some(_), _, _) => Err(bad(
            "conductor",
            "give either a named `conductor` or `eta` and `k`, not both",
        )),
        (None, Some(eta), Some(k)) => {
            let eta = finite3("eta", eta)?;
            let k = non_negative3("k", k)?;
            if eta.min_element() <= 0.0 {
                return Err(bad("eta", format!("{eta} must be positive")));
            }
            Ok(Some(Conductor::new(eta, k)))
        }
        (None, Some(_), None) => Err(bad("eta", "`eta` needs `k` (the extinction coefficient)")),
        (None, None, Some(_)) => Err(bad("k", "`k` needs `eta` (the real part of the index)")),
    }
}

/// The medium inside a material's shapes: `medium`, or the absorption of
/// `attenuation_color` and `attenuation_distance`.
fn medium_from_desc(d: &MaterialDesc) -> Result<Option<Medium>, SceneError> {
    let attenuation = d.attenuation_color.is_some() || d.attenuation_distance.is_some();
    if let Some(m) = d.medium {
        if attenuation {
            return Err(bad(
                "medium",
                "give either a `medium` or `attenuation_color` and `attenuation_distance`, not both",
            ));
        }
        let sigma_a = non_negative3("sigma_a", m.sigma_a)?;
        let sigma_s = non_negative3("sigma_s", m.sigma_s)?;
        if !(m.g > -1.0 && m.g < 1.0) {
            return Err(bad("g", format!("{} is outside (-1, 1)", m.g)));
        }
        if (sigma_a + sigma_s).max_element() <= 0.0 {
            return Ok(None);
        }
        return Ok(Some(Medium {
            sigma_a,
            sigma_s,
            g: m.g,
        }));
    }
    if !attenuation {
        return Ok(None);
    }
    let color = d.attenuation_color.unwrap_or([1.0; 3]);
    let color = non_negative3("attenuation_color", color)?;
    if color.max_element() > 1.0 {
        return Err(bad(
            "attenuation_color",
            format!("{color} has a component above 1"),
        ));
    }
    let distance = d.attenuation_distance.unwrap_or(f32::INFINITY);
    if distance.is_nan() || distance <= 0.0 {
        return Err(bad(
            "attenuation_distance",
            format!("{distance} must be positive"),
        ));
    }
    Ok(Medium::attenuation(color, distance))
}

fn material_from_desc(name: &str, d: &MaterialDesc) -> Result<Material, SceneError> {
    let ior = d.ior;
    if !(ior > 0.0 && ior.is_finite()) {
        return Err(bad("ior", format!("{ior} must be a positive number")));
    }
    let conductor = conductor_from_desc(d)?;
    let metallic = d
        .metallic
        .unwrap_or(if conductor.is_some() { 1.0 } else { 0.0 });
    if conductor.is_some() && metallic == 0.0 {
        return Err(bad(
            "metallic",
            "a conductor needs `metallic` > 0 (it is the metal lobe's Fresnel)",
        ));
    }
    // A conductor's colour is its reflectance at normal incidence (albedo outputs and the
    // denoiser read it); `base_color` is not used by its Fresnel.
    let base_color = match conductor {
        Some(c) => c.normal_reflectance(),
        None => non_negative3("base_color", d.base_color)?,
    };
    let medium = medium_from_desc(d)?;
    if d.index_matched && medium.is_none() {
        return Err(bad(
            "index_matched",
            "an index-matched boundary needs a `medium` inside (without one the shape is invisible)",
        ));
    }
    if d.index_matched && d.emission.iter().any(|&x| x != 0.0) {
        return Err(bad(
            "emission",
            "an index-matched boundary has no surface to emit",
        ));
    }
    let mut m = Material {
        name: name.to_owned(),
        base_color,
        emission: non_negative3("emission", d.emission)?,
        metallic: unit_range("metallic", metallic)?,
        ior,
        two_sided: d.two_sided,
        conductor,
        multiscatter: d.multiscatter,
        medium,
        index_matched: d.index_matched,
        opacity: unit_range("opacity", d.opacity)?,
        alpha_mode: match d.alpha_mode {
            crate::file::AlphaModeDesc::Opaque => crate::scene::AlphaMode::Opaque,
            crate::file::AlphaModeDesc::Mask => crate::scene::AlphaMode::Mask {
                cutoff: unit_range("alpha_cutoff", d.alpha_cutoff)?,
            },
            crate::file::AlphaModeDesc::Blend => crate::scene::AlphaMode::Blend,
        },
        ..Material::named(name)
    };
    for p in crate::lobes::PARAMS {
        (p.load)(d, &mut m)?;
    }
    Ok(m)
}

fn light_from_desc(d: &LightDesc) -> Result<PunctualLight, SceneError> {
    crate::lights::KINDS[d.kind as usize].load(&d.fields)
}

/// A version 1 environment map in version 2's (Mitsuba's) orientation, lighting the scene
/// the same: version 1 saw the map's centre column along −z, i.e. turned by 180° about y
/// from Mitsuba's, and rotated by the opposite angles.
fn environment_from_v1(env: Environment) -> Environment {
    match env {
        Environment::Map {
            path,
            intensity,
            azimuth,
            elevation,
            show_background,
        } => Environment::Map {
            path,
            intensity,
            azimuth: -(azimuth + 180.0),
            elevation: -elevation,
            show_background,
        },
        other => other,
    }
}

impl Scene {
    /// Loads a scene file and the mesh files it references.
    ///
    /// # Errors
    /// When a file cannot be read or is invalid; the error names the file, the line and
    /// column when known, and the shape or material concerned.
    pub fn load(path: &Path) -> Result<Self, SceneError> {
        crate::edit::SceneText::load(path)?.build()
    }

    /// Parses a scene from RON text; mesh paths are relative to `base_dir`.
    ///
    /// # Errors
    /// As [`Scene::load`], without the file name for errors in the text itself.
    pub fn from_ron(text: &str, base_dir: &Path) -> Result<Self, SceneError> {
        let file = SceneFile::from_ron(text)?;
        Self::build(&file, text, base_dir)
    }

    /// Builds a scene from a parsed (and perhaps edited) file; mesh paths are relative to
    /// `base_dir`. Errors have no line and column (there is no text to point into).
    ///
    /// # Errors
    /// As [`Scene::load`].
    pub fn from_file(file: &SceneFile, base_dir: &Path) -> Result<Self, SceneError> {
        Self::build(file, "", base_dir)
    }

    /// The camera `file` describes, as [`Scene::from_file`] would build it: a perspective
    /// camera without loading anything, a glTF file's camera by loading the scene.
    ///
    /// # Errors
    /// As [`Scene::from_file`] for the camera (a bad field, a camera the file lacks).
    pub fn camera_of(file: &SceneFile, base_dir: &Path) -> Result<Camera, SceneError> {
        match &file.camera {
            CameraDesc::Perspective { .. } => Builder::new("", base_dir)
                .camera(&file.camera)
                .map_err(|e| e.about("camera")),
            _ => Ok(Self::from_file(file, base_dir)?.camera),
        }
    }

    fn build(file: &SceneFile, text: &str, base_dir: &Path) -> Result<Self, SceneError> {
        let started = std::time::Instant::now();
        let mut scene = if file.version == 1 {
            let mut file = file.clone();
            file.environment = environment_from_v1(file.environment);
            Builder::new(text, base_dir).build(&file)?
        } else {
            Builder::new(text, base_dir).build(file)?
        };
        scene.apply_instancing(file.instancing)?;
        scene.stats.total = started.elapsed();
        Ok(scene)
    }
}

impl SceneFile {
    /// Parses a scene file's text as written (a version 1 file keeps its version 1
    /// environment angles; [`Scene::from_file`] converts them).
    ///
    /// # Errors
    /// Syntax errors and unknown versions, with line and column.
    pub fn from_ron(text: &str) -> Result<Self, SceneError> {
        let syntax = |e: ron::error::SpannedError| {
            SceneError::new(ErrorKind::Syntax(e.code.to_string())).at(Some(Pos {
                line: e.span.start.line,
                col: e.span.start.col,
            }))
        };
        let options = ron::Options::default().with_default_extension(Extensions::IMPLICIT_SOME);
        let probe: VersionProbe = options.from_str(text).map_err(syntax)?;
        if !(1..=VERSION).contains(&probe.version) {
            let loc = Locator::new(text);
            return Err(SceneError::new(ErrorKind::Version {
                found: probe.version,
                supported: VERSION,
            })
            .at(loc.find("version")));
        }
        options.from_str(text).map_err(syntax)
    }
}

struct Builder<'a> {
    loc: Locator<'a>,
    base_dir: PathBuf,
    materials: Vec<Material>,
    by_name: HashMap<String, u32>,
    /// (base material, emission bits, two-sided) → derived emissive material.
    derived: HashMap<(u32, [u32; 3], bool), u32>,
    scene_triangles: Vec<crate::scene::Triangle>,
    instanced: Vec<crate::scene::InstancedMesh>,
    shapes: Vec<Shape>,
    lights: Vec<PunctualLight>,
    textures: Vec<crate::texture::Texture>,
    report: LoadReport,
    decode: crate::import::DecodeStats,
    /// Cameras of each named `Mesh` shape.
    mesh_cameras: BTreeMap<String, Vec<Camera>>,
    /// The shapes with a medium inside so far: their label and bounds.
    media: Vec<MediumBounds>,
}

/// Where a shape's medium is: a sphere's, or a box around the triangles whose material has
/// a medium.
#[derive(Clone)]
struct MediumBounds {
    label: String,
    min: Vec3,
    max: Vec3,
    sphere: Option<(Vec3, f32)>,
}

impl MediumBounds {
    /// Whether the two may share space: spheres exactly, otherwise by their boxes.
    fn overlaps(&self, other: &Self) -> bool {
        if let (Some((c0, r0)), Some((c1, r1))) = (self.sphere, other.sphere) {
            return c0.distance(c1) < r0 + r1;
        }
        self.min.cmplt(other.max).all() && other.min.cmplt(self.max).all()
    }
}

impl<'a> Builder<'a> {
    fn new(text: &'a str, base_dir: &Path) -> Self {
        Self {
            loc: Locator::new(text),
            base_dir: base_dir.to_owned(),
            materials: Vec::new(),
            by_name: HashMap::new(),
            derived: HashMap::new(),
            scene_triangles: Vec::new(),
            instanced: Vec::new(),
            shapes: Vec::new(),
            lights: Vec::new(),
            textures: Vec::new(),
            report: LoadReport::default(),
            decode: crate::import::DecodeStats::default(),
            mesh_cameras: BTreeMap::new(),
            media: Vec::new(),
        }
    }

    /// Records the medium of the shape just built (its primitives from `first_tri` and
    /// `first_shape` on), refusing one that overlaps an earlier shape's medium: a path
    /// is in one medium at a time.
    fn check_medium(
        &mut self,
        label: &str,
        first_tri: usize,
        first_shape: usize,
    ) -> Result<(), SceneError> {
        let has = |m: u32| self.materials[m as usize].medium.is_some();
        let (mut min, mut max) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
        let mut spheres = Vec::new();
        for t in &self.scene_triangles[first_tri..] {
            if has(t.material) {
                for p in t.positions {
                    min = min.min(p);
                    max = max.max(p);
                }
            }
        }
        for s in &self.shapes[first_shape..] {
            if has(s.material) {
                let kind = s.kind();
                if !kind.closed() {
                    return Err(bad(
                        "medium",
                        format!(
                            "a {} encloses no volume, so it cannot have a medium inside",
                            kind.name()
                        ),
                    ));
                }
                let [lo, hi] = kind.bounds(&s.record());
                min = min.min(lo);
                max = max.max(hi);
                if s.kind == crate::shapes::SPHERE {
                    spheres.push((s.center, s.radius));
                }
            }
        }
        if min.x > max.x {
            return Ok(());
        }
        let bounds = MediumBounds {
            label: label.to_owned(),
            min,
            max,
            sphere: (spheres.len() == 1 && min == spheres[0].0 - spheres[0].1).then(|| spheres[0]),
        };
        if let Some(other) = self.media.iter().find(|o| o.overlaps(&bounds)) {
            return Err(bad(
                "medium",
                format!(
                    "the medium inside overlaps that of {}: media may neither overlap nor nest \
                     (a path is in one medium at a time)",
                    other.label
                ),
            ));
        }
        self.media.push(bounds);
        Ok(())
    }

    fn build(mut self, file: &SceneFile) -> Result<Scene, SceneError> {
        for (name, desc) in &file.materials {
            let m = material_from_desc(name, desc).map_err(|e| {
                let field = match &*e.kind {
                    ErrorKind::BadValue { field, .. } => Some(*field),
                    _ => None,
                };
                e.about(format!("material \"{name}\""))
                    .at(self.loc.in_material(name, field))
            })?;
            self.by_name
                .insert(name.clone(), self.materials.len() as u32);
            self.materials.push(m);
        }
        for (i, shape) in file.shapes.iter().enumerate() {
            let label = match shape.name() {
                Some(n) => format!("shape \"{n}\""),
                None => format!("shape {i} ({})", shape.kind()),
            };
            let (first_tri, first_shape) = (self.scene_triangles.len(), self.shapes.len());
            self.shape(shape)
                .and_then(|()| self.check_medium(&label, first_tri, first_shape))
                .map_err(|e| {
                    let needle = match &*e.kind {
                        ErrorKind::UnknownMaterial { material, .. } => format!("\"{material}\""),
                        ErrorKind::BadValue { field, .. } => (*field).to_owned(),
                        _ => String::new(),
                    };
                    e.about(label).at(self.loc.in_shape(i, &needle))
                })?;
        }
        for (i, light) in file.lights.iter().enumerate() {
            let l = light_from_desc(light).map_err(|e| {
                let label = match light.name() {
                    Some(n) => format!("light \"{n}\""),
                    None => format!("light {i} ({})", light.kind()),
                };
                let needle = match &*e.kind {
                    ErrorKind::BadValue { field, .. } => *field,
                    _ => "",
                };
                e.about(label).at(self.loc.in_light(i, needle))
            })?;
            self.lights.push(l);
        }
        let camera = self
            .camera(&file.camera)
            .map_err(|e| e.about("camera").at(self.loc.find("camera")))?;
        let s = file.render;
        if s.width == 0 || s.height == 0 || s.spp == 0 {
            return Err(bad("render", "width, height and spp must be at least 1")
                .at(self.loc.find("render")));
        }
        let mut environment = file.environment.clone();
        if let Environment::Map { path, .. } = &mut environment {
            let full = self.base_dir.join(&*path);
            if !full.is_file() {
                return Err(bad(
                    "environment",
                    format!("cannot open environment map {}", full.display()),
                )
                .at(self.loc.find("environment")));
            }
            *path = full.to_string_lossy().into_owned();
        }
        Ok(Scene {
            camera,
            materials: self.materials,
            triangles: self.scene_triangles,
            instanced: self.instanced,
            shapes: self.shapes,
            lights: self.lights,
            textures: self.textures,
            environment,
            settings: s,
            report: self.report,
            stats: crate::scene::LoadStats {
                decode: self.decode,
                ..Default::default()
            },
        })
    }

    fn lookup(&self, name: &str) -> Result<u32, SceneError> {
        self.by_name.get(name).copied().ok_or_else(|| {
            let known: Vec<_> = self.by_name.keys().map(String::as_str).collect();
            let mut known = known;
            known.sort_unstable();
            SceneError::new(ErrorKind::UnknownMaterial {
                material: name.to_owned(),
                known: known.join(", "),
            })
        })
    }

    /// The material to use for `base` given a shape's emission override.
    fn emissive(
        &mut self,
        base: u32,
        emission: Option<V3>,
        two_sided: bool,
    ) -> Result<u32, SceneError> {
        let emission = match emission {
            Some(e) => non_negative3("emission", e)?,
            None if !two_sided => return Ok(base),
            None => self.materials[base as usize].emission,
        };
        if self.materials[base as usize].index_matched && emission.max_element() > 0.0 {
            return Err(bad(
                "emission",
                "an index-matched boundary has no surface to emit",
            ));
        }
        let key = (base, emission.to_array().map(f32::to_bits), two_sided);
        if let Some(&id) = self.derived.get(&key) {
            return Ok(id);
        }
        let mut m = self.materials[base as usize].clone();
        m.name = format!("{}+emitter{}", m.name, self.derived.len());
        m.emission = emission;
        m.two_sided = two_sided;
        let id = self.materials.len() as u32;
        self.materials.push(m);
        self.derived.insert(key, id);
        Ok(id)
    }

    fn shape(&mut self, shape: &ShapeDesc) -> Result<(), SceneError> {
        let (emission, two_sided) = shape.emitter();
        if let Some((kind, center, radius, axis, material)) = shape.analytic() {
            let center = finite3("center", center)?;
            if !(radius > 0.0 && radius.is_finite()) {
                return Err(bad("radius", format!("{radius} must be a positive number")));
            }
            let mut axis = finite3("normal", axis)?;
            if axis != Vec3::ZERO {
                axis = axis.normalize();
                if !axis.is_finite() {
                    return Err(bad("normal", "is too short to have a direction"));
                }
            } else if kind != crate::shapes::SPHERE {
                return Err(bad("normal", "must not be (0, 0, 0)"));
            }
            let m = self.lookup(material)?;
            let material = self.emissive(m, emission, two_sided)?;
            self.shapes.push(Shape {
                kind,
                center,
                radius,
                axis,
                material,
            });
            return Ok(());
        }
        match shape {
            ShapeDesc::Quad {
                corners, material, ..
            } => {
                let [a, b, c, d] = corners.as_slice() else {
                    return Err(bad(
                        "corners",
                        format!("give 4 corners, not {}", corners.len()),
                    ));
                };
                let c = [
                    finite3("corners", *a)?,
                    finite3("corners", *b)?,
                    finite3("corners", *c)?,
                    finite3("corners", *d)?,
                ];
                let m = self.lookup(material)?;
                let m = self.emissive(m, emission, two_sided)?;
                self.push_quads(&[c], &Mat4::IDENTITY, m);
            }
            ShapeDesc::Rectangle {
                transform,
                material,
                ..
            } => {
                let t = transform_matrix(transform)?;
                let m = self.lookup(material)?;
                let m = self.emissive(m, emission, two_sided)?;
                self.push_quads(&[rectangle_quad()], &t, m);
            }
            ShapeDesc::Box {
                transform,
                material,
                ..
            } => {
                let t = transform_matrix(transform)?;
                let m = self.lookup(material)?;
                let m = self.emissive(m, emission, two_sided)?;
                self.push_quads(&cube_quads(), &t, m);
            }
            ShapeDesc::Mesh {
                name,
                path,
                transform,
                material,
                diffuse,
                instances,
                ..
            } => self.mesh(
                name.as_ref(),
                path,
                transform,
                material.as_deref(),
                *diffuse,
                instances,
                emission,
                two_sided,
            )?,
            // The analytic shapes (`ShapeDesc::analytic`), built above.
            _ => {}
        }
        Ok(())
    }

    /// A `Mesh` shape: the file imported (once, for all its `instances`), its materials
    /// and textures added after the scene's, its triangles and instanced meshes kept.
    #[allow(clippy::too_many_arguments)]
    fn mesh(
        &mut self,
        name: Option<&String>,
        path: &String,
        transform: &TransformDesc,
        material: Option<&str>,
        diffuse: bool,
        instances: &[TransformDesc],
        emission: Option<V3>,
        two_sided: bool,
    ) -> Result<(), SceneError> {
        let t = transform_matrix(transform)?;
        let places = instances
            .iter()
            .map(transform_matrix)
            .collect::<Result<Vec<_>, _>>()?;
        let over = material.map(|m| self.lookup(m)).transpose()?;
        let full = self.base_dir.join(path);
        let mut mesh = import_mesh_with(&full, t, diffuse)?;
        if diffuse {
            reduce_to_diffuse(&mut mesh);
        }
        let prefix = name.cloned().unwrap_or_else(|| path.clone());
        if !places.is_empty() {
            if !mesh.lights.is_empty() {
                return Err(bad(
                    "instances",
                    format!(
                        "the file has {} light(s), which lumagraph places once, not per \
                             instance; give them in the scene file's `lights`",
                        mesh.lights.len()
                    ),
                ));
            }
            place_instances(&mut mesh, &places, &prefix);
        }
        let mut ids = Vec::with_capacity(mesh.materials.len());
        // The file's textures follow the scene's; its materials' indices move along
        // (an override material has none, so the file's textures are not kept).
        let first_texture = self.textures.len() as u32;
        if over.is_none() {
            self.textures.extend(mesh.textures);
        }
        for mut m in mesh.materials {
            let id = if let Some(o) = over {
                o
            } else {
                for t in m.textures.all_mut() {
                    if *t != crate::scene::NO_TEXTURE {
                        *t += first_texture;
                    }
                }
                self.materials.push(Material {
                    name: format!("{prefix}/{}", m.name),
                    ..m
                });
                self.materials.len() as u32 - 1
            };
            ids.push(self.emissive(id, emission, two_sided)?);
        }
        let remap = |mut t: crate::scene::Triangle| {
            t.material = ids[t.material as usize];
            // An override material replaces the file's look, vertex colours too.
            if over.is_some() {
                t.colors = None;
            }
            t
        };
        self.scene_triangles
            .extend(mesh.triangles.into_iter().map(remap));
        for mut m in mesh.instanced {
            m.triangles = m.triangles.into_iter().map(remap).collect();
            // Media need their boundaries in world space (and `check_medium`):
            // such meshes are copied here.
            if m.triangles.iter().any(|t| {
                let mat = &self.materials[t.material as usize];
                mat.medium.is_some() || mat.index_matched
            }) {
                crate::scene::copy_instances(&[m], &mut self.scene_triangles, &mut self.report)?;
            } else {
                self.instanced.push(m);
            }
        }
        self.report.merge(mesh.report);
        self.decode.add(&mesh.decode);
        self.lights.extend(mesh.lights);
        if let Some(n) = name {
            self.mesh_cameras.insert(n.clone(), mesh.cameras);
        }
        Ok(())
    }

    fn push_quads(&mut self, quads: &[[Vec3; 4]], t: &Mat4, material: u32) {
        for q in quads {
            for tri in quad_triangles(*q, material) {
                push_triangle(
                    &mut self.scene_triangles,
                    &mut self.report,
                    transform_triangle(t, &tri),
                );
            }
        }
    }

    fn camera(&self, desc: &CameraDesc) -> Result<Camera, SceneError> {
        let (mut cam, aperture, focus) = match desc {
            CameraDesc::Perspective {
                position,
                target,
                up,
                fov_y,
                aperture_radius,
                focus_distance,
                autofocus,
            } => {
                let position = finite3("position", *position)?;
                let target = finite3("target", *target)?;
                let up = finite3("up", *up)?;
                let dir = target - position;
                if dir.length() == 0.0 || dir.normalize().cross(up).length() <= 1e-6 {
                    return Err(bad(
                        "target",
                        "the camera must look somewhere not parallel to `up`",
                    ));
                }
                let cam = Camera {
                    position,
                    forward: dir.normalize(),
                    up,
                    fov_y_deg: *fov_y,
                    aperture_radius: 0.0,
                    focus_distance: dir.length(),
                    autofocus: *autofocus,
                };
                (cam, *aperture_radius, *focus_distance)
            }
            CameraDesc::Gltf {
                shape,
                index,
                aperture_radius,
                focus_distance,
                autofocus,
            } => {
                let cams = self.mesh_cameras.get(shape).ok_or_else(|| {
                    SceneError::new(ErrorKind::Camera(format!(
                        "no Mesh shape named \"{shape}\""
                    )))
                })?;
                let mut cam = *cams.get(*index).ok_or_else(|| {
                    SceneError::new(ErrorKind::Camera(format!(
                        "shape \"{shape}\" has {} perspective camera(s), no camera {index}",
                        cams.len()
                    )))
                })?;
                cam.autofocus = *autofocus;
                (cam, *aperture_radius, *focus_distance)
            }
        };
        if !(cam.fov_y_deg > 0.0 && cam.fov_y_deg < 180.0) {
            return Err(bad(
                "fov_y",
                format!("{} must be in (0, 180) degrees", cam.fov_y_deg),
            ));
        }
        if !(aperture >= 0.0 && aperture.is_finite()) {
            return Err(bad("aperture_radius", format!("{aperture} must be >= 0")));
        }
        cam.aperture_radius = aperture;
        if let Some(f) = focus {
            if !(f > 0.0 && f.is_finite()) {
                return Err(bad("focus_distance", format!("{f} must be > 0")));
            }
            cam.focus_distance = f;
        }
        Ok(cam)
    }
}
