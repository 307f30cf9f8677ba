//! The extreme scenes of `scenes/extreme/`, embedded so `ptui check` runs anywhere. The
//! transformed variants of the built-in scenes are written by `examples/gen_extreme.rs`;
//! `tests/extreme_files.rs` checks this list matches the directory and the generator.

/// (name, TOML source), in the order `ptui check` runs them.
pub const EXTREME: &[(&str, &str)] = &[
    (
        "translate-1e4",
        include_str!("../../../scenes/extreme/translate-1e4.toml"),
    ),
    (
        "translate-1e6",
        include_str!("../../../scenes/extreme/translate-1e6.toml"),
    ),
    (
        "scale-1e-3",
        include_str!("../../../scenes/extreme/scale-1e-3.toml"),
    ),
    (
        "scale-1e3",
        include_str!("../../../scenes/extreme/scale-1e3.toml"),
    ),
    (
        "walls-1e6",
        include_str!("../../../scenes/extreme/walls-1e6.toml"),
    ),
    (
        "walls-1e8",
        include_str!("../../../scenes/extreme/walls-1e8.toml"),
    ),
    (
        "index-matched",
        include_str!("../../../scenes/extreme/index-matched.toml"),
    ),
    (
        "small-light-1e-2",
        include_str!("../../../scenes/extreme/small-light-1e-2.toml"),
    ),
    (
        "small-light-1e-4",
        include_str!("../../../scenes/extreme/small-light-1e-4.toml"),
    ),
    (
        "furnace-0.99",
        include_str!("../../../scenes/extreme/furnace-0.99.toml"),
    ),
    (
        "furnace-0.999",
        include_str!("../../../scenes/extreme/furnace-0.999.toml"),
    ),
    (
        "inside-light",
        include_str!("../../../scenes/extreme/inside-light.toml"),
    ),
    (
        "grazing",
        include_str!("../../../scenes/extreme/grazing.toml"),
    ),
    (
        "tir-inside-glass",
        include_str!("../../../scenes/extreme/tir-inside-glass.toml"),
    ),
    (
        "critical-angle",
        include_str!("../../../scenes/extreme/critical-angle.toml"),
    ),
    (
        "overlapping",
        include_str!("../../../scenes/extreme/overlapping.toml"),
    ),
    (
        "nested",
        include_str!("../../../scenes/extreme/nested.toml"),
    ),
    (
        "light-in-glass",
        include_str!("../../../scenes/extreme/light-in-glass.toml"),
    ),
    (
        "silhouettes",
        include_str!("../../../scenes/extreme/silhouettes.toml"),
    ),
    (
        "glossy-furnace",
        include_str!("../../../scenes/extreme/glossy-furnace.toml"),
    ),
    (
        "glossy-small-light",
        include_str!("../../../scenes/extreme/glossy-small-light.toml"),
    ),
    (
        "metal-index-1",
        include_str!("../../../scenes/extreme/metal-index-1.toml"),
    ),
    (
        "glass-index-1",
        include_str!("../../../scenes/extreme/glass-index-1.toml"),
    ),
];

pub fn get(name: &str) -> Option<&'static str> {
    EXTREME.iter().find(|(n, _)| *n == name).map(|(_, s)| *s)
}

pub fn names() -> Vec<&'static str> {
    EXTREME.iter().map(|(n, _)| *n).collect()
}
