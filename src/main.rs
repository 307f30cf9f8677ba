use clap::Parser;
use ptui::cli::{self, Cli, Command};
use ptui::scene::builtin;
use ptui::tui::{self, TuiOptions};

fn main() {
    pin_mmap_threshold();
    let cli = Cli::parse();
    let result = match &cli.command {
        Some(Command::Render(args)) => cli::render::run(args),
        Some(Command::Converge(args)) => cli::converge::run(args),
        Some(Command::Merge(args)) => cli::merge::run(args),
        Some(Command::Check(args)) => cli::check::run(args),
        Some(Command::Bench(args)) => cli::bench::run(args),
        Some(Command::Scene(args)) => cli::scene_from::run(args),
        Some(Command::Scenes) => {
            for name in builtin::names() {
                println!("{name}");
            }
            Ok(())
        }
        None => tui_film(cli.scene.as_deref()).and_then(|film| {
            let (scene, layer, resume) = match film {
                Some((scene, layer, path)) => (scene, layer, Some(path)),
                None => (
                    cli.scene.clone().unwrap_or_else(|| builtin::DEFAULT.into()),
                    cli.settings.overrides(),
                    None,
                ),
            };
            tui::run(TuiOptions {
                scene,
                cli: layer,
                color: cli.tui.color,
                fps: cli.tui.fps,
                halfblock: !cli.tui.spaces,
                graphics: cli.tui.graphics,
                watch: !cli.tui.no_watch,
                bench_log: cli.tui.bench_log.clone(),
                resume,
            })
        }),
    };
    if let Err(e) = result {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}

/// `ptui part.film`: the film's scene and settings, checked against the scene as it is now.
fn tui_film(
    arg: Option<&str>,
) -> anyhow::Result<
    Option<(
        String,
        ptui::settings::SettingsOverrides,
        std::path::PathBuf,
    )>,
> {
    let Some(path) = arg.map(std::path::Path::new) else {
        return Ok(None);
    };
    if !ptui::io::film_file::is_film_path(path) {
        return Ok(None);
    }
    let h = ptui::io::film_file::open(path)?.header;
    let hash = ptui::io::film_file::scene_hash(&h.scene).map_err(|e| anyhow::anyhow!(e))?;
    if hash != h.scene_hash {
        anyhow::bail!(
            "{}: its scene {} has changed since (scene_hash {} there, {hash} now)",
            path.display(),
            h.scene,
            h.scene_hash
        );
    }
    Ok(Some((h.scene.clone(), h.overrides(), path.to_path_buf())))
}

/// glibc raises its mmap threshold each time a large block is freed (up to 32 MB), and blocks
/// under the raised threshold then come from the heap, where a pass's freed buffers fragment
/// and stay resident: a 1920x1080 render grew from 141 to 162 MB in its first adaptive passes
/// (+80 MB at 3840x2160, past the 600 MB budget). Pinned at glibc's default, large buffers are
/// mapped and unmapped whole: 136 and 139 MB.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
fn pin_mmap_threshold() {
    // SAFETY: mallopt only sets an allocator parameter; called before any other thread exists.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, 128 * 1024);
    }
}

#[cfg(not(all(target_os = "linux", target_env = "gnu")))]
fn pin_mmap_threshold() {}
