//! `ptui merge PART... -o OUT`: shards of one render into its image (.png, .exr) or film.

use crate::io::film_file;
use crate::io::output;
use crate::io::shard;
use clap::Args;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct MergeArgs {
    /// Film files (`render --shard I/N -o part.film`), in any order.
    #[arg(required = true, value_name = "PART")]
    pub parts: Vec<PathBuf>,
    /// Output: .png tonemapped, .exr linear, .film the merged film.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Fail unless the parts hold every pass of the render.
    #[arg(long)]
    pub require_complete: bool,
}

pub fn run(args: &MergeArgs) -> anyhow::Result<()> {
    let to_film = film_file::is_film_path(&args.output);
    // Fail on a bad output path before reading gigabytes of parts.
    if !to_film {
        output::check_writable(&args.output)?;
    }
    let m = shard::merge(&args.parts, args.require_complete)?;
    let h = &m.header;
    if to_film {
        film_file::write(&args.output, h, &m.film, m.map.as_ref())?;
    } else {
        output::save_film(&args.output, &m.film, h.exposure, h.tonemap)?;
    }
    let err = m.film.error_estimate(h.error_from_halves);
    println!(
        "merged {} parts: {}x{}, passes {} of {}, {:.1} M samples, {:.1} s of rendering",
        m.parts,
        h.width,
        h.height,
        h.passes_text(),
        h.spp,
        h.stats.samples as f64 / 1e6,
        h.stats.seconds
    );
    println!("estimated error: {err}");
    if !m.missing.is_empty() {
        eprintln!(
            "warning: passes {} are missing (a shard not rendered or not given): the image \
             has {} of {} passes; --require-complete makes this an error",
            shard::ranges_text(&m.missing),
            h.pass_count(),
            h.spp
        );
    }
    println!("wrote {}", args.output.display());
    Ok(())
}
