// Compile-time options of the G-buffer. The renderer replaces this file for the scene at hand
// (crates/pathtrace/src/nodes/gbuffer.rs); this is the default the shader validation test
// compiles.

// Some material has a texture: textured albedo and normal maps compiled in.
const HAS_TEXTURES: bool = true;

// Some material is alpha-masked or blended: its cut-out fragments are discarded.
const HAS_ALPHA: bool = true;
