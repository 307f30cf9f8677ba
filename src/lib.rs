//! ptui: a physically based path tracer that lives in the terminal.
//!
//! Data flows one way (see docs/ARCHITECTURE.md):
//! scene file → [`scene::description`] → validated, immutable [`scene::Scene`] →
//! [`render::Renderer`] (progressive passes on a rayon pool) → [`film::Film`] →
//! snapshot → preview, PNG/EXR writer, convergence report.

#![forbid(unsafe_op_in_unsafe_fn)]

pub mod accel;
pub mod adaptive;
pub mod camera;
pub mod check;
pub mod cli;
pub mod convergence;
pub mod cpu;
pub mod error_map;
pub mod film;
pub mod film_file;
pub mod geometry;
pub mod integrator;
pub mod light;
pub mod material;
pub mod math;
pub mod output;
pub mod plot;
pub mod reference;
pub mod render;
pub mod sampling;
pub mod scene;
pub mod settings;
pub mod shard;
pub mod tui;
