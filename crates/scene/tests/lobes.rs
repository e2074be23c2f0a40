//! Every lobe parameter (`lumagraph_scene::lobes::PARAMS`) reaches every step by its name
//! alone: a value set through the editor's handle on the scene format's description is
//! saved, loaded, checked, flattened into the GPU record's field of the same name and
//! exported, with no code of its own in any of them.

use lumagraph_scene::file::SceneFile;
use lumagraph_scene::lobes::{PARAMS, ParamMut, Value};
use lumagraph_scene::{GpuMaterial, GpuScene, Scene, save};

const SCENE: &str = r#"(
    version: 2,
    camera: Perspective(position: (0.0, 0.0, 4.0), target: (0.0, 0.0, 0.0), fov_y: 40.0),
    materials: {
        "m": (),
    },
    shapes: [Sphere(center: (0.0, 0.0, 0.0), radius: 1.0, material: "m")],
    render: (width: 4, height: 4),
)
"#;

#[test]
fn every_lobe_parameter_is_saved_loaded_flattened_and_exported_by_its_name() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("scene.ron");
    // 0.25 is no parameter's default, and in every one's range.
    let (scalar, rgb) = (Value::F32(0.25), Value::Vec3f([0.25; 3]));
    for p in PARAMS {
        let mut file = SceneFile::from_ron(SCENE).unwrap();
        let desc = file.materials.get_mut("m").unwrap();
        let want = match (p.edit)(desc) {
            ParamMut::Scalar(x) => {
                *x = 0.25;
                scalar
            }
            ParamMut::Rgb(c) => {
                *c = [0.25; 3];
                rgb
            }
        };
        let text = save::write(SCENE, &file).unwrap();
        assert!(
            text.contains(&format!("{}: ", p.name)),
            "{}: saved\n{text}",
            p.name
        );
        std::fs::write(&path, &text).unwrap();
        let scene = Scene::load(&path).unwrap();
        let gpu = GpuScene::build(&scene).unwrap();
        let m = scene.materials.iter().position(|m| m.name == "m").unwrap();
        let field = GpuMaterial::FIELDS.iter().position(|f| f.name == p.name);
        let field = field.unwrap_or_else(|| panic!("{}: no field in the record", p.name));
        assert_eq!(
            gpu.materials[m].values()[field],
            want,
            "{}: flattened",
            p.name
        );
        let out = dir.path().join(p.name);
        lumagraph_scene::export::export(&scene, &gpu, &out).unwrap();
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("scene.json")).unwrap())
                .unwrap();
        let exported = &json["materials"][m][p.name];
        let expected = match want {
            Value::Vec3f(_) => serde_json::json!([0.25, 0.25, 0.25]),
            _ => serde_json::json!(0.25),
        };
        assert_eq!(exported, &expected, "{}: exported", p.name);
    }
}

/// `docs/scene-format.md`'s materials table has a row for every lobe parameter, with the
/// default the scene format gives it: a parameter added to the table without its doc row,
/// or a default changed without its doc, fails here.
#[test]
fn the_scene_format_page_has_every_lobe_parameter_and_its_default() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let page = std::fs::read_to_string(root.join("docs/scene-format.md")).unwrap();
    let num = |x: f32| format!("{x}");
    for p in PARAMS {
        let row = format!("| `{}` | ", p.name);
        let line = page
            .lines()
            .find(|l| l.starts_with(&row))
            .unwrap_or_else(|| panic!("docs/scene-format.md has no row for `{}`", p.name));
        let mut desc = lumagraph_scene::file::MaterialDesc::default();
        let default = match (p.edit)(&mut desc) {
            ParamMut::Scalar(x) => format!("`{}`", num(*x)),
            ParamMut::Rgb(c) => format!("`({}, {}, {})`", num(c[0]), num(c[1]), num(c[2])),
        };
        let cell = line[row.len()..].split(" | ").next().unwrap_or_default();
        assert_eq!(
            cell, default,
            "docs/scene-format.md gives `{}` the default {cell}, the scene format {default}",
            p.name
        );
    }
}
