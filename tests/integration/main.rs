//! The integration tests, one binary with a module per subject (one link of the crate instead of
//! one per file). Run one module with `cargo test --release --test integration caustics::`.
//! Tests that need a process of their own stay beside this folder: `tests/allocations.rs`
//! installs a counting global allocator, and `tests/tui_e2e.rs` drives the binary in tmux
//! against deadlines of its own.

mod common;

mod bad_input;
mod bsdf_mitsuba;
mod bvh;
mod caustics;
mod cli;
mod convergence;
mod degenerate;
mod determinism;
mod doc_text;
mod docs;
mod environment;
mod extreme_files;
mod extreme_scenes;
mod furnace;
mod fuzz_obj;
mod fuzz_scene;
mod invariance_power;
mod lens;
mod materials;
mod mesh;
mod painterly;
mod ray_count;
mod reference;
mod reference_materials;
mod reference_mesh;
mod sampling_chi2;
mod scene_errors;
mod shard;
mod smooth;
mod special_files;
mod strategies;
mod tui_graphics;
mod tui_preview;
