//! The film file (`.film`, format "ptui film", version 1): a render's whole film, so that
//! shards rendered on different machines merge into the image of one render, and a stopped
//! render resumes where it stopped. docs/FILM.md describes the layout; in short:
//!
//! ```text
//! "PTUIFILM"  u32 format version  u32 header length  header (TOML, UTF-8)
//! width x height pixel records of 56 bytes (mean f64 x3, M2 f32 x3, count u32,
//!                                            odd-pass mean f32 x3, odd count u32)
//! the adaptive map, one byte per pixel (when the header has `map_start`)
//! CRC-32 of every byte before it (u32)
//! ```
//!
//! All numbers are little-endian. Reading checks the magic, the version, the size the header
//! implies and the checksum, and names the file and the field of anything wrong. Writing goes
//! through a temporary file and a rename, so a film file is whole or absent.

use crate::render::adaptive::SampleMap;
use crate::render::film::{Film, PixelState};
use crate::render::RenderStats;
use crate::sampling::SamplerKind;
use crate::settings::{Caustics, IntegratorKind, RenderSettings, Strategy, Tonemap};
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use std::io::{BufReader, BufWriter, Read, Write};
use std::path::{Path, PathBuf};
use std::time::Duration;

/// The first bytes of every film file.
pub const MAGIC: &[u8; 8] = b"PTUIFILM";

/// The layout version this build writes and reads.
pub const FORMAT_VERSION: u32 = 1;

/// Bytes per pixel record.
pub const RECORD: usize = 56;

/// Largest header accepted (a header is a few hundred bytes; this bounds what a corrupt length
/// makes us allocate).
const MAX_HEADER: u32 = 1 << 20;

#[derive(Debug, thiserror::Error)]
pub enum FilmFileError {
    #[error("{}: {reason}", .path.display())]
    Io { path: PathBuf, reason: String },
    #[error(transparent)]
    Input(#[from] crate::input::InputError),
    #[error("{}: not a ptui film file ({why})", .path.display())]
    NotAFilm { path: PathBuf, why: String },
    #[error("{}: film format version {found}, this ptui reads version {FORMAT_VERSION}", .path.display())]
    Version { path: PathBuf, found: u32 },
    #[error("{}: header: {why}", .path.display())]
    Header { path: PathBuf, why: String },
    #[error("{}: {expected} bytes expected from the header ({width}x{height}{map}), the file has {found}: truncated or corrupt", .path.display())]
    Size {
        path: PathBuf,
        expected: u64,
        found: u64,
        width: u32,
        height: u32,
        map: &'static str,
    },
    #[error("{}: checksum mismatch (stored {stored:08x}, computed {computed:08x}): the file is corrupt", .path.display())]
    Checksum {
        path: PathBuf,
        stored: u32,
        computed: u32,
    },
}

/// Render counters a film carries, summed when films merge.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FilmStats {
    pub samples: u64,
    pub rays: u64,
    pub light_rays: u64,
    pub light_paths: u64,
    pub invalid: u64,
    /// Wall-clock seconds spent in passes (summed over merged parts).
    pub seconds: f64,
}

impl FilmStats {
    pub fn from_render(s: &RenderStats) -> Self {
        FilmStats {
            samples: s.samples,
            rays: s.rays,
            light_rays: s.light_rays,
            light_paths: s.light_paths,
            invalid: s.invalid,
            seconds: s.elapsed.as_secs_f64(),
        }
    }

    /// The counters as the renderer keeps them (passes set by the caller).
    pub fn to_render(self) -> RenderStats {
        RenderStats {
            samples: self.samples,
            rays: self.rays,
            light_rays: self.light_rays,
            light_paths: self.light_paths,
            invalid: self.invalid,
            elapsed: Duration::try_from_secs_f64(self.seconds).unwrap_or_default(),
            ..Default::default()
        }
    }

    pub fn add(&mut self, o: &FilmStats) {
        self.samples += o.samples;
        self.rays += o.rays;
        self.light_rays += o.light_rays;
        self.light_paths += o.light_paths;
        self.invalid += o.invalid;
        self.seconds += o.seconds;
    }
}

/// Everything a film says about itself. The fields [`FilmHeader::identity`] lists must agree
/// for two films to merge; `passes`, `until`, `shard` and `stats` describe this film alone.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FilmHeader {
    /// The ptui version that rendered it (`ptui --version`).
    pub ptui_version: String,
    /// The scene as given on the command line (a file path or a built-in name).
    pub scene: String,
    /// "sha256:" and the SHA-256 of the scene file and every file it references.
    pub scene_hash: String,
    pub width: u32,
    pub height: u32,
    /// Passes of the whole render (`--spp`).
    pub spp: u32,
    pub seed: u64,
    pub sampler: SamplerKind,
    pub integrator: IntegratorKind,
    pub caustics: Caustics,
    /// Absent: `mis` (films written before the setting existed).
    #[serde(default, skip_serializing_if = "is_mis")]
    pub strategy: Strategy,
    /// Longest path in bounces; absent = unlimited.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_depth: Option<u32>,
    pub adaptive: bool,
    /// The painterly integrator's parameters as `ptui render` prints them.
    pub painterly: String,
    /// The lens, where the CLI or the TUI changed the scene's (absent: the scene's camera).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub aperture: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub focus_distance: Option<f64>,
    /// Output settings: not part of the film's data, used when a merge or resume saves an image.
    pub exposure: f64,
    pub tonemap: Tonemap,
    /// The pass ranges [first, end) this film holds, sorted and disjoint.
    pub passes: Vec<[u32; 2]>,
    /// The pass this film's render stops at (its shard's end, or `spp`).
    pub until: u32,
    /// "I/N" for a shard rendered with `--shard I/N`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shard: Option<String>,
    /// Whether the error estimate reads the half-buffers (stratified samples, or an adaptive
    /// map with light-traced caustics; see `Renderer::error_from_halves`).
    pub error_from_halves: bool,
    /// Passes of `passes` that were cancelled part-way (a TUI render paused or changed): their
    /// samples are in the film for the rows they reached. Such a film continues, but does not
    /// merge (its passes are not whole).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub cancelled: u32,
    /// First pass of the adaptive map stored after the pixels, if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub map_start: Option<u32>,
    pub stats: FilmStats,
}

/// A lens setting as the identity compares it: "scene" where the scene's camera holds.
fn lens_text(v: Option<f64>) -> String {
    v.map_or_else(|| "scene".into(), |v| v.to_string())
}

impl FilmHeader {
    /// A header for a render of `scene` (its spec and hash) with `settings`.
    pub fn new(scene: &str, scene_hash: &str, settings: &RenderSettings) -> Self {
        FilmHeader {
            ptui_version: env!("CARGO_PKG_VERSION").to_string(),
            scene: scene.to_string(),
            scene_hash: scene_hash.to_string(),
            width: settings.width,
            height: settings.height,
            spp: settings.spp,
            seed: settings.seed,
            sampler: settings.sampler,
            integrator: settings.integrator,
            caustics: settings.caustics,
            strategy: settings.strategy,
            max_depth: settings.max_depth,
            adaptive: settings.adaptive,
            painterly: settings.painterly.to_string(),
            aperture: settings.aperture,
            focus_distance: settings.focus_distance,
            exposure: settings.exposure,
            tonemap: settings.tonemap,
            passes: Vec::new(),
            until: settings.spp,
            shard: None,
            error_from_halves: settings.sampler.is_stratified(),
            cancelled: 0,
            map_start: None,
            stats: FilmStats::default(),
        }
    }

    /// The fields that must agree for films to merge, as (name, value).
    pub fn identity(&self) -> Vec<(&'static str, String)> {
        vec![
            ("ptui_version", self.ptui_version.clone()),
            ("scene_hash", self.scene_hash.clone()),
            ("width", self.width.to_string()),
            ("height", self.height.to_string()),
            ("spp", self.spp.to_string()),
            ("seed", self.seed.to_string()),
            ("sampler", self.sampler.name().to_string()),
            ("integrator", self.integrator.name().to_string()),
            ("caustics", self.caustics.name().to_string()),
            ("strategy", self.strategy.name().to_string()),
            (
                "max_depth",
                self.max_depth
                    .map_or_else(|| "unlimited".into(), |d| d.to_string()),
            ),
            ("adaptive", self.adaptive.to_string()),
            ("painterly", self.painterly.clone()),
            ("aperture", lens_text(self.aperture)),
            ("focus_distance", lens_text(self.focus_distance)),
        ]
    }

    /// Passes the film holds.
    pub fn pass_count(&self) -> u64 {
        self.passes.iter().map(|r| (r[1] - r[0]) as u64).sum()
    }

    /// The passes as text: "0..128, 256..384".
    pub fn passes_text(&self) -> String {
        if self.passes.is_empty() {
            return "none".into();
        }
        self.passes
            .iter()
            .map(|r| format!("{}..{}", r[0], r[1]))
            .collect::<Vec<_>>()
            .join(", ")
    }

    fn pixels(&self) -> u64 {
        self.width as u64 * self.height as u64
    }

    /// The file's size this header implies.
    pub fn file_size(&self, header_len: usize) -> u64 {
        let map = if self.map_start.is_some() {
            self.pixels()
        } else {
            0
        };
        16 + header_len as u64 + self.pixels() * RECORD as u64 + map + 4
    }

    fn check(&self, path: &Path) -> Result<(), FilmFileError> {
        let bad = |why: String| FilmFileError::Header {
            path: path.to_path_buf(),
            why,
        };
        let max = crate::settings::MAX_DIMENSION;
        if self.width == 0 || self.height == 0 || self.width > max || self.height > max {
            return Err(bad(format!(
                "width and height must be 1..={max}, found {}x{}",
                self.width, self.height
            )));
        }
        let mut prev = 0;
        for r in &self.passes {
            if r[0] >= r[1] || r[0] < prev {
                return Err(bad(format!(
                    "passes must be sorted, disjoint, non-empty ranges, found {}",
                    self.passes_text()
                )));
            }
            prev = r[1];
        }
        if self.until < prev {
            return Err(bad(format!(
                "until = {} is before the end of passes {}",
                self.until,
                self.passes_text()
            )));
        }
        Ok(())
    }
}

/// The header of `r`'s film now: `head`'s render fields with the film's passes, adaptive
/// flags and counters.
pub fn header_of(r: &crate::render::Renderer, head: &FilmHeader) -> FilmHeader {
    let (first, end) = r.pass_range();
    // Passes started: those complete, and those cancelled part-way (their numbers are used).
    let done = r.stats().passes;
    FilmHeader {
        passes: if done > first {
            vec![[first, done]]
        } else {
            Vec::new()
        },
        until: end,
        error_from_halves: r.error_from_halves(),
        cancelled: r.stats().passes - r.stats().complete_passes,
        stats: FilmStats::from_render(&r.stats()),
        ..head.clone()
    }
}

fn is_zero(v: &u32) -> bool {
    *v == 0
}

fn is_mis(s: &Strategy) -> bool {
    *s == Strategy::Mis
}

impl FilmHeader {
    /// The settings layer that renders this film's image (for the TUI's request).
    pub fn overrides(&self) -> crate::settings::SettingsOverrides {
        crate::settings::SettingsOverrides {
            width: Some(self.width),
            height: Some(self.height),
            spp: Some(self.spp),
            seed: Some(self.seed),
            sampler: Some(self.sampler),
            integrator: Some(self.integrator),
            caustics: Some(self.caustics),
            strategy: Some(self.strategy),
            max_depth: self.max_depth,
            exposure: Some(self.exposure),
            tonemap: Some(self.tonemap),
            adaptive: Some(self.adaptive),
            aperture: self.aperture,
            focus_distance: self.focus_distance,
            ..Default::default()
        }
    }

    /// Whether `other` is a film of the same render (any spp): the field that differs, with
    /// both values, if not.
    pub fn same_render(&self, other: &FilmHeader) -> Result<(), String> {
        for ((field, a), (_, b)) in self.identity().iter().zip(other.identity()) {
            if *field != "spp" && *a != b {
                return Err(format!("{field} is {b} there, {a} here"));
            }
        }
        Ok(())
    }
}

/// The hash of a scene: SHA-256 over the scene's source, every mesh file and the environment
/// map it names (each preceded by its path as written and its length), so a changed OBJ or
/// map beside an unchanged scene file is another scene. The files those read in turn (an
/// OBJ's .mtl and textures, a glTF's buffers and images) are not in it (docs/FILM.md). `spec` is what `ptui render` takes: a file, else a built-in.
pub fn scene_hash(spec: &str) -> Result<String, String> {
    use crate::scene::load::{scene_text, SceneText};
    let path = Path::new(spec);
    let (src, base) = if path.is_file() && crate::scene::model::is_model(path) {
        let name = path
            .file_name()
            .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
        let src = crate::scene::model::scene_text(path, &name)?;
        (src, path.parent().map(Path::to_path_buf))
    } else {
        match scene_text(spec).map_err(|e| e.to_string())? {
            // A film names its scene to load it again: a pipe cannot be read twice.
            SceneText::Read { base_dir: None, .. } => {
                return Err(format!(
                    "{spec}: a film needs its scene in a file (it is read again to resume or \
                     merge), not a pipe or standard input"
                ))
            }
            SceneText::Read {
                text,
                base_dir: Some(base),
            } => (text, Some(base)),
            SceneText::Builtin(src) => (src.to_string(), None),
        }
    };
    let mut h = Sha256::new();
    h.update((src.len() as u64).to_le_bytes());
    h.update(src.as_bytes());
    let desc = crate::scene::load::parse(&src, spec).map_err(|e| e.to_string())?;
    // The files as the scene writes them (not resolved: shards rendered in other directories
    // share a hash), each with what it is for the error message.
    let mut named: Vec<(&str, &str)> = desc
        .mesh
        .iter()
        .filter_map(|m| m.path.as_ref())
        .map(|p| (p.get_ref().as_str(), "mesh file"))
        .collect();
    if let Some(map) = desc
        .environment
        .as_ref()
        .and_then(|e| e.get_ref().map.as_ref())
        .filter(|m| m.get_ref() != crate::scene::BUILTIN_SKY)
    {
        named.push((map.get_ref().as_str(), "environment map"));
    }
    for (p, what) in named {
        let full = match &base {
            Some(b) => b.join(p),
            None => PathBuf::from(p),
        };
        let source = crate::input::Source::Path(full);
        let bytes = crate::input::read(&source, what, crate::input::Content::Binary)
            .map_err(|e| e.to_string())?;
        h.update((p.len() as u64).to_le_bytes());
        h.update(p.as_bytes());
        h.update((bytes.len() as u64).to_le_bytes());
        h.update(&bytes);
    }
    let digest = h.finalize();
    let hex: String = digest.iter().map(|b| format!("{b:02x}")).collect();
    Ok(format!("sha256:{hex}"))
}

/// A writer that keeps the CRC of what passes through it.
struct Crc<W> {
    inner: W,
    crc: crc32fast::Hasher,
}

impl<W: Write> Write for Crc<W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let n = self.inner.write(buf)?;
        self.crc.update(&buf[..n]);
        Ok(n)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush()
    }
}

/// A reader that keeps the CRC of what passes through it.
struct CrcRead<R> {
    inner: R,
    crc: crc32fast::Hasher,
}

impl<R: Read> Read for CrcRead<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.crc.update(&buf[..n]);
        Ok(n)
    }
}

fn encode_record(s: &PixelState, out: &mut [u8; RECORD]) {
    let mut o = 0;
    let mut put = |b: &[u8]| {
        out[o..o + b.len()].copy_from_slice(b);
        o += b.len();
    };
    for v in s.mean {
        put(&v.to_le_bytes());
    }
    for v in s.m2 {
        put(&v.to_le_bytes());
    }
    put(&s.count.to_le_bytes());
    for v in s.odd_mean {
        put(&v.to_le_bytes());
    }
    put(&s.odd_count.to_le_bytes());
}

fn decode_record(b: &[u8; RECORD]) -> PixelState {
    let f64_at = |o: usize| f64::from_le_bytes(b[o..o + 8].try_into().unwrap_or([0; 8]));
    let f32_at = |o: usize| f32::from_le_bytes(b[o..o + 4].try_into().unwrap_or([0; 4]));
    let u32_at = |o: usize| u32::from_le_bytes(b[o..o + 4].try_into().unwrap_or([0; 4]));
    PixelState {
        mean: [f64_at(0), f64_at(8), f64_at(16)],
        m2: [f32_at(24), f32_at(28), f32_at(32)],
        count: u32_at(36),
        odd_mean: [f32_at(40), f32_at(44), f32_at(48)],
        odd_count: u32_at(52),
    }
}

/// Write `film` (and `map`, whose start the header's `map_start` must name) to `path`
/// atomically: a temporary file beside it, synced, then renamed over it.
pub fn write(
    path: &Path,
    header: &FilmHeader,
    film: &Film,
    map: Option<&SampleMap>,
) -> Result<(), FilmFileError> {
    let io = |e: std::io::Error| FilmFileError::Io {
        path: path.to_path_buf(),
        reason: crate::input::os_reason(&e),
    };
    let mut header = header.clone();
    header.map_start = map.map(SampleMap::start);
    let text = toml::to_string(&header).map_err(|e| FilmFileError::Header {
        path: path.to_path_buf(),
        why: e.to_string(),
    })?;
    crate::io::output::write_atomic_with(path, &[], |f, _| {
        let mut w = Crc {
            inner: BufWriter::with_capacity(1 << 20, f),
            crc: crc32fast::Hasher::new(),
        };
        w.write_all(MAGIC)?;
        w.write_all(&FORMAT_VERSION.to_le_bytes())?;
        w.write_all(&(text.len() as u32).to_le_bytes())?;
        w.write_all(text.as_bytes())?;
        let mut rec = [0u8; RECORD];
        for i in 0..film.pixels() {
            encode_record(&film.pixel_state(i), &mut rec);
            w.write_all(&rec)?;
        }
        if let Some(m) = map {
            w.write_all(m.weights())?;
        }
        let crc = w.crc.clone().finalize();
        let mut inner = w.inner;
        inner.write_all(&crc.to_le_bytes())?;
        inner.flush()
    })
    .map_err(|e| match e {
        crate::io::output::OutputError::Io { error, .. } => io(error),
        other => io(std::io::Error::other(other.to_string())),
    })
}

/// An open film file whose header has been read and checked; the pixels follow.
pub struct FilmReader {
    pub path: PathBuf,
    pub header: FilmHeader,
    reader: CrcRead<BufReader<std::fs::File>>,
}

/// Open `path` and read its header, checking the magic, version and the file's size.
pub fn open(path: &Path) -> Result<FilmReader, FilmFileError> {
    let p = || path.to_path_buf();
    let io = |e: std::io::Error| FilmFileError::Io {
        path: p(),
        reason: crate::input::os_reason(&e),
    };
    // A regular file only (its length is checked against the header): a directory, a device or
    // a pipe is refused before anything is read.
    let (file, len) = crate::input::open_regular(path, "film file")?;
    let mut reader = CrcRead {
        inner: BufReader::with_capacity(1 << 20, file),
        crc: crc32fast::Hasher::new(),
    };
    let mut fixed = [0u8; 16];
    if len < 16 {
        return Err(FilmFileError::NotAFilm {
            path: p(),
            why: format!("{len} bytes, shorter than the 16-byte preamble"),
        });
    }
    reader.read_exact(&mut fixed).map_err(io)?;
    if &fixed[..8] != MAGIC {
        return Err(FilmFileError::NotAFilm {
            path: p(),
            why: "it does not start with PTUIFILM".into(),
        });
    }
    let version = u32::from_le_bytes([fixed[8], fixed[9], fixed[10], fixed[11]]);
    if version != FORMAT_VERSION {
        return Err(FilmFileError::Version {
            path: p(),
            found: version,
        });
    }
    let hlen = u32::from_le_bytes([fixed[12], fixed[13], fixed[14], fixed[15]]);
    if hlen > MAX_HEADER || 16 + hlen as u64 > len {
        return Err(FilmFileError::NotAFilm {
            path: p(),
            why: format!("header length {hlen} does not fit the file's {len} bytes"),
        });
    }
    let mut text = vec![0u8; hlen as usize];
    reader.read_exact(&mut text).map_err(io)?;
    let text = String::from_utf8(text).map_err(|_| FilmFileError::Header {
        path: p(),
        why: "not UTF-8".into(),
    })?;
    let header: FilmHeader = toml::from_str(&text).map_err(|e| FilmFileError::Header {
        path: p(),
        why: e.to_string().trim_end().to_string(),
    })?;
    header.check(path)?;
    let expected = header.file_size(hlen as usize);
    if expected != len {
        return Err(FilmFileError::Size {
            path: p(),
            expected,
            found: len,
            width: header.width,
            height: header.height,
            map: if header.map_start.is_some() {
                " and an adaptive map"
            } else {
                ""
            },
        });
    }
    Ok(FilmReader {
        path: p(),
        header,
        reader,
    })
}

impl FilmReader {
    fn io(&self, e: std::io::Error) -> FilmFileError {
        FilmFileError::Io {
            path: self.path.clone(),
            reason: crate::input::os_reason(&e),
        }
    }

    /// Read the pixels, handing each (index, state) to `each`, then the map and the checksum.
    /// Memory: one buffered chunk of the file, whatever its size.
    pub fn read_pixels(
        mut self,
        mut each: impl FnMut(usize, PixelState),
    ) -> Result<(FilmHeader, Option<SampleMap>), FilmFileError> {
        let n = self.header.pixels() as usize;
        let mut rec = [0u8; RECORD];
        for i in 0..n {
            self.reader.read_exact(&mut rec).map_err(|e| self.io(e))?;
            each(i, decode_record(&rec));
        }
        let map = match self.header.map_start {
            Some(start) => {
                let mut w = vec![0u8; n];
                self.reader.read_exact(&mut w).map_err(|e| self.io(e))?;
                Some(SampleMap::from_weights(start, self.header.width, w))
            }
            None => None,
        };
        let computed = self.reader.crc.clone().finalize();
        let mut stored = [0u8; 4];
        self.reader
            .inner
            .read_exact(&mut stored)
            .map_err(|e| self.io(e))?;
        let stored = u32::from_le_bytes(stored);
        if stored != computed {
            return Err(FilmFileError::Checksum {
                path: self.path,
                stored,
                computed,
            });
        }
        Ok((self.header, map))
    }

    /// Read the whole film.
    pub fn read_film(self) -> Result<(FilmHeader, Film, Option<SampleMap>), FilmFileError> {
        let mut film = Film::new(self.header.width, self.header.height);
        let (header, map) = self.read_pixels(|i, s| film.set_pixel_state(i, s))?;
        Ok((header, film, map))
    }
}

/// Read a whole film file.
pub fn read(path: &Path) -> Result<(FilmHeader, Film, Option<SampleMap>), FilmFileError> {
    open(path)?.read_film()
}

/// Whether `path` names a film file by its extension.
pub fn is_film_path(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("film"))
}
