// The clear coat (glTF KHR_materials_clearcoat): a dielectric layer of ior 1.5 (F0 = 0.04,
// Schlick's Fresnel) on top of the material, a perfect mirror or a GGX lobe of its own
// roughness, weighted by `clearcoat`. What the coat does not reflect reaches the layers below
// (bsdf.wgsl's `eval_bsdf` scales them by 1 - clearcoat E_c(mu_o), E_c the coat's directional
// albedo from the GGX tables: albedo scaling, as glTF's layering does with the view angle).
// The coat has a normal of its own (`coat_normal`): glTF's coat is smooth where the base is
// normal-mapped, or follows its own normal map. Its lobe and albedo are taken in its frame,
// with its cosines; it reflects nothing towards or from below its own horizon. A tinted coat
// (`clearcoat_tint`) multiplies what lies below it by `CoatParams::through`.
#import "pathtrace/scene_types.wgsl"
#import "pathtrace/bsdf/microfacet.wgsl"
#import "common/sampling.wgsl"

// The coat's normal at the point shaded, in the shading frame of the base (+z where it
// shares the base's normal), set by whoever shades the point (`bounce_path`).
var<private> coat_normal: vec3f = vec3f(0.0, 0.0, 1.0);

// Whether the coat's normal is the base's: then its frame is the base's, exactly.
fn coat_shares_normal() -> bool {
    return all(coat_normal == vec3f(0.0, 0.0, 1.0));
}

// `w` (shading frame) in the coat's frame.
fn to_coat(w: vec3f) -> vec3f {
    if coat_shares_normal() {
        return w;
    }
    return transpose(onb(coat_normal)) * w;
}

// `w` (coat frame) in the shading frame.
fn from_coat(w: vec3f) -> vec3f {
    if coat_shares_normal() {
        return w;
    }
    return onb(coat_normal) * w;
}

const COAT_F0: f32 = 0.04;

struct CoatParams {
    // `clearcoat` in [0, 1].
    weight: f32,
    lobe: LobeParams,
    // What the layers below are multiplied by besides the share the coat reflects
    // (1 - coat_albedo): white for a clear coat. bsdf.wgsl's layering applies it to their
    // evaluation and to their delta samples' weights.
    through: vec3f,
}

// What passes a coat of weight w and tint T (`clearcoat_tint`, Standard Surface's
// `coat_color`): 1 + w (T - 1), exactly 1 for a white tint.
fn coat_params(m: Material) -> CoatParams {
    let w = clamp(m.clearcoat, 0.0, 1.0);
    return CoatParams(w, ggx_lobe(m.clearcoat_roughness), 1.0 + w * (m.clearcoat_tint - 1.0));
}

// No coat: nothing reflected, everything through.
fn no_coat() -> CoatParams {
    return CoatParams(0.0, ggx_lobe(0.0), vec3f(1.0));
}

// The coat's directional albedo (its weight included) at view cosine mu: what it reflects
// and so takes from the layers below, and the probability of sampling it.
fn coat_albedo(c: CoatParams, mu: f32) -> f32 {
    if c.lobe.is_smooth {
        return c.weight * schlick(vec3f(COAT_F0), mu).x;
    }
    return c.weight * lobe_albedo(vec3f(COAT_F0), ggx_albedo(mu, c.lobe.roughness)).x;
}

// The rough coat's f * cos (weight included; its own cosine) and the density of its
// visible-normal sampling, for directions in the coat's frame; zero for a smooth coat (a
// delta lobe, reached by sampling only) and below the coat's horizon.
fn coat_eval(c: CoatParams, wo: vec3f, wi: vec3f) -> BsdfEval {
    let a2 = c.lobe.a2;
    if c.lobe.is_smooth || wo.z <= 0.0 || wi.z <= 0.0 {
        return BsdfEval(vec3f(0.0), 0.0);
    }
    let h = normalize(wo + wi);
    let d = ggx_d(h.z, a2);
    let fresnel = schlick(vec3f(COAT_F0), dot(wo, h)).x;
    let f_cos = c.weight * fresnel * d * smith_g2(wo.z, wi.z, a2) / (4.0 * wo.z);
    return BsdfEval(vec3f(f_cos), smith_g1(wo.z, a2) * d / (4.0 * wo.z));
}

// A direction reflected by the coat: the mirror direction, or one by visible normals.
fn coat_sample(c: CoatParams, wo: vec3f, u: vec2f) -> vec3f {
    if c.lobe.is_smooth {
        return vec3f(-wo.xy, wo.z);
    }
    let mh = sample_vndf(wo, sqrt(c.lobe.a2), u);
    return 2.0 * dot(wo, mh) * mh - wo;
}
