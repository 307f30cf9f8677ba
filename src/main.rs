use clap::Parser;
use ptui::cli::{self, Cli, Command, RenderArgs};
use ptui::scene::builtin;

fn main() {
    let cli = Cli::parse();
    let result = match &cli.command {
        Some(Command::Render(args)) => cli::render::run(args),
        Some(Command::Bench(args)) => cli::bench::run(args),
        Some(Command::Scenes) => {
            for name in builtin::names() {
                println!("{name}");
            }
            Ok(())
        }
        // Until the TUI lands, the main job is the headless render of the default scene.
        None => cli::render::run(&RenderArgs {
            scene: cli.scene.clone(),
            settings: cli.settings.clone(),
            output: "render.png".into(),
            quiet: false,
            accel: None,
        }),
    };
    if let Err(e) = result {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}
