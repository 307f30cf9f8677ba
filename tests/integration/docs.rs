//! The documentation, run as a user copies from it: every TOML example in the README and the
//! docs loads as a scene and renders a few samples at a small size (a film header example parses
//! as one and lists every field a header has); every `ptui ...` command line, in a shell example
//! or a code span, parses with today's command line; every repository path a doc names exists,
//! and every Rust path (`render::film::Film`) names a module and an item that exist. A doc that
//! drifts from the code fails here, with the file and line.
//!
//! The documents: README.md, docs/*.md, and the READMEs of benches/, scenes/models/ and
//! tests/refs/. benches/HISTORY.md is a log of what was measured when, and names what existed
//! then: it is not checked.

use crate::doc_text::{blocks, code_spans, joined_lines, link_targets, prose, ptui_commands};
use clap::Parser;
use ptui::cli::Cli;
use ptui::render::Renderer;
use ptui::scene::{self, BuildOptions};
use ptui::settings::{RenderSettings, SettingsOverrides};
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// (path relative to the root, text) of every document checked.
fn documents() -> Vec<(String, String)> {
    let mut names = vec![
        "README.md".to_string(),
        "benches/README.md".into(),
        "scenes/models/README.md".into(),
        "tests/refs/README.md".into(),
    ];
    let mut docs: Vec<String> = std::fs::read_dir(root().join("docs"))
        .expect("docs/")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .map(|p| format!("docs/{}", p.file_name().expect("name").to_string_lossy()))
        .collect();
    docs.sort();
    names.extend(docs);
    names
        .into_iter()
        .map(|n| {
            let text =
                std::fs::read_to_string(root().join(&n)).unwrap_or_else(|e| panic!("{n}: {e}"));
            (n, text)
        })
        .collect()
}

// ---------------------------------------------------------------------------------------------
// TOML examples

/// Every ```toml block loads as a scene (files it names stood in for by small valid ones) and
/// renders 8x6 pixels at 2 spp without invalid samples.
#[test]
fn every_toml_example_loads_and_renders() {
    let mut tried = 0;
    for (doc, text) in documents() {
        for b in blocks(&text).into_iter().filter(|b| b.info == "toml") {
            let label = format!("{doc}:{}", b.line);
            let dir = tempfile::tempdir().expect("temp dir");
            let desc = scene::load::parse(&b.body, &label).unwrap_or_else(|e| panic!("{e}"));
            for m in desc.mesh.iter().filter_map(|m| m.path.as_ref()) {
                stand_in(dir.path(), m.get_ref(), &label);
            }
            if let Some(map) = desc
                .environment
                .as_ref()
                .and_then(|e| e.get_ref().map.clone())
            {
                if !map.get_ref().starts_with("builtin:") {
                    stand_in(dir.path(), map.get_ref(), &label);
                }
            }
            let value: toml::Value = toml::from_str(&b.body).unwrap_or_else(|e| panic!("{e}"));
            for texture in textures(&value) {
                stand_in(dir.path(), &texture, &label);
            }
            let options = BuildOptions {
                base_dir: Some(dir.path().to_path_buf()),
                ..Default::default()
            };
            let scene =
                scene::load_str_with(&b.body, &label, &options).unwrap_or_else(|e| panic!("{e}"));
            let scene = Arc::new(scene);
            let settings = RenderSettings::merged(&[
                &scene.render,
                &SettingsOverrides {
                    width: Some(8),
                    height: Some(6),
                    spp: Some(2),
                    threads: Some(1),
                    target_error: None,
                    ..Default::default()
                },
            ]);
            let mut r = Renderer::new(scene, settings).unwrap_or_else(|e| panic!("{label}: {e}"));
            r.render(&AtomicBool::new(false), |_| true);
            assert_eq!(r.stats().invalid, 0, "{label}: invalid samples");
            tried += 1;
        }
    }
    assert!(tried >= 4, "only {tried} TOML examples found");
}

/// A small valid file where an example names one: a triangle for an OBJ, a 4x2 grey map for
/// an EXR or HDR image. Names must be relative (an example a user copies).
/// The image files a scene's texture tables (`{ texture = "..." }`) name, anywhere in it.
fn textures(v: &toml::Value) -> Vec<String> {
    match v {
        toml::Value::Table(t) => {
            let own = t
                .get("texture")
                .and_then(|x| x.as_str())
                .map(str::to_string);
            own.into_iter()
                .chain(t.values().flat_map(textures))
                .collect()
        }
        toml::Value::Array(a) => a.iter().flat_map(textures).collect(),
        _ => Vec::new(),
    }
}

fn stand_in(dir: &Path, name: &str, label: &str) {
    assert!(
        Path::new(name).is_relative(),
        "{label}: {name} is not relative"
    );
    let path = dir.join(name);
    std::fs::create_dir_all(path.parent().expect("parent")).expect("mkdir");
    match path.extension().and_then(|e| e.to_str()) {
        Some("obj") => std::fs::write(&path, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"),
        Some("png" | "jpg" | "jpeg") => {
            image::RgbImage::from_pixel(2, 2, image::Rgb([128, 64, 32]))
                .save(&path)
                .map_err(std::io::Error::other)
        }
        Some("exr" | "hdr") => image::Rgb32FImage::from_pixel(4, 2, image::Rgb([0.5, 0.5, 0.5]))
            .save(&path)
            .map_err(std::io::Error::other),
        other => panic!("{label}: no stand-in for {name} ({other:?})"),
    }
    .unwrap_or_else(|e| panic!("{label}: {e}"));
}

/// The film header example (```toml film-header) is a header: it parses as one (unknown keys
/// refused), and it shows every field a header can have.
#[test]
fn the_film_header_example_is_complete() {
    use ptui::io::film_file::FilmHeader;
    let (doc, text) = documents()
        .into_iter()
        .find(|(d, _)| d == "docs/FILM.md")
        .expect("docs/FILM.md");
    let b = blocks(&text)
        .into_iter()
        .find(|b| b.info == "toml film-header")
        .expect("a ```toml film-header block");
    let shown: FilmHeader =
        toml::from_str(&b.body).unwrap_or_else(|e| panic!("{doc}:{}: {e}", b.line));
    // Every optional field set, so every key is written.
    let mut full = shown.clone();
    full.max_depth = Some(1);
    full.aperture = Some(1.0);
    full.focus_distance = Some(1.0);
    full.shard = Some("0/1".into());
    full.cancelled = 1;
    full.map_start = Some(16);
    let keys = |t: &str| -> Vec<String> {
        let table: toml::Table = toml::from_str(t).expect("TOML");
        let mut k: Vec<String> = table.keys().cloned().collect();
        for (name, v) in &table {
            if let Some(inner) = v.as_table() {
                k.extend(inner.keys().map(|i| format!("{name}.{i}")));
            }
        }
        k.sort();
        k
    };
    let all = keys(&toml::to_string(&full).expect("serialise"));
    assert_eq!(
        keys(&b.body),
        all,
        "{doc}:{}: the example's keys differ from a header's",
        b.line
    );
    // The fields a merge compares, as the text lists them.
    let para = text
        .split("\n\n")
        .find(|p| p.starts_with("Two films merge only if these agree"))
        .expect("the paragraph on what must agree");
    let listed: Vec<&str> = para
        .split(';')
        .next()
        .unwrap_or("")
        .split('`')
        .skip(1)
        .step_by(2)
        .collect();
    let compared: Vec<&str> = shown.identity().iter().map(|(name, _)| *name).collect();
    assert_eq!(listed, compared, "{doc}: the fields a merge compares");
}

/// The README's sample of `ptui render`'s summary has the summary's shape today: its lines start
/// with the same words, and its build line names the same clauses (`accel:`, `light sampling:`,
/// `environment:`, `caustics:`), in order.
#[test]
fn the_readme_summary_sample_matches_the_summary() {
    let readme = std::fs::read_to_string(root().join("README.md")).expect("README.md");
    let sample = blocks(&readme)
        .into_iter()
        .find(|b| b.info.is_empty() && b.body.starts_with("cornell: "))
        .expect("the README's summary sample");
    let scene = Arc::new(scene::load("cornell").expect("built-in"));
    let settings = RenderSettings::merged(&[
        &scene.render,
        &SettingsOverrides {
            width: Some(16),
            height: Some(12),
            spp: Some(20),
            threads: Some(1),
            ..Default::default()
        },
    ]);
    let mut r = Renderer::new(scene, settings).expect("settings");
    r.render(&AtomicBool::new(false), |_| true);
    let real = ptui::cli::render::summary(&r);
    let first_words = |t: &str| -> Vec<String> {
        t.lines()
            .map(|l| l.split_whitespace().next().unwrap_or("").to_string())
            .collect()
    };
    let clauses = |t: &str| -> Vec<String> {
        let build = t.lines().nth(2).unwrap_or("");
        ["accel:", "light sampling:", "environment:", "caustics:"]
            .iter()
            .filter_map(|c| build.find(c).map(|i| (i, c.to_string())))
            .collect::<std::collections::BTreeMap<_, _>>()
            .into_values()
            .collect()
    };
    // The sample ends with the line naming the file written, which the summary does not hold.
    let shown: String = sample
        .body
        .lines()
        .filter(|l| !l.starts_with("wrote "))
        .map(|l| format!("{l}\n"))
        .collect();
    assert_eq!(
        first_words(&shown),
        first_words(&real),
        "README.md:{}:\n{real}",
        sample.line
    );
    assert_eq!(
        clauses(&shown),
        clauses(&real),
        "README.md:{}:\n{real}",
        sample.line
    );
    assert_eq!(clauses(&real).len(), 4, "{real}");
}

// ---------------------------------------------------------------------------------------------
// Command lines

/// Every `ptui ...` command line of the shell examples and code spans parses with today's CLI.
#[test]
fn every_ptui_command_line_parses() {
    let mut failures = Vec::new();
    let mut tried = 0;
    for (doc, text) in documents() {
        // (line, text, whether it is a code span in prose).
        let mut lines: Vec<(usize, String, bool)> = Vec::new();
        for b in blocks(&text)
            .into_iter()
            .filter(|b| !b.info.starts_with("toml"))
        {
            for (i, line) in joined_lines(&b.body) {
                lines.push((b.line + i, line, false));
            }
        }
        lines.extend(code_spans(&text).into_iter().map(|(n, c)| (n, c, true)));
        for (n, line, span) in lines {
            for args in ptui_commands(&line) {
                tried += 1;
                let argv = std::iter::once("ptui".to_string()).chain(args.clone());
                match Cli::try_parse_from(argv) {
                    Ok(_) => {}
                    Err(e) if e.kind() == clap::error::ErrorKind::DisplayHelp => {}
                    // Prose names a subcommand or a flag (`ptui merge`, `ptui render
                    // --accel`) without the arguments a run needs.
                    Err(e) if span && names_only(&e) => {}
                    Err(e) => failures.push(format!(
                        "{doc}:{n}: ptui {}: {}",
                        args.join(" "),
                        e.to_string().lines().next().unwrap_or("")
                    )),
                }
            }
        }
    }
    assert!(tried > 40, "only {tried} command lines found");
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// A parse that failed only for want of arguments: what prose naming a subcommand or a flag
/// leaves out.
fn names_only(e: &clap::Error) -> bool {
    use clap::error::ErrorKind;
    matches!(
        e.kind(),
        ErrorKind::MissingRequiredArgument | ErrorKind::MissingSubcommand
    ) || e.to_string().contains("but none was supplied")
}

// ---------------------------------------------------------------------------------------------
// Paths

/// Every repository path a document names exists: link targets, and the paths in code spans and
/// code blocks under the repository's folders (`src/...`, `tests/...`, `harness/...`, ...),
/// where git does not ignore them (fetched models, `target/`). Every Rust path in a code span
/// that starts with a top-level module names modules and an item that exist. No document sends
/// a user to `../shared`, which a clone does not have.
#[test]
fn every_path_a_document_names_exists() {
    let ignored = gitignored();
    let files = repository_files();
    let mut failures = Vec::new();
    for (doc, text) in documents() {
        let dir = Path::new(&doc).parent().expect("dir").to_path_buf();
        for (n, line) in text.lines().enumerate() {
            if line.contains("../shared") {
                failures.push(format!("{doc}:{}: names ../shared", n + 1));
            }
        }
        for (n, line) in prose(&text) {
            for target in link_targets(line) {
                if !root().join(&dir).join(&target).exists() {
                    failures.push(format!("{doc}:{n}: link to {target}: no such file"));
                }
            }
        }
        let mut words: Vec<(usize, String)> = code_spans(&text);
        for b in blocks(&text) {
            for (i, line) in b.body.lines().enumerate() {
                words.push((b.line + i, line.to_string()));
            }
        }
        for (n, code) in &words {
            for word in code.split(|c: char| c.is_whitespace() || "\"'`(),=:;<>[]".contains(c)) {
                let word = word.trim_end_matches(['.', ',']);
                if is_repo_path(word)
                    && !ignored.iter().any(|g| matches(g, word))
                    && !root().join(word).exists()
                {
                    failures.push(format!("{doc}:{n}: {word}: no such file"));
                }
            }
        }
        for (n, code) in code_spans(&text) {
            if let Some(why) = rust_path_problem(&code) {
                failures.push(format!("{doc}:{n}: `{code}`: {why}"));
            }
            // A bare file name (`adaptive.rs`) must name a file somewhere in the repository.
            let bare = !code.contains(['/', ' ', '*'])
                && [".rs", ".sh", ".py"].iter().any(|e| code.ends_with(e));
            if bare && !files.iter().any(|f| f.ends_with(&format!("/{code}"))) {
                failures.push(format!("{doc}:{n}: `{code}`: no file of that name"));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Every file under the repository's source folders, as paths from the root.
fn repository_files() -> Vec<String> {
    fn walk(dir: &Path, out: &mut Vec<String>) {
        for e in std::fs::read_dir(dir).into_iter().flatten().flatten() {
            let p = e.path();
            if p.is_dir() {
                walk(&p, out);
            } else if let Ok(rel) = p.strip_prefix(root()) {
                out.push(format!("/{}", rel.display()));
            }
        }
    }
    let mut out = Vec::new();
    for dir in [
        "src", "tests", "harness", "xtask", "benches", "scenes", "docs",
    ] {
        walk(&root().join(dir), &mut out);
    }
    out
}

/// The fields Enter cycles are listed as the code has them (`Field::cycling`), wherever the
/// docs list them.
#[test]
fn the_docs_list_the_fields_enter_cycles() {
    let list = ptui::tui::form::Field::cycling();
    for doc in ["README.md", "docs/TUI.md", "docs/ARCHITECTURE.md"] {
        let text = std::fs::read_to_string(root().join(doc)).expect(doc);
        assert!(text.contains(&list), "{doc} does not list `{list}`");
    }
}

/// A path inside the repository: under one of its folders, or one of its top-level files.
fn is_repo_path(word: &str) -> bool {
    const FOLDERS: [&str; 8] = [
        "src/", "tests/", "docs/", "harness/", "scenes/", "benches/", "xtask/", ".ci/",
    ];
    const FILES: [&str; 3] = ["README.md", "Cargo.toml", ".gitignore"];
    let globbed = word.contains(['*', '{', '$', '<']);
    !globbed && (FOLDERS.iter().any(|f| word.starts_with(f)) || FILES.contains(&word))
}

/// The patterns of the root .gitignore, without their leading `/`.
fn gitignored() -> Vec<String> {
    std::fs::read_to_string(root().join(".gitignore"))
        .expect(".gitignore")
        .lines()
        .map(|l| l.trim().trim_matches('/').to_string())
        .filter(|l| !l.is_empty() && !l.starts_with('#'))
        .collect()
}

/// A .gitignore pattern (a path, or a `*` within its last part) against a path, or a folder
/// pattern against anything under it.
fn matches(pattern: &str, path: &str) -> bool {
    if path == pattern || path.starts_with(&format!("{pattern}/")) {
        return true;
    }
    match pattern.split_once('*') {
        Some((head, tail)) => {
            path.starts_with(head)
                && path.ends_with(tail)
                && !path[head.len()..path.len() - tail.len()].contains('/')
        }
        None => false,
    }
}

/// Whether a line of Rust defines `name` (or re-exports it with `use`).
fn defines(line: &str, name: &str) -> bool {
    let l = line.trim_start();
    let l = l
        .strip_prefix("pub(crate) ")
        .or_else(|| l.strip_prefix("pub "))
        .unwrap_or(l);
    let is_word_at = |r: &str| {
        r.strip_prefix(name)
            .is_some_and(|after| !after.starts_with(|c: char| c.is_alphanumeric() || c == '_'))
    };
    const KINDS: [&str; 10] = [
        "struct ",
        "enum ",
        "trait ",
        "type ",
        "fn ",
        "const fn ",
        "unsafe fn ",
        "const ",
        "static ",
        "mod ",
    ];
    KINDS
        .iter()
        .any(|kind| l.strip_prefix(kind).is_some_and(is_word_at))
        || (l.starts_with("use ")
            && l.match_indices(name).any(|(i, _)| {
                let before = l[..i].chars().last();
                before.is_some_and(|c| !(c.is_alphanumeric() || c == '_')) && is_word_at(&l[i..])
            }))
}

/// For a code span like `render::film::Film` or `integrator::path::Stream` (its first part a
/// top-level module of src/): why it names nothing, if it does not. Modules are files or
/// folders; the first part that is neither must be defined in the module reached (a struct,
/// enum, trait, type, fn, const, static or mod of that name, or a `pub use` of it).
fn rust_path_problem(code: &str) -> Option<String> {
    let parts: Vec<&str> = code.split("::").collect();
    let valid = parts.len() >= 2
        && parts
            .iter()
            .all(|p| !p.is_empty() && p.chars().all(|c| c.is_alphanumeric() || c == '_'));
    if !valid {
        return None;
    }
    let src = root().join("src");
    let top = parts[0];
    if !(src.join(format!("{top}.rs")).exists() || src.join(top).join("mod.rs").exists()) {
        return None;
    }
    let mut dir = src.clone();
    let mut file = PathBuf::new();
    for (k, part) in parts.iter().enumerate() {
        let as_file = dir.join(format!("{part}.rs"));
        let as_dir = dir.join(part).join("mod.rs");
        if as_dir.exists() {
            file = as_dir;
            dir = dir.join(part);
        } else if as_file.exists() {
            file = as_file;
            dir = dir.join(part);
        } else {
            let text = std::fs::read_to_string(&file).unwrap_or_default();
            let defined = text.lines().any(|l| defines(l, part));
            return (!defined).then(|| {
                format!(
                    "no `{part}` in {} (after {})",
                    file.strip_prefix(root()).unwrap_or(&file).display(),
                    parts[..k].join("::")
                )
            });
        }
    }
    None
}
