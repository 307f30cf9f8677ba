//! What is measured of a render: convergence against a reference, the `check` expectations,
//! the statistics behind them, plots and error maps.

pub mod check;
pub mod convergence;
pub mod error_map;
pub mod plot;
pub mod reference;
pub mod stats;
