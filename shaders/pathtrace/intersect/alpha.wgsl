// The any-hit test of every intersector (the BVH traversal of bvh.wgsl and the inline
// intersection generated for small scenes; the CPU mirror is `triangle_hit_counts` in
// crates/scene/src/traverse.rs, line for line): whether a candidate hit counts, by its
// material's alpha mode. `Mask` cuts the surface out where its opacity (the material's, times
// the vertex colour's alpha and the base colour texture's alpha at the hit) is below the
// cutoff; `Blend` lets a ray through
// with probability 1 - opacity (stochastic transparency: `alpha_hash` draws the choice from
// the ray and the primitive alone, so it is the same wherever the ray is traced). Camera
// rays, bounces and shadow rays all take it. Compiled in with HAS_ALPHA only.
//
// requires: var tri_texcoords (integrator/pathtrace.wgsl)
#import "pathtrace/scene_types.wgsl"
#import "pathtrace/options.wgsl"
#import "pathtrace/scene_data.wgsl"
#import "common/rng.wgsl"
#import "pathtrace/textures.wgsl"

// A number in [0, 1) that is a function of the ray and the primitive only.
fn alpha_hash(prim: u32, ray: Ray) -> f32 {
    var h = pcg_hash(bitcast<u32>(ray.dir.z));
    h = pcg_hash(bitcast<u32>(ray.dir.y) ^ h);
    h = pcg_hash(bitcast<u32>(ray.dir.x) ^ h);
    h = pcg_hash(bitcast<u32>(ray.origin.z) ^ h);
    h = pcg_hash(bitcast<u32>(ray.origin.y) ^ h);
    h = pcg_hash(bitcast<u32>(ray.origin.x) ^ h);
    h = pcg_hash(prim ^ h);
    return f32(h >> 8u) * INV_2_24;
}

// Whether `alpha` lets the surface of `m` stop the ray (`prim` and `ray` draw the blend).
fn alpha_stops(m: Material, alpha: f32, prim: u32, ray: Ray) -> bool {
    if (m.flags & MATERIAL_ALPHA_MASK) != 0u {
        return alpha >= m.alpha_cutoff;
    }
    return alpha_hash(prim, ray) < alpha;
}

// Whether a hit on triangle `prim` at barycentrics (u, v) counts.
fn triangle_hit_counts(prim: u32, u: f32, v: f32, ray: Ray) -> bool {
    if !HAS_ALPHA {
        return true;
    }
    let m = scene_material(scene_tri_shading(prim).material);
    if (m.flags & (MATERIAL_ALPHA_MASK | MATERIAL_ALPHA_BLEND)) == 0u {
        return true;
    }
    var alpha = m.opacity;
    if HAS_TEXTURES {
        let tc = tri_texcoords[prim];
        alpha *= tri_color(tc, u, v).a;
        let tex = tex_lo(m.tex_base_mr);
        if tex != NO_TEX {
            alpha *= tex_sample(tex, tri_uv(tc, u, v), false).a;
        }
    }
    return alpha_stops(m, alpha, prim, ray);
}

// Whether a hit on shape `i` counts (shapes have no texture: the opacity alone).
fn shape_hit_counts(i: u32, ray: Ray) -> bool {
    if !HAS_ALPHA {
        return true;
    }
    let m = scene_material(scene_shape(i).material);
    if (m.flags & (MATERIAL_ALPHA_MASK | MATERIAL_ALPHA_BLEND)) == 0u {
        return true;
    }
    return alpha_stops(m, m.opacity, i | PRIM_SHAPE, ray);
}
