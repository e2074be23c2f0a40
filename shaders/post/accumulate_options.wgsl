// Compile-time option of Accumulate: how the variance of the mean is estimated, one of the
// VARIANCE_* constants of accumulate.wgsl (0: not at all, 1: from the frames' spread, 2:
// from two halves). The node replaces this file for its mode (crates/render/src/nodes/
// accumulate.rs), so a pass that estimates no variance carries none of that code: on
// lavapipe the mere presence of the neighborhood estimates (private arrays, a median sort)
// made the pass 10× slower. The shader validation test compiles this default.
const VARIANCE: u32 = 2u;
