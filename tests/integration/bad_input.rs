//! Every kind of bad scene file gets an error value whose message names the file, the line and
//! the field, and says what is wrong: types, ranges, NaN/Inf (TOML `nan`, `inf`), missing values,
//! unknown keys, duplicate names, and a resolution whose film would not fit in memory.
//!
//! Each case is a small scene with the offending line marked by a trailing `#!`; the error must
//! start with `bad.toml:<that line>:` and carry the field path and a fragment of the message.
//! The `[check]` table is read by the check code from the same text, so a case loads as
//! `ptui check` does: the scene, then its check table.

use ptui::analysis::check::{check_desc, Source};
use ptui::scene::{load_str, SceneError};
use std::borrow::Cow;

const CAMERA: &str = "[camera]\nposition = [0, 0, 5]\n";

/// (scene text with the bad line marked `#!`, field path, message fragment).
fn cases() -> Vec<(String, &'static str, &'static str)> {
    let sphere = |body: &str| format!("{CAMERA}\n[[sphere]]\n{body}\n");
    let render = |body: &str| format!("{CAMERA}\n[render]\n{body}\n");
    let camera = |body: &str| format!("[camera]\n{body}\n");
    let ok_sphere = "center = [0, 0, 0]\nradius = 1";
    vec![
        // Types.
        (sphere("center = [0, 0, 0]\nradius = \"one\" #!"), "sphere[0].radius", "invalid type"),
        (sphere("center = 5 #!\nradius = 1"), "sphere[0].center", "array of 3 numbers"),
        (sphere("center = [0, 0] #!\nradius = 1"), "sphere[0].center", "invalid length 2"),
        (sphere("center = [0, 0, 0, 0] #!\nradius = 1"), "sphere[0].center", "invalid length"),
        (sphere("center = [0, \"y\", 0] #!\nradius = 1"), "sphere[0].center[1]", "invalid type"),
        (sphere(&format!("{ok_sphere}\nmaterial = \"metal\" #!")), "sphere[0].material", "unknown variant `metal`"),
        (sphere(&format!("{ok_sphere}\nname = 3 #!")), "sphere[0].name", "invalid type"),
        (format!("sphere = 5 #!\n{CAMERA}"), "sphere", "invalid type"),
        (render("width = 320.5 #!"), "render.width", "invalid type"),
        (render("seed = -1 #!"), "render.seed", "invalid value"),
        (render("max_depth = -1 #!"), "render.max_depth", "invalid value"),
        (render("integrator = \"bdpt\" #!"), "render.integrator", "unknown variant `bdpt`"),
        (render("tonemap = \"filmic\" #!"), "render.tonemap", "unknown variant `filmic`"),
        // Ranges.
        (sphere("center = [0, 0, 0]\nradius = -1 #!"), "sphere[0].radius", "must be > 0"),
        (sphere("center = [0, 0, 0]\nradius = 0 #!"), "sphere[0].radius", "must be > 0"),
        (sphere("center = [0, 0, 0]\nradius = 1e31 #!"), "sphere[0].radius", "magnitude must be at most 1e30"),
        (sphere("center = [0, 0, 0]\nradius = 1e-31 #!"), "sphere[0].radius", "must be at least 1e-30"),
        (sphere("center = [0, 0, 2e30] #!\nradius = 1"), "sphere[0].center", "magnitude must be at most 1e30"),
        (sphere(&format!("{ok_sphere}\ncolor = 1.5 #!")), "sphere[0].color", "must be in [0, 1]"),
        (sphere(&format!("{ok_sphere}\ncolor = [0.5, -0.1, 0.5] #!")), "sphere[0].color", "must be in [0, 1]"),
        (sphere(&format!("{ok_sphere}\nemission = -1 #!")), "sphere[0].emission", "must be >= 0"),
        (sphere(&format!("{ok_sphere}\nemission = 1e31 #!")), "sphere[0].emission", "magnitude"),
        (sphere(&format!("{ok_sphere}\nmaterial = \"glass\"\nior = 0.05 #!")), "sphere[0].ior", "between 0.1 and 10"),
        (sphere(&format!("{ok_sphere}\nmaterial = \"glass\"\nior = 11 #!")), "sphere[0].ior", "between 0.1 and 10"),
        (sphere(&format!("{ok_sphere}\nior = 1.5 #!")), "sphere[0].ior", "only applies to material = \"glass\""),
        (camera("vfov = 180 #!"), "camera.vfov", "between 0 and 180"),
        (camera("vfov = 0 #!"), "camera.vfov", "between 0 and 180"),
        (camera("near = -1 #!"), "camera.near", "must be >= 0"),
        (camera("direction = [0, 0, 0] #!"), "camera.direction", "zero vector"),
        (camera("direction = [1e-31, 0, 0] #!"), "camera.direction", "too short to normalise"),
        (camera("direction = [0, 0, -1]\nlook_at = [0, 0, -1] #!"), "camera.look_at", "not both"),
        (camera("position = [1, 2, 3]\nlook_at = [1, 2, 3] #!"), "camera.look_at", "its own position"),
        (camera("direction = [0, 1, 0]\nup = [0, 2, 0] #!"), "camera.up", "parallel"),
        (camera("aperture = -0.1 #!"), "camera.aperture", "must be >= 0"),
        (camera("focus_distance = 0 #!"), "camera.focus_distance", "must be > 0"),
        (camera("focus_distance = 3\nfocus_on = [0, 0, -1] #!"), "camera.focus_on", "not both"),
        (camera("focus_on = [0, 0, 4] #!"), "camera.focus_on", "not in front of the camera"),
        (render("width = 0 #!"), "render.width", "between 1 and 32768"),
        (render("height = 40000 #!"), "render.height", "between 1 and 32768"),
        (render("spp = 0 #!"), "render.spp", "at least 1"),
        (render("exposure = 0 #!"), "render.exposure", "must be > 0"),
        (render("threads = 5000 #!"), "render.threads", "between 0 (one per core) and 1024"),
        (format!("background = -1 #!\n{CAMERA}"), "background", "must be >= 0"),
        // NaN and infinities, as TOML writes them.
        (sphere("center = [0, 0, 0]\nradius = nan #!"), "sphere[0].radius", "finite"),
        (sphere("center = [0, 0, 0]\nradius = inf #!"), "sphere[0].radius", "finite"),
        (sphere("center = [0, -inf, 0] #!\nradius = 1"), "sphere[0].center", "finite"),
        (sphere(&format!("{ok_sphere}\ncolor = [0.5, nan, 0.5] #!")), "sphere[0].color", "finite"),
        (sphere(&format!("{ok_sphere}\nemission = +inf #!")), "sphere[0].emission", "finite"),
        (sphere(&format!("{ok_sphere}\nmaterial = \"glass\"\nior = nan #!")), "sphere[0].ior", "finite"),
        (camera("vfov = nan #!"), "camera.vfov", "finite"),
        (camera("position = [inf, 0, 0] #!"), "camera.position", "finite"),
        (camera("up = [0, nan, 1] #!"), "camera.up", "finite"),
        (camera("near = inf #!"), "camera.near", "finite"),
        (render("exposure = nan #!"), "render.exposure", "finite"),
        (render("exposure = -inf #!"), "render.exposure", "finite"),
        (format!("background = [0, 0, nan] #!\n{CAMERA}"), "background", "finite"),
        // Missing values.
        (format!("{CAMERA}\n[[sphere]] #!\nradius = 1\n"), "sphere[0]", "missing field `center`"),
        (format!("{CAMERA}\n[[sphere]] #!\ncenter = [0, 0, 0]\n"), "sphere[0]", "missing field `radius`"),
        // Unknown keys.
        (sphere(&format!("{ok_sphere}\nradus = 2 #!")), "sphere[0].radus", "unknown field `radus`"),
        (camera("fov = 40 #!"), "camera.fov", "unknown field `fov`"),
        (format!("{CAMERA}\n[lights] #!\nx = 1\n"), "lights", "unknown field `lights`"),
        (render("samples = 4 #!"), "render.samples", "unknown field `samples`"),
        // Duplicates.
        (
            format!("{CAMERA}\n[[sphere]]\nname = \"a\"\n{ok_sphere}\n\n[[sphere]]\nname = \"a\" #!\n{ok_sphere}\n"),
            "sphere[1].name",
            "duplicate object name `a`",
        ),
        (sphere("center = [0, 0, 0]\nradius = 1\nradius = 2 #!"), "", "duplicate key"),
        // The [check] table of `ptui check`.
        (format!("{CAMERA}\n[check]\nspp = 1 #!\n"), "check.spp", "at least 2 samples"),
        (format!("{CAMERA}\n[check]\nrange = [2, 1] #!\n"), "check.range", "lo <= hi"),
        (format!("{CAMERA}\n[check]\nrange = [0, nan] #!\n"), "check.range", "finite"),
        (format!("{CAMERA}\n[check]\nmean = -1 #!\n"), "check.mean", "must be >= 0"),
        (format!("{CAMERA}\n[check]\nexpect = 1 #!\n"), "check.expect", "unknown field `expect`"),
        // Syntax.
        (sphere("center = [0, 0, 0]\nradius = #!"), "", "expected"),
        (format!("{CAMERA}\n[[sphere] #!\n"), "", "expected"),
    ]
}

fn marked_line(src: &str) -> usize {
    src.lines()
        .position(|l| l.contains("#!"))
        .map(|i| i + 1)
        .expect("case has a #! marker")
}

/// The scene and its `[check]` table, as `ptui check` reads a file.
fn load(src: &str) -> Result<(), SceneError> {
    load_str(src, "bad.toml")?;
    check_desc(&Source {
        name: "bad.toml".into(),
        text: Cow::Owned(src.to_string()),
        dir: None,
    })?;
    Ok(())
}

#[test]
fn every_bad_value_is_named_with_file_line_and_field() {
    let mut failures = Vec::new();
    for (src, field, fragment) in cases() {
        let line = marked_line(&src);
        let err = match load(&src) {
            Ok(_) => {
                failures.push(format!("accepted:\n{src}"));
                continue;
            }
            Err(e) => e.to_string(),
        };
        let located = err.starts_with(&format!("bad.toml:{line}:"));
        let named = field.is_empty() || err.contains(&format!("field `{field}`"));
        let says = err.contains(fragment);
        if !(located && named && says) {
            failures.push(format!(
                "want line {line}, field `{field}`, \"{fragment}\"; got: {err}\n--- scene:\n{src}"
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

/// MemAvailable in bytes, as `settings` reads it.
fn available_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    Some(line.split_whitespace().nth(1)?.parse::<u64>().ok()? * 1024)
}

/// A film of 32768 x 32768 needs 64 GiB: the loader says so at the `width` line, on machines
/// with less memory than that available (all our CI machines).
#[test]
fn a_film_larger_than_memory_is_an_error_of_the_scene_file() {
    let src = format!("{CAMERA}\n[render]\nwidth = 32768 #!\nheight = 32768\n");
    let need = 32768u64 * 32768 * ptui::settings::BYTES_PER_PIXEL;
    match available_memory() {
        Some(avail) if avail < need => {
            let err = load_str(&src, "bad.toml")
                .expect_err("rejected")
                .to_string();
            assert!(
                err.starts_with(&format!("bad.toml:{}:", marked_line(&src)))
                    && err.contains("field `render.width`")
                    && err.contains("needs 64.0 GiB"),
                "{err}"
            );
        }
        _ => eprintln!("skipped: this machine has 64 GiB available"),
    }
    // A size that fits is accepted.
    load_str(
        &format!("{CAMERA}\n[render]\nwidth = 64\nheight = 48\n"),
        "ok.toml",
    )
    .unwrap();
}

/// Errors are values: missing files and directories are reported with their path.
#[test]
fn missing_paths_and_directories_are_errors() {
    let err = ptui::scene::load("/nonexistent/scene.toml")
        .err()
        .unwrap()
        .to_string();
    assert!(err.contains("/nonexistent/scene.toml"), "{err}");
    let dir = std::env::temp_dir();
    let err = ptui::scene::load(dir.to_str().unwrap())
        .err()
        .unwrap()
        .to_string();
    assert!(
        err.ends_with("cannot read scene file: a directory, not a file"),
        "{err}"
    );
}

/// Values at the edge of every range are accepted and render finite images.
#[test]
fn extremes_of_every_range_are_accepted_and_render() {
    use ptui::render::Renderer;
    use ptui::settings::RenderSettings;
    use std::sync::{atomic::AtomicBool, Arc};
    let src = "[camera]\nposition = [0, 0, 1e30]\ndirection = [1e-30, 0, -1e-30]\nvfov = 179.9\n\
               near = 1e30\n[render]\nexposure = 1e30\nthreads = 1\n\
               [[sphere]]\ncenter = [0, 0, 0]\nradius = 1e30\ncolor = 1\nemission = 1e30\n\
               [[sphere]]\ncenter = [-1e30, 1e30, 0]\nradius = 1e-30\nmaterial = \"glass\"\nior = 10\n\
               [[sphere]]\ncenter = [1, 1, 1]\nradius = 1e-30\nmaterial = \"glass\"\nior = 0.1\n";
    let scene = Arc::new(load_str(src, "edge.toml").unwrap());
    let mut settings = RenderSettings::merged(&[&scene.render]);
    (settings.width, settings.height, settings.spp) = (8, 6, 4);
    let mut r = Renderer::new(scene, settings).unwrap();
    r.render(&AtomicBool::new(false), |_| true);
    assert_eq!(r.stats().invalid, 0);
    assert!(r.film().mean_rgb_f32().iter().all(|v| v.is_finite()));
}
