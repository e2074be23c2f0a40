//! Edits of a scene file's values by path, for programs (the Python package's
//! `Scene.set("camera.fov_y", 30)`): the parts the editor's scene panel edits, and no more.
//!
//! A path names a part, then perhaps a field of it:
//! - `camera`, `camera.fov_y`, `camera.position`, …
//! - `materials.NAME`, `materials.NAME.base_color`, … (a name may hold dots);
//! - `environment`, `environment.intensity` (the fields of a `Map`);
//! - `render`, `render.width`, `render.spp`, ….
//!
//! Values are RON text as the file would hold it (`30`, `(0.8, 0.1, 0.1)`, `"Au"`,
//! `Constant((1, 1, 1))`, `None`). A set value is checked against the field's type at
//! once; what the loader checks besides (a camera looking along `up`, a negative
//! roughness) is reported when the scene is built. `version`, `shapes` and `lights` are not
//! edited here, as the editor does not edit them: [`crate::save::write`] writes the edited
//! values back into the file's text, keeping its comments and layout.
//!
//! ```
//! use lumagraph_scene::edit;
//! use lumagraph_scene::file::SceneFile;
//! let mut f = SceneFile::from_ron(
//!     "(version: 2, camera: Perspective(position: (0, 0, 5), target: (0, 0, 0), fov_y: 40),
//!       materials: { \"red\": (base_color: (0.8, 0.1, 0.1)) },
//!       shapes: [], render: (width: 64, height: 64))").unwrap();
//! edit::set(&mut f, "camera.fov_y", "30").unwrap();
//! edit::set(&mut f, "materials.red.roughness", "0.25").unwrap();
//! assert_eq!(edit::get(&f, "camera.fov_y").unwrap(), "30.0");
//! assert!(edit::set(&mut f, "render.width", "\"wide\"").is_err());
//! ```

use std::path::{Path, PathBuf};

use ron::extensions::Extensions;
use serde::de::DeserializeOwned;

use crate::error::{ErrorKind, SceneError};
use crate::file::{CameraDesc, Environment, MaterialDesc, RenderSettings, SceneFile};
use crate::save::{Val, camera_value, environment_value, material_value, render, render_value};

/// The parts of a scene file that can be edited.
pub const PARTS: [&str; 4] = ["camera", "materials", "environment", "render"];

/// What a path names.
enum Target<'a> {
    Camera,
    Materials,
    Material(String),
    Environment,
    Render,
    /// A field of one of the above.
    Field(Box<Target<'a>>, &'a str),
}

fn error(path: &str, message: impl Into<String>) -> SceneError {
    SceneError::new(ErrorKind::Edit(format!("{path}: {}", message.into())))
}

/// Splits `path` into a part and a field; `new_material` allows a material the file does
/// not have (setting a whole material adds it).
fn target<'a>(
    file: &SceneFile,
    path: &'a str,
    new_material: bool,
) -> Result<Target<'a>, SceneError> {
    let (part, rest) = match path.split_once('.') {
        Some((p, r)) => (p, Some(r)),
        None => (path, None),
    };
    let whole = match part {
        "camera" => Target::Camera,
        "environment" => Target::Environment,
        "render" => Target::Render,
        "materials" => {
            let Some(rest) = rest else {
                return Ok(Target::Materials);
            };
            if file.materials.contains_key(rest) {
                return Ok(Target::Material(rest.to_owned()));
            }
            if let Some((name, field)) = rest.rsplit_once('.')
                && file.materials.contains_key(name)
            {
                return Ok(Target::Field(
                    Box::new(Target::Material(name.to_owned())),
                    field,
                ));
            }
            // A new material, unless the path ends in a material's field (`blue.roughness`
            // is a field of a material "blue" the file lacks).
            let ends_in_field = rest.rsplit_once('.').is_some_and(|(_, field)| {
                matches!(material_value(&MaterialDesc::default()),
                    Val::Struct { fields, .. } if fields.iter().any(|f| f.name == field))
            });
            if new_material && !rest.is_empty() && !ends_in_field {
                return Ok(Target::Material(rest.to_owned()));
            }
            let missing = if ends_in_field {
                rest.rsplit_once('.').map_or(rest, |(name, _)| name)
            } else {
                rest
            };
            let names: Vec<&str> = file.materials.keys().map(String::as_str).collect();
            return Err(error(
                path,
                format!(
                    "the scene file has no material \"{missing}\" (it has: {}; materials a mesh \
                     file defines are not in the scene file: name one in the shape's \
                     `material` to replace them)",
                    if names.is_empty() {
                        "none".to_owned()
                    } else {
                        names.join(", ")
                    }
                ),
            ));
        }
        "version" | "shapes" | "lights" => {
            return Err(error(
                path,
                format!(
                    "the {part} of a scene are not edited by path (only {})",
                    PARTS.join(", ")
                ),
            ));
        }
        _ => {
            return Err(error(
                path,
                format!(
                    "no such part of a scene file (the parts edited: {})",
                    PARTS.join(", ")
                ),
            ));
        }
    };
    Ok(match rest {
        None => whole,
        Some(field) => Target::Field(Box::new(whole), field),
    })
}

/// The value of a part as the writer sees it.
fn value(file: &SceneFile, t: &Target<'_>) -> Option<Val> {
    Some(match t {
        Target::Camera => camera_value(&file.camera),
        Target::Materials => Val::Map(
            file.materials
                .iter()
                .map(|(k, m)| (k.clone(), material_value(m)))
                .collect(),
        ),
        Target::Material(name) => material_value(file.materials.get(name)?),
        Target::Environment => environment_value(&file.environment),
        Target::Render => render_value(&file.render),
        Target::Field(..) => return None,
    })
}

/// The fields of a struct value, or why there are none.
fn fields_of<'v>(
    path: &str,
    v: &'v mut Val,
) -> Result<&'v mut Vec<crate::save::Field>, SceneError> {
    match v {
        Val::Struct { fields, .. } => Ok(fields),
        Val::Leaf(text) => Err(error(
            path,
            format!("the value there is `{text}`, which has no fields: set it whole"),
        )),
        Val::Map(_) => Err(error(path, "name a material: materials.NAME")),
    }
}

fn no_field(path: &str, name: &str, fields: &[crate::save::Field]) -> SceneError {
    let names: Vec<&str> = fields.iter().map(|f| f.name).collect();
    error(
        path,
        format!("no field `{name}` there (its fields: {})", names.join(", ")),
    )
}

/// The value at `path` as RON text (`None` for an optional field left out).
///
/// # Errors
/// When the path names no editable part or field ([`ErrorKind::Edit`]).
pub fn get(file: &SceneFile, path: &str) -> Result<String, SceneError> {
    let t = target(file, path, false)?;
    let v = match &t {
        Target::Field(whole, name) => {
            let mut v = value(file, whole).ok_or_else(|| error(path, "no such value"))?;
            let fields = fields_of(path, &mut v)?;
            let f = fields
                .iter()
                .find(|f| f.name == *name)
                .ok_or_else(|| no_field(path, name, fields))?;
            if f.none {
                return Ok("None".to_owned());
            }
            f.value.clone()
        }
        whole => value(file, whole).ok_or_else(|| error(path, "no such value"))?,
    };
    Ok(render(&v, None, ""))
}

/// The names one level under `path`: the parts for `""`, the material names for
/// `materials`, a struct's fields.
///
/// # Errors
/// When the path names no editable part, or a value without fields.
pub fn fields(file: &SceneFile, path: &str) -> Result<Vec<String>, SceneError> {
    if path.is_empty() {
        return Ok(PARTS.iter().map(|&p| p.to_owned()).collect());
    }
    let t = target(file, path, false)?;
    if matches!(t, Target::Materials) {
        return Ok(file.materials.keys().cloned().collect());
    }
    let mut v = value(file, &t).ok_or_else(|| error(path, "a single value has no fields"))?;
    Ok(fields_of(path, &mut v)?
        .iter()
        .map(|f| f.name.to_owned())
        .collect())
}

fn parse<T: DeserializeOwned>(path: &str, text: &str) -> Result<T, SceneError> {
    ron::Options::default()
        .with_default_extension(Extensions::IMPLICIT_SOME)
        .from_str(text)
        .map_err(|e| error(path, format!("`{text}` does not fit: {}", e.code)))
}

/// Sets the value at `path` to `value`, RON text as the file would hold it; setting a whole
/// material the file does not have adds it.
///
/// # Errors
/// When the path names no editable part or field, or the value does not fit the field's
/// type ([`ErrorKind::Edit`], naming both); `file` is then unchanged.
pub fn set(file: &mut SceneFile, path: &str, value: &str) -> Result<(), SceneError> {
    let t = target(file, path, true)?;
    let (whole, text) = match t {
        Target::Field(whole, name) => {
            let mut v = self::value(file, &whole).ok_or_else(|| error(path, "no such value"))?;
            let fields = fields_of(path, &mut v)?;
            let Some(f) = fields.iter_mut().find(|f| f.name == name) else {
                return Err(no_field(path, name, fields));
            };
            f.value = Val::Leaf(value.trim().to_owned());
            f.default = false;
            f.none = false;
            (*whole, render(&v, None, ""))
        }
        whole => (whole, value.trim().to_owned()),
    };
    match whole {
        Target::Camera => file.camera = parse::<CameraDesc>(path, &text)?,
        Target::Environment => file.environment = parse::<Environment>(path, &text)?,
        Target::Render => file.render = parse::<RenderSettings>(path, &text)?,
        Target::Material(name) => {
            let m = parse::<MaterialDesc>(path, &text)?;
            file.materials.insert(name, m);
        }
        Target::Materials => {
            file.materials = parse(path, &text)?;
        }
        Target::Field(..) => return Err(error(path, "a field of a field")),
    }
    Ok(())
}

/// A scene file's text and its values as edited: what [`set`] changes, written back
/// into the text by [`crate::save::write`] (comments and layout kept).
#[derive(Clone, Debug)]
pub struct SceneText {
    /// The file it was read from (mesh paths are relative to its folder).
    pub path: PathBuf,
    /// The text as read.
    pub text: String,
    /// The values as edited.
    pub file: SceneFile,
}

impl SceneText {
    /// Reads and parses `path`.
    ///
    /// # Errors
    /// When it cannot be read, or does not parse (naming the file, line and column).
    pub fn load(path: &Path) -> Result<Self, SceneError> {
        let text = std::fs::read_to_string(path).map_err(|source| {
            SceneError::new(ErrorKind::Io {
                what: "scene file",
                source,
            })
            .in_file(path)
        })?;
        let file = SceneFile::from_ron(&text).map_err(|e| e.in_file(path))?;
        Ok(Self {
            path: path.to_owned(),
            text,
            file,
        })
    }

    /// The folder the file's paths are relative to.
    pub fn base_dir(&self) -> &Path {
        self.path.parent().unwrap_or(Path::new("."))
    }

    /// The scene of the edited values (its meshes and textures loaded).
    ///
    /// # Errors
    /// What loading reports, naming the file (with line and column while unedited).
    pub fn build(&self) -> Result<crate::Scene, SceneError> {
        let scene = if self.is_edited() {
            crate::Scene::from_file(&self.file, self.base_dir())
        } else {
            crate::Scene::from_ron(&self.text, self.base_dir())
        };
        scene.map_err(|e| e.in_file(&self.path))
    }

    /// Whether the values differ from the text's.
    pub fn is_edited(&self) -> bool {
        SceneFile::from_ron(&self.text).ok().as_ref() != Some(&self.file)
    }

    /// The text with the edited values written in ([`crate::save::write`]).
    ///
    /// # Errors
    /// As [`crate::save::write`].
    pub fn to_ron(&self) -> Result<String, SceneError> {
        crate::save::write(&self.text, &self.file).map_err(|e| e.in_file(&self.path))
    }

    /// Writes [`Self::to_ron`] to `to` atomically (the file it was read from when `None`,
    /// which then counts as unedited).
    ///
    /// # Errors
    /// When the text cannot be written or the file cannot be (it is then unchanged).
    pub fn save(&mut self, to: Option<&Path>) -> Result<(), SceneError> {
        let target = to.unwrap_or(&self.path).to_owned();
        let text = crate::save::save(&target, &self.text, &self.file)?;
        if to.is_none() {
            self.text = text;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const TEXT: &str = "(
    version: 2,
    // the camera
    camera: Perspective(position: (0, 1, 5), target: (0, 1, 0), fov_y: 40),
    materials: {
        \"red\": (base_color: (0.8, 0.1, 0.1)), // red
        \"glass.clear\": (transmission: 1),
    },
    shapes: [Sphere(center: (0, 1, 0), radius: 1, material: \"red\")],
    environment: Constant((1, 1, 1)),
    render: (width: 64, height: 48, spp: 4),
)";

    fn file() -> SceneFile {
        SceneFile::from_ron(TEXT).unwrap()
    }

    /// Every editable value of this test's file and of every scene file in the
    /// repository's `assets/` and `tests/scenes/` reads back, and setting it as read
    /// changes nothing.
    #[test]
    fn fields_of_every_part_read_back_and_set_as_the_file_has_them() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
        let mut files = vec![file()];
        for dir in ["assets", "tests/scenes"] {
            for entry in std::fs::read_dir(root.join(dir)).unwrap() {
                let path = entry.unwrap().path();
                if path.extension().is_some_and(|e| e == "ron") {
                    let text = std::fs::read_to_string(&path).unwrap();
                    files.push(SceneFile::from_ron(&text).unwrap());
                }
            }
        }
        assert!(files.len() > 20, "{} scene files", files.len());
        for f in &files {
            round_trip(f);
        }
    }

    fn round_trip(f: &SceneFile) {
        for part in PARTS {
            let text = get(f, part).unwrap();
            let mut g = f.clone();
            set(&mut g, part, &text).unwrap();
            assert_eq!(&g, f, "{part}: {text}");
            if part == "environment" {
                continue;
            }
            let mut paths = vec![part.to_owned()];
            if part == "materials" {
                paths = fields(f, part)
                    .unwrap()
                    .into_iter()
                    .map(|m| format!("materials.{m}"))
                    .collect();
            }
            for (part, name) in paths
                .iter()
                .flat_map(|p| fields(f, p).unwrap().into_iter().map(move |n| (p, n)))
            {
                let path = format!("{part}.{name}");
                let text = get(f, &path).unwrap();
                let mut g = f.clone();
                set(&mut g, &path, &text).unwrap();
                assert_eq!(&g, f, "{path}: {text}");
            }
        }
    }

    #[test]
    fn a_set_changes_that_value_only() {
        let mut f = file();
        set(&mut f, "camera.fov_y", "30").unwrap();
        set(&mut f, "materials.glass.clear.ior", "1.33").unwrap();
        set(&mut f, "render.width", "128").unwrap();
        set(&mut f, "environment", "Constant((0.5, 0.5, 0.5))").unwrap();
        set(&mut f, "materials.new", "(base_color: (0, 1, 0))").unwrap();
        let CameraDesc::Perspective {
            fov_y, position, ..
        } = &f.camera
        else {
            panic!("a perspective camera")
        };
        assert_eq!((*fov_y, *position), (30.0, [0.0, 1.0, 5.0]));
        assert_eq!(f.materials["glass.clear"].ior, 1.33);
        assert_eq!(f.materials["glass.clear"].transmission, 1.0);
        assert_eq!(f.materials["new"].base_color, [0.0, 1.0, 0.0]);
        assert_eq!(
            (f.render.width, f.render.height, f.render.spp),
            (128, 48, 4)
        );
        assert_eq!(f.environment, Environment::Constant([0.5; 3]));
        // Written back into the text: the comments stay.
        let text = crate::save::write(TEXT, &f).unwrap();
        assert!(
            text.contains("// the camera") && text.contains("// red"),
            "{text}"
        );
        assert_eq!(SceneFile::from_ron(&text).unwrap(), f);
    }

    #[test]
    fn bad_paths_and_values_are_named_and_change_nothing() {
        let f = file();
        let cases = [
            ("camera.fov", "30", "no field `fov`"),
            ("render.width", "\"wide\"", "does not fit"),
            ("materials.blue.roughness", "0.5", "no material \"blue\""),
            ("shapes", "[]", "not edited by path"),
            ("environment.intensity", "2", "has no fields"),
            ("lens", "1", "no such part"),
        ];
        for (path, value, says) in cases {
            let mut g = f.clone();
            let e = set(&mut g, path, value).unwrap_err().to_string();
            assert!(e.contains(path) && e.contains(says), "{path}: {e}");
            assert_eq!(g, f);
        }
        assert_eq!(get(&f, "camera.focus_distance").unwrap(), "None");
        assert!(get(&f, "materials.blue").is_err());
    }
}
