// Compile-time options of the path tracer. The renderer replaces this file with values for
// the scene and graph at hand (crates/pathtrace/src/specialize/features.rs); these are the
// defaults the shader validation test compiles.

// Write first-hit albedo, normal and depth (through the pixel center) to the AOV outputs.
const WRITE_AOVS: bool = true;
// Adaptive sampling: skip the pixels `pathtrace/integrator/adaptive.wgsl` has stopped, and keep the
// statistics it stops them by.
const ADAPTIVE: bool = true;
// Workgroups trace rows of tiles spread over the image (CPU adapters: llvmpipe gives each
// thread one contiguous range of a dispatch's workgroups).
const SPREAD_WORKGROUPS: bool = true;

// One loop over the bounces of all of a pixel's samples, where a lane whose path ended
// starts its next sample (CPU adapters, scenes intersected inline), instead of one bounce
// loop per sample.
const REGENERATE_PATHS: bool = true;

// The scene has triangles; it has analytic shapes. The BVH leaf and surface code of a kind the scene
// lacks is left out (llvmpipe would run it at every node visit and bounce, masked).
const HAS_TRIANGLES: bool = true;
const HAS_SHAPES: bool = true;

// Lobes some material of the scene uses; the code of the others is left out.
const HAS_SPECULAR: bool = true;
const HAS_METAL: bool = true;
const HAS_GLASS: bool = true;
// Emissive primitives exist: next-event estimation compiled in.
const HAS_LIGHTS: bool = true;
// The environment is not black.
const HAS_ENVIRONMENT: bool = true;
// The environment is an equirectangular map: its sampling is compiled in.
const HAS_ENV_MAP: bool = true;
// Some material has a texture: UVs, tangents and texture sampling compiled in.
const HAS_TEXTURES: bool = true;
// Some material has diffuse_roughness > 0: the energy-preserving Oren-Nayar (EON) diffuse
// base and its sampling compiled in (else the diffuse base is Lambertian only).
const HAS_ROUGH_DIFFUSE: bool = true;
// Some material has a clear coat (coat.wgsl); some has a sheen (sheen.wgsl).
const HAS_COAT: bool = true;
const HAS_SHEEN: bool = true;
// Some material has a medium inside (absorbing glass, scattering media) or is an
// index-matched boundary: medium tracking, distance sampling and shadow-ray transmittance
// compiled in.
const HAS_MEDIA: bool = true;

// The scene has instanced meshes: the BVH walk has two levels (bvh.wgsl, instances.wgsl).
const HAS_INSTANCES: bool = true;

// Some material is alpha-masked or blended (and can be seen through): every intersector
// runs the any-hit test of alpha.wgsl.
const HAS_ALPHA: bool = true;

// The host intersects the rays (CPU adapters with Embree, scenes of triangles without
// media): each dispatch takes every path one step, between the host's answers (the entry
// points `wave_start`, `wave_misses` and `wave_hits` in pathtrace/integrator/wave.wgsl), instead of
// tracing whole paths.
const HOST_RAYS: bool = true;

// The paths of a frame are taken one bounce at a time by small kernels (`wave_trace` traces
// the rays the steps write, on the device; `pathtrace/integrator/wave.wgsl`).
const WAVEFRONT: bool = true;
// Paths traced in steps (`pathtrace/integrator/wave.wgsl`): HOST_RAYS or WAVEFRONT.
const WAVES: bool = true;
