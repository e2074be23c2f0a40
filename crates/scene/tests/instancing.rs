//! Instanced meshes: loading (`Mesh(instances: …)`, glTF meshes placed several times), the
//! `instancing` choice, and the two-level traversal of the CPU mirror against the same scene
//! with its instances copied, ray by ray.

mod common;

use glam::Vec3;
use lumagraph_scene::traverse::{Hit, Ray, intersect_within, occluded, place_triangle};
use lumagraph_scene::{ErrorKind, GpuScene, Instancing, NO_INSTANCE, Scene};

/// The sphere grid (55 200 triangles) placed 7 times: moved, turned, scaled unevenly, and
/// mirrored; with a sphere and a quad of the scene's own.
fn scene_text(instancing: &str) -> String {
    format!(
        r#"(
    version: 2,
    camera: Perspective(position: (0, 0, 30), target: (0, 0, 0), up: (0, 1, 0), fov_y: 40),
    materials: {{ "grey": (base_color: (0.5, 0.5, 0.5)) }},
    shapes: [
        Mesh(name: "grid", path: "SphereGrids/SphereGrid_MetalRough.gltf", instances: [
            (),
            (translate: (7, 0, 0)),
            (translate: (-7, 1, 0), rotate: [(axis: (0, 1, 0), degrees: 30)]),
            (translate: (0, 7, -3), scale: (1, 2, 0.5)),
            (translate: (0, -7, 2), scale: (-1, 1, 1)),
            (translate: (1000, 0, 0)),
            (matrix: [[0, -1, 0, 3], [1, 0, 0, -3], [0, 0, 1, 4], [0, 0, 0, 1]]),
        ]),
        Sphere(center: (3, 3, 3), radius: 1.5, material: "grey"),
        Quad(corners: [(-20, -20, -8), (20, -20, -8), (20, 20, -8), (-20, 20, -8)], material: "grey"),
    ],
    render: (width: 8, height: 8),
    instancing: {instancing},
)"#
    )
}

fn load(instancing: &str) -> Scene {
    Scene::from_ron(&scene_text(instancing), &common::assets()).unwrap()
}

/// Where a hit is and which way its triangle faces, in world space.
fn world_point(g: &GpuScene, ray: &Ray, hit: &Hit) -> (Vec3, Vec3) {
    if hit.is_shape() || hit.inst == NO_INSTANCE {
        let t = &g.tri_positions[hit.index()];
        let n = if hit.is_shape() {
            Vec3::ZERO
        } else {
            Vec3::from(t.e1).cross(Vec3::from(t.e2)).normalize()
        };
        return (ray.origin + hit.t * ray.dir, n);
    }
    let inst = g.instance_at(hit.inst, 0);
    let (v0, e1, e2) = place_triangle(inst, &g.tri_positions[hit.index()]);
    let mirror = inst.flags & lumagraph_scene::INSTANCE_MIRROR != 0;
    let n = e1.cross(e2).normalize() * if mirror { -1.0 } else { 1.0 };
    (v0 + hit.u * e1 + hit.v * e2, n)
}

#[test]
fn instances_are_kept_or_copied_as_asked() {
    let on = load("On");
    assert_eq!(on.instanced.len(), 1);
    assert_eq!(on.instanced[0].transforms.len(), 7);
    let unique = on.instanced[0].triangles.len();
    assert_eq!(on.triangles.len(), 2, "the quad");
    let off = load("Off");
    assert!(off.instanced.is_empty());
    assert_eq!(off.triangles.len(), 2 + 7 * unique);
    // Auto copies what adds up to at most 4 M triangles.
    let auto = load("Auto");
    assert!(auto.instanced.is_empty());
    assert_eq!(auto.triangles.len(), off.triangles.len());

    let g = GpuScene::build(&on).unwrap();
    assert_eq!(g.instances.len(), 7);
    assert_eq!(g.tri_positions.len(), 2 + unique);
    assert_eq!(g.instanced_triangles, 7 * unique as u64);
    assert_ne!(g.header.features & lumagraph_scene::FEATURE_INSTANCES, 0);
    let flat = GpuScene::build(&off).unwrap();
    assert_eq!(flat.header.features & lumagraph_scene::FEATURE_INSTANCES, 0);
    println!(
        "instanced: {} triangles, {} nodes; copied: {} triangles, {} nodes",
        g.tri_positions.len(),
        g.bvh_nodes.len(),
        flat.tri_positions.len(),
        flat.bvh_nodes.len()
    );
}

/// 20 000 random rays (half aimed at the instances) through the two-level BVH and through
/// the copies: the same hits or misses, at the same distance (1e-5 of the distance and the
/// origin's coordinates) and point, on
/// surfaces facing the same way. Where a ray meets two triangles at one distance (an edge),
/// either may be reported: the point and distance must still agree. Occlusion agrees too.
#[test]
fn instanced_traversal_finds_what_the_copies_give() {
    let g = GpuScene::build(&load("On")).unwrap();
    let flat = GpuScene::build(&load("Off")).unwrap();
    let mut rng = common::Pcg::new(7);
    let (mut hits, mut worst, mut differ) = (0, 0.0f32, 0);
    let n = 20_000;
    for k in 0..n {
        let origin = Vec3::new(
            rng.range(-15.0, 15.0),
            rng.range(-15.0, 15.0),
            rng.range(-10.0, 20.0),
        );
        let target = if k % 2 == 0 {
            Vec3::new(
                rng.range(-9.0, 9.0),
                rng.range(-9.0, 9.0),
                rng.range(-3.0, 3.0),
            )
        } else {
            Vec3::new(
                rng.range(-30.0, 30.0),
                rng.range(-30.0, 30.0),
                rng.range(-30.0, 30.0),
            )
        };
        let ray = Ray {
            origin,
            dir: (target - origin).normalize(),
        };
        let t_max = if k % 3 == 0 { 20.0 } else { f32::MAX };
        let a = intersect_within(&g, &ray, t_max);
        let b = intersect_within(&flat, &ray, t_max);
        assert_eq!(
            occluded(&g, &ray, t_max),
            occluded(&flat, &ray, t_max),
            "ray {k}: occlusion differs"
        );
        match (a, b) {
            (None, None) => {}
            (Some(a), Some(b)) => {
                hits += 1;
                // Relative to the coordinates involved: the copies' corners and the placed
                // ones round differently, by float steps of the coordinates.
                let rel = (a.t - b.t).abs() / (b.t + origin.abs().max_element());
                worst = worst.max(rel);
                assert!(rel < 1e-5, "ray {k}: t {} against {}", a.t, b.t);
                let (pa, na) = world_point(&g, &ray, &a);
                let (pb, nb) = world_point(&flat, &ray, &b);
                assert!(
                    pa.distance(pb) < 1e-4 * (1.0 + pb.abs().max_element()),
                    "ray {k}: point {pa} against {pb}"
                );
                assert_eq!(a.is_shape(), b.is_shape(), "ray {k}");
                if !a.is_shape() && na.dot(nb) < 0.999 {
                    differ += 1;
                }
            }
            (a, b) => panic!("ray {k}: {a:?} against {b:?}"),
        }
    }
    println!(
        "{hits} of {n} rays hit; distances within {worst:.1e} relative; {differ} on triangles \
         facing another way (ties at edges)"
    );
    assert!(hits > n / 4, "too few hits to mean anything: {hits}");
    // Ties at edges: a sphere-grid edge between two faces, met exactly, is rare.
    assert!(
        differ * 1000 <= hits,
        "{differ} of {hits} hits face another way"
    );
}

#[test]
fn copies_over_the_limit_are_refused_and_emitters_are_copied() {
    // 1000 placements of 55 200 triangles is 55.2 M, over the 50 M copies may make.
    let many: Vec<String> = (0..1000)
        .map(|i| format!("(translate: ({i}, 0, 0))"))
        .collect();
    let text = scene_text("Off").replacen(
        "instances: [",
        &format!("instances: [{},", many.join(", ")),
        1,
    );
    let err = Scene::from_ron(&text, &common::assets()).unwrap_err();
    assert!(
        matches!(&*err.kind, ErrorKind::TooManyInstancedTriangles(c) if c.instances == 1007),
        "{err}"
    );
    assert!(err.to_string().contains("instancing: On"), "{err}");
    // Kept as instances, the same scene loads with the mesh stored once.
    let on = Scene::from_ron(
        &text.replace("instancing: Off", "instancing: On"),
        &common::assets(),
    )
    .unwrap();
    assert_eq!(on.instanced[0].transforms.len(), 1007);

    // An emitting instanced mesh is copied: emitters are sampled in world space.
    let glow = scene_text("On").replacen(
        "Mesh(name: \"grid\",",
        "Mesh(name: \"grid\", emission: (1, 1, 1),",
        1,
    );
    let s = Scene::from_ron(&glow, &common::assets()).unwrap();
    assert!(s.instanced.is_empty());
    assert_eq!(s.triangles.len(), 2 + 7 * 55_200);
}

#[test]
fn gltf_meshes_placed_several_times_are_instances() {
    let path = common::assets().join("gltf-conformance/SimpleInstancing/SimpleInstancing.glb");
    let text = |instancing: Instancing| {
        format!(
            "(version: 2, camera: Perspective(position: (0, 0, 30), target: (0, 0, 0), fov_y: 40),
              shapes: [Mesh(path: {:?})], render: (width: 8, height: 8), instancing: {instancing:?})",
            path.to_string_lossy()
        )
    };
    let on = Scene::from_ron(&text(Instancing::On), &common::assets()).unwrap();
    let off = Scene::from_ron(&text(Instancing::Off), &common::assets()).unwrap();
    assert!(!on.instanced.is_empty());
    let placed: u64 = on
        .instanced
        .iter()
        .map(lumagraph_scene::InstancedMesh::copies)
        .sum();
    println!(
        "SimpleInstancing: {} meshes stored once for {placed} placed triangles",
        on.instanced.len()
    );
    assert_eq!(
        off.triangles.len() as u64,
        on.triangles.len() as u64 + placed
    );
    assert!(off.instanced.is_empty());
}

/// `export` writes instances as copies: the same OBJ triangles, group by group, as the
/// scene with its instances copied.
#[test]
fn export_writes_instances_as_copies() {
    let count = |instancing: &str| {
        let scene = load(instancing);
        let gpu = GpuScene::build(&scene).unwrap();
        let dir = tempfile::tempdir().unwrap();
        lumagraph_scene::export::export(&scene, &gpu, dir.path()).unwrap();
        let text = std::fs::read_to_string(dir.path().join("scene.json")).unwrap();
        let json: serde_json::Value = serde_json::from_str(&text).unwrap();
        let faces: usize = std::fs::read_dir(dir.path())
            .unwrap()
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|x| x == "obj"))
            .map(|p| {
                std::fs::read_to_string(p)
                    .unwrap()
                    .lines()
                    .filter(|l| l.starts_with("f "))
                    .count()
            })
            .sum();
        let listed: u64 = json["meshes"]
            .as_array()
            .unwrap()
            .iter()
            .map(|m| m["triangles"].as_u64().unwrap())
            .sum();
        (faces, listed)
    };
    let (on, off) = (count("On"), count("Off"));
    assert_eq!(on, off);
    assert_eq!(on.0, 2 + 7 * 55_200);
    assert_eq!(on.1, on.0 as u64);
}

/// An instance whose transform cannot be inverted (a glTF instance scaled by 0) or is not
/// finite is dropped with a warning naming its mesh; a mesh left with none is dropped.
#[test]
fn singular_instances_are_dropped_and_said() {
    let mut scene = load("On");
    scene.instanced[0]
        .transforms
        .push(glam::Mat4::from_scale(Vec3::new(1.0, 0.0, 1.0)));
    scene.instanced[0]
        .transforms
        .push(glam::Mat4::from_translation(Vec3::splat(f32::NAN)));
    scene.apply_instancing(Instancing::On).unwrap();
    assert_eq!(scene.instanced[0].transforms.len(), 7);
    assert!(
        scene
            .report
            .warnings
            .iter()
            .any(|w| w.contains("grid: 2 of its 9 instances dropped")),
        "{:?}",
        scene.report.warnings
    );
    scene.instanced[0].transforms.clear();
    scene.apply_instancing(Instancing::On).unwrap();
    assert!(scene.instanced.is_empty());
    GpuScene::build(&scene).unwrap();
}
