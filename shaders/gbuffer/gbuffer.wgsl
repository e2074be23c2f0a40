// GBuffer: rasterizes what the path tracer's first hit through each pixel center sees.
//
// Projection, from the path tracer's pinhole camera (image y down): a world point p, with
// d = p - position, lands at
//   x_ndc = dot(d, right) / (z tan_half_fov aspect),  y_ndc = dot(d, up) / (z tan_half_fov)
// where z = dot(d, forward) (NDC y up is image row 0 at the top, as in the path tracer).
// Depth is reversed and infinite: clip.z = NEAR, clip.w = z, so NDC depth = NEAR / z, cleared
// to 0 and tested with `greater`.
//
// Triangles interpolate their corner normals (perspective-correct, so the same barycentrics
// as the ray hit). Analytic shapes arrive as their kind's hull (crates/scene/src/shapes/);
// each fragment intersects the shape itself along its pixel-center ray with the path
// tracer's test (pathtrace/shapes.wgsl), drops the fragment on a miss and writes the exact
// normal and depth, so silhouettes and normals match the ray tracer's.
// With textures (HAS_TEXTURES), fragments of textured materials take their albedo and normal
// through the path tracer's own functions (pathtrace/textures.wgsl) at the interpolated UV.
// With HAS_ALPHA, fragments of alpha-masked materials whose opacity (times the base colour
// texture's alpha) is below the cutoff are discarded, as the path tracer's any-hit test cuts
// them out (pathtrace/intersect/alpha.wgsl); blended ones are discarded with probability 1 - opacity,
// drawn per pixel and material (the path tracer draws per ray and primitive).
// Outputs: albedo (base color; alpha 2 on emissive materials, 1 on others, which Denoise uses
// to keep lights and lit surfaces apart), shading normal, distance along the ray; 0 where
// nothing is hit.
#import "pathtrace/scene_types.wgsl"
#import "pathtrace/textures.wgsl"
#import "gbuffer/options.wgsl"
#import "common/rng.wgsl"
#import "pathtrace/shapes.wgsl"

struct RasterCamera {
    position: vec3f,
    tan_half_fov: f32,
    right: vec3f,
    aspect: f32,
    up: vec3f,
    width: f32,
    forward: vec3f,
    height: f32,
    // The pixels this pass renders: left, top, width and height in the whole image (all of
    // it unless the render is tiled).
    window: vec4f,
}

const NEAR: f32 = 1e-4;

@group(0) @binding(0) var<uniform> cam: RasterCamera;
// Materials, where every texture is in the atlas, and the atlas (zeroed stand-ins, and a
// 1x1 atlas, without textures).
@group(0) @binding(1) var<storage, read> materials: array<Material>;
@group(0) @binding(2) var<storage, read> texture_descs: array<TexDesc>;
@group(0) @binding(3) var textures: texture_2d_array<f32>;
// The analytic shapes (a zeroed stand-in without).
@group(0) @binding(4) var<storage, read> shapes: array<Shape>;

struct VertexIn {
    @location(0) position: vec3f,
    @location(1) normal: vec3f,
    @location(2) albedo: vec3f,
    // For a triangle, its unit geometric normal and 0; for a shape's hull, 0 and the shape's
    // index + 1.
    @location(3) shape: vec4f,
    // Both UV sets (set 0 in xy).
    @location(4) uv: vec4f,
    // Tangent (xyz) and handedness (w, corner 0's on every corner).
    @location(5) tangent: vec4f,
    @location(6) material: u32,
    // Vertex colour, decoded (white without).
    @location(7) color: vec4f,
}

// The instance a vertex is drawn for (a `GpuInstance`, pathtrace/intersect/instances.wgsl): its
// object-to-world and world-to-object rows and (root, flags, pad_scale, pad_base); the identity for
// the scene's own triangles and shapes.
struct InstanceIn {
    @location(8) world_x: vec4f,
    @location(9) world_y: vec4f,
    @location(10) world_z: vec4f,
    @location(11) object_x: vec4f,
    @location(12) object_y: vec4f,
    @location(13) object_z: vec4f,
    @location(14) info: vec4u,
}

struct VertexOut {
    @builtin(position) clip: vec4f,
    @location(0) world: vec3f,
    @location(1) normal: vec3f,
    @location(2) @interpolate(flat) albedo: vec3f,
    @location(3) @interpolate(flat) shape: vec4f,
    @location(4) uv: vec4f,
    @location(5) tangent: vec4f,
    @location(6) @interpolate(flat) material: u32,
    @location(7) color: vec4f,
}

@vertex
fn vs_main(v: VertexIn, i: InstanceIn) -> VertexOut {
    // Placed as the path tracer places an instance's triangle (instances.wgsl): points and
    // tangents by the object-to-world rows, normals by the world-to-object ones transposed,
    // the front side turned where the instance mirrors. Exact for the identity.
    let position = vec3f(dot(i.world_x.xyz, v.position) + i.world_x.w, dot(i.world_y.xyz, v.position) + i.world_y.w, dot(i.world_z.xyz, v.position) + i.world_z.w);
    let to_world = mat3x3f(i.world_x.xyz, i.world_y.xyz, i.world_z.xyz);
    let normal_of = mat3x3f(i.object_x.xyz, i.object_y.xyz, i.object_z.xyz);
    let turn = select(1.0, -1.0, (i.info.y & INSTANCE_MIRROR) != 0u);
    // The identity has no mesh root: the scene's own geometry is drawn as it was.
    let placed = i.info.x != 0u;
    var shape = v.shape;
    if placed && v.shape.w <= 0.0 {
        // A triangle's unit geometric normal.
        shape = vec4f(turn * normalize(normal_of * v.shape.xyz), 0.0);
    }
    let d = position - cam.position;
    let z = dot(d, cam.forward);
    var out: VertexOut;
    // NDC of the whole image, then of the window: x' = x W / w + (W - 2 left) / w - 1 and
    // y' = y H / h + 1 - (H - 2 top) / h (y up), exactly x and y for the whole image.
    let size = vec2f(cam.width, cam.height);
    let scale = size / cam.window.zw;
    let shift = vec2f(
        (cam.width - 2.0 * cam.window.x) / cam.window.z - 1.0,
        1.0 - (cam.height - 2.0 * cam.window.y) / cam.window.w,
    );
    let xy = vec2f(
        dot(d, cam.right) / (cam.tan_half_fov * cam.aspect),
        dot(d, cam.up) / cam.tan_half_fov,
    );
    out.clip = vec4f(xy * scale + z * shift, NEAR, z);
    out.world = position;
    out.normal = normal_of * v.normal;
    out.albedo = v.albedo;
    out.shape = shape;
    out.uv = v.uv;
    out.tangent = vec4f(v.tangent.xyz * to_world, turn * v.tangent.w);
    out.material = v.material;
    out.color = v.color;
    return out;
}

struct FragmentOut {
    @location(0) albedo: vec4f,
    @location(1) normal: vec4f,
    @location(2) depth: vec4f,
    @builtin(frag_depth) frag_depth: f32,
}

// The unit ray through framebuffer position `xy` (pixel centers at .5) of the window, as
// `pinhole_ray`.
fn pixel_ray(xy: vec2f) -> vec3f {
    let u = (xy + cam.window.xy) / vec2f(cam.width, cam.height);
    return normalize(cam.forward + (2.0 * u.x - 1.0) * cam.tan_half_fov * cam.aspect * cam.right
        - (2.0 * u.y - 1.0) * cam.tan_half_fov * cam.up);
}

// Whether the fragment's surface stops the pixel's ray (see HAS_ALPHA above).
fn opaque_here(f: VertexOut) -> bool {
    let m = materials[f.material];
    if (m.flags & (MATERIAL_ALPHA_MASK | MATERIAL_ALPHA_BLEND)) == 0u {
        return true;
    }
    var alpha = m.opacity;
    let tex = tex_lo(m.tex_base_mr);
    if HAS_TEXTURES && f.shape.w <= 0.0 {
        alpha *= f.color.a;
        if tex != NO_TEX {
            alpha *= tex_sample(tex, f.uv, false).a;
        }
    }
    if (m.flags & MATERIAL_ALPHA_MASK) != 0u {
        return alpha >= m.alpha_cutoff;
    }
    let px = vec2u(f.clip.xy + cam.window.xy);
    let h = pcg_hash(px.x ^ pcg_hash(px.y ^ pcg_hash(f.material)));
    return f32(h >> 8u) * INV_2_24 < alpha;
}

@fragment
fn fs_main(f: VertexOut) -> FragmentOut {
    let dir = pixel_ray(f.clip.xy);
    // The pixel's footprint per UV set (textures.wgsl `tex_sample_lod`): log2 of the larger
    // screen-space derivative of the coordinates, taken before any branch (derivatives need
    // uniform control flow).
    let lod = log2(max(
        max(vec2f(length(dpdx(f.uv.xy)), length(dpdx(f.uv.zw))), vec2f(length(dpdy(f.uv.xy)), length(dpdy(f.uv.zw)))),
        vec2f(1e-30),
    ));
    if HAS_ALPHA && !opaque_here(f) {
        discard;
    }
    var out: FragmentOut;
    let flag = select(1.0, 2.0, any(materials[f.material].emission > vec3f(0.0)));
    out.albedo = vec4f(f.albedo, flag);
    if f.shape.w > 0.0 {
        // The shape's hit nearest the camera in front of it (the path tracer's test).
        let i = u32(f.shape.w) - 1u;
        let s = shapes[i];
        let t = shape_intersect(i | PRIM_SHAPE, s, Ray(cam.position, dir), F32_MAX);
        if t <= 0.0 {
            discard;
        }
        let p = cam.position + t * dir;
        out.normal = vec4f(shape_normal(s, p), 1.0);
        out.depth = vec4f(t, 0.0, 0.0, 0.0);
        out.frag_depth = NEAR / max(dot(p - cam.position, cam.forward), NEAR);
    } else {
        let n = f.normal;
        // A zero interpolated normal falls back to the geometric one, as in the path tracer.
        var ns = select(f.shape.xyz, normalize(n), dot(n, n) > 0.0);
        if HAS_TEXTURES {
            let m = textured_material(materials[f.material], f.uv, lod, f.color);
            out.albedo = vec4f(m.base_color, flag);
            ns = normal_mapped(m, ns, f.shape.xyz, f.uv, lod, f.tangent);
        }
        out.normal = vec4f(ns, 1.0);
        out.depth = vec4f(length(f.world - cam.position), 0.0, 0.0, 0.0);
        out.frag_depth = f.clip.z;
    }
    return out;
}
