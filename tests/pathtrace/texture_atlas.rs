//! Textures live in an atlas (one 2D array texture of pages), so a scene's texels are not
//! bounded by one storage binding (128 MiB on lavapipe and many GPUs: the Crytek Sponza's
//! 195 MiB once failed with a bind-group error), and what does not fit a device is one
//! error naming the scene part, its size and the limit.

use crate::common;

use std::sync::Arc;

use glam::Vec2;
use lumagraph::graph::{Graph, Node};
use lumagraph::pathtrace::{check_scene_limits, library::compile};
use lumagraph::render::Resources;
use lumagraph::scene::texture::srgb_decode;
use lumagraph::scene::{GpuScene, Scene, Texture, Wrap};

/// A row of `n` unit quads facing the camera, each with its own material.
fn quads_scene(n: usize) -> Scene {
    let mut shapes = String::new();
    let mut materials = String::new();
    for i in 0..n {
        let x = i as f32 * 1.25 - (n as f32 - 1.0) * 0.625;
        materials.push_str(&format!(
            "\"m{i}\": (base_color: (1.0, 1.0, 1.0), roughness: 1.0, specular: 0.0),\n"
        ));
        shapes.push_str(&format!(
            "Quad(material: \"m{i}\", corners: [({:?}, -0.5, 0.0), ({:?}, -0.5, 0.0), ({:?}, 0.5, 0.0), ({:?}, 0.5, 0.0)]),\n",
            x - 0.5,
            x + 0.5,
            x + 0.5,
            x - 0.5
        ));
    }
    let width = 8 * n as u32;
    let text = format!(
        "(version: 2,
          camera: Perspective(position: (0.0, 0.0, 10.0), target: (0.0, 0.0, 0.0), fov_y: {:?}),
          materials: {{ {materials} }},
          shapes: [ {shapes} ],
          environment: Constant((1.0, 1.0, 1.0)),
          render: (width: {width}, height: 8, max_bounces: 1, spp: 1, seed: 0))",
        2.0 * (0.5f32 / 10.0).atan().to_degrees() * 1.25
    );
    Scene::from_ron(&text, &common::repo("assets")).unwrap()
}

/// A texture of one colour, `side`² texels.
fn constant(i: usize, side: u32, c: [u8; 4]) -> Texture {
    Texture {
        name: format!("constant {i}"),
        width: side,
        height: side,
        texels: vec![c; (side * side) as usize].into(),
        wrap: [Wrap::Repeat; 2],
        nearest: false,
        uv_set: 0,
        transform: lumagraph::scene::UvTransform::IDENTITY,
    }
}

/// The colour of texture `i`, distinct for every i below 4096.
fn colour(i: usize) -> [u8; 4] {
    [
        (i * 37 % 251) as u8,
        (i * 91 % 241) as u8,
        (i * 53 % 239) as u8,
        255,
    ]
}

/// Each quad's texture to its material, UVs over the quad; the first-hit albedo at each
/// quad's centre pixel against its texture's colour (sRGB decoded, as the shader does).
fn check_each_texture_where_it_belongs(n: usize, side: u32) {
    let mut scene = quads_scene(n);
    scene.textures = (0..n).map(|i| constant(i, side, colour(i))).collect();
    for m in &mut scene.materials {
        m.textures.base_color = m.name[1..].parse().unwrap();
    }
    for t in &mut scene.triangles {
        t.uvs = Some(t.positions.map(|p| Vec2::new(p.x.fract().abs(), 0.5 - p.y)));
    }
    let gpu = Arc::new(GpuScene::build(&scene).unwrap());
    let atlas = &gpu.atlas;
    println!(
        "{n} textures of {side}²: {} pages of {}², {:.1} MiB",
        atlas.pages,
        atlas.page_size,
        atlas.bytes() as f64 / 1048576.0
    );
    let Some(ctx) = common::gpu() else { return };
    let graph = Graph {
        nodes: vec![Node::new("pt", "PathTrace")],
        edges: Vec::new(),
        ..Graph::default()
    };
    let plan = compile(&graph, &["pt.albedo".to_owned()], Some(&gpu)).unwrap();
    let resources = Resources {
        scene: Some(Arc::clone(&gpu)),
        ..Resources::default()
    };
    let mut exec = lumagraph::pathtrace::library::executor(ctx, plan, &resources).unwrap();
    exec.run_frame().unwrap();
    let albedo = exec.read_port("pt.albedo").unwrap();
    let width = gpu.settings.width as usize;
    for i in 0..n {
        let px = albedo.pixels[4 * width + 8 * i + 4];
        let want = colour(i).map(|c| srgb_decode(f32::from(c) / 255.0));
        for c in 0..3 {
            assert!(
                (px[c] - want[c]).abs() < 1e-5,
                "quad {i}: albedo {px:?}, its texture's colour {want:?}"
            );
        }
    }
}

/// 40 textures of 256², each a page of its own (the page is as large as the largest
/// texture): addressing across 40 array layers.
#[test]
fn textures_on_many_pages_are_each_read_from_their_own() {
    check_each_texture_where_it_belongs(40, 256);
}

/// 36 textures of 1024² (144 MiB of texels, more than lavapipe's 128 MiB storage binding):
/// 36 pages of 1024², each texture read where it was placed.
#[test]
fn more_texels_than_a_storage_binding_holds_render() {
    check_each_texture_where_it_belongs(36, 1024);
}

/// A device too small for the scene: the error names the scene part, its size and the
/// limit, for the atlas's page side, its page count and a storage buffer.
#[test]
fn a_scene_over_a_device_limit_gets_one_named_error() {
    let mut scene = quads_scene(3);
    scene.textures = (0..3).map(|i| constant(i, 1024, colour(i))).collect();
    for (i, m) in scene.materials.iter_mut().enumerate() {
        m.textures.base_color = i as u32;
    }
    let gpu = GpuScene::build(&scene).unwrap();
    let limits = lumagraph::render::wgpu::Limits::default();
    check_scene_limits(&gpu, &limits, "a test device").unwrap();
    let small_page = lumagraph::render::wgpu::Limits {
        max_texture_dimension_2d: 512,
        ..limits.clone()
    };
    let e = check_scene_limits(&gpu, &small_page, "a test device")
        .unwrap_err()
        .to_string();
    println!("{e}");
    assert!(
        // Three pages of images and two of their mip levels.
        e.contains("scene part \"textures\": 3 textures in 5 pages of 1024x1024")
            && e.contains("largest 2D texture side of 512")
            && e.contains("a test device"),
        "{e}"
    );
    let few_layers = lumagraph::render::wgpu::Limits {
        max_texture_array_layers: 0,
        ..limits.clone()
    };
    let e = check_scene_limits(&gpu, &few_layers, "a test device")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("5 pages, over the adapter's 0 array layers"),
        "{e}"
    );
    let small_binding = lumagraph::render::wgpu::Limits {
        max_storage_buffer_binding_size: 256,
        ..limits
    };
    let e = check_scene_limits(&gpu, &small_binding, "a test device")
        .unwrap_err()
        .to_string();
    println!("{e}");
    assert!(
        e.contains("scene part \"BVH nodes\"") && e.contains("max_storage_buffer_binding_size 256"),
        "{e}"
    );
}
