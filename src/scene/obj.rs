//! A Wavefront OBJ reader for what common exporters write: `v`, `vt`, `vn` and `f` (polygons of
//! any size, fan-triangulated; `v`, `v/vt`, `v//vn`, `v/vt/vn` corners; negative indices
//! counting back from the last vertex defined so far), `mtllib` (the material libraries, read by
//! `scene::mtl`) and `usemtl` (each face's material). Groups (`o`, `g`), smoothing groups (`s`),
//! points and lines are skipped. Statements the format has but a renderer of triangles does not
//! need (free-form curves and surfaces) are skipped with one warning.
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
/// No texture coordinate (also: no material for a face).
pub const NONE: u32 = u32::MAX;

/// One corner of a face: indices into [`ObjData::positions`], [`ObjData::texcoords`] and
/// [`ObjData::normals`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Corner {
    pub v: u32,
    /// [`NO_NORMAL`] when the corner names none.
    pub vn: u32,
    /// [`NONE`] when the corner names none.
    pub vt: u32,
}

/// The geometry of an OBJ file, triangulated: three corners per triangle.
#[derive(Clone, Debug, Default)]
pub struct ObjData {
    pub positions: Vec<[f64; 3]>,
    pub normals: Vec<[f64; 3]>,
    /// `vt` u and v as written (v growing upwards).
    pub texcoords: Vec<[f64; 2]>,
    pub triangles: Vec<[Corner; 3]>,
    /// Per triangle, its `usemtl` material: an index into `material_names` ([`NONE`] before
    /// any `usemtl`); empty when the file has no `usemtl`.
    pub triangle_materials: Vec<u32>,
    /// The names `usemtl` gives, in order of first use, with that line.
    pub material_names: Vec<(String, usize)>,
    /// The `mtllib` files as written, with their line.
    pub material_libs: Vec<(String, usize)>,
    /// Things skipped that the user may want to know about (unknown statements).
    pub warnings: Vec<String>,
}

/// A face before its indices are checked against the final vertex counts (positive indices may
/// name vertices defined further down).
struct Face {
    start: usize,
    len: usize,
    material: u32,
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
    let mut corners: Vec<(i64, i64, i64, usize)> = Vec::new();
    let mut faces: Vec<Face> = Vec::new();
    let mut triangle_count: u64 = 0;
    let mut material = NONE;
    let mut material_index: std::collections::HashMap<String, u32> = Default::default();
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
            "vt" => {
                let t = texcoord(&mut words).map_err(|m| err(line, m))?;
                if t.iter().any(|c| !c.is_finite() || c.abs() > MAX_MAGNITUDE) {
                    return Err(err(
                        line,
                        format!(
                            "texture coordinate {} is {t:?}: each must be a finite number of \
                             magnitude at most {MAX_MAGNITUDE:e}",
                            data.texcoords.len() + 1
                        ),
                    ));
                }
                data.texcoords.push(t);
            }
            "f" | "fo" => {
                let start = corners.len();
                let counts = (
                    data.positions.len(),
                    data.texcoords.len(),
                    data.normals.len(),
                );
                for word in words {
                    let c = corner(word, counts).map_err(|m| err(line, m))?;
                    corners.push((c.0, c.1, c.2, line));
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
                faces.push(Face {
                    start,
                    len,
                    material,
                });
            }
            "mtllib" => {
                // File names may hold spaces; several files are rare and then space-separated,
                // so a name that exists whole is taken whole (`scene::mtl` resolves them).
                let rest = content.trim_start()["mtllib".len()..].trim();
                if !rest.is_empty() {
                    data.material_libs.push((rest.to_string(), line));
                }
            }
            "usemtl" => {
                let name = content.trim_start()["usemtl".len()..].trim().to_string();
                let next = data.material_names.len() as u32;
                material = *material_index.entry(name.clone()).or_insert_with(|| {
                    data.material_names.push((name, line));
                    next
                });
            }
            // Groups, smoothing groups, points, lines: nothing to do.
            "vp" | "o" | "g" | "s" | "l" | "p" | "mg" => {}
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
    let with_materials = !data.material_names.is_empty();
    for f in &faces {
        let mut resolved = Vec::with_capacity(f.len);
        for &(v, vt, vn, line) in &corners[f.start..f.start + f.len] {
            let v = check(v, data.positions.len(), "vertex", line)?;
            let vn = if vn == i64::MIN {
                NO_NORMAL
            } else {
                check(vn, data.normals.len(), "normal", line)?
            };
            let vt = if vt == i64::MIN {
                NONE
            } else {
                check(vt, data.texcoords.len(), "texture coordinate", line)?
            };
            resolved.push(Corner { v, vn, vt });
        }
        // A fan around the first corner, as tobj, pbrt and Mitsuba triangulate.
        for k in 1..f.len - 1 {
            data.triangles
                .push([resolved[0], resolved[k], resolved[k + 1]]);
            if with_materials {
                data.triangle_materials.push(f.material);
            }
        }
    }
    if data.triangles.is_empty() {
        return Err(format!("{name}: contains no faces"));
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

/// A face corner `v`, `v/vt`, `v//vn` or `v/vt/vn` as 0-based indices (texture coordinate and
/// normal i64::MIN when absent). Negative indices count back from the counts so far
/// (positions, texture coordinates, normals); the range of positive ones is checked once the
/// whole file is read.
fn corner(
    word: &str,
    (positions, texcoords, normals): (usize, usize, usize),
) -> Result<(i64, i64, i64), String> {
    let mut parts = word.split('/');
    let v = parts.next().unwrap_or("");
    let vt = parts.next();
    let vn = parts.next();
    if parts.next().is_some() {
        return Err(format!(
            "face corner `{}` has more than three parts",
            short(word)
        ));
    }
    let v = index(v, positions, "vertex", word)?;
    let vt = match vt {
        None | Some("") => i64::MIN,
        Some(s) => index(s, texcoords, "texture coordinate", word)?,
    };
    let vn = match vn {
        None | Some("") => i64::MIN,
        Some(s) => index(s, normals, "normal", word)?,
    };
    Ok((v, vt, vn))
}

/// `vt u [v [w]]`: v is 0 when absent, w is ignored.
fn texcoord(words: &mut std::str::SplitWhitespace) -> Result<[f64; 2], String> {
    let mut out = [0.0; 2];
    for (i, slot) in out.iter_mut().enumerate() {
        match words.next() {
            Some(word) => {
                *slot = word
                    .parse::<f64>()
                    .map_err(|_| format!("`vt`: `{}` is not a number", short(word)))?
            }
            None if i == 0 => {
                return Err("truncated `vt` line: a texture coordinate needs u".into())
            }
            None => break,
        }
    }
    Ok(out)
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
            ok("f 1//1 2//1 3//1\nf 1 2 3\nf 1/1 2/1/ 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nvt 0 0\n");
        assert_eq!(d.triangles[0][2].vn, 0);
        assert_eq!(d.triangles[1][0].vn, NO_NORMAL);
        assert_eq!(d.triangles[2][1].vn, NO_NORMAL);
    }

    #[test]
    fn materials_and_texture_coordinates_are_read() {
        let d = ok(
            "mtllib my lib.mtl\no x\ng y\ns 1\nusemtl m\nv 0 0 0\nv 1 0 0\nv 0 1 0\n\
             vt 0.25 0.75\nvt 1\nusemtl n\nf 1/1 2/2 3/-1\nusemtl m\nf 1 2 3\n",
        );
        assert!(d.warnings.is_empty(), "{:?}", d.warnings);
        assert_eq!(d.material_libs, [("my lib.mtl".to_string(), 1)]);
        let names: Vec<&str> = d.material_names.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names, ["m", "n"]);
        assert_eq!(d.triangle_materials, [1, 0]);
        assert_eq!(d.texcoords, [[0.25, 0.75], [1.0, 0.0]]);
        assert_eq!(d.triangles[0].map(|c| c.vt), [0, 1, 1]);
        assert_eq!(d.triangles[1][0].vt, NONE);
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
            (
                format!("{tri}vt 0 0\nf 1/1 2/2 3/1\n"),
                5,
                "texture coordinate index 2",
            ),
            (format!("{tri}vt nan 0\nf 1 2 3\n"), 4, "finite"),
            (format!("{tri}vt\nf 1 2 3\n"), 4, "truncated"),
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
