//! The command line as a user meets it: bad flags, bad scene files, unwritable outputs and a full
//! disk all end in one clear message on stderr and a non-zero exit, and never damage an existing
//! output file.

use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn ptui(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_ptui"))
        .args(args)
        .output()
        .expect("run ptui")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A fresh directory for one test.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("ptui-cli-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn files_in(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn bad_flags_are_rejected_with_the_flag_named() {
    for (args, fragment) in [
        (&["render", "--spp", "0"][..], "--spp"),
        (&["render", "--spp", "-3"], "'-3'"),
        (&["render", "--size", "0x5"], "--size"),
        (&["render", "--size", "640"], "WIDTHxHEIGHT"),
        (&["render", "--size", "40000x10"], "between 1 and 32768"),
        (&["render", "--exposure", "nan"], "--exposure"),
        (&["render", "--exposure=-1"], "--exposure"),
        (&["render", "--threads", "0"], "--threads"),
        (&["render", "--integrator", "bdpt"], "--integrator"),
        (&["render", "--frobnicate"], "--frobnicate"),
        (&["check", "--spp", "1"], "--spp"),
    ] {
        let o = ptui(args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(stderr(&o).contains(fragment), "{args:?}: {}", stderr(&o));
    }
}

#[test]
fn out_of_range_flag_values_that_pass_the_parser_are_caught_before_rendering() {
    let o = ptui(&[
        "render",
        "-q",
        "--exposure",
        "1e300",
        "-o",
        "/tmp/never.png",
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("exposure must be"), "{}", stderr(&o));
}

#[test]
fn bad_scene_file_error_names_file_line_and_field() {
    let dir = scratch("scene");
    let scene = dir.join("bad.toml");
    std::fs::write(&scene, "[camera]\nvfov = 200\n").unwrap();
    let o = ptui(&["render", "-q", scene.to_str().unwrap(), "-o", "/tmp/x.png"]);
    assert_eq!(o.status.code(), Some(1));
    let err = stderr(&o);
    assert!(
        err.contains(&format!("{}:2:8: field `camera.vfov`", scene.display())),
        "{err}"
    );
    let o = ptui(&["render", "-q", "no-such-scene"]);
    assert!(
        stderr(&o).contains("no scene file `no-such-scene`"),
        "{}",
        stderr(&o)
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_film_larger_than_memory_is_refused_with_its_size() {
    let o = ptui(&["render", "-q", "--size", "32768x32768", "-o", "/tmp/x.png"]);
    // 64 GiB: more than any machine this runs on has available.
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("needs 64.0 GiB"), "{}", stderr(&o));
}

#[test]
fn unwritable_output_paths_are_named_before_rendering() {
    let dir = scratch("unwritable");
    let file = dir.join("file");
    std::fs::write(&file, "x").unwrap();
    for out in [
        "/nonexistent-ptui-dir/out.png".to_string(),
        format!("{}/out.png", file.display()), // the parent is a file
        dir.display().to_string(),             // a directory
        format!("{}/out.bmp", dir.display()),  // a format we do not write
    ] {
        let started = std::time::Instant::now();
        // 4096 spp of cornell would take minutes: the error must come first.
        let o = ptui(&[
            "render", "-q", "--spp", "4096", "--size", "320x240", "-o", &out,
        ]);
        assert_eq!(o.status.code(), Some(1), "{out}");
        assert!(stderr(&o).contains(&out), "{out}: {}", stderr(&o));
        assert!(started.elapsed().as_secs() < 20, "{out}: rendered first");
    }
    assert_eq!(files_in(&dir), ["file"]);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A full disk for real: the child's file size limit (RLIMIT_FSIZE, which binds root too) is
/// below the image's size, with SIGXFSZ ignored so the write fails with EFBIG instead of killing
/// the process. The existing output keeps its old content and no temporary file is left behind,
/// for PNG and for EXR (both encoded straight into the temporary file).
#[test]
fn full_disk_leaves_the_existing_output_intact() {
    for (name, magic) in [
        ("render.png", &b"\x89PNG"[..]),
        ("render.exr", &[0x76, 0x2f, 0x31, 0x01][..]),
    ] {
        let dir = scratch("fulldisk");
        let out = dir.join(name);
        std::fs::write(&out, b"the previous render").unwrap();
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_ptui"));
        cmd.args(["render", "-q", "--spp", "2", "--size", "64x48", "-o"])
            .arg(&out);
        // SAFETY: only async-signal-safe calls (signal, setrlimit) between fork and exec.
        unsafe {
            cmd.pre_exec(|| {
                libc::signal(libc::SIGXFSZ, libc::SIG_IGN);
                let lim = libc::rlimit {
                    rlim_cur: 100,
                    rlim_max: 100,
                };
                if libc::setrlimit(libc::RLIMIT_FSIZE, &lim) != 0 {
                    return Err(std::io::Error::last_os_error());
                }
                Ok(())
            });
        }
        let o = cmd.output().unwrap();
        assert_eq!(o.status.code(), Some(1), "{name}: {}", stderr(&o));
        let err = stderr(&o);
        assert!(
            err.contains(&out.display().to_string()) && err.contains("cannot write"),
            "{name}: {err}"
        );
        assert_eq!(std::fs::read(&out).unwrap(), b"the previous render");
        assert_eq!(files_in(&dir), [name]);
        // Without the limit the same command replaces the file with the image.
        let o = ptui(&[
            "render",
            "-q",
            "--spp",
            "2",
            "--size",
            "64x48",
            "-o",
            out.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{name}: {}", stderr(&o));
        assert!(std::fs::read(&out).unwrap().starts_with(magic), "{name}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}

/// The same through the library: a writer that takes 100 bytes and then reports ENOSPC.
#[test]
fn failing_writer_loses_nothing() {
    struct FullDisk<'a, W: std::io::Write> {
        inner: &'a mut W,
        room: usize,
    }
    impl<W: std::io::Write> std::io::Write for FullDisk<'_, W> {
        fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
            if self.room == 0 {
                return Err(std::io::Error::from_raw_os_error(libc::ENOSPC));
            }
            let n = buf.len().min(self.room);
            self.room -= n;
            self.inner.write(&buf[..n])
        }
        fn flush(&mut self) -> std::io::Result<()> {
            self.inner.flush()
        }
    }
    let dir = scratch("writer");
    let out = dir.join("img.png");
    std::fs::write(&out, b"old").unwrap();
    let err = ptui::io::output::write_atomic_with(&out, &[7u8; 1000], |f, data| {
        ptui::io::output::write_all_to(
            &mut FullDisk {
                inner: f,
                room: 100,
            },
            data,
        )
    })
    .unwrap_err()
    .to_string();
    assert!(err.contains(&out.display().to_string()), "{err}");
    assert!(err.to_lowercase().contains("no space"), "{err}");
    assert_eq!(std::fs::read(&out).unwrap(), b"old");
    assert_eq!(files_in(&dir), ["img.png"]);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn check_prints_a_table_and_fails_on_a_broken_expectation() {
    let o = ptui(&["check", "inside-light", "--spp", "16"]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{out}{}", stderr(&o));
    assert!(out.contains("invalid") && out.contains("inside-light") && out.contains("pass"));

    let dir = scratch("check");
    let wrong = dir.join("wrong.toml");
    let text = ptui::analysis::check::extreme::get("inside-light")
        .unwrap()
        .replace("mean = 0.5", "mean = 0.55");
    std::fs::write(&wrong, text).unwrap();
    let bad = dir.join("bad.toml");
    std::fs::write(&bad, "[check]\nspp = 1\n").unwrap();
    let o = ptui(&["check", wrong.to_str().unwrap(), bad.to_str().unwrap()]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert_eq!(o.status.code(), Some(1), "{out}");
    assert!(out.contains("FAIL"), "{out}");
    assert!(
        out.contains("ERROR") && out.contains("bad.toml:2:7"),
        "{out}"
    );
    assert!(
        stderr(&o).contains("2 of 2 checks failed"),
        "{}",
        stderr(&o)
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
