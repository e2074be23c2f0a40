// The material model: three lobes mixed by metallic and transmission.
//   dielectric layer  (1 - metallic)(1 - transmission): GGX specular with Schlick Fresnel
//                     (F0 = 0.08 specular, tinted by specular_tint, times specular_color;
//                     `dielectric_fresnel`) over a Lambertian base
//                     that receives exactly the energy the specular does not reflect, or
//                     with diffuse_roughness > 0 an energy-preserving Oren-Nayar base (EON,
//                     eon.wgsl, compiled in with HAS_ROUGH_DIFFUSE) weighted the same way;
//   metal             metallic: GGX with Schlick Fresnel on base_color, or the exact
//                     conductor Fresnel of a complex index eta + i k (MATERIAL_CONDUCTOR),
//                     plus Kulla-Conty multiple-scattering compensation;
//   glass             (1 - metallic) transmission: dielectric interface (exact Fresnel with
//                     ior), reflection or refraction chosen by Fresnel, rough by GGX.
// Over these, layered by albedo scaling (`eval_bsdf`, `sample_bsdf`): glTF's sheen
// (sheen.wgsl, compiled in with HAS_SHEEN), and on top the clear coat (coat.wgsl, HAS_COAT).
// MATERIAL_SINGLE_SCATTER leaves out what stands in for multiple scattering (the metal's
// Kulla-Conty term; rough glass's reflections into the surface, sent back out, and its
// missing shadowing of the outgoing direction), as Mitsuba's roughconductor and
// roughdielectric do.
// The GGX albedo tables (`ggx_table`, computed by crates/pathtrace/src/bsdf_tables.rs and
// declared by the includer) make the white furnace white at every roughness.
// Vectors are in the shading frame (normal = +z); wo points to the viewer.
// Uses nothing its includer must define; what its imports need they declare (`ggx_table`,
// bsdf/microfacet.wgsl).
#import "pathtrace/scene_types.wgsl"
#import "pathtrace/options.wgsl"
#import "common/color.wgsl"
#import "common/sampling.wgsl"
#import "pathtrace/bsdf/eon.wgsl"
#import "pathtrace/bsdf/microfacet.wgsl"
#import "pathtrace/bsdf/coat.wgsl"
#import "pathtrace/bsdf/sheen.wgsl"

// The largest f32 below 1.
const ONE_MINUS_EPSILON: f32 = 0.99999994;

// Unpolarized Fresnel reflectance of a conductor of complex index eta + i k (per channel) at
// incidence cosine cos_i; mirrors crates/scene/src/conductor.rs.
fn fresnel_conductor(cos_i: f32, eta: vec3f, k: vec3f) -> vec3f {
    let c2 = clamp(cos_i * cos_i, 0.0, 1.0);
    let s2 = 1.0 - c2;
    let t0 = eta * eta - k * k - s2;
    let a2b2 = sqrt(max(t0 * t0 + 4.0 * eta * eta * k * k, vec3f(0.0)));
    let t1 = a2b2 + c2;
    let a = sqrt(max(0.5 * (a2b2 + t0), vec3f(0.0)));
    let t2 = 2.0 * abs(cos_i) * a;
    let rs = (t1 - t2) / max(t1 + t2, vec3f(1e-30));
    let t3 = c2 * a2b2 + s2 * s2;
    let t4 = t2 * s2;
    let rp = rs * (t3 - t4) / max(t3 + t4, vec3f(1e-30));
    return clamp(0.5 * (rs + rp), vec3f(0.0), vec3f(1.0));
}

fn is_conductor(m: Material) -> bool {
    return (m.flags & MATERIAL_CONDUCTOR) != 0u;
}

fn multiscatter(m: Material) -> bool {
    return (m.flags & MATERIAL_SINGLE_SCATTER) == 0u;
}

// The metal lobe's Fresnel reflectance at microfacet cosine c.
fn metal_fresnel(m: Material, c: f32) -> vec3f {
    if is_conductor(m) {
        return fresnel_conductor(c, m.eta, m.k);
    }
    return schlick(m.base_color, c);
}

// Its cosine-weighted hemispherical average (Schlick's in closed form; a conductor's is
// integrated on the CPU).
fn metal_fresnel_avg(m: Material) -> vec3f {
    if is_conductor(m) {
        return m.f_avg;
    }
    let f0 = m.base_color;
    return f0 + (schlick_f90(f0) - f0) / 21.0;
}

// Unpolarized Fresnel reflectance of a dielectric interface; eta = eta_t / eta_i.
fn fresnel_dielectric(cos_i: f32, eta: f32) -> f32 {
    let sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = sqrt(1.0 - sin2_t);
    let rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    let rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    return 0.5 * (rs * rs + rp * rp);
}

// Mixing weights (dielectric layer, metal, glass); they sum to 1 and are also the
// probabilities of sampling each lobe.
fn lobe_weights(m: Material) -> vec3f {
    let metal = clamp(m.metallic, 0.0, 1.0);
    let t = clamp(m.transmission, 0.0, 1.0);
    return vec3f((1.0 - metal) * (1.0 - t), metal, (1.0 - metal) * t);
}

// The dielectric specular's Fresnel: F0 = 0.08 specular, tinted towards the base colour by
// specular_tint, then times specular_color and clamped to 1. F90 is taken from F0 before
// specular_color, which (as glTF's KHR_materials_specular has it) colours normal incidence
// only: the grazing reflection of a material with specular > 0 stays white.
fn dielectric_fresnel(m: Material) -> Fresnel {
    let l = luminance(m.base_color);
    let tint = select(vec3f(1.0), m.base_color / l, l > 0.0);
    let f0 = clamp(0.08 * m.specular, 0.0, 1.0) * mix(vec3f(1.0), tint, clamp(m.specular_tint, 0.0, 1.0));
    return Fresnel(min(f0 * m.specular_color, vec3f(1.0)), schlick_f90(f0));
}

// Whether the dielectric layer's diffuse base is EON (else Lambertian).
fn rough_diffuse(m: Material) -> bool {
    return HAS_ROUGH_DIFFUSE && m.diffuse_roughness > 0.0;
}

fn diffuse_roughness(m: Material) -> f32 {
    return clamp(m.diffuse_roughness, 0.0, 1.0);
}

// Probability of sampling the specular part of the dielectric layer.
fn layer_spec_prob(m: Material, es_o: vec3f) -> f32 {
    let s = luminance(es_o);
    let d = luminance(m.base_color * (1.0 - es_o));
    return clamp(s / max(s + d, 1e-6), 0.1, 0.9);
}

// `layer_spec_prob`, or 0 for a rough diffuse base with no specular at all (F90 = 0, which
// makes F0 = 0 too).
fn layer_spec_sample_prob(m: Material, f: Fresnel, es_o: vec3f) -> f32 {
    if rough_diffuse(m) && f.f90 == 0.0 {
        return 0.0;
    }
    return layer_spec_prob(m, es_o);
}

// Probability of sampling the single-scattering part of the metal lobe (the rest is
// cosine-sampled for the multiple-scattering term).
fn metal_ss_prob(e_o: f32) -> f32 {
    return clamp(e_o, 0.25, 1.0);
}

fn lobe_params(m: Material) -> LobeParams {
    return ggx_lobe(m.roughness);
}

// `metal_ss_prob`, or 1 where there is no multiple-scattering term to sample.
fn metal_ss_sample_prob(m: Material, lp: LobeParams, e_o: f32) -> f32 {
    return select(metal_ss_prob(e_o), 1.0, lp.is_smooth || !multiscatter(m));
}

// The three lobes without the layers on top (`eval_bsdf`).
fn eval_base(m: Material, wo: vec3f, wi: vec3f) -> BsdfEval {
    var out = BsdfEval(vec3f(0.0), 0.0);
    if wo.z <= 0.0 || wi.z <= 0.0 {
        return out;
    }
    let w = lobe_weights(m);
    let cos_pdf = wi.z * INV_PI;
    if !HAS_SPECULAR && !HAS_METAL {
        // The scene has only diffuse and glass lobes: no microfacet code compiled in.
        if rough_diffuse(m) {
            let r = diffuse_roughness(m);
            out.f_cos = w.x * eon_f(m.base_color, r, wo, wi) * wi.z;
            out.pdf = w.x * eon_pdf(wo, wi, r);
            return out;
        }
        out.f_cos = w.x * m.base_color * cos_pdf;
        out.pdf = w.x * cos_pdf;
        return out;
    }
    let lp = lobe_params(m);
    let h = normalize(wo + wi);
    var g2_over = 0.0;
    var vndf_pdf = 0.0;
    if !lp.is_smooth {
        let d = ggx_d(h.z, lp.a2);
        // D * G2 / (4 wo.z): f * cos(wi) of the microfacet lobe without Fresnel.
        g2_over = d * smith_g2(wo.z, wi.z, lp.a2) / (4.0 * wo.z);
        vndf_pdf = smith_g1(wo.z, lp.a2) * d / (4.0 * wo.z);
    }
    let to = ggx_albedo(wo.z, lp.roughness);
    let ti = ggx_albedo(wi.z, lp.roughness);
    let ta = ggx_albedo_avg(lp.roughness);
    if w.x > 0.0 {
        let f = dielectric_fresnel(m);
        let es_o = fresnel_albedo(f, to);
        let es_i = fresnel_albedo(f, ti);
        let es_avg = fresnel_albedo(f, ta);
        var diffuse = m.base_color * (1.0 - es_o) * (1.0 - es_i) / (PI * max(1.0 - es_avg, vec3f(1e-4))) * wi.z;
        var diffuse_pdf = cos_pdf;
        if rough_diffuse(m) {
            // EON in place of rho / pi, with the same (reciprocal) weighting by what the
            // specular leaves.
            let r = diffuse_roughness(m);
            diffuse = eon_f(m.base_color, r, wo, wi) * (1.0 - es_o) * (1.0 - es_i) / max(1.0 - es_avg, vec3f(1e-4)) * wi.z;
            diffuse_pdf = eon_pdf(wo, wi, r);
        }
        let spec = g2_over * fresnel_at(f, dot(wo, h));
        let ps = layer_spec_sample_prob(m, f, es_o);
        out.f_cos += w.x * (diffuse + spec);
        out.pdf += w.x * (ps * vndf_pdf + (1.0 - ps) * diffuse_pdf);
    }
    if HAS_METAL && w.y > 0.0 {
        let e_o = to.x + to.y;
        let ss = g2_over * metal_fresnel(m, dot(wo, h));
        var ms = vec3f(0.0);
        if multiscatter(m) {
            let e_i = ti.x + ti.y;
            let e_avg = ta.x + ta.y;
            let f_avg = metal_fresnel_avg(m);
            let f_ms = f_avg * f_avg * e_avg / (1.0 - f_avg * (1.0 - e_avg));
            ms = f_ms * (1.0 - e_o) * (1.0 - e_i) / (PI * max(1.0 - e_avg, 1e-4)) * wi.z;
        }
        let q = metal_ss_sample_prob(m, lp, e_o);
        out.f_cos += w.y * (ss + ms);
        out.pdf += w.y * (q * vndf_pdf + (1.0 - q) * cos_pdf);
    }
    return out;
}

struct BsdfSample {
    wi: vec3f,
    // f * cos / pdf of the sampling actually done.
    weight: vec3f,
    // Solid-angle pdf for MIS; 0 for mirror, interface and glass samples (not light-sampled).
    pdf: f32,
    valid: bool,
}

fn sample_glass(m: Material, lp: LobeParams, wo: vec3f, u: vec3f) -> BsdfSample {
    // Work on the side wo is on: flip z so that wo_l.z > 0.
    let s = select(-1.0, 1.0, wo.z >= 0.0);
    let wo_l = vec3f(wo.xy, abs(wo.z));
    let eta = select(1.0 / m.ior, m.ior, s > 0.0);
    var mh = vec3f(0.0, 0.0, 1.0);
    if !lp.is_smooth {
        mh = sample_vndf(wo_l, sqrt(lp.a2), u.xy);
    }
    let c = dot(wo_l, mh);
    let f = fresnel_dielectric(c, eta);
    var wi: vec3f;
    var weight = vec3f(1.0);
    let single = !lp.is_smooth && !multiscatter(m);
    if u.z < f {
        wi = 2.0 * c * mh - wo_l;
        // A reflection into the surface would scatter again on the microsurface; send it
        // out mirrored instead, which keeps the energy (a multiple-scattering stand-in), or
        // lose it (single scattering).
        if single && wi.z <= 0.0 {
            return BsdfSample(vec3f(0.0, 0.0, 1.0), vec3f(0.0), 0.0, false);
        }
        wi.z = abs(wi.z);
    } else {
        wi = refract(-wo_l, mh, 1.0 / eta);
        if single && wi.z >= 0.0 {
            return BsdfSample(vec3f(0.0, 0.0, 1.0), vec3f(0.0), 0.0, false);
        }
        wi.z = -abs(wi.z);
        // Radiance is compressed into a smaller solid angle entering a denser medium.
        weight = m.base_color / (eta * eta);
    }
    if single {
        // f cos / pdf of a visible-normal sample of a single-scattering microfacet
        // interface: the shadowing of wi, G2(wo, wi) / G1(wo). Exactly tangent directions
        // (0 / 0) carry nothing.
        let zi = abs(wi.z);
        let g1 = smith_g1(wo_l.z, lp.a2);
        if !(g1 > 0.0 && zi > 0.0) {
            return BsdfSample(vec3f(0.0, 0.0, 1.0), vec3f(0.0), 0.0, false);
        }
        weight *= smith_g2(wo_l.z, zi, lp.a2) / g1;
    }
    return BsdfSample(normalize(vec3f(wi.xy, wi.z * s)), weight, 0.0, true);
}

// A sample of the three lobes. Its non-delta samples are to be weighted by the whole BSDF
// (`eval_bsdf`, layers included), as one-sample MIS over every lobe asks: for these it
// gives only the direction, with `eval` set, and `sample_bsdf` evaluates it (one call of
// `eval_bsdf` in the code for every way of sampling: a driver inlines each call). Where no
// microfacet code is compiled in (!HAS_SPECULAR && !HAS_METAL), the samples carry the
// diffuse base's own weight, and `sample_bsdf` weights them again over the layers.
struct BaseSample {
    s: BsdfSample,
    eval: bool,
}

fn sample_base(m: Material, wo: vec3f, u_lobe: f32, u: vec3f) -> BaseSample {
    var out = BsdfSample(vec3f(0.0, 0.0, 1.0), vec3f(0.0), 0.0, false);
    let w = lobe_weights(m);
    let lp = lobe_params(m);
    if HAS_GLASS && u_lobe < w.z {
        return BaseSample(sample_glass(m, lp, wo, u), false);
    }
    if wo.z <= 0.0 {
        return BaseSample(out, false);
    }
    if !HAS_SPECULAR && !HAS_METAL {
        if rough_diffuse(m) {
            let r = diffuse_roughness(m);
            let wi = eon_sample(wo, r, u.xy);
            let pdf = eon_pdf(wo, wi, r);
            out.wi = wi;
            out.weight = eon_f(m.base_color, r, wo, wi) * (wi.z / pdf) * (w.x / max(1.0 - w.z, 1e-6));
            out.pdf = w.x * pdf;
            out.valid = wi.z > 0.0 && pdf > 0.0;
            return BaseSample(out, false);
        }
        // Lambertian: f cos / pdf = base_color for the dielectric share of the material.
        out.wi = sample_cosine(vec3f(0.0, 0.0, 1.0), u.xy);
        out.weight = m.base_color * (w.x / max(1.0 - w.z, 1e-6));
        out.pdf = w.x * out.wi.z * INV_PI;
        out.valid = out.wi.z > 0.0;
        return BaseSample(out, false);
    }
    let to = ggx_albedo(wo.z, lp.roughness);
    // Choose a sub-lobe: mirror-like (GGX or perfect mirror) or diffuse-like (cosine).
    var p_mirror: f32;
    // The dielectric layer's Fresnel (unused by the metal lobe).
    var layer_fresnel: Fresnel;
    let v = (u_lobe - w.z) / max(1.0 - w.z, 1e-6);
    let layer = v * (w.x + w.y) < w.x;
    if layer {
        layer_fresnel = dielectric_fresnel(m);
        p_mirror = w.x * layer_spec_sample_prob(m, layer_fresnel, fresnel_albedo(layer_fresnel, to));
    } else {
        p_mirror = w.y * metal_ss_sample_prob(m, lp, to.x + to.y);
    }
    let p_lobe = select(w.y, w.x, layer);
    let mirror = u.z * p_lobe < p_mirror;
    if mirror && lp.is_smooth {
        // Perfect mirror: a delta lobe, weighted by its Fresnel over its probability.
        out.wi = vec3f(-wo.xy, wo.z);
        let fresnel = select(metal_fresnel(m, wo.z), fresnel_at(layer_fresnel, wo.z), layer);
        out.weight = p_lobe * fresnel / p_mirror;
        out.valid = true;
        return BaseSample(out, false);
    }
    var wi: vec3f;
    if mirror {
        let mh = sample_vndf(wo, sqrt(lp.a2), u.xy);
        wi = 2.0 * dot(wo, mh) * mh - wo;
    } else if layer && rough_diffuse(m) {
        wi = eon_sample(wo, diffuse_roughness(m), u.xy);
    } else {
        wi = sample_cosine(vec3f(0.0, 0.0, 1.0), u.xy);
    }
    out.wi = wi;
    return BaseSample(out, true);
}

// A non-delta sample towards wi: weighted by the whole BSDF's f * cos over its pdf
// (`eval_bsdf`), as one-sample MIS over every lobe asks; none below the surface or where
// no lobe could have drawn it.
fn sampled_by_eval(m: Material, wo: vec3f, wi: vec3f) -> BsdfSample {
    var out = BsdfSample(vec3f(0.0, 0.0, 1.0), vec3f(0.0), 0.0, false);
    if wi.z <= 0.0 {
        return out;
    }
    let e = eval_bsdf(m, wo, wi);
    if !(e.pdf > 0.0) {
        return out;
    }
    out.wi = wi;
    out.weight = e.f_cos / e.pdf;
    out.pdf = e.pdf;
    out.valid = true;
    return out;
}

// The layers over the three lobes at view cosine mu_o > 0: the coat and what it reflects,
// and the share of the sheen. Each layer's albedo (coat: clearcoat E_c(mu_o); sheen:
// max(sheen_color) E_s(mu_o)) is taken from what lies below and is also the probability of
// sampling it, so a sample of a lower layer keeps the weight it has alone.
struct Layers {
    coat: CoatParams,
    p_coat: f32,
    sheen_alpha: f32,
    p_sheen: f32,
}

// The coat's albedo is taken at the view cosine to its own normal (`coat_normal`); it
// reflects nothing from below its horizon.
fn layers(m: Material, wo: vec3f) -> Layers {
    let mu_o = wo.z;
    var l = Layers(no_coat(), 0.0, 1.0, 0.0);
    let mu_c = dot(wo, coat_normal);
    if HAS_COAT && m.clearcoat > 0.0 && mu_c > 0.0 {
        l.coat = coat_params(m);
        l.p_coat = clamp(coat_albedo(l.coat, mu_c), 0.0, 1.0);
    }
    let sheen = max(m.sheen_color.x, max(m.sheen_color.y, m.sheen_color.z));
    if HAS_SHEEN && sheen > 0.0 {
        l.sheen_alpha = sheen_alpha(m.sheen_roughness);
        l.p_sheen = clamp(sheen * sheen_albedo(mu_o, m.sheen_roughness), 0.0, 1.0);
    }
    return l;
}

// The non-delta, non-glass part of the BSDF, the coat over the sheen over the three lobes
// (`eval_base`): f * cos(wi) and the solid-angle pdf with which `sample_bsdf` produces wi
// (lobe choice included). Light sampling evaluates this; the glass lobe and perfect mirrors
// are reached by BSDF sampling only.
fn eval_bsdf(m: Material, wo: vec3f, wi: vec3f) -> BsdfEval {
    var out = eval_base(m, wo, wi);
    if !(HAS_COAT || HAS_SHEEN) || wo.z <= 0.0 || wi.z <= 0.0 {
        return out;
    }
    let l = layers(m, wo);
    if l.p_sheen > 0.0 {
        out.f_cos = m.sheen_color * sheen_f_cos(l.sheen_alpha, wo, wi) + (1.0 - l.p_sheen) * out.f_cos;
        out.pdf = l.p_sheen * wi.z * INV_PI + (1.0 - l.p_sheen) * out.pdf;
    }
    if l.p_coat > 0.0 {
        let c = coat_eval(l.coat, to_coat(wo), to_coat(wi));
        out.f_cos = c.f_cos + (1.0 - l.p_coat) * l.coat.through * out.f_cos;
        out.pdf = l.p_coat * c.pdf + (1.0 - l.p_coat) * out.pdf;
    }
    return out;
}

// A sample of the whole BSDF: the coat, the sheen or the three lobes, chosen by u_lobe with
// the layers' probabilities (`layers`), the rest of u_lobe choosing among the lobes.
fn sample_bsdf(m: Material, wo: vec3f, u_lobe: f32, u: vec3f) -> BsdfSample {
    var l = Layers(no_coat(), 0.0, 1.0, 0.0);
    if (HAS_COAT || HAS_SHEEN) && !(wo.z <= 0.0) {
        l = layers(m, wo);
    }
    let layered = l.p_coat != 0.0 || l.p_sheen != 0.0;
    var wi: vec3f;
    var u_base = u_lobe;
    var base = true;
    if layered {
        if u_lobe < l.p_coat {
            base = false;
            let wc = coat_sample(l.coat, to_coat(wo), u.xy);
            wi = from_coat(wc);
            if l.coat.lobe.is_smooth {
                // The mirror reflects clearcoat F(mu_o), the probability of choosing it
                // (lost where a tilted coat's mirror points into the surface).
                return BsdfSample(wi, vec3f(1.0), 0.0, wi.z > 0.0);
            }
            if wc.z <= 0.0 {
                // Below the coat's horizon, where its density is 0 (with a coat normal of
                // its own, possibly above the base's).
                return BsdfSample(vec3f(0.0, 0.0, 1.0), vec3f(0.0), 0.0, false);
            }
        } else {
            let v = (u_lobe - l.p_coat) / max(1.0 - l.p_coat, 1e-7);
            if v < l.p_sheen {
                base = false;
                wi = sample_cosine(vec3f(0.0, 0.0, 1.0), u.xy);
            } else {
                u_base = min((v - l.p_sheen) / max(1.0 - l.p_sheen, 1e-7), ONE_MINUS_EPSILON);
            }
        }
    }
    if base {
        let b = sample_base(m, wo, u_base, u);
        // A delta sample (mirror, glass) or none: the layers take from it exactly the
        // probability of passing them, and it is weighted by what passes the coat. With the microfacet code compiled in, every other
        // sample of the lobes is weighted by the whole BSDF (`eval`); without, the diffuse
        // base's sample is weighted again here only under layers.
        if !b.eval && (!layered || !b.s.valid || b.s.pdf == 0.0 || HAS_SPECULAR || HAS_METAL) {
            var s = b.s;
            s.weight *= l.coat.through;
            return s;
        }
        wi = b.s.wi;
    }
    return sampled_by_eval(m, wo, wi);
}
