//! Built-in scenes: the files in `scenes/`, embedded so `ptui render cornell` works anywhere.

/// (name, TOML source).
pub const BUILTIN: &[(&str, &str)] = &[
    ("cornell", include_str!("../../scenes/cornell.toml")),
    (
        "cornell-small-light",
        include_str!("../../scenes/cornell-small-light.toml"),
    ),
    ("smallpaint", include_str!("../../scenes/smallpaint.toml")),
    (
        "cornell-mesh",
        include_str!("../../scenes/cornell-mesh.toml"),
    ),
    (
        "spheres-field",
        include_str!("../../scenes/spheres-field.toml"),
    ),
    ("torus-knot", include_str!("../../scenes/torus-knot.toml")),
    ("sky", include_str!("../../scenes/sky.toml")),
    ("veach", include_str!("../../scenes/veach.toml")),
    ("materials", include_str!("../../scenes/materials.toml")),
];

/// The scene the TUI and `render` open without an argument.
pub const DEFAULT: &str = "cornell";

pub fn get(name: &str) -> Option<&'static str> {
    BUILTIN.iter().find(|(n, _)| *n == name).map(|(_, s)| *s)
}

pub fn names() -> Vec<&'static str> {
    BUILTIN.iter().map(|(n, _)| *n).collect()
}
