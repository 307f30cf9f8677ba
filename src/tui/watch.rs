//! Watching the files a scene reads (the scene file, its meshes, its map) for changes on disk:
//! a thread compares each file's modification time, size and inode with what it saw before,
//! every [`POLL`], and reports the files that differ on the UI's channel.
//!
//! Polling rather than inotify: a handful of `stat` calls a tenth of a second cost nothing, and
//! it sees every way an editor saves (in place, or a new file renamed over the old one, which
//! an inotify watch on the old file would miss) on every platform.

use super::event::Event;
use std::path::PathBuf;
use std::sync::mpsc::Sender;
use std::sync::{Arc, Mutex};
use std::time::{Duration, SystemTime};

/// How often the files are looked at: a change is seen within this (the 0.5 s for the
/// reload, scene build included).
pub const POLL: Duration = Duration::from_millis(100);

/// What a file looks like from outside: None when it cannot be read.
#[derive(Clone, Debug, PartialEq)]
struct Stamp(Option<(SystemTime, u64, u64)>);

fn stamp(path: &PathBuf) -> Stamp {
    Stamp(std::fs::metadata(path).ok().map(|m| {
        #[cfg(unix)]
        let inode = std::os::unix::fs::MetadataExt::ino(&m);
        #[cfg(not(unix))]
        let inode = 0;
        (
            m.modified().unwrap_or(SystemTime::UNIX_EPOCH),
            m.len(),
            inode,
        )
    }))
}

/// The files watched and how each looked when last seen.
#[derive(Default)]
struct Watched {
    files: Vec<(PathBuf, Stamp)>,
}

impl Watched {
    /// Watch `files` from now on (a file watched already keeps what it was last seen as, so a
    /// change made while the list was replaced is not missed).
    fn set(&mut self, files: &[PathBuf]) {
        let old = std::mem::take(&mut self.files);
        self.files = files
            .iter()
            .map(|f| {
                let seen = old
                    .iter()
                    .find(|(p, _)| p == f)
                    .map_or_else(|| stamp(f), |(_, s)| s.clone());
                (f.clone(), seen)
            })
            .collect();
    }

    /// The files that changed since last seen.
    fn changed(&mut self) -> Vec<PathBuf> {
        let mut out = Vec::new();
        for (path, seen) in &mut self.files {
            let now = stamp(path);
            if now != *seen {
                *seen = now;
                out.push(path.clone());
            }
        }
        out
    }
}

/// The UI's handle on the watcher thread.
pub struct Watcher {
    watched: Arc<Mutex<Watched>>,
    files: Vec<PathBuf>,
}

impl Watcher {
    /// Start watching `files`; changes arrive as [`Event::FilesChanged`].
    pub fn spawn(files: &[PathBuf], tx: Sender<Event>) -> std::io::Result<Watcher> {
        let mut w = Watched::default();
        w.set(files);
        let watched = Arc::new(Mutex::new(w));
        let shared = watched.clone();
        std::thread::Builder::new()
            .name("ptui-watch".into())
            .spawn(move || loop {
                std::thread::sleep(POLL);
                let changed = shared.lock().map(|mut w| w.changed()).unwrap_or_default();
                if !changed.is_empty() && tx.send(Event::FilesChanged(changed)).is_err() {
                    return;
                }
            })?;
        Ok(Watcher {
            watched,
            files: files.to_vec(),
        })
    }

    /// Watch `files` instead (the scene was written elsewhere, or names other files now).
    pub fn set(&mut self, files: &[PathBuf]) {
        if self.files == files {
            return;
        }
        self.files = files.to_vec();
        if let Ok(mut w) = self.watched.lock() {
            w.set(files);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_rewrite_or_a_rename_over_the_file_is_a_change() {
        let dir = tempfile::tempdir().unwrap();
        let (a, b) = (dir.path().join("a.toml"), dir.path().join("b.obj"));
        std::fs::write(&a, "x = 1\n").unwrap();
        let mut w = Watched::default();
        w.set(&[a.clone(), b.clone()]);
        assert!(w.changed().is_empty());
        // Same size, same second: the inode of a file renamed over it differs.
        let tmp = dir.path().join("a.tmp");
        std::fs::write(&tmp, "x = 2\n").unwrap();
        std::fs::rename(&tmp, &a).unwrap();
        assert_eq!(w.changed(), vec![a.clone()]);
        assert!(w.changed().is_empty(), "seen once");
        // A file that appears, one that goes.
        std::fs::write(&b, "v 0 0 0\n").unwrap();
        std::fs::remove_file(&a).unwrap();
        assert_eq!(w.changed(), vec![a.clone(), b.clone()]);
        // A new list keeps what it knew of the files it still holds.
        std::fs::write(&b, "v 0 0 1 and more\n").unwrap();
        w.set(std::slice::from_ref(&b));
        assert_eq!(w.changed(), vec![b]);
    }
}
