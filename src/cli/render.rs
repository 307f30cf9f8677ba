//! `ptui render`: headless progressive render with a progress bar and a summary.

use super::RenderArgs;
use crate::analysis::error_map;
use crate::io::film_file::{self, header_of as film_header, FilmHeader};
use crate::io::output;
use crate::io::shard::Shard;
use crate::render::adaptive::{SampleMap, PILOT_PASSES};
use crate::render::Renderer;
use crate::scene::{self, builtin};
use crate::settings::{IntegratorKind, RenderSettings};
use anyhow::Context;
use indicatif::{ProgressBar, ProgressStyle};
use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Arc;

pub fn run(args: &RenderArgs) -> anyhow::Result<()> {
    let shard = match (args.shard, args.shard_from_env) {
        (Some(s), _) => Some(s),
        (None, true) => Some(
            Shard::from_env(args.shards, |k| std::env::var(k).ok())
                .map_err(|e| anyhow::anyhow!("--shard-from-env: {e}"))?,
        ),
        (None, false) => None,
    };
    let resumed = match &args.resume {
        Some(path) => Some(film_file::read(path)?),
        None => None,
    };
    let spec = match (&args.scene, &resumed) {
        (Some(s), _) => s.clone(),
        (None, Some((h, _, _))) => h.scene.clone(),
        (None, None) => builtin::DEFAULT.to_string(),
    };
    let options = scene::BuildOptions {
        accel: args.accel,
        ..Default::default()
    };
    let scene = Arc::new(super::scene_progress::load(&spec, &options, args.quiet)?);
    let output_path = match (&args.output, &args.resume) {
        (Some(o), _) => o.clone(),
        (None, Some(r)) => r.clone(),
        (None, None) => PathBuf::from("render.png"),
    };
    let to_film = film_file::is_film_path(&output_path);
    let checkpoint = args
        .checkpoint
        .clone()
        .or_else(|| to_film.then(|| output_path.clone()));
    // A film names its scene by path and hash, to be resumed or merged later; a render that
    // reads or writes none needs neither (and a scene read from a pipe has no path to name).
    let films = resumed.is_some() || args.pilot.is_some() || checkpoint.is_some();
    let hash = if films {
        film_file::scene_hash(&spec).map_err(|e| anyhow::anyhow!("scene hash: {e}"))?
    } else {
        String::new()
    };
    let overrides = args.settings.overrides();
    let mut settings = RenderSettings::resolve(&scene.render, &overrides, None);
    if let Some((h, _, _)) = &resumed {
        settings = resume_settings(args, h, &hash, settings)?;
    }
    if args.checkpoint_every.is_some() && checkpoint.is_none() {
        anyhow::bail!(
            "--checkpoint-every needs a film to write: --checkpoint FILE or -o FILE.film"
        );
    }
    if let Some(c) = &checkpoint {
        if !film_file::is_film_path(c) {
            anyhow::bail!(
                "--checkpoint {}: a checkpoint is a film file (.film)",
                c.display()
            );
        }
    }
    if shard.is_some() {
        if !to_film {
            anyhow::bail!(
                "a shard is merged from its film: give -o PART.film (not {})",
                output_path.display()
            );
        }
        if settings.target_error.is_some() {
            anyhow::bail!(
                "--target-error stops on the whole image's error, which no shard sees: render \
                 shards by --spp"
            );
        }
    }
    // Fail on a bad output path before spending minutes rendering.
    for path in [Some(&output_path), checkpoint.as_ref()]
        .into_iter()
        .flatten()
    {
        if film_file::is_film_path(path) {
            check_dir_writable(path, "a film")?;
        } else {
            output::check_writable(path)?;
        }
    }
    if let Some(path) = &args.error_map {
        error_map::check_format(path)?;
        check_dir_writable(path, "the error map")?;
        if settings.spp < 2 {
            return Err(error_map::ErrorMapError::TooFewSamples.into());
        }
    }
    let mut renderer = Renderer::new(scene.clone(), settings.clone())?;
    let cancel = AtomicBool::new(false);
    if let Some(s) = shard {
        let (a, b) = s.passes(settings.spp);
        renderer.set_range(a, b);
    }
    let mut shard_text = shard.map(|s| s.to_string());
    if let Some((h, film, map)) = resumed {
        let (first, next) = match h.passes.as_slice() {
            [] => (0, 0),
            [r] => (r[0], r[1]),
            _ => anyhow::bail!(
                "{}: holds passes {} with gaps between them: only a film of one range resumes",
                args.resume.as_deref().unwrap_or(Path::new("")).display(),
                h.passes_text()
            ),
        };
        let until = if args.settings.spp.is_some() {
            settings.spp
        } else {
            h.until
        };
        let mut stats = h.stats.to_render();
        stats.passes = next;
        renderer.resume(film, first, next, until, stats, map);
        shard_text = h.shard.clone();
    }
    // A shard from pass 0 given --pilot starts from the pilot film's passes instead of
    // rendering them again (with --pilot, the pilot is rendered once in all).
    if let (Some(path), None, (0, end)) = (&args.pilot, &args.resume, renderer.pass_range()) {
        if shard.is_some() {
            let (h, film, map) = film_file::read(path)?;
            if let Err(e) = FilmHeader::new(&spec, &hash, &settings).same_render(&h) {
                anyhow::bail!("--pilot {}: not a film of this render: {e}", path.display());
            }
            if let [[0, next]] = h.passes[..] {
                if next <= end && h.cancelled == 0 {
                    let mut stats = h.stats.to_render();
                    stats.passes = next;
                    renderer.resume(film, 0, next, end, stats, map);
                }
            }
        }
    }
    let pilot_started = std::time::Instant::now();
    let mut pilot_seconds = None;
    let head = FilmHeader {
        shard: shard_text,
        ..FilmHeader::new(&spec, &hash, &settings)
    };
    if renderer.needs_pilot() {
        let map = match &args.pilot {
            Some(path) => Some(pilot_map(path, &head)?),
            None => {
                let map = renderer.pilot_map(&cancel);
                pilot_seconds = Some(pilot_started.elapsed().as_secs_f64());
                map
            }
        };
        renderer.set_map(map);
    }

    // SIGTERM, SIGINT, SIGHUP: finish the batch, write the checkpoint, exit; a second signal
    // exits at once.
    let signal = Arc::new(AtomicUsize::new(0));
    if checkpoint.is_some() {
        let again = Arc::new(AtomicBool::new(false));
        for sig in [SIGTERM, SIGINT, SIGHUP] {
            signal_hook::flag::register_conditional_shutdown(sig, 128 + sig, again.clone())?;
            signal_hook::flag::register(sig, again.clone())?;
            signal_hook::flag::register_usize(sig, signal.clone(), sig as usize)?;
        }
    }

    let (first, end) = renderer.pass_range();
    let bar = if args.quiet {
        ProgressBar::hidden()
    } else {
        ProgressBar::new(end.saturating_sub(first) as u64)
    };
    bar.set_style(
        ProgressStyle::with_template("{bar:40} {pos}/{len} spp  {elapsed} (eta {eta})  {msg}")
            .context("progress bar template")?,
    );
    let mut last_checkpoint = std::time::Instant::now();
    renderer.render(&cancel, |r| {
        bar.set_position(r.stats().complete_passes.saturating_sub(first) as u64);
        bar.set_message(format!(
            "{:.2} M samples/s",
            r.stats().samples_per_second() / 1e6
        ));
        if signal.load(Ordering::Relaxed) != 0 {
            return false;
        }
        if let (Some(every), Some(path)) = (args.checkpoint_every, &checkpoint) {
            if last_checkpoint.elapsed() >= every {
                if let Err(e) =
                    film_file::write(path, &film_header(r, &head), r.film(), r.sample_map())
                {
                    bar.println(format!("warning: checkpoint not written: {e}"));
                }
                last_checkpoint = std::time::Instant::now();
            }
        }
        true
    });
    bar.finish_and_clear();

    let sig = signal.load(Ordering::Relaxed);
    if sig != 0 {
        let path = checkpoint.as_deref().unwrap_or(Path::new(""));
        let header = film_header(&renderer, &head);
        let written = film_file::write(path, &header, renderer.film(), renderer.sample_map());
        // Over a dropped SSH session stderr may be gone: a failed message must not panic.
        let mut err = std::io::stderr();
        let _ = match written {
            Ok(()) => writeln!(
                err,
                "stopped by signal {sig}: wrote {} (passes {}); continue with \
                 `ptui render --resume {}`",
                path.display(),
                header.passes_text(),
                path.display()
            ),
            Err(e) => writeln!(err, "stopped by signal {sig}: checkpoint failed: {e}"),
        };
        std::process::exit(128 + sig as i32);
    }

    if to_film {
        let header = film_header(&renderer, &head);
        film_file::write(
            &output_path,
            &header,
            renderer.film(),
            renderer.sample_map(),
        )?;
    } else {
        if let Some(c) = &checkpoint {
            let header = film_header(&renderer, &head);
            film_file::write(c, &header, renderer.film(), renderer.sample_map())?;
        }
        output::save_film(
            &output_path,
            renderer.film(),
            settings.exposure,
            settings.tonemap,
        )?;
    }
    print!("{}", summary(&renderer));
    if let Some(s) = &head.shard {
        println!(
            "shard {s}: passes {first}..{end} of {}{}",
            settings.spp,
            pilot_seconds.map_or_else(String::new, |t| format!(
                ", after the adaptive pilot's {PILOT_PASSES} passes ({t:.2} s)"
            ))
        );
    }
    println!("wrote {}", output_path.display());
    if let Some(path) = &args.error_map {
        let scale = error_map::save(path, renderer.film())?;
        println!("wrote error map {} ({scale})", path.display());
    }
    Ok(())
}

/// The adaptive map of the render `head` describes, from a film of it (any spp) holding its
/// pilot passes: the map the film stores, or the one built from its passes 0..16.
fn pilot_map(path: &Path, head: &FilmHeader) -> anyhow::Result<SampleMap> {
    let (h, film, map) = film_file::read(path)?;
    if let Err(e) = head.same_render(&h) {
        anyhow::bail!("--pilot {}: not a film of this render: {e}", path.display());
    }
    match (map, h.passes.first()) {
        (Some(m), _) => Ok(m),
        (None, Some(r)) if r[0] == 0 && r[1] == PILOT_PASSES => {
            Ok(SampleMap::build(&film, PILOT_PASSES))
        }
        _ => anyhow::bail!(
            "--pilot {}: holds passes {}, the pilot is passes 0..{PILOT_PASSES} (render it \
             with --spp {PILOT_PASSES})",
            path.display(),
            h.passes_text()
        ),
    }
}

/// Settings of a resumed film: the film's, with only --spp and --threads from the command line
/// (a flag changing the image is refused, naming it), after checking the scene is the film's.
fn resume_settings(
    args: &RenderArgs,
    h: &FilmHeader,
    hash: &str,
    mut s: RenderSettings,
) -> anyhow::Result<RenderSettings> {
    let film = args.resume.as_deref().unwrap_or(Path::new("")).display();
    if h.scene_hash != hash {
        anyhow::bail!(
            "{film}: rendered from another scene: scene_hash is {} there, {hash} for {}",
            h.scene_hash,
            args.scene.as_deref().unwrap_or(&h.scene)
        );
    }
    if h.ptui_version != env!("CARGO_PKG_VERSION") {
        anyhow::bail!(
            "{film}: ptui_version is {} there, {} here: resume with the version that rendered it",
            h.ptui_version,
            env!("CARGO_PKG_VERSION")
        );
    }
    let o = args.settings.overrides();
    let clash = |field: &str, given: bool| -> anyhow::Result<()> {
        if given {
            anyhow::bail!("{film}: --{field} cannot change on resume (the film's settings hold)");
        }
        Ok(())
    };
    clash(
        "size",
        o.width.is_some_and(|w| w != h.width) || o.height.is_some_and(|v| v != h.height),
    )?;
    clash("seed", o.seed.is_some_and(|v| v != h.seed))?;
    clash("sampler", o.sampler.is_some_and(|v| v != h.sampler))?;
    clash(
        "integrator",
        o.integrator.is_some_and(|v| v != h.integrator),
    )?;
    clash("caustics", o.caustics.is_some_and(|v| v != h.caustics))?;
    clash(
        "max-depth",
        o.max_depth.is_some() && o.max_depth != h.max_depth,
    )?;
    clash("adaptive", o.adaptive.is_some_and(|v| v != h.adaptive))?;
    clash(
        "target-error",
        o.target_error.is_some() && h.shard.is_some(),
    )?;
    (s.width, s.height, s.seed, s.sampler) = (h.width, h.height, h.seed, h.sampler);
    (s.integrator, s.caustics, s.max_depth, s.adaptive) =
        (h.integrator, h.caustics, h.max_depth, h.adaptive);
    if o.exposure.is_none() {
        s.exposure = h.exposure;
    }
    if o.tonemap.is_none() {
        s.tonemap = h.tonemap;
    }
    if s.painterly.to_string() != h.painterly {
        anyhow::bail!(
            "{film}: painterly is {} there, {} here",
            h.painterly,
            s.painterly
        );
    }
    let end = h.passes.last().map_or(0, |r| r[1]);
    match args.settings.spp {
        Some(n) if h.shard.is_some() => anyhow::bail!(
            "{film}: shard {} ends at pass {}: --spp cannot move a shard's end (merge the \
             shards, then resume the merged film with --spp {n})",
            h.shard.as_deref().unwrap_or(""),
            h.until
        ),
        Some(n) if n < end => anyhow::bail!(
            "{film}: already holds passes {}: --spp {n} is fewer",
            h.passes_text()
        ),
        Some(n) => s.spp = n,
        None => s.spp = h.spp,
    }
    Ok(s)
}

/// A film's directory accepts a new file (probed as a save would write it).
/// Fail before rendering if `what` cannot be written at `path` (probed with a file beside it).
fn check_dir_writable(path: &Path, what: &str) -> anyhow::Result<()> {
    if path.is_dir() {
        anyhow::bail!("{}: is a directory", path.display());
    }
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let probe = dir.join(format!(".ptui-probe.{}.tmp", std::process::id()));
    std::fs::File::create(&probe)
        .and_then(|_| std::fs::remove_file(&probe))
        .map_err(|e| {
            anyhow::anyhow!(
                "{}: cannot write {what} there: {}",
                path.display(),
                crate::input::os_reason(&e)
            )
        })
}

/// The end-of-render report: what was rendered, how fast, and what the scene build chose.
pub fn summary(r: &Renderer) -> String {
    let s = &r.settings;
    let st = r.stats();
    let err = r.error_estimate();
    format!(
        "{name}: {w}x{h}, {spp}, {integ} integrator, {lens}, seed {seed}, {threads} threads, \
         {code} code\n\
         time {time:.2} s (scene build {build:.1} ms), {rate:.2} M samples/s, {rays:.1} M rays, \
         invalid samples {invalid}\n\
         {report}; caustics: {caustics}{light_paths}\n\
         sampling: {sampling}\n\
         estimated error: {err}\n\
         {stop}\n",
        name = r.scene.name,
        w = s.width,
        h = s.height,
        spp = spp_text(r),
        integ = match s.integrator {
            IntegratorKind::Painterly => format!("painterly ({})", s.painterly),
            kind => kind.name().to_string(),
        },
        lens = r
            .scene
            .camera
            .with_lens_settings(s.aperture, s.focus_distance)
            .lens_text(),
        seed = s.seed,
        threads = r.threads(),
        code = crate::cpu::ShadingCode::detect().name(),
        time = st.elapsed.as_secs_f64(),
        build = r.scene.report.build_time.as_secs_f64() * 1e3,
        rate = st.samples_per_second() / 1e6,
        rays = st.rays as f64 / 1e6,
        sampling = r.sampling_note(),
        invalid = st.invalid,
        report = r.scene.report,
        caustics = r.caustics_note(),
        light_paths = if st.light_paths > 0 {
            format!(
                ", {:.1} M light paths, {:.1}% of all rays",
                st.light_paths as f64 / 1e6,
                100.0 * st.light_rays as f64 / st.rays.max(1) as f64
            )
        } else {
            String::new()
        },
        stop = stop_reason(r),
    )
}

/// Passes, and with adaptive sampling the samples per pixel they came to on average.
pub fn spp_text(r: &Renderer) -> String {
    let passes = r.stats().complete_passes;
    match r.sample_map() {
        Some(_) => format!("{passes} spp ({:.1} per pixel on average)", r.mean_spp()),
        None => format!("{passes} spp"),
    }
}

/// Why the render ended, in the words the summary uses.
pub fn stop_reason(r: &Renderer) -> String {
    let spp = spp_text(r);
    match r.settings.target_error {
        Some(e) if r.target_error_reached() => {
            format!("stopped at target error {e} after {spp}")
        }
        Some(e) if r.stats().complete_passes >= r.settings.spp => {
            format!("target error {e} not reached within the spp limit: stopped after {spp} (raise --spp)")
        }
        Some(e) => format!("target error {e} not reached: stopped after {spp}"),
        None => format!("stopped after {spp}"),
    }
}
