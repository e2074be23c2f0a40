//! Scene format version 2: environment maps in Mitsuba's orientation (version 1 files
//! converted), conductors, the multiple-scattering switch, point, spot and directional
//! lights from the scene file and from glTF, and the export for other renderers.

mod common;

use std::path::{Path, PathBuf};

use glam::Vec3;
use lumagraph_scene::{
    Environment, GpuScene, MATERIAL_CONDUCTOR, MATERIAL_SINGLE_SCATTER, Scene, SceneError,
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
    let spot = &s.lights[1];
    assert!((Vec3::from(spot.e1) - Vec3::NEG_Y).length() < 1e-6);
    assert!((spot.params[0] - 30f32.to_radians()).abs() < 1e-6);
    // Mitsuba's default beam width: 3/4 of the cutoff.
    assert!((spot.params[1] - 22.5f32.to_radians()).abs() < 1e-6);
    let g = GpuScene::build(&s).unwrap();
    let kinds: Vec<&str> = g
        .lights
        .iter()
        .map(|l| lumagraph_scene::lights::kind_of(l).unwrap().name())
        .collect();
    assert_eq!(kinds, ["Point", "Spot", "Directional"]);
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
        (
            "Projector(position: (0, 1, 0), target: (1, 0, 0), irradiance: (1, 1, 1), fov: 180)",
            "fov: 180 must be in (0, 180) degrees",
        ),
        (
            "Projector(position: (0, 1, 0), target: (0, 0, 0), up: (0, 2, 0), irradiance: (1, 1, 1), fov: 30)",
            "up: must not be parallel to the axis",
        ),
        (
            "Projector(position: (0, 1, 0), target: (1, 0, 0), irradiance: (1, 1, 1))",
            "fov: is missing",
        ),
        (
            "Point(position: (0, 1), intensity: (1, 1, 1))",
            "position: must be three numbers",
        ),
        // An unknown kind, or a field its kind does not read, is refused as the file is
        // read, with the kinds or fields there are.
        (
            "Area(position: (0, 1, 0))",
            "unknown light `Area`, expected one of `Point`, `Spot`, `Directional`, `Projector`",
        ),
        (
            "Point(position: (0, 1, 0), intensity: (1, 1, 1), radius: 2)",
            "`radius`",
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
        let close =
            |x: [f32; 3], y: [f32; 3]| (Vec3::from(x) - Vec3::from(y)).abs().max_element() < 1e-5;
        assert_eq!(a.kind, b.kind, "{a:?} vs {b:?}");
        assert!(
            close(a.p0, b.p0) && close(a.e1, b.e1) && close(a.e2, b.e2),
            "{a:?} vs {b:?}"
        );
        assert!(close(a.emission, b.emission), "{a:?} vs {b:?}");
        assert!(close(a.params, b.params), "{a:?} vs {b:?}");
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
    assert_eq!(json["shapes"].as_array().unwrap().len(), 2);
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

/// `AlphaBlendModeTest` as a `Mesh`, reduced to diffuse materials or not.
fn alpha_blend_mode_test(diffuse: bool) -> Scene {
    parse(&format!(
        r#"(
    version: 2,
    camera: Perspective(position: (0, 1, 6), target: (0, 1, 0), fov_y: 40),
    shapes: [Mesh(name: "m", path: "gltf-conformance/AlphaBlendModeTest/AlphaBlendModeTest.glb", diffuse: {diffuse})],
    environment: Constant((1, 1, 1)),
    render: (width: 64, height: 64, max_bounces: 4, spp: 1, seed: 0),
)"#
    ))
    .unwrap()
}

#[test]
fn diffuse_meshes_keep_only_their_base_colour_and_opacity() {
    let full = alpha_blend_mode_test(false);
    let reduced = alpha_blend_mode_test(true);
    assert_eq!(full.materials.len(), reduced.materials.len());
    // The control: the file's materials have textures besides the base colour's.
    assert!(full.materials.iter().any(|m| {
        m.textures.all()[1..]
            .iter()
            .any(|&t| t != lumagraph_scene::NO_TEXTURE)
    }));
    for (f, r) in full.materials.iter().zip(&reduced.materials) {
        // The same image, at its own index: textures no material reads are left out.
        let name = |s: &Scene, t: u32| s.textures.get(t as usize).map(|t| t.name.clone());
        assert_eq!(
            name(&reduced, r.textures.base_color),
            name(&full, f.textures.base_color),
            "{}",
            f.name
        );
        assert!(
            r.textures.all()[1..]
                .iter()
                .all(|&t| t == lumagraph_scene::NO_TEXTURE),
            "{}",
            f.name
        );
        assert_eq!(
            (r.base_color, r.opacity, r.alpha_mode, r.two_sided),
            (f.base_color, f.opacity, f.alpha_mode, f.two_sided)
        );
        assert_eq!((r.metallic, r.specular, r.transmission), (0.0, 0.0, 0.0));
    }
    assert!(reduced.textures.len() < full.textures.len());
    for i in 0..reduced.textures.len() as u32 {
        assert!(reduced.materials.iter().any(|m| m.textures.base_color == i));
    }
}

#[test]
fn export_writes_base_colour_textures_texture_coordinates_and_cut_outs() {
    use lumagraph_scene::AlphaMode;
    let s = alpha_blend_mode_test(true);
    let g = GpuScene::build(&s).unwrap();
    let dir = tempfile::tempdir().unwrap();
    lumagraph_scene::export::export(&s, &g, dir.path()).unwrap();
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("scene.json")).unwrap())
            .unwrap();
    let materials = json["materials"].as_array().unwrap();
    let mut masks = 0;
    for (i, (m, out)) in s.materials.iter().zip(materials).enumerate() {
        assert_eq!(out["other_textures"].as_array().unwrap().len(), 0);
        let Some(t) = s.textures.get(m.textures.base_color as usize) else {
            assert!(out["base_color_texture"].is_null());
            continue;
        };
        // The base colour texture's RGB, byte for byte.
        let file = out["base_color_texture"]["file"].as_str().unwrap();
        let png = image::open(dir.path().join(file)).unwrap().to_rgb8();
        assert_eq!((png.width(), png.height()), (t.width, t.height));
        assert!(
            png.pixels()
                .zip(t.texels.iter())
                .all(|(p, q)| p.0 == q[..3])
        );
        // A mask's opacity: cut out or not, texel by texel, as the path tracer tests it.
        if let AlphaMode::Mask { cutoff } = m.alpha_mode {
            masks += 1;
            assert_eq!(out["alpha_mode"], "mask");
            let file = out["opacity_texture"]["file"].as_str().unwrap();
            let png = image::open(dir.path().join(file)).unwrap().to_luma8();
            let (mut cut, mut kept) = (0, 0);
            for (p, q) in png.pixels().zip(t.texels.iter()) {
                let keep = f32::from(q[3]) / 255.0 * m.opacity >= cutoff;
                assert_eq!(p.0[0], if keep { 255 } else { 0 }, "material {i}");
                if keep { kept += 1 } else { cut += 1 }
            }
            assert!(cut > 0 && kept > 0, "material {i}: {cut} cut, {kept} kept");
        }
    }
    assert!(masks > 0, "no mask material: the test checks nothing");
    // Texture coordinates: OBJ's V up, the texture's transform applied; one per corner.
    let mut checked = 0;
    for mesh in json["meshes"].as_array().unwrap() {
        if !mesh["uvs"].as_bool().unwrap() {
            continue;
        }
        let obj = std::fs::read_to_string(dir.path().join(mesh["file"].as_str().unwrap())).unwrap();
        let vt: Vec<[f32; 2]> = obj
            .lines()
            .filter_map(|l| l.strip_prefix("vt "))
            .map(|l| {
                let mut w = l.split(' ').map(|x| x.parse::<f32>().unwrap());
                [w.next().unwrap(), w.next().unwrap()]
            })
            .collect();
        let material = mesh["material"].as_u64().unwrap() as u32;
        let first = s.triangles.iter().find(|t| t.material == material).unwrap();
        let tex = &s.textures[s.materials[material as usize].textures.base_color as usize];
        for (k, uv) in first.uvs.unwrap().iter().enumerate() {
            let uv = tex.transform.apply(*uv);
            assert_eq!(vt[k], [uv.x, 1.0 - uv.y]);
        }
        assert_eq!(vt.len(), 3 * mesh["triangles"].as_u64().unwrap() as usize);
        checked += 1;
    }
    assert!(checked > 0);
}
