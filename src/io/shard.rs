//! Shards of one render and their merge.
//!
//! A render of `spp` passes splits by passes: shard I of N renders passes
//! `floor(I spp / N) .. floor((I + 1) spp / N)` of the whole image, with the pass numbers (hence
//! random numbers, light paths and half-buffer parity) of the whole render. A pixel's state
//! after the passes of two shards is the pairwise (Chan) merge of its two states, merged in pass
//! order; the result is the single render's film to within rounding (mean within 1e-12
//! relative, M2 and the odd-pass mean to their f32 storage), not bit for bit: the single render
//! adds samples one at a time, and floating-point addition is not associative.
//!
//! With adaptive sampling, a shard that starts after pass 0 renders the pilot passes on a film
//! of its own first, to build the same map as the whole render (see
//! [`crate::render::Renderer::pilot_map`]); every shard's film file carries the map, and a merge
//! checks they agree.

use crate::io::film_file::{self, FilmFileError, FilmHeader};
use crate::render::adaptive::SampleMap;
use crate::render::film::Film;
use std::path::{Path, PathBuf};

/// Shard `index` of `count` (0-based).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    pub index: u32,
    pub count: u32,
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl std::str::FromStr for Shard {
    type Err = String;

    /// "I/N", 0 <= I < N.
    fn from_str(s: &str) -> Result<Self, String> {
        let (i, n) = s
            .split_once('/')
            .ok_or_else(|| format!("expected I/N (e.g. 0/8), got `{s}`"))?;
        let num = |v: &str, what: &str| -> Result<u32, String> {
            v.trim()
                .parse()
                .map_err(|_| format!("shard {what} `{v}` is not a whole number (in `{s}`)"))
        };
        Shard::new(num(i, "index")?, num(n, "count")?)
    }
}

impl Shard {
    pub fn new(index: u32, count: u32) -> Result<Self, String> {
        if count == 0 {
            return Err("the shard count must be at least 1".into());
        }
        if index >= count {
            return Err(format!(
                "shard index {index} is out of range for {count} shards (0..{count}, 0-based)"
            ));
        }
        Ok(Shard { index, count })
    }

    /// The passes [first, end) of a render of `spp` passes this shard renders.
    pub fn passes(self, spp: u32) -> (u32, u32) {
        let at = |i: u32| (i as u64 * spp as u64 / self.count as u64) as u32;
        (at(self.index), at(self.index + 1))
    }

    /// The shard a scheduler's environment names: Slurm job arrays (`SLURM_ARRAY_TASK_ID` less
    /// `SLURM_ARRAY_TASK_MIN`, of `SLURM_ARRAY_TASK_COUNT`), Kubernetes Indexed Jobs
    /// (`JOB_COMPLETION_INDEX`) or AWS Batch array jobs (`AWS_BATCH_JOB_ARRAY_INDEX`); the count
    /// is `shards` where the scheduler gives none, and must agree with it where it does.
    pub fn from_env(
        shards: Option<u32>,
        env: impl Fn(&str) -> Option<String>,
    ) -> Result<Shard, String> {
        let num = |var: &str| -> Result<Option<u32>, String> {
            match env(var) {
                None => Ok(None),
                Some(v) => v
                    .trim()
                    .parse()
                    .map(Some)
                    .map_err(|_| format!("{var}={v} is not a whole number")),
            }
        };
        let count = |given: Option<u32>, var: &str| -> Result<u32, String> {
            match (given, shards) {
                (Some(g), Some(s)) if g != s => Err(format!(
                    "--shards {s} disagrees with {var}={g}: drop --shards or fix the array size"
                )),
                (Some(g), _) => Ok(g),
                (None, Some(s)) => Ok(s),
                (None, None) => Err(format!(
                    "{var} gives no shard count here: pass --shards N with --shard-from-env"
                )),
            }
        };
        if let Some(id) = num("SLURM_ARRAY_TASK_ID")? {
            let min = num("SLURM_ARRAY_TASK_MIN")?.unwrap_or(0);
            let index = id.checked_sub(min).ok_or_else(|| {
                format!("SLURM_ARRAY_TASK_ID={id} is below SLURM_ARRAY_TASK_MIN={min}")
            })?;
            let n = count(num("SLURM_ARRAY_TASK_COUNT")?, "SLURM_ARRAY_TASK_COUNT")?;
            return Shard::new(index, n).map_err(|e| format!("from SLURM_ARRAY_TASK_ID: {e}"));
        }
        for var in ["JOB_COMPLETION_INDEX", "AWS_BATCH_JOB_ARRAY_INDEX"] {
            if let Some(index) = num(var)? {
                let n = count(None, var)?;
                return Shard::new(index, n).map_err(|e| format!("from {var}: {e}"));
            }
        }
        Err(
            "--shard-from-env: none of SLURM_ARRAY_TASK_ID, JOB_COMPLETION_INDEX, \
             AWS_BATCH_JOB_ARRAY_INDEX is set"
                .into(),
        )
    }
}

#[derive(Debug, thiserror::Error)]
pub enum MergeError {
    #[error(transparent)]
    File(#[from] FilmFileError),
    #[error("{}: {cancelled} of its passes were cancelled part-way (saved from the TUI while a pass ran): it can be continued (`ptui {}`), not merged", .path.display(), .path.display())]
    Cancelled { path: PathBuf, cancelled: u32 },
    #[error("nothing to merge: no parts given")]
    NoParts,
    #[error("{} does not belong with {}: {field} is {b} there, {a} in {}", .b_path.display(), .a_path.display(), .a_path.display())]
    Mismatch {
        field: &'static str,
        a_path: PathBuf,
        a: String,
        b_path: PathBuf,
        b: String,
    },
    #[error("{} (passes {a}) and {} (passes {b}) overlap: their samples would count twice", .a_path.display(), .b_path.display())]
    Overlap {
        a_path: PathBuf,
        a: String,
        b_path: PathBuf,
        b: String,
    },
    #[error("{}: its adaptive map differs from {}'s (the same render builds one map)", .b_path.display(), .a_path.display())]
    MapMismatch { a_path: PathBuf, b_path: PathBuf },
    #[error("passes {missing} of 0..{spp} are missing (no part holds them); merged {have} passes from {parts} parts")]
    Incomplete {
        missing: String,
        spp: u32,
        have: u64,
        parts: usize,
    },
}

/// A merged film and what it is missing.
pub struct Merged {
    pub header: FilmHeader,
    pub film: Film,
    pub map: Option<SampleMap>,
    /// Pass ranges of 0..spp no part holds.
    pub missing: Vec<[u32; 2]>,
    pub parts: usize,
}

/// Ranges of 0..spp that `have` (sorted, disjoint) leaves out.
pub fn gaps(have: &[[u32; 2]], spp: u32) -> Vec<[u32; 2]> {
    let mut out = Vec::new();
    let mut at = 0;
    for r in have {
        if r[0] > at {
            out.push([at, r[0].min(spp)]);
        }
        at = at.max(r[1]);
    }
    if at < spp {
        out.push([at, spp]);
    }
    out.retain(|r| r[0] < r[1]);
    out
}

/// Ranges as text: "16..32, 48..64".
pub fn ranges_text(r: &[[u32; 2]]) -> String {
    r.iter()
        .map(|r| format!("{}..{}", r[0], r[1]))
        .collect::<Vec<_>>()
        .join(", ")
}

/// Merge film files into one film. Refuses parts of another scene, settings, seed or version
/// (naming the field and both values), parts whose passes overlap, corrupt parts; with
/// `require_complete`, a merge that leaves passes of 0..spp out.
///
/// The parts are merged in pass order whatever the order given, so the result is the same bit
/// for bit for any order. Memory: the merged film, and one buffered chunk of the part being
/// read (parts are streamed pixel by pixel, never held whole).
pub fn merge(paths: &[PathBuf], require_complete: bool) -> Result<Merged, MergeError> {
    let mut parts: Vec<(PathBuf, FilmHeader)> = Vec::with_capacity(paths.len());
    for p in paths {
        // Only the header now: the reader's buffer is dropped until the part's turn comes.
        let h = film_file::open(p)?.header;
        if h.cancelled > 0 {
            return Err(MergeError::Cancelled {
                path: p.clone(),
                cancelled: h.cancelled,
            });
        }
        parts.push((p.clone(), h));
    }
    let Some((first_path, first)) = parts.first().cloned() else {
        return Err(MergeError::NoParts);
    };
    let reference = first.identity();
    for (path, h) in &parts[1..] {
        for ((field, a), (_, b)) in reference.iter().zip(h.identity()) {
            if *a != b {
                return Err(MergeError::Mismatch {
                    field,
                    a_path: first_path.clone(),
                    a: a.clone(),
                    b_path: path.clone(),
                    b,
                });
            }
        }
    }
    // Pass order; empty parts last (they add nothing but are still checked whole).
    parts.sort_by_key(|(p, h)| {
        (
            h.passes.first().map_or(u32::MAX, |r| r[0]),
            p.to_string_lossy().into_owned(),
        )
    });
    let mut ranges: Vec<([u32; 2], &Path)> = parts
        .iter()
        .flat_map(|(p, h)| h.passes.iter().map(move |r| (*r, p.as_path())))
        .collect();
    ranges.sort_by_key(|(r, _)| *r);
    for w in ranges.windows(2) {
        let ((a, ap), (b, bp)) = (w[0], w[1]);
        if b[0] < a[1] {
            return Err(MergeError::Overlap {
                a_path: ap.to_path_buf(),
                a: format!("{}..{}", a[0], a[1]),
                b_path: bp.to_path_buf(),
                b: format!("{}..{}", b[0], b[1]),
            });
        }
    }
    let mut covered: Vec<[u32; 2]> = Vec::new();
    for (r, _) in &ranges {
        match covered.last_mut() {
            Some(last) if last[1] == r[0] => last[1] = r[1],
            _ => covered.push(*r),
        }
    }
    let spp = first.spp;
    let missing = gaps(&covered, spp);
    if require_complete && !missing.is_empty() {
        return Err(MergeError::Incomplete {
            missing: ranges_text(&missing),
            spp,
            have: covered.iter().map(|r| (r[1] - r[0]) as u64).sum(),
            parts: parts.len(),
        });
    }
    let base = parts[0].1.clone();
    let mut film = Film::new(base.width, base.height);
    let mut header = FilmHeader {
        passes: covered,
        until: parts.iter().map(|(_, h)| h.until).max().unwrap_or(spp),
        shard: None,
        map_start: None,
        stats: Default::default(),
        ..base
    };
    let mut map: Option<(SampleMap, PathBuf)> = None;
    for (path, _) in &parts {
        let reader = film_file::open(path)?;
        let (h, part_map) = reader.read_pixels(|i, s| {
            let merged = film.pixel_state(i).merged(s);
            film.set_pixel_state(i, merged);
        })?;
        header.stats.add(&h.stats);
        header.error_from_halves |= h.error_from_halves;
        match (&map, part_map) {
            (Some((m, from)), Some(pm)) if *m != pm => {
                return Err(MergeError::MapMismatch {
                    a_path: from.clone(),
                    b_path: path.clone(),
                })
            }
            (None, Some(pm)) => map = Some((pm, path.clone())),
            _ => {}
        }
    }
    let map = map.map(|(m, _)| m);
    header.map_start = map.as_ref().map(SampleMap::start);
    Ok(Merged {
        header,
        film,
        map,
        missing,
        parts: parts.len(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_split_the_passes_without_gaps_or_overlaps() {
        for (spp, n) in [(1024, 8), (10, 3), (5, 8), (1, 1), (17, 4)] {
            let mut at = 0;
            for i in 0..n {
                let (a, b) = Shard::new(i, n).expect("valid").passes(spp);
                assert_eq!(a, at);
                assert!(b >= a);
                at = b;
            }
            assert_eq!(at, spp);
        }
        assert_eq!(Shard::new(3, 8).expect("valid").passes(1024), (384, 512));
    }

    #[test]
    fn shard_text_and_environment() {
        assert_eq!("2/8".parse::<Shard>(), Ok(Shard { index: 2, count: 8 }));
        for bad in ["8/8", "1", "a/2", "0/0", "-1/4"] {
            assert!(bad.parse::<Shard>().is_err(), "{bad}");
        }
        let env = |vars: &'static [(&'static str, &'static str)]| {
            move |k: &str| {
                vars.iter()
                    .find(|(n, _)| *n == k)
                    .map(|(_, v)| v.to_string())
            }
        };
        let slurm = env(&[
            ("SLURM_ARRAY_TASK_ID", "5"),
            ("SLURM_ARRAY_TASK_MIN", "1"),
            ("SLURM_ARRAY_TASK_COUNT", "8"),
        ]);
        assert_eq!(
            Shard::from_env(None, slurm),
            Ok(Shard { index: 4, count: 8 })
        );
        assert!(Shard::from_env(Some(4), slurm)
            .unwrap_err()
            .contains("disagrees"));
        let k8s = env(&[("JOB_COMPLETION_INDEX", "3")]);
        assert!(Shard::from_env(None, k8s).unwrap_err().contains("--shards"));
        assert_eq!(
            Shard::from_env(Some(4), k8s),
            Ok(Shard { index: 3, count: 4 })
        );
        let aws = env(&[("AWS_BATCH_JOB_ARRAY_INDEX", "9")]);
        assert!(Shard::from_env(Some(4), aws)
            .unwrap_err()
            .contains("out of range"));
        assert!(Shard::from_env(Some(4), env(&[])).is_err());
    }

    #[test]
    fn gaps_are_what_the_parts_leave_out() {
        assert_eq!(gaps(&[[0, 10]], 10), Vec::<[u32; 2]>::new());
        assert_eq!(gaps(&[[2, 4], [6, 8]], 10), [[0, 2], [4, 6], [8, 10]]);
        assert_eq!(gaps(&[], 3), [[0, 3]]);
    }
}
