//! Fuzz-style property tests of the model readers, as `fuzz_obj` does the OBJ reader: MTL files
//! of random statements (bad numbers, options, missing files) and mutations of a valid glTF
//! binary (bytes flipped in its JSON or its binary chunk, numbers in the JSON replaced, the file
//! cut short). The readers never panic: they return a model with finite vertices or an error
//! that names the file (an MTL error also its line).

use proptest::prelude::*;
use ptui::scene::{gltf, mtl};
use ptui::texture::load::Cache;
use std::path::{Path, PathBuf};

const MTL_LINES: &[&str] = &[
    "newmtl a",
    "newmtl",
    "newmtl b c",
    "Kd 0.5 0.5 0.5",
    "Kd 1",
    "Kd",
    "Kd nan 0 0",
    "Kd -1 2 1e308",
    "Kd spectral f.spd",
    "Ks 0.5 0.5 0.5",
    "Ke 10 10 10",
    "Ke inf 0 0",
    "Ns 250",
    "Ns -5",
    "Ns x",
    "Ni 1.45",
    "Ni 0",
    "Ni 1e300",
    "d 0.5",
    "Tr 0.2",
    "Tf 0.9 0.9 0.9",
    "illum 7",
    "illum -3",
    "map_Kd tex.png",
    "map_Kd -s 2 2 1 -o 0.5 0.5 0 tex.png",
    "map_Kd -s",
    "map_Kd -clamp on -bm 1 tex.png",
    "map_Kd missing.png",
    "map_Kd notimage.png",
    "map_Ke tex.png",
    "map_d tex.png",
    "map_Bump -bm 0.5 n.png",
    "refl -type sphere r.png",
    "# comment",
    "",
    "\u{0}\u{ff}garbage",
];

fn fixture_dir() -> tempfile::TempDir {
    let dir = tempfile::tempdir().expect("temp dir");
    let png = std::fs::read(
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/examples/textured/floor.png"),
    )
    .expect("floor.png");
    std::fs::write(dir.path().join("tex.png"), png).unwrap();
    std::fs::write(dir.path().join("notimage.png"), "not an image").unwrap();
    dir
}

fn check_mtl(lines: &[usize], dir: &Path) -> Result<(), TestCaseError> {
    let text: Vec<&str> = lines
        .iter()
        .map(|&i| MTL_LINES[i % MTL_LINES.len()])
        .collect();
    let text = text.join("\n");
    match mtl::parse(text.as_bytes(), "f.mtl") {
        Err(e) => prop_assert!(e.starts_with("f.mtl:"), "{e}"),
        Ok(lib) => {
            let mut cache = Cache::default();
            for m in &lib.materials {
                if let Err(e) = mtl::material_desc(m, "f.mtl", dir, &mut cache) {
                    prop_assert!(e.starts_with("f.mtl:"), "{e}");
                    continue;
                }
                let desc = mtl::material_desc(m, "f.mtl", dir, &mut cache).expect("same again");
                // The table's keys are always valid ones: the material builds.
                let built =
                    ptui::scene::materials::build_material(&desc, "", "s.toml", "mesh[0]", true);
                prop_assert!(built.is_ok(), "{:?}", built.err().map(|e| e.to_string()));
            }
        }
    }
    Ok(())
}

#[derive(Clone, Debug)]
enum GlbEdit {
    /// Set a byte of the JSON chunk to a character of `JSON_CHARS`.
    JsonByte(usize, usize),
    /// Replace the n-th number of the JSON with one of `NUMBERS`.
    JsonNumber(usize, usize),
    /// Set a byte of the binary chunk.
    BinByte(usize, u8),
    /// Cut the file short.
    Truncate(usize),
}

const JSON_CHARS: &[u8] = b"{}[]\",:0-9ex ";
const NUMBERS: &[&str] = &[
    "-1",
    "0",
    "4294967295",
    "1e30",
    "3",
    "7",
    "99999999999",
    "0.5",
];

fn apply(glb: &[u8], edits: &[GlbEdit]) -> Vec<u8> {
    let json_len = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
    let (json, rest) = glb[20..].split_at(json_len);
    let mut json = json.to_vec();
    let mut bin = rest.to_vec();
    let mut cut = None;
    for e in edits {
        match *e {
            GlbEdit::JsonByte(at, c) => {
                let n = json.len();
                json[at % n] = JSON_CHARS[c % JSON_CHARS.len()];
            }
            GlbEdit::JsonNumber(k, with) => {
                let text = String::from_utf8_lossy(&json).into_owned();
                let spans: Vec<(usize, usize)> = number_spans(&text);
                if let Some(&(a, b)) = spans.get(k % spans.len().max(1)) {
                    let mut t = text[..a].to_string();
                    t.push_str(NUMBERS[with % NUMBERS.len()]);
                    t.push_str(&text[b..]);
                    json = t.into_bytes();
                }
            }
            GlbEdit::BinByte(at, v) => {
                let n = bin.len();
                bin[8 + at % (n - 8)] = v;
            }
            GlbEdit::Truncate(at) => cut = Some(at),
        }
    }
    while json.len() % 4 != 0 {
        json.push(b' ');
    }
    let mut out = glb[..12].to_vec();
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(&glb[16..20]);
    out.extend_from_slice(&json);
    out.extend_from_slice(&bin);
    let total = out.len() as u32;
    out[8..12].copy_from_slice(&total.to_le_bytes());
    if let Some(at) = cut {
        out.truncate(at % (out.len() + 1));
    }
    out
}

/// Byte ranges of the JSON's numbers.
fn number_spans(text: &str) -> Vec<(usize, usize)> {
    let b = text.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        if (b[i].is_ascii_digit() || b[i] == b'-')
            && (i == 0 || matches!(b[i - 1], b':' | b'[' | b','))
        {
            let start = i;
            while i < b.len() && (b[i].is_ascii_digit() || b"-.eE+".contains(&b[i])) {
                i += 1;
            }
            out.push((start, i));
        } else {
            i += 1;
        }
    }
    out
}

fn glb_edit() -> impl Strategy<Value = GlbEdit> {
    prop_oneof![
        (any::<usize>(), any::<usize>()).prop_map(|(a, b)| GlbEdit::JsonByte(a, b)),
        (any::<usize>(), any::<usize>()).prop_map(|(a, b)| GlbEdit::JsonNumber(a, b)),
        (any::<usize>(), any::<u8>()).prop_map(|(a, b)| GlbEdit::BinByte(a, b)),
        any::<usize>().prop_map(GlbEdit::Truncate),
    ]
}

fn check_glb(bytes: &[u8], dir: &Path, case: u64) -> Result<(), TestCaseError> {
    let path = dir.join(format!("case-{case}.glb"));
    std::fs::write(&path, bytes).unwrap();
    let shown = path.display().to_string();
    match gltf::load(&path, 100_000, None, &mut Cache::default(), None) {
        Ok((mesh, model)) => {
            for t in &mesh.triangles {
                prop_assert!(t.p().iter().all(|v| v.is_finite()), "non-finite vertex");
            }
            prop_assert!(mesh.uvs.is_empty() || mesh.uvs.len() == mesh.triangles.len());
            let n = model.materials.len() as u32;
            prop_assert!(
                mesh.materials.iter().all(|&m| m < n),
                "material index out of range"
            );
        }
        Err(e) => {
            prop_assert!(e.starts_with(&shown), "{e}");
            prop_assert!(!e.contains('\n'), "{e}");
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 96, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn mtl_files_of_random_statements_never_panic(lines in prop::collection::vec(any::<usize>(), 0..24)) {
        let dir = fixture_dir();
        check_mtl(&lines, dir.path())?;
    }

    #[test]
    fn mutated_gltf_binaries_never_panic(edits in prop::collection::vec(glb_edit(), 1..6), case in any::<u64>()) {
        let glb = std::fs::read(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/examples/textured/room.glb")).unwrap();
        let dir = tempfile::tempdir().unwrap();
        check_glb(&apply(&glb, &edits), dir.path(), case)?;
    }
}
