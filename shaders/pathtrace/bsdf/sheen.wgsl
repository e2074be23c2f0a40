// Sheen (glTF KHR_materials_sheen): the retro-reflective velvet of cloth, over the rest of
// the material and under the clear coat. The glTF specification's lobe: the "Charlie"
// microfiber distribution
//     D(h) = (2 + 1/alpha) sin(theta_h)^(1/alpha) / (2 pi),  alpha = roughness^2,
// with the visibility of Estevez and Kulla (2017), V = 1 / ((1 + L(mu_o) + L(mu_i)) 4 mu_o mu_i)
// clamped to [0, 1], L their fit of the shadowing; f = sheen_color D V. The layers below are
// scaled by 1 - max(sheen_color) E_s(mu_o) (E_s the lobe's directional albedo at colour 1,
// from the table crates/pathtrace/src/bsdf_tables.rs appends to the GGX tables), as glTF's
// albedo scaling does. Sampled by the cosine.
// Uses nothing its includer must define; bsdf/microfacet.wgsl declares the `ggx_table` it
// reads (the sheen table follows the GGX tables).
#import "common/sampling.wgsl"
#import "pathtrace/bsdf/microfacet.wgsl"

// Perceptual roughness below this is taken as this: the distribution of a smaller one is a
// spike at grazing angles that no table resolves (Filament clamps to 0.07 too).
const SHEEN_ROUGHNESS_MIN: f32 = 0.07;

fn sheen_alpha(roughness: f32) -> f32 {
    let r = clamp(roughness, SHEEN_ROUGHNESS_MIN, 1.0);
    return r * r;
}

fn sheen_d(cos_h: f32, alpha: f32) -> f32 {
    let inv = 1.0 / alpha;
    let sin2 = max(1.0 - cos_h * cos_h, 0.0);
    return (2.0 + inv) * pow(sin2, 0.5 * inv) / (2.0 * PI);
}

// Estevez and Kulla's fit of the Charlie distribution's shadowing, in the form the glTF
// sample renderer gives it.
fn sheen_lambda_fit(x: f32, alpha: f32) -> f32 {
    let t = (1.0 - alpha) * (1.0 - alpha);
    let a = mix(21.5473, 25.3245, t);
    let b = mix(3.82987, 3.32435, t);
    let c = mix(0.19823, 0.16801, t);
    let d = mix(-1.97760, -1.27393, t);
    let e = mix(-4.32054, -4.85967, t);
    return a / (1.0 + b * pow(x, c)) + d * x + e;
}

fn sheen_lambda(mu: f32, alpha: f32) -> f32 {
    if mu < 0.5 {
        return exp(sheen_lambda_fit(mu, alpha));
    }
    return exp(2.0 * sheen_lambda_fit(0.5, alpha) - sheen_lambda_fit(1.0 - mu, alpha));
}

// f * cos of the sheen lobe at colour 1 (wo.z, wi.z > 0).
fn sheen_f_cos(alpha: f32, wo: vec3f, wi: vec3f) -> f32 {
    let h = normalize(wo + wi);
    let v = clamp(1.0 / ((1.0 + sheen_lambda(wo.z, alpha) + sheen_lambda(wi.z, alpha)) * (4.0 * wo.z * wi.z)), 0.0, 1.0);
    return sheen_d(h.z, alpha) * v * wi.z;
}

// The lobe's directional albedo at colour 1, view cosine mu and perceptual roughness r: the
// table after the GGX tables (x of each entry).
fn sheen_albedo(mu: f32, roughness: f32) -> f32 {
    return albedo_table(GGX_TABLE_N * GGX_TABLE_N + GGX_TABLE_N, mu, roughness).x;
}
