// Compile-time options of the path tracer. The renderer replaces this file with values for
// the scene and graph at hand (crates/render/src/specialize.rs); these are the defaults the
// shader validation test compiles.

// Write first-hit albedo, normal and depth (through the pixel center) to the AOV outputs.
const WRITE_AOVS: bool = true;
