//! A Wavefront OBJ reader for what common exporters write: `v`, `vn` and `f` (polygons of any
//! size, fan-triangulated; `v`, `v/vt`, `v//vn`, `v/vt/vn` corners; negative indices counting
//! back from the last vertex defined so far). Texture coordinates, groups (`o`, `g`), smoothing
//! groups (`s`), points and lines are skipped; `mtllib` / `usemtl` are skipped with one warning
//! (a mesh takes the material of its `[[mesh]]` entry). Statements the format has but a renderer
//! of triangles does not need (free-form curves and surfaces) are skipped with one warning.
//!
//! Written here rather than read with `tobj` so every refusal names its line: a non-finite or
//! huge coordinate, an index of 0 or out of range, a truncated statement or a word that is not a
//! number is an error `file:line: reason`. Nothing here panics on any input.

use crate::checked::MAX_MAGNITUDE;
use crate::input::{self, Content, Source};
use crate::progress::{tick, Progress};
use std::path::Path;

/// No normal: the corner or face is flat-shaded.
pub const NO_NORMAL: u32 = u32::MAX;

/// One corner of a face: indices into [`ObjData::positions`] and [`ObjData::normals`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Corner {
    pub v: u32,
    /// [`NO_NORMAL`] when the corner names none.
    pub vn: u32,
}

/// The geometry of an OBJ file, triangulated: three corners per triangle.
#[derive(Clone, Debug, Default)]
pub struct ObjData {
    pub positions: Vec<[f64; 3]>,
    pub normals: Vec<[f64; 3]>,
    pub triangles: Vec<[Corner; 3]>,
    /// Things skipped that the user may want to know about (materials, unknown statements).
    pub warnings: Vec<String>,
}

/// A face before its indices are checked against the final vertex counts (positive indices may
/// name vertices defined further down).
struct Face {
    start: usize,
    len: usize,
}

/// Parse the OBJ file at `path`; `limit` is how many triangles the caller accepts. Errors read
/// `path:line: reason` (or `path: reason` for the file as a whole).
pub fn read(path: &Path, limit: u64, progress: Option<&Progress>) -> Result<ObjData, String> {
    let shown = path.display();
    // A file or a pipe only, within the memory and with text-sized lines (`crate::input`).
    let source = Source::Path(path.to_path_buf());
    let bytes = input::read(&source, "OBJ file", Content::Text).map_err(|e| e.to_string())?;
    if let Some(p) = progress {
        p.start(format!("reading {shown}"), bytes.len() as u64);
    }
    parse_with(&bytes, &shown.to_string(), limit, progress)
}

/// The end of the message for a file with more triangles than the scene has room for (the
/// scene build adds why).
pub const NO_ROOM: &str = "the most this scene has room for";

/// [`read`] on bytes already in memory; `name` stands for the file in messages.
pub fn parse(bytes: &[u8], name: &str, limit: u64) -> Result<ObjData, String> {
    parse_with(bytes, name, limit, None)
}

/// [`parse`], counting the bytes read into `progress` as it goes.
pub fn parse_with(
    bytes: &[u8],
    name: &str,
    limit: u64,
    progress: Option<&Progress>,
) -> Result<ObjData, String> {
    let mut data = ObjData::default();
    let mut corners: Vec<(i64, i64, usize)> = Vec::new();
    let mut faces: Vec<Face> = Vec::new();
    let mut triangle_count: u64 = 0;
    let mut materials_seen = false;
    let mut unknown: Option<(usize, String)> = None;
    let mut unknown_count = 0usize;
    let err = |line: usize, msg: String| format!("{name}:{line}: {msg}");

    // A line ending in a backslash continues on the next one; `line` is where a statement starts.
    let mut pending = String::new();
    let mut pending_line = 0usize;
    let mut unticked = 0u64;
    for (i, raw) in bytes.split(|&b| b == b'\n').enumerate() {
        unticked += raw.len() as u64 + 1;
        if unticked >= 1 << 20 {
            tick(progress, unticked);
            unticked = 0;
        }
        let text = String::from_utf8_lossy(raw);
        let text = text.trim_end_matches('\r');
        if pending.is_empty() {
            pending_line = i + 1;
        }
        if let Some(head) = text.strip_suffix('\\') {
            pending.push_str(head);
            pending.push(' ');
            continue;
        }
        pending.push_str(text);
        let statement = std::mem::take(&mut pending);
        let line = pending_line;
        let content = statement.split('#').next().unwrap_or("");
        let mut words = content.split_whitespace();
        let Some(keyword) = words.next() else {
            continue;
        };
        match keyword {
            "v" => {
                let p = numbers::<3>(&mut words, "v", "a vertex needs x y z")
                    .map_err(|m| err(line, m))?;
                if p.iter().any(|c| !c.is_finite() || c.abs() > MAX_MAGNITUDE) {
                    return Err(err(
                        line,
                        format!(
                            "vertex {} has coordinates {p:?}: each must be a finite number of \
                             magnitude at most {MAX_MAGNITUDE:e}",
                            data.positions.len() + 1
                        ),
                    ));
                }
                data.positions.push(p);
            }
            "vn" => {
                let n = numbers::<3>(&mut words, "vn", "a normal needs x y z")
                    .map_err(|m| err(line, m))?;
                if n.iter().any(|c| !c.is_finite()) {
                    return Err(err(
                        line,
                        format!(
                            "normal {} is {n:?}: each component must be a finite number",
                            data.normals.len() + 1
                        ),
                    ));
                }
                data.normals.push(n);
            }
            "f" | "fo" => {
                let start = corners.len();
                for word in words {
                    let c = corner(word, data.positions.len(), data.normals.len())
                        .map_err(|m| err(line, m))?;
                    corners.push((c.0, c.1, line));
                }
                let len = corners.len() - start;
                if len < 3 {
                    return Err(err(
                        line,
                        format!("a face needs at least 3 vertices, this one has {len}"),
                    ));
                }
                triangle_count += len as u64 - 2;
                if triangle_count > limit {
                    return Err(format!(
                        "{name}: has more than {limit} triangles, {NO_ROOM}"
                    ));
                }
                faces.push(Face { start, len });
            }
            "mtllib" | "usemtl" => materials_seen = true,
            // Texture coordinates, groups, smoothing groups, points, lines: nothing to do.
            "vt" | "vp" | "o" | "g" | "s" | "l" | "p" | "mg" => {}
            _ => {
                unknown_count += 1;
                unknown.get_or_insert((line, keyword.chars().take(32).collect()));
            }
        }
    }

    // Resolve the corners now every vertex is known (positive indices may point ahead).
    let check = |idx: i64, count: usize, what: &str, line: usize| -> Result<u32, String> {
        if idx < 0 || idx as u64 >= count as u64 || idx >= NO_NORMAL as i64 {
            Err(err(
                line,
                format!(
                    "{what} index {} is out of range: the file has {count} {what}s",
                    idx + 1
                ),
            ))
        } else {
            Ok(idx as u32)
        }
    };
    data.triangles.reserve(triangle_count as usize);
    for f in &faces {
        let mut resolved = Vec::with_capacity(f.len);
        for &(v, vn, line) in &corners[f.start..f.start + f.len] {
            let v = check(v, data.positions.len(), "vertex", line)?;
            let vn = if vn == i64::MIN {
                NO_NORMAL
            } else {
                check(vn, data.normals.len(), "normal", line)?
            };
            resolved.push(Corner { v, vn });
        }
        // A fan around the first corner, as tobj, pbrt and Mitsuba triangulate.
        for k in 1..f.len - 1 {
            data.triangles
                .push([resolved[0], resolved[k], resolved[k + 1]]);
        }
    }
    if data.triangles.is_empty() {
        return Err(format!("{name}: contains no faces"));
    }
    if materials_seen {
        data.warnings.push(format!(
            "{name}: its materials (mtllib / usemtl) are ignored: a mesh takes the material of \
             its [[mesh]] entry"
        ));
    }
    if let Some((line, word)) = unknown {
        data.warnings.push(format!(
            "{name}:{line}: skipped {unknown_count} statement(s) this reader does not use, the \
             first `{word}`"
        ));
    }
    Ok(data)
}

/// The first N numbers of a statement (more are allowed: `v x y z w` and vertex colours).
fn numbers<const N: usize>(
    words: &mut std::str::SplitWhitespace,
    keyword: &str,
    need: &str,
) -> Result<[f64; N], String> {
    let mut out = [0.0; N];
    for (i, slot) in out.iter_mut().enumerate() {
        let word = words
            .next()
            .ok_or_else(|| format!("truncated `{keyword}` line: {need}, found {i} number(s)"))?;
        *slot = word.parse::<f64>().map_err(|_| {
            format!(
                "`{keyword}`: `{}` is not a number",
                word.chars().take(32).collect::<String>()
            )
        })?;
    }
    Ok(out)
}

/// A face corner `v`, `v/vt`, `v//vn` or `v/vt/vn` as 0-based indices (the normal i64::MIN
/// when absent). Negative indices count back from the counts so far; the range of positive ones
/// is checked once the whole file is read.
fn corner(word: &str, positions: usize, normals: usize) -> Result<(i64, i64), String> {
    let mut parts = word.split('/');
    let v = parts.next().unwrap_or("");
    let _vt = parts.next();
    let vn = parts.next();
    if parts.next().is_some() {
        return Err(format!(
            "face corner `{}` has more than three parts",
            short(word)
        ));
    }
    let v = index(v, positions, "vertex", word)?;
    let vn = match vn {
        None | Some("") => i64::MIN,
        Some(s) => index(s, normals, "normal", word)?,
    };
    Ok((v, vn))
}

fn index(s: &str, count: usize, what: &str, word: &str) -> Result<i64, String> {
    let i: i64 = s.parse().map_err(|_| {
        format!(
            "face corner `{}`: `{}` is not a {what} index",
            short(word),
            short(s)
        )
    })?;
    match i {
        0 => Err(format!(
            "face corner `{}`: {what} index 0 (OBJ indices start at 1)",
            short(word)
        )),
        i if i > 0 => Ok(i - 1),
        // -1 is the last vertex defined so far.
        i => {
            let back = i.unsigned_abs();
            if back > count as u64 {
                Err(format!(
                    "face corner `{}`: relative {what} index {i} reaches before the first \
                     {what} ({count} defined so far)",
                    short(word)
                ))
            } else {
                Ok(count as i64 - back as i64)
            }
        }
    }
}

fn short(s: &str) -> String {
    s.chars().take(32).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ok(src: &str) -> ObjData {
        parse(src.as_bytes(), "t.obj", 1000).expect("parses")
    }

    fn bad(src: &str) -> String {
        parse(src.as_bytes(), "t.obj", 1000).expect_err("refused")
    }

    #[test]
    fn ngons_are_fans_and_negative_indices_count_back() {
        let d = ok("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv -1 1 0\nf -5 -4 -3 -2 -1\n");
        assert_eq!(d.triangles.len(), 3);
        let v: Vec<[u32; 3]> = d.triangles.iter().map(|t| t.map(|c| c.v)).collect();
        assert_eq!(v, [[0, 1, 2], [0, 2, 3], [0, 3, 4]]);
    }

    #[test]
    fn normals_partial_and_forward_references() {
        let d =
            ok("f 1//1 2//1 3//1\nf 1 2 3\nf 1/1 2/1/ 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\n");
        assert_eq!(d.triangles[0][2].vn, 0);
        assert_eq!(d.triangles[1][0].vn, NO_NORMAL);
        assert_eq!(d.triangles[2][1].vn, NO_NORMAL);
    }

    #[test]
    fn groups_and_materials_are_skipped_with_one_warning() {
        let d = ok(
            "mtllib a.mtl\no x\ng y\ns 1\nusemtl m\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl n\nf 1 2 3\n",
        );
        assert_eq!(d.warnings.len(), 1, "{:?}", d.warnings);
        assert!(d.warnings[0].contains("t.obj") && d.warnings[0].contains("mtllib"));
    }

    #[test]
    fn refusals_name_the_line_and_the_reason() {
        let tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
        for (src, line, what) in [
            (format!("{tri}v nan 0 0\nf 1 2 3\n"), 4, "finite"),
            (format!("{tri}v 1 2\nf 1 2 3\n"), 4, "truncated"),
            (format!("{tri}vn 0 inf 1\nf 1 2 3\n"), 4, "finite"),
            (format!("{tri}f 1 2 4\n"), 4, "out of range"),
            (format!("{tri}f 1 2\n"), 4, "at least 3"),
            (format!("{tri}f 0 1 2\n"), 4, "index 0"),
            (format!("{tri}f -4 1 2\n"), 4, "before the first"),
            (
                format!("{tri}f 1//2 2//1 3//1\nvn 0 0 1\n"),
                4,
                "normal index 2",
            ),
            (format!("{tri}\nf 1 2 x\n"), 5, "not a vertex index"),
            (format!("{tri}v 1e39 0 0\n"), 4, "magnitude"),
            (format!("{tri}v 1 2 \\\n\nf 1 2 3\n"), 4, "truncated"),
        ] {
            let e = bad(&src);
            assert!(
                e.starts_with(&format!("t.obj:{line}: ")) && e.contains(what),
                "{src:?}: {e}"
            );
        }
        assert!(bad("# nothing\n").contains("no faces"));
        assert!(bad("v 0 0 0\n").contains("no faces"));
    }

    #[test]
    fn the_triangle_limit_is_checked_while_reading() {
        let src = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 3\n";
        assert!(parse(src.as_bytes(), "t.obj", 1)
            .unwrap_err()
            .contains("more than 1"));
    }
}
