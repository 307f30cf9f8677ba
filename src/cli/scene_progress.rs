//! A scene build with a progress bar: large meshes take seconds to read and to build their BVH
//! for, and a silent terminal looks hung. The bar appears only for a build slower than
//! [`SHOW_AFTER`], so small scenes print nothing.

use crate::progress::Progress;
use crate::scene::{self, BuildOptions, Scene, SceneError};
use indicatif::{ProgressBar, ProgressStyle};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

const SHOW_AFTER: Duration = Duration::from_millis(300);
const POLL: Duration = Duration::from_millis(100);

/// `scene::load_with`, with a bar on stderr for its stages unless `quiet`.
pub fn load(spec: &str, options: &BuildOptions, quiet: bool) -> Result<Scene, SceneError> {
    if quiet {
        return scene::load_with(spec, options);
    }
    let progress = Arc::new(Progress::default());
    let options = BuildOptions {
        progress: Some(progress.clone()),
        ..options.clone()
    };
    let done = AtomicBool::new(false);
    std::thread::scope(|s| {
        s.spawn(|| watch(&progress, &done));
        let scene = scene::load_with(spec, &options);
        done.store(true, Ordering::Relaxed);
        scene
    })
}

fn watch(progress: &Progress, done: &AtomicBool) {
    let started = Instant::now();
    let mut bar: Option<(ProgressBar, String)> = None;
    while !done.load(Ordering::Relaxed) {
        std::thread::sleep(POLL);
        if started.elapsed() < SHOW_AFTER {
            continue;
        }
        let (stage, total, count) = progress.snapshot();
        if stage.is_empty() {
            continue;
        }
        if bar.as_ref().is_none_or(|(_, shown)| *shown != stage) {
            if let Some((old, _)) = bar.take() {
                old.finish();
            }
            bar = Some((new_bar(&stage, total), stage));
        }
        if let Some((b, _)) = &bar {
            b.set_position(count);
        }
    }
    if let Some((b, _)) = bar {
        b.finish();
    }
}

/// A bar for a stage with a total, a spinner for one without (generating a mesh).
fn new_bar(stage: &str, total: u64) -> ProgressBar {
    let (bar, template) = if total > 0 {
        (
            ProgressBar::new(total),
            "{bar:40} {percent:>3}%  {elapsed}  {msg}",
        )
    } else {
        (ProgressBar::new_spinner(), "{spinner} {elapsed}  {msg}")
    };
    if let Ok(style) = ProgressStyle::with_template(template) {
        bar.set_style(style);
    }
    bar.set_message(stage.to_string());
    bar
}
