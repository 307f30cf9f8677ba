//! ptui: a physically based path tracer that lives in the terminal.
//!
//! Data flows one way (see docs/ARCHITECTURE.md):
//! scene file → [`scene::description`] → validated, immutable [`scene::Scene`] →
//! [`render::Renderer`] (progressive passes on a rayon pool) → [`film::Film`] →
//! snapshot → preview, PNG/EXR writer, convergence report.

#![forbid(unsafe_op_in_unsafe_fn)]

pub mod accel;
pub mod analysis;
pub mod camera;
pub mod checked;
pub mod cli;
pub mod cpu;
pub mod geometry;
pub mod input;
pub mod integrator;
pub mod io;
pub mod light;
pub mod material;
pub mod math;
pub mod memory;
pub mod progress;
pub mod render;
pub mod sampling;
pub mod scene;
pub mod session;
pub mod settings;
pub mod tui;

#[cfg(test)]
mod layers;
