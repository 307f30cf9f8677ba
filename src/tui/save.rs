//! Saving from the TUI: the film's full-resolution mean image (not the preview) to a PNG
//! (tonemapped like `ptui render`) or a linear EXR, named after scene, spp and time, encoded and
//! written atomically on its own thread so the UI never stalls. The image is the render's own,
//! read as it is encoded: a save while passes run holds each pixel as it is when read (the rows
//! a pass has reached have one sample more than the name's spp), a save of a finished or paused
//! render the film exactly.

use super::event::Event;
use crate::io::output;
use crate::session::Snapshot;
use crate::settings::Tonemap;
use std::path::{Path, PathBuf};
use std::sync::mpsc::Sender;
use std::sync::Arc;
use std::time::SystemTime;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SaveKind {
    Png,
    Exr,
}

impl SaveKind {
    pub fn ext(self) -> &'static str {
        match self {
            SaveKind::Png => "png",
            SaveKind::Exr => "exr",
        }
    }
}

/// `<scene stem>-<spp>spp-<YYYYMMDD-HHMMSS>.<ext>` (UTC), in `dir`.
pub fn file_name(dir: &Path, scene: &str, spp: u32, unix_secs: u64, kind: SaveKind) -> PathBuf {
    let stem = Path::new(scene)
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let stem: String = stem
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    let stem = if stem.is_empty() {
        "render".into()
    } else {
        stem
    };
    let (y, mo, d) = civil_from_days((unix_secs / 86_400) as i64);
    let s = unix_secs % 86_400;
    dir.join(format!(
        "{stem}-{spp}spp-{y:04}{mo:02}{d:02}-{:02}{:02}{:02}.{}",
        s / 3600,
        s / 60 % 60,
        s % 60,
        kind.ext()
    ))
}

/// Days since 1970-01-01 to (year, month, day) in the proleptic Gregorian calendar (Howard
/// Hinnant's `civil_from_days`).
fn civil_from_days(z: i64) -> (i64, u32, u32) {
    let z = z + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = (doy - (153 * mp + 2) / 5 + 1) as u32;
    let m = if mp < 10 { mp + 3 } else { mp - 9 } as u32;
    let y = yoe + era * 400 + i64::from(m <= 2);
    (y, m, d)
}

/// Encode and write `snap` on a new thread; the outcome arrives as [`Event::Saved`].
pub fn spawn_save(
    snap: Arc<Snapshot>,
    scene: String,
    kind: SaveKind,
    exposure: f64,
    tonemap: Tonemap,
    events: Sender<Event>,
) {
    let unix = SystemTime::now()
        .duration_since(SystemTime::UNIX_EPOCH)
        .map(|d| d.as_secs())
        .unwrap_or(0);
    let path = file_name(
        Path::new("."),
        &scene,
        snap.stats.complete_passes,
        unix,
        kind,
    );
    let tx = events.clone();
    let spawned = std::thread::Builder::new()
        .name("ptui-save".into())
        .spawn(move || {
            let result = std::panic::catch_unwind(|| {
                output::save_mean(&path, &snap.image, exposure, tonemap)
                    .map_err(|e| e.to_string())?;
                Ok(path.strip_prefix(".").unwrap_or(&path).to_path_buf())
            })
            .unwrap_or_else(|p| Err(super::term::panic_message(&*p)));
            let _ = tx.send(Event::Saved(result));
        });
    if let Err(e) = spawned {
        let _ = events.send(Event::Saved(Err(format!("cannot start saving: {e}"))));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_carry_scene_spp_and_utc_time() {
        // 2026-11-22 01:02:03 UTC.
        let t = 1_795_309_323;
        let p = file_name(Path::new("."), "scenes/my box.toml", 64, t, SaveKind::Png);
        assert_eq!(p, Path::new("./my_box-64spp-20261122-010203.png"));
        assert_eq!(civil_from_days(0), (1970, 1, 1));
        assert_eq!(civil_from_days(11_016), (2000, 2, 29));
    }
}
