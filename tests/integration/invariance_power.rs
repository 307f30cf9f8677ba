//! The invariance tests can fail: the same per-pixel z-test that accepts translated, scaled and
//! re-walled Cornell boxes (tests/extreme_scenes.rs) rejects small but real changes of the image
//! at the same size, sample count and significance level.

use ptui::analysis::check::{self, Options, Source};
use std::borrow::Cow;

/// Check a variant of an extreme scene's text, edited by `edit`.
fn check_variant(base: &str, edit: impl Fn(&str) -> String) -> check::Outcome {
    let text = edit(check::extreme::get(base).expect("extreme scene"));
    let source = Source {
        name: format!("{base} (variant)"),
        text: Cow::Owned(text),
        dir: None,
    };
    check::run(&source, &Options::default()).expect("variant renders")
}

fn only(text: &str, from: &str, to: &str) -> String {
    assert_eq!(text.matches(from).count(), 1, "`{from}` must occur once");
    text.replace(from, to)
}

/// A global change of 3% (the light's emission 12 -> 11.64) in the translated Cornell box: no
/// pixel can show it at 256 spp, but the image-mean test does.
#[test]
fn a_three_percent_darker_light_is_rejected() {
    let o = check_variant("translate-1e4", |t| {
        only(t, "emission = 12.0", "emission = 11.64")
    });
    eprintln!("{:?}", o.verdicts);
    assert_eq!(o.invalid, 0);
    assert!(!o.passed(), "darkened light accepted: {:?}", o.verdicts);
}

/// A local change: the mirror ball made diffuse. Pixels that saw the light in the mirror
/// (radiance 12 * 0.999, nearly noise-free) now see a grey ball: the per-pixel test rejects it.
#[test]
fn a_mirror_made_diffuse_is_rejected() {
    let o = check_variant("translate-1e4", |t| only(t, "material = \"mirror\"\n", ""));
    eprintln!("{:?}", o.verdicts);
    assert!(!o.passed(), "diffuse mirror accepted: {:?}", o.verdicts);
}

/// The index-matched sphere given an index of 1.5 refracts the room behind it: many pixels change
/// moderately, none enough alone (max|z| 4.8 against 5.0, measured), so the chi-square test is
/// the one that rejects it (3.9 against 3.06, measured). Deep tier: the scene's 8192 spp take
/// about 12 s.
#[test]
#[ignore = "deep tier: cargo test --release -- --ignored"]
fn index_matched_glass_made_visible_is_rejected() {
    let o = check_variant("index-matched", |t| only(t, "ior = 1.0", "ior = 1.5"));
    eprintln!("{:?}", o.verdicts);
    assert!(!o.passed(), "visible glass accepted: {:?}", o.verdicts);
}

/// The stiff tests have power too: the albedo-0.99 furnace checked against 98 instead of 100 (2%
/// off), and the radius-1e-4 light given 3% less power than the radius-1e-2 one, are rejected.
#[test]
fn furnace_with_the_wrong_expectation_is_rejected() {
    let o = check_variant("furnace-0.99", |t| {
        only(
            &only(t, "mean = 100\n", "mean = 98\n"),
            "range = [100, 100]",
            "range = [98, 98]",
        )
    });
    eprintln!("{:?}", o.verdicts);
    assert!(!o.passed(), "2% off accepted: {:?}", o.verdicts);
}

#[test]
fn small_light_with_less_power_is_rejected() {
    let o = check_variant("small-light-1e-4", |t| {
        only(t, "emission = 90000000000.0", "emission = 87300000000.0")
    });
    eprintln!("{:?}", o.verdicts);
    assert!(!o.passed(), "3% less power accepted: {:?}", o.verdicts);
}
