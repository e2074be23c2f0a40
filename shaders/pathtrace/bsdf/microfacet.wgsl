// GGX microfacet lobes with Schlick's Fresnel, shared by the material's lobes (bsdf.wgsl)
// and the clear coat (coat.wgsl): the distribution, height-correlated Smith shadowing,
// visible-normal sampling, and the albedo tables that make layers over them conserve energy
// (`ggx_table`, computed by crates/pathtrace/src/bsdf_tables.rs).
// Vectors are in the shading frame (normal = +z); wo points to the viewer.
// requires: var ggx_table (the GGX albedo tables of crates/pathtrace/src/bsdf_tables.rs:
//   integrator/pathtrace.wgsl, bsdf/bsdf_check.wgsl)
#import "common/sampling.wgsl"

// Below this alpha (= roughness^2) a lobe is a perfect mirror or interface.
const ALPHA_MIN: f32 = 1e-3;
const GGX_TABLE_N: u32 = 32u;

// A GGX lobe's roughness as its functions take it: perceptual roughness clamped to [0, 1],
// alpha^2, and whether it is a perfect mirror or interface.
struct LobeParams {
    roughness: f32,
    a2: f32,
    is_smooth: bool,
}

fn ggx_lobe(roughness: f32) -> LobeParams {
    let r = clamp(roughness, 0.0, 1.0);
    let alpha = r * r;
    return LobeParams(r, alpha * alpha, alpha < ALPHA_MIN);
}

// The N x N table starting at entry `first` of `ggx_table`, bilinearly interpolated at view
// cosine mu (along a row) and roughness (down the rows).
fn albedo_table(first: u32, mu: f32, roughness: f32) -> vec2f {
    let last = f32(GGX_TABLE_N - 1u);
    let x = clamp(mu, 0.0, 1.0) * last;
    let y = clamp(roughness, 0.0, 1.0) * last;
    let x0 = min(u32(x), GGX_TABLE_N - 2u);
    let y0 = min(u32(y), GGX_TABLE_N - 2u);
    let i = first + y0 * GGX_TABLE_N + x0;
    let lo = mix(ggx_table[i], ggx_table[i + 1u], x - f32(x0));
    let hi = mix(ggx_table[i + GGX_TABLE_N], ggx_table[i + GGX_TABLE_N + 1u], x - f32(x0));
    return mix(lo, hi, y - f32(y0));
}

// Albedo of a GGX lobe with Schlick Fresnel F0, F90 at view cosine mu is F0 t.x + F90 t.y.
fn ggx_albedo(mu: f32, roughness: f32) -> vec2f {
    return albedo_table(0u, mu, roughness);
}

// Cosine-weighted hemispherical average of `ggx_albedo`.
fn ggx_albedo_avg(roughness: f32) -> vec2f {
    let last = f32(GGX_TABLE_N - 1u);
    let y = clamp(roughness, 0.0, 1.0) * last;
    let y0 = min(u32(y), GGX_TABLE_N - 2u);
    let base = GGX_TABLE_N * GGX_TABLE_N;
    return mix(ggx_table[base + y0], ggx_table[base + y0 + 1u], y - f32(y0));
}

fn ggx_d(z: f32, a2: f32) -> f32 {
    let t = z * z * (a2 - 1.0) + 1.0;
    return a2 / (PI * t * t);
}

fn smith_term(z: f32, a2: f32) -> f32 {
    return sqrt(a2 + (1.0 - a2) * z * z);
}

fn smith_g1(z: f32, a2: f32) -> f32 {
    return 2.0 * z / (z + smith_term(z, a2));
}

// Height-correlated masking-shadowing.
fn smith_g2(zo: f32, zi: f32, a2: f32) -> f32 {
    return 2.0 * zo * zi / (zo * smith_term(zi, a2) + zi * smith_term(zo, a2));
}

// Visible normal of GGX seen from wo (wo.z > 0), by the spherical cap method
// (Dupuy and Benyoub 2023).
fn sample_vndf(wo: vec3f, alpha: f32, u: vec2f) -> vec3f {
    let v = normalize(vec3f(wo.xy * alpha, wo.z));
    let phi = TWO_PI * u.x;
    let z = (1.0 - u.y) * (1.0 + v.z) - v.z;
    let sin_t = sqrt(clamp(1.0 - z * z, 0.0, 1.0));
    let h = vec3f(sin_t * cos(phi), sin_t * sin(phi), z) + v;
    return normalize(vec3f(h.xy * alpha, max(h.z, 1e-7)));
}

// Reflectance at grazing incidence: 1 for real materials, 0 when F0 is 0, so a material
// with no specular is purely Lambertian (F90 = min(1, 50 F0), as Filament does).
fn schlick_f90(f0: vec3f) -> f32 {
    return clamp(50.0 * max(f0.x, max(f0.y, f0.z)), 0.0, 1.0);
}

// Schlick's Fresnel from its reflectance at normal (f0) and grazing (f90) incidence.
struct Fresnel {
    f0: vec3f,
    f90: f32,
}

fn schlick_fresnel(f0: vec3f) -> Fresnel {
    return Fresnel(f0, schlick_f90(f0));
}

fn fresnel_at(f: Fresnel, c: f32) -> vec3f {
    let m = clamp(1.0 - c, 0.0, 1.0);
    let m2 = m * m;
    return f.f0 + (f.f90 - f.f0) * (m2 * m2 * m);
}

// Albedo of a GGX lobe with Fresnel `fresnel_at(f, .)` from the (A, B) table entry t (A
// weights F0, B weights F90).
fn fresnel_albedo(f: Fresnel, t: vec2f) -> vec3f {
    return f.f0 * t.x + f.f90 * t.y;
}

fn schlick(f0: vec3f, c: f32) -> vec3f {
    return fresnel_at(schlick_fresnel(f0), c);
}

fn lobe_albedo(f0: vec3f, t: vec2f) -> vec3f {
    return fresnel_albedo(schlick_fresnel(f0), t);
}

// f * cos(wi) of a lobe (or the whole non-delta BSDF) and the solid-angle pdf of its sampling.
struct BsdfEval {
    f_cos: vec3f,
    pdf: f32,
}
