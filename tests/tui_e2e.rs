//! End to end: the real `ptui` binary in a real terminal (a detached tmux session on a private
//! socket). Start on a small cornell, wait for progress, change spp in the form, save a PNG,
//! check it has the full film resolution, quit, and check the terminal was restored (cooked
//! mode, main screen, cursor visible).
//!
//! Waits poll the screen with generous deadlines, so a loaded 2-core CI machine only makes the
//! test slower. Without tmux the test is skipped, except under CI (CI=true) where it fails.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

const SESSION: &str = "e2e";

struct Tmux {
    socket: String,
}

impl Tmux {
    fn run(&self, args: &[&str]) -> Output {
        Command::new("tmux")
            .args(["-L", &self.socket, "-f", "/dev/null"])
            .args(args)
            .output()
            .expect("run tmux")
    }

    fn screen(&self) -> String {
        String::from_utf8_lossy(&self.run(&["capture-pane", "-p", "-t", SESSION]).stdout)
            .into_owned()
    }

    fn keys(&self, keys: &[&str]) {
        for k in keys {
            let out = self.run(&["send-keys", "-t", SESSION, k]);
            assert!(out.status.success(), "send-keys {k}: {out:?}");
        }
    }

    /// Type `text` as it is (no key names).
    fn literal(&self, text: &str) {
        let out = self.run(&["send-keys", "-t", SESSION, "-l", text]);
        assert!(out.status.success(), "send-keys -l {text}: {out:?}");
    }

    fn display(&self, format: &str) -> String {
        let out = self.run(&["display-message", "-p", "-t", SESSION, format]);
        String::from_utf8_lossy(&out.stdout).trim().to_string()
    }

    /// Poll the screen until `ok` holds; panic with the last screen after `secs`.
    fn wait_for(&self, what: &str, secs: u64, ok: impl Fn(&str) -> bool) -> String {
        let deadline = Instant::now() + Duration::from_secs(secs);
        loop {
            let screen = self.screen();
            if ok(&screen) {
                return screen;
            }
            if Instant::now() > deadline {
                panic!("timed out waiting for {what}; screen:\n{screen}");
            }
            std::thread::sleep(Duration::from_millis(100));
        }
    }
}

impl Drop for Tmux {
    fn drop(&mut self) {
        let _ = self.run(&["kill-server"]);
    }
}

fn wait_for_file(path: &Path, secs: u64) -> bool {
    let deadline = Instant::now() + Duration::from_secs(secs);
    while Instant::now() < deadline {
        if path.exists() {
            return true;
        }
        std::thread::sleep(Duration::from_millis(100));
    }
    false
}

/// The `N/M spp` of the gauge (the form's `spp` line has no slash).
fn gauge(screen: &str) -> Option<(u32, u32)> {
    screen.lines().find_map(|line| {
        let at = line.find(" spp  ")?;
        let head = &line[..at];
        let start = head
            .char_indices()
            .rev()
            .take_while(|(_, c)| c.is_ascii_digit() || *c == '/')
            .last()?
            .0;
        let (done, target) = head[start..].split_once('/')?;
        Some((done.parse().ok()?, target.parse().ok()?))
    })
}

fn tmux_available() -> bool {
    if Command::new("tmux").arg("-V").output().is_ok() {
        return true;
    }
    assert!(
        std::env::var_os("CI").is_none(),
        "tmux is needed for the end-to-end tests"
    );
    eprintln!("skipping: tmux is not installed");
    false
}

/// A fresh directory and a detached 100x30 tmux session running `script` in it.
fn session(name: &str, script: &str) -> (Tmux, PathBuf) {
    session_sized(name, script, (100, 30))
}

/// [`session`] in a terminal of `size` (columns, rows).
fn session_sized(name: &str, script: &str, size: (u16, u16)) -> (Tmux, PathBuf) {
    let dir = std::env::temp_dir().join(format!("ptui-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let tmux = in_dir(&dir, name, script, size);
    (tmux, dir)
}

/// A detached tmux session of `size` running `script` in `dir`.
fn in_dir(dir: &Path, name: &str, script: &str, size: (u16, u16)) -> Tmux {
    let tmux = Tmux {
        socket: format!("ptui-{name}-{}", std::process::id()),
    };
    let out = tmux.run(&[
        "new-session",
        "-d",
        "-s",
        SESSION,
        "-x",
        &size.0.to_string(),
        "-y",
        &size.1.to_string(),
        "-c",
        dir.to_str().unwrap(),
        script,
    ]);
    assert!(out.status.success(), "tmux new-session: {out:?}");
    tmux
}

/// The terminal is back to normal: cooked mode (as recorded by `stty -a` after ptui exited),
/// main screen, cursor shown.
fn assert_restored(tmux: &Tmux, dir: &Path) {
    assert!(
        wait_for_file(&dir.join("stty.txt"), 60),
        "ptui did not exit; screen:\n{}",
        tmux.screen()
    );
    std::thread::sleep(Duration::from_millis(300));
    let stty = std::fs::read_to_string(dir.join("stty.txt")).unwrap();
    let modes: Vec<&str> = stty.split_whitespace().collect();
    for mode in ["icanon", "echo", "isig"] {
        assert!(modes.contains(&mode), "{mode} not restored: {stty}");
    }
    assert_eq!(
        tmux.display("#{alternate_on}"),
        "0",
        "left the alternate screen"
    );
    assert_eq!(tmux.display("#{cursor_flag}"), "1", "cursor visible again");
}

#[test]
fn sigterm_restores_the_terminal() {
    if !tmux_available() {
        return;
    }
    let bin = env!("CARGO_BIN_EXE_ptui");
    // The inner shell records its pid and becomes ptui, so pid.txt names ptui.
    let script = format!(
        "sh -c 'echo $$ > pid.txt; exec \"{bin}\" cornell --size 32x24 --spp 100000'; \
         echo $? > exit.txt; stty -a > stty.txt; sleep 600"
    );
    let (tmux, dir) = session("sigterm", &script);
    tmux.wait_for("render progress", 120, |s| {
        gauge(s).is_some_and(|(done, _)| done >= 1)
    });
    let pid = std::fs::read_to_string(dir.join("pid.txt")).unwrap();
    let status = Command::new("kill")
        .args(["-TERM", pid.trim()])
        .status()
        .unwrap();
    assert!(status.success());
    assert_restored(&tmux, &dir);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn tui_renders_changes_spp_saves_and_restores_the_terminal() {
    if !tmux_available() {
        return;
    }
    let bin = env!("CARGO_BIN_EXE_ptui");
    // After ptui exits, record the tty's modes and the exit code in the same terminal.
    let script = format!(
        "'{bin}' cornell --size 64x48 --spp 100000 --color 256; echo $? > exit.txt; \
         stty -a > stty.txt; sleep 600"
    );
    let (tmux, dir) = session("e2e", &script);

    // Progress: some passes of the 100000 done.
    tmux.wait_for("render progress", 120, |s| {
        gauge(s).is_some_and(|(done, target)| done >= 1 && target == 100000)
    });

    // spp is the 4th field: select it, clear the edit, type 2, apply. The film goes on to 2
    // samples (or stops at once if it already has more).
    tmux.keys(&["Tab", "Tab", "Tab", "Enter", "C-u", "2", "Enter"]);
    let screen = tmux.wait_for("the render to finish at the new spp", 120, |s| {
        gauge(s).is_some_and(|(done, target)| target == 2 && done >= 2) && s.contains(" done")
    });
    assert!(
        screen.contains("spp        2"),
        "form shows the new spp:\n{screen}"
    );

    tmux.keys(&["s"]);
    let screen = tmux.wait_for("the save", 120, |s| s.contains("saved "));
    let line = screen.lines().find(|l| l.contains("saved ")).unwrap();
    let name = line
        .split("saved ")
        .nth(1)
        .and_then(|r| r.split_whitespace().next())
        .unwrap();
    assert!(
        name.starts_with("cornell-") && name.ends_with(".png"),
        "{name}"
    );
    let png = image::open(dir.join(name)).expect("the saved PNG opens");
    assert_eq!(
        (png.width(), png.height()),
        (64, 48),
        "full film resolution"
    );

    tmux.keys(&["q"]);
    assert_restored(&tmux, &dir);
    let exit = std::fs::read_to_string(dir.join("exit.txt")).unwrap();
    assert_eq!(exit.trim(), "0");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The file the status line says was saved (`saved NAME`).
fn saved_name(screen: &str) -> String {
    let line = screen.lines().find(|l| l.contains("saved ")).unwrap();
    line.split("saved ")
        .nth(1)
        .and_then(|r| r.split_whitespace().next())
        .unwrap()
        .to_string()
}

/// Send each key on its own, a little apart, as typed (a bare Escape followed at once by a
/// letter would read as Alt+letter).
fn typed(tmux: &Tmux, keys: &[&str]) {
    for k in keys {
        tmux.keys(&[k]);
        std::thread::sleep(Duration::from_millis(60));
    }
}

/// The built-in scene's file in the repository.
fn builtin(name: &str) -> String {
    std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("scenes/{name}.toml")),
    )
    .unwrap()
}

/// The lines of `a` and `b` that differ (they have as many lines).
fn changed_lines(a: &str, b: &str) -> Vec<(String, String)> {
    assert_eq!(a.lines().count(), b.lines().count(), "{b}");
    a.lines()
        .zip(b.lines())
        .filter(|(x, y)| x != y)
        .map(|(x, y)| (x.to_string(), y.to_string()))
        .collect()
}

/// Render `args` headless in `dir` to `out`.
fn headless(dir: &Path, args: &[&str], out: &str) {
    let st = Command::new(env!("CARGO_BIN_EXE_ptui"))
        .current_dir(dir)
        .arg("render")
        .args(args)
        .args(["--quiet", "-o", out])
        .status()
        .unwrap();
    assert!(st.success());
}

#[test]
fn camera_moves_and_w_change_the_camera_only_and_the_file_renders_the_same() {
    if !tmux_available() {
        return;
    }
    let bin = env!("CARGO_BIN_EXE_ptui");
    let script = format!("'{bin}' cornell --size 64x48 --spp 6 --seed 3 --color 256; sleep 600");
    let (tmux, dir) = session("camera", &script);
    tmux.wait_for("render progress", 120, |s| {
        gauge(s).is_some_and(|(done, _)| done >= 1)
    });
    typed(&tmux, &["v"]);
    tmux.wait_for("camera mode", 30, |s| s.contains("camera mode"));
    typed(&tmux, &["Left", "Left", "Up", "-", "v", "W"]);
    let screen = tmux.wait_for("the scene written", 60, |s| {
        s.contains("wrote cornell.toml")
    });
    assert!(
        screen.contains("camera.position, camera.direction"),
        "{screen}"
    );
    // Only the camera's position and direction changed; comments and the rest are as they were.
    let written = std::fs::read_to_string(dir.join("cornell.toml")).unwrap();
    let original = builtin("cornell");
    let changed = changed_lines(&original, &written);
    let keys: Vec<&str> = changed
        .iter()
        .map(|(a, _)| a.split(' ').next().unwrap())
        .collect();
    assert_eq!(keys, vec!["position", "direction"], "{changed:?}");
    assert!(written.contains("near = 140                  # rays start 140 units along"));
    // The TUI's render of the moved camera, saved when done, is the image `ptui render` makes of
    // the written file with the same seed and spp, bit for bit.
    tmux.wait_for("the render to finish", 120, |s| {
        gauge(s) == Some((6, 6)) && s.contains(" done")
    });
    typed(&tmux, &["e"]);
    let screen = tmux.wait_for("the save", 60, |s| s.contains("saved "));
    let tui = std::fs::read(dir.join(saved_name(&screen))).unwrap();
    headless(
        &dir,
        &[
            "cornell.toml",
            "--size",
            "64x48",
            "--spp",
            "6",
            "--seed",
            "3",
        ],
        "ref.exr",
    );
    assert!(
        tui == std::fs::read(dir.join("ref.exr")).unwrap(),
        "the images differ"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn picking_the_red_wall_and_setting_it_green_changes_that_one_key() {
    if !tmux_available() {
        return;
    }
    let bin = env!("CARGO_BIN_EXE_ptui");
    let script = format!("'{bin}' cornell-mesh --size 256x256 --spp 100000 --color 256; sleep 600");
    let (tmux, dir) = session("pick", &script);
    tmux.wait_for("render progress", 120, |s| {
        gauge(s).is_some_and(|(done, _)| done >= 1)
    });
    // Zoom in twice and pan to the left edge: the preview's centre is on the red wall.
    typed(
        &tmux,
        &[
            "+", "+", "h", "h", "h", "h", "h", "h", "h", "h", "h", "h", "o",
        ],
    );
    let screen = tmux.wait_for("the pick", 30, |s| s.contains("picked "));
    assert!(screen.contains("picked left (red) (quad[4])"), "{screen}");
    assert!(screen.contains("colour     0.63 0.065 0.05"), "{screen}");
    // The colour is the field after the material.
    typed(&tmux, &["Tab", "Enter", "C-u"]);
    tmux.literal("[0.1, 0.6, 0.1]");
    typed(&tmux, &["Enter"]);
    tmux.wait_for("the new colour", 30, |s| {
        s.contains("colour     0.1 0.6 0.1")
    });
    typed(&tmux, &["W"]);
    let screen = tmux.wait_for("the scene written", 30, |s| s.contains("wrote "));
    assert!(
        screen.contains("wrote cornell-mesh.toml: quad[4].color"),
        "{screen}"
    );
    let written = std::fs::read_to_string(dir.join("cornell-mesh.toml")).unwrap();
    let changed = changed_lines(&builtin("cornell-mesh"), &written);
    assert_eq!(
        changed,
        vec![(
            "color = [0.63, 0.065, 0.05]".to_string(),
            "color = [0.1, 0.6, 0.1]".to_string()
        )]
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_scene_edited_in_another_pane_reloads_and_a_broken_one_keeps_the_image() {
    if !tmux_available() {
        return;
    }
    let bin = env!("CARGO_BIN_EXE_ptui");
    let dir = std::env::temp_dir().join(format!("ptui-watch-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("box.toml");
    let src = builtin("cornell");
    std::fs::write(&file, &src).unwrap();
    let script = format!("'{bin}' box.toml --size 48x36 --spp 100000 --color 256; sleep 600");
    let tmux = in_dir(&dir, "watch", &script, (100, 30));
    tmux.wait_for("render progress", 120, |s| {
        gauge(s).is_some_and(|(done, _)| done >= 1)
    });
    // An editor that writes a new file and renames it over the old one.
    let save = |text: &str| {
        let tmp = dir.join(".box.toml.swp");
        std::fs::write(&tmp, text).unwrap();
        std::fs::rename(&tmp, &file).unwrap();
        Instant::now()
    };
    let at = save(&src.replace("emission = 12", "emission = 20"));
    tmux.wait_for("the reload", 30, |s| s.contains("reloaded box.toml"));
    eprintln!(
        "reloaded {} ms after the save (screen polled every 100 ms)",
        at.elapsed().as_millis()
    );
    // Broken: the loader's message with the file, line and column; the image stays.
    std::fs::write(&file, src.replace("radius = 600", "radius = -600")).unwrap();
    let screen = tmux.wait_for("the error", 30, |s| s.contains("box.toml:69:10: field"));
    assert!(
        screen.contains("`sphere[8].radius`: must be > 0, got -600"),
        "{screen}"
    );
    let blocks = screen.matches('▀').count();
    assert!(
        blocks > 500,
        "the preview stays: {blocks} half-blocks\n{screen}"
    );
    let spp = gauge(&screen).unwrap().0;
    tmux.wait_for("the render to go on", 60, |s| {
        gauge(s).is_some_and(|(done, _)| done > spp)
    });
    // Fixed: rendered again, the error gone.
    save(&src);
    let screen = tmux.wait_for("the fixed file", 30, |s| s.contains("reloaded box.toml"));
    assert!(!screen.contains("must be > 0"), "{screen}");
    drop(tmux);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn sighup_leaves_a_film_that_continues_to_the_uninterrupted_image() {
    if !tmux_available() {
        return;
    }
    let bin = env!("CARGO_BIN_EXE_ptui");
    let args = "cornell --size 32x24 --spp 400 --seed 5";
    let script = format!("sh -c 'echo $$ > pid.txt; exec \"{bin}\" {args} --color 256'");
    let (tmux, dir) = session("hangup", &script);
    // Past the adaptive pilot (16 passes), not done.
    tmux.wait_for("render progress", 120, |s| {
        gauge(s).is_some_and(|(done, _)| done >= 20)
    });
    let pid = std::fs::read_to_string(dir.join("pid.txt")).unwrap();
    // The terminal goes away as a dropped SSH session's does: the pty closes, SIGHUP.
    drop(tmux);
    let proc = PathBuf::from(format!("/proc/{}", pid.trim()));
    let deadline = Instant::now() + Duration::from_secs(60);
    while proc.exists() && Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(100));
    }
    let films: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "film"))
        .collect();
    assert_eq!(films.len(), 1, "{films:?}");
    let name = films[0].file_name().unwrap().to_str().unwrap().to_string();
    assert!(
        name.starts_with("cornell-") && name.contains("spp-"),
        "{name}"
    );
    // `ptui FILM` goes on to 400 spp; its image is that of a render never stopped.
    let script = format!("'{bin}' {name} --color 256; sleep 600");
    let tmux = in_dir(&dir, "resume", &script, (100, 30));
    tmux.wait_for("the render to finish", 120, |s| {
        gauge(s) == Some((400, 400)) && s.contains(" done")
    });
    typed(&tmux, &["e"]);
    let screen = tmux.wait_for("the save", 60, |s| s.contains("saved "));
    let resumed = std::fs::read(dir.join(saved_name(&screen))).unwrap();
    let args: Vec<&str> = args.split(' ').collect();
    headless(&dir, &args, "ref.exr");
    assert!(
        resumed == std::fs::read(dir.join("ref.exr")).unwrap(),
        "the images differ"
    );
    drop(tmux);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Two headless renders at full priority, as other work on the machine: killed when dropped.
struct Load(Vec<std::process::Child>);

impl Load {
    fn start(dir: &Path) -> Load {
        let bin = env!("CARGO_BIN_EXE_ptui");
        Load(
            (0..2)
                .map(|i| {
                    Command::new(bin)
                        .args(["render", "cornell", "--spp", "100000", "--quiet", "-o"])
                        .arg(dir.join(format!("load-{i}.png")))
                        .stdout(std::process::Stdio::null())
                        .stderr(std::process::Stdio::null())
                        .spawn()
                        .expect("start a load")
                })
                .collect(),
        )
    }
}

impl Drop for Load {
    fn drop(&mut self) {
        for c in &mut self.0 {
            let _ = c.kill();
            let _ = c.wait();
        }
    }
}

/// At 20x6 with two renders loading the machine, `q` quits: pressed while ptui starts (it is
/// then read by the graphics probe, which used to drop it, so ptui never quit) and pressed
/// while it renders. Each exit must come within the deadline (a hang never does; the exit
/// itself measured 0.02-0.1 s under this load).
#[test]
fn q_quits_at_20x6_under_load() {
    if !tmux_available() {
        return;
    }
    const DEADLINE: u64 = 10;
    let bin = env!("CARGO_BIN_EXE_ptui");
    let scratch = std::env::temp_dir().join(format!("ptui-load-{}", std::process::id()));
    std::fs::create_dir_all(&scratch).unwrap();
    let _load = Load::start(&scratch);
    // The q is typed before ptui starts: it waits in the terminal until ptui reads it.
    let script = format!("sleep 1; '{bin}'; echo $? > exit.txt; stty -a > stty.txt; sleep 600");
    let (tmux, dir) = session_sized("quit-early", &script, (20, 6));
    tmux.keys(&["q"]);
    assert!(
        wait_for_file(&dir.join("exit.txt"), 1 + DEADLINE),
        "q typed at start: ptui did not quit; screen:\n{}",
        tmux.screen()
    );
    assert_restored(&tmux, &dir);
    let _ = std::fs::remove_dir_all(&dir);

    let script = format!("'{bin}'; echo $? > exit.txt; stty -a > stty.txt; sleep 600");
    let (tmux, dir) = session_sized("quit-late", &script, (20, 6));
    tmux.wait_for("the screen", 120, |s| !s.trim().is_empty());
    std::thread::sleep(Duration::from_secs(1));
    let pressed = Instant::now();
    tmux.keys(&["q"]);
    assert!(
        wait_for_file(&dir.join("exit.txt"), DEADLINE),
        "q while rendering: ptui did not quit; screen:\n{}",
        tmux.screen()
    );
    eprintln!("quit {:?} after q", pressed.elapsed());
    assert_restored(&tmux, &dir);
    let exit = std::fs::read_to_string(dir.join("exit.txt")).unwrap();
    assert_eq!(exit.trim(), "0");
    let _ = std::fs::remove_dir_all(&dir);
    let _ = std::fs::remove_dir_all(&scratch);
}
