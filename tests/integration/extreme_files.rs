//! The committed `scenes/extreme/` files are what the generator writes and what `ptui check`
//! embeds: no scene can drift from its transformation or be left out of the checks.

#[allow(dead_code)]
#[path = "../../xtask/src/gen_extreme.rs"]
mod gen_extreme;

use std::path::Path;

fn dir() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/extreme")
}

#[test]
fn generated_scenes_are_up_to_date() {
    for (name, text) in gen_extreme::generated() {
        let path = dir().join(format!("{name}.toml"));
        let on_disk =
            std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        assert!(
            on_disk == text,
            "{} is stale: run `cargo xtask gen-extreme`",
            path.display()
        );
    }
}

#[test]
fn embedded_list_matches_the_directory() {
    let mut on_disk: Vec<(String, String)> = std::fs::read_dir(dir())
        .expect("scenes/extreme")
        .filter_map(|e| {
            let path = e.ok()?.path();
            (path.extension()? == "toml").then(|| {
                let stem = path.file_stem()?.to_str()?.to_string();
                Some((stem, std::fs::read_to_string(&path).ok()?))
            })?
        })
        .collect();
    on_disk.sort();
    let mut embedded: Vec<(String, String)> = ptui::analysis::check::extreme::EXTREME
        .iter()
        .map(|(n, s)| (n.to_string(), s.to_string()))
        .collect();
    embedded.sort();
    assert_eq!(on_disk, embedded);
}

#[test]
fn every_extreme_scene_loads_and_states_an_expectation() {
    for (name, src) in ptui::analysis::check::extreme::EXTREME {
        let desc = ptui::scene::load::parse(src, name).unwrap_or_else(|e| panic!("{e}"));
        assert!(desc.check.is_some(), "{name} has no [check] table");
        ptui::scene::load_str(src, name).unwrap_or_else(|e| panic!("{e}"));
    }
}
