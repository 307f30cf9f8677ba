//! Random numbers and warps. Every warp takes uniform numbers as arguments and comes with its pdf,
//! so the chi-square tests can check the pair directly.

pub mod distribution;
pub mod rng;
pub mod sampler;
pub mod sobol;
pub mod warp;

pub use rng::Rng;
pub use sampler::{Sampler, SamplerKind};
