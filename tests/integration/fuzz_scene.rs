//! Fuzz-style property tests of the scene loader: random text and mutations of the built-in and
//! extreme scenes (numbers replaced by NaN, infinities, huge, tiny or negative values, strings,
//! arrays; lines duplicated, deleted, cut short; random characters inserted). The loader must
//! never panic: it returns a scene or an error with a message. Whatever loads must render a tiny
//! image without panicking and without NaN or infinite samples. Every case runs with a time limit
//! (`common::within`), so a hang fails the test instead of stalling it.

use proptest::prelude::*;
use ptui::render::Renderer;
use ptui::scene::{builtin, load_str};
use ptui::settings::RenderSettings;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

fn sources() -> Vec<&'static str> {
    builtin::BUILTIN
        .iter()
        .chain(ptui::analysis::check::extreme::EXTREME)
        .map(|(_, s)| *s)
        .collect()
}

/// Values a mutation may put where a number was.
const REPLACEMENTS: &[&str] = &[
    "nan",
    "inf",
    "-inf",
    "+inf",
    "-1",
    "0",
    "-0.0",
    "1e308",
    "1e-308",
    "1e31",
    "1e-31",
    "1e30",
    "1e-30",
    "99999999999999999999",
    "\"x\"",
    "[1, 2]",
    "[1, 2, 3, 4]",
    "true",
    "{}",
    "0.5",
    "1",
    "1e5",
    "[0, 0, 0]",
    "2000-01-01",
];

#[derive(Clone, Debug)]
enum Mutation {
    /// Replace the n-th number-like token.
    Number(usize, usize),
    DeleteLine(usize),
    DuplicateLine(usize),
    /// Insert text at a character position.
    Insert(usize, String),
    /// Cut the text at a character position.
    Truncate(usize),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        4 => (any::<usize>(), 0..REPLACEMENTS.len()).prop_map(|(i, r)| Mutation::Number(i, r)),
        1 => any::<usize>().prop_map(Mutation::DeleteLine),
        1 => any::<usize>().prop_map(Mutation::DuplicateLine),
        1 => (any::<usize>(), "[\\[\\]{}=\",.#\\n a-z0-9\u{e9}\u{1F600}-]{1,8}")
            .prop_map(|(i, s)| Mutation::Insert(i, s)),
        1 => any::<usize>().prop_map(Mutation::Truncate),
    ]
}

fn apply(src: &str, m: &Mutation) -> String {
    match m {
        Mutation::Number(i, r) => {
            // Number-like tokens: maximal runs of digits, signs, dots and exponents.
            let is_num = |c: char| c.is_ascii_digit() || matches!(c, '.' | '-' | '+' | 'e');
            let mut tokens = Vec::new();
            let mut start = None;
            for (k, c) in src.char_indices().chain([(src.len(), ' ')]) {
                match (start, is_num(c)) {
                    (None, true) => start = Some(k),
                    (Some(s), false) => {
                        if src[s..k].chars().any(|c| c.is_ascii_digit()) {
                            tokens.push(s..k);
                        }
                        start = None;
                    }
                    _ => {}
                }
            }
            if tokens.is_empty() {
                return src.to_string();
            }
            let range = tokens[i % tokens.len()].clone();
            format!(
                "{}{}{}",
                &src[..range.start],
                REPLACEMENTS[*r],
                &src[range.end..]
            )
        }
        Mutation::DeleteLine(i) | Mutation::DuplicateLine(i) => {
            let mut lines: Vec<&str> = src.lines().collect();
            if lines.is_empty() {
                return src.to_string();
            }
            let k = i % lines.len();
            if matches!(m, Mutation::DeleteLine(_)) {
                lines.remove(k);
            } else {
                lines.insert(k, lines[k]);
            }
            lines.join("\n")
        }
        Mutation::Insert(i, s) => {
            let chars: Vec<char> = src.chars().collect();
            let k = i % (chars.len() + 1);
            chars[..k]
                .iter()
                .chain(s.chars().collect::<Vec<_>>().iter())
                .chain(chars[k..].iter())
                .collect()
        }
        Mutation::Truncate(i) => {
            let chars: Vec<char> = src.chars().collect();
            chars[..i % (chars.len() + 1)].iter().collect()
        }
    }
}

/// [`load_and_render_now`] within the fuzzers' time limit.
fn load_and_render(text: &str) -> Result<(), TestCaseError> {
    let owned = text.to_string();
    crate::common::within(crate::common::CASE_LIMIT, text, move || {
        load_and_render_now(&owned)
    })
}

/// Load; if it loads, render 4x3 with one sample per pixel on one thread.
fn load_and_render_now(text: &str) -> Result<(), TestCaseError> {
    match load_str(text, "fuzz.toml") {
        Err(e) => {
            let msg = e.to_string();
            prop_assert!(
                msg.starts_with("fuzz.toml"),
                "error without the file: {msg}"
            );
            prop_assert!(msg.len() > "fuzz.toml: ".len(), "empty message");
        }
        Ok(scene) => {
            let scene = Arc::new(scene);
            let mut s = RenderSettings::merged(&[&scene.render]);
            (s.width, s.height, s.spp, s.threads) = (4, 3, 1, 1);
            let mut r = Renderer::new(scene, s).map_err(|e| TestCaseError::fail(e.to_string()))?;
            r.render(&AtomicBool::new(false), |_| true);
            prop_assert_eq!(r.stats().invalid, 0, "invalid samples in:\n{}", text);
        }
    }
    Ok(())
}

/// Fixed seed and 512 cases in CI; `PTUI_FUZZ_CASES=100000 PTUI_FUZZ_SEED=7` for a longer run.
fn config() -> ProptestConfig {
    let env = |k: &str| std::env::var(k).ok().and_then(|v| v.parse::<u64>().ok());
    ProptestConfig {
        cases: env("PTUI_FUZZ_CASES").unwrap_or(512) as u32,
        rng_seed: prop::test_runner::RngSeed::Fixed(env("PTUI_FUZZ_SEED").unwrap_or(6)),
        failure_persistence: None,
        ..ProptestConfig::default()
    }
}

proptest! {
    #![proptest_config(config())]

    #[test]
    fn mutated_scenes_never_panic(
        which in any::<usize>(),
        mutations in prop::collection::vec(mutation(), 1..4),
    ) {
        let all = sources();
        let mut text = all[which % all.len()].to_string();
        for m in &mutations {
            text = apply(&text, m);
        }
        load_and_render(&text)?;
    }

    #[test]
    fn random_text_never_panics(text in "\\PC{0,300}") {
        load_and_render(&text)?;
    }

    #[test]
    fn random_toml_shaped_text_never_panics(
        text in "(\\[\\[?(camera|render|sphere|check)\\]\\]?\n|[a-z_]{1,9} = (-?[0-9.e]{1,6}|nan|inf|\"[a-z]{0,5}\"|\\[[0-9., -]{0,12}\\])\n){0,12}"
    ) {
        load_and_render(&text)?;
    }
}
