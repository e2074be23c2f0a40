//! The denoisers: à-trous, regression, OIDN, temporal reuse; their suite and numerics.
//!
//! One test binary per area (`cargo test --test denoise`); one module per subject
//! (`cargo test --test denoise atrous::`).

#[path = "../common/mod.rs"]
mod common;

mod atrous;
mod numerics;
mod oidn;
mod regression;
mod suite;
mod temporal;
