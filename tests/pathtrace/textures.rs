//! glTF textures: decoding, tangents, extensions (CPU) and their use by the path tracer and
//! the G-buffer (GPU). Scenes are generated here: small glTF files whose buffers and PNGs are
//! data URIs, buffer views or files next to them, written into a temporary folder.
//!
//! GPU checks compare the first-hit AOVs (through pixel centers) with the CPU mirror of the
//! shader's sampling (`lumagraph_scene::texture`) at the UV of a CPU ray cast over the same
//! flattened scene; the tolerances and what was measured are stated at each test.

use crate::common;
use lumagraph::pathtrace::specialize::Tracing;

use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{Vec2, Vec3, Vec4};
use lumagraph::graph::{Graph, Node, ParamValue};
use lumagraph::pathtrace::library::compile;
use lumagraph::render::Resources;
use lumagraph::render::cpu::Image;
use lumagraph::scene::texture::{Texture, srgb_decode, triangle_tangents};
use lumagraph::scene::{GpuScene, NO_TEXTURE, Ray, Scene, UvTransform, Wrap};

// ---------------------------------------------------------------- glTF generation

fn base64(bytes: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for c in bytes.chunks(3) {
        let n = (u32::from(c[0]) << 16)
            | (u32::from(*c.get(1).unwrap_or(&0)) << 8)
            | u32::from(*c.get(2).unwrap_or(&0));
        for i in 0..4 {
            if i <= c.len() {
                out.push(A[(n >> (18 - 6 * i) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

fn png(w: u32, h: u32, px: &[[u8; 4]]) -> Vec<u8> {
    let img = image::RgbaImage::from_raw(w, h, px.concat()).unwrap();
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png).unwrap();
    out.into_inner()
}

/// How an image is stored.
#[derive(Clone, Copy, PartialEq)]
enum Embed {
    DataUri,
    File,
    View,
}

struct Img {
    w: u32,
    h: u32,
    px: Vec<[u8; 4]>,
    embed: Embed,
    /// glTF wrap codes (S, T) and whether magFilter is NEAREST.
    wrap: (u32, u32),
    nearest: bool,
}

impl Img {
    fn new(w: u32, h: u32, px: Vec<[u8; 4]>) -> Self {
        Self {
            w,
            h,
            px,
            embed: Embed::DataUri,
            wrap: (10497, 10497),
            nearest: false,
        }
    }

    fn constant(c: [u8; 4]) -> Self {
        Self::new(2, 2, vec![c; 4])
    }
}

/// A unit quad in the z = 0 plane with its lower-left corner at `origin`, facing +z; U grows
/// along +x from `uv0.x` to `uv1.x`, V grows along −y (image rows go down) from `uv0.y` at
/// the top edge to `uv1.y` at the bottom.
#[derive(Clone, Copy)]
struct Quad {
    origin: Vec2,
    z: f32,
    size: f32,
    uv0: Vec2,
    uv1: Vec2,
    material: usize,
    tangent: Option<Vec4>,
    /// A second UV set (`TEXCOORD_1`), laid out as `uv0`..`uv1` are.
    uv_1: Option<(Vec2, Vec2)>,
    /// Vertex colours (`COLOR_0`, linear RGBA) at the corners top-left, top-right,
    /// bottom-right, bottom-left.
    colors: Option<[[f32; 4]; 4]>,
}

impl Quad {
    /// Corner positions: top-left, top-right, bottom-right, bottom-left.
    fn corners(&self) -> [[f32; 3]; 4] {
        let (o, s, z) = (self.origin, self.size, self.z);
        [
            [o.x, o.y + s, z],
            [o.x + s, o.y + s, z],
            [o.x + s, o.y, z],
            [o.x, o.y, z],
        ]
    }

    fn at(x: f32, y: f32, material: usize) -> Self {
        Self {
            origin: Vec2::new(x, y),
            z: 0.0,
            size: 1.0,
            uv0: Vec2::ZERO,
            uv1: Vec2::ONE,
            material,
            tangent: None,
            uv_1: None,
            colors: None,
        }
    }
}

/// UVs at a quad's corners (top-left, top-right, bottom-right, bottom-left): `a` at the
/// top-left, `b` at the bottom-right.
fn uv_corners(a: Vec2, b: Vec2) -> [[f32; 2]; 4] {
    [[a.x, a.y], [b.x, a.y], [b.x, b.y], [a.x, b.y]]
}

#[derive(Default)]
struct Gltf {
    images: Vec<Img>,
    /// Material JSON objects; texture `i` is image `i` with its own sampler.
    materials: Vec<String>,
    quads: Vec<Quad>,
}

impl Gltf {
    /// Writes `name.gltf` (and its external files) into `dir`.
    fn write(&self, dir: &Path, name: &str) -> PathBuf {
        let mut bin: Vec<u8> = Vec::new();
        let mut views = Vec::new();
        let mut accessors = Vec::new();
        let mut push_view = |bin: &mut Vec<u8>, data: &[u8]| {
            while !bin.len().is_multiple_of(4) {
                bin.push(0);
            }
            views.push(format!(
                r#"{{"buffer":0,"byteOffset":{},"byteLength":{}}}"#,
                bin.len(),
                data.len()
            ));
            bin.extend_from_slice(data);
            views.len() - 1
        };
        let f32s = |v: &[f32]| -> Vec<u8> { v.iter().flat_map(|x| x.to_le_bytes()).collect() };
        let mut meshes = Vec::new();
        for q in &self.quads {
            let (o, s, z) = (q.origin, q.size, q.z);
            let pos = q.corners();
            let uv = uv_corners(q.uv0, q.uv1);
            let normals = [[0.0, 0.0, 1.0_f32]; 4];
            let mut attrs = Vec::new();
            let mut acc = |view: usize, count: usize, ty: &str, comp: u32, extra: &str| {
                accessors.push(format!(
                    r#"{{"bufferView":{view},"componentType":{comp},"count":{count},"type":"{ty}"{extra}}}"#
                ));
                accessors.len() - 1
            };
            let v = push_view(&mut bin, &f32s(&pos.concat()));
            let extra = format!(
                r#","min":[{},{},{z}],"max":[{},{},{z}]"#,
                o.x,
                o.y,
                o.x + s,
                o.y + s
            );
            attrs.push(format!(r#""POSITION":{}"#, acc(v, 4, "VEC3", 5126, &extra)));
            let v = push_view(&mut bin, &f32s(&normals.concat()));
            attrs.push(format!(r#""NORMAL":{}"#, acc(v, 4, "VEC3", 5126, "")));
            let v = push_view(&mut bin, &f32s(&uv.concat()));
            attrs.push(format!(r#""TEXCOORD_0":{}"#, acc(v, 4, "VEC2", 5126, "")));
            if let Some((a, b)) = q.uv_1 {
                let v = push_view(&mut bin, &f32s(&uv_corners(a, b).concat()));
                attrs.push(format!(r#""TEXCOORD_1":{}"#, acc(v, 4, "VEC2", 5126, "")));
            }
            if let Some(c) = q.colors {
                let v = push_view(&mut bin, &f32s(&c.concat()));
                attrs.push(format!(r#""COLOR_0":{}"#, acc(v, 4, "VEC4", 5126, "")));
            }
            if let Some(t) = q.tangent {
                let v = push_view(&mut bin, &f32s(&[t.to_array(); 4].concat()));
                attrs.push(format!(r#""TANGENT":{}"#, acc(v, 4, "VEC4", 5126, "")));
            }
            // Counter-clockwise seen from +z.
            let idx: Vec<u8> = [3u16, 2, 1, 3, 1, 0]
                .iter()
                .flat_map(|i| i.to_le_bytes())
                .collect();
            let v = push_view(&mut bin, &idx);
            let indices = acc(v, 6, "SCALAR", 5123, "");
            meshes.push(format!(
                r#"{{"primitives":[{{"attributes":{{{}}},"indices":{indices},"material":{}}}]}}"#,
                attrs.join(","),
                q.material
            ));
        }
        let mut images = Vec::new();
        let mut samplers = Vec::new();
        let mut textures = Vec::new();
        for (i, img) in self.images.iter().enumerate() {
            let data = png(img.w, img.h, &img.px);
            images.push(match img.embed {
                Embed::DataUri => format!(r#"{{"uri":"data:image/png;base64,{}"}}"#, base64(&data)),
                Embed::File => {
                    let file = format!("{name}_image{i}.png");
                    std::fs::write(dir.join(&file), &data).unwrap();
                    format!(r#"{{"uri":"{file}"}}"#)
                }
                Embed::View => {
                    let v = push_view(&mut bin, &data);
                    format!(r#"{{"bufferView":{v},"mimeType":"image/png"}}"#)
                }
            });
            let mag = if img.nearest { 9728 } else { 9729 };
            samplers.push(format!(
                r#"{{"magFilter":{mag},"wrapS":{},"wrapT":{}}}"#,
                img.wrap.0, img.wrap.1
            ));
            textures.push(format!(r#"{{"sampler":{i},"source":{i}}}"#));
        }
        let nodes: Vec<String> = (0..self.quads.len())
            .map(|i| format!(r#"{{"mesh":{i}}}"#))
            .collect();
        let list = |v: &[String]| v.join(",");
        let json = format!(
            r#"{{"asset":{{"version":"2.0"}},"extensionsUsed":["KHR_materials_transmission","KHR_materials_ior","KHR_materials_specular","KHR_materials_emissive_strength","KHR_materials_volume","KHR_texture_transform"],
"scene":0,"scenes":[{{"nodes":[{}]}}],"nodes":[{}],"meshes":[{}],"materials":[{}],
"textures":[{}],"images":[{}],"samplers":[{}],"accessors":[{}],"bufferViews":[{}],
"buffers":[{{"byteLength":{},"uri":"data:application/octet-stream;base64,{}"}}]}}"#,
            (0..self.quads.len())
                .map(|i| i.to_string())
                .collect::<Vec<_>>()
                .join(","),
            list(&nodes),
            list(&meshes),
            list(&self.materials),
            list(&textures),
            list(&images),
            list(&samplers),
            list(&accessors),
            list(&views),
            bin.len(),
            base64(&bin)
        );
        let path = dir.join(format!("{name}.gltf"));
        std::fs::write(&path, json).unwrap();
        path
    }
}

/// A scene file around `gltf`: camera at `eye` looking at `target`, black environment
/// unless `env` is given.
fn scene_file(
    dir: &Path,
    gltf: &Path,
    eye: Vec3,
    target: Vec3,
    size: (u32, u32),
    extra: &str,
) -> PathBuf {
    let text = format!(
        "(version: 1,
  camera: Perspective(position: ({:?}, {:?}, {:?}), target: ({:?}, {:?}, {:?}), up: (0.0, 1.0, 0.0), fov_y: 40.0),
  shapes: [Mesh(name: \"m\", path: \"{}\"){extra}],
  render: (width: {}, height: {}, max_bounces: 2, spp: 1, seed: 7),
)",
        eye.x,
        eye.y,
        eye.z,
        target.x,
        target.y,
        target.z,
        gltf.file_name().unwrap().to_string_lossy(),
        size.0,
        size.1
    );
    let path = dir.join("scene.ron");
    std::fs::write(&path, text).unwrap();
    path
}

// ---------------------------------------------------------------- GPU helpers

/// `PathTrace` (color, albedo, normal) and `GBuffer` (albedo, normal) of `scene`.
fn render(scene: &Arc<GpuScene>, spp: i64) -> Option<[Image; 5]> {
    let ctx = common::gpu()?;
    let graph = Graph {
        nodes: vec![
            Node::new("gb", "GBuffer"),
            Node::new("pt", "PathTrace").with("samples_per_frame", ParamValue::Int(spp)),
        ],
        edges: Vec::new(),
        ..Graph::default()
    };
    let ports = [
        "pt.color",
        "pt.albedo",
        "pt.normal",
        "gb.albedo",
        "gb.normal",
    ];
    let keep: Vec<String> = ports.iter().map(|p| (*p).to_owned()).collect();
    let plan = compile(&graph, &keep, Some(scene)).unwrap();
    // BVH traversal, which the CPU's `hits` mirrors test for test: the inline intersection
    // of small scenes tests each quad as one parallelogram, with no crack along its diagonal
    // where the mirror's two triangle tests can both miss (a pixel of the many-textures
    // scene, x = y = 0.667 on a quad from (0, 0) to (1, 1), is such a crack).
    let resources = Resources {
        scene: Some(Arc::clone(scene)),
        ..Resources::default()
    }
    .with(Tracing {
        as_gpu_adapter: true,
        ..Tracing::default()
    });
    let mut exec = lumagraph::pathtrace::library::executor(ctx, plan, &resources).unwrap();
    exec.run_frame().unwrap();
    Some(ports.map(|p| exec.read_port(p).unwrap()))
}

/// The pinhole ray through the center of pixel `(x, y)`, as the shader makes it.
fn pixel_ray(g: &GpuScene, x: u32, y: u32) -> Ray {
    image_ray(g, Vec2::new(x as f32 + 0.5, y as f32 + 0.5))
}

/// The pinhole ray through image position `p` (in pixels from the top-left corner).
fn image_ray(g: &GpuScene, p: Vec2) -> Ray {
    common::image_ray(g, p)
}

/// The material and UV the CPU ray cast finds along `ray`.
fn hit_uv(g: &GpuScene, ray: &Ray) -> Option<(u32, Vec2)> {
    let hit = lumagraph::scene::intersect(g, ray)?;
    let uv = g.tri_texcoords[hit.prim as usize].uv(hit.u, hit.v);
    Some((
        g.tri_shading[hit.prim as usize].material,
        Vec2::new(uv.x, uv.y),
    ))
}

/// Per pixel: the material and UV the CPU ray cast finds through its center.
fn hits(g: &GpuScene) -> Vec<Option<(u32, Vec2)>> {
    let (w, h) = (g.settings.width, g.settings.height);
    (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .map(|(x, y)| hit_uv(g, &pixel_ray(g, x, y)))
        .collect()
}

/// Writes `g` into its own folder `name` under `dir` and flattens its scene: camera at
/// `eye` looking at the origin, `size` pixels.
fn flat_scene(dir: &Path, name: &str, g: &Gltf, eye: Vec3, size: (u32, u32)) -> GpuScene {
    let sub = dir.join(name);
    std::fs::create_dir_all(&sub).unwrap();
    let path = g.write(&sub, name);
    let scene = Scene::load(&scene_file(&sub, &path, eye, Vec3::ZERO, size, "")).unwrap();
    GpuScene::build(&scene).unwrap()
}

/// The `PathTrace` color of `g` at `spp` samples per pixel, or `None` without a GPU.
fn color(g: GpuScene, spp: i64) -> Option<Image> {
    let [color, ..] = render(&Arc::new(g), spp)?;
    Some(color)
}

/// Largest per-channel difference of `a` from `b` relative to `b` (floored at 1e-3), over
/// the pixels where `keep` holds, and the sum of `b` there.
fn max_rel_diff(a: &Image, b: &Image, keep: impl Fn(usize) -> bool) -> (f32, f64) {
    let mut worst = 0.0_f32;
    let mut sum = 0.0_f64;
    for (i, (p, q)) in a.pixels.iter().zip(&b.pixels).enumerate() {
        if !keep(i) {
            continue;
        }
        for ch in 0..3 {
            worst = worst.max((p[ch] - q[ch]).abs() / q[ch].abs().max(1e-3));
            sum += f64::from(q[ch]);
        }
    }
    (worst, sum)
}

fn temp() -> tempfile::TempDir {
    tempfile::tempdir().unwrap()
}

// ---------------------------------------------------------------- CPU tests

#[test]
fn wrap_modes_index_as_gltf_defines_them() {
    let n = 4;
    let idx = |w: Wrap| (-5..9).map(|i| w.index(i, n)).collect::<Vec<_>>();
    assert_eq!(
        idx(Wrap::Repeat),
        [3, 0, 1, 2, 3, 0, 1, 2, 3, 0, 1, 2, 3, 0]
    );
    assert_eq!(
        idx(Wrap::ClampToEdge),
        [0, 0, 0, 0, 0, 0, 1, 2, 3, 3, 3, 3, 3, 3]
    );
    assert_eq!(
        idx(Wrap::MirroredRepeat),
        [3, 3, 2, 1, 0, 0, 1, 2, 3, 3, 2, 1, 0, 0]
    );
}

#[test]
fn bilinear_sampling_interpolates_decoded_texels() {
    let t = Texture {
        name: "t".into(),
        width: 2,
        height: 1,
        texels: vec![[0, 0, 0, 255], [255, 128, 64, 0]].into(),
        wrap: [Wrap::ClampToEdge; 2],
        nearest: false,
        uv_set: 0,
        transform: lumagraph::scene::UvTransform::IDENTITY,
    };
    // At the texel centers: the texels themselves; half-way: the mean of the decoded values.
    let a = t.sample(Vec2::new(0.25, 0.5), true);
    let b = t.sample(Vec2::new(0.75, 0.5), true);
    assert_eq!(a, Vec4::new(0.0, 0.0, 0.0, 1.0));
    assert!(
        (b - Vec4::new(
            1.0,
            srgb_decode(128.0 / 255.0),
            srgb_decode(64.0 / 255.0),
            0.0
        ))
        .abs()
        .max_element()
            < 1e-7
    );
    let m = t.sample(Vec2::new(0.5, 0.5), true);
    assert!((m - 0.5 * (a + b)).abs().max_element() < 1e-6, "{m}");
    // Linear (not sRGB): the raw unorm values.
    let l = t.sample(Vec2::new(0.75, 0.5), false);
    assert!((l.y - 128.0 / 255.0).abs() < 1e-7);
}

#[test]
fn generated_tangents_are_orthonormal_and_follow_u() {
    // Pseudo-random triangles, UVs and vertex normals tilted up to ~35° off the face normal.
    let mut seed = 12345_u32;
    let mut rnd = || {
        seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        (seed >> 8) as f32 / (1u32 << 24) as f32 * 2.0 - 1.0
    };
    let mut worst = (0.0_f32, 0.0_f32);
    for _ in 0..1000 {
        let p = [0; 3].map(|_| Vec3::new(rnd(), rnd(), rnd()) * 3.0);
        let uv = [0; 3].map(|_| Vec2::new(rnd(), rnd()) * 2.0);
        let face = (p[1] - p[0]).cross(p[2] - p[0]);
        let uv_area = (uv[1] - uv[0]).perp_dot(uv[2] - uv[0]);
        if face.length() < 1e-2 || uv_area.abs() < 1e-2 {
            continue;
        }
        let n =
            [0; 3].map(|_| (face.normalize() + 0.5 * Vec3::new(rnd(), rnd(), rnd())).normalize());
        let t = triangle_tangents(p, n, uv);
        // dP/du and dP/dv of the triangle, solved independently.
        let m = glam::Mat2::from_cols(uv[1] - uv[0], uv[2] - uv[0]).inverse();
        let (e1, e2) = (p[1] - p[0], p[2] - p[0]);
        let dpdu = e1 * m.col(0).x + e2 * m.col(0).y;
        let dpdv = e1 * m.col(1).x + e2 * m.col(1).y;
        for k in 0..3 {
            let tk = t[k].truncate();
            worst.0 = worst
                .0
                .max(tk.dot(n[k]).abs())
                .max((tk.length() - 1.0).abs());
            // Along +U: the tangent is dP/du's part orthogonal to the normal.
            let want = (dpdu - n[k] * n[k].dot(dpdu)).normalize();
            worst.1 = worst.1.max((tk - want).length());
            assert!(t[k].w == 1.0 || t[k].w == -1.0);
            assert!(t[k].w * n[k].cross(tk).dot(dpdv) > 0.0, "handedness");
        }
    }
    println!(
        "orthonormality error {:.2e}, distance to +U {:.2e}",
        worst.0, worst.1
    );
    assert!(worst.0 < 1e-5 && worst.1 < 1e-3, "{worst:?}");
}

#[test]
fn khr_transmission_ior_specular_and_emissive_strength_are_read() {
    let dir = temp();
    let gltf = Gltf {
        images: vec![
            Img::constant([255, 255, 255, 255]),
            Img::constant([200, 100, 50, 255]),
        ],
        materials: vec![
            r#"{"name":"glassy","emissiveFactor":[1,0.5,0.25],
            "extensions":{"KHR_materials_transmission":{"transmissionFactor":0.7,"transmissionTexture":{"index":0}},
            "KHR_materials_ior":{"ior":1.33},
            "KHR_materials_specular":{"specularFactor":0.5,"specularColorFactor":[0.2,0.4,0.8],
              "specularTexture":{"index":0},"specularColorTexture":{"index":1}},
            "KHR_materials_emissive_strength":{"emissiveStrength":3}}}"#
                .into(),
        ],
        quads: vec![Quad::at(0.0, 0.0, 0)],
    }
    .write(dir.path(), "khr");
    let scene = Scene::load(&scene_file(
        dir.path(),
        &gltf,
        Vec3::Z * 3.0,
        Vec3::ZERO,
        (8, 8),
        "",
    ))
    .unwrap();
    let m = &scene.materials[0];
    assert_eq!(m.transmission, 0.7);
    assert_eq!(m.ior, 1.33);
    let f0 = ((1.33_f32 - 1.0) / (1.33 + 1.0)).powi(2);
    let want = 12.5 * f0 * 0.5;
    assert!((m.specular - want).abs() < 1e-6, "{} vs {want}", m.specular);
    assert_eq!(m.specular_color, Vec3::new(0.2, 0.4, 0.8));
    assert_eq!(m.emission, Vec3::new(3.0, 1.5, 0.75));
    let t = m.textures;
    assert_eq!((t.transmission, t.specular, t.specular_color), (0, 0, 1));
    assert_eq!((t.base_color, t.normal), (NO_TEXTURE, NO_TEXTURE));
    // Two textures decoded, each once.
    assert_eq!(scene.textures.len(), 2);
    assert_eq!(scene.textures[1].texels[0], [200, 100, 50, 255]);
}

#[test]
fn khr_materials_volume_is_an_absorbing_medium() {
    let dir = temp();
    let volume = |thickness: f32| {
        format!(
            r#"{{"name":"v{thickness}","extensions":{{"KHR_materials_transmission":{{"transmissionFactor":1}},
            "KHR_materials_volume":{{"thicknessFactor":{thickness},"attenuationDistance":2,"attenuationColor":[0.5,0.25,1]}}}}}}"#
        )
    };
    let gltf = Gltf {
        images: Vec::new(),
        materials: vec![volume(1.0), volume(0.0)],
        quads: vec![Quad::at(0.0, 0.0, 0), Quad::at(1.0, 0.0, 1)],
    }
    .write(dir.path(), "volume");
    let scene = Scene::load(&scene_file(
        dir.path(),
        &gltf,
        Vec3::Z * 3.0,
        Vec3::ZERO,
        (8, 8),
        "",
    ))
    .unwrap();
    // sigma_a = -ln(color) / distance; a thickness of 0 is thin-walled: no volume.
    let m = scene.materials[0]
        .medium
        .expect("a medium from KHR_materials_volume");
    let want = Vec3::new(0.5f32.ln(), 0.25f32.ln(), 0.0) / -2.0;
    assert!((m.sigma_a - want).abs().max_element() < 1e-6, "{m:?}");
    assert_eq!(m.sigma_s, Vec3::ZERO);
    assert_eq!(scene.materials[1].medium, None);
}

#[test]
fn missing_or_broken_images_name_the_material_and_image() {
    let dir = temp();
    let mut g = Gltf {
        images: vec![Img {
            embed: Embed::File,
            ..Img::constant([1, 2, 3, 255])
        }],
        materials: vec![
            r#"{"name":"painted","pbrMetallicRoughness":{"baseColorTexture":{"index":0}}}"#.into(),
        ],
        quads: vec![Quad::at(0.0, 0.0, 0)],
    };
    let path = g.write(dir.path(), "broken");
    std::fs::remove_file(dir.path().join("broken_image0.png")).unwrap();
    let scene = scene_file(dir.path(), &path, Vec3::Z * 3.0, Vec3::ZERO, (8, 8), "");
    let e = Scene::load(&scene).unwrap_err().to_string();
    println!("{e}");
    for want in [
        "broken.gltf",
        "material \"painted\"",
        "broken_image0.png",
        "cannot read",
    ] {
        assert!(e.contains(want), "{want:?} not in: {e}");
    }
    // Not a PNG at all.
    std::fs::write(dir.path().join("broken_image0.png"), b"not an image").unwrap();
    let e = Scene::load(&scene).unwrap_err().to_string();
    println!("{e}");
    assert!(
        e.contains("material \"painted\"") && e.contains("broken_image0.png"),
        "{e}"
    );
    // A data URI that does not decode.
    g.images[0].embed = Embed::DataUri;
    let path = g.write(dir.path(), "broken");
    let text = std::fs::read_to_string(&path).unwrap();
    let i = text.find("data:image/png;base64,").unwrap() + 22;
    std::fs::write(&path, format!("{}AAAA{}", &text[..i], &text[i + 8..])).unwrap();
    let e = Scene::load(&scene).unwrap_err().to_string();
    println!("{e}");
    assert!(
        e.contains("material \"painted\"") && e.contains("data URI"),
        "{e}"
    );
}

#[test]
fn plan_lists_textures_for_textured_scenes_only() {
    use lumagraph::pathtrace::specialize::{Feature, Features, PathTraceOptions};
    let opts = PathTraceOptions {
        specialize: true,
        cpu_adapter: true,
        aovs: false,
        adaptive: false,
        data_in_buffers: false,
        in_image_order: false,
        host_rays: false,
        ..PathTraceOptions::default()
    };
    let on = |path: &Path| {
        let scene = GpuScene::build(&Scene::load(path).unwrap()).unwrap();
        let f = Features::decide(&scene, opts);
        let t = f.on(Feature::Textures);
        println!("{}: {t} ({})", path.display(), f.reason(Feature::Textures));
        (t, scene.tri_texcoords.len(), scene.atlas.texels.len())
    };
    let (inc, tc, words) = on(&common::repo("assets/boxtextured.ron"));
    assert!(inc && tc == 12 && words > 4, "{inc} {tc} {words}");
    // Untextured: left out, and no texcoords or texels uploaded.
    assert_eq!(on(&common::repo("assets/cornell.ron")), (false, 0, 0));
    // Textured scenes keep materials and lights in their buffers, however small.
    let scene =
        GpuScene::build(&Scene::load(&common::repo("assets/boxtextured.ron")).unwrap()).unwrap();
    let f = Features::decide(&scene, opts);
    assert!(
        !f.on(Feature::InlineData) && f.reason(Feature::InlineData).contains("textured"),
        "{}",
        f.reason(Feature::InlineData)
    );
}

/// `Texture::triangle_mean` against a dense grid over the same triangles (the mean of the
/// bilinear texture at 2 001 × 2 001 lattice points per triangle): within 2 % of the
/// texture's range (it takes ~16 samples per texel, so a 1-texel-wide feature is resolved to
/// a few %); exactly the texel for a constant texture.
#[test]
fn triangle_mean_matches_a_dense_average() {
    let px: Vec<[u8; 4]> = (0..5 * 3)
        .map(|k| [(k * 53 % 256) as u8, (k * 97 % 256) as u8, 0, 255])
        .collect();
    let t = Texture {
        name: "t".into(),
        width: 5,
        height: 3,
        texels: px.into(),
        wrap: [Wrap::Repeat, Wrap::MirroredRepeat],
        nearest: false,
        uv_set: 0,
        transform: lumagraph::scene::UvTransform::IDENTITY,
    };
    let tris = [
        [Vec2::ZERO, Vec2::X, Vec2::Y],
        [
            Vec2::new(0.1, 0.2),
            Vec2::new(0.35, 0.3),
            Vec2::new(0.2, 0.6),
        ],
        [
            Vec2::new(-0.4, 1.3),
            Vec2::new(2.1, -0.2),
            Vec2::new(0.5, 0.9),
        ],
        [
            Vec2::new(0.3, 0.3),
            Vec2::new(0.31, 0.3),
            Vec2::new(0.3, 0.32),
        ],
    ];
    let mut worst = 0.0_f32;
    for uv in tris {
        let got = t.triangle_mean(uv, true);
        let m = 2000;
        let (mut sum, mut n) = (Vec4::ZERO, 0);
        for i in 0..=m {
            for j in 0..=m - i {
                let (a, b) = (i as f32 / m as f32, j as f32 / m as f32);
                sum += t.sample(uv[0] + a * (uv[1] - uv[0]) + b * (uv[2] - uv[0]), true);
                n += 1;
            }
        }
        let want = sum / n as f32;
        worst = worst.max((got - want).abs().max_element());
    }
    println!("triangle mean vs dense average: max difference {worst:.2e}");
    assert!(worst < 0.02, "{worst}");
    let c = Texture {
        texels: vec![[200, 100, 50, 255]; 15].into(),
        ..t
    };
    let want = c.fetch(0, 0, true);
    let got = c.triangle_mean(tris[2], true);
    assert!((got - want).abs().max_element() < 1e-6, "{got} vs {want}");
}

/// A `Mesh` with a `material` override keeps none of the file's textures: no texture is
/// decoded or uploaded and the shader leaves texturing out.
#[test]
fn material_override_drops_the_files_textures() {
    let dir = temp();
    let path = Gltf {
        images: vec![Img::constant([10, 20, 30, 255])],
        materials: vec![
            r#"{"pbrMetallicRoughness":{"baseColorTexture":{"index":0}},"emissiveTexture":{"index":0},"emissiveFactor":[1,1,1]}"#.into(),
        ],
        quads: vec![Quad::at(0.0, 0.0, 0)],
    }
    .write(dir.path(), "textured");
    let text = format!(
        "(version: 1,
  camera: Perspective(position: (0.5, 0.5, 3.0), target: (0.5, 0.5, 0.0), up: (0.0, 1.0, 0.0), fov_y: 40.0),
  materials: {{ \"plain\": (base_color: (0.2, 0.3, 0.4)) }},
  shapes: [Mesh(name: \"m\", path: \"{}\", material: \"plain\")],
  render: (width: 8, height: 8, spp: 1),
)",
        path.file_name().unwrap().to_string_lossy()
    );
    let file = dir.path().join("override.ron");
    std::fs::write(&file, text).unwrap();
    let scene = Scene::load(&file).unwrap();
    assert!(
        scene.textures.is_empty(),
        "{} textures",
        scene.textures.len()
    );
    assert!(scene.materials.iter().all(|m| !m.textures.any()));
    let g = GpuScene::build(&scene).unwrap();
    assert!(g.atlas.texels.is_empty() && g.tri_texcoords.is_empty() && g.lights.is_empty());
}

// ---------------------------------------------------------------- GPU tests

/// Albedo AOVs of 24 quads, each with its own texture (sizes 1×1 to 7×5; data URIs, buffer
/// views and files; all three wrap modes with UVs outside [0, 1]; one NEAREST), against the
/// CPU sampler at the CPU ray cast's UV.
///
/// Tolerance: `PathTrace`'s AOV and the CPU agree but for the f32 rounding of the two
/// intersection routines' barycentrics; 2e-3 per channel holds that with room (measured max
/// 6.0e-6 over 5 100 pixels). The G-buffer interpolates UVs in the rasterizer: against the
/// path tracer, ≥ 99 % of pixels within 1/255 (measured 100 %).
#[test]
fn albedo_of_many_textures_matches_cpu_sampling() {
    let dir = temp();
    let mut g = Gltf::default();
    let wraps = [
        (10497, 10497),
        (33071, 33071),
        (33648, 33648),
        (10497, 33648),
    ];
    for i in 0..24_usize {
        let (w, h) = (1 + (i as u32 * 3) % 7, 1 + (i as u32 * 2) % 5);
        let px = (0..w * h)
            .map(|k| {
                let k = k as usize + 7 * i;
                [
                    (k * 37 % 256) as u8,
                    (k * 91 % 256) as u8,
                    (k * 53 % 256) as u8,
                    255,
                ]
            })
            .collect();
        g.images.push(Img {
            embed: [Embed::DataUri, Embed::View, Embed::File][i % 3],
            wrap: wraps[i % 4],
            nearest: i == 5,
            ..Img::new(w, h, px)
        });
        g.materials.push(format!(
            r#"{{"pbrMetallicRoughness":{{"baseColorFactor":[0.9,0.8,1.0,1.0],"baseColorTexture":{{"index":{i}}}}}}}"#
        ));
        let mut q = Quad::at((i % 6) as f32 * 1.1 - 3.3, (i / 6) as f32 * 1.1 - 2.2, i);
        if i % 2 == 1 {
            q.uv0 = Vec2::new(-0.7, -0.4);
            q.uv1 = Vec2::new(1.8, 1.3);
        }
        g.quads.push(q);
    }
    let path = g.write(dir.path(), "many");
    let scene = Scene::load(&scene_file(
        dir.path(),
        &path,
        Vec3::new(-0.05, -0.05, 9.0),
        Vec3::new(-0.05, -0.05, 0.0),
        (144, 96),
        "",
    ))
    .unwrap();
    assert_eq!(scene.textures.len(), 24);
    let gpu = Arc::new(GpuScene::build(&scene).unwrap());
    let Some([_, pt_albedo, _, gb_albedo, _]) = render(&gpu, 1) else {
        return;
    };
    let mut per_material = [0_usize; 24];
    let mut worst = 0.0_f32;
    let mut gb_ok = 0_u32;
    let mut covered = 0_u32;
    for (i, hit) in hits(&gpu).iter().enumerate() {
        let pt = Vec4::from(pt_albedo.pixels[i]).truncate();
        let gb = Vec4::from(gb_albedo.pixels[i]).truncate();
        let Some((m, uv)) = *hit else {
            assert_eq!(pt, Vec3::ZERO, "pixel {i}: no hit on the CPU");
            continue;
        };
        let tex = &scene.textures[m as usize];
        if tex.nearest {
            // Skip pixels within 1e-3 texel of a texel edge, where rounding picks either side.
            let p = uv * Vec2::new(tex.width as f32, tex.height as f32);
            let edge = (p - p.round()).abs().min_element();
            if edge < 1e-3 {
                continue;
            }
        }
        let want = Vec3::new(0.9, 0.8, 1.0) * tex.sample(uv, true).truncate();
        worst = worst.max((pt - want).abs().max_element());
        per_material[m as usize] += 1;
        covered += 1;
        if (gb - pt).abs().max_element() <= 1.0 / 255.0 {
            gb_ok += 1;
        }
    }
    let gb_frac = f64::from(gb_ok) / f64::from(covered);
    println!(
        "PathTrace albedo vs CPU: max error {worst:.2e} over {covered} pixels; GBuffer within 1/255 of PathTrace: {:.2} %",
        100.0 * gb_frac
    );
    assert!(per_material.iter().all(|&n| n >= 50), "{per_material:?}");
    assert!(worst < 2e-3, "max albedo error {worst}");
    assert!(gb_frac >= 0.99, "GBuffer albedo agrees on {gb_frac}");
}

/// How a base colour texture is read: the `KHR_texture_transform` JSON, the transform it
/// must become, the coordinate set, whether the quad has a second set, and whether it has
/// vertex colours.
type ReadCase = (&'static str, UvTransform, u32, bool, bool);

/// Vertex colours of the coloured quads (linear RGBA, corners as in [`Quad::colors`]).
const QUAD_COLORS: [[f32; 4]; 4] = [
    [1.0, 0.2, 0.1, 1.0],
    [0.1, 0.9, 0.3, 1.0],
    [0.2, 0.3, 1.0, 1.0],
    [0.9, 0.9, 0.05, 1.0],
];

/// The 12 ways of reading one 4×4 texture of distinct texels, a quad each.
fn read_cases() -> (Gltf, [ReadCase; 12]) {
    let mut g = Gltf::default();
    let px: Vec<[u8; 4]> = (0..16_u32)
        .map(|k| {
            [
                (k * 16) as u8,
                (255 - k * 15) as u8,
                ((k * 7) % 16 * 16) as u8,
                255,
            ]
        })
        .collect();
    g.images.push(Img::new(4, 4, px));
    let rot = std::f32::consts::FRAC_PI_8;
    let id = [1.0, 1.0];
    let cases: [ReadCase; 12] = [
        (
            r#"{"offset":[0.5,0.0]}"#,
            UvTransform::khr([0.5, 0.0], 0.0, id),
            0,
            false,
            false,
        ),
        (
            r#"{"offset":[0.25,-0.5]}"#,
            UvTransform::khr([0.25, -0.5], 0.0, id),
            0,
            false,
            false,
        ),
        (
            r#"{"rotation":0.39269908}"#,
            UvTransform::khr([0.0; 2], rot, id),
            0,
            false,
            false,
        ),
        (
            r#"{"scale":[1.5,0.75]}"#,
            UvTransform::khr([0.0; 2], 0.0, [1.5, 0.75]),
            0,
            false,
            false,
        ),
        (
            r#"{"offset":[-0.2,-0.1],"rotation":0.3,"scale":[1.5,1.5]}"#,
            UvTransform::khr([-0.2, -0.1], 0.3, [1.5, 1.5]),
            0,
            false,
            false,
        ),
        ("", UvTransform::IDENTITY, 1, true, false),
        (
            r#"{"rotation":1.0}"#,
            UvTransform::khr([0.0; 2], 1.0, id),
            1,
            true,
            false,
        ),
        // The transform's texCoord overrides the reference's.
        (
            r#"{"texCoord":1,"scale":[2.0,2.0]}"#,
            UvTransform::khr([0.0; 2], 0.0, [2.0, 2.0]),
            1,
            true,
            false,
        ),
        ("", UvTransform::IDENTITY, 0, false, true),
        ("", UvTransform::IDENTITY, 0, true, true),
        (
            r#"{"offset":[0.1,0.2],"rotation":-0.7}"#,
            UvTransform::khr([0.1, 0.2], -0.7, id),
            1,
            true,
            true,
        ),
        ("", UvTransform::IDENTITY, 0, false, true),
    ];
    for (i, (ext, _, set, second, colored)) in cases.iter().enumerate() {
        // The reference's own texCoord is 1 only where the set comes from it, not the
        // transform.
        let own = u32::from(*set == 1 && !ext.contains("texCoord"));
        let ext = if ext.is_empty() {
            String::new()
        } else {
            format!(r#","extensions":{{"KHR_texture_transform":{ext}}}"#)
        };
        g.materials.push(format!(
            r#"{{"pbrMetallicRoughness":{{"baseColorFactor":[0.9,0.8,1.0,1.0],"baseColorTexture":{{"index":0,"texCoord":{own}{ext}}}}}}}"#
        ));
        let mut q = Quad::at((i % 4) as f32 * 1.1 - 2.2, (i / 4) as f32 * 1.1 - 1.65, i);
        q.uv0 = Vec2::new(-0.3, -0.2);
        q.uv1 = Vec2::new(1.4, 1.1);
        if *second {
            q.uv_1 = Some((Vec2::new(0.9, -0.6), Vec2::new(-0.4, 1.7)));
        }
        if *colored {
            q.colors = Some(QUAD_COLORS);
        }
        g.quads.push(q);
    }
    (g, cases)
}

/// The file's vertex colour of quad `q` ([`QUAD_COLORS`]) at point `p` on it: linear over
/// each of its triangles.
fn file_colour(q: &Quad, p: Vec3) -> Vec4 {
    // s from the left edge, t down from the top edge, in [0, 1].
    let (s, t) = (
        (p.x - q.origin.x) / q.size,
        (q.origin.y + q.size - p.y) / q.size,
    );
    // Corners 0 top-left, 1 top-right, 2 bottom-right, 3 bottom-left; the triangles
    // (3, 1, 0) (s + t ≤ 1) and (3, 2, 1).
    let c = |k: usize| Vec4::from(QUAD_COLORS[k]);
    if s + t <= 1.0 {
        c(0) + s * (c(1) - c(0)) + t * (c(3) - c(0))
    } else {
        c(2) + (1.0 - s) * (c(3) - c(2)) + (1.0 - t) * (c(1) - c(2))
    }
}

/// Albedo AOVs of 12 quads whose base colour textures are read through
/// `KHR_texture_transform`s (offset, rotation, scale, and a `texCoord` override), from the
/// second UV set (`TEXCOORD_1`), and multiplied by vertex colours (`COLOR_0`), alone and
/// together, against the CPU: the scene's texture (its transform checked against the
/// file's numbers) sampled at its own coordinates, times the factor and the interpolated
/// vertex colour (8-bit stored: checked within 1 % of the file's linear colours).
///
/// Tolerances as in `albedo_of_many_textures_matches_cpu_sampling`: 2e-3 per channel for
/// `PathTrace` (measured below 1e-5), ≥ 99 % of pixels within 1/255 for the `GBuffer`.
#[test]
fn texture_transforms_second_uv_sets_and_vertex_colours_match_cpu() {
    let dir = temp();
    let (g, cases) = read_cases();
    let path = g.write(dir.path(), "transforms");
    let scene = Scene::load(&scene_file(
        dir.path(),
        &path,
        Vec3::new(-0.05, -0.05, 7.0),
        Vec3::new(-0.05, -0.05, 0.0),
        (128, 96),
        "",
    ))
    .unwrap();
    // (The helper's file lists extensions it does not use: only those warnings.)
    assert!(
        scene
            .report
            .warnings
            .iter()
            .all(|w| w.contains("KHR_materials_specular") || w.contains("KHR_materials_volume")),
        "{:?}",
        scene.report.warnings
    );
    // One image, decoded once, shared by every way of reading it.
    let images: std::collections::HashSet<_> =
        scene.textures.iter().map(|t| t.texels.as_ptr()).collect();
    assert_eq!(images.len(), 1);
    for (i, (_, transform, set, _, _)) in cases.iter().enumerate() {
        let t = &scene.textures[scene.materials[i].textures.base_color as usize];
        assert_eq!(t.uv_set, *set, "material {i}'s set");
        for (a, b) in t
            .transform
            .m
            .iter()
            .chain(&t.transform.offset)
            .zip(transform.m.iter().chain(&transform.offset))
        {
            assert!(
                (a - b).abs() < 1e-6,
                "material {i}: {:?} against {:?}",
                t.transform,
                transform
            );
        }
    }
    let gpu = Arc::new(GpuScene::build(&scene).unwrap());
    let Some([_, pt_albedo, _, gb_albedo, _]) = render(&gpu, 1) else {
        return;
    };
    let mut per_material = [0_usize; 12];
    let (mut worst, mut worst_color) = (0.0_f32, 0.0_f32);
    let (mut gb_ok, mut covered) = (0_u32, 0_u32);
    let (w, h) = (gpu.settings.width, gpu.settings.height);
    for y in 0..h {
        for x in 0..w {
            let i = (y * w + x) as usize;
            let pt = Vec4::from(pt_albedo.pixels[i]).truncate();
            let gb = Vec4::from(gb_albedo.pixels[i]).truncate();
            let Some(hit) = lumagraph::scene::intersect(&gpu, &pixel_ray(&gpu, x, y)) else {
                assert_eq!(pt, Vec3::ZERO, "pixel {i}: no hit on the CPU");
                continue;
            };
            let m = gpu.tri_shading[hit.prim as usize].material as usize;
            let tc = gpu.tri_texcoords[hit.prim as usize];
            let uvs = tc.uv(hit.u, hit.v);
            let tex = &scene.textures[scene.materials[m].textures.base_color as usize];
            let uv = tex.uv([uvs.truncate().truncate(), Vec2::new(uvs.z, uvs.w)]);
            let color = tc.color(hit.u, hit.v);
            if cases[m].4 {
                // The stored colour against the file's.
                let ray = pixel_ray(&gpu, x, y);
                let want = file_colour(&g.quads[m], ray.origin + hit.t * ray.dir);
                worst_color = worst_color.max((color - want).abs().max_element());
            } else {
                assert_eq!(color, Vec4::ONE, "pixel {i}: white without colours");
            }
            let want =
                Vec3::new(0.9, 0.8, 1.0) * color.truncate() * tex.sample(uv, true).truncate();
            worst = worst.max((pt - want).abs().max_element());
            per_material[m] += 1;
            covered += 1;
            if (gb - pt).abs().max_element() <= 1.0 / 255.0 {
                gb_ok += 1;
            }
        }
    }
    let gb_frac = f64::from(gb_ok) / f64::from(covered);
    println!(
        "PathTrace albedo vs CPU: max error {worst:.2e} over {covered} pixels; stored vertex colours vs the file's: {worst_color:.2e}; GBuffer within 1/255 of PathTrace: {:.2} %",
        100.0 * gb_frac
    );
    assert!(per_material.iter().all(|&n| n >= 50), "{per_material:?}");
    assert!(worst < 2e-3, "max albedo error {worst}");
    assert!(
        worst_color < 0.01,
        "vertex colours stored off by {worst_color}"
    );
    assert!(gb_frac >= 0.99, "GBuffer albedo agrees on {gb_frac}");
}

/// A constant normal map tilting the normal 30° towards +U (and 30° towards −V with the
/// file's own TANGENT rotated by 90°) gives that normal in both AOVs. Expected: the decoded
/// texel, `normal_scale` applied, in the frame (T, w·N×T, N). Tolerance 0.05° for f32
/// rounding (measured: 0.0000° in both AOVs).
#[test]
fn normal_map_tilts_the_aov_normal() {
    let dir = temp();
    let s = 30_f32.to_radians().sin();
    let c = 30_f32.to_radians().cos();
    let enc = |x: f32| ((x + 1.0) * 0.5 * 255.0).round() as u8;
    let texel = [enc(s), enc(0.0), enc(c), 255];
    let mut g = Gltf {
        images: vec![Img::constant(texel)],
        materials: vec![
            r#"{"normalTexture":{"index":0}}"#.into(),
            r#"{"normalTexture":{"index":0,"scale":0.5}}"#.into(),
        ],
        quads: vec![Quad::at(-1.05, -0.5, 0), Quad::at(0.05, -0.5, 1)],
    };
    let dec = |b: u8| f32::from(b) / 255.0 * 2.0 - 1.0;
    let t = Vec3::new(dec(texel[0]), dec(texel[1]), dec(texel[2]));
    // Generated tangents: T = +x (U grows along +x), B = dP/dv = −y, w = −1.
    let want = [
        (t.x * Vec3::X + t.y * Vec3::NEG_Y + t.z * Vec3::Z).normalize(),
        (0.5 * t.x * Vec3::X + 0.5 * t.y * Vec3::NEG_Y + t.z * Vec3::Z).normalize(),
    ];
    let check = |g: &Gltf, want: [Vec3; 2], name: &str| {
        let path = g.write(dir.path(), name);
        let scene = Scene::load(&scene_file(
            dir.path(),
            &path,
            Vec3::new(0.0, 0.0, 2.5),
            Vec3::ZERO,
            (48, 24),
            "",
        ))
        .unwrap();
        let gpu = Arc::new(GpuScene::build(&scene).unwrap());
        let Some([_, _, pt_normal, _, gb_normal]) = render(&gpu, 1) else {
            return;
        };
        let mut worst = [0.0_f32; 2];
        let mut n = 0;
        for (i, hit) in hits(&gpu).iter().enumerate() {
            let Some((m, _)) = *hit else { continue };
            for (k, img) in [&pt_normal, &gb_normal].iter().enumerate() {
                let got = Vec4::from(img.pixels[i]).truncate();
                let angle = got.angle_between(want[m as usize]).to_degrees();
                worst[k] = worst[k].max(angle);
            }
            n += 1;
        }
        println!(
            "{name}: worst angle PathTrace {:.4}°, GBuffer {:.4}° over {n} pixels",
            worst[0], worst[1]
        );
        assert!(n > 300, "{n}");
        assert!(worst[0] < 0.05 && worst[1] < 0.05, "{worst:?}");
    };
    check(&g, want, "generated");
    // The file's tangent along +y with w = 1: B = N × T = −x.
    for q in &mut g.quads {
        q.tangent = Some(Vec4::new(0.0, 1.0, 0.0, 1.0));
    }
    let want_file = [
        (t.x * Vec3::Y + t.y * Vec3::NEG_X + t.z * Vec3::Z).normalize(),
        (0.5 * t.x * Vec3::Y + 0.5 * t.y * Vec3::NEG_X + t.z * Vec3::Z).normalize(),
    ];
    check(&g, want_file, "file_tangents");
}

/// Constant metallic-roughness and emissive textures render the image of the equivalent
/// factors (same seed, 4 spp, max 2 bounces so Russian roulette never runs): the factor
/// scene's values are the CPU decode of the same texels. Difference allowed: 1e-4 relative
/// per channel (f32 `pow` and unorm rounding of the GPU against the CPU; measured 3.4e-7).
#[test]
fn constant_textures_render_like_factors() {
    let dir = temp();
    // Floor with metallic-roughness (G = roughness 0.6, B = metallic 0.4) and an emitter
    // above it with an emissive texture (sRGB 200, 150, 90).
    let mr = [0, 153, 102, 255];
    let em = [200, 150, 90, 255];
    let mut floor = Quad::at(-1.0, -1.0, 0);
    floor.size = 2.0;
    let mut light = Quad::at(-0.4, -0.4, 1);
    light.size = 0.8;
    light.z = 0.6;
    let textured = Gltf {
        images: vec![Img::constant(mr), Img::constant(em)],
        materials: vec![
            r#"{"pbrMetallicRoughness":{"baseColorFactor":[0.8,0.6,0.5,1],"metallicRoughnessTexture":{"index":0}}}"#.into(),
            r#"{"emissiveFactor":[1,1,1],"emissiveTexture":{"index":1},"extensions":{"KHR_materials_emissive_strength":{"emissiveStrength":4}},"doubleSided":true}"#.into(),
        ],
        quads: vec![floor, light],
    };
    let u = |b: u8| f32::from(b) / 255.0;
    let e = [em[0], em[1], em[2]].map(|b| 4.0 * srgb_decode(u(b)));
    let factors = Gltf {
        images: Vec::new(),
        materials: vec![
            format!(
                r#"{{"pbrMetallicRoughness":{{"baseColorFactor":[0.8,0.6,0.5,1],"roughnessFactor":{:?},"metallicFactor":{:?}}}}}"#,
                u(mr[1]),
                u(mr[2])
            ),
            format!(
                r#"{{"emissiveFactor":[{:?},{:?},{:?}],"doubleSided":true}}"#,
                e[0], e[1], e[2]
            ),
        ],
        quads: textured.quads.clone(),
    };
    let mut images = Vec::new();
    for (name, g) in [("textured", &textured), ("factors", &factors)] {
        let sub = dir.path().join(name);
        std::fs::create_dir_all(&sub).unwrap();
        let path = g.write(&sub, name);
        let scene = Scene::load(&scene_file(
            &sub,
            &path,
            Vec3::new(0.0, -2.5, 1.6),
            Vec3::new(0.0, 0.0, 0.0),
            (32, 32),
            "",
        ))
        .unwrap();
        let gpu = Arc::new(GpuScene::build(&scene).unwrap());
        let Some([color, ..]) = render(&gpu, 4) else {
            return;
        };
        images.push(color);
    }
    let (a, b) = (&images[0], &images[1]);
    let mut worst = 0.0_f32;
    let mut sum = 0.0_f64;
    for (p, q) in a.pixels.iter().zip(&b.pixels) {
        for ch in 0..3 {
            let d = (p[ch] - q[ch]).abs() / q[ch].abs().max(1e-3);
            worst = worst.max(d);
            sum += f64::from(q[ch]);
        }
    }
    println!("textured vs factors: max relative difference {worst:.2e} (image sum {sum:.1})");
    assert!(sum > 10.0, "the image is lit");
    assert!(worst < 1e-4, "{worst}");
}

/// Constant KHR transmission, specular and specular color textures render the image of the
/// equivalent factors (same seed, 4 spp, 2 bounces): a floor of two quads, one transmitting
/// (factor 1 × R 153 = 0.6), one with `specular` = 0.5 × A 77 and `specular_color` the
/// decoded sRGB color (230, 180, 120), under an emitter. The factor scene's values are the CPU
/// decode of the same texels. Difference allowed: 1e-4 relative per channel, as for the
/// metallic-roughness and emissive textures (f32 rounding of the GPU's unorm decode and
/// products against the CPU's). The same scene with the textures left out differs by more
/// than 100 × that, so a texture that is not read fails the test.
#[test]
fn constant_transmission_and_specular_textures_render_like_factors() {
    let dir = temp();
    let tr = [153, 0, 0, 255];
    let sp = [0, 0, 0, 77];
    let sc = [230, 180, 120, 255];
    let base = r#""pbrMetallicRoughness":{"baseColorFactor":[0.8,0.6,0.5,1],"metallicFactor":0,"roughnessFactor":0.3}"#;
    let u = |b: u8| f32::from(b) / 255.0;
    let d = [sc[0], sc[1], sc[2]].map(|b| srgb_decode(u(b)));
    let transmission = Ways {
        textured: r#"{"KHR_materials_transmission":{"transmissionFactor":1,"transmissionTexture":{"index":0}}}"#.into(),
        factors: format!(r#"{{"KHR_materials_transmission":{{"transmissionFactor":{:?}}}}}"#, u(tr[0])),
        ignored: r#"{"KHR_materials_transmission":{"transmissionFactor":1}}"#.into(),
    };
    let specular = Ways {
        textured: r#"{"KHR_materials_specular":{"specularFactor":1,"specularColorFactor":[1,1,1],"specularTexture":{"index":1},"specularColorTexture":{"index":2}}}"#.into(),
        factors: format!(
            r#"{{"KHR_materials_specular":{{"specularFactor":{:?},"specularColorFactor":[{:?},{:?},{:?}]}}}}"#,
            u(sp[3]),
            d[0],
            d[1],
            d[2]
        ),
        // Specular 0.5, white.
        ignored: "{}".into(),
    };
    let images = vec![Img::constant(tr), Img::constant(sp), Img::constant(sc)];
    renders_like_factors(dir.path(), base, images, &[transmission, specular], |f| {
        // The factor scene has what the CPU expects.
        let f0 = ((1.5_f32 - 1.0) / (1.5 + 1.0)).powi(2);
        let want = 12.5 * f0 * u(sp[3]);
        assert!((f.materials[1].specular - want).abs() < 1e-6 * want);
        assert_eq!(f.materials[1].specular_color, d);
        assert_eq!(f.materials[0].transmission, 0.6);
    });
}

/// One material of [`renders_like_factors`]'s floor, as the `extensions` object of a glTF
/// material: with its textures, with the factors they equal, and with the textures left out.
struct Ways {
    textured: String,
    factors: String,
    ignored: String,
}

/// The floor of [`two_materials_under_a_light`], its two materials `base` (the
/// `pbrMetallicRoughness` member) with the extensions of `ways` (textures from `images`),
/// three times: textured, with the factors, and without the textures, seen from above at
/// 32×32 with 4 spp. After `check` has looked at the factor scene, the textured render
/// equals the factors' within 1e-4 relative per channel, and the one without textures
/// differs by more than 1e-2.
fn renders_like_factors(
    dir: &Path,
    base: &str,
    images: Vec<Img>,
    ways: &[Ways; 2],
    check: impl FnOnce(&GpuScene),
) {
    let light = r#"{"emissiveFactor":[1,0.9,0.7],"extensions":{"KHR_materials_emissive_strength":{"emissiveStrength":4}},"doubleSided":true}"#;
    let gltf = |images: Vec<Img>, ext: fn(&Ways) -> &String| Gltf {
        images,
        materials: vec![
            format!(r#"{{{base},"extensions":{}}}"#, ext(&ways[0])),
            format!(r#"{{{base},"extensions":{}}}"#, ext(&ways[1])),
            light.into(),
        ],
        quads: two_materials_under_a_light(),
    };
    let eye = Vec3::new(0.0, -2.5, 1.6);
    let scene = |name, g| flat_scene(dir, name, &g, eye, (32, 32));
    let t = scene("textured", gltf(images, |w| &w.textured));
    let f = scene("factors", gltf(Vec::new(), |w| &w.factors));
    let n = scene("ignored", gltf(Vec::new(), |w| &w.ignored));
    check(&f);
    let (Some(t), Some(f), Some(n)) = (color(t, 4), color(f, 4), color(n, 4)) else {
        return;
    };
    let (worst, sum) = max_rel_diff(&t, &f, |_| true);
    let (ignored_diff, _) = max_rel_diff(&n, &f, |_| true);
    println!(
        "textured vs factors: max relative difference {worst:.2e} (image sum {sum:.1}); \
         without the textures: {ignored_diff:.2e}"
    );
    assert!(sum > 10.0, "the image is lit");
    assert!(ignored_diff > 1e-2, "the textures change the image");
    assert!(worst < 1e-4, "{worst}");
}

/// A floor of four unit quads, materials 0 (left) and 1 (right), under a small emitter of
/// material 2.
fn two_materials_under_a_light() -> Vec<Quad> {
    let unit = |x, y, m| {
        let mut q = Quad::at(x, y, m);
        q.size = 1.0;
        q
    };
    let mut light = Quad::at(-0.4, -0.4, 2);
    light.size = 0.8;
    light.z = 0.6;
    vec![
        unit(-1.0, -1.0, 0),
        unit(0.0, -1.0, 1),
        unit(-1.0, 0.0, 0),
        unit(0.0, 0.0, 1),
        light,
    ]
}

/// Constant clear coat and sheen textures render the image of the equivalent factors (same
/// seed, 4 spp, 2 bounces), as the transmission and specular ones do: left, a clear coat of
/// factor 1 and roughness factor 1 read from R 140 and G 90 of its two textures; right, a
/// sheen of colour factor 1 times the sRGB texel (200, 120, 60) and roughness factor 1 times
/// A 128. Allowed: 1e-4 relative per channel, as there; the same scene without the textures
/// must differ by more than 1e-2.
#[test]
fn constant_clear_coat_and_sheen_textures_render_like_factors() {
    let dir = temp();
    let cc = [140, 90, 0, 255];
    let sh = [200, 120, 60, 128];
    let base = r#""pbrMetallicRoughness":{"baseColorFactor":[0.3,0.2,0.5,1],"metallicFactor":0,"roughnessFactor":0.6}"#;
    let u = |b: u8| f32::from(b) / 255.0;
    let d = [sh[0], sh[1], sh[2]].map(|b| srgb_decode(u(b)));
    let coat = Ways {
        textured: r#"{"KHR_materials_clearcoat":{"clearcoatFactor":1,"clearcoatRoughnessFactor":1,"clearcoatTexture":{"index":0},"clearcoatRoughnessTexture":{"index":0}}}"#.into(),
        factors: format!(
            r#"{{"KHR_materials_clearcoat":{{"clearcoatFactor":{:?},"clearcoatRoughnessFactor":{:?}}}}}"#,
            u(cc[0]),
            u(cc[1])
        ),
        ignored: r#"{"KHR_materials_clearcoat":{"clearcoatFactor":1,"clearcoatRoughnessFactor":1}}"#.into(),
    };
    let sheen = Ways {
        textured: r#"{"KHR_materials_sheen":{"sheenColorFactor":[1,1,1],"sheenRoughnessFactor":1,"sheenColorTexture":{"index":1},"sheenRoughnessTexture":{"index":1}}}"#.into(),
        factors: format!(
            r#"{{"KHR_materials_sheen":{{"sheenColorFactor":[{:?},{:?},{:?}],"sheenRoughnessFactor":{:?}}}}}"#,
            d[0],
            d[1],
            d[2],
            u(sh[3])
        ),
        ignored: r#"{"KHR_materials_sheen":{"sheenColorFactor":[1,1,1],"sheenRoughnessFactor":1}}"#.into(),
    };
    let images = vec![Img::constant(cc), Img::constant(sh)];
    renders_like_factors(dir.path(), base, images, &[coat, sheen], |f| {
        assert_eq!(f.materials[0].clearcoat, u(cc[0]));
        assert_eq!(f.materials[1].sheen_roughness, u(sh[3]));
    });
}

/// A transmission texture whose left texel transmits (R = 255) and right one does not
/// (R = 0), sampled NEAREST with clamped edges on a floor under an emitter: pixels whose
/// four corners see the left half render exactly as with a constant transmitting texture,
/// those that see the right half as with a constant opaque one (same seed, 4 spp, 2 bounces,
/// nothing but the emitter above and a black environment below, so a pixel's paths depend
/// only on the texel they first hit). Allowed: 1e-4 relative per channel, as for the
/// constant textures; the two constant renders differ by far more on both halves.
#[test]
fn half_transmitting_texture_transmits_where_its_texel_says() {
    let dir = temp();
    let mut floor = Quad::at(-1.0, -1.0, 0);
    floor.size = 2.0;
    let mut light = Quad::at(-0.4, -0.4, 1);
    light.size = 0.8;
    light.z = 0.6;
    let g = |img: Img| {
        Gltf {
        images: vec![Img {
            wrap: (33071, 33071),
            nearest: true,
            ..img
        }],
        materials: vec![
            r#"{"pbrMetallicRoughness":{"baseColorFactor":[0.8,0.6,0.5,1],"metallicFactor":0,"roughnessFactor":0.3},
            "extensions":{"KHR_materials_transmission":{"transmissionFactor":1,"transmissionTexture":{"index":0}}}}"#.into(),
            r#"{"emissiveFactor":[1,0.9,0.7],"extensions":{"KHR_materials_emissive_strength":{"emissiveStrength":4}},"doubleSided":true}"#.into(),
        ],
        quads: vec![floor, light],
    }
    };
    let eye = Vec3::new(0.0, -2.5, 1.6);
    let size = (40, 32);
    let scene = |name, img| flat_scene(dir.path(), name, &g(img), eye, size);
    let half = scene(
        "half",
        Img::new(2, 1, vec![[255, 0, 0, 255], [0, 0, 0, 255]]),
    );
    let all = scene("all", Img::constant([255, 0, 0, 255]));
    let none = scene("none", Img::constant([0, 0, 0, 255]));
    // Pixels whose four corners hit the floor on one side of U = 0.5 (−1: left, 1: right).
    let side: Vec<i32> = (0..size.1)
        .flat_map(|y| (0..size.0).map(move |x| (x, y)))
        .map(|(x, y)| {
            let corners = [(0, 0), (1, 0), (0, 1), (1, 1)].map(|(dx, dy)| {
                let p = Vec2::new((x + dx) as f32, (y + dy) as f32);
                match hit_uv(&half, &image_ray(&half, p)) {
                    Some((0, uv)) if uv.x < 0.49 => -1,
                    Some((0, uv)) if uv.x > 0.51 => 1,
                    _ => 0,
                }
            });
            if corners.iter().all(|&c| c == corners[0]) {
                corners[0]
            } else {
                0
            }
        })
        .collect();
    let count = |s: i32| side.iter().filter(|&&c| c == s).count();
    let (n_left, n_right) = (count(-1), count(1));
    let (Some(half), Some(all), Some(none)) = (color(half, 4), color(all, 4), color(none, 4))
    else {
        return;
    };
    let (left, left_sum) = max_rel_diff(&half, &all, |i| side[i] == -1);
    let (right, right_sum) = max_rel_diff(&half, &none, |i| side[i] == 1);
    // How much transmission changes each half: the mean relative difference of the two
    // constant renders there.
    let contrast = |s: i32| {
        let (mut d, mut t) = (0.0_f64, 0.0_f64);
        for (i, (p, q)) in all.pixels.iter().zip(&none.pixels).enumerate() {
            if side[i] == s {
                for ch in 0..3 {
                    d += f64::from((p[ch] - q[ch]).abs());
                    t += f64::from(q[ch]);
                }
            }
        }
        d / t
    };
    let (c_left, c_right) = (contrast(-1), contrast(1));
    println!(
        "left half ({n_left} px) vs transmitting: max relative difference {left:.2e}; right half \
         ({n_right} px) vs opaque: {right:.2e}; transmitting vs opaque differ by {:.1} % \
         (left) and {:.1} % (right) of the opaque image",
        100.0 * c_left,
        100.0 * c_right
    );
    assert!(n_left > 150 && n_right > 150, "{n_left} {n_right}");
    assert!(left_sum > 1.0 && right_sum > 1.0, "both halves are lit");
    assert!(c_left > 0.1 && c_right > 0.1, "{c_left} {c_right}");
    assert!(left < 1e-4 && right < 1e-4, "{left} {right}");
}

/// Light selection weighs a textured emitter by its texture: a 0.8 × 0.8 emitter whose 4 × 4
/// NEAREST emissive texture is black but for one texel, beside a small untextured emitter,
/// over a diffuse floor. The same flattened scene is rendered with the texture-weighted
/// selection and with the emissive factors' powers put back (the former behaviour), 16 spp
/// each, and compared with a 1 024-spp render of another seed. Both are unbiased: each mean
/// lies within 4 standard errors of the reference's over the pixels that see only the floor
/// (standard error: the RMSE over √pixels; measured within 1.6). The texture-weighted one is
/// less noisy: RMSE ratio below 0.95 (measured 0.910 at this seed, 0.899 at another; half of
/// the light samples are spread uniformly over the lights, `light_selection`, so the
/// weighting acts on the other half: with selection by power alone the ratio was 0.62–0.65).
#[test]
fn textured_emitter_selection_follows_the_texture() {
    let dir = temp();
    let mut floor = Quad::at(-1.0, -1.0, 0);
    floor.size = 2.0;
    let mut big = Quad::at(-0.7, -0.4, 1);
    big.size = 0.8;
    big.z = 0.6;
    let mut small = Quad::at(0.4, -0.2, 2);
    small.size = 0.3;
    small.z = 0.5;
    let mut px = vec![[0, 0, 0, 255]; 16];
    px[5] = [255, 255, 255, 255];
    let g = Gltf {
        images: vec![Img {
            nearest: true,
            ..Img::new(4, 4, px)
        }],
        materials: vec![
            r#"{"pbrMetallicRoughness":{"baseColorFactor":[0.8,0.8,0.8,1],"metallicFactor":0,"roughnessFactor":1}}"#.into(),
            r#"{"pbrMetallicRoughness":{"baseColorFactor":[0,0,0,1]},"emissiveFactor":[1,1,1],"emissiveTexture":{"index":0},"extensions":{"KHR_materials_emissive_strength":{"emissiveStrength":8}},"doubleSided":true}"#.into(),
            r#"{"pbrMetallicRoughness":{"baseColorFactor":[0,0,0,1]},"emissiveFactor":[1,1,1],"extensions":{"KHR_materials_emissive_strength":{"emissiveStrength":8}},"doubleSided":true}"#.into(),
        ],
        quads: vec![floor, big, small],
    };
    let weighted = flat_scene(
        dir.path(),
        "emitters",
        &g,
        Vec3::new(0.0, -2.5, 1.6),
        (48, 48),
    );
    // The big emitter's two triangles: each keeps the mean of its footprint (one has the
    // bright texel, 1/8 of its area; the other none, so the 1 % floor).
    let factor_power = |l: &lumagraph::scene::GpuLight| {
        let sides = if l.flags & lumagraph::scene::LIGHT_TWO_SIDED != 0 {
            2.0
        } else {
            1.0
        };
        lumagraph::scene::luminance(Vec3::from(l.emission)) * l.area * std::f32::consts::PI * sides
    };
    let scales: Vec<f32> = weighted
        .lights
        .iter()
        .map(|l| l.power / factor_power(l))
        .collect();
    println!("power / factor power per light: {scales:?}");
    assert_eq!(weighted.lights.len(), 4);
    let mut big_scales: Vec<f32> = scales.iter().copied().filter(|&s| s < 0.99).collect();
    big_scales.sort_by(f32::total_cmp);
    assert_eq!(big_scales.len(), 2, "{scales:?}");
    assert!((big_scales[0] - 0.01).abs() < 1e-6 && (big_scales[1] - 0.125).abs() < 0.01);
    let mut by_factor = weighted.clone();
    for l in &mut by_factor.lights {
        l.power = factor_power(l);
    }
    let powers: Vec<f32> = by_factor.lights.iter().map(|l| l.power).collect();
    by_factor.light_alias =
        lumagraph::scene::alias_table(&lumagraph::scene::light_selection(&powers));
    by_factor.header.total_light_power = powers.iter().sum();
    // Pixels that see only the floor (their four corners hit it): the emitters' own faces
    // are the same in both and only add antialiasing noise.
    let (width, height) = (weighted.settings.width, weighted.settings.height);
    let floor_px: Vec<bool> = (0..height)
        .flat_map(|y| (0..width).map(move |x| (x, y)))
        .map(|(x, y)| {
            [(0, 0), (1, 0), (0, 1), (1, 1)].iter().all(|&(dx, dy)| {
                let p = Vec2::new((x + dx) as f32, (y + dy) as f32);
                matches!(hit_uv(&weighted, &image_ray(&weighted, p)), Some((0, _)))
            })
        })
        .collect();
    let mut reference = weighted.clone();
    reference.settings.seed = 1234;
    let (Some(w), Some(f), Some(r)) = (
        color(weighted, 16),
        color(by_factor, 16),
        color(reference, 1024),
    ) else {
        return;
    };
    let n = floor_px.iter().filter(|&&f| f).count() as f64;
    let mean = |img: &Image| {
        let s: f64 = (img.pixels.iter().zip(&floor_px))
            .filter(|(_, f)| **f)
            .map(|(p, _)| f64::from(p[0] + p[1] + p[2]))
            .sum();
        s / (3.0 * n)
    };
    let rmse = |img: &Image| {
        let s: f64 = (img.pixels.iter().zip(&r.pixels).zip(&floor_px))
            .filter(|(_, f)| **f)
            .map(|((p, q), _)| (0..3).map(|c| f64::from(p[c] - q[c]).powi(2)).sum::<f64>())
            .sum();
        (s / (3.0 * n)).sqrt()
    };
    println!("{n} floor pixels");
    assert!(n > 800.0, "{n}");
    let (mr, mw, mf) = (mean(&r), mean(&w), mean(&f));
    let (ew, ef) = (rmse(&w), rmse(&f));
    println!(
        "mean: reference {mr:.4}, texture-weighted {mw:.4} ({:+.1} standard errors), \
         factor-weighted {mf:.4} ({:+.1}); RMSE texture-weighted {ew:.4}, factor-weighted \
         {ef:.4}, ratio {:.3}",
        (mw - mr) / (ew / n.sqrt()),
        (mf - mr) / (ef / n.sqrt()),
        ew / ef
    );
    assert!(mr > 0.01, "the image is lit");
    assert!(
        (mw - mr).abs() < 4.0 * ew / n.sqrt(),
        "texture-weighted mean {mw} vs {mr}"
    );
    assert!(
        (mf - mr).abs() < 4.0 * ef / n.sqrt(),
        "factor-weighted mean {mf} vs {mr}"
    );
    assert!(ew / ef < 0.95, "RMSE ratio {}", ew / ef);
}

/// On a GPU adapter small scenes are traversed through their BVH, never intersected
/// inline (the inline test of every primitive is 2.6-3.6× slower than the BVH on 64
/// spheres on an H100); on a CPU adapter they are inlined, with their data. The plan says
/// which and why.
#[test]
fn small_scenes_are_inlined_on_cpu_adapters_only() {
    use lumagraph::pathtrace::specialize::{Feature, Features, Intersector, PathTraceOptions};
    let scene = GpuScene::build(&Scene::load(&common::repo("assets/cornell_spheres.ron")).unwrap())
        .unwrap();
    for cpu_adapter in [true, false] {
        let opts = PathTraceOptions {
            specialize: true,
            cpu_adapter,
            aovs: false,
            adaptive: false,
            data_in_buffers: false,
            in_image_order: false,
            host_rays: false,
            ..PathTraceOptions::default()
        };
        let f = Features::decide(&scene, opts);
        assert_eq!(f.intersector() == Intersector::INLINE, cpu_adapter);
        assert_eq!(f.on(Feature::InlineData), cpu_adapter);
        assert_eq!(f.intersector() == Intersector::BINARY_BVH, !cpu_adapter);
        assert_eq!(f.on(Feature::SpreadWorkgroups), cpu_adapter);
        if !cpu_adapter {
            let why = f.why(Intersector::INLINE);
            assert!(why.contains("a GPU adapter"), "{why}");
        }
    }
}

// ---------------------------------------------------------------- mip levels

/// A 20 × 20 floor (the z = 0 plane) under a one-texel black and white checker of 64² texels
/// repeated 40 times each way, seen at a grazing angle from 0.5 above it: beyond a few
/// metres each pixel covers dozens of texels. `texture_mips` as given; 64 × 48 pixels, a
/// constant white sky, one bounce; with `ceiling`, a second such quad 2 above the floor
/// (double-sided), which rays bouncing off the floor meet, and 3 bounces.
pub(crate) fn grazing_checker(dir: &Path, mips: bool, ceiling: bool) -> GpuScene {
    let px: Vec<[u8; 4]> = (0..64 * 64)
        .map(|i| {
            if (i % 64 + i / 64) % 2 == 0 {
                [255, 255, 255, 255]
            } else {
                [0, 0, 0, 255]
            }
        })
        .collect();
    let mut floor = Quad::at(-10.0, -10.0, 0);
    floor.size = 20.0;
    floor.uv1 = Vec2::splat(40.0);
    let mut quads = vec![floor];
    if ceiling {
        let mut top = floor;
        top.z = 2.0;
        quads.push(top);
    }
    let g = Gltf {
        images: vec![Img::new(64, 64, px)],
        materials: vec![r#"{"doubleSided":true,"pbrMetallicRoughness":{"baseColorTexture":{"index":0},"metallicFactor":0.0,"roughnessFactor":1.0}}"#.into()],
        quads,
    };
    let bounces = if ceiling { 3 } else { 1 };
    let sub = dir.join(format!("grazing_{mips}_{ceiling}"));
    std::fs::create_dir_all(&sub).unwrap();
    g.write(&sub, "floor");
    let text = format!(
        "(version: 1,
  camera: Perspective(position: (0.0, -9.0, 0.5), target: (0.0, 10.0, -0.6), up: (0.0, 0.0, 1.0), fov_y: 40.0),
  shapes: [Mesh(name: \"m\", path: \"floor.gltf\")],
  environment: Constant((1.0, 1.0, 1.0)),
  render: (width: 64, height: 48, max_bounces: {bounces}, spp: 1, seed: 7, texture_mips: {mips}),
)"
    );
    let scene_path = sub.join("scene.ron");
    std::fs::write(&scene_path, text).unwrap();
    GpuScene::build(&Scene::load(&scene_path).unwrap()).unwrap()
}

/// Mip levels take out the aliasing of a minified texture. On the grazing checker, the
/// first-hit albedo (`PathTrace`'s AOV through each pixel center, from the ray cone, and the
/// `GBuffer`'s, from screen-space derivatives) of every pixel whose hit is over 3 m away
/// is the checker's mean: level 1 of a one-texel checker is already uniform, byte 188 in
/// sRGB, 0.5029 in linear light (within 0.01: the blend with level 0 where the level of
/// detail is under 1 — none at that distance, measured 0). Without mips the same pixels
/// alias: some are over 0.25 from the mean (measured 0.47). And the colour converges
/// faster: at 4 spp its relMSE against a 256-spp image of the same settings is under half
/// of that without mips (measured 0.0032 against 0.0157); the grey region's noise is then
/// the sky's alone.
#[test]
fn mip_levels_turn_a_distant_checker_grey() {
    let dir = temp();
    let grey = srgb_decode(188.0 / 255.0);
    let mut relmse = [0.0_f64; 2];
    for (k, mips) in [true, false].into_iter().enumerate() {
        let g = grazing_checker(dir.path(), mips, false);
        // The pixels whose center ray meets the floor over 3 m away (CPU ray cast).
        let far: Vec<bool> = (0..48)
            .flat_map(|y| (0..64).map(move |x| (x, y)))
            .map(|(x, y)| {
                let ray = pixel_ray(&g, x, y);
                lumagraph::scene::intersect(&g, &ray).is_some_and(|h| h.t > 3.0)
            })
            .collect();
        let count = far.iter().filter(|&&f| f).count();
        assert!(count > 300, "{count} far pixels");
        let g = Arc::new(g);
        let Some([color, pt_albedo, _, gb_albedo, _]) = render(&g, 4) else {
            return;
        };
        let Some([reference, ..]) = render(&g, 256) else {
            return;
        };
        relmse[k] = lumagraph::render::metrics::relmse(&color, &reference);
        for (name, img) in [("PathTrace", &pt_albedo), ("GBuffer", &gb_albedo)] {
            let worst = img
                .pixels
                .iter()
                .zip(&far)
                .filter(|(_, f)| **f)
                .map(|(p, _)| (p[0] - grey).abs().max((p[1] - grey).abs()))
                .fold(0.0_f32, f32::max);
            println!(
                "mips {mips}: {name} albedo of {count} far pixels: worst {worst:.4} from the mean {grey:.4}"
            );
            if mips {
                assert!(worst < 0.01, "{name}: {worst}");
            } else {
                assert!(worst > 0.25, "{name}: {worst}");
            }
        }
    }
    println!(
        "4 spp against 256 spp: relMSE {:.5} with mips, {:.5} without",
        relmse[0], relmse[1]
    );
    assert!(relmse[0] < 0.5 * relmse[1], "{relmse:?}");
}
