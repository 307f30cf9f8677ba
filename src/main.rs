use clap::Parser;
use ptui::cli::{self, Cli, Command};
use ptui::scene::builtin;
use ptui::tui::{self, TuiOptions};

fn main() {
    let cli = Cli::parse();
    let result = match &cli.command {
        Some(Command::Render(args)) => cli::render::run(args),
        Some(Command::Converge(args)) => cli::converge::run(args),
        Some(Command::Check(args)) => cli::check::run(args),
        Some(Command::Bench(args)) => cli::bench::run(args),
        Some(Command::Scenes) => {
            for name in builtin::names() {
                println!("{name}");
            }
            Ok(())
        }
        None => tui::run(TuiOptions {
            scene: cli.scene.clone().unwrap_or_else(|| builtin::DEFAULT.into()),
            cli: cli.settings.overrides(),
            color: cli.tui.color,
            fps: cli.tui.fps,
            halfblock: !cli.tui.spaces,
            bench_log: cli.tui.bench_log.clone(),
        }),
    };
    if let Err(e) = result {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}
