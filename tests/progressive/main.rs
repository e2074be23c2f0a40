//! Renders over time and space: accumulation, adaptive sampling, split-and-merge renders,
//! tiles.
//!
//! One test binary per area (`cargo test --test progressive`); one module per subject
//! (`cargo test --test progressive accumulate::`).

#[path = "../common/mod.rs"]
mod common;

mod accumulate;
mod adaptive;
mod split;
mod tiled;
