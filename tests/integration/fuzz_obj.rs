//! Fuzz-style property tests of the OBJ loader: random lines from the OBJ vocabulary and
//! mutations of a valid mesh (numbers replaced by NaN, infinities, huge or out-of-range indices,
//! lines deleted, duplicated or cut, garbage inserted). The loader must never panic: it returns
//! triangles with finite vertices or an error with a message, and whatever loads must render a
//! tiny image without NaN or infinite samples. Every case runs with a time limit
//! (`common::within`), so a hang fails the test instead of stalling it; the devices and special
//! files a path may name are fed to the readers by `special_files.rs`.

use proptest::prelude::*;
use ptui::render::Renderer;
use ptui::scene::{load_str, mesh};
use ptui::settings::{RenderSettings, SettingsOverrides};
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

/// A unit cube: quads (triangulated by the loader), texture and normal indices, a negative
/// (relative) index, groups and a material reference the loader must ignore.
const CUBE: &str = "\
mtllib cube.mtl
o cube
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 0 0 1
v 1 0 1
v 1 1 1
v 0 1 1
vt 0 0
vt 1 0
vt 1 1
vn 0 0 -1
g sides
usemtl grey
f 1/1/1 2/2/1 3/3/1 4/1/1
f 5//1 8//1 7//1 6//1
f 1 5 6 2
f 2 6 7 3
f 3 7 8 4
f -8 -4 -1 -5
";

const LINES: &[&str] = &[
    "v 1 2 3",
    "v nan 0 0",
    "v inf 1 1",
    "v 1e308 1e308 1e308",
    "v 1",
    "v",
    "vn 0 0 1",
    "vt 0.5",
    "f 1 2 3",
    "f 1 2",
    "f 1",
    "f",
    "f 0 1 2",
    "f -1 -2 -3",
    "f -100 1 2",
    "f 99999999999 1 2",
    "f 1/2/3 2/3/4 3/4/5",
    "f 1//1 2//1 3//1 4//1 5//1",
    "f a b c",
    "l 1 2",
    "p 1",
    "o x",
    "g",
    "s off",
    "usemtl nothing",
    "mtllib missing.mtl",
    "# comment",
    "",
    "\u{0}\u{ff}garbage",
    // What exporters write besides: n-gons, w and vertex colours, relative normals, zero and
    // NaN normals, smoothing groups, continued lines, free-form statements.
    "f 1 2 3 4 5 6",
    "f -1//-1 -2//-1 -3//-1 -4//-1",
    "f 1/1/1 2/1/1 3/1/1",
    "v 1 2 3 1",
    "v 0.1 0.2 0.3 1 0 0",
    "vn 0 0 0",
    "vn nan 0 1",
    "vn 0 1",
    "s 1",
    "g a b",
    "mtllib a.mtl b.mtl",
    "v 1 2 \\",
    "cstype bspline",
    "f 1//99 2//1 3//1",
];

#[derive(Clone, Debug)]
enum Edit {
    ReplaceNumber(usize, usize),
    DeleteLine(usize),
    DuplicateLine(usize),
    InsertLine(usize, usize),
    Truncate(usize),
}

const NUMBERS: &[&str] = &[
    "nan", "inf", "-inf", "0", "-0", "-9", "9", "1e308", "-1e308", "1e-320", "x", "2/", "/",
];

fn apply(src: &str, edits: &[Edit]) -> String {
    let mut lines: Vec<String> = src.lines().map(String::from).collect();
    for e in edits {
        let n = lines.len().max(1);
        match e {
            Edit::ReplaceNumber(at, with) => {
                let tokens: Vec<(usize, usize)> = lines
                    .iter()
                    .enumerate()
                    .flat_map(|(li, l)| {
                        l.split_whitespace()
                            .enumerate()
                            .skip(1)
                            .map(move |(ti, _)| (li, ti))
                    })
                    .collect();
                if let Some(&(li, ti)) = tokens.get(at % tokens.len().max(1)) {
                    let mut parts: Vec<String> =
                        lines[li].split_whitespace().map(String::from).collect();
                    parts[ti] = NUMBERS[with % NUMBERS.len()].to_string();
                    lines[li] = parts.join(" ");
                }
            }
            Edit::DeleteLine(i) => {
                if !lines.is_empty() {
                    lines.remove(i % n);
                }
            }
            Edit::DuplicateLine(i) => {
                if !lines.is_empty() {
                    let l = lines[i % n].clone();
                    lines.insert(i % n, l);
                }
            }
            Edit::InsertLine(i, which) => lines.insert(
                i % (n + 1).min(lines.len() + 1),
                LINES[which % LINES.len()].into(),
            ),
            Edit::Truncate(i) => lines.truncate(i % (n + 1)),
        }
    }
    lines.join("\n")
}

fn edit() -> impl Strategy<Value = Edit> {
    prop_oneof![
        (any::<usize>(), any::<usize>()).prop_map(|(a, b)| Edit::ReplaceNumber(a, b)),
        any::<usize>().prop_map(Edit::DeleteLine),
        any::<usize>().prop_map(Edit::DuplicateLine),
        (any::<usize>(), any::<usize>()).prop_map(|(a, b)| Edit::InsertLine(a, b)),
        any::<usize>().prop_map(Edit::Truncate),
    ]
}

/// `text` in a temporary .obj file, removed when the returned guard drops.
fn temp_obj(text: &str, case: u64) -> tempfile::NamedTempFile {
    let mut file = tempfile::Builder::new()
        .prefix(&format!("ptui-fuzz-obj-case-{case}-"))
        .suffix(".obj")
        .tempfile()
        .expect("temp OBJ");
    std::io::Write::write_all(&mut file, text.as_bytes()).expect("write temp OBJ");
    file
}

/// [`check_now`] within the fuzzers' time limit.
fn check(text: &str, case: u64) -> Result<(), TestCaseError> {
    let owned = text.to_string();
    crate::common::within(crate::common::CASE_LIMIT, text, move || {
        check_now(&owned, case)
    })
}

/// Load `text` as an OBJ file and, if it loads, render it inside a lit scene.
fn check_now(text: &str, case: u64) -> Result<(), TestCaseError> {
    let file = temp_obj(text, case);
    let path = file.path();
    let loaded = mesh::load_obj(path, 10_000, None);
    match &loaded {
        Ok(m) => {
            for t in &m.triangles {
                prop_assert!(
                    t.p().iter().all(|v| v.is_finite()),
                    "non-finite vertex {t:?}"
                );
            }
        }
        Err(msg) => {
            // Every refusal names the file, and the line where one is to blame (all but an
            // empty file and one over the triangle limit).
            let shown = path.display().to_string();
            prop_assert!(msg.contains(&shown), "{msg}");
            if !msg.contains("no faces") && !msg.contains("more than") {
                let rest = &msg[msg.find(&shown).unwrap_or(0) + shown.len()..];
                let line = rest
                    .strip_prefix(':')
                    .map(|r| r.split(':').next().unwrap_or(""));
                prop_assert!(
                    line.is_some_and(|l| l.parse::<usize>().is_ok()),
                    "no file:line in {msg}"
                );
            }
        }
    }
    let scene_src = format!(
        "[camera]\nposition = [0.5, 0.5, 4]\n\n[[mesh]]\npath = {:?}\n\n[[sphere]]\ncenter = [0, 5, 5]\nradius = 1\nemission = 5\n",
        path.display().to_string()
    );
    match load_str(&scene_src, "fuzz.toml") {
        Ok(scene) => {
            prop_assert!(loaded.is_ok(), "scene loaded a mesh the loader rejected");
            let settings = RenderSettings::merged(&[&SettingsOverrides {
                width: Some(8),
                height: Some(6),
                spp: Some(2),
                threads: Some(1),
                ..Default::default()
            }]);
            let mut r = Renderer::new(Arc::new(scene), settings).expect("settings");
            r.render(&AtomicBool::new(false), |_| true);
            prop_assert_eq!(r.stats().invalid, 0);
        }
        Err(e) => {
            let msg = e.to_string();
            prop_assert!(
                msg.contains("fuzz.toml"),
                "error without the scene file: {msg}"
            );
        }
    }
    Ok(())
}

fn config() -> ProptestConfig {
    ProptestConfig {
        cases: 256,
        failure_persistence: None,
        rng_algorithm: proptest::test_runner::RngAlgorithm::ChaCha,
        ..ProptestConfig::default()
    }
}

static CASE: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

fn next_case() -> u64 {
    CASE.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
}

#[test]
fn the_unmutated_cube_loads() {
    let file = temp_obj(CUBE, u64::MAX);
    let path = file.path();
    let m = mesh::load_obj(path, 100, None).expect("valid cube");
    assert_eq!(m.triangles.len(), 12);
    assert_eq!(
        m.warnings.len(),
        1,
        "one warning for mtllib / usemtl: {:?}",
        m.warnings
    );
}

proptest! {
    #![proptest_config(config())]

    #[test]
    fn mutated_cubes_never_panic(edits in prop::collection::vec(edit(), 1..6)) {
        check(&apply(CUBE, &edits), next_case())?;
    }

    #[test]
    fn random_lines_never_panic(lines in prop::collection::vec(0..LINES.len(), 0..24)) {
        let text: Vec<&str> = lines.iter().map(|&i| LINES[i]).collect();
        check(&text.join("\n"), next_case())?;
    }

    #[test]
    fn random_bytes_never_panic(text in ".{0,200}") {
        check(&text, next_case())?;
    }
}
