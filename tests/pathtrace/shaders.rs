//! Every WGSL file under `shaders/`, with its imports resolved exactly as the program
//! resolves them, parses and validates with naga: a broken shader fails here without a GPU.
//! Files with an entry point that no other file imports are validated as they are; the
//! others are fragments (they use bindings or functions their includer declares — the
//! generic post filter's `post/filter.wgsl` even holds the entry point), validated through
//! every entry that imports them, and each must be imported by at least one.

use lumagraph::render::shader;

/// The shaders the program loads as they are: files with an entry point that no other file
/// imports.
fn entry_shaders() -> Vec<&'static str> {
    let names: Vec<_> = shader::all_names().collect();
    let has_entry = |name: &str| {
        let text = shader::resolve(name).unwrap();
        ["@compute", "@vertex", "@fragment"]
            .iter()
            .any(|e| text.contains(e))
    };
    let imported = |name: &str| {
        names.iter().any(|other| {
            *other != name
                && shader::raw(other)
                    .unwrap()
                    .lines()
                    .any(|l| l.trim_start().starts_with("#import") && l.contains(name))
        })
    };
    names
        .iter()
        .copied()
        .filter(|n| has_entry(n) && !imported(n))
        .collect()
}

/// Fragments only the path tracer's specialization imports (in place of
/// `pathtrace/intersect.wgsl`), with the whole shader it assembles around each.
fn specialized_sources() -> Vec<(&'static str, String)> {
    use lumagraph::pathtrace::specialize::{Intersector, PathTraceOptions, Specialization};
    use lumagraph::scene::{GpuScene, Scene};
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/cornell_spheres.ron");
    let scene = GpuScene::build(&Scene::load(&path).unwrap()).unwrap();
    let ray_queries = PathTraceOptions {
        specialize: true,
        ray_query_limit: Some(1 << 24),
        intersector: Intersector::RAY_QUERIES,
        ..PathTraceOptions::default()
    };
    let source = Specialization::new(&scene, ray_queries).source().unwrap();
    assert!(source.contains("rayQueryInitialize"));
    let wide = PathTraceOptions {
        specialize: true,
        intersector: Intersector::WIDE_BVH,
        ..PathTraceOptions::default()
    };
    let wide_source = Specialization::new(&scene, wide).source().unwrap();
    assert!(wide_source.contains("WIDE_ROBUST_FAR"));
    vec![
        ("pathtrace/intersect/ray_query.wgsl", source),
        ("pathtrace/intersect/wide_bvh.wgsl", wide_source),
    ]
}

#[test]
fn every_shader_validates_with_naga() {
    let names: Vec<_> = shader::all_names().collect();
    assert!(names.len() >= 4, "shaders not embedded: {names:?}");
    let entries = entry_shaders();
    let specialized = specialized_sources();
    let mut failures = Vec::new();
    for name in &names {
        if entries.contains(name) {
            continue;
        }
        let imported = entries
            .iter()
            .any(|e| shader::imports(e).unwrap().iter().any(|i| i == name))
            || specialized.iter().any(|(s, _)| s == name);
        if !imported {
            failures.push(format!(
                "{name}: a fragment no entry shader imports, so it is never checked"
            ));
        }
    }
    let sources = entries
        .iter()
        .map(|&name| (name, shader::resolve(name).unwrap()))
        .chain(specialized);
    for (name, source) in sources {
        let module = match naga::front::wgsl::parse_str(&source) {
            Ok(m) => m,
            Err(e) => {
                failures.push(format!("{name}: {}", e.emit_to_string(&source)));
                continue;
            }
        };
        let mut validator = naga::valid::Validator::new(
            naga::valid::ValidationFlags::all(),
            naga::valid::Capabilities::all(),
        );
        if let Err(e) = validator.validate(&module) {
            failures.push(format!("{name}: {}", e.emit_to_string(&source)));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The identifiers of WGSL source `text` (comments left out, and members after a `.`),
/// each with the character that follows it (`(` for a call, `:` for a parameter or a
/// member declared).
fn identifiers(text: &str) -> Vec<(String, char)> {
    let code: String = text
        .lines()
        .map(|l| l.split("//").next().unwrap_or(""))
        .collect::<Vec<_>>()
        .join("\n");
    let chars: Vec<char> = code.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        if c.is_ascii_alphabetic() || c == '_' {
            let start = i;
            while i < chars.len() && (chars[i].is_ascii_alphanumeric() || chars[i] == '_') {
                i += 1;
            }
            let word: String = chars[start..i].iter().collect();
            let mut j = i;
            while j < chars.len() && chars[j].is_whitespace() {
                j += 1;
            }
            let preceded_by_dot = start > 0 && chars[start - 1] == '.';
            if !preceded_by_dot {
                out.push((word, chars.get(j).copied().unwrap_or(' ')));
            }
        } else if c.is_ascii_digit() {
            while i < chars.len() && (chars[i].is_ascii_alphanumeric() || chars[i] == '.') {
                i += 1;
            }
        } else {
            i += 1;
        }
    }
    out
}

/// The module-scope names `text` declares, each with its kind (`fn`, `struct`, `const`,
/// `alias`, `override` or `var`): functions, structs, constants, variables (what is inside
/// braces, bodies and members, left out).
fn declared(text: &str) -> std::collections::BTreeMap<String, &'static str> {
    let mut depth = 0usize;
    let mut top = String::new();
    for line in text.lines() {
        for c in line.split("//").next().unwrap_or("").chars() {
            match c {
                '{' => depth += 1,
                '}' => depth = depth.saturating_sub(1),
                _ if depth == 0 => top.push(c),
                _ => {}
            }
        }
        top.push('\n');
    }
    let words = identifiers(&top);
    let mut out = std::collections::BTreeMap::new();
    for (k, (word, _)) in words.iter().enumerate() {
        let kind = match word.as_str() {
            "fn" => "fn",
            "struct" => "struct",
            "const" => "const",
            "alias" => "alias",
            "override" => "override",
            _ => continue,
        };
        if let Some((name, _)) = words.get(k + 1) {
            out.insert(name.clone(), kind);
        }
    }
    // `var<storage, read> name`, `var<private> name`, `var name`: the first word after the
    // address space that is not one.
    for (k, (word, _)) in words.iter().enumerate() {
        if word == "var" {
            let name = words[k + 1..].iter().map(|(w, _)| w).find(|w| {
                !matches!(
                    w.as_str(),
                    "storage"
                        | "read"
                        | "read_write"
                        | "private"
                        | "uniform"
                        | "workgroup"
                        | "function"
                )
            });
            if let Some(name) = name {
                out.insert(name.clone(), "var");
            }
        }
    }
    out
}

/// What a file's `// requires:` lines declare it leaves to its includer, as (kind, name)
/// pairs: each line is `// requires: KIND NAME, KIND NAME, ... (where it comes from)`,
/// KIND one of `fn`, `var` (a binding or module-scope variable), `const`, `struct`,
/// `alias`, `override`. Malformed items are returned as errors.
fn requires(text: &str) -> (Vec<(String, String)>, Vec<String>) {
    let mut out = Vec::new();
    let mut errors = Vec::new();
    for line in text.lines() {
        let Some(rest) = line.trim_start().strip_prefix("// requires:") else {
            continue;
        };
        let list = rest.split('(').next().unwrap_or("");
        for item in list.split(',') {
            let parts: Vec<&str> = item.split_whitespace().collect();
            match parts.as_slice() {
                [kind, name]
                    if matches!(
                        *kind,
                        "fn" | "var" | "const" | "struct" | "alias" | "override"
                    ) && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') =>
                {
                    out.push(((*kind).to_owned(), (*name).to_owned()));
                }
                _ => errors.push(format!("malformed `// requires:` item {:?}", item.trim())),
            }
        }
    }
    (out, errors)
}

/// No file of the path tracer leans on its includer unannounced, and none announces what it
/// no longer needs. What a file of `shaders/pathtrace/` or `shaders/common/` uses (a
/// function it calls, a struct or constant it names, a module-scope variable or binding it
/// reads) and neither it nor what it imports defines is left to its includer; exactly those
/// names, with their kinds, must be declared on the file's `// requires:` lines.
///
/// An identifier scan, not a compiler: "uses" means the name appears outside comments and
/// import lines, not after a `.`, and is not a local or parameter of the file; only names
/// that some file of those folders (or the generated `pathtrace/shared.wgsl`,
/// `pathtrace/shapes.wgsl` and `pathtrace/material.wgsl`) declares at module scope are considered, so a name only
/// generated code (specialization's replacements) defines is not caught, and a local that
/// shadows a module-scope name of the same spelling counts as a local.
#[test]
fn every_path_tracer_file_imports_or_requires_what_it_uses() {
    let names: Vec<&str> = shader::all_names()
        .filter(|n| n.starts_with("pathtrace/") || n.starts_with("common/"))
        .collect();
    let mut everywhere = std::collections::BTreeMap::new();
    for name in names.iter().copied().chain([
        "pathtrace/shared.wgsl",
        "pathtrace/shapes.wgsl",
        "pathtrace/material.wgsl",
    ]) {
        everywhere.extend(declared(&shader::raw(name).unwrap()));
    }
    let mut failures = Vec::new();
    for name in &names {
        let own = shader::raw(name).unwrap();
        let visible = declared(&shader::resolve(name).unwrap());
        // The import lines name files, not what the file uses.
        let code: Vec<&str> = own
            .lines()
            .filter(|l| !l.trim_start().starts_with("#import"))
            .collect();
        let words = identifiers(&code.join("\n"));
        // Names the file declares for itself inside functions: locals and parameters.
        let locals: std::collections::BTreeSet<&str> = words
            .iter()
            .enumerate()
            .filter(|(k, (_, next))| {
                *next == ':' || (*k > 0 && matches!(words[k - 1].0.as_str(), "let" | "var"))
            })
            .map(|(_, (w, _))| w.as_str())
            .collect();
        let missing: std::collections::BTreeMap<&str, &str> = words
            .iter()
            .filter(|(w, next)| *next == '(' || !locals.contains(w.as_str()))
            .filter_map(|(w, _)| everywhere.get_key_value(w.as_str()))
            .filter(|(w, _)| !visible.contains_key(w.as_str()))
            .map(|(w, kind)| (w.as_str(), *kind))
            .collect();
        let (required, errors) = requires(&own);
        failures.extend(errors.into_iter().map(|e| format!("{name}: {e}")));
        let required: std::collections::BTreeMap<&str, &str> = required
            .iter()
            .map(|(kind, w)| (w.as_str(), kind.as_str()))
            .collect();
        let undeclared: Vec<String> = missing
            .iter()
            .filter(|(w, kind)| required.get(*w) != Some(*kind))
            .map(|(w, kind)| format!("{kind} {w}"))
            .collect();
        if !undeclared.is_empty() {
            failures.push(format!(
                "{name}: uses {} without importing it or declaring it on a `// requires:` line",
                undeclared.join(", ")
            ));
        }
        let stale: Vec<String> = required
            .iter()
            .filter(|(w, kind)| missing.get(*w) != Some(*kind))
            .map(|(w, kind)| format!("{kind} {w}"))
            .collect();
        if !stale.is_empty() {
            failures.push(format!(
                "{name}: `// requires:` names {}, which it does not use, imports, or declares \
                 with another kind",
                stale.join(", ")
            ));
        }
    }
    assert!(names.len() >= 20, "{} files", names.len());
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn imports_are_resolved_once() {
    let text = shader::resolve("post/tonemap.wgsl").unwrap();
    assert_eq!(text.matches("fn srgb_encode").count(), 1);
    assert!(!text.contains("#import"));
}

#[test]
fn missing_shader_is_an_error_not_a_panic() {
    let e = shader::resolve("post/nope.wgsl").unwrap_err();
    assert!(e.to_string().contains("no such shader file"), "{e}");
}

/// Every compute shader declares only bindings kernels support, numbered from 0 in group 0,
/// and an entry point `main`: what `Kernel` reads instead of a list in Rust.
#[test]
fn every_compute_shader_reflects_its_bindings() {
    let mut checked = 0;
    for name in entry_shaders() {
        if !shader::resolve(name).unwrap().contains("@compute") {
            continue;
        }
        let source = shader::resolve(name).unwrap();
        let (bindings, workgroup) =
            lumagraph::render::kernel::reflect(name, &source).unwrap_or_else(|e| panic!("{e}"));
        assert!(!bindings.is_empty() && workgroup[0] > 0, "{name}");
        checked += 1;
    }
    assert!(checked >= 8, "{checked} compute shaders");
}

/// Textures in a shader with a filtering sampler are reflected as filterable (2D and 3D),
/// the sampler as a sampler; without a sampler a texture stays a plain `textureLoad` one.
#[test]
fn samplers_make_textures_filterable() {
    use lumagraph::render::Binding;
    use lumagraph::render::kernel::reflect;
    let source = "
        @group(0) @binding(0) var image: texture_2d<f32>;
        @group(0) @binding(1) var lut: texture_3d<f32>;
        @group(0) @binding(2) var smp: sampler;
        @group(0) @binding(3) var out: texture_storage_2d<rgba32float, write>;
        @compute @workgroup_size(8, 8)
        fn main(@builtin(global_invocation_id) id: vec3u) {
            let c = textureSampleLevel(image, smp, vec2f(0.5), 0.0);
            let g = textureSampleLevel(lut, smp, c.rgb, 0.0);
            textureStore(out, id.xy, g);
        }";
    let (bindings, _) = reflect("lut", source).unwrap();
    assert_eq!(
        bindings,
        [
            Binding::FilteredTexture {
                dim: wgpu::TextureViewDimension::D2
            },
            Binding::FilteredTexture {
                dim: wgpu::TextureViewDimension::D3
            },
            Binding::Sampler,
            Binding::StorageTexture {
                format: wgpu::TextureFormat::Rgba32Float,
                access: wgpu::StorageTextureAccess::WriteOnly
            },
        ]
    );
    let resize = shader::resolve("post/resize.wgsl").unwrap();
    let (bindings, _) = reflect("post/resize.wgsl", &resize).unwrap();
    assert_eq!(bindings[1], Binding::Sampler);
    let exposure = shader::resolve("post/exposure.wgsl").unwrap();
    let (bindings, _) = reflect("post/exposure.wgsl", &exposure).unwrap();
    assert_eq!(bindings[0], Binding::Texture);
}
