// Scene intersection for the path tracer: BVH traversal over storage buffers. For small
// scenes the renderer replaces this file with generated code that tests every primitive
// with its coordinates written into the shader (see
// crates/pathtrace/src/specialize/codegen.rs).
#import "pathtrace/intersect/bvh.wgsl"
