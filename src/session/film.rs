//! The session's film files: writing the current film (the TUI's `w`, and on SIGHUP) and
//! continuing one (`ptui part.film`).

use super::{JobStatus, Worker};
use crate::io::film_file::{self, FilmHeader};
use crate::io::output::write_atomic;
use crate::scene::edit::standalone;
use std::path::Path;
use std::sync::atomic::AtomicBool;

impl Worker {
    /// Write the current film to `path`. A film names its scene (and hashes its files) so that
    /// `ptui FILM` renders the same scene on: when the scene was edited and not written back,
    /// its text as rendered is written first beside the film (`path` with `.toml`, paths to
    /// meshes and maps made absolute), and the film names that file.
    pub(super) fn save_film(&self, path: &Path) -> Result<(), String> {
        let (Some(job), Some(built)) = (&self.job, &self.scene) else {
            return Err("nothing rendered yet".into());
        };
        let spec = if built.edited() {
            let copy = path.with_extension("toml");
            let text = standalone(&built.source.spec, &built.text).map_err(|e| e.to_string())?;
            write_atomic(&copy, text.as_bytes()).map_err(|e| e.to_string())?;
            copy.to_string_lossy().into_owned()
        } else {
            built.source.spec.clone()
        };
        let hash = film_file::scene_hash(&spec)?;
        let head = FilmHeader::new(&spec, &hash, &job.renderer.settings);
        let header = film_file::header_of(&job.renderer, &head);
        film_file::write(
            path,
            &header,
            job.renderer.film(),
            job.renderer.sample_map(),
        )
        .map_err(|e| e.to_string())
    }

    /// Continue the film in `path` in the current job, started with the film's settings.
    pub(super) fn resume_film(&mut self, path: &Path) -> Result<(), String> {
        let (h, film, map) = film_file::read(path).map_err(|e| e.to_string())?;
        let (Some(job), Some(built)) = (&mut self.job, &self.scene) else {
            return Err("no render to continue".into());
        };
        let spec = &built.source.spec;
        let hash = film_file::scene_hash(spec)?;
        let head = FilmHeader::new(spec, &hash, &job.renderer.settings);
        head.same_render(&h)
            .map_err(|e| format!("not a film of this render: {e}"))?;
        let (first, next) = match h.passes.as_slice() {
            [] => (0, 0),
            [r] => (r[0], r[1]),
            _ => return Err(format!("its passes {} have gaps", h.passes_text())),
        };
        let mut stats = h.stats.to_render();
        stats.passes = next;
        job.renderer.resume(film, first, next, h.until, stats, map);
        if h.shard.is_none() {
            job.renderer.set_end(None);
        }
        if job.renderer.needs_pilot() {
            let map = job.renderer.pilot_map(&AtomicBool::new(false));
            job.renderer.set_map(map);
        }
        job.status = JobStatus::Running;
        self.update_status();
        self.snapshot(true);
        Ok(())
    }
}
