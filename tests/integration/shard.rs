//! Shards, film files, merge and resume (issue 36): the merge of N shards is the single render
//! (the mean within 1e-12 relative per pixel and channel, sample counts exact; not bit for bit,
//! see `ptui::io::shard`), in any order; mismatched, overlapping and corrupt parts are refused; a
//! resumed film equals a render never stopped, bit for bit.

use ptui::io::film_file::{self, FilmHeader, FilmStats};
use ptui::io::shard::{self, MergeError, Shard};
use ptui::render::adaptive::SampleMap;
use ptui::render::film::Film;
use ptui::render::Renderer;
use ptui::scene;
use ptui::settings::{Caustics, RenderSettings};
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

const W: u32 = 64;
const H: u32 = 48;

fn settings(name: &str, spp: u32, edit: impl Fn(&mut RenderSettings)) -> RenderSettings {
    let scene = scene::load(name).expect("built-in scene");
    let mut s = RenderSettings::merged(&[&scene.render]);
    (s.width, s.height, s.spp, s.threads) = (W, H, spp, 2);
    edit(&mut s);
    s
}

fn header_of(r: &Renderer, scene: &str) -> FilmHeader {
    let (first, end) = r.pass_range();
    let done = r.stats().complete_passes;
    FilmHeader {
        passes: if done > first {
            vec![[first, done]]
        } else {
            vec![]
        },
        until: end,
        error_from_halves: r.error_from_halves(),
        stats: FilmStats::from_render(&r.stats()),
        ..FilmHeader::new(
            scene,
            &film_file::scene_hash(scene).expect("hash"),
            &r.settings,
        )
    }
}

/// Render `name` with `s`, passes `range` (the whole render if None), as `render --shard`
/// does, and write its film to `path`.
fn render_part(name: &str, s: &RenderSettings, range: Option<(u32, u32)>, path: &Path) -> Renderer {
    let scene = Arc::new(scene::load(name).expect("built-in scene"));
    let mut r = Renderer::new(scene, s.clone()).expect("settings");
    let cancel = AtomicBool::new(false);
    if let Some((a, b)) = range {
        r.set_range(a, b);
    }
    if r.needs_pilot() {
        let map = r.pilot_map(&cancel);
        r.set_map(map);
    }
    r.render(&cancel, |_| true);
    film_file::write(path, &header_of(&r, name), r.film(), r.sample_map()).expect("write");
    r
}

fn shards(name: &str, s: &RenderSettings, n: u32, dir: &Path, tag: &str) -> Vec<PathBuf> {
    (0..n)
        .map(|i| {
            let path = dir.join(format!("{tag}-{i}.film"));
            let range = Shard::new(i, n).expect("shard").passes(s.spp);
            render_part(name, s, Some(range), &path);
            path
        })
        .collect()
}

/// The largest relative difference between two films' means, per pixel and channel; counts
/// must agree exactly.
fn max_rel_diff(a: &Film, b: &Film) -> f64 {
    let mut worst = 0.0f64;
    for i in 0..a.pixels() {
        assert_eq!(a.count(i), b.count(i), "pixel {i}'s sample count");
        let (x, y) = (a.mean(i).to_array(), b.mean(i).to_array());
        for c in 0..3 {
            let scale = x[c].abs().max(y[c].abs());
            if scale > 0.0 {
                worst = worst.max((x[c] - y[c]).abs() / scale);
            }
        }
    }
    worst
}

fn same_bits(a: &Film, b: &Film) -> bool {
    (0..a.pixels()).all(|i| {
        let (x, y) = (a.pixel_state(i), b.pixel_state(i));
        x.mean.map(f64::to_bits) == y.mean.map(f64::to_bits)
            && x.m2.map(f32::to_bits) == y.m2.map(f32::to_bits)
            && x.odd_mean.map(f32::to_bits) == y.odd_mean.map(f32::to_bits)
            && (x.count, x.odd_count) == (y.count, y.odd_count)
    })
}

/// The merged film's error estimate equals the single render's to the precision the film
/// stores it in: M2 and the odd-pass mean are f32, accumulated sample by sample in one and
/// merged pairwise in the other, each with a relative rounding error of at most n 2^-24 per
/// pixel (n <= 64 samples here: 4e-6). The image's estimate averages those over the pixels, so
/// they stay at that order (measured: 1e-8 to 1e-7 on these renders); a merge that lost a term
/// (M2's between-part spread, an odd-pass count) is off by percents.
const ERROR_TOLERANCE: f64 = 1e-5;

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol * a.abs().max(b.abs())
}

/// The merge of the shards of a render is that render: default integrator (caustics left to
/// the camera paths, uniform sampling), the light tracer (cornell's default `caustics =
/// "light"`), adaptive sampling (cornell's default, with shards starting before, at and after
/// the pilot's end), with Sobol and independent samples.
#[test]
fn merged_shards_equal_the_single_render() {
    let dir = tempfile::tempdir().expect("tempdir");
    let cases: Vec<(&str, RenderSettings, u32)> = vec![
        (
            "plain",
            settings("cornell", 24, |s| {
                s.caustics = Caustics::Path;
                s.adaptive = false;
            }),
            3,
        ),
        ("light", settings("cornell", 24, |s| s.adaptive = false), 4),
        ("adaptive-light", settings("cornell", 40, |_| {}), 3),
        (
            "adaptive-independent",
            settings("cornell-small-light", 36, |s| {
                s.sampler = ptui::sampling::SamplerKind::Independent;
                s.caustics = Caustics::Path;
            }),
            5,
        ),
    ];
    for (tag, s, n) in cases {
        let name = if tag == "adaptive-independent" {
            "cornell-small-light"
        } else {
            "cornell"
        };
        let single = render_part(name, &s, None, &dir.path().join(format!("{tag}.film")));
        let parts = shards(name, &s, n, dir.path(), tag);
        let m = shard::merge(&parts, true).expect("merge");
        assert!(m.missing.is_empty());
        assert_eq!(m.header.passes, [[0, s.spp]]);
        let worst = max_rel_diff(single.film(), &m.film);
        assert!(worst <= 1e-12, "{tag}: mean differs by {worst:e} relative");
        assert_eq!(m.map.as_ref(), single.sample_map(), "{tag}: adaptive map");
        assert_eq!(m.header.error_from_halves, single.error_from_halves());
        let (a, b) = (
            single.error_estimate(),
            m.film.error_estimate(m.header.error_from_halves),
        );
        assert!(
            close(a.rmse, b.rmse, ERROR_TOLERANCE) && close(a.rel_mse, b.rel_mse, ERROR_TOLERANCE),
            "{tag}: error estimate {a:?} vs merged {b:?}"
        );
        assert_eq!(m.header.stats.samples, single.stats().samples, "{tag}");
        assert_eq!(m.header.stats.invalid, single.stats().invalid, "{tag}");
        // The one-part merge is the film itself, bit for bit.
        let one = shard::merge(&[dir.path().join(format!("{tag}.film"))], true).expect("merge");
        assert!(same_bits(&one.film, single.film()), "{tag}");
    }
}

/// The merge is the same bit for bit whatever the order of its parts.
#[test]
fn merge_does_not_depend_on_the_order_of_parts() {
    let dir = tempfile::tempdir().expect("tempdir");
    let s = settings("cornell", 24, |_| {});
    let p = shards("cornell", &s, 4, dir.path(), "o");
    let a = shard::merge(&p, true).expect("merge");
    for order in [[3, 1, 0, 2], [2, 3, 1, 0], [1, 0, 3, 2]] {
        let q: Vec<PathBuf> = order.iter().map(|&i| p[i].clone()).collect();
        let b = shard::merge(&q, true).expect("merge");
        assert!(same_bits(&a.film, &b.film), "{order:?}");
        assert_eq!(a.header, b.header);
    }
}

fn refusal(paths: &[PathBuf]) -> String {
    match shard::merge(paths, false) {
        Ok(_) => panic!("merge accepted parts it should refuse"),
        Err(e) => e.to_string(),
    }
}

/// Parts of another scene, seed, setting or version, overlapping passes and corrupt files are
/// refused with the field and both values; missing shards are reported, or refused with
/// `require_complete`.
#[test]
fn merge_refuses_parts_that_do_not_belong_together() {
    let dir = tempfile::tempdir().expect("tempdir");
    let d = dir.path();
    let s = settings("cornell", 8, |s| s.adaptive = false);
    let p = shards("cornell", &s, 2, d, "a");
    // Another seed.
    let other = shards(
        "cornell",
        &settings("cornell", 8, |s| {
            s.adaptive = false;
            s.seed = 7;
        }),
        2,
        d,
        "seed",
    );
    let e = refusal(&[p[0].clone(), other[1].clone()]);
    assert!(e.contains("seed is 7") && e.contains("0 in"), "{e}");
    // Another scene (same size and settings).
    let small = shards(
        "cornell-small-light",
        &settings("cornell-small-light", 8, |s| {
            s.adaptive = false;
        }),
        2,
        d,
        "scene",
    );
    let e = refusal(&[p[0].clone(), small[1].clone()]);
    assert!(e.contains("scene_hash is sha256:"), "{e}");
    // Another setting.
    let depth = shards(
        "cornell",
        &settings("cornell", 8, |s| {
            s.adaptive = false;
            s.max_depth = Some(3);
        }),
        2,
        d,
        "depth",
    );
    let e = refusal(&[p[0].clone(), depth[1].clone()]);
    assert!(
        e.contains("max_depth is 3") && e.contains("unlimited"),
        "{e}"
    );
    // Another version.
    let (mut h, film, map) = film_file::read(&p[1]).expect("read");
    h.ptui_version = "0.0.9".into();
    let old = d.join("old.film");
    film_file::write(&old, &h, &film, map.as_ref()).expect("write");
    let e = refusal(&[p[0].clone(), old]);
    assert!(e.contains("ptui_version is 0.0.9"), "{e}");
    // Overlapping passes: a shard twice, and shards of different splits.
    let e = refusal(&[p[0].clone(), p[1].clone(), p[0].clone()]);
    assert!(e.contains("overlap") && e.contains("0..4"), "{e}");
    let thirds = shards("cornell", &s, 3, d, "t");
    let e = refusal(&[p[0].clone(), thirds[1].clone()]);
    assert!(e.contains("overlap") && e.contains("2..5"), "{e}");
    // Missing shards: reported, refused on request.
    let m = shard::merge(&[p[1].clone()], false).expect("a partial merge");
    assert_eq!(m.missing, [[0, 4]]);
    assert_eq!(m.header.passes, [[4, 8]]);
    match shard::merge(&[p[1].clone()], true) {
        Err(MergeError::Incomplete { missing, .. }) => assert_eq!(missing, "0..4"),
        other => panic!("{:?}", other.err()),
    }
    // Corrupt and truncated files.
    let bytes = std::fs::read(&p[1]).expect("read");
    let mut flipped = bytes.clone();
    let at = bytes.len() / 2;
    flipped[at] ^= 0x10;
    let bad = d.join("bad.film");
    std::fs::write(&bad, &flipped).expect("write");
    let e = refusal(&[p[0].clone(), bad.clone()]);
    assert!(e.contains("bad.film") && e.contains("checksum"), "{e}");
    std::fs::write(&bad, &bytes[..bytes.len() - 100]).expect("write");
    let e = refusal(&[p[0].clone(), bad.clone()]);
    assert!(e.contains("truncated"), "{e}");
    std::fs::write(&bad, b"P3\n1 1\n255\n0 0 0\n").expect("write");
    let e = refusal(&[bad]);
    assert!(e.contains("not a ptui film file"), "{e}");
}

/// Every byte of a film file is covered: a flipped bit anywhere (header, pixels, map, checksum)
/// is an error, never a film.
#[test]
fn a_corrupt_byte_anywhere_is_detected() {
    let dir = tempfile::tempdir().expect("tempdir");
    let s = settings("cornell", 18, |s| (s.width, s.height) = (8, 6));
    let path = dir.path().join("f.film");
    render_part("cornell", &s, None, &path);
    let bytes = std::fs::read(&path).expect("read");
    assert!(film_file::read(&path).is_ok());
    let bad = dir.path().join("bad.film");
    for at in (0..bytes.len()).step_by(7).chain([bytes.len() - 1]) {
        let mut b = bytes.clone();
        b[at] ^= 0x04;
        std::fs::write(&bad, &b).expect("write");
        assert!(
            film_file::read(&bad).is_err(),
            "byte {at} flipped went unseen"
        );
    }
}

/// A render stopped at a pass and resumed from its film equals the render never stopped, bit
/// for bit: adaptive (stopped before the pilot's end, and after) with the light tracer; a shard
/// stopped half-way too.
#[test]
fn a_resumed_film_equals_an_uninterrupted_render() {
    let dir = tempfile::tempdir().expect("tempdir");
    let s = settings("cornell", 30, |_| {});
    let whole = render_part("cornell", &s, None, &dir.path().join("whole.film"));
    for (first, stop, end) in [(0, 9, 30), (0, 22, 30), (10, 21, 30), (20, 25, 30)] {
        let path = dir.path().join(format!("stop-{first}-{stop}.film"));
        render_part("cornell", &s, Some((first, stop)), &path);
        let (h, film, map) = film_file::read(&path).expect("read");
        let scene = Arc::new(scene::load("cornell").expect("scene"));
        let mut r = Renderer::new(scene, s.clone()).expect("settings");
        let mut stats = h.stats.to_render();
        stats.passes = stop;
        r.resume(film, first, stop, end, stats, map);
        let cancel = AtomicBool::new(false);
        if r.needs_pilot() {
            let map = r.pilot_map(&cancel);
            r.set_map(map);
        }
        r.render(&cancel, |_| true);
        if first == 0 {
            assert!(same_bits(r.film(), whole.film()), "stopped at {stop}");
            assert_eq!(r.stats().samples, whole.stats().samples);
        } else {
            let straight = dir.path().join("straight.film");
            let shard = render_part("cornell", &s, Some((first, end)), &straight);
            assert!(same_bits(r.film(), shard.film()), "{first}..{stop}..{end}");
        }
        assert_eq!(r.sample_map(), whole.sample_map());
    }
}

/// The command line end to end: shards merged by `ptui merge` into a film equal to `ptui
/// render`'s; `--resume` continues a film to `--spp`; SIGTERM writes a final checkpoint that
/// resumes to the uninterrupted film.
#[test]
fn the_command_line_shards_merges_resumes_and_checkpoints_on_sigterm() {
    let dir = tempfile::tempdir().expect("tempdir");
    let d = dir.path();
    let ptui = env!("CARGO_BIN_EXE_ptui");
    let run = |args: &[&str]| {
        let out = std::process::Command::new(ptui)
            .args(args)
            .current_dir(d)
            .output()
            .expect("run ptui");
        assert!(
            out.status.success(),
            "ptui {args:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        String::from_utf8_lossy(&out.stdout).into_owned()
    };
    let common = ["--size", "48x36", "-q"];
    let with = |extra: &[&str]| -> Vec<String> {
        ["render", "cornell"]
            .iter()
            .chain(&common)
            .chain(extra)
            .map(|s| s.to_string())
            .collect()
    };
    fn args(v: &[String]) -> Vec<&str> {
        v.iter().map(String::as_str).collect()
    }
    run(&args(&with(&["--spp", "24", "-o", "single.film"])));
    for i in 0..3 {
        let shard = format!("{i}/3");
        run(&args(&with(&[
            "--spp",
            "24",
            "--shard",
            &shard,
            "-o",
            &format!("p{i}.film"),
        ])));
    }
    let out = run(&["merge", "p2.film", "p0.film", "p1.film", "-o", "m.film"]);
    assert!(out.contains("passes 0..24 of 24"), "{out}");
    run(&[
        "merge",
        "p0.film",
        "p1.film",
        "p2.film",
        "-o",
        "m.exr",
        "--require-complete",
    ]);
    let (_, single, _) = film_file::read(&d.join("single.film")).expect("read");
    let (_, merged, _) = film_file::read(&d.join("m.film")).expect("read");
    assert!(max_rel_diff(&single, &merged) <= 1e-12);
    // Adaptive shards with the pilot rendered once: shard 0 starts from the pilot film's 16
    // passes, shard 1 takes its map from it.
    run(&args(&with(&["--spp", "16", "-o", "pilot.film"])));
    run(&args(&with(&["--spp", "40", "-o", "single40.film"])));
    for i in 0..2 {
        let shard = format!("{i}/2");
        let out = run(&args(&with(&[
            "--spp",
            "40",
            "--shard",
            &shard,
            "--pilot",
            "pilot.film",
            "-o",
            &format!("q{i}.film"),
        ])));
        assert!(!out.contains("adaptive pilot's"), "{out}");
    }
    run(&[
        "merge",
        "q0.film",
        "q1.film",
        "-o",
        "q.film",
        "--require-complete",
    ]);
    let (_, single40, _) = film_file::read(&d.join("single40.film")).expect("read");
    let (h, q, _) = film_file::read(&d.join("q.film")).expect("read");
    assert!(max_rel_diff(&single40, &q) <= 1e-12);
    let (h0, _, _) = film_file::read(&d.join("q0.film")).expect("read");
    let (hp, _, _) = film_file::read(&d.join("pilot.film")).expect("read");
    assert_eq!(
        h.stats.samples,
        h0.stats.samples + {
            let (h1, _, _) = film_file::read(&d.join("q1.film")).expect("read");
            h1.stats.samples
        }
    );
    assert!(
        h0.stats.samples > hp.stats.samples,
        "shard 0 carries the pilot's samples"
    );
    // Resume: 10 passes, then on to 24.
    run(&args(&with(&["--spp", "10", "-o", "r.film"])));
    run(&["render", "--resume", "r.film", "--spp", "24", "-q"]);
    let (h, resumed, _) = film_file::read(&d.join("r.film")).expect("read");
    assert_eq!(h.passes, [[0, 24]]);
    assert!(same_bits(&resumed, &single));
    // SIGTERM: a long render, stopped once its first checkpoint exists.
    let mut child = std::process::Command::new(ptui)
        .args(args(&with(&[
            "--spp",
            "100000",
            "-o",
            "long.film",
            "--checkpoint-every",
            "0.05s",
        ])))
        .current_dir(d)
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("spawn");
    let long = d.join("long.film");
    while !long.exists() {
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    // SAFETY: kill only sends a signal to the child this test started.
    unsafe {
        libc::kill(child.id() as i32, libc::SIGTERM);
    }
    let status = child.wait().expect("wait");
    assert_eq!(status.code(), Some(128 + libc::SIGTERM));
    let (h, _, _) = film_file::read(&long).expect("the final checkpoint is whole");
    let done = h.passes[0][1];
    assert!((1..100000).contains(&done));
    // Resume it to a pass count of its own and compare with a render of that count.
    let target = (done + 3).to_string();
    run(&["render", "--resume", "long.film", "--spp", &target, "-q"]);
    run(&args(&with(&["--spp", &target, "-o", "straight.film"])));
    let (_, a, _) = film_file::read(&long).expect("read");
    let (_, b, _) = film_file::read(&d.join("straight.film")).expect("read");
    assert!(same_bits(&a, &b));
}

/// Maps built from the same pilot are equal; a map read back equals the one written.
#[test]
fn the_adaptive_map_survives_the_film_file() {
    let dir = tempfile::tempdir().expect("tempdir");
    let s = settings("cornell", 20, |_| {});
    let path = dir.path().join("a.film");
    let r = render_part("cornell", &s, None, &path);
    let (h, _, map) = film_file::read(&path).expect("read");
    assert_eq!(h.map_start, Some(16));
    let map: Option<SampleMap> = map;
    assert_eq!(map.as_ref(), r.sample_map());
}

/// The TUI's worker saves its film (`w`) and continues a film (`ptui part.film`): a film saved
/// when a render is done equals `render -o film`'s, and one continued to more passes equals a
/// render of that many, bit for bit.
#[test]
fn the_tui_worker_saves_and_continues_films() {
    use ptui::session::{Command, JobStatus, Request, SessionEvent, SessionHandle};
    use ptui::settings::SettingsOverrides;
    use std::time::Duration;
    let dir = tempfile::tempdir().expect("tempdir");
    let (saved, continued) = (dir.path().join("tui.film"), dir.path().join("more.film"));
    // Run a worker on `layer` (continuing `resume` if given) until done with `spp` passes, then
    // save its film to `to`.
    let run = |layer: SettingsOverrides, resume: Option<&Path>, spp: u32, to: &Path| {
        let (tx, rx) = std::sync::mpsc::channel();
        let sink = Box::new(move |e| {
            let _ = tx.send(e);
        });
        let w = SessionHandle::spawn(sink, Duration::from_millis(20)).expect("worker");
        w.send(Command::Start(Request {
            id: 1,
            scene: "cornell".into(),
            cli: layer,
            form: SettingsOverrides::default(),
            fresh: true,
        }));
        if let Some(p) = resume {
            w.send_after_batch(Command::Resume(p.to_path_buf()));
        }
        loop {
            match rx.recv_timeout(Duration::from_secs(120)).expect("an event") {
                SessionEvent::Progress(s)
                    if s.status == JobStatus::Done && s.stats.complete_passes == spp =>
                {
                    break
                }
                SessionEvent::Failed { message, .. } | SessionEvent::Panicked(message) => {
                    panic!("{message}")
                }
                _ => {}
            }
        }
        w.send_after_batch(Command::SaveFilm(to.to_path_buf()));
        loop {
            if let SessionEvent::FilmSaved(r) =
                rx.recv_timeout(Duration::from_secs(60)).expect("saved")
            {
                assert_eq!(r.expect("the film saved"), to);
                break;
            }
        }
        w.shutdown();
    };
    let layer = SettingsOverrides {
        width: Some(W),
        height: Some(H),
        spp: Some(20),
        threads: Some(2),
        ..Default::default()
    };
    run(layer, None, 20, &saved);
    let straight = render_part(
        "cornell",
        &settings("cornell", 20, |_| {}),
        None,
        &dir.path().join("s20.film"),
    );
    let (h, film, _) = film_file::read(&saved).expect("read");
    assert_eq!((h.passes.clone(), h.cancelled), (vec![[0, 20]], 0));
    assert!(same_bits(&film, straight.film()));
    let mut more = h.overrides();
    more.spp = Some(30);
    run(more, Some(&saved), 30, &continued);
    let straight = render_part(
        "cornell",
        &settings("cornell", 30, |_| {}),
        None,
        &dir.path().join("s30.film"),
    );
    let (_, film, _) = film_file::read(&continued).expect("read");
    assert!(same_bits(&film, straight.film()));
}

/// A film's scene hash covers the files the scene names (a mesh and an environment map): a
/// change to either is another scene, while the same files in another directory (a shard on
/// another machine) are the same scene.
#[test]
fn the_scene_hash_covers_the_mesh_and_the_map_but_not_the_directory() {
    let write_scene = |dir: &Path, map_texel: f32, z: f32| {
        std::fs::write(
            dir.join("tri.obj"),
            format!("v 0 0 {z}\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"),
        )
        .expect("obj");
        let map = image::Rgb32FImage::from_pixel(4, 2, image::Rgb([map_texel; 3]));
        map.save(dir.join("sky.exr")).expect("exr");
        let scene = dir.join("s.toml");
        std::fs::write(
            &scene,
            "[[mesh]]\npath = \"tri.obj\"\n[environment]\nmap = \"sky.exr\"\n",
        )
        .expect("scene");
        film_file::scene_hash(scene.to_str().expect("utf-8 path")).expect("hash")
    };
    let (a, b) = (
        tempfile::tempdir().expect("dir"),
        tempfile::tempdir().expect("dir"),
    );
    let base = write_scene(a.path(), 1.0, 0.0);
    assert_eq!(write_scene(b.path(), 1.0, 0.0), base, "another directory");
    assert_ne!(write_scene(b.path(), 2.0, 0.0), base, "another map");
    assert_ne!(write_scene(b.path(), 1.0, 0.5), base, "another mesh");
}
