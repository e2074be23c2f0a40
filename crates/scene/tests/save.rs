//! Writing edited scene files over their text: an unchanged file is written byte for byte,
//! an edit changes only what it edits, and what is written reads back as the edit.

mod common;

use std::path::{Path, PathBuf};

use lumagraph_scene::file::{CameraDesc, MaterialDesc, SceneFile, ShapeDesc};
use lumagraph_scene::{Environment, ErrorKind, LightDesc, save};

/// Every `assets/*.ron` scene: its path and text.
fn scenes() -> Vec<(PathBuf, String)> {
    let mut paths: Vec<PathBuf> = std::fs::read_dir(common::assets())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "ron"))
        .collect();
    paths.sort();
    paths
        .into_iter()
        .map(|p| {
            let text = std::fs::read_to_string(&p).unwrap();
            (p, text)
        })
        .collect()
}

fn asset(name: &str) -> String {
    std::fs::read_to_string(common::assets().join(name)).unwrap()
}

fn parse(text: &str) -> SceneFile {
    SceneFile::from_ron(text).unwrap()
}

/// `edited` written over `text`; checks that it reads back as `edited` and that writing
/// it again over itself changes nothing.
fn write(text: &str, edited: &SceneFile) -> String {
    let out = save::write(text, edited).unwrap_or_else(|e| panic!("{e}\n{text}\n{edited:#?}"));
    assert_eq!(&parse(&out), edited, "{out}");
    assert_eq!(save::write(&out, edited).unwrap(), out);
    out
}

/// The lines of `after` that differ from those of `before` (same number of lines).
fn changed_lines<'a>(before: &str, after: &'a str) -> Vec<&'a str> {
    let (b, a): (Vec<_>, Vec<_>) = (before.lines().collect(), after.lines().collect());
    assert_eq!(b.len(), a.len(), "{after}");
    b.iter()
        .zip(&a)
        .filter(|(x, y)| x != y)
        .map(|(_, y)| *y)
        .collect()
}

fn perspective(file: &mut SceneFile) -> (&mut f32, &mut f32, &mut Option<f32>, &mut bool) {
    match &mut file.camera {
        CameraDesc::Perspective {
            fov_y,
            aperture_radius,
            focus_distance,
            autofocus,
            ..
        } => (fov_y, aperture_radius, focus_distance, autofocus),
        _ => panic!("not a perspective camera"),
    }
}

const NO_ENVIRONMENT: &str = r#"// A scene without environment and materials.
(
    version: 2,
    camera: Perspective(position: (0, 0, 4), target: (0, 0, 0), fov_y: 40),
    shapes: [
        Sphere(center: (0, 0, 0), radius: 1, material: "white"),
    ],
    // Small.
    render: (width: 64, height: 32),
)
"#;

/// A scene on one line, with a material map.
const ONE_LINE: &str = "(version: 2, camera: Gltf(shape: \"s\"), materials: {\"a\": (), \"b\": \
                        (roughness: 1.0)}, shapes: [], render: (width: 1, height: 1))";

#[test]
fn unchanged_scenes_are_written_byte_for_byte() {
    let scenes = scenes();
    assert!(scenes.len() >= 6, "{} scenes", scenes.len());
    for (path, text) in scenes {
        let out = save::write(&text, &parse(&text)).unwrap();
        assert!(out == text, "{} changed:\n{out}", path.display());
    }
    let text = "#![enable(implicit_some)]\n(version: 2, camera: Gltf(shape: \"a\"), shapes: [], \
                render: (width: 1, height: 1))";
    assert_eq!(save::write(text, &parse(text)).unwrap(), text);
}

#[test]
fn one_material_edit_changes_only_its_line() {
    let text = asset("cornell.ron");
    let mut edited = parse(&text);
    edited.materials.get_mut("green").unwrap().base_color = [0.1, 0.2, 0.3];
    let out = write(&text, &edited);
    assert_eq!(
        changed_lines(&text, &out),
        [r#"        "green": (base_color: (0.1, 0.2, 0.3), roughness: 1.0, specular: 0.0),"#]
    );
    assert!(out.starts_with("// Cornell box reproducing the Mitsuba 3 reference scene"));

    // A field the text leaves out is added to the line (before the next field in
    // declaration order); one set to its default stays.
    edited.materials.get_mut("red").unwrap().metallic = Some(0.25);
    edited.materials.get_mut("white").unwrap().specular = 0.5;
    let out = write(&text, &edited);
    let changed = changed_lines(&text, &out);
    assert_eq!(changed.len(), 3);
    assert!(changed.contains(
        &r#"        "red": (base_color: (0.570068, 0.0430135, 0.0443706), roughness: 1.0, metallic: 0.25, specular: 0.0),"#
    ));
    assert!(changed.contains(
        &r#"        "white": (base_color: (0.885809, 0.698859, 0.666422), roughness: 1.0, specular: 0.5),"#
    ));

    // Back to `None`: the field goes.
    let mut again = parse(&out);
    again.materials.get_mut("red").unwrap().metallic = None;
    assert!(!write(&out, &again).contains("metallic"));
}

#[test]
fn camera_edits_read_back() {
    // One field a line (cornell) and all on one line (furnace_materials).
    for name in ["cornell.ron", "furnace_materials.ron"] {
        let text = asset(name);
        let mut edited = parse(&text);
        *perspective(&mut edited).0 = 45.5;
        let out = write(&text, &edited);
        assert_eq!(changed_lines(&text, &out).len(), 1, "{out}");
        assert!(out.contains("fov_y: 45.5"), "{out}");

        let (_, aperture, focus, autofocus) = perspective(&mut edited);
        *aperture = 0.05;
        *focus = Some(3.25);
        *autofocus = true;
        let out = write(&text, &edited);
        assert!(out.contains("aperture_radius: 0.05"), "{out}");
        assert!(out.contains("focus_distance: 3.25"), "{out}");
        assert!(out.contains("autofocus: true"), "{out}");

        // Back to the defaults, from the text just written.
        let mut back = edited.clone();
        let (_, aperture, focus, autofocus) = perspective(&mut back);
        *aperture = 0.0;
        *focus = None;
        *autofocus = false;
        let out = write(&out, &back);
        assert!(!out.contains("focus_distance"), "{out}");

        // Another kind of camera is written anew.
        let mut gltf = edited.clone();
        gltf.camera = CameraDesc::Gltf {
            shape: "box".into(),
            index: 1,
            aperture_radius: 0.0,
            focus_distance: None,
            autofocus: true,
        };
        let out = write(&text, &gltf);
        assert!(
            out.contains(r#"    camera: Gltf(shape: "box", index: 1, autofocus: true),"#),
            "{out}"
        );
    }
    // Multi-line camera: a new field gets its own line.
    let text = asset("cornell.ron");
    let mut edited = parse(&text);
    *perspective(&mut edited).1 = 0.125;
    let out = write(&text, &edited);
    assert!(
        out.contains("        fov_y: 39.3077,\n        aperture_radius: 0.125,\n    ),\n"),
        "{out}"
    );
}

#[test]
fn environment_edits_read_back() {
    let text = asset("cornell.ron");
    let mut edited = parse(&text);
    edited.environment = Environment::Map {
        path: "hdri/venice_sunset_1k.hdr".into(),
        intensity: 2.5,
        azimuth: 90.0,
        elevation: 0.0,
        show_background: false,
    };
    let out = write(&text, &edited);
    assert_eq!(
        changed_lines(&text, &out),
        [
            r#"    environment: Map(path: "hdri/venice_sunset_1k.hdr", intensity: 2.5, azimuth: 90.0, show_background: false),"#
        ]
    );

    // Map → Constant, and a field of a map.
    let text = asset("boxtextured.ron");
    let mut edited = parse(&text);
    edited.environment = Environment::Constant([0.5, 0.25, 1.0]);
    let out = write(&text, &edited);
    assert_eq!(
        changed_lines(&text, &out),
        ["    environment: Constant((0.5, 0.25, 1.0)),"]
    );
    let mut edited = parse(&text);
    if let Environment::Map { elevation, .. } = &mut edited.environment {
        *elevation = -10.0;
    }
    let out = write(&text, &edited);
    assert_eq!(
        changed_lines(&text, &out),
        [
            r#"    environment: Map(path: "hdri/venice_sunset_1k.hdr", intensity: 1.0, azimuth: 180.0, elevation: -10.0),"#
        ]
    );
}

#[test]
fn missing_fields_are_inserted_before_the_next_one() {
    let mut edited = parse(NO_ENVIRONMENT);
    edited.environment = Environment::Constant([1.0, 1.0, 1.0]);
    edited
        .materials
        .insert("white".into(), MaterialDesc::default());
    let out = write(NO_ENVIRONMENT, &edited);
    assert_eq!(
        out,
        r#"// A scene without environment and materials.
(
    version: 2,
    camera: Perspective(position: (0, 0, 4), target: (0, 0, 0), fov_y: 40),
    materials: {
        "white": (),
    },
    shapes: [
        Sphere(center: (0, 0, 0), radius: 1, material: "white"),
    ],
    environment: Constant((1.0, 1.0, 1.0)),
    // Small.
    render: (width: 64, height: 32),
)
"#
    );

    // The same on one line.
    let text = "(version: 2, camera: Perspective(position: (0, 0, 4), target: (0, 0, 0), \
                fov_y: 40), shapes: [], render: (width: 64, height: 32))";
    let mut edited = parse(text);
    edited.environment = Environment::Constant([1.0, 1.0, 1.0]);
    edited.render.spp = 4;
    let out = write(text, &edited);
    assert!(
        out.ends_with(
            "shapes: [], environment: Constant((1.0, 1.0, 1.0)), render: (width: 64, height: \
             32, spp: 4))"
        ),
        "{out}"
    );
}

#[test]
fn render_edits_keep_the_fields_as_written() {
    let text = asset("cornell.ron");
    let mut edited = parse(&text);
    edited.render.spp = 512;
    edited.render.max_bounces = 8;
    let out = write(&text, &edited);
    assert_eq!(
        changed_lines(&text, &out),
        ["    render: (width: 256, height: 256, max_bounces: 8, spp: 512, seed: 0),"]
    );
    let mut edited = parse(NO_ENVIRONMENT);
    edited.render.seed = 7;
    edited.render.max_bounces = 3;
    let out = write(NO_ENVIRONMENT, &edited);
    assert!(
        out.contains("    render: (width: 64, height: 32, max_bounces: 3, seed: 7),"),
        "{out}"
    );
}

#[test]
fn materials_are_added_and_removed() {
    let text = asset("cornell.ron");
    let mut edited = parse(&text);
    edited.materials.remove("red");
    edited.materials.insert(
        "gold \"Au\"".into(),
        MaterialDesc {
            conductor: Some("Au".into()),
            roughness: 0.25,
            ..MaterialDesc::default()
        },
    );
    let out = write(&text, &edited);
    assert!(!out.contains("\"red\": "), "{out}");
    assert!(
        out.contains(
            "        \"green\": (base_color: (0.105421, 0.37798, 0.076425), roughness: 1.0, \
             specular: 0.0),\n        \"gold \\\"Au\\\"\": (roughness: 0.25, conductor: \
             \"Au\"),\n    },\n"
        ),
        "{out}"
    );
    assert_eq!(out.lines().count(), text.lines().count());

    // A removed material takes the comment lines directly above it along.
    let commented = text.replace(
        "        \"green\": (",
        "        // Green wall.\n        // (Mitsuba's.)\n        \"green\": (",
    );
    let mut edited = parse(&commented);
    edited.materials.remove("green");
    let out = write(&commented, &edited);
    assert!(
        !out.contains("Green wall") && !out.contains("Mitsuba's.)"),
        "{out}"
    );
    assert_eq!(out.lines().count(), text.lines().count() - 1);

    // All removed, then added to the empty map; and a map on one line.
    let mut edited = parse(&text);
    edited.materials.clear();
    let empty = write(&text, &edited);
    assert!(empty.contains("    materials: {\n    },\n"), "{empty}");
    edited.materials.insert("a".into(), MaterialDesc::default());
    assert!(write(&empty, &edited).contains("    materials: {\n        \"a\": (),\n    },\n"));
    let text = ONE_LINE;
    let mut edited = parse(text);
    edited.materials.remove("b");
    edited.materials.insert("c".into(), MaterialDesc::default());
    let out = write(text, &edited);
    assert!(out.contains(r#"materials: {"a": (), "c": ()}"#), "{out}");
}

#[test]
fn shapes_lights_and_version_are_not_edited() {
    let text = asset("cornell.ron");
    let not_editable = |edited: &SceneFile| match save::write(&text, edited) {
        Err(e) => match *e.kind {
            ErrorKind::NotEditable(what) => what,
            other => panic!("{other}"),
        },
        Ok(out) => panic!("written:\n{out}"),
    };
    let mut edited = parse(&text);
    if let ShapeDesc::Quad { corners, .. } = &mut edited.shapes[0] {
        corners[0][1] = -2.0;
    }
    assert_eq!(not_editable(&edited), "shapes");
    let mut edited = parse(&text);
    edited.shapes.pop();
    assert_eq!(not_editable(&edited), "shapes");
    let mut edited = parse(&text);
    edited.lights.push(LightDesc {
        kind: lumagraph_scene::lights::kind_named("Directional").unwrap(),
        name: None,
        fields: lumagraph_scene::lights::Fields::of([
            (
                "direction",
                ron::Value::Seq(vec![ron::Value::from(0.0f32); 3]),
            ),
            (
                "irradiance",
                ron::Value::Seq(vec![ron::Value::from(1.0f32); 3]),
            ),
        ]),
    });
    assert_eq!(not_editable(&edited), "lights");
    let mut edited = parse(&text);
    edited.version = 1;
    assert_eq!(not_editable(&edited), "version");
    let err = save::write(&text, &edited).unwrap_err();
    assert_eq!(
        err.to_string(),
        "the editor cannot change the version of a scene file"
    );

    // Broken text is an error too.
    let edited = parse(&text);
    assert!(save::write("(version: 2,", &edited).is_err());
    assert!(save::write("", &edited).is_err());
}

/// A value from a few that matter (defaults, 0, 1, negative zero, very small and large)
/// or a random one.
fn float(rng: &mut common::Pcg, default: f32) -> f32 {
    match rng.next_u32() % 8 {
        0 => default,
        1 => [0.0, 1.0, -0.0, 1e-7, 3e20, 0.1][rng.next_u32() as usize % 6],
        2 => rng.range(-10.0, 10.0),
        _ => (rng.next_u32() % 1000) as f32 / 1000.0,
    }
}

fn vec3(rng: &mut common::Pcg, default: [f32; 3]) -> [f32; 3] {
    if rng.next_u32().is_multiple_of(3) {
        default
    } else {
        [rng.f32(), rng.f32(), float(rng, 0.5)]
    }
}

fn maybe<T>(rng: &mut common::Pcg, value: impl FnOnce(&mut common::Pcg) -> T) -> Option<T> {
    rng.next_u32().is_multiple_of(2).then(|| value(rng))
}

/// Conductor names, one of them no real conductor but a string that needs escaping.
const CONDUCTORS: [&str; 3] = ["Au", "Cu", "q\"x"];

fn random_material(rng: &mut common::Pcg, m: &mut MaterialDesc) {
    let d = MaterialDesc::default();
    for _ in 0..1 + rng.next_u32() % 3 {
        match rng.next_u32() % 16 {
            0 => m.base_color = vec3(rng, d.base_color),
            1 => m.emission = vec3(rng, d.emission),
            2 => m.roughness = float(rng, d.roughness),
            3 => m.metallic = maybe(rng, |r| float(r, 1.0)),
            4 => m.conductor = maybe(rng, |r| CONDUCTORS[r.next_u32() as usize % 3].into()),
            5 => m.eta = maybe(rng, |r| vec3(r, [0.2, 0.9, 1.1])),
            6 => m.k = maybe(rng, |r| vec3(r, [3.9, 2.4, 2.1])),
            7 => m.multiscatter = !m.multiscatter,
            8 => m.specular = float(rng, d.specular),
            9 => m.specular_tint = float(rng, d.specular_tint),
            10 => m.transmission = float(rng, d.transmission),
            11 => m.ior = float(rng, d.ior),
            12 => m.specular_color = vec3(rng, d.specular_color),
            13 => m.clearcoat = float(rng, 1.0),
            14 => m.sheen_color = vec3(rng, [0.5, 0.2, 0.1]),
            _ => m.two_sided = !m.two_sided,
        }
    }
}

fn random_camera(rng: &mut common::Pcg, camera: &mut CameraDesc) {
    if rng.next_u32().is_multiple_of(10) {
        *camera = if matches!(camera, CameraDesc::Gltf { .. }) {
            CameraDesc::Perspective {
                position: [0.0, 1.0, 5.0],
                target: [0.0; 3],
                up: vec3(rng, [0.0, 1.0, 0.0]),
                fov_y: 30.0,
                aperture_radius: 0.0,
                focus_distance: None,
                autofocus: false,
            }
        } else {
            CameraDesc::Gltf {
                shape: "mesh".into(),
                index: rng.next_u32() as usize % 2,
                aperture_radius: 0.0,
                focus_distance: maybe(rng, |r| float(r, 1.0)),
                autofocus: false,
            }
        };
        return;
    }
    match camera {
        CameraDesc::Perspective {
            position,
            up,
            fov_y,
            aperture_radius,
            focus_distance,
            autofocus,
            ..
        } => match rng.next_u32() % 6 {
            0 => *position = vec3(rng, *position),
            1 => *up = vec3(rng, [0.0, 1.0, 0.0]),
            2 => *fov_y = float(rng, 40.0),
            3 => *aperture_radius = float(rng, 0.0),
            4 => *focus_distance = maybe(rng, |r| float(r, 1.0)),
            _ => *autofocus = !*autofocus,
        },
        CameraDesc::Gltf {
            index,
            aperture_radius,
            autofocus,
            ..
        } => match rng.next_u32() % 3 {
            0 => *index = rng.next_u32() as usize % 3,
            1 => *aperture_radius = float(rng, 0.0),
            _ => *autofocus = !*autofocus,
        },
        _ => {}
    }
}

fn random_environment(rng: &mut common::Pcg, env: &mut Environment) {
    match (rng.next_u32() % 4, &mut *env) {
        (0, _) => *env = Environment::None,
        (1, _) => *env = Environment::Constant(vec3(rng, [1.0; 3])),
        (
            _,
            Environment::Map {
                intensity,
                azimuth,
                elevation,
                show_background,
                ..
            },
        ) => match rng.next_u32() % 4 {
            0 => *intensity = float(rng, 1.0),
            1 => *azimuth = float(rng, 0.0),
            2 => *elevation = float(rng, 0.0),
            _ => *show_background = !*show_background,
        },
        _ => {
            *env = Environment::Map {
                path: ["hdri/a.hdr", "b\\c.exr"][rng.next_u32() as usize % 2].into(),
                intensity: float(rng, 1.0),
                azimuth: float(rng, 0.0),
                elevation: 0.0,
                show_background: rng.next_u32().is_multiple_of(2),
            }
        }
    }
}

/// Random edits of every shipped scene, each written over the text the last one wrote:
/// all read back as edited, and writing again changes nothing.
#[test]
fn random_edits_read_back() {
    let names = [
        "white",
        "m3",
        "diffuse",
        "new",
        "new \"q\"",
        "back\\slash",
        "é",
    ];
    let mut rng = common::Pcg::new(7);
    let mut texts = scenes();
    texts.push(("NO_ENVIRONMENT".into(), NO_ENVIRONMENT.into()));
    texts.push(("ONE_LINE".into(), ONE_LINE.into()));
    for (path, original) in texts {
        let mut text = original.clone();
        for _ in 0..60 {
            let mut edited = parse(&text);
            for _ in 0..1 + rng.next_u32() % 3 {
                match rng.next_u32() % 6 {
                    0 | 1 => {
                        let name = names[rng.next_u32() as usize % names.len()];
                        let m = edited.materials.entry(name.into()).or_default();
                        random_material(&mut rng, m);
                    }
                    2 => {
                        let name = names[rng.next_u32() as usize % names.len()];
                        edited.materials.remove(name);
                    }
                    3 => random_camera(&mut rng, &mut edited.camera),
                    4 => random_environment(&mut rng, &mut edited.environment),
                    _ => {
                        let r = &mut edited.render;
                        match rng.next_u32() % 3 {
                            0 => r.spp = [1, 4, 256][rng.next_u32() as usize % 3],
                            1 => r.max_bounces = [20, 0, 8][rng.next_u32() as usize % 3],
                            _ => r.seed = rng.next_u32() % 3,
                        }
                    }
                }
            }
            let out = save::write(&text, &edited)
                .unwrap_or_else(|e| panic!("{}: {e}\n{text}\n{edited:#?}", path.display()));
            assert_eq!(parse(&out), edited, "{}:\n{out}", path.display());
            assert_eq!(save::write(&out, &edited).unwrap(), out);
            // The header comment always stays.
            let header: Vec<&str> = original
                .lines()
                .take_while(|l| l.starts_with("//"))
                .collect();
            assert!(out.lines().zip(&header).all(|(a, b)| a == *b), "{out}");
            text = out;
        }
    }
}

#[test]
fn save_writes_atomically_and_names_the_file() {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("scene-save");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("cornell.ron");
    let text = asset("cornell.ron");
    std::fs::write(&path, &text).unwrap();

    let mut edited = parse(&text);
    edited.render.spp = 4;
    let written = save::save(&path, &text, &edited).unwrap();
    assert_eq!(std::fs::read_to_string(&path).unwrap(), written);
    assert_eq!(parse(&written), edited);
    let files: Vec<_> = std::fs::read_dir(&dir).unwrap().collect();
    assert_eq!(files.len(), 1, "temporary files left: {files:?}");

    // A refused edit leaves the file as it was, and the error names it.
    edited.shapes.clear();
    let err = save::save(&path, &written, &edited).unwrap_err();
    assert_eq!(err.file.as_deref(), Some(path.as_path()));
    assert!(err.to_string().starts_with(&path.display().to_string()));
    assert_eq!(std::fs::read_to_string(&path).unwrap(), written);

    // A folder that does not exist: an error naming the file.
    let missing = dir.join("missing/scene.ron");
    let err = save::save(&missing, &text, &parse(&text)).unwrap_err();
    assert!(matches!(*err.kind, ErrorKind::Write { .. }), "{err}");
    assert_eq!(err.file.as_deref(), Some(missing.as_path()));
}

/// Comments and line breaks after any `,`, `(`, `:`, `{`, `}` or `)` of every shipped
/// scene (where the file still parses): unchanged files are written byte for byte and
/// edits read back.
#[test]
fn comments_and_line_breaks_anywhere() {
    let junk = [" /* c, ) } */ ", "// x: (\n", "\n", "  ", "\n    // y\n"];
    let mut rng = common::Pcg::new(3);
    let mut written = 0;
    for (path, original) in scenes() {
        for _ in 0..150 {
            let mut text = original.clone();
            for _ in 0..4 {
                let after: Vec<usize> = text
                    .char_indices()
                    .filter(|(_, c)| matches!(c, ',' | '(' | ':' | '{' | '}' | ')'))
                    .map(|(i, _)| i + 1)
                    .collect();
                let at = after[rng.next_u32() as usize % after.len()];
                text.insert_str(at, junk[rng.next_u32() as usize % junk.len()]);
            }
            let Ok(mut edited) = SceneFile::from_ron(&text) else {
                continue;
            };
            assert_eq!(save::write(&text, &edited).unwrap(), text);
            for _ in 0..3 {
                let name = ["white", "zz", "m3", "metal"][rng.next_u32() as usize % 4];
                match rng.next_u32() % 4 {
                    0 => {
                        let m = edited.materials.entry(name.into()).or_default();
                        random_material(&mut rng, m);
                    }
                    1 => {
                        edited.materials.remove(name);
                    }
                    2 => random_camera(&mut rng, &mut edited.camera),
                    _ => random_environment(&mut rng, &mut edited.environment),
                }
            }
            let out = save::write(&text, &edited)
                .unwrap_or_else(|e| panic!("{}: {e}\n{text}", path.display()));
            assert_eq!(parse(&out), edited, "{out}");
            written += 1;
        }
    }
    assert!(written > 500, "{written}");
}
