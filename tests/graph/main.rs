//! Graph files: custom kinds, node groups, what a file from someone else can do, and
//! fuzzing of every loader (graphs, scenes, meshes, images).
//!
//! One test binary per area (`cargo test --test graph`); one module per subject
//! (`cargo test --test graph custom_kinds::`).

#[path = "../common/mod.rs"]
mod common;

mod custom_kinds;
mod fuzz;
mod fuzz_graphs;
mod node_groups;
mod ply;
mod security;
