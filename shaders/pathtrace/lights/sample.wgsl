// What light sampling returns (lights.wgsl, and each light without area's file: point.wgsl,
// spot.wgsl, … through the generated pathtrace/light_kinds.wgsl).
// requires: const EDGE_ERR (integrator/surface.wgsl)

struct LightSample {
    // Unit direction from the shading point to the light.
    wi: vec3f,
    dist: f32,
    radiance: vec3f,
    // Solid-angle pdf, light selection included; 0 when the sample is invalid.
    pdf: f32,
    // How far the shadow ray stops short of `dist`, so that it does not reach the light (or
    // what is coplanar with it): the sampled point's error off the light's plane over the
    // cosine there, and a relative term for the error of t.
    margin: f32,
    // A light without area (point, spot, …): `pdf` is only its selection probability, and
    // no BSDF-sampled ray can reach it (no MIS).
    delta: bool,
}

// Towards a light at the point `p` from `x`: direction, distance and the shadow ray's
// margin (a relative term for the error of t), radiance 0 and pdf 1 for its kind to fill in.
fn toward_point(p: vec3f, x: vec3f) -> LightSample {
    let d = p - x;
    let dist = sqrt(dot(d, d));
    return LightSample(d / dist, dist, vec3f(0.0), 1.0, EDGE_ERR * dist, true);
}
