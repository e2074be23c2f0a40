//! Specialization is an optimization, never a change of image: the shader specialized to a
//! scene (lobes, primitive kinds, environment and texture code the scene cannot use left
//! out) renders what the general shader renders, on generated scenes.
//!
//! Each scene is the Cornell box or the sphere furnace with every material drawn at random
//! (metallic, transmission, specular and diffuse roughness each 0, 1 or between; roughness,
//! IOR and colours between; a clear coat and a sheen on some; opaque, alpha-masked or
//! blended) and random textures given to some of them: metallic-roughness,
//! transmission, specular, specular-colour, clear coat and sheen textures whose channels are constant (0 or 255)
//! or spread, so a factor of 1 or 0 can be lowered per texel, or not. The first scene holds
//! the case that once rendered black: glass (transmission 1) with a metallic factor of 1
//! that a metallic-roughness texture lowers to 0 over part of it. Both shaders traverse the
//! BVH and read the scene from buffers (what a GPU adapter runs), so they differ only in
//! what the specialized one leaves out.

use crate::common;
use lumagraph::pathtrace::specialize::Tracing;

use std::sync::Arc;

use glam::{Vec2, Vec3};
use lumagraph::graph::{Graph, Node, ParamValue};
use lumagraph::pathtrace::library::compile;
use lumagraph::pathtrace::specialize::{Feature, Features};
use lumagraph::render::Resources;
use lumagraph::render::cpu::Image;
use lumagraph::scene::{AlphaMode, GpuScene, NO_TEXTURE, Scene, Texture, Wrap};

/// A small deterministic generator (`SplitMix64`), so a failing case can be rerun by its seed.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    fn f(&mut self) -> f32 {
        (self.next() >> 40) as f32 / (1u64 << 24) as f32
    }

    /// 0, 1, or uniform between, a third each.
    fn factor(&mut self) -> f32 {
        match self.next() % 3 {
            0 => 0.0,
            1 => 1.0,
            _ => self.f(),
        }
    }

    fn chance(&mut self, p: f32) -> bool {
        self.f() < p
    }
}

/// A 4×4 texture whose channels are each constant 0, constant 255 or spread over [0, 255].
fn random_texture(rng: &mut Rng, name: String) -> Texture {
    let kinds: [u64; 4] = std::array::from_fn(|_| rng.next() % 3);
    let texels = (0..16)
        .map(|_| {
            std::array::from_fn(|c| match kinds[c] {
                0 => 0,
                1 => 255,
                _ => (rng.next() % 256) as u8,
            })
        })
        .collect();
    Texture {
        name,
        width: 4,
        height: 4,
        texels,
        wrap: [Wrap::Repeat; 2],
        nearest: false,
        uv_set: 0,
        transform: lumagraph::scene::UvTransform::IDENTITY,
    }
}

/// `scene` with its materials drawn at random and textures given to some (reading either UV
/// set, some through a transform); the triangles get two UV sets from their positions, and
/// in half the scenes half of them random vertex colours. Each of metallic, transmission, specular, diffuse
/// roughness, clear coat and sheen is allowed in a scene with probability 0.6, else 0 in all its materials. `glass_case`: the first material is metallic 1, transmission 1
/// with a metallic-roughness texture whose metallic (blue) channel spreads over [0, 255].
fn randomize(scene: &mut Scene, rng: &mut Rng, glass_case: bool) {
    let colored = rng.chance(0.5);
    for t in &mut scene.triangles {
        t.uvs = Some(
            t.positions
                .map(|p| Vec2::new(p.x + 0.37 * p.z, p.y - 0.21 * p.z)),
        );
        t.uvs1 = Some(t.positions.map(|p| Vec2::new(0.5 * p.z - p.y, p.x)));
        // Vertex colours on some triangles, their alpha cutting or blending too.
        if colored && rng.chance(0.5) {
            t.colors = Some(std::array::from_fn(|_| {
                std::array::from_fn(|_| (rng.next() % 256) as u8)
            }));
        }
    }
    let textures = 3 + (rng.next() % 3) as usize;
    scene.textures = (0..textures)
        .map(|i| {
            let mut t = random_texture(rng, format!("random {i}"));
            // Some read the second UV set, some through a transform.
            t.uv_set = u32::from(rng.chance(0.3));
            if rng.chance(0.3) {
                t.transform = lumagraph::scene::UvTransform::khr(
                    [rng.f(), rng.f()],
                    6.0 * rng.f(),
                    [0.5 + 2.0 * rng.f(), 0.5 + 2.0 * rng.f()],
                );
            }
            t
        })
        .collect();
    let pick = |rng: &mut Rng, p: f32| {
        if rng.chance(p) {
            (rng.next() % textures as u64) as u32
        } else {
            NO_TEXTURE
        }
    };
    // Which factors this scene's materials may set at all: a lobe no material can use is
    // what specialization leaves out.
    let [metal, glass, specular, rough, coat, sheen] = std::array::from_fn(|_| rng.chance(0.6));
    for m in &mut scene.materials {
        if m.emission.max_element() > 0.0 {
            continue;
        }
        m.base_color = Vec3::new(rng.f(), rng.f(), rng.f()) * 0.9;
        m.roughness = rng.f();
        m.metallic = if metal { rng.factor() } else { 0.0 };
        m.transmission = if glass { rng.factor() } else { 0.0 };
        m.specular = if specular { rng.factor() } else { 0.0 };
        if specular && rng.chance(0.5) {
            // Over 1 too: F0 clamps at 1.
            m.specular_color = Vec3::new(rng.f(), rng.f(), rng.f()) * 2.0;
        }
        m.diffuse_roughness = if rough && rng.chance(0.5) {
            rng.f()
        } else {
            0.0
        };
        m.ior = 1.2 + 0.6 * rng.f();
        if coat && rng.chance(0.5) {
            m.clearcoat = rng.factor();
            m.clearcoat_roughness = rng.f();
            m.textures.clearcoat = pick(rng, 0.3);
            m.textures.clearcoat_roughness = pick(rng, 0.3);
            // The coat's own normal map (a random texture as a normal map).
            m.textures.clearcoat_normal = pick(rng, 0.3);
        }
        if sheen && rng.chance(0.5) {
            m.sheen_color = Vec3::new(rng.f(), rng.f(), rng.f());
            m.sheen_roughness = rng.f();
            m.textures.sheen_color = pick(rng, 0.3);
            m.textures.sheen_roughness = pick(rng, 0.3);
        }
        m.conductor = None;
        m.textures.metallic_roughness = pick(rng, 0.5);
        m.textures.transmission = pick(rng, 0.3);
        m.textures.specular = pick(rng, 0.25);
        m.textures.specular_color = pick(rng, 0.2);
        // Alpha: masked or blended, by a factor and the base colour texture's alpha.
        m.alpha_mode = match rng.next() % 4 {
            0 => AlphaMode::Mask { cutoff: rng.f() },
            1 => AlphaMode::Blend,
            _ => AlphaMode::Opaque,
        };
        m.opacity = if rng.chance(0.5) { 1.0 } else { rng.f() };
        m.textures.base_color = pick(rng, 0.4);
    }
    if glass_case && let Some(m) = scene.materials.first_mut() {
        m.metallic = 1.0;
        m.transmission = 1.0;
        m.roughness = 0.3;
        m.textures.transmission = NO_TEXTURE;
        let mut mr = random_texture(rng, "metallic 0 to 1".into());
        let mut texels = mr.texels.to_vec();
        for (i, t) in texels.iter_mut().enumerate() {
            t[2] = (i * 17) as u8;
        }
        mr.texels = texels.into();
        scene.textures.push(mr);
        m.textures.metallic_roughness = scene.textures.len() as u32 - 1;
    }
}

/// Frames of each shader, and the significance of the comparison of their block means.
const FRAMES: u32 = 16;
const SPP_PER_FRAME: i64 = 4;
const ALPHA: f64 = 1e-3;

/// `FRAMES` frames of `SPP_PER_FRAME` samples of `scene` with random seed `seed`, the
/// independent sampler, the specialized or the general shader, and the shader's features.
fn frames(scene: &GpuScene, general: bool, seed: u32) -> Option<(Vec<Image>, Features)> {
    let ctx = common::gpu()?;
    let mut scene = scene.clone();
    scene.settings.seed = seed;
    let scene = Arc::new(scene);
    let graph = Graph {
        nodes: vec![
            Node::new("pt", "PathTrace")
                .with("samples_per_frame", ParamValue::Int(SPP_PER_FRAME))
                .with("sampler", ParamValue::Str("independent".into())),
        ],
        edges: Vec::new(),
        ..Graph::default()
    };
    let plan = compile(&graph, &["pt.color".to_owned()], Some(&scene)).unwrap();
    let resources = Resources {
        scene: Some(Arc::clone(&scene)),
        ..Resources::default()
    }
    .with(Tracing {
        general_shaders: general,
        as_gpu_adapter: true,
        scene_data_in_buffers: true,
        ..Tracing::default()
    });
    let mut exec = lumagraph::pathtrace::library::executor(ctx, plan, &resources).unwrap();
    let features = lumagraph::pathtrace::nodes::pathtrace::features(&exec, "pt")
        .unwrap()
        .clone();
    let images = (0..FRAMES)
        .map(|_| {
            exec.run_frames(1, true).unwrap();
            exec.read_port("pt.color").unwrap()
        })
        .collect();
    Some((images, features))
}

/// What one seed of [`specialized_shaders_render_what_the_general_shader_renders`] found: the
/// features its specialized shader left out, whether it needs the alpha test, and whether
/// its frames were bit-identical to the general shader's. `None` without a GPU.
fn check_seed(seed: u32) -> Option<(Vec<&'static str>, bool, bool)> {
    let base = if seed.is_multiple_of(2) {
        "assets/cornell.ron"
    } else {
        "assets/furnace_materials.ron"
    };
    let mut scene = Scene::load(&common::repo(base)).unwrap();
    scene.settings.width = 40;
    scene.settings.height = 40;
    randomize(&mut scene, &mut Rng(u64::from(seed)), seed == 0);
    let gpu = GpuScene::build(&scene).unwrap();
    let (specialized, features) = frames(&gpu, false, seed)?;
    let (general, _) = frames(&gpu, true, seed).unwrap();
    let left_out = features
        .iter()
        .filter(|(_, d)| !d.included)
        .map(|(f, _)| f.label())
        .collect();
    if seed == 0 {
        assert!(
            features.on(Feature::GlassLobe),
            "glass left out though a texture lowers metallic: {}",
            features.reason(Feature::GlassLobe)
        );
    }
    assert!(
        specialized
            .iter()
            .any(|f| f.pixels.iter().any(|p| p[0] > 0.0)),
        "seed {seed}: black image"
    );
    let alpha = features.on(Feature::Alpha);
    if specialized == general {
        println!(
            "seed {seed} ({base}): bit-identical; {}",
            features.summary()
        );
        return Some((left_out, alpha, true));
    }
    let (other, _) = frames(&gpu, true, seed + 1000).unwrap();
    match common::same_means(&specialized, &other, 8, 1e-3, ALPHA) {
        Ok((tests, worst)) => println!(
            "seed {seed} ({base}): same means ({tests} tests, largest |t| {worst:.2} of the critical value); {}",
            features.summary()
        ),
        Err(e) => panic!(
            "seed {seed} ({base}): the specialized shader renders another image than the general one: {e}; {}",
            features.summary()
        ),
    }
    Some((left_out, alpha, false))
}

/// 16 scenes drawn from seeds 0-15 over the Cornell box (triangles, an area light) and the
/// sphere furnace (spheres, a constant environment), 40×40 pixels. With the same random
/// seed the two shaders render the same frames bit for bit where the arithmetic on every
/// path is the same; where it is not (the general shader samples a GGX lobe of F0 = 0 on a
/// tenth of the bounces off a material with `specular: 0`, whose value is 0, where the
/// specialized one samples the diffuse base alone), a second general render with another
/// seed must have the same 8×8-block means: Welch's t-test on every block and channel over
/// 16 independent frames of 4 spp each, at overall significance 1e-3 (Bonferroni). Also
/// asserted: each lobe is left out in some scene, and the first scene keeps the glass lobe.
#[test]
fn specialized_shaders_render_what_the_general_shader_renders() {
    // The seeds on two threads: each compiles a shader of its own, which the driver does on
    // one core (the renders use them all).
    let found: Vec<_> = std::thread::scope(|s| {
        let halves: Vec<_> = [0u32, 1]
            .map(|h| s.spawn(move || (h..16).step_by(2).map(check_seed).collect::<Vec<_>>()))
            .into_iter()
            .collect();
        halves.into_iter().flat_map(|h| h.join().unwrap()).collect()
    });
    let Some(found) = found.into_iter().collect::<Option<Vec<_>>>() else {
        return;
    };
    let mut left_out_somewhere = std::collections::BTreeSet::new();
    let mut alpha_somewhere = false;
    let mut identical = 0;
    for (left_out, alpha, same) in found {
        left_out_somewhere.extend(left_out);
        alpha_somewhere |= alpha;
        identical += usize::from(same);
    }
    println!(
        "{identical} of 16 scenes bit-identical; left out in some scene: {left_out_somewhere:?}"
    );
    assert!(alpha_somewhere, "no scene needs the alpha test");
    for f in [
        Feature::SpecularLobe,
        Feature::GlassLobe,
        Feature::MetalLobe,
        Feature::RoughDiffuse,
        Feature::Alpha,
    ] {
        assert!(
            left_out_somewhere.contains(f.label()),
            "{} never left out",
            f.label()
        );
    }
}

/// The WGSL options are written from the typed features, each feature to its own constant:
/// turning one feature off changes exactly its line.
#[test]
fn each_feature_sets_its_own_wgsl_constant() {
    let scene =
        GpuScene::build(&Scene::load(&common::repo("assets/cornell.ron")).unwrap()).unwrap();
    let options = lumagraph::pathtrace::specialize::PathTraceOptions::default();
    let all = Features::decide(&scene, options);
    let mut labels = std::collections::HashSet::new();
    for f in Feature::ALL {
        assert!(
            labels.insert(f.label()),
            "two features called {}",
            f.label()
        );
        let on = all.clone().with(f, true);
        let off = all.clone().with(f, false);
        // `WAVES` is derived: paths traced in steps, by host intersection or the wavefront.
        for x in [&on, &off] {
            let waves = x.kind().host_steps() || x.on(Feature::Wavefront);
            let line = format!("const WAVES: bool = {waves};");
            assert!(x.wgsl_options().lines().any(|l| l == line), "{f:?}: {line}");
        }
        let (on, off) = (on.wgsl_options(), off.wgsl_options());
        let changed: Vec<_> = on
            .lines()
            .zip(off.lines())
            .filter(|(a, b)| a != b && !a.starts_with("const WAVES:"))
            .collect();
        match f.wgsl_const() {
            Some(name) => assert_eq!(
                changed,
                [(
                    format!("const {name}: bool = true;").as_str(),
                    format!("const {name}: bool = false;").as_str()
                )],
                "{f:?}"
            ),
            None => assert!(changed.is_empty(), "{f:?}"),
        }
    }
}
