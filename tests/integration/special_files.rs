//! Every file ptui reads (a scene, an OBJ mesh, an environment map, a film, a reference image)
//! fed the paths that used to hang it or read it to exhaustion: `/dev/zero`, `/dev/urandom`, a
//! directory and a FIFO nobody writes. Each is refused with one message that names the file and
//! the reason once, well within a deadline (a hang never ends: the deadlines are hang detectors,
//! far above the half second a writerless FIFO is waited for). And what should work does: a scene
//! from a pipe, from standard input, and a FIFO with a writer, relative paths resolved from the
//! current directory.

use crate::common::within;
use std::ffi::CString;
use std::io::Write;
use std::os::unix::ffi::OsStrExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

/// Far above the longest refusal (a FIFO's half-second wait for a writer).
const DEADLINE: Duration = Duration::from_secs(10);

/// A scratch directory holding a FIFO nobody writes, `fifo`.
fn with_fifo(name: &str) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::Builder::new()
        .prefix(&format!("ptui-special-{name}-"))
        .tempdir()
        .expect("temp dir");
    let fifo = dir.path().join("fifo");
    make_fifo(&fifo);
    (dir, fifo)
}

fn make_fifo(path: &Path) {
    let c = CString::new(path.as_os_str().as_bytes()).expect("no NUL");
    // SAFETY: a valid NUL-terminated path.
    let rc = unsafe { libc::mkfifo(c.as_ptr(), 0o600) };
    assert_eq!(rc, 0, "mkfifo {}", path.display());
}

/// The special files, each with the reason its refusal must give.
fn specials(dir: &Path, fifo: &Path) -> Vec<(PathBuf, &'static str)> {
    vec![
        (PathBuf::from("/dev/zero"), "a character device"),
        (PathBuf::from("/dev/urandom"), "a character device"),
        (dir.to_path_buf(), "a directory, not a file"),
        (fifo.to_path_buf(), "a pipe nobody writes to"),
    ]
}

/// `message` names `path` and says `reason` exactly once (an error chain printed with its
/// source's message again said it twice).
fn assert_refused(message: &str, path: &Path, what: &str, reason: &str) {
    let shown = path.display().to_string();
    assert!(message.contains(&shown), "{message}");
    assert!(
        message.contains(&format!("cannot read {what}")),
        "{message}"
    );
    assert_eq!(message.matches(reason).count(), 1, "{message}");
    assert_eq!(message.trim_end().lines().count(), 1, "{message}");
}

/// A scene that names `path` in `field` (the mesh's OBJ or the environment's map).
fn scene_naming(field: &str, path: &Path) -> String {
    let p = path.to_str().expect("UTF-8 path");
    match field {
        "mesh" => format!("[camera]\nposition = [0, 0, 5]\n[[mesh]]\npath = {p:?}\n"),
        _ => format!("[camera]\nposition = [0, 0, 5]\n[environment]\nmap = {p:?}\n"),
    }
}

#[test]
fn every_reader_refuses_devices_directories_and_writerless_fifos() {
    let (dir, fifo) = with_fifo("readers");
    for (path, reason) in specials(dir.path(), &fifo) {
        let started = Instant::now();
        let p = path.clone();
        let messages = within(DEADLINE, &path.display().to_string(), move || {
            let spec = p.to_str().expect("UTF-8").to_string();
            let err = |r: Result<(), String>| r.expect_err("refused");
            [
                (
                    "scene file",
                    err(ptui::scene::load(&spec)
                        .map(|_| ())
                        .map_err(|e| e.to_string())),
                ),
                (
                    "OBJ file",
                    err(ptui::scene::load_str(&scene_naming("mesh", &p), "s.toml")
                        .map(|_| ())
                        .map_err(|e| e.to_string())),
                ),
                (
                    "environment map",
                    err(ptui::scene::load_str(&scene_naming("map", &p), "s.toml")
                        .map(|_| ())
                        .map_err(|e| e.to_string())),
                ),
                (
                    "reference image",
                    err(ptui::analysis::reference::load(&p)
                        .map(|_| ())
                        .map_err(|e| e.to_string())),
                ),
                (
                    "scene file",
                    err(ptui::analysis::check::resolve(&spec, None)
                        .map(|_| ())
                        .map_err(|e| e.to_string())),
                ),
            ]
        });
        for (what, message) in &messages {
            eprintln!("{message}");
            assert_refused(message, &path, what, reason);
        }
        // A film is read as it goes and its length checked first: a regular file only.
        let film = ptui::io::film_file::open(&path).err().expect("refused");
        let film_reason = match reason {
            "a pipe nobody writes to" => "a pipe; this must be a regular file",
            other => other,
        };
        assert_refused(&film.to_string(), &path, "film file", film_reason);
        eprintln!("{}: refused in {:?}", path.display(), started.elapsed());
    }
}

/// A FIFO whose writer comes a moment later, and one whose writer holds it open silently for a
/// while, are read like any file: only a FIFO no writer opens is refused.
#[test]
fn a_fifo_with_a_writer_is_read() {
    let src = "[camera]\nposition = [0, 0, 5]\n[[sphere]]\ncenter = [0, 0, 0]\nradius = 1\n";
    for (name, before, between) in [
        ("late", Duration::from_millis(200), Duration::ZERO),
        ("silent", Duration::ZERO, Duration::from_millis(1200)),
    ] {
        let (_dir, fifo) = with_fifo(name);
        let path = fifo.clone();
        let writer = std::thread::spawn(move || {
            std::thread::sleep(before);
            let mut f = std::fs::OpenOptions::new()
                .write(true)
                .open(&path)
                .expect("open the FIFO for writing");
            std::thread::sleep(between);
            f.write_all(src.as_bytes()).expect("write");
        });
        let spec = fifo.to_str().expect("UTF-8").to_string();
        let scene = within(DEADLINE, name, move || ptui::scene::load(&spec));
        writer.join().expect("writer");
        let scene = scene.unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(scene.prims.len(), 1, "{name}");
    }
}

fn ptui_in(dir: &Path, args: &[&str], stdin: Option<&str>) -> Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_ptui"));
    cmd.args(args)
        .current_dir(dir)
        .stdin(if stdin.is_some() {
            Stdio::piped()
        } else {
            Stdio::null()
        })
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    let mut child = cmd.spawn().expect("run ptui");
    if let Some(text) = stdin {
        let mut pipe = child.stdin.take().expect("stdin");
        pipe.write_all(text.as_bytes()).expect("write stdin");
    }
    let what = format!("ptui {}", args.join(" "));
    within(DEADLINE, &what, move || {
        child.wait_with_output().expect("wait")
    })
}

/// From the command line: one line on stderr, a non-zero exit, for a scene or an output that
/// cannot be used.
#[test]
fn the_command_line_says_what_is_wrong_in_one_line() {
    let (dir, fifo) = with_fifo("cli");
    let mut cases: Vec<(Vec<String>, String)> = specials(dir.path(), &fifo)
        .into_iter()
        .map(|(path, reason)| {
            let p = path.to_str().expect("UTF-8").to_string();
            (
                vec!["render".into(), p, "-o".into(), "x.png".into()],
                reason.into(),
            )
        })
        .collect();
    for (args, reason) in [
        (
            &["render", "cornell", "-o", "/nonexistent/dir/x.png"][..],
            "cannot write: no such file or directory",
        ),
        (
            &["render", "cornell", "-o", "/nonexistent/dir/x.film"],
            "cannot write a film there: no such file or directory",
        ),
        (
            &[
                "render",
                "cornell",
                "--error-map",
                "/nonexistent/e.png",
                "-o",
                "x.png",
            ],
            "cannot write the error map there: no such file or directory",
        ),
    ] {
        cases.push((args.iter().map(|a| a.to_string()).collect(), reason.into()));
    }
    for (args, reason) in cases {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let o = ptui_in(dir.path(), &args, None);
        let err = String::from_utf8_lossy(&o.stderr);
        eprintln!("{args:?}: {err}");
        assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
        assert_eq!(err.matches(reason.as_str()).count(), 1, "{args:?}: {err}");
    }
}

/// `ptui render -` reads the scene from standard input, and its relative mesh path starts at the
/// current directory, as a shell user expects.
#[test]
fn a_scene_from_standard_input_renders_with_paths_from_the_current_directory() {
    let dir = tempfile::tempdir().expect("temp dir");
    std::fs::create_dir(dir.path().join("meshes")).expect("mkdir");
    std::fs::write(
        dir.path().join("meshes/tri.obj"),
        "v -1 -1 0\nv 1 -1 0\nv 0 1 0\nf 1 2 3\n",
    )
    .expect("write OBJ");
    let scene = "[camera]\nposition = [0, 0, 4]\n[render]\nwidth = 8\nheight = 6\nspp = 2\n\
                 [[mesh]]\npath = \"meshes/tri.obj\"\nemission = 1\ntwo_sided = true\n";
    let o = ptui_in(
        dir.path(),
        &["render", "-", "-o", "out.png", "--quiet"],
        Some(scene),
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(dir.path().join("out.png").is_file());
    // Mistakes name standard input.
    let o = ptui_in(dir.path(), &["render", "-"], Some("[camera]\nvfov = -1\n"));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("standard input:2:"), "{err}");
    // A film records its scene's path, which a pipe has not: refused before rendering.
    let o = ptui_in(dir.path(), &["render", "-", "-o", "x.film"], Some(scene));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("a film needs its scene in a file"), "{err}");
}

/// One sample per pixel has no spread to estimate an error from: the summary says so instead of
/// printing an infinite error.
#[test]
fn one_sample_per_pixel_has_no_error_estimate() {
    let dir = tempfile::tempdir().expect("temp dir");
    let o = ptui_in(
        dir.path(),
        &[
            "render", "cornell", "--spp", "1", "--size", "8x6", "-o", "x.png", "--quiet",
        ],
        None,
    );
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(out.contains("estimated error: none yet"), "{out}");
    assert!(!out.contains("inf"), "{out}");
}
