//! The layers of docs/ARCHITECTURE.md, checked: a module may name (`crate::...`) only modules of
//! its own layer or below, so data and dependencies run one way.

/// Each top-level module's layer, bottom first (docs/ARCHITECTURE.md, "Layers and modules").
const LAYERS: &[(&str, u32)] = &[
    ("math", 1),
    ("cpu", 1),
    ("checked", 1),
    ("progress", 1),
    ("memory", 1),
    ("input", 1),
    ("sampling", 2),
    ("settings", 3),
    ("geometry", 4),
    ("camera", 4),
    ("accel", 5),
    ("material", 6),
    ("light", 6),
    ("scene", 7),
    ("integrator", 8),
    ("render", 9),
    ("io", 10),
    ("analysis", 11),
    ("session", 12),
    ("cli", 13),
    ("tui", 13),
];

fn layer(module: &str) -> Option<u32> {
    LAYERS.iter().find(|(m, _)| *m == module).map(|&(_, l)| l)
}

/// The top-level module a source file belongs to (`src/render/film.rs` -> `render`).
fn module_of(path: &std::path::Path, src: &std::path::Path) -> Option<String> {
    let rel = path.strip_prefix(src).ok()?;
    let first = rel.components().next()?.as_os_str().to_str()?;
    Some(first.trim_end_matches(".rs").to_string())
}

fn rust_files(dir: &std::path::Path, out: &mut Vec<std::path::PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// Every `crate::NAME` in `line` (NAME a top-level module).
fn named_modules(line: &str) -> Vec<&str> {
    line.match_indices("crate::")
        .map(|(i, m)| {
            let rest = &line[i + m.len()..];
            let end = rest
                .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
                .unwrap_or(rest.len());
            &rest[..end]
        })
        .collect()
}

/// Upward references in the source tree: (file:line, from, to).
fn upward(src: &std::path::Path) -> Vec<(String, String, String)> {
    let mut files = Vec::new();
    rust_files(src, &mut files);
    let mut bad = Vec::new();
    for f in files {
        let Some(from) = module_of(&f, src) else {
            continue;
        };
        // The library root, the binary and this check sit above every layer.
        let Some(from_layer) = layer(&from) else {
            continue;
        };
        let text = std::fs::read_to_string(&f).unwrap_or_default();
        for (n, line) in text.lines().enumerate() {
            // Unit tests may use anything; they sit at the end of a file.
            if line.starts_with("mod tests {") {
                break;
            }
            // Doc links may point anywhere; code may not.
            if line.trim_start().starts_with("//") {
                continue;
            }
            for to in named_modules(line) {
                if layer(to).is_some_and(|l| l > from_layer) {
                    bad.push((
                        format!("{}:{}", f.display(), n + 1),
                        from.clone(),
                        to.into(),
                    ));
                }
            }
        }
    }
    bad
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    fn src() -> std::path::PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
    }

    #[test]
    fn every_module_has_a_layer() {
        let mut files = Vec::new();
        rust_files(&src(), &mut files);
        let mut missing: Vec<String> = files
            .iter()
            .filter_map(|f| module_of(f, &src()))
            .filter(|m| !matches!(m.as_str(), "lib" | "main" | "layers") && layer(m).is_none())
            .collect();
        missing.sort();
        missing.dedup();
        assert!(missing.is_empty(), "modules without a layer: {missing:?}");
    }

    #[test]
    fn layers_run_one_way() {
        let bad = upward(&src());
        let list: Vec<String> = bad
            .iter()
            .map(|(at, from, to)| format!("{at}: {from} names {to}, a layer above it"))
            .collect();
        assert!(list.is_empty(), "{}", list.join("\n"));
    }

    #[test]
    fn an_upward_reference_is_caught() {
        let dir = tempfile::tempdir().expect("tempdir");
        let geo = dir.path().join("geometry");
        std::fs::create_dir(&geo).expect("mkdir");
        let code = "use crate::math::Ray;\nuse crate::render::Renderer;\n// crate::tui\nmod tests {\nuse crate::cli;\n";
        std::fs::write(geo.join("x.rs"), code).expect("write");
        let bad = upward(dir.path());
        assert_eq!(bad.len(), 1, "{bad:?}");
        assert_eq!(
            (bad[0].1.as_str(), bad[0].2.as_str()),
            ("geometry", "render")
        );
    }
}
