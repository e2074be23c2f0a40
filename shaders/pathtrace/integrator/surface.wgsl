// What a hit is: the surface point (position and its rounding error, normals, material,
// light, texture coordinates) reconstructed from the intersector's hit, and the robust
// origin of a ray leaving it.
// requires: var tri_texcoords (integrator/pathtrace.wgsl)
#import "pathtrace/scene_types.wgsl"
#import "pathtrace/options.wgsl"
#import "pathtrace/intersect.wgsl"
#import "pathtrace/scene_data.wgsl"
#import "pathtrace/textures.wgsl"
#import "pathtrace/intersect/instances.wgsl"
#import "pathtrace/shapes.wgsl"

struct Surface {
    p: vec3f,
    // Geometric normal, front side (triangles: e1 x e2; shapes: `shape_normal`).
    ng: vec3f,
    // Shading normal, front side.
    ns: vec3f,
    // The clear coat's normal, front side (HAS_COAT; else `ns`): the interpolated normal,
    // or the coat's own normal map applied to it, not the base's normal map.
    coat_n: vec3f,
    material: u32,
    light: u32,
    // Componentwise bound on the rounding error of `p` (triangles; 0 on shapes).
    err: vec3f,
    // Texture coordinates, set 0 in xy and set 1 in zw (HAS_TEXTURES; 0 on shapes).
    uv: vec4f,
    // Vertex colour (HAS_TEXTURES; white on shapes).
    color: vec4f,
    // The footprint of the ray's cone here, per UV set (HAS_TEXTURES; `tri_lod` in
    // pathtrace/textures.wgsl; TEX_LOD_NONE on shapes).
    lod: vec2f,
}

// Rounding error bounds of a point computed as v0 + u e1 + v e2 in f32: a float step of each
// term (2^-23 relative) for the sum, plus 2^-20 of the edges for the error of the plane
// distance Moller-Trumbore computes against a neighbouring triangle. At 1e5 this is 1.5 float
// steps (0.012 units); at the origin of a unit-sized scene, about 4e-6.
const POSITION_ERR: f32 = 1.1920929e-7;
const EDGE_ERR: f32 = 9.536743e-7;

fn barycentric_err(v0: vec3f, e1: vec3f, e2: vec3f, u: f32, v: f32) -> vec3f {
    return POSITION_ERR * (abs(v0) + abs(u * e1) + abs(v * e2)) + EDGE_ERR * (abs(e1) + abs(e2));
}

// Whether `prim` (a hit's) is an analytic shape; a constant where the scene has one kind only.
fn is_shape(prim: u32) -> bool {
    return HAS_SHAPES && (!HAS_TRIANGLES || (prim & PRIM_SHAPE) != 0u);
}

// The surface `ray` meets at `hit`; `cone` is the ray's cone (its width at the ray's origin
// and its spread angle, see PathState), which gives the footprint of texture lookups.
fn surface_at(ray: Ray, hit: Hit, cone: vec2f) -> Surface {
    var s: Surface;
    s.lod = vec2f(TEX_LOD_NONE);
    s.p = ray.origin + hit.t * ray.dir;
    s.err = vec3f(0.0);
    s.uv = vec4f(0.0);
    s.color = vec4f(1.0);
    if is_shape(hit.prim) {
        let sh = scene_shape(hit.prim & ~PRIM_SHAPE);
        s.ng = shape_normal(sh, s.p);
        s.ns = s.ng;
        s.coat_n = s.ns;
        s.material = sh.material;
        s.light = sh.light;
    } else {
        let tri = scene_tri_positions(hit.prim);
        let sh = scene_tri_shading(hit.prim);
        // A triangle of an instanced mesh: in world space as its test saw it
        // (instances.wgsl), its front side that of a copy (a mirroring instance's turned).
        let placed = HAS_INSTANCES && hit.inst != NO_INSTANCE;
        var w = PlacedTriangle(tri.v0, tri.e1, tri.e2);
        var turn = 1.0;
        if placed {
            w = place_triangle(hit.inst, tri);
            turn = select(1.0, -1.0, instance_mirrors(hit.inst));
        }
        // Position from the barycentrics: more accurate than origin + t * dir far away.
        s.p = w.v0 + hit.u * w.e1 + hit.v * w.e2;
        s.err = barycentric_err(w.v0, w.e1, w.e2, hit.u, hit.v);
        s.ng = turn * normalize(cross(w.e1, w.e2));
        if (sh.flags & TRI_VERTEX_NORMALS) != 0u {
            var n = (1.0 - hit.u - hit.v) * sh.n0 + hit.u * sh.n1 + hit.v * sh.n2;
            if placed {
                n = instance_normal(hit.inst, n);
            }
            s.ns = select(s.ng, normalize(n), dot(n, n) > 0.0);
        } else {
            s.ns = s.ng;
        }
        s.material = sh.material;
        s.light = sh.light;
        if HAS_TEXTURES {
            let tc = tri_texcoords[hit.prim];
            s.uv = tri_uv(tc, hit.u, hit.v);
            s.color = tri_color(tc, hit.u, hit.v);
            s.lod = tri_lod(tc, w.e1, w.e2, cone.x + cone.y * hit.t, dot(s.ng, ray.dir));
            let m = scene_material(sh.material);
            var tangent = tri_tangent(tc, hit.u, hit.v);
            if placed {
                tangent = vec4f(instance_apply(hit.inst, 0u, tangent.xyz, 0.0), turn * tangent.w);
            }
            let interpolated = s.ns;
            s.ns = normal_mapped(m, interpolated, s.ng, s.uv, s.lod, tangent);
            if HAS_COAT && m.clearcoat > 0.0 {
                s.coat_n = normal_mapped_by(tex_hi(m.tex_specular_color), m.clearcoat_normal_scale, interpolated, s.ng, s.uv, s.lod, tangent);
            } else {
                s.coat_n = s.ns;
            }
        } else {
            s.coat_n = s.ns;
        }
    }
    return s;
}

// For a ray that leaves no surface (a camera ray, a ray from a point in a medium): no
// primitive skipped, no origin error.
fn leave_no_surface() {
    skip_prim = NO_HIT;
    skip_inst = NO_INSTANCE;
    origin_n = vec3f(0.0);
    origin_err = vec3f(0.0);
    origin_off = 0.0;
    origin_slab = 0.0;
}

// The origin of a ray leaving `s` towards the side `n` faces, and its error for the
// intersection routines (`origin_n`, `origin_err`, `origin_off`, `origin_slab`,
// `skip_inward`). Rays start at the hit itself, never offset (`skip_prim`).
fn leave(s: Surface, on_shape: bool, n: vec3f, dir: vec3f) -> vec3f {
    if on_shape {
        origin_n = vec3f(0.0);
        origin_err = vec3f(0.0);
        origin_off = 0.0;
        origin_slab = 0.0;
        skip_inward = dot(dir, s.ng) < 0.0;
        return s.p;
    }
    // The front of the plane left is the side the ray goes to.
    origin_n = n;
    origin_err = s.err;
    origin_off = dot(abs(n), s.err);
    origin_slab = origin_off / abs(dot(n, dir));
    return s.p;
}
