//! Scene files: syntax and semantic errors with positions, the Cornell box and furnace.

mod common;

use std::path::Path;

use glam::Vec3;
use lumagraph_scene::{
    Environment, ErrorKind, GpuScene, LIGHT_TWO_SIDED, NO_LIGHT, Scene, SceneError, luminance,
};

fn parse(text: &str) -> Result<Scene, SceneError> {
    Scene::from_ron(text, &common::assets())
}

const MINIMAL: &str = r#"(
    version: 1,
    camera: Perspective(position: (0, 0, 4), target: (0, 0, 0), fov_y: 40),
    materials: { "white": (base_color: (0.8, 0.8, 0.8)) },
    shapes: [
        Sphere(name: "ball", center: (0, 0, 0), radius: 1, material: "white"),
    ],
    render: (width: 64, height: 32),
)"#;

#[test]
fn minimal_scene_and_defaults() {
    let s = parse(MINIMAL).unwrap();
    assert_eq!(s.shapes.len(), 1);
    assert_eq!(s.settings.max_bounces, 20);
    assert_eq!(s.settings.spp, 1);
    assert_eq!(s.environment, Environment::None);
    let m = &s.materials[0];
    assert_eq!(
        (m.roughness, m.metallic, m.specular, m.ior),
        (0.5, 0.0, 0.5, 1.5)
    );
    assert!((s.camera.focus_distance - 4.0).abs() < 1e-6);
    let g = GpuScene::build(&s).unwrap();
    assert!((g.camera.aspect - 2.0).abs() < 1e-6);
    assert_eq!(g.camera.right, [1.0, 0.0, 0.0]);
}

#[test]
fn syntax_error_names_line_and_column() {
    let text = MINIMAL.replace("radius: 1,", "radius: 1,,");
    let e = parse(&text).unwrap_err();
    assert!(matches!(*e.kind, ErrorKind::Syntax(_)), "{e}");
    let pos = e.pos.unwrap();
    assert_eq!(pos.line, 6, "{e}");
    assert!(pos.col > 50, "{e}");
}

#[test]
fn unknown_field_is_refused_with_position() {
    let text = MINIMAL.replace("radius: 1,", "radius: 1, radios: 2,");
    let e = parse(&text).unwrap_err();
    let msg = e.to_string();
    assert!(msg.contains("radios"), "{msg}");
    assert_eq!(e.pos.unwrap().line, 6, "{msg}");
}

#[test]
fn file_errors_name_the_file() {
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR"));
    let path = dir.join("broken_scene.ron");
    std::fs::write(&path, MINIMAL.replace("fov_y: 40", "fov_y: 40,,")).unwrap();
    let e = Scene::load(&path).unwrap_err();
    let msg = e.to_string();
    assert!(msg.starts_with(&format!("{}:3:", path.display())), "{msg}");
    let e = Scene::load(Path::new("/nonexistent/scene.ron")).unwrap_err();
    assert!(matches!(*e.kind, ErrorKind::Io { .. }), "{e}");
}

#[test]
fn unknown_material_names_shape_and_position() {
    let text = MINIMAL.replace("material: \"white\"", "material: \"whte\"");
    let e = parse(&text).unwrap_err();
    let msg = e.to_string();
    assert!(
        matches!(*e.kind, ErrorKind::UnknownMaterial { .. }),
        "{msg}"
    );
    assert!(msg.contains("shape \"ball\""), "{msg}");
    assert!(msg.contains("\"whte\"") && msg.contains("white"), "{msg}");
    let pos = e.pos.unwrap();
    assert_eq!(pos.line, 6, "{msg}");
    let line = text.lines().nth(5).unwrap();
    assert_eq!(&line[pos.col - 1..pos.col + 5], "\"whte\"", "{msg}");
}

#[test]
fn semantic_errors_name_item() {
    let e = parse(&MINIMAL.replace("radius: 1", "radius: -1")).unwrap_err();
    assert!(e.to_string().contains("shape \"ball\": radius"), "{e}");
    assert_eq!(e.pos.unwrap().line, 6);
    let e =
        parse(&MINIMAL.replace("(0.8, 0.8, 0.8))", "(0.8, 0.8, 0.8), roughness: 2)")).unwrap_err();
    assert!(
        e.to_string().contains("material \"white\": roughness"),
        "{e}"
    );
    assert_eq!(e.pos.unwrap().line, 4);
    let e = parse(&MINIMAL.replace("version: 1", "version: 7")).unwrap_err();
    assert!(
        matches!(*e.kind, ErrorKind::Version { found: 7, .. }),
        "{e}"
    );
    let e = parse(&MINIMAL.replace("fov_y: 40", "fov_y: 190")).unwrap_err();
    assert!(e.to_string().contains("camera: fov_y"), "{e}");
}

fn cornell() -> Scene {
    Scene::load(&common::assets().join("cornell.ron")).unwrap()
}

#[test]
fn cornell_loads_with_36_triangles_and_2_lights() {
    let s = cornell();
    assert!(s.report.is_clean(), "{:?}", s.report);
    // 5 walls + light = 6 quads, 2 boxes × 6 faces = 12 quads: 18 quads, 36 triangles.
    assert_eq!(s.triangles.len(), 36);
    assert_eq!(s.shapes.len(), 0);
    assert_eq!(s.camera.position, Vec3::new(0.0, 0.0, 3.9));
    assert_eq!(s.camera.fov_y_deg, 39.3077);
    assert_eq!((s.settings.width, s.settings.height), (256, 256));
    assert_eq!(s.settings.max_bounces, 20);

    let g = GpuScene::build(&s).unwrap();
    assert_eq!(g.lights.len(), 2);
    assert_eq!(g.header.num_lights, 2);
    let emission = Vec3::new(18.387, 13.9873, 6.75357);
    let area = 0.46 * 0.38 / 2.0;
    let power = luminance(emission) * area * std::f32::consts::PI;
    for l in &g.lights {
        assert!((l.area - area).abs() < 1e-6, "{}", l.area);
        assert!(
            (l.power - power).abs() < 1e-4 * power,
            "{} {power}",
            l.power
        );
        assert_eq!(l.flags & LIGHT_TWO_SIDED, 0);
        assert_eq!(Vec3::from(l.emission), emission);
        // The light faces down.
        let n = Vec3::from(l.e1).cross(Vec3::from(l.e2)).normalize();
        assert!((n - Vec3::NEG_Y).length() < 1e-6, "{n}");
        // Its triangle points back at it, and its material is `white` + emission.
        let shading = g.tri_shading[l.prim as usize];
        assert_eq!(g.lights[shading.light as usize], *l);
        let m = &s.materials[shading.material as usize];
        assert!(m.name.starts_with("white"));
        assert_eq!(m.base_color, Vec3::new(0.885809, 0.698859, 0.666422));
    }
    let non_lights = g.tri_shading.iter().filter(|t| t.light == NO_LIGHT).count();
    assert_eq!(non_lights, 34);
    assert!((g.header.total_light_power - 2.0 * power).abs() < 1e-3);
    assert_eq!(g.light_alias.len(), 2);
    // luminance 14.4 × 0.1748 × π.
    assert!((2.0 * power - 7.908).abs() < 1e-2, "{}", 2.0 * power);
}

#[test]
fn cornell_box_transform_matches_world_quads() {
    // Mitsuba `cube` with the small box's to_world must give the same faces as the
    // reference world quads written in cornell.ron.
    let text = r#"(
        version: 1,
        camera: Perspective(position: (0, 0, 3.9), target: (0, 0, 0), fov_y: 39.3077),
        materials: { "white": () },
        shapes: [
            Box(material: "white", transform: (matrix: [
                [0.286891427, 0, -0.0877115114, 0.335],
                [0, 0.3, 0, -0.7],
                [0.0877115114, 0, 0.286891427, 0.38],
                [0, 0, 0, 1],
            ])),
            Rectangle(material: "white", transform: (matrix: [
                [0.23, 0, 0, 0], [0, 0, -0.19, 0.99], [0, 0.19, 0, 0.01], [0, 0, 0, 1],
            ])),
        ],
        render: (width: 8, height: 8),
    )"#;
    let s = parse(text).unwrap();
    let c = cornell();
    let small_box: Vec<_> = c.triangles[12..24].to_vec();
    let light: Vec<_> = c.triangles[10..12].to_vec();
    let key = |t: &lumagraph_scene::Triangle| {
        let centroid = (t.positions[0] + t.positions[1] + t.positions[2]) / 3.0;
        (centroid, t.normal(), t.area())
    };
    for (ours, reference) in [
        (&s.triangles[..12], &small_box[..]),
        (&s.triangles[12..], &light[..]),
    ] {
        // Same faces: every quad's outward normal and total area match one of the reference.
        for t in ours {
            let (_, n, _) = key(t);
            let same_face: f32 = reference
                .iter()
                .filter(|r| (key(r).1 - n).length() < 1e-5)
                .map(lumagraph_scene::Triangle::area)
                .sum();
            let ours_face: f32 = ours
                .iter()
                .filter(|o| (key(o).1 - n).length() < 1e-5)
                .map(lumagraph_scene::Triangle::area)
                .sum();
            assert!(
                (same_face - ours_face).abs() < 1e-5,
                "{n}: {same_face} vs {ours_face}"
            );
        }
    }
    // And the same corner positions.
    for (ours, reference) in [
        (&s.triangles[..12], &small_box[..]),
        (&s.triangles[12..], &light[..]),
    ] {
        for t in ours {
            for p in t.positions {
                assert!(
                    reference
                        .iter()
                        .flat_map(|r| r.positions)
                        .any(|q| (q - p).length() < 1e-5),
                    "{p}"
                );
            }
        }
    }
}

#[test]
fn furnace_loads() {
    let s = Scene::load(&common::assets().join("furnace.ron")).unwrap();
    assert_eq!(s.shapes.len(), 1);
    assert_eq!(s.shapes[0].radius, 1.0);
    assert_eq!(s.environment, Environment::Constant([1.0; 3]));
    assert_eq!(s.camera.position, Vec3::new(0.0, 0.0, 4.0));
    assert_eq!(s.camera.fov_y_deg, 40.0);
    let m = &s.materials[s.shapes[0].material as usize];
    assert_eq!(m.base_color, Vec3::ONE);
    let g = GpuScene::build(&s).unwrap();
    assert_eq!(g.header.num_shapes, 1);
    assert_eq!(g.lights.len(), 0);
    assert_eq!(g.bvh_nodes.len(), 1);
}

#[test]
fn transforms_and_emission_overrides() {
    let text = r#"(
        version: 1,
        camera: Perspective(position: (0, 0, 4), target: (0, 0, 0), fov_y: 40),
        materials: { "m": (base_color: (0.5, 0.5, 0.5)) },
        shapes: [
            Rectangle(name: "lamp", material: "m", emission: (1, 2, 3), two_sided: true,
                transform: (scale: (2, 1, 1), rotate: [(axis: (1, 0, 0), degrees: 90)],
                            translate: (0, 5, 0))),
            Sphere(name: "sun", center: (0, 10, 0), radius: 0.5, material: "m", emission: (4, 4, 4)),
        ],
        render: (width: 8, height: 8),
    )"#;
    let s = parse(text).unwrap();
    assert_eq!(s.materials.len(), 3);
    let t = &s.triangles[0];
    // +z rotated 90° about x is -y.
    assert!((t.normal() - Vec3::NEG_Y).length() < 1e-6, "{}", t.normal());
    assert!((t.positions.iter().map(|p| p.y).sum::<f32>() / 3.0 - 5.0).abs() < 1e-6);
    let g = GpuScene::build(&s).unwrap();
    assert_eq!(g.lights.len(), 3);
    let rect_area: f32 = g
        .lights
        .iter()
        .filter(|l| l.flags & LIGHT_TWO_SIDED != 0)
        .map(|l| l.area)
        .sum();
    assert!((rect_area - 8.0).abs() < 1e-5);
    let total: f32 = g.lights.iter().map(|l| l.power).sum();
    assert!((total - g.header.total_light_power).abs() < 1e-3);
}

#[test]
fn gltf_camera_from_mesh_shape() {
    let text = r#"(
        version: 1,
        camera: Gltf(shape: "box"),
        shapes: [ Mesh(name: "box", path: "CornellBox/CornellBox.gltf", transform: (scale: (2, 2, 2))) ],
        render: (width: 8, height: 8),
    )"#;
    let s = parse(text).unwrap();
    assert!(
        (s.camera.position - Vec3::new(0.556, 0.546, -1.6)).length() < 1e-5,
        "{:?}",
        s.camera
    );
    assert!((s.camera.forward - Vec3::Z).length() < 1e-6);
    assert!((s.camera.fov_y_deg - 39.3077).abs() < 1e-3);
    let e =
        parse(&text.replace("Gltf(shape: \"box\")", "Gltf(shape: \"box\", index: 3)")).unwrap_err();
    assert!(e.to_string().contains("no camera 3"), "{e}");
}

#[test]
fn alias_table_reproduces_weights() {
    let w = [1.0, 2.0, 3.0, 4.0, 0.0, 10.0];
    let table = lumagraph_scene::alias_table(&w);
    let n = w.len() as f32;
    let total: f32 = w.iter().sum();
    for (i, &wi) in w.iter().enumerate() {
        let mut p = table[i].prob / n;
        for e in &table {
            if e.other as usize == i {
                p += (1.0 - e.prob) / n;
            }
        }
        // Entries kept with probability 1 point at themselves and add nothing.
        if table[i].other as usize == i {
            p -= (1.0 - table[i].prob) / n;
        }
        assert!((p - wi / total).abs() < 1e-6, "{i}: {p} vs {}", wi / total);
    }
}

#[test]
fn autofocus_focuses_on_the_image_center() {
    let text = r#"(
        version: 1,
        camera: Perspective(position: (0, 0, 5), target: (0, 0, -10), fov_y: 30, aperture_radius: 0.1, autofocus: true),
        materials: { "m": (base_color: (0.5, 0.5, 0.5)) },
        shapes: [ Sphere(center: (0, 0, 0), radius: 1, material: "m") ],
        render: (width: 8, height: 8),
    )"#;
    let scene = parse(text).unwrap();
    let gpu = lumagraph_scene::GpuScene::build(&scene).unwrap();
    assert!(
        (gpu.camera.focus_distance - 4.0).abs() < 1e-5,
        "{}",
        gpu.camera.focus_distance
    );
    // Without autofocus: the distance to the target.
    let plain = parse(&text.replace("autofocus: true", "autofocus: false")).unwrap();
    let gpu = lumagraph_scene::GpuScene::build(&plain).unwrap();
    assert!((gpu.camera.focus_distance - 15.0).abs() < 1e-5);
}
