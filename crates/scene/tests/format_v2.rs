//! Scene format version 2: environment maps in Mitsuba's orientation (version 1 files
//! converted), conductors, the multiple-scattering switch, point, spot and directional
//! lights from the scene file and from glTF, and the export for other renderers.

mod common;

use std::path::{Path, PathBuf};

use glam::Vec3;
use lumagraph_scene::{
    Environment, GpuScene, LIGHT_DIRECTIONAL, LIGHT_POINT, LIGHT_SPOT, MATERIAL_CONDUCTOR,
    MATERIAL_SINGLE_SCATTER, PunctualLight, Scene, SceneError,
};

fn parse(text: &str) -> Result<Scene, SceneError> {
    Scene::from_ron(text, &common::assets())
}

fn tests_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../tests/scenes")
}

const BASE: &str = r#"(
    version: 2,
    camera: Perspective(position: (0, 0, 4), target: (0, 0, 0), fov_y: 40),
    materials: {
        "white": (base_color: (0.8, 0.8, 0.8)),
        MATERIAL
    },
    shapes: [
        Sphere(name: "ball", center: (0, 0, 0), radius: 1, material: "white"),
    ],
    LIGHTS
    environment: ENVIRONMENT,
    render: (width: 16, height: 16),
)"#;

fn scene(material: &str, lights: &str, environment: &str) -> String {
    BASE.replace("MATERIAL", material)
        .replace("LIGHTS", lights)
        .replace("ENVIRONMENT", environment)
}

#[test]
fn version_1_maps_are_turned_to_light_the_scene_as_before() {
    let map = "Map(path: \"hdri/venice_sunset_1k.hdr\", azimuth: 30, elevation: 20)";
    let v2 = parse(&scene("", "", map)).unwrap();
    let v1 = parse(&scene("", "", map).replace("version: 2", "version: 1")).unwrap();
    let angles = |s: &Scene| match &s.environment {
        Environment::Map {
            azimuth, elevation, ..
        } => (*azimuth, *elevation),
        e => panic!("{e:?}"),
    };
    assert_eq!(angles(&v2), (30.0, 20.0));
    assert_eq!(angles(&v1), (-210.0, -20.0));
    // Constant environments mean the same in both versions.
    let c = parse(&scene("", "", "Constant((1, 2, 3))").replace("version: 2", "version: 1"));
    assert_eq!(
        c.unwrap().environment,
        Environment::Constant([1.0, 2.0, 3.0])
    );
    let e = parse(&scene("", "", "None").replace("version: 2", "version: 3")).unwrap_err();
    assert!(e.to_string().contains("versions 1 to 2"), "{e}");
}

#[test]
fn conductors_by_name_or_index_of_refraction() {
    let s = parse(&scene(
        r#""gold": (conductor: "Au", roughness: 0.3),"#,
        "",
        "None",
    ))
    .unwrap();
    let gold = s.materials.iter().find(|m| m.name == "gold").unwrap();
    assert_eq!(
        gold.metallic, 1.0,
        "a conductor is a metal unless told otherwise"
    );
    let au = gold.conductor.unwrap();
    assert_eq!(au.eta, Vec3::new(0.143_036, 0.375_307, 1.442_05));
    // Its colour is its normal-incidence reflectance.
    assert!((gold.base_color - au.normal_reflectance()).length() < 1e-6);
    assert!(gold.multiscatter);
    let g = GpuScene::build(&s).unwrap();
    let gm = g.materials[s.materials.iter().position(|m| m.name == "gold").unwrap()];
    assert_eq!(gm.flags & MATERIAL_CONDUCTOR, MATERIAL_CONDUCTOR);
    assert_eq!(gm.flags & MATERIAL_SINGLE_SCATTER, 0);
    assert_eq!(gm.k, [3.983, 2.385_56, 1.603_36]);

    let s = parse(&scene(
        r#""m": (eta: (1.5, 1.0, 0.5), k: (3, 2, 1), metallic: 0.5, multiscatter: false),"#,
        "",
        "None",
    ))
    .unwrap();
    let m = s.materials.iter().find(|m| m.name == "m").unwrap();
    assert_eq!((m.metallic, m.multiscatter), (0.5, false));
    let g = GpuScene::build(&s).unwrap();
    let gm = g.materials[s.materials.iter().position(|m| m.name == "m").unwrap()];
    assert_eq!(gm.flags & MATERIAL_SINGLE_SCATTER, MATERIAL_SINGLE_SCATTER);
}

#[test]
fn bad_conductors_are_located_errors() {
    for (material, says) in [
        (
            r#""m": (conductor: "Unobtainium"),"#,
            "no conductor \"Unobtainium\" (known: Ag, Al, Au",
        ),
        (
            r#""m": (conductor: "Au", eta: (1, 1, 1), k: (1, 1, 1)),"#,
            "not both",
        ),
        (r#""m": (eta: (1, 1, 1)),"#, "`eta` needs `k`"),
        (r#""m": (k: (1, 1, 1)),"#, "`k` needs `eta`"),
        (
            r#""m": (eta: (0, 1, 1), k: (1, 1, 1)),"#,
            "must be positive",
        ),
        (
            r#""m": (conductor: "Au", metallic: 0),"#,
            "needs `metallic` > 0",
        ),
    ] {
        let e = parse(&scene(material, "", "None")).unwrap_err();
        let msg = e.to_string();
        assert!(
            msg.contains("material \"m\"") && msg.contains(says),
            "{msg}"
        );
        assert_eq!(e.pos.unwrap().line, 6, "{msg}");
    }
}

#[test]
fn point_spot_and_directional_lights() {
    let lights = r#"lights: [
        Point(position: (0, 2, 0), intensity: (1, 2, 3)),
        Spot(position: (0, 3, 0), target: (0, 0, 0), intensity: (4, 4, 4), cutoff_angle: 30),
        Directional(direction: (0, -2, 0), irradiance: (0.5, 0.5, 0.5)),
    ],"#;
    let s = parse(&scene("", lights, "None")).unwrap();
    assert_eq!(s.lights.len(), 3);
    match s.lights[1] {
        PunctualLight::Spot {
            axis, cutoff, beam, ..
        } => {
            assert!((axis - Vec3::NEG_Y).length() < 1e-6);
            assert!((cutoff - 30f32.to_radians()).abs() < 1e-6);
            // Mitsuba's default beam width: 3/4 of the cutoff.
            assert!((beam - 22.5f32.to_radians()).abs() < 1e-6);
        }
        l => panic!("{l:?}"),
    }
    let g = GpuScene::build(&s).unwrap();
    let flags: Vec<u32> = g.lights.iter().map(|l| l.flags).collect();
    assert_eq!(flags, [LIGHT_POINT, LIGHT_SPOT, LIGHT_DIRECTIONAL]);
    assert_eq!(g.lights[2].e1, [0.0, -1.0, 0.0]);
    // Power for selection: 4 pi I for the point light.
    let point_power =
        4.0 * std::f32::consts::PI * lumagraph_scene::luminance(Vec3::new(1.0, 2.0, 3.0));
    assert!((g.lights[0].power - point_power).abs() < 1e-4 * point_power);
}

#[test]
fn bad_lights_are_located_errors() {
    for (light, says) in [
        (
            "Point(position: (0, 1, 0), intensity: (-1, 1, 1))",
            "light 0 (Point): intensity",
        ),
        (
            "Spot(name: \"s\", position: (0, 1, 0), target: (0, 1, 0), intensity: (1, 1, 1))",
            "light \"s\": target",
        ),
        (
            "Spot(position: (0, 1, 0), target: (0, 0, 0), intensity: (1, 1, 1), cutoff_angle: 100)",
            "cutoff_angle",
        ),
        (
            "Spot(position: (0, 1, 0), target: (0, 0, 0), intensity: (1, 1, 1), cutoff_angle: 20, beam_width: 30)",
            "beam_width",
        ),
        (
            "Directional(direction: (0, 0, 0), irradiance: (1, 1, 1))",
            "direction",
        ),
    ] {
        let text = scene("", &format!("lights: [\n        {light},\n    ],"), "None");
        let e = parse(&text).unwrap_err();
        let msg = e.to_string();
        assert!(msg.contains(says), "{msg}");
        assert_eq!(e.pos.unwrap().line, 12, "{msg}");
    }
}

/// `tests/scenes/gltf_lights.gltf` holds the lights of `punctual_lights.ron` under a scaled,
/// translated parent node, in candela and lux: imported, they are the same lights.
#[test]
fn gltf_lights_import_as_the_scene_file_lights() {
    let from_gltf = Scene::load(&tests_dir().join("gltf_lights.ron")).unwrap();
    let from_ron = Scene::load(&tests_dir().join("punctual_lights.ron")).unwrap();
    assert_eq!(from_gltf.lights.len(), 3);
    for (a, b) in from_gltf.lights.iter().zip(&from_ron.lights) {
        let close = |x: Vec3, y: Vec3| (x - y).abs().max_element() < 1e-5;
        match (a, b) {
            (
                PunctualLight::Point {
                    position: p,
                    intensity: i,
                },
                PunctualLight::Point {
                    position: q,
                    intensity: j,
                },
            ) => assert!(close(*p, *q) && close(*i, *j), "{a:?} vs {b:?}"),
            (
                PunctualLight::Spot {
                    position: p,
                    axis: x,
                    intensity: i,
                    cutoff: c,
                    beam: w,
                },
                PunctualLight::Spot {
                    position: q,
                    axis: y,
                    intensity: j,
                    cutoff: d,
                    beam: v,
                },
            ) => assert!(
                close(*p, *q)
                    && close(*x, *y)
                    && close(*i, *j)
                    && (c - d).abs() < 1e-6
                    && (w - v).abs() < 1e-6,
                "{a:?} vs {b:?}"
            ),
            (
                PunctualLight::Directional {
                    direction: x,
                    irradiance: i,
                },
                PunctualLight::Directional {
                    direction: y,
                    irradiance: j,
                },
            ) => assert!(close(*x, *y) && close(*i, *j), "{a:?} vs {b:?}"),
            _ => panic!("{a:?} vs {b:?}"),
        }
    }
}

#[test]
fn export_writes_the_resolved_scene() {
    let s = Scene::load(&tests_dir().join("gltf_lights.ron")).unwrap();
    let g = GpuScene::build(&s).unwrap();
    let dir = std::env::temp_dir().join(format!("lumagraph-export-{}", std::process::id()));
    let written = lumagraph_scene::export::export(&s, &g, &dir).unwrap();
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("scene.json")).unwrap()).unwrap();
    assert_eq!(json["format"], "lumagraph-scene-export");
    assert_eq!(json["lights"].as_array().unwrap().len(), 3);
    assert_eq!(json["lights"][1]["type"], "spot");
    assert_eq!(json["spheres"].as_array().unwrap().len(), 2);
    let gold = json["materials"]
        .as_array()
        .unwrap()
        .iter()
        .find(|m| m["name"] == "gold")
        .unwrap();
    assert_eq!(gold["eta"][0].as_f64().unwrap() as f32, 0.143_036);
    // Every triangle is in exactly one OBJ file, flat triangles without normals.
    let triangles: usize = json["meshes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| {
            let obj = std::fs::read_to_string(dir.join(m["file"].as_str().unwrap())).unwrap();
            assert!(!obj.contains("vn "));
            obj.lines().filter(|l| l.starts_with("f ")).count()
        })
        .sum();
    assert_eq!(triangles, s.triangles.len());
    assert_eq!(written.len(), json["meshes"].as_array().unwrap().len() + 1);
    assert!(written.iter().all(|p| Path::new(p).is_file()));
    std::fs::remove_dir_all(&dir).unwrap();
}
