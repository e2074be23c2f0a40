// The path tracer's per-hit scene data: materials, lights and their alias table, and the
// triangles' and shapes' positions and shading data, read by index from the storage
// buffers the includer declares. For small scenes the renderer replaces this file with
// generated code that returns them from `switch` statements with the values written into the
// shader, so no bounce loads them from memory (see
// crates/pathtrace/src/specialize/codegen.rs).
// requires: var materials, var lights, var light_alias (integrator/pathtrace.wgsl)
// requires: var tri_positions, var tri_shading, var shapes (integrator/pathtrace.wgsl)
#import "pathtrace/scene_types.wgsl"

fn scene_material(id: u32) -> Material {
    return materials[id];
}

fn scene_light(id: u32) -> Light {
    return lights[id];
}

fn scene_light_alias(i: u32) -> AliasEntry {
    return light_alias[i];
}

fn scene_tri_positions(i: u32) -> TriPositions {
    return tri_positions[i];
}

fn scene_tri_shading(i: u32) -> TriShading {
    return tri_shading[i];
}

fn scene_shape(i: u32) -> Shape {
    return shapes[i];
}
